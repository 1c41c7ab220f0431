//! Hand-made sheet-cutting programs for the acceptance check's own tests
//! (`tests/sheet_acceptance.rs`): each contour offset to its scrap side by a given distance
//! (round joins at convex corners as G2/G3 arcs, mitred at concave ones), entered by a
//! straight lead-in square to one edge, written as LinuxCNC-style G-code. The construction is
//! exact for polygons whose offset does not collapse, which is all these tests use.
#![allow(dead_code)] // each test binary uses a different subset

use std::fmt::Write as _;

use crate::plane::{add, cross, dot, right_of, scale, signed_area2, sub, unit, P};

/// How to cut one contour.
#[derive(Debug, Clone)]
pub struct ModelCut {
    pub ring: Vec<P>,
    /// True for a hole (scrap inside).
    pub hole: bool,
    /// Distance of the path from the contour, to the scrap side (negative: to the part side).
    pub offset: f64,
    /// Lead-in length; 0 pierces on the path.
    pub lead: f64,
    /// The edge the lead-in enters at its middle.
    pub lead_edge: usize,
    /// Stop the cut after this fraction of the turn (1 = whole).
    pub fraction: f64,
    /// Program the nominal contour with G41/G42 instead (offset ignored).
    pub controller: bool,
}

impl ModelCut {
    pub fn new(ring: &[P], hole: bool, offset: f64, lead: f64, lead_edge: usize) -> Self {
        ModelCut {
            ring: ring.to_vec(),
            hole,
            offset,
            lead,
            lead_edge,
            fraction: 1.0,
            controller: false,
        }
    }
}

/// One move of a model path.
enum Move {
    Line(P),
    Arc { to: P, centre: P, ccw: bool },
}

/// The scrap-side unit normal of every edge.
fn scrap_normals(ring: &[P], hole: bool) -> Vec<P> {
    let ccw = signed_area2(ring) > 0.0;
    let n = ring.len();
    (0..n)
        .map(|i| {
            let right = right_of(unit(sub(ring[(i + 1) % n], ring[i])));
            let outward = if ccw { right } else { scale(right, -1.0) };
            if hole {
                scale(outward, -1.0)
            } else {
                outward
            }
        })
        .collect()
}

/// The entry point and the moves once round the offset contour, back to the entry.
fn offset_turn(cut: &ModelCut) -> (P, Vec<Move>) {
    let ring = &cut.ring;
    let n = ring.len();
    let normals = scrap_normals(ring, cut.hole);
    let e = cut.offset;
    let k = cut.lead_edge % n;
    let mid = scale(add(ring[k], ring[(k + 1) % n]), 0.5);
    let entry = add(mid, scale(normals[k], e));
    let mut moves = Vec::new();
    for step in 1..=n {
        let v = (k + step) % n; // the vertex at the end of edge v − 1
        if e == 0.0 {
            moves.push(Move::Line(ring[v]));
            continue;
        }
        let (n_in, n_out) = (normals[(v + n - 1) % n], normals[v]);
        let d_out = unit(sub(ring[(v + 1) % n], ring[v]));
        let turns_away = dot(d_out, n_in) * e.signum() < -1e-12;
        if turns_away {
            let a = add(ring[v], scale(n_in, e));
            let b = add(ring[v], scale(n_out, e));
            moves.push(Move::Line(a));
            let ccw = cross(sub(a, ring[v]), sub(b, ring[v])) > 0.0;
            moves.push(Move::Arc {
                to: b,
                centre: ring[v],
                ccw,
            });
        } else {
            // Mitre: where the two offset lines meet.
            let miter = scale(add(n_in, n_out), e / (1.0 + dot(n_in, n_out)));
            moves.push(Move::Line(add(ring[v], miter)));
        }
    }
    moves.push(Move::Line(entry));
    (entry, moves)
}

fn xy(p: P) -> String {
    format!("X{:.4} Y{:.4}", p[0], p[1])
}

/// The G-code of `cuts` in order (module docs).
pub fn program(cuts: &[ModelCut]) -> String {
    let mut g = String::from("(model program)\nG17 G21 G90 G91.1 G94\nG0 Z10\n");
    for cut in cuts {
        let mut cut = cut.clone();
        if cut.controller {
            cut.offset = 0.0;
        }
        let (entry, moves) = offset_turn(&cut);
        let normals = scrap_normals(&cut.ring, cut.hole);
        let pierce = add(
            entry,
            scale(normals[cut.lead_edge % cut.ring.len()], cut.lead),
        );
        let _ = writeln!(
            g,
            "G0 {}\nG0 Z3.8\nM3 S100\nG4 P0.5\nG1 Z1.5 F2400",
            xy(pierce)
        );
        if cut.controller {
            // G41 keeps the tool left of the path: left is the scrap side when the path runs
            // with the scrap on its left.
            let ring = &cut.ring;
            let k = cut.lead_edge % ring.len();
            let d = unit(sub(ring[(k + 1) % ring.len()], ring[k]));
            let scrap_left = dot(right_of(d), normals[k]) < 0.0;
            let _ = writeln!(g, "{} D1", if scrap_left { "G41" } else { "G42" });
        }
        if cut.lead > 0.0 {
            let _ = writeln!(g, "G1 {}", xy(entry));
        }
        let total = moves.len();
        let keep = ((total as f64) * cut.fraction).round() as usize;
        let mut at = entry;
        for m in moves.into_iter().take(keep) {
            match m {
                Move::Line(p) => {
                    let _ = writeln!(g, "G1 {}", xy(p));
                    at = p;
                }
                Move::Arc { to, centre, ccw } => {
                    let ij = sub(centre, at);
                    let _ = writeln!(
                        g,
                        "{} {} I{:.4} J{:.4}",
                        if ccw { "G3" } else { "G2" },
                        xy(to),
                        ij[0],
                        ij[1]
                    );
                    at = to;
                }
            }
        }
        if cut.controller {
            g.push_str("G40\n");
        }
        g.push_str("M5\nG0 Z10\n");
    }
    g.push_str("G0 X0 Y0\nM2\n");
    g
}
