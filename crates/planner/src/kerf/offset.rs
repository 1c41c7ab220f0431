//! Wire-centre path: the section outline offset by λ/2 (seed 001 §4.4).
//!
//! The offset itself is `cavalier_contours`' parallel offset (exact line/arc geometry, round
//! joins, self-intersection trimming in concave regions). Only the flattening of its join arcs
//! into points is done here, because the wire controller takes points.

use cavalier_contours::polyline::{
    seg_arc_radius_and_center, PlineCreation, PlineOffsetOptions, PlineSource, PlineSourceMut,
    PlineVertex, Polyline,
};
use nalgebra::Point2;

use super::KerfError;

/// Largest turn of one flattened arc step. 10° keeps a sharp trailing edge (≈180° of join) to
/// about 18 points while the flattened join stays within d·(1/cos 5° − 1) ≈ 0.4 % of d.
const MAX_ARC_STEP_RAD: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// The closed outline `points` offset by `offset_mm` to the **right of the direction of
/// travel**, which for an anticlockwise section (every [`crate::airfoil::Airfoil`]) is the
/// outside: the wire-centre path for a kerf λ is `offset_polyline(points, λ/2)`.
///
/// - `points` is a closed polygon (the closing segment last → first is implied; a repeated
///   first point at the end is ignored) in mm. Exact duplicate consecutive points are dropped.
/// - Joins are **round** (arcs of radius `offset_mm` about the input vertex): the kerf of a
///   round wire really is round at corners, and unlike miter joins they keep the path exactly
///   `offset_mm` from convex corners such as a sharp trailing edge.
/// - Arcs are flattened by circumscribed polygons (vertices on radius d / cos(θ/2), θ ≤ 10°),
///   so no part of the path comes closer than `offset_mm` to the input; collinear points are
///   merged, which turns the tiny joins of a dense outline into single miter points (about one
///   output point per input point there).
/// - Concave regions tighter than the offset are trimmed (no self-intersecting wire path).
///
/// The result keeps the input's rotational order, starts at the output vertex closest to
/// `points[0]` (the TE of a section) and ends with that point repeated, so it is explicitly
/// closed. `offset_mm = 0` returns the input closed the same way.
///
/// Positions closer than 1e-5 are merged by the offset algorithm, so the input should be in
/// mm (or similar) rather than metres.
///
/// # Errors
/// `offset_mm` NaN, infinite or negative; a non-finite point; fewer than 3 distinct points;
/// zero area; an offset with no result (only possible for clockwise input offset inwards).
pub fn offset_polyline(
    points: &[Point2<f64>],
    offset_mm: f64,
) -> Result<Vec<Point2<f64>>, KerfError> {
    if !(offset_mm.is_finite() && offset_mm >= 0.0) {
        return Err(KerfError::InvalidParameter {
            name: "offset_mm".into(),
            value: offset_mm,
            requirement: "finite and >= 0",
        });
    }
    if let Some(i) = points
        .iter()
        .position(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(KerfError::InvalidParameter {
            name: format!("points[{i}]"),
            value: if points[i].x.is_finite() {
                points[i].y
            } else {
                points[i].x
            },
            requirement: "finite",
        });
    }
    let mut ring = points.to_vec();
    ring.dedup();
    if ring.len() > 1 && ring.first() == ring.last() {
        ring.pop();
    }
    if ring.len() < 3 {
        return Err(KerfError::Offset(format!(
            "{} distinct points, need at least 3",
            ring.len()
        )));
    }
    let start = ring[0];
    if offset_mm > 0.0 {
        let mut pline = Polyline::with_capacity(ring.len(), true);
        for p in &ring {
            pline.add(p.x, p.y, 0.0);
        }
        if pline.area() == 0.0 {
            return Err(KerfError::Offset("zero enclosed area".into()));
        }
        let options = PlineOffsetOptions {
            handle_self_intersects: true,
            ..PlineOffsetOptions::new()
        };
        // cavalier_contours offsets positive distances to the left of travel; the wire goes right.
        let loops = pline.parallel_offset_opt(-offset_mm, &options);
        let outer = loops
            .iter()
            .filter(|l| l.vertex_count() >= 2)
            .max_by(|a, b| a.area().abs().total_cmp(&b.area().abs()))
            .ok_or_else(|| KerfError::Offset("the offset has no result".into()))?;
        ring = merge_collinear(flatten(outer));
    }
    // Start where the input starts (the trailing edge of a section), then close explicitly.
    let first = (0..ring.len())
        .min_by(|&a, &b| {
            nalgebra::distance_squared(&ring[a], &start)
                .total_cmp(&nalgebra::distance_squared(&ring[b], &start))
        })
        .unwrap_or(0);
    ring.rotate_left(first);
    ring.push(ring[0]);
    Ok(ring)
}

