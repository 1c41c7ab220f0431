//! Kerf compensation (issue 19, item 2): the path the tool centre follows round a contour is
//! the drawn contour offset by half the kerf towards the scrap side, so the part keeps its
//! drawn size: outer contours grow, holes shrink.
//!
//! **Direction.** A compensated cut goes round every contour with the part on its right:
//! outer contours clockwise, holes counter-clockwise (y up), whatever the drawing's winding.
//! The scrap side is then always the left one, which is where the offset goes, where lead-ins
//! come from ([`crate::leads`]), and the side a controller's `G41` puts the tool on.
//!
//! **Offset.** The contour becomes a `cavalier_contours` polyline and is offset by `+kerf/2`
//! (to the left): straight edges move parallel, convex corners (seen from the scrap side)
//! become arcs of radius `kerf/2` about the drawn vertex, concave ones are trimmed. The arcs
//! are flattened with chords at most [`CHORD_TOL_MM`] inside them, so every point of the
//! result lies between `kerf/2 − CHORD_TOL_MM` and `kerf/2` from the drawn contour, and the
//! emitter's arc fitting writes them as G2/G3 again.
//!
//! **Failures.** A hole whose inward offset vanishes (smaller than the kerf) or falls apart
//! into several loops (a neck narrower than the kerf) cannot be cut as drawn:
//! [`OffsetFailure`]; so can an outward offset that comes back as several loops. A notch of a
//! part narrower than the kerf is bridged by the offset (the tool cannot enter it):
//! [`uncut_stretch`] finds the drawing the kerf misses.

use cavalier_contours::polyline::{PlineSource, PlineSourceMut, Polyline};
use cell_geometry::signed_area_from_first_vertex;
use static_aabb2d_index::StaticAABB2DIndexBuilder;

use crate::containment::{dedup_ring, to_pline};
use crate::problem::{ContourRole, Point};

/// Largest distance between a flattened offset arc and the true arc, mm (the chords' sagitta).
pub const CHORD_TOL_MM: f64 = 0.005;

/// Why a contour's offset cannot be cut (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OffsetFailure {
    /// Nothing is left: the hole is smaller than the kerf.
    Vanishes,
    /// The offset falls apart into this many loops: a neck or notch narrower than the kerf.
    Splits(usize),
}

impl std::fmt::Display for OffsetFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OffsetFailure::Vanishes => f.write_str("its offset vanishes (smaller than the kerf)"),
            OffsetFailure::Splits(n) => write!(
                f,
                "its offset falls apart into {n} loops (a neck or notch narrower than the kerf)"
            ),
        }
    }
}

/// The ring turned so that the part lies on the right of its direction (module docs): outer
/// contours clockwise, holes counter-clockwise.
pub fn orient_part_right(points: &[Point], role: ContourRole) -> Vec<Point> {
    let ccw = signed_area_from_first_vertex(points) > 0.0;
    let want_ccw = role == ContourRole::Hole;
    if ccw == want_ccw {
        points.to_vec()
    } else {
        points.iter().rev().copied().collect()
    }
}

/// The compensated cut path of a contour (module docs): `points` turned part-right and offset
/// by `half_kerf_mm` (≥ 0) to the scrap side, arcs flattened to [`CHORD_TOL_MM`]. With
/// `half_kerf_mm = 0` the turned ring itself.
///
/// # Errors
/// [`OffsetFailure`] when the offset vanishes or falls apart.
pub fn offset_contour(
    points: &[Point],
    role: ContourRole,
    half_kerf_mm: f64,
) -> Result<Vec<Point>, OffsetFailure> {
    let ring = orient_part_right(points, role);
    if half_kerf_mm <= 0.0 {
        return Ok(ring);
    }
    let pline = to_pline(&ring);
    // The scrap side is on the left, which is cavalier's positive offset.
    let mut loops: Vec<Polyline<f64>> = pline
        .parallel_offset(half_kerf_mm)
        .into_iter()
        .filter(|p| p.vertex_count() >= 2 && p.area().abs() > 0.0)
        .collect();
    match loops.len() {
        0 => Err(OffsetFailure::Vanishes),
        1 => {
            let mut offset = loops.remove(0);
            offset.set_is_closed(true);
            let flat = offset
                .arcs_to_approx_lines(CHORD_TOL_MM)
                .unwrap_or_else(|| offset.clone());
            let pts: Vec<Point> = flat.iter_vertexes().map(|v| [v.x, v.y]).collect();
            let pts = dedup_ring(&pts, 1e-9);
            if pts.len() < 3 {
                return Err(OffsetFailure::Vanishes);
            }
            // The offset keeps the winding; turn it again should rounding have flipped a sliver.
            Ok(orient_part_right(&pts, role))
        }
        n => Err(OffsetFailure::Splits(n)),
    }
}

