//! Polyline and ring lengths, and resampling by step or by arc length.

use crate::point::{AsPoint2, Norm, Point2, Point3};

/// Length of the open polyline, Σᵢ ‖pᵢ₊₁ − pᵢ‖ (no closing edge), summed in order, each edge
/// rounded by `norm`.
///
/// Degenerate cases: no point or one point give 0; zero-length edges (repeated points) add 0.
pub fn polyline_length<P: AsPoint2>(points: &[P], norm: Norm) -> f64 {
    points.windows(2).map(|w| norm.distance(w[0], w[1])).sum()
}

/// Distance ‖b − a‖ between two points in space: √(dx² + dy² + dz²), the squares summed in
/// x, y, z order (nalgebra's `distance`). Degenerate case: equal points give 0.
pub fn distance3(a: impl Into<Point3>, b: impl Into<Point3>) -> f64 {
    nalgebra::distance(&a.into(), &b.into())
}

/// Length of the open polyline in space, Σᵢ ‖pᵢ₊₁ − pᵢ‖ ([`distance3`] per edge, summed in
/// order). Degenerate cases: no point or one point give 0; repeated points add 0.
pub fn polyline_length3<P: Copy + Into<Point3>>(points: &[P]) -> f64 {
    points.windows(2).map(|w| distance3(w[0], w[1])).sum()
}

/// Perimeter of the ring, Σᵢ ‖pᵢ₊₁ − pᵢ‖ with the closing edge pₙ₋₁ → p₀ included, summed in
/// edge order, each edge rounded by `norm`.
///
/// Degenerate cases: no point or one point give 0; two points give twice their distance; a
/// repeated closing point adds a zero-length edge.
pub fn ring_perimeter<P: AsPoint2>(ring: &[P], norm: Norm) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| norm.distance(ring[i], ring[(i + 1) % n]))
        .sum()
}

/// Cumulative arc length at each point of the open polyline: s₀ = 0, sᵢ₊₁ = sᵢ + ‖pᵢ₊₁ − pᵢ‖
/// (edges rounded by `norm`), one entry per point; the last is [`polyline_length`].
///
/// Degenerate cases: no point gives `[0]` (one entry, not none); repeated points repeat sᵢ.
pub fn cumulative_lengths<P: AsPoint2>(points: &[P], norm: Norm) -> Vec<f64> {
    let mut cum = Vec::with_capacity(points.len());
    let mut s = 0.0;
    cum.push(0.0);
    for w in points.windows(2) {
        s += norm.distance(w[0], w[1]);
        cum.push(s);
    }
    cum
}

/// The open polyline with points inserted so that no piece is longer than `max_step`: edge
/// a → b of length l (rounded by `norm`) is split into k = max(⌈l / max_step⌉, 1) equal pieces,
/// giving a + (j/k)(b − a) for j = 0 … k−1; the last input point ends the output. Every input
/// point is kept exactly.
///
/// Degenerate cases: no point gives none, one point gives itself; a zero-length edge keeps
/// its repeated point (k = 1). `max_step` must be positive (0 or less would ask for infinitely
/// many points; debug builds panic); NaN splits nothing.
pub fn resample_max_step<P: AsPoint2 + From<Point2>>(
    points: &[P],
    max_step: f64,
    norm: Norm,
) -> Vec<P> {
    debug_assert!(
        max_step > 0.0 || max_step.is_nan(),
        "resample_max_step: max_step {max_step} must be positive"
    );
    let mut out = Vec::with_capacity(points.len());
    for w in points.windows(2) {
        let (a, b) = (w[0].point2(), w[1].point2());
        let l = norm.distance(a, b);
        let k = (l / max_step).ceil().max(1.0) as usize;
        for j in 0..k {
            let t = j as f64 / k as f64;
            out.push(P::from(Point2::new(
                a.x + t * (b.x - a.x),
                a.y + t * (b.y - a.y),
            )));
        }
    }
    if let Some(&last) = points.last() {
        out.push(last);
    }
    out
}

