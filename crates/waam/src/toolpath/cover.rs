//! Coverage with a machining allowance (issue 20, item 1): where the beads of one layer go so
//! that their footprints contain the layer's part region grown by the allowance.
//!
//! The deposit model: a bead of width LW (seed 004 eq. 14) and height h (eq. 28) is its
//! rectangular cross-section swept along the path; seen from above, the path swept by a disk
//! of diameter LW (round at turns and at the ends, where the weld pool is round). The planner:
//! 1. target T = the part region grown by `machining_allowance_mm` (walls out, holes in);
//! 2. a connected piece of T too narrow for a bead of the widest width (its inset by LW_max/2
//!    is empty) gets thin-feature beads ([`super::thin`]);
//! 3. any other piece gets perimeters on T inset by LW/2 (so the bead's outer edge lies on
//!    T's edge: net surface + allowance) and zig-zag infill up to the innermost perimeter's
//!    centre line as run, pushed corners included (an infill bead's end then falls inside that
//!    perimeter's bead, and two touching infill beads leave no wedge next to it); a convex turn
//!    of the outer perimeter moves out along its bisector until its disk reaches T's corner;
//! 4. what the footprints still leave of T, if thicker than 0.1 mm (or of the part itself, if
//!    thicker than 0.02 mm), gets thin-feature beads, up to three rounds; a piece still left is
//!    returned as uncovered.

use super::geom::{dist, ray_hit, P2};
use super::region::{self, Shape};
use super::thin;
use crate::bead;
use crate::process::WaamProcess;

/// Rim pieces (between the part and the grown target) no thicker than twice this (mm) are
/// ignored: the allowance there is at most 0.1 mm short, which with the chords of the round
/// joins and ends (each within `arc_tolerance_mm`, 0.05 by default) stays within the 0.2 mm the
/// acceptance allows.
pub const IGNORED_HALF_THICKNESS_MM: f64 = 0.05;

/// Rounds of thin-feature beads added for what the beads leave uncovered.
const RESIDUAL_ROUNDS: usize = 3;

/// (LW_lo, LW_hi) in mm for thin-feature beads: the process's width limits
/// ([`WaamProcess::width_limits_mm`]) with the lower one raised until the bead is at least one
/// layer high (eq. 28: h = WFS·(d_w/2)²·π / (TS·LW), TS from eq. 14's inverse), so a column of
/// such beads stacks without gaps. If no width in range reaches the layer height, both are the
/// widest (the tallest bead).
pub fn cover_width_limits_mm(process: &WaamProcess) -> (f64, f64) {
    let (lo, hi) = process.width_limits_mm();
    let q = bead::deposition_rate_mm3_s(process.wire_feed_m_min, process.wire_diameter_mm);
    let wfs = process.wire_feed_m_min;
    let height =
        |w: f64| bead::travel_speed_for_width_mm_s(w, wfs).map_or(f64::NAN, |ts| q / (ts * w));
    let layer = process.layer_height_mm;
    if height(lo) >= layer {
        return (lo, hi);
    }
    // NaN (no speed for the width) counts as too low.
    if height(hi).partial_cmp(&layer).is_none_or(|o| o.is_lt()) {
        return (hi, hi);
    }
    // h grows with LW over eq. 14's range: bisect for h(LW) = layer.
    let (mut a, mut b) = (lo, hi);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if height(m) >= layer {
            b = m;
        } else {
            a = m;
        }
    }
    (b, hi)
}

/// One bead before it becomes a segment: its role, path and width per point.
#[derive(Debug, Clone)]
pub struct PlannedBead {
    /// Perimeter, infill or wall bead.
    pub role: super::SegmentRole,
    /// Path (mm).
    pub pts: Vec<P2>,
    /// Width of the piece from each point on (mm).
    pub widths: Vec<f64>,
    /// Whether `pts` is a closed loop (its last point repeats the first).
    pub closed: bool,
}