/// A stretch of the drawing the kerf does not reach ([`uncut_stretch`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UncutStretch {
    /// Its middle, along the drawing.
    pub at: Point,
    /// Its length along the drawn contour, mm (exact up to rounding: no sampling).
    pub length_mm: f64,
}

/// The longest stretch of `nominal` the kerf along `path` misses, if it is longer than two
/// kerfs: a notch narrower than the kerf, which the offset bridges (the stretch is the notch's
/// two walls and bottom), or a concave corner much sharper than a right angle.
///
/// The kerf (half width `h` = `half_kerf_mm` either side of `path`) reaches a drawn point iff
/// the point lies within `reach = 1.05·h + CHORD_TOL_MM` of the closed path (5 % margin and
/// the chords' tolerance). Straight edges and
/// convex corners are reached everywhere; a concave corner of angle `θ` is missed for
/// `h · cot(θ/2)` along each wall (the kerf's round, `2h` in all at 90°, not reported).
///
/// **Exact, no sampling.** The points within `reach` of one path segment `s = q₀q₁` form a
/// capsule: the union of the discs of radius `reach` about `q₀` and `q₁` and the rectangle
/// `{x : 0 ≤ (x−q₀)·u ≤ |s|, |(x−q₀)·n| ≤ reach}` (`u` along `s`, `n` its normal). Along a
/// drawn edge `p(t) = a + t·(b−a)` each disc gives the interval where the quadratic
/// `|p(t)−c|² − reach² ≤ 0`, the rectangle the intersection of two linear slabs; the capsule
/// is convex, so the line meets it in one interval, which is therefore the hull `[min, max]` of
/// those three. The reached part of the edge is the union of these intervals over the path
/// segments whose bounding boxes, grown by `reach`, meet the edge's box (a packed Hilbert
/// R-tree, `static_aabb2d_index`); the rest is missed. Missed parts that run on across a
/// vertex, also from the last edge round to the first, form one stretch. Memory
/// O(edges + path), time O((edges + path)·log(path) + candidate pairs).
///
/// Zero-length edges (repeated points) are skipped without breaking a stretch; a drawing the
/// path misses everywhere is one stretch of its whole length. No kerf, fewer than three
/// points or a non-finite coordinate: `None`.
pub fn uncut_stretch(nominal: &[Point], path: &[Point], half_kerf_mm: f64) -> Option<UncutStretch> {
    let h = half_kerf_mm;
    let finite = |ring: &[Point]| ring.iter().flatten().all(|c| c.is_finite());
    if !(h > 0.0 && h.is_finite()) || path.len() < 3 || nominal.len() < 3 {
        return None;
    }
    if !finite(nominal) || !finite(path) {
        return None;
    }
    let reach = h * 1.05 + CHORD_TOL_MM;
    let segments: Vec<(Point, Point)> = (0..path.len())
        .map(|i| (path[i], path[(i + 1) % path.len()]))
        .collect();
    let mut builder = StaticAABB2DIndexBuilder::new(segments.len());
    for (p, q) in &segments {
        builder.add(
            p[0].min(q[0]),
            p[1].min(q[1]),
            p[0].max(q[0]),
            p[1].max(q[1]),
        );
    }
    // Fails only on a wrong item count or a non-f64 coordinate type: neither can happen here.
    let index = builder.build().ok()?;
    let edges: Vec<(Point, Point, f64)> = (0..nominal.len())
        .map(|i| (nominal[i], nominal[(i + 1) % nominal.len()]))
        .map(|(a, b)| (a, b, (b[0] - a[0]).hypot(b[1] - a[1])))
        .filter(|e| e.2 > 0.0)
        .collect();
    // Missed pieces in drawing order: (edge, t from, t to).
    let mut missed: Vec<(usize, f64, f64)> = Vec::new();
    let mut reached: Vec<(f64, f64)> = Vec::new();
    let mut stack = Vec::new();
    for (e, &(a, b, _)) in edges.iter().enumerate() {
        reached.clear();
        let hits = index.query_iter_with_stack(
            a[0].min(b[0]) - reach,
            a[1].min(b[1]) - reach,
            a[0].max(b[0]) + reach,
            a[1].max(b[1]) + reach,
            &mut stack,
        );
        for s in hits {
            let (q0, q1) = segments[s];
            if let Some((lo, hi)) = capsule_interval(a, b, q0, q1, reach) {
                let (lo, hi) = (lo.max(0.0), hi.min(1.0));
                if lo <= hi {
                    reached.push((lo, hi));
                }
            }
        }
        reached.sort_by(|x, y| x.0.total_cmp(&y.0));
        // The complement in [0, 1] of the union of the reached intervals.
        let mut covered_to = 0.0_f64;
        for &(lo, hi) in &reached {
            if lo > covered_to {
                missed.push((e, covered_to, lo));
            }
            covered_to = covered_to.max(hi);
        }
        if covered_to < 1.0 {
            missed.push((e, covered_to, 1.0));
        }
    }
    if missed.is_empty() {
        return None;
    }
    let piece_len = |&(e, t0, t1): &(usize, f64, f64)| edges[e].2 * (t1 - t0);
    // A piece continues the one before it when that ends at its edge's end and it starts at
    // the start of the next edge.
    let continues = |before: (usize, f64, f64), after: (usize, f64, f64)| {
        before.2 == 1.0 && after.1 == 0.0 && (before.0 + 1) % edges.len() == after.0
    };
    // Runs as (first piece, piece count, length).
    let mut runs: Vec<(usize, usize, f64)> = Vec::new();
    for (k, piece) in missed.iter().enumerate() {
        match runs.last_mut() {
            Some(run) if continues(missed[k - 1], *piece) => {
                run.1 += 1;
                run.2 += piece_len(piece);
            }
            _ => runs.push((k, 1, piece_len(piece))),
        }
    }
    let wraps = continues(missed[missed.len() - 1], missed[0]);
    if wraps && runs.len() > 1 {
        let last = runs.pop()?;
        runs[0] = (last.0, last.1 + runs[0].1, last.2 + runs[0].2);
    }
    let &(first, count, length_mm) = runs.iter().max_by(|x, y| x.2.total_cmp(&y.2))?;
    if length_mm <= 4.0 * h {
        return None;
    }
    // Its middle: walk half its length along its pieces.
    let mut left = length_mm / 2.0;
    let mut at = nominal[0];
    for k in 0..count {
        let piece = missed[(first + k) % missed.len()];
        let (a, b, len) = edges[piece.0];
        let piece_len = piece_len(&piece);
        if left <= piece_len || k + 1 == count {
            let t = (piece.1 + left.min(piece_len) / len).min(1.0);
            at = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            break;
        }
        left -= piece_len;
    }
    Some(UncutStretch { at, length_mm })
}

