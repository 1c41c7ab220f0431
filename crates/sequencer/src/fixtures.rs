//! Hand-built sequencing problems for tests and the bench (until the layout generator lands):
//! a grid of square parts with a round hole each, optionally a big square hole holding a small
//! nested part (the seed 003 §A2 structure), with the precedence rules built by hand in both
//! modes.

use cell_profiles::{Compensation, LeadShape};

use crate::cut::CutSpec;
use crate::precedence::{Precedence, PrecedenceMode};
use crate::problem::{Contour, ContourRole, Point, Problem};

fn contour(
    part: usize,
    role: ContourRole,
    points: Vec<Point>,
    pierce_candidates: Vec<Point>,
) -> Contour {
    Contour {
        part,
        role,
        points,
        pierce_candidates,
        leads: Vec::new(),
        drawn: Vec::new(),
    }
}

fn square(x: f64, y: f64, s: f64) -> Vec<Point> {
    vec![[x, y], [x + s, y], [x + s, y + s], [x, y + s]]
}

fn square_candidates(x: f64, y: f64, s: f64, free: bool) -> Vec<Point> {
    let mid = [x + s / 2.0, y];
    if free {
        vec![
            mid,
            [x, y],
            [x + s, y + s / 2.0],
            [x + s / 2.0, y + s],
            [x, y + s / 2.0],
        ]
    } else {
        vec![mid]
    }
}

fn circle(c: Point, r: f64) -> Vec<Point> {
    (0..16)
        .map(|i| {
            let a = i as f64 * std::f64::consts::TAU / 16.0;
            [c[0] + r * a.cos(), c[1] + r * a.sin()]
        })
        .collect()
}

/// A grid problem (seed 003 §A1/§A2): `nx × ny` parts of 50 mm at `pitch` mm; `nest` adds a hole with a nested part to every
/// part; `free` gives several pierce candidates per contour.
pub fn grid(
    nx: usize,
    ny: usize,
    pitch: f64,
    nest: bool,
    free: bool,
    mode: PrecedenceMode,
) -> Problem {
    let s = 50.0;
    let mut contours = Vec::new();
    let mut predecessors: Vec<Vec<usize>> = Vec::new();
    let mut groups = Vec::new();
    let mut part = 0;
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (10.0 + i as f64 * pitch, 10.0 + j as f64 * pitch);
            let host = part;
            part += 1;
            let round = contours.len();
            let c = [x + 40.0, y + 40.0];
            let cands = if free {
                vec![
                    [c[0] + 6.0, c[1]],
                    [c[0], c[1] + 6.0],
                    [c[0] - 6.0, c[1]],
                    [c[0], c[1] - 6.0],
                ]
            } else {
                vec![[c[0] + 6.0, c[1]]]
            };
            contours.push(contour(host, ContourRole::Hole, circle(c, 6.0), cands));
            predecessors.push(vec![]);
            let mut holes = vec![round];
            let mut nested = None;
            if nest {
                let big = contours.len();
                contours.push(contour(
                    host,
                    ContourRole::Hole,
                    square(x + 5.0, y + 5.0, 25.0),
                    square_candidates(x + 5.0, y + 5.0, 25.0, free),
                ));
                predecessors.push(vec![]);
                holes.push(big);
                let small = contours.len();
                contours.push(contour(
                    part,
                    ContourRole::Outer,
                    square(x + 10.0, y + 10.0, 15.0),
                    square_candidates(x + 10.0, y + 10.0, 15.0, free),
                ));
                part += 1;
                predecessors.push(vec![]);
                nested = Some((big, small));
            }
            let outer = contours.len();
            contours.push(contour(
                host,
                ContourRole::Outer,
                square(x, y, s),
                square_candidates(x, y, s, free),
            ));
            predecessors.push(holes.clone());
            if let Some((big, small)) = nested {
                match mode {
                    PrecedenceMode::Strict => {
                        for &h in &holes {
                            predecessors[h].push(small);
                        }
                        groups.push(vec![small]);
                    }
                    PrecedenceMode::Relaxed => predecessors[big].push(small),
                }
            }
            if mode == PrecedenceMode::Strict {
                let mut g = holes;
                g.push(outer);
                groups.push(g);
            }
        }
    }
    Problem {
        sheet: [20.0 + nx as f64 * pitch, 20.0 + ny as f64 * pitch],
        start: [0.0, 0.0],
        origin: [0.0, 0.0],
        contours,
        precedence: Precedence {
            predecessors,
            groups,
        },
    }
}

/// `n` small round contours (8-gons of radius 5 mm) at seeded random places on a 1 m sheet,
/// one pierce point each and no precedence: a plain TSP for comparing idle length with a TSP
/// solver (issue 7's LKH-3 target).
pub fn scattered(n: usize, seed: u64) -> Problem {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let contours = (0..n)
        .map(|i| {
            let c = [rng.random_range(20.0..980.0), rng.random_range(20.0..980.0)];
            let points = (0..8)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 8.0;
                    [c[0] + 5.0 * a.cos(), c[1] + 5.0 * a.sin()]
                })
                .collect();
            contour(i, ContourRole::Outer, points, vec![[c[0] + 5.0, c[1]]])
        })
        .collect();
    Problem {
        sheet: [1000.0, 1000.0],
        start: [0.0, 0.0],
        origin: [0.0, 0.0],
        contours,
        precedence: Precedence {
            predecessors: vec![vec![]; n],
            groups: vec![],
        },
    }
}

/// The cut of the shipped plasma profiles' default material (6 mm mild steel): kerf 1.5 mm,
/// 5 mm arc lead-in, 2 mm lead-out, centre pierce below 12 mm, geometric compensation.
pub fn plasma_cut_spec() -> CutSpec {
    CutSpec {
        kerf_mm: 1.5,
        lead_in_mm: 5.0,
        lead_shape: LeadShape::Arc,
        lead_out_mm: 2.0,
        overcut_mm: 0.0,
        small_hole_diameter_mm: 12.0,
        skip_too_small_holes: false,
        compensation: Compensation::Geometric,
    }
}