/// The footprint of a planned bead: runs of pieces of equal width stroked as open paths (a
/// closed loop repeats its first point; stroking it as closed would cut a false hole into a
/// loop narrower than its bead).
pub fn bead_footprint(b: &PlannedBead, tol_mm: f64) -> Vec<Shape> {
    let n = b.pts.len();
    if n < 2 || b.widths.iter().all(|w| (*w - b.widths[0]).abs() < 1e-9) {
        return region::footprint(
            &b.pts,
            b.widths.first().copied().unwrap_or(0.0),
            false,
            tol_mm,
        );
    }
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < n {
        let w = b.widths[i];
        let mut j = i + 1;
        while j + 1 < n && (b.widths[j] - w).abs() < 1e-9 {
            j += 1;
        }
        out.extend(region::footprint(&b.pts[i..=j], w, false, tol_mm));
        i = j;
    }
    out
}

/// Moves each convex turn of the closed loop `ring` (material on its left) out along its
/// bisector until the disk of radius `half_w` there reaches the edge of `target` (the ray
/// distance along the bisector minus `half_w`), by at most `half_w`.
fn push_corners(ring: &[P2], target: &[Vec<P2>], half_w: f64) -> Vec<P2> {
    let n = ring.len();
    (0..n)
        .map(|i| {
            let (a, v, b) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
            let (d1, d2) = ([v[0] - a[0], v[1] - a[1]], [b[0] - v[0], b[1] - v[1]]);
            let (l1, l2) = (d1[0].hypot(d1[1]), d2[0].hypot(d2[1]));
            if l1 <= 1e-12 || l2 <= 1e-12 || d1[0] * d2[1] - d1[1] * d2[0] <= 0.0 {
                return v;
            }
            // Right normals point away from the material, towards the target's edge.
            let out = [d1[1] / l1 + d2[1] / l2, -d1[0] / l1 - d2[0] / l2];
            let lo = out[0].hypot(out[1]);
            if lo <= 1e-12 {
                return v;
            }
            let u = [out[0] / lo, out[1] / lo];
            match ray_hit(target, v, u, 4.0 * half_w) {
                Some(t) if t - half_w > 1e-3 => {
                    let e = (t - half_w).min(half_w);
                    [v[0] + u[0] * e, v[1] + u[1] * e]
                }
                _ => v,
            }
        })
        .collect()
}

/// Whether a shape is thicker than `2·half_mm` somewhere (its inset by `half_mm` survives).
fn thicker_than(shape: &Shape, half_mm: f64, tol_mm: f64) -> bool {
    !region::shrink(std::slice::from_ref(shape), half_mm, tol_mm).is_empty()
}

/// What [`cover_layer`] planned.
#[derive(Debug, Clone, Default)]
pub struct LayerCover {
    /// Perimeters (in the order to weld them).
    pub perimeters: Vec<PlannedBead>,
    /// Infill regions (rings), filled by the caller's zig-zag.
    pub infill_region: Vec<Vec<P2>>,
    /// Thin-feature beads (medial runs and pin circles).
    pub thin: Vec<PlannedBead>,
    /// The target: the part region grown by the allowance.
    pub target: Vec<Shape>,
    /// The part region itself.
    pub part: Vec<Shape>,
}

/// Perimeters, the infill region and thin-feature beads for the part region `rings` (oriented:
/// outer CCW, holes CW), before the residual rounds (see [`fill_residual`]).
pub fn cover_layer(rings: &[Vec<P2>], process: &WaamProcess) -> LayerCover {
    let tol = process.arc_tolerance_mm;
    let part = region::union(rings);
    let target = region::grow(&part, process.machining_allowance_mm, tol);
    let limits = cover_width_limits_mm(process);
    let w = process.fixed_width_mm();
    let mut out = LayerCover::default();
    for shape in &target {
        if !thicker_than(shape, limits.1 / 2.0 - 1e-3, tol) {
            for b in thin::thin_beads(shape, limits, process.wall_sample_mm, tol) {
                out.thin.push(thin_planned(b));
            }
            continue;
        }
        let one = std::slice::from_ref(shape);
        // The innermost loops' centre lines (as run, corners pushed), where the infill ends.
        let mut innermost = Vec::new();
        for k in 0..process.perimeters {
            innermost.clear();
            for ring in region::shrink(one, w / 2.0 + k as f64 * w, tol)
                .into_iter()
                .flatten()
            {
                let ring = if k == 0 {
                    push_corners(&ring, shape, w / 2.0)
                } else {
                    ring
                };
                innermost.push(ring.clone());
                let mut pts = ring.clone();
                pts.push(ring[0]);
                out.perimeters.push(PlannedBead {
                    role: super::SegmentRole::Perimeter,
                    widths: vec![w; pts.len()],
                    pts,
                    closed: true,
                });
            }
        }
        if process.infill {
            if innermost.is_empty() {
                out.infill_region
                    .extend(region::shrink(one, w / 2.0, tol).into_iter().flatten());
            } else {
                // Up to the loops as run: a pushed corner drags its edges out, and raster lines
                // that stopped on the unpushed inset would leave a wedge at every seam between
                // two infill beads next to the perimeter.
                out.infill_region.extend(innermost);
            }
        }
    }
    out.target = target;
    out.part = part;
    out
}

