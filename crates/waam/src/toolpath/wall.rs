//! The thesis's width-driven mode (seed 004 §4.4–4.5, notes B4): the bead width is measured
//! along the path normal to the product walls, clamped to [LW_min, LW_max], and the travel
//! speed follows from the inverse of eq. 14.

use super::geom::{dist, inset, ray_hit, NORM, P2};
use cell_geometry::{bounding_box, resample_max_step, signed_area};

/// One sample of a wall-driven bead path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallSample {
    /// Position (mm), midway between the two walls along the normal.
    pub xy: P2,
    /// Wall-to-wall width along the normal before clamping (mm); infinite if a side has no wall.
    pub measured_mm: f64,
    /// Bead width after clamping to the limits (mm).
    pub width_mm: f64,
}

/// Distances (mm) from `p` to the nearest wall along `+n` and along `−n` (`n` a unit vector),
/// `None` for a side with no wall within `max_mm`: seed 004 B4's "distance along ±N to a
/// crossing with a Product-Matrix wall segment".
pub fn wall_distances(walls: &[Vec<P2>], p: P2, n: P2, max_mm: f64) -> (Option<f64>, Option<f64>) {
    (
        ray_hit(walls, p, n, max_mm),
        ray_hit(walls, p, [-n[0], -n[1]], max_mm),
    )
}

/// Mid-wall bead loops for one layer: each outer-derived loop of the region inset by
/// `LW_min/2` is resampled every `sample_mm`, and each sample moved to the middle of the wall
/// along its normal (or, where the wall is wider than LW_max, to LW_max/2 from the outer side), with the wall-to-wall width clamped to `limits_mm` (seed 004 B4: "if the
/// width is larger than the data supports, use LW_max; if smaller, LW_min").
///
/// Returned loops are open (no repeated last point) and CCW, like the outer contours. Hole-
/// derived loops are skipped: in a wall one bead wide they are the same wall seen from the
/// other side.
pub fn mid_wall_loops(
    walls: &[Vec<P2>],
    limits_mm: (f64, f64),
    sample_mm: f64,
    tol_mm: f64,
) -> Vec<Vec<WallSample>> {
    let (lo, hi) = limits_mm;
    let (bmin, bmax) = bounding_box(walls.iter().flatten());
    let reach = 2.0 * dist(bmin, bmax) + 1.0;
    let mut out = Vec::new();
    for ring in inset(walls, lo / 2.0, tol_mm) {
        if signed_area(&ring) <= 0.0 {
            continue;
        }
        let mut closed = ring.clone();
        closed.push(ring[0]);
        let mut pts = resample_max_step(&closed, sample_mm, NORM);
        pts.pop();
        let n = pts.len();
        let mut samples = Vec::with_capacity(n);
        for i in 0..n {
            let (a, b) = (pts[(i + n - 1) % n], pts[(i + 1) % n]);
            let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
            let l = tx.hypot(ty);
            if l <= 0.0 {
                continue;
            }
            // Left of a CCW loop is inside the material.
            let normal = [-ty / l, tx / l];
            let p = pts[i];
            let (inward, outward) = wall_distances(walls, p, normal, reach);
            let (Some(b_in), Some(a_out)) = (inward, outward) else {
                samples.push(WallSample {
                    xy: p,
                    measured_mm: f64::INFINITY,
                    width_mm: hi,
                });
                continue;
            };
            let measured = a_out + b_in;
            // Mid-wall when the bead can fill the wall; a wall wider than LW_max (or a ray that
            // runs along a wall near a corner) keeps the bead LW_max/2 from the outer side.
            let shift = if measured <= hi {
                (b_in - a_out) / 2.0
            } else {
                hi / 2.0 - a_out
            };
            samples.push(WallSample {
                xy: [p[0] + normal[0] * shift, p[1] + normal[1] * shift],
                measured_mm: measured,
                width_mm: measured.clamp(lo, hi),
            });
        }
        if samples.len() >= 3 {
            out.push(samples);
        }
    }
    out
}