/// The closed polyline's vertices with each arc segment replaced by its circumscribed polygon.
fn flatten(pline: &Polyline<f64>) -> Vec<Point2<f64>> {
    let n = pline.vertex_count();
    let mut out = Vec::with_capacity(2 * n);
    for i in 0..n {
        let (v1, v2): (PlineVertex<f64>, PlineVertex<f64>) = (pline.at(i), pline.at((i + 1) % n));
        out.push(Point2::new(v1.x, v1.y));
        // A degenerate arc (end points fuzzy-equal) is a point; cavalier asserts against it.
        if v1.bulge == 0.0 || v1.pos().fuzzy_eq(v2.pos()) {
            continue;
        }
        let (radius, c) = seg_arc_radius_and_center(v1, v2);
        // Bulge = tan(sweep / 4); positive sweeps anticlockwise.
        let sweep = 4.0 * v1.bulge.atan();
        let steps = (sweep.abs() / MAX_ARC_STEP_RAD).ceil().max(1.0);
        let step = sweep / steps;
        // Vertices at angle midpoints on radius r / cos(θ/2): every chord is tangent to the arc.
        let r_out = radius / (step / 2.0).cos();
        let a0 = (v1.y - c.y).atan2(v1.x - c.x);
        for j in 0..steps as usize {
            let a = a0 + step * (j as f64 + 0.5);
            out.push(Point2::new(c.x + r_out * a.cos(), c.y + r_out * a.sin()));
        }
    }
    out
}