/// The parameters `t` (on the whole line, not clipped to `[0, 1]`) where `a + t·(b−a)` lies
/// within `r` of the segment `q0 q1`: the hull of the intervals of its two end discs and its
/// rectangle ([`uncut_stretch`]), `None` if the line misses the capsule. `a ≠ b`.
fn capsule_interval(a: Point, b: Point, q0: Point, q1: Point, r: f64) -> Option<(f64, f64)> {
    let d = [b[0] - a[0], b[1] - a[1]];
    let dd = d[0] * d[0] + d[1] * d[1];
    let mut hull: Option<(f64, f64)> = None;
    let mut join = |i: Option<(f64, f64)>| {
        if let Some((lo, hi)) = i {
            hull = Some(hull.map_or((lo, hi), |(l, h)| (l.min(lo), h.max(hi))));
        }
    };
    // |a + t·d − c|² ≤ r²:  dd·t² + 2·β·t + γ ≤ 0.
    let disc = |c: Point| {
        let w = [a[0] - c[0], a[1] - c[1]];
        let beta = d[0] * w[0] + d[1] * w[1];
        let gamma = w[0] * w[0] + w[1] * w[1] - r * r;
        let disc = beta * beta - dd * gamma;
        (disc >= 0.0).then(|| {
            let root = disc.sqrt();
            ((-beta - root) / dd, (-beta + root) / dd)
        })
    };
    join(disc(q0));
    join(disc(q1));
    let s = [q1[0] - q0[0], q1[1] - q0[1]];
    let len = s[0].hypot(s[1]);
    if len > 0.0 {
        let u = [s[0] / len, s[1] / len];
        let n = [-u[1], u[0]];
        let w = [a[0] - q0[0], a[1] - q0[1]];
        // (a − q0 + t·d)·v ∈ [lo, hi], linear in t.
        let slab = |v: Point, lo: f64, hi: f64| {
            let (c0, c1) = (w[0] * v[0] + w[1] * v[1], d[0] * v[0] + d[1] * v[1]);
            if c1 == 0.0 {
                (lo..=hi)
                    .contains(&c0)
                    .then_some((f64::NEG_INFINITY, f64::INFINITY))
            } else {
                let (t0, t1) = ((lo - c0) / c1, (hi - c0) / c1);
                Some((t0.min(t1), t0.max(t1)))
            }
        };
        if let (Some(along), Some(across)) = (slab(u, 0.0, len), slab(n, -r, r)) {
            let (lo, hi) = (along.0.max(across.0), along.1.min(across.1));
            join((lo <= hi).then_some((lo, hi)));
        }
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_geometry::{point_in_ring_nonzero, point_segment_distance, Norm};

    /// Distance from `p` to the ring's edges (our own, not cavalier's).
    fn dist_to_ring(p: Point, ring: &[Point]) -> f64 {
        (0..ring.len())
            .map(|i| point_segment_distance(p, ring[i], ring[(i + 1) % ring.len()], Norm::Hypot))
            .fold(f64::INFINITY, f64::min)
    }

    /// Every vertex and edge midpoint of `path` lies `half` (within the chord tolerance) from
    /// `nominal`, on the scrap side.
    fn assert_offset(nominal: &[Point], path: &[Point], role: ContourRole, half: f64) {
        let n = path.len();
        for i in 0..n {
            let (a, b) = (path[i], path[(i + 1) % n]);
            for p in [a, [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]] {
                let d = dist_to_ring(p, nominal);
                assert!(
                    d <= half + 1e-9 && d >= half - CHORD_TOL_MM - 1e-9,
                    "{p:?} is {d} from the contour, want {half}"
                );
                let inside = point_in_ring_nonzero(p, nominal);
                assert_eq!(inside, role == ContourRole::Hole, "{p:?} on the wrong side");
            }
        }
    }

    fn square(x: f64, y: f64, s: f64) -> Vec<Point> {
        vec![[x, y], [x + s, y], [x + s, y + s], [x, y + s]]
    }

    fn circle(c: Point, r: f64, n: usize) -> Vec<Point> {
        (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                [c[0] + r * a.cos(), c[1] + r * a.sin()]
            })
            .collect()
    }

    #[test]
    fn outer_contours_grow_and_holes_shrink_by_half_the_kerf() {
        let sq = square(10.0, 10.0, 50.0);
        let out = offset_contour(&sq, ContourRole::Outer, 0.75).unwrap();
        assert_offset(&sq, &out, ContourRole::Outer, 0.75);
        assert!(
            signed_area_from_first_vertex(&out) < 0.0,
            "outer: clockwise"
        );
        // The corners became arcs: more points than the square.
        assert!(out.len() > 8, "{}", out.len());
        let hole = offset_contour(&sq, ContourRole::Hole, 0.75).unwrap();
        assert_offset(&sq, &hole, ContourRole::Hole, 0.75);
        assert!(
            signed_area_from_first_vertex(&hole) > 0.0,
            "hole: counter-clockwise"
        );
        // A hole's square corners stay sharp: four points.
        assert_eq!(hole.len(), 4);
        // Either winding of the drawing gives the same path.
        let rev: Vec<Point> = sq.iter().rev().copied().collect();
        let out2 = offset_contour(&rev, ContourRole::Outer, 0.75).unwrap();
        assert_offset(&sq, &out2, ContourRole::Outer, 0.75);
    }

    #[test]
    fn flattened_circles_and_concave_shapes_stay_at_half_the_kerf() {
        let c = circle([100.0, 100.0], 20.0, 72);
        for role in [ContourRole::Outer, ContourRole::Hole] {
            let p = offset_contour(&c, role, 0.1).unwrap();
            assert_offset(&c, &p, role, 0.1);
        }
        // An L shape: one concave corner.
        let l = vec![
            [0.0, 0.0],
            [40.0, 0.0],
            [40.0, 10.0],
            [10.0, 10.0],
            [10.0, 40.0],
            [0.0, 40.0],
        ];
        for role in [ContourRole::Outer, ContourRole::Hole] {
            let p = offset_contour(&l, role, 1.5).unwrap();
            assert_offset(&l, &p, role, 1.5);
            // A 90° inside corner keeps the kerf's round: not reported.
            assert_eq!(uncut_stretch(&l, &p, 1.5), None, "{role:?}");
        }
    }

    #[test]
    fn holes_too_small_or_too_narrow_for_the_kerf_fail() {
        let tiny = square(0.0, 0.0, 1.0);
        assert_eq!(
            offset_contour(&tiny, ContourRole::Hole, 0.75),
            Err(OffsetFailure::Vanishes)
        );
        // Two 10 mm squares joined by a 1 mm neck: a 1.5 mm kerf splits it.
        let dumbbell = vec![
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 4.5],
            [20.0, 4.5],
            [20.0, 0.0],
            [30.0, 0.0],
            [30.0, 10.0],
            [20.0, 10.0],
            [20.0, 5.5],
            [10.0, 5.5],
            [10.0, 10.0],
            [0.0, 10.0],
        ];
        assert_eq!(
            offset_contour(&dumbbell, ContourRole::Hole, 0.75),
            Err(OffsetFailure::Splits(2))
        );
        // The same shape as an outer contour grows without trouble.
        let p = offset_contour(&dumbbell, ContourRole::Outer, 0.75).unwrap();
        assert_offset(&dumbbell, &p, ContourRole::Outer, 0.75);
        // A part with a 1 mm notch: the outward offset closes it.
        let notched = notched();
        // A notch narrower than the kerf cannot be cut: the outward offset bridges it, still
        // half a kerf from the part everywhere.
        let p = offset_contour(&notched, ContourRole::Outer, 0.75).unwrap();
        assert_offset(&notched, &p, ContourRole::Outer, 0.75);
        assert!(
            !p.iter().any(|q| q[0] > 4.0 && q[0] < 6.0 && q[1] < 10.5),
            "{p:?}"
        );
        // ... and reported: both walls and the bottom (8 + 1 + 8 mm, less the corners'
        // rounds the kerf reaches), its middle at the bottom.
        let miss = uncut_stretch(&notched, &p, 0.75).expect("the bridged notch");
        assert!((miss.at[1] - 2.0).abs() < 0.5, "{miss:?}");
        assert!((miss.length_mm - 17.0).abs() < 1.5, "{miss:?}");
        // A 2 mm notch, wider than the kerf, is cut: nothing to report.
        let wide = vec![
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 10.0],
            [6.0, 10.0],
            [6.0, 2.0],
            [4.0, 2.0],
            [4.0, 10.0],
            [0.0, 10.0],
        ];
        let p = offset_contour(&wide, ContourRole::Outer, 0.75).unwrap();
        assert_eq!(uncut_stretch(&wide, &p, 0.75), None);
        // The same 1 mm slot in a hole's edge (the hole's offset bridges it too).
        let p = offset_contour(&notched, ContourRole::Hole, 0.75).unwrap();
        assert_eq!(
            uncut_stretch(&notched, &p, 0.75),
            None,
            "a tab into a hole is cut round"
        );
        // No kerf: the ring, turned part-right.
        assert_eq!(
            offset_contour(&tiny, ContourRole::Hole, 0.0).unwrap(),
            tiny,
            "counter-clockwise already"
        );
    }

    /// A 10 mm square part with a 1 mm notch 8 mm deep.
    fn notched() -> Vec<Point> {
        vec![
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 10.0],
            [5.5, 10.0],
            [5.5, 2.0],
            [4.5, 2.0],
            [4.5, 10.0],
            [0.0, 10.0],
        ]
    }

    #[test]
    fn repeated_points_and_any_start_vertex_give_the_same_stretch() {
        let nominal = notched();
        let path = offset_contour(&nominal, ContourRole::Outer, 0.75).unwrap();
        let miss = uncut_stretch(&nominal, &path, 0.75).expect("the bridged notch");
        // The corners' arcs meet at the dip (5, 10 + √(0.75² − 0.5²)); from it the kerf
        // reaches `reach` = 0.7925 down each wall, to 0.056 mm below the mouth: the walls' other
        // 7.944 mm and the bottom are missed (to within the arcs' chord tolerance).
        let dip = 10.0 + (0.75f64.powi(2) - 0.25).sqrt();
        let reach = 0.75 * 1.05 + CHORD_TOL_MM;
        let reached = 10.0 - (dip - (reach * reach - 0.25).sqrt());
        let expected = 2.0 * (8.0 - reached) + 1.0;
        assert!(
            (miss.length_mm - expected).abs() < 2.0 * CHORD_TOL_MM,
            "{miss:?}, want {expected}"
        );
        assert!(
            (miss.at[0] - 5.0).abs() < 1e-9 && (miss.at[1] - 2.0).abs() < 1e-9,
            "{miss:?}"
        );
        // Every point repeated (zero-length edges of the drawing, zero-length path segments):
        // nothing changes, not even where the run is split by the repeated notch corners.
        let twice = |ring: &[Point]| -> Vec<Point> { ring.iter().flat_map(|&p| [p, p]).collect() };
        let again = uncut_stretch(&twice(&nominal), &twice(&path), 0.75).expect("still missed");
        assert!(
            (again.length_mm - miss.length_mm).abs() < 1e-9,
            "{again:?} vs {miss:?}"
        );
        assert!((again.at[0] - 5.0).abs() < 1e-9 && (again.at[1] - 2.0).abs() < 1e-9);
        // Starting the drawing anywhere, in the notch too (the run then wraps from the last
        // edge round to the first), finds the same stretch.
        for k in 0..nominal.len() {
            let mut turned = nominal.clone();
            turned.rotate_left(k);
            let m = uncut_stretch(&turned, &path, 0.75).expect("the bridged notch");
            assert!(
                (m.length_mm - miss.length_mm).abs() < 1e-9,
                "start {k}: {m:?}"
            );
            assert!(
                (m.at[0] - 5.0).abs() < 1e-9 && (m.at[1] - 2.0).abs() < 1e-9,
                "{m:?}"
            );
        }
        // Non-finite input is no stretch (and no panic).
        let mut broken = nominal.clone();
        broken[3] = [f64::NAN, f64::NAN];
        assert_eq!(uncut_stretch(&broken, &path, 0.75), None);
        assert_eq!(uncut_stretch(&nominal, &path, f64::INFINITY), None);
        // A drawing all of whose vertices coincide has no length to miss.
        assert_eq!(uncut_stretch(&[[1.0, 1.0]; 4], &path, 0.75), None);
        // A path far away misses the whole outline: one stretch, its perimeter.
        let far: Vec<Point> = path.iter().map(|p| [p[0] + 100.0, p[1]]).collect();
        let all = uncut_stretch(&nominal, &far, 0.75).expect("all missed");
        assert!((all.length_mm - 56.0).abs() < 1e-9, "{all:?}");
    }

    /// The reference for the property test: the drawing sampled at the middles of pieces at
    /// most `step` long, each missed when farther than `reach` from every segment of `path`
    /// (its own distance code), the longest circular run of missed pieces.
    fn sampled_longest_miss(nominal: &[Point], path: &[Point], reach: f64, step: f64) -> f64 {
        fn dist(p: Point, a: Point, b: Point) -> f64 {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let l2 = dx * dx + dy * dy;
            let t = if l2 == 0.0 {
                0.0
            } else {
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
            };
            (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
        }
        let mut pieces: Vec<(bool, f64)> = Vec::new();
        for i in 0..nominal.len() {
            let (a, b) = (nominal[i], nominal[(i + 1) % nominal.len()]);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            let k = (len / step).ceil() as usize;
            for j in 0..k {
                let t = (j as f64 + 0.5) / k as f64;
                let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                let d = (0..path.len())
                    .map(|s| dist(p, path[s], path[(s + 1) % path.len()]))
                    .fold(f64::INFINITY, f64::min);
                pieces.push((d > reach, len / k as f64));
            }
        }
        let Some(start) = pieces.iter().position(|p| !p.0) else {
            return pieces.iter().map(|p| p.1).sum();
        };
        let (mut best, mut run) = (0.0f64, 0.0);
        for i in 1..=pieces.len() {
            let (missed, len) = pieces[(start + i) % pieces.len()];
            run = if missed { run + len } else { 0.0 };
            best = best.max(run);
        }
        best
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

        /// On rectangles with up to four notches of random widths, depths and wall slants
        /// (some narrower than the kerf, some V-shaped, some with repeated points), the exact
        /// stretch agrees with dense sampling to within the sampling step at each of its ends.
        #[test]
        fn the_exact_stretch_agrees_with_dense_sampling(
            notches in proptest::collection::vec(
                (0.2f64..3.0, 0.0f64..1.0, 0.5f64..8.0, -1.0f64..1.0), 1..5),
            half in 0.3f64..1.0,
            hole: bool,
        ) {
            let mut ring: Vec<Point> = vec![[0.0, 0.0], [8.0 * notches.len() as f64, 0.0]];
            for (i, &(width, bottom, depth, shift)) in notches.iter().enumerate().rev() {
                let mid = 8.0 * i as f64 + 4.0;
                let (w, wb) = (width / 2.0, width * bottom / 2.0);
                ring.extend([
                    [mid + w, 10.0],
                    [mid + shift + wb, 10.0 - depth],
                    [mid + shift - wb, 10.0 - depth],
                    [mid - w, 10.0],
                ]);
            }
            ring.push([0.0, 10.0]);
            let role = if hole { ContourRole::Hole } else { ContourRole::Outer };
            let path = offset_contour(&ring, role, half);
            proptest::prop_assume!(path.is_ok());
            let path = path.unwrap();
            let reach = half * 1.05 + CHORD_TOL_MM;
            let step = half / 40.0;
            let reference = sampled_longest_miss(&ring, &path, reach, step);
            let exact = uncut_stretch(&ring, &path, half);
            // Only stretches longer than 4h are reported: near that line either may be.
            let tol = 2.0 * step + 1e-9;
            match exact {
                Some(m) => {
                    proptest::prop_assert!((m.length_mm - reference).abs() <= tol,
                        "exact {:?}, sampled {}", m, reference);
                    // Its middle is on the drawing and itself missed.
                    let on_drawing = (0..ring.len())
                        .map(|i| point_segment_distance(m.at, ring[i], ring[(i + 1) % ring.len()], Norm::Hypot))
                        .fold(f64::INFINITY, f64::min);
                    proptest::prop_assert!(on_drawing < 1e-9, "{:?} off the drawing", m);
                    proptest::prop_assert!(dist_to_ring(m.at, &path) >= reach - 1e-9, "{:?} reached", m);
                }
                None => proptest::prop_assert!(reference <= 4.0 * half + tol,
                    "sampled {} missed, exact none", reference),
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// The capsule interval on a line holds exactly the points within `r` of the segment
        /// (checked at 401 points of the line, away from the interval's ends), segments of
        /// zero length included.
        #[test]
        fn the_capsule_interval_is_where_the_line_is_within_reach(
            c in proptest::collection::vec(-5.0f64..5.0, 8),
            zero_segment: bool,
            r in 0.1f64..3.0,
        ) {
            let (a, b, q0) = ([c[0], c[1]], [c[2], c[3]], [c[4], c[5]]);
            let q1 = if zero_segment { q0 } else { [c[6], c[7]] };
            proptest::prop_assume!((b[0] - a[0]).hypot(b[1] - a[1]) > 1e-3);
            let got = capsule_interval(a, b, q0, q1, r);
            for k in 0..=400 {
                let t = -2.0 + 5.0 * k as f64 / 400.0;
                let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                let d = point_segment_distance(p, q0, q1, Norm::Hypot);
                if (d - r).abs() < 1e-6 {
                    continue;
                }
                let inside = got.is_some_and(|(lo, hi)| lo <= t && t <= hi);
                proptest::prop_assert_eq!(inside, d < r, "t {} at {} from the segment: {:?}", t, d, got);
            }
        }
    }
}
