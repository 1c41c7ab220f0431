//! Thin features (issue 20, item 2): a region too narrow for a perimeter loop gets one bead
//! along its medial axis, its width the region's local width clamped to the process range
//! (the speed then follows from the inverse of seed 004 eq. 14); a region that fits in one
//! bead's reach in every direction (a pin) gets a small circle, one per layer, so the layers
//! stack into a column.
//!
//! The medial axis is found without a skeleton: every boundary sample casts a ray along its
//! inward normal to the opposite wall, and the midpoint of that chord is a point of the axis
//! with the chord's length as the local width (as the thesis measures walls, seed 004 B4).
//! Both walls of a strip give the same axis, so a midpoint within a third of a bead of the
//! axis already kept is dropped: a strip gives one open run, a closed wall one loop, a branched
//! rib a few runs.

use super::geom::{dist, ray_hit, P2};
use super::region::Shape;
use cell_geometry::{bounding_box, point_segment_distance, resample_max_step};

/// One thin-feature bead: points and the bead width (mm) of the piece from each point on.
#[derive(Debug, Clone, PartialEq)]
pub struct ThinBead {
    /// Path (mm); a closed path repeats its first point at the end.
    pub pts: Vec<P2>,
    /// Bead width per point (mm), within the limits given.
    pub widths: Vec<f64>,
    /// A pin's circle (a column when stacked) rather than a medial run.
    pub column: bool,
}

/// Beads covering the thin `shape` (outer ring CCW, holes CW) with widths in
/// `limits_mm = (lo, hi)`, boundary samples at most `sample_mm` apart, round parts as chords
/// within `tol_mm`.
///
/// A shape whose vertices lie within `hi − 0.1` mm of its bounding-box centre is a pin: a circle
/// of radius ρ = max(w/4, r − w/2 + 0.05) around that centre with w = clamp(r + 0.1, lo, hi), so
/// the circle's footprint (radius ρ + w/2) reaches past every vertex and its centre stays
/// covered (ρ ≤ w/2). Otherwise the medial runs of the module docs.
pub fn thin_beads(
    shape: &Shape,
    limits_mm: (f64, f64),
    sample_mm: f64,
    tol_mm: f64,
) -> Vec<ThinBead> {
    let (lo, hi) = limits_mm;
    let Some(outer) = shape.first() else {
        return Vec::new();
    };
    let (bmin, bmax) = bounding_box(outer.iter());
    let c = [(bmin.x + bmax.x) / 2.0, (bmin.y + bmax.y) / 2.0];
    let r = outer.iter().map(|p| dist(*p, c)).fold(0.0, f64::max);
    if r <= hi - 0.1 {
        return vec![pin(c, r, lo, hi, tol_mm)];
    }
    medial_runs(shape, lo, hi, sample_mm)
}

/// The pin's circle (see [`thin_beads`]).
fn pin(c: P2, r: f64, lo: f64, hi: f64, tol_mm: f64) -> ThinBead {
    let w = (r + 0.1).clamp(lo, hi);
    let rho = (w / 4.0).max(r - w / 2.0 + 0.05);
    // Chords within tol of the circle.
    let step = (2.0 * (1.0 - (tol_mm / rho).min(1.0)).acos()).clamp(0.05, 0.5);
    let n = ((std::f64::consts::TAU / step).ceil() as usize).max(8);
    let mut pts: Vec<P2> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [c[0] + rho * a.cos(), c[1] + rho * a.sin()]
        })
        .collect();
    pts.push(pts[0]);
    ThinBead {
        widths: vec![w; pts.len()],
        pts,
        column: true,
    }
}

/// A boundary sample's chord across the region: its midpoint and length (mm).
#[derive(Debug, Clone, Copy)]
struct Chord {
    mid: P2,
    width: f64,
}

/// Chords from `ring`'s samples across `shape` (left of travel is material for outer CCW and
/// hole CW rings); `None` where the ray finds no wall within `2·hi` (a strip's end cap).
fn chords(shape: &Shape, ring: &[P2], step: f64, hi: f64) -> Vec<Option<Chord>> {
    let mut closed = ring.to_vec();
    closed.push(ring[0]);
    let mut pts = resample_max_step(&closed, step, super::geom::NORM);
    pts.pop();
    let n = pts.len();
    (0..n)
        .map(|i| {
            let (a, b) = (pts[(i + n - 1) % n], pts[(i + 1) % n]);
            let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
            let l = tx.hypot(ty);
            if l <= 0.0 {
                return None;
            }
            let nrm = [-ty / l, tx / l];
            let p = pts[i];
            let t = ray_hit(shape, p, nrm, 2.0 * hi)?;
            Some(Chord {
                mid: [p[0] + nrm[0] * t / 2.0, p[1] + nrm[1] * t / 2.0],
                width: t,
            })
        })
        .collect()
}