/// Points of the open polyline at the given arc-length `fractions` (0 … 1 of its total length
/// L, ascending): fraction f lands at arc length s = f·L on the edge i with sᵢ ≤ s ≤ sᵢ₊₁
/// ([`cumulative_lengths`], rounded by `norm`), at pᵢ + t(pᵢ₊₁ − pᵢ), t = (s − sᵢ)/(sᵢ₊₁ − sᵢ)
/// clamped to 0 … 1. The search only moves forward, so unsorted fractions are placed no
/// earlier than the previous one's edge.
///
/// Degenerate cases: no point gives none; one point gives it for every fraction; fractions
/// ≤ 0 and ≥ 1 give the first and last point exactly; a zero-length edge is skipped over
/// (t = 0 on it); a polyline of zero length gives its first point for fractions in (0, 1).
pub fn sample_at_arc_fractions<P: AsPoint2 + From<Point2>>(
    points: &[P],
    fractions: &[f64],
    norm: Norm,
) -> Vec<P> {
    let (first, last) = match points {
        [] => return Vec::new(),
        [p] => return vec![*p; fractions.len()],
        [first, .., last] => (*first, *last),
    };
    let cum = cumulative_lengths(points, norm);
    let total = cum[cum.len() - 1];
    let mut seg = 0;
    fractions
        .iter()
        .map(|&f| {
            if f <= 0.0 {
                return first;
            }
            if f >= 1.0 {
                return last;
            }
            let s = f * total;
            while seg + 2 < points.len() && cum[seg + 1] < s {
                seg += 1;
            }
            let len = cum[seg + 1] - cum[seg];
            let t = if len > 0.0 { (s - cum[seg]) / len } else { 0.0 };
            let t = t.clamp(0.0, 1.0);
            let (a, b) = (points[seg].point2(), points[seg + 1].point2());
            P::from(Point2::new(a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t))
        })
        .collect()
}

/// The point at arc length `s` along the open polyline: on the first edge a → b of non-zero
/// length l (rounded by `norm`) with s ≤ l, after subtracting the lengths of the edges before
/// it, at a + (s/l)(b − a).
///
/// Degenerate cases: s = 0 gives the start of the first edge of non-zero length, and a
/// negative s extrapolates backwards along it; s beyond the length, one point, or only
/// zero-length edges give the last point; no point gives the origin.
pub fn point_at_arc_length<P: AsPoint2 + From<Point2>>(points: &[P], s: f64, norm: Norm) -> P {
    let mut s = s;
    for w in points.windows(2) {
        let (a, b) = (w[0].point2(), w[1].point2());
        let len = norm.distance(a, b);
        if s <= len && len > 0.0 {
            let f = s / len;
            return P::from(Point2::new(a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)));
        }
        s -= len;
    }
    points
        .last()
        .copied()
        .unwrap_or_else(|| P::from(Point2::origin()))
}

