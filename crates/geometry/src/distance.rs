//! Distances from a point to a segment, between segments, and from a point to ring edges.

use crate::point::{AsPoint2, Norm, Point2};

/// The point of segment a–b nearest to p: a + t·(b − a) with
/// t = clamp(((p − a)·(b − a)) / ‖b − a‖², 0, 1), the foot of the perpendicular from p, or the
/// nearer end when the foot falls outside the segment.
///
/// Degenerate cases: a zero-length segment (a = b, or ‖b − a‖² underflowing to 0) or a NaN
/// ‖b − a‖² gives a itself.
#[inline]
pub fn closest_point_on_segment(p: impl AsPoint2, a: impl AsPoint2, b: impl AsPoint2) -> Point2 {
    let (p, a, b) = (p.point2(), a.point2(), b.point2());
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let l2 = dx * dx + dy * dy;
    if l2 > 0.0 {
        let t = (((p.x - a.x) * dx + (p.y - a.y) * dy) / l2).clamp(0.0, 1.0);
        Point2::new(a.x + t * dx, a.y + t * dy)
    } else {
        a
    }
}

/// Distance from p to the segment a–b: ‖p − q‖ for q the [`closest_point_on_segment`],
/// rounded by `norm`.
///
/// Degenerate cases: a zero-length segment gives the distance to a; p on the segment gives 0
/// (up to rounding of the foot when the segment is not axis-parallel).
#[inline]
pub fn point_segment_distance(
    p: impl AsPoint2,
    a: impl AsPoint2,
    b: impl AsPoint2,
    norm: Norm,
) -> f64 {
    let p = p.point2();
    norm.distance(p, closest_point_on_segment(p, a, b))
}

/// Orientation of the triangle p, q, r: (q − p) × (r − p), positive when r lies left of p → q.
#[inline]
fn orient(p: Point2, q: Point2, r: Point2) -> f64 {
    (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x)
}

/// Distance between the segments a–b and c–d: 0 when they cross or touch, otherwise the least
/// of the four endpoint-to-segment distances ([`point_segment_distance`]; for two segments
/// that do not meet, the nearest pair of points always includes an endpoint).
///
/// "Cross or touch" is the sign test on the four orientations d₁ = cd×a, d₂ = cd×b,
/// d₃ = ab×c, d₄ = ab×d: d₁d₂ ≤ 0 and d₃d₄ ≤ 0, not all four zero.
///
/// Degenerate cases: collinear segments (all four orientations 0), overlapping or not, and
/// zero-length segments fall through to the endpoint distances, which are 0 (up to rounding)
/// when they overlap or a point lies on the other segment.
pub fn segment_distance(
    a: impl AsPoint2,
    b: impl AsPoint2,
    c: impl AsPoint2,
    d: impl AsPoint2,
    norm: Norm,
) -> f64 {
    let (a, b, c, d) = (a.point2(), b.point2(), c.point2(), d.point2());
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && (d1 != 0.0 || d2 != 0.0 || d3 != 0.0 || d4 != 0.0) {
        return 0.0;
    }
    point_segment_distance(a, c, d, norm)
        .min(point_segment_distance(b, c, d, norm))
        .min(point_segment_distance(c, a, b, norm))
        .min(point_segment_distance(d, a, b, norm))
}