/// Distance from `p` to the polyline `run` (∞ for an empty one).
fn dist_to_run(p: P2, run: &[P2]) -> f64 {
    match run.len() {
        0 => f64::INFINITY,
        1 => dist(p, run[0]),
        _ => run
            .windows(2)
            .map(|w| point_segment_distance(p, w[0], w[1], super::geom::NORM))
            .fold(f64::INFINITY, f64::min),
    }
}

fn medial_runs(shape: &Shape, lo: f64, hi: f64, sample_mm: f64) -> Vec<ThinBead> {
    let step = sample_mm.min(lo / 4.0).max(0.05);
    let dup = lo / 3.0;
    let mut runs: Vec<(Vec<P2>, Vec<f64>)> = Vec::new();
    let mut closed_loop = false;
    for (k, ring) in shape.iter().enumerate() {
        let cs = chords(shape, ring, step, hi);
        let n = cs.len();
        // Start right after a sample with no chord (a strip's end), so a strip is one run.
        let start = (0..n)
            .find(|&i| cs[i].is_none() && cs[(i + 1) % n].is_some())
            .map_or(0, |i| (i + 1) % n);
        let mut cur: (Vec<P2>, Vec<f64>) = (Vec::new(), Vec::new());
        let mut broken = false;
        for j in 0..n {
            let Some(ch) = cs[(start + j) % n] else {
                broken = true;
                continue;
            };
            let near_kept = runs.iter().any(|(r, _)| dist_to_run(ch.mid, r) < dup);
            // The current run's own tail (the last 2·dup of it) is not a duplicate.
            let mut tail = cur.0.len();
            let mut s = 0.0;
            while tail > 1 && s < 2.0 * dup {
                s += dist(cur.0[tail - 1], cur.0[tail - 2]);
                tail -= 1;
            }
            let near_own =
                dist_to_run(ch.mid, &cur.0[..tail.min(cur.0.len())]) < dup && cur.0.len() > 2;
            let jump = cur.0.last().is_some_and(|&q| dist(q, ch.mid) > 3.0 * dup);
            if near_kept || near_own || jump {
                broken = true;
                if cur.0.len() >= 2 {
                    runs.push(std::mem::take(&mut cur));
                } else {
                    cur = (Vec::new(), Vec::new());
                }
                if near_kept || near_own {
                    continue;
                }
            }
            cur.0.push(ch.mid);
            cur.1.push((ch.width + 0.2).clamp(lo, hi));
        }
        if cur.0.len() >= 2 {
            if k == 0 && !broken && runs.is_empty() {
                closed_loop = true;
            }
            runs.push(cur);
        }
    }
    runs.into_iter()
        .enumerate()
        .map(|(i, (mut pts, mut widths))| {
            if i == 0 && closed_loop {
                pts.push(pts[0]);
                widths.push(widths[0]);
            } else {
                extend_end(shape, &mut pts, &mut widths, hi);
                pts.reverse();
                widths.reverse();
                extend_end(shape, &mut pts, &mut widths, hi);
                pts.reverse();
                widths.reverse();
            }
            ThinBead {
                pts,
                widths,
                column: false,
            }
        })
        .collect()
}

/// Moves an open run's last point along its last direction to within 0.25 mm of the wall it
/// runs into, when that wall is within `hi` (a strip's end): the chords stop a sample short of
/// the end.
fn extend_end(shape: &Shape, pts: &mut Vec<P2>, widths: &mut Vec<f64>, hi: f64) {
    let n = pts.len();
    if n < 2 {
        return;
    }
    let (a, b) = (pts[n - 2], pts[n - 1]);
    let l = dist(a, b);
    if l <= 1e-9 {
        return;
    }
    let d = [(b[0] - a[0]) / l, (b[1] - a[1]) / l];
    if let Some(t) = ray_hit(shape, b, d, hi) {
        if t > 0.25 {
            pts.push([b[0] + d[0] * (t - 0.25), b[1] + d[1] * (t - 0.25)]);
            widths.push(widths[n - 1]);
        }
    }
}
