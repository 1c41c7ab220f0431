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
use cell_geometry::{distance_to_rings, signed_area_from_first_vertex, Norm};

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
    /// Its length along the drawn contour, mm (to within the sampling step, half a kerf).
    pub length_mm: f64,
}

/// The longest stretch of `nominal` the kerf along `path` misses, if it is longer than two
/// kerfs: a notch narrower than the kerf, which the offset bridges (the stretch is the notch's
/// two walls and bottom), or a concave corner much sharper than a right angle.
///
/// The kerf (half width `h` = `half_kerf_mm` either side of `path`) reaches a drawn point iff
/// the point lies within `h` of the path (plus the chords' tolerance). Straight edges and
/// convex corners are reached everywhere; a concave corner of angle `θ` is missed for
/// `h · cot(θ/2)` along each wall (the kerf's round, `2h` in all at 90°, not reported). The
/// drawing is sampled every `h / 2`.
pub fn uncut_stretch(nominal: &[Point], path: &[Point], half_kerf_mm: f64) -> Option<UncutStretch> {
    let h = half_kerf_mm;
    if h <= 0.0 || path.len() < 3 || nominal.len() < 3 {
        return None;
    }
    let step = h / 2.0;
    let reach = h * 1.05 + CHORD_TOL_MM;
    // (point, distance to the path, length of drawing it stands for)
    let mut samples: Vec<(Point, f64, f64)> = Vec::new();
    for i in 0..nominal.len() {
        let (a, b) = (nominal[i], nominal[(i + 1) % nominal.len()]);
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let k = (len / step).ceil().max(1.0) as usize;
        for j in 0..k {
            let t = j as f64 / k as f64;
            let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            samples.push((
                p,
                distance_to_rings(p, &[path], Norm::Hypot),
                len / k as f64,
            ));
        }
    }
    let missed = |i: usize| samples[i].1 > reach;
    // Start the circular scan just after a reached sample, so no run wraps round.
    let first = (0..samples.len()).find(|&i| !missed(i))?;
    let mut best: Option<UncutStretch> = None;
    let mut run: Vec<(Point, f64)> = Vec::new();
    for step in 1..=samples.len() {
        let i = (first + step) % samples.len();
        if missed(i) {
            run.push((samples[i].0, samples[i].2));
            continue;
        }
        let length_mm: f64 = run.iter().map(|r| r.1).sum();
        if !run.is_empty() && best.is_none_or(|b| length_mm > b.length_mm) {
            // The run's middle along the drawing.
            let mut walked = 0.0;
            let at = run
                .iter()
                .find(|r| {
                    walked += r.1;
                    walked >= length_mm / 2.0
                })
                .map_or(run[0].0, |r| r.0);
            best = Some(UncutStretch { at, length_mm });
        }
        run.clear();
    }
    best.filter(|b| b.length_mm > 4.0 * h)
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
        let notched = vec![
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 10.0],
            [5.5, 10.0],
            [5.5, 2.0],
            [4.5, 2.0],
            [4.5, 10.0],
            [0.0, 10.0],
        ];
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
}