/// A thin bead as a planned one.
pub fn thin_planned(b: thin::ThinBead) -> PlannedBead {
    let closed = b.pts.len() > 2 && b.pts.first() == b.pts.last();
    PlannedBead {
        role: super::SegmentRole::WallBead,
        pts: b.pts,
        widths: b.widths,
        closed,
    }
}

/// Thin-feature beads for what `beads` leave of `target` (pieces thicker than 0.1 mm: thinner
/// ones cost at most that much allowance) and of the `part` itself (voids thicker than 0.02 mm,
/// [`crate::allowance::CRACK_HALF_MM`]), in up to three rounds; returns them and the pieces
/// still uncovered. A wide uncovered piece (only when infill or perimeters are off) is returned
/// as uncovered, not filled.
pub fn fill_residual(
    target: &[Shape],
    part: &[Shape],
    beads: &[PlannedBead],
    process: &WaamProcess,
) -> (Vec<PlannedBead>, Vec<Shape>) {
    let tol = process.arc_tolerance_mm;
    let limits = cover_width_limits_mm(process);
    let mut prints: Vec<Shape> = beads.iter().flat_map(|b| bead_footprint(b, tol)).collect();
    let mut added = Vec::new();
    let mut left = Vec::new();
    for round in 0..=RESIDUAL_ROUNDS {
        let covered = region::union_shapes(&prints);
        let rim = region::difference(target, &covered)
            .into_iter()
            .filter(|s| thicker_than(s, IGNORED_HALF_THICKNESS_MM, tol));
        let voids = region::difference(part, &covered)
            .into_iter()
            .filter(|s| thicker_than(s, crate::allowance::CRACK_HALF_MM, tol));
        left = region::union_shapes(&rim.chain(voids).collect::<Vec<_>>());
        if left.is_empty() || round == RESIDUAL_ROUNDS {
            break;
        }
        let mut any = false;
        for s in &left {
            if thicker_than(s, limits.1 / 2.0 - 1e-3, tol) {
                continue;
            }
            for b in thin::thin_beads(s, limits, process.wall_sample_mm, tol) {
                let b = thin_planned(b);
                prints.extend(bead_footprint(&b, tol));
                added.push(b);
                any = true;
            }
        }
        if !any {
            break;
        }
    }
    (added, left)
}

/// Orders beads nearest-first from `from` (each entered at its start), keeping their
/// direction; returns them and where the torch ends.
pub fn nearest_first(
    mut beads: Vec<PlannedBead>,
    from: Option<P2>,
) -> (Vec<PlannedBead>, Option<P2>) {
    let mut out = Vec::with_capacity(beads.len());
    let mut pos = from;
    while !beads.is_empty() {
        let i = match pos {
            Some(p) => (0..beads.len())
                .min_by(|&a, &b| dist(beads[a].pts[0], p).total_cmp(&dist(beads[b].pts[0], p)))
                .unwrap_or(0),
            None => 0,
        };
        let b = beads.remove(i);
        pos = b.pts.last().copied();
        out.push(b);
    }
    (out, pos)
}