/// The ring as an explicitly closed polyline (first point repeated at the end) that starts at
/// arc length `shift` (taken mod the perimeter, so negative shifts count backwards) from the
/// ring's lowest-leftmost vertex: least x + y, then least x. That start does not depend on
/// which vertex the ring happened to begin with. Lengths are rounded by `norm`.
///
/// The start point is interpolated on its edge; when it falls on a vertex (within rounding,
/// t = 0) that vertex is the start. Consecutive points closer than 1e-12 are merged.
///
/// Degenerate cases: an empty ring gives an empty polyline (no start point to close on); a
/// ring of zero perimeter (one point, or all points equal) ignores `shift` and is returned as
/// it is, closed by repeating its first point; in any other ring a repeated closing point or
/// other zero-length edge is merged away.
pub fn closed_from_arc_length<P: AsPoint2 + From<Point2>>(
    ring: &[P],
    shift: f64,
    norm: Norm,
) -> Vec<P> {
    let n = ring.len();
    if n == 0 {
        return Vec::new();
    }
    let key = |p: &P| {
        let p = p.point2();
        (p.x + p.y, p.x)
    };
    let first = (0..n)
        .min_by(|&a, &b| {
            key(&ring[a])
                .partial_cmp(&key(&ring[b]))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .unwrap_or(0);
    let mut r: Vec<P> = ring[first..]
        .iter()
        .chain(&ring[..first])
        .copied()
        .collect();
    let perimeter: f64 = (0..n).map(|i| norm.distance(r[i], r[(i + 1) % n])).sum();
    let mut s = if perimeter > 0.0 {
        shift.rem_euclid(perimeter)
    } else {
        0.0
    };
    for i in 0..n {
        let (a, b) = (r[i].point2(), r[(i + 1) % n].point2());
        let l = norm.distance(a, b);
        if s < l {
            let t = s / l;
            let start = P::from(Point2::new(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)));
            let mut out = Vec::with_capacity(n + 2);
            out.push(start);
            if t > 0.0 {
                out.extend(r[i + 1..].iter().chain(&r[..=i]).copied());
            } else {
                out.extend(r[i + 1..].iter().chain(&r[..i]).copied());
                // `start` is vertex i itself; the loop returns to it below.
            }
            if norm.distance(*out.last().unwrap_or(&start), start) > 1e-12 {
                out.push(start);
            }
            out.dedup_by(|x, y| norm.distance(*x, *y) < 1e-12);
            return out;
        }
        s -= l;
    }
    r.push(r[0]);
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn space_lengths_and_their_degenerate_cases() {
        assert_eq!(distance3([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]), 0.0);
        assert_eq!(distance3([0.0, 0.0, 0.0], [2.0, 3.0, 6.0]), 7.0);
        assert_eq!(distance3([2.0, 3.0, 6.0], [0.0, 0.0, 0.0]), 7.0);
        assert_eq!(polyline_length3::<[f64; 3]>(&[]), 0.0);
        assert_eq!(polyline_length3(&[[5.0, 5.0, 5.0]]), 0.0);
        let path = [
            [0.0, 0.0, 0.0],
            [2.0, 3.0, 6.0],
            [2.0, 3.0, 6.0],
            [2.0, 3.0, 7.5],
        ];
        assert_eq!(polyline_length3(&path), 8.5);
    }

    #[test]
    fn lengths_of_polylines_and_rings() {
        let square = [[0.0, 0.0], [3.0, 0.0], [3.0, 4.0], [0.0, 4.0]];
        for norm in [Norm::Sqrt, Norm::Hypot] {
            assert_eq!(polyline_length(&square, norm), 10.0);
            assert_eq!(ring_perimeter(&square, norm), 14.0);
            assert_eq!(cumulative_lengths(&square, norm), vec![0.0, 3.0, 7.0, 10.0]);
            // Repeated closing point: the polyline closes, the ring gains a zero edge.
            let mut closed = square.to_vec();
            closed.push(square[0]);
            assert_eq!(polyline_length(&closed, norm), 14.0);
            assert_eq!(ring_perimeter(&closed, norm), 14.0);
        }
        let empty: [[f64; 2]; 0] = [];
        assert_eq!(polyline_length(&empty, Norm::Sqrt), 0.0);
        assert_eq!(polyline_length(&square[..1], Norm::Sqrt), 0.0);
        assert_eq!(ring_perimeter(&empty, Norm::Sqrt), 0.0);
        assert_eq!(ring_perimeter(&square[..1], Norm::Sqrt), 0.0);
        assert_eq!(ring_perimeter(&[[0.0, 0.0], [3.0, 4.0]], Norm::Sqrt), 10.0);
        assert_eq!(cumulative_lengths(&empty, Norm::Sqrt), vec![0.0]);
        // Repeated points: zero-length edges.
        assert_eq!(
            cumulative_lengths(&[[1.0, 1.0], [1.0, 1.0], [1.0, 2.0]], Norm::Sqrt),
            vec![0.0, 0.0, 1.0]
        );
    }

    #[test]
    fn resampling_by_step_keeps_the_input_points() {
        let pts = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.25]];
        let r = resample_max_step(&pts, 0.3, Norm::Hypot);
        assert_eq!(
            r,
            vec![
                [0.0, 0.0],
                [0.25, 0.0],
                [0.5, 0.0],
                [0.75, 0.0],
                [1.0, 0.0],
                [1.0, 0.25]
            ]
        );
        // Point2 in, Point2 out.
        let p2: Vec<Point2> = pts.iter().map(|p| p.point2()).collect();
        assert_eq!(resample_max_step(&p2, 0.3, Norm::Sqrt).len(), 6);
        // Degenerate: nothing, one point, a zero-length edge.
        let empty: [[f64; 2]; 0] = [];
        assert!(resample_max_step(&empty, 0.5, Norm::Hypot).is_empty());
        assert_eq!(
            resample_max_step(&pts[..1], 0.5, Norm::Hypot),
            vec![[0.0, 0.0]]
        );
        assert_eq!(
            resample_max_step(&[[2.0, 2.0], [2.0, 2.0]], 0.5, Norm::Hypot),
            vec![[2.0, 2.0], [2.0, 2.0]]
        );
        // NaN step: no splitting.
        assert_eq!(resample_max_step(&pts, f64::NAN, Norm::Hypot), pts.to_vec());
    }

    #[test]
    #[should_panic(expected = "must be positive")]
    #[cfg(debug_assertions)]
    fn resampling_by_a_zero_step_is_refused_in_debug_builds() {
        resample_max_step(&[[0.0, 0.0], [1.0, 0.0]], 0.0, Norm::Hypot);
    }

    #[test]
    fn sampling_at_arc_fractions() {
        let pts = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]];
        let r = sample_at_arc_fractions(&pts, &[-1.0, 0.0, 0.25, 0.5, 0.75, 1.0, 2.0], Norm::Sqrt);
        assert_eq!(
            r,
            vec![
                [0.0, 0.0],
                [0.0, 0.0],
                [1.0, 0.0],
                [2.0, 0.0],
                [2.0, 1.0],
                [2.0, 2.0],
                [2.0, 2.0]
            ]
        );
        // Degenerate: nothing, one point, zero length, a zero-length edge.
        let empty: [[f64; 2]; 0] = [];
        assert!(sample_at_arc_fractions(&empty, &[0.5], Norm::Sqrt).is_empty());
        assert_eq!(
            sample_at_arc_fractions(&pts[..1], &[0.2, 0.7], Norm::Sqrt),
            vec![[0.0, 0.0]; 2]
        );
        let flat = [[1.0, 1.0], [1.0, 1.0]];
        assert_eq!(
            sample_at_arc_fractions(&flat, &[0.5], Norm::Sqrt),
            vec![[1.0, 1.0]]
        );
        let doubled = [[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 2.0]];
        assert_eq!(
            sample_at_arc_fractions(&doubled, &[0.25, 0.5, 0.75], Norm::Sqrt),
            vec![[1.0, 0.0], [2.0, 0.0], [2.0, 1.0]]
        );
    }

    #[test]
    fn points_at_arc_lengths() {
        let pts = [[0.0, 0.0], [0.0, 0.0], [2.0, 0.0], [2.0, 2.0]];
        let at = |s| point_at_arc_length(&pts, s, Norm::Hypot);
        assert_eq!(at(1.0), [1.0, 0.0]);
        assert_eq!(at(3.0), [2.0, 1.0]);
        // On a vertex: the end of the edge it closes.
        assert_eq!(at(2.0), [2.0, 0.0]);
        // Before the start (the zero-length first edge is skipped) and past the end.
        assert_eq!(at(-1.0), [-1.0, 0.0]);
        assert_eq!(at(0.0), [0.0, 0.0]);
        assert_eq!(at(9.0), [2.0, 2.0]);
        // Degenerate: one point, only zero-length edges, nothing.
        assert_eq!(point_at_arc_length(&pts[..1], 1.0, Norm::Hypot), [0.0, 0.0]);
        assert_eq!(
            point_at_arc_length(&[[3.0, 3.0]; 3], 0.5, Norm::Hypot),
            [3.0, 3.0]
        );
        let empty: [Point2; 0] = [];
        assert_eq!(
            point_at_arc_length(&empty, 1.0, Norm::Sqrt),
            Point2::origin()
        );
    }

    #[test]
    fn closed_from_arc_length_starts_at_the_lowest_left_vertex() {
        // Begins at (4, 4); the lowest-leftmost vertex is (0, 0).
        let sq = [[4.0, 4.0], [0.0, 4.0], [0.0, 0.0], [4.0, 0.0]];
        let c = closed_from_arc_length(&sq, 0.0, Norm::Hypot);
        assert_eq!(
            c,
            vec![[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0], [0.0, 0.0]]
        );
        // Shifted along the first edge, and backwards (mod the perimeter 16).
        let c = closed_from_arc_length(&sq, 1.0, Norm::Hypot);
        assert_eq!(c.first(), Some(&[1.0, 0.0]));
        assert_eq!(c.last(), Some(&[1.0, 0.0]));
        assert_eq!(c.len(), 6);
        assert_eq!(
            closed_from_arc_length(&sq, -1.0, Norm::Hypot)[0],
            [0.0, 1.0]
        );
        // Onto a vertex: that vertex starts, no duplicate.
        let c = closed_from_arc_length(&sq, 4.0, Norm::Hypot);
        assert_eq!(
            c,
            vec![[4.0, 0.0], [4.0, 4.0], [0.0, 4.0], [0.0, 0.0], [4.0, 0.0]]
        );
        // A repeated closing point in the input is merged away.
        let mut closed = sq.to_vec();
        closed.push(sq[0]);
        assert_eq!(
            closed_from_arc_length(&closed, 0.0, Norm::Hypot),
            closed_from_arc_length(&sq, 0.0, Norm::Hypot)
        );
        // Degenerate: empty, one point, zero perimeter.
        let empty: [[f64; 2]; 0] = [];
        assert!(closed_from_arc_length(&empty, 1.0, Norm::Hypot).is_empty());
        assert_eq!(
            closed_from_arc_length(&[[2.0, 3.0]], 5.0, Norm::Hypot),
            vec![[2.0, 3.0], [2.0, 3.0]]
        );
        assert_eq!(
            closed_from_arc_length(&[[1.0, 1.0], [1.0, 1.0]], 5.0, Norm::Hypot),
            vec![[1.0, 1.0], [1.0, 1.0], [1.0, 1.0]]
        );
    }
}