/// Distance from p to the nearest edge of any of the `rings` (closing edges included):
/// the least [`point_segment_distance`] over all edges.
///
/// Degenerate cases: no rings (or only empty ones) give +∞; a one-point ring is the distance
/// to that point.
pub fn distance_to_rings<P: AsPoint2, R: AsRef<[P]>>(
    p: impl AsPoint2,
    rings: &[R],
    norm: Norm,
) -> f64 {
    let p = p.point2();
    let mut best = f64::INFINITY;
    for r in rings {
        let r = r.as_ref();
        for i in 0..r.len() {
            best = best.min(point_segment_distance(p, r[i], r[(i + 1) % r.len()], norm));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_to_segment_inside_beyond_and_on() {
        for norm in [Norm::Sqrt, Norm::Hypot] {
            let (a, b) = ([0.0, 0.0], [4.0, 0.0]);
            assert_eq!(point_segment_distance([2.0, 3.0], a, b, norm), 3.0);
            // Beyond either end: the distance to that end.
            assert_eq!(point_segment_distance([7.0, 4.0], a, b, norm), 5.0);
            assert_eq!(point_segment_distance([-3.0, -4.0], a, b, norm), 5.0);
            // On the segment, at a vertex.
            assert_eq!(point_segment_distance([1.5, 0.0], a, b, norm), 0.0);
            assert_eq!(point_segment_distance(b, a, b, norm), 0.0);
            // Zero-length segment: the distance to the point.
            assert_eq!(point_segment_distance([3.0, 4.0], a, a, norm), 5.0);
        }
        assert_eq!(
            closest_point_on_segment([5.0, 5.0], [1.0, 1.0], [1.0, 1.0]),
            Point2::new(1.0, 1.0)
        );
        assert_eq!(
            closest_point_on_segment([1.0, 9.0], [0.0, 0.0], [2.0, 2.0]),
            Point2::new(2.0, 2.0)
        );
    }

    #[test]
    fn the_norms_round_alike_on_the_foot_and_may_differ_last_on_the_length() {
        let (p, a, b) = ([0.3, 0.7], [-1.1, 0.2], [2.9, -0.4]);
        let q = closest_point_on_segment(p, a, b);
        assert_eq!(
            point_segment_distance(p, a, b, Norm::Sqrt),
            nalgebra::distance(&q, &p.point2())
        );
        assert_eq!(
            point_segment_distance(p, a, b, Norm::Hypot),
            (p[0] - q.x).hypot(p[1] - q.y)
        );
    }

    #[test]
    fn segments_crossing_touching_parallel_and_collinear() {
        let n = Norm::Sqrt;
        // Crossing.
        assert_eq!(
            segment_distance([0.0, 0.0], [2.0, 2.0], [0.0, 2.0], [2.0, 0.0], n),
            0.0
        );
        // Touching at an endpoint (T junction).
        assert_eq!(
            segment_distance([0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 3.0], n),
            0.0
        );
        // Parallel, 1 apart.
        assert_eq!(
            segment_distance([0.0, 0.0], [2.0, 0.0], [0.0, 1.0], [2.0, 1.0], n),
            1.0
        );
        // Collinear: overlapping gives 0, apart gives the gap.
        assert_eq!(
            segment_distance([0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [3.0, 0.0], n),
            0.0
        );
        assert_eq!(
            segment_distance([0.0, 0.0], [1.0, 0.0], [3.0, 0.0], [4.0, 0.0], n),
            2.0
        );
        // Zero-length segments: point to segment, point to point.
        assert_eq!(
            segment_distance([1.0, 1.0], [1.0, 1.0], [0.0, 0.0], [2.0, 0.0], n),
            1.0
        );
        assert_eq!(
            segment_distance([0.0, 0.0], [0.0, 0.0], [3.0, 4.0], [3.0, 4.0], n),
            5.0
        );
    }

    #[test]
    fn distance_to_ring_edges() {
        let sq = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]];
        let rings = [sq.clone()];
        assert_eq!(distance_to_rings([1.0, 2.0], &rings, Norm::Hypot), 1.0);
        // The closing edge counts.
        assert_eq!(distance_to_rings([-0.5, 2.0], &rings, Norm::Hypot), 0.5);
        let mut closed = sq;
        closed.push([0.0, 0.0]);
        assert_eq!(distance_to_rings([-0.5, 2.0], &[closed], Norm::Hypot), 0.5);
        let none: [Vec<[f64; 2]>; 0] = [];
        assert_eq!(
            distance_to_rings([0.0, 0.0], &none, Norm::Hypot),
            f64::INFINITY
        );
        assert_eq!(
            distance_to_rings([0.0, 0.0], &[vec![[3.0, 4.0]]], Norm::Sqrt),
            5.0
        );
    }
}