/// Drops points that continue the previous direction (cross product ≈ 0, same heading), e.g.
/// arc end points that lie on the straight offset segments either side of a one-step join.
fn merge_collinear(points: Vec<Point2<f64>>) -> Vec<Point2<f64>> {
    let n = points.len();
    if n < 4 {
        return points;
    }
    let mut keep = Vec::with_capacity(n);
    keep.push(points[0]);
    for i in 1..n {
        let (a, b, c) = (keep[keep.len() - 1], points[i], points[(i + 1) % n]);
        let (u, v) = (b - a, c - b);
        let straight = u.dot(&v) > 0.0 && u.perp(&v).abs() <= 1e-10 * u.norm() * v.norm();
        if !straight {
            keep.push(b);
        }
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_geometry::{point_segment_distance, segment_distance, signed_area, Norm};
    use proptest::prelude::*;

    /// Smallest distance between the closed polygons `path` and `outline` (segments, not just
    /// vertices).
    fn min_distance(path: &[Point2<f64>], outline: &[Point2<f64>]) -> f64 {
        let closed = |p: &[Point2<f64>]| {
            let mut v = p.to_vec();
            v.push(p[0]);
            v
        };
        let (p, q) = (closed(path), closed(outline));
        let mut best = f64::INFINITY;
        for s in p.windows(2) {
            for t in q.windows(2) {
                best = best.min(segment_distance(s[0], s[1], t[0], t[1], Norm::Sqrt));
            }
        }
        best
    }

    #[test]
    fn unit_square_offsets_outwards_with_round_corners() {
        let sq = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(x, y)| Point2::new(x, y));
        let out = offset_polyline(&sq, 0.1).unwrap();
        assert_eq!(out.first(), out.last(), "explicitly closed");
        let ring = &out[..out.len() - 1];
        let (min_x, max_x) = ring.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
            (lo.min(p.x), hi.max(p.x))
        });
        assert!(
            (min_x + 0.1).abs() < 1e-9 && (max_x - 1.1).abs() < 1e-9,
            "right of travel = outside"
        );
        let a = signed_area(ring);
        let exact = 1.0 + 4.0 * 0.1 + std::f64::consts::PI * 0.01;
        assert!(a > exact && a < exact * 1.001, "area {a} vs {exact}");
        assert!(min_distance(ring, &sq) >= 0.1 - 1e-9);
        assert!(
            nalgebra::distance(&out[0], &sq[0]) < 0.2,
            "starts near the input start"
        );
    }

    #[test]
    fn circle_offsets_to_larger_circle() {
        let (r, d) = (10.0, 2.0);
        let circle: Vec<_> = (0..720)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 720.0;
                Point2::new(r * a.cos(), r * a.sin())
            })
            .collect();
        let out = offset_polyline(&circle, d).unwrap();
        for p in &out {
            assert!(
                (p.coords.norm() - (r + d)).abs() < 1e-3,
                "{p} not on radius {}",
                r + d
            );
        }
        assert!(out.len() <= circle.len() + 2, "{} points", out.len());
    }

    #[test]
    fn foil_offset_stays_clear_and_compact() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../config/airfoils/s1223.dat"
        );
        let foil = crate::airfoil::Airfoil::load(path)
            .unwrap()
            .scaled(200.0)
            .unwrap();
        let d = 0.31;
        let out = offset_polyline(foil.points(), d).unwrap();
        let ring = &out[..out.len() - 1];
        assert!(min_distance(ring, foil.points()) >= d - 1e-9);
        assert!(
            signed_area(ring) > signed_area(foil.points()),
            "outside of an anticlockwise foil"
        );
        assert!(out.len() < 2 * foil.points().len(), "{} points", out.len());
        assert!(
            nalgebra::distance(&out[0], &foil.points()[0]) <= d * 1.01,
            "starts at the TE"
        );
    }

    #[test]
    fn zero_offset_and_bad_input() {
        let tri = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.0, 0.0)].map(|(x, y)| Point2::new(x, y));
        assert_eq!(offset_polyline(&tri, 0.0).unwrap(), tri.to_vec());
        assert!(offset_polyline(&tri, -1.0).is_err());
        assert!(offset_polyline(&tri, f64::NAN).is_err());
        assert!(offset_polyline(&tri[..2], 1.0).is_err());
        let flat = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)].map(|(x, y)| Point2::new(x, y));
        assert!(offset_polyline(&flat, 1.0).is_err());
        let nan = [Point2::new(0.0, f64::NAN); 4];
        let e = offset_polyline(&nan, 1.0).unwrap_err();
        assert!(e.to_string().starts_with("points[0]"), "{e}");
    }

    proptest! {
        #[test]
        fn convex_offset_keeps_its_distance(
            gaps in prop::collection::vec(0.05f64..1.0, 3..40),
            semi_axes in (1.0f64..100.0, 1.0f64..100.0),
            rotation in 0.0f64..std::f64::consts::TAU,
            d in 0.01f64..10.0,
        ) {
            let total: f64 = gaps.iter().sum();
            let (a, b) = semi_axes;
            let (s, c) = rotation.sin_cos();
            let mut angle = 0.0;
            let polygon: Vec<_> = gaps
                .iter()
                .map(|g| {
                    angle += g / total * std::f64::consts::TAU;
                    let (x, y) = (a * angle.cos(), b * angle.sin());
                    Point2::new(c * x - s * y, s * x + c * y)
                })
                .collect();
            let out = offset_polyline(&polygon, d).unwrap();
            let ring = &out[..out.len() - 1];
            let dist = min_distance(ring, &polygon);
            prop_assert!(dist >= d - 1e-9 * (1.0 + d), "min distance {dist} < {d}");
            // Nothing strays further than the flattened arcs allow.
            for p in ring {
                let far = polygon
                    .iter()
                    .zip(polygon.iter().cycle().skip(1))
                    .map(|(&u, &v)| point_segment_distance(*p, u, v, Norm::Sqrt))
                    .fold(f64::INFINITY, f64::min);
                prop_assert!(far <= d / (MAX_ARC_STEP_RAD / 2.0).cos() + 1e-9, "{far}");
            }
            prop_assert!(signed_area(ring) > signed_area(&polygon));
            prop_assert!(ring.len() <= 2 * polygon.len() + 40);
        }
    }
}
