//! Signed area of a ring and its orientation.

use crate::point::AsPoint2;

/// The shoelace sum Σᵢ (xᵢ yᵢ₊₁ − xᵢ₊₁ yᵢ) over the edges i → i+1 (mod n), summed in edge
/// order: twice the signed area.
#[inline]
fn twice_signed_area<P: AsPoint2>(ring: &[P]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| {
            let (a, b) = (ring[i].point2(), ring[(i + 1) % n].point2());
            a.x * b.y - b.x * a.y
        })
        .sum::<f64>()
}

/// Signed area of the ring by the shoelace formula, A = ½ Σᵢ (xᵢ yᵢ₊₁ − xᵢ₊₁ yᵢ) with the
/// closing edge implied (i + 1 taken mod n), summed in edge order: positive for a
/// counter-clockwise ring, negative for a clockwise one (y up).
///
/// Degenerate cases: an empty ring, one point or two points give exactly 0 (the terms cancel
/// exactly); collinear points give 0 up to rounding; a repeated closing point adds a zero term.
/// The products are taken about the origin, so far from it the result loses digits to
/// cancellation (a unit square 1e9 from the origin gets area 0); see
/// [`signed_area_from_first_vertex`].
pub fn signed_area<P: AsPoint2>(ring: &[P]) -> f64 {
    twice_signed_area(ring) / 2.0
}

/// Signed area of the ring as a fan of triangles from its first vertex o:
/// A = ½ Σᵢ₌₁ⁿ⁻² (pᵢ − o) × (pᵢ₊₁ − o), the same area as [`signed_area`] in exact arithmetic
/// but with products about o, so a small ring far from the origin keeps its digits.
///
/// Degenerate cases: fewer than 3 points give exactly 0; collinear points give 0 up to
/// rounding; a repeated closing point adds a zero-area triangle.
pub fn signed_area_from_first_vertex<P: AsPoint2>(ring: &[P]) -> f64 {
    let n = ring.len();
    if n < 3 {
        return 0.0;
    }
    let o = ring[0].point2();
    let mut twice = 0.0;
    for i in 1..n - 1 {
        let (a, b) = (ring[i].point2(), ring[i + 1].point2());
        twice += (a.x - o.x) * (b.y - o.y) - (b.x - o.x) * (a.y - o.y);
    }
    0.5 * twice
}

/// Which way a ring turns (y up).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Orientation {
    /// Positive signed area.
    CounterClockwise,
    /// Negative signed area.
    Clockwise,
    /// Zero (fewer than 3 points, or collinear points whose shoelace sum rounds to 0) or NaN.
    Degenerate,
}

/// The ring's orientation: the sign of its shoelace sum (twice [`signed_area`], so exactly the
/// sign the area has, without the halving).
///
/// Degenerate cases: fewer than 3 points, an exactly cancelling sum, or a non-finite
/// coordinate give [`Orientation::Degenerate`].
pub fn orientation<P: AsPoint2>(ring: &[P]) -> Orientation {
    let twice = twice_signed_area(ring);
    if twice > 0.0 {
        Orientation::CounterClockwise
    } else if twice < 0.0 {
        Orientation::Clockwise
    } else {
        Orientation::Degenerate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::point::Point2;

    const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

    fn reversed(r: &[[f64; 2]]) -> Vec<[f64; 2]> {
        r.iter().rev().copied().collect()
    }

    #[test]
    fn unit_square_both_ways() {
        for area in [signed_area::<[f64; 2]>, signed_area_from_first_vertex] {
            assert_eq!(area(&SQUARE), 1.0);
            assert_eq!(area(&reversed(&SQUARE)), -1.0);
        }
        assert_eq!(orientation(&SQUARE), Orientation::CounterClockwise);
        assert_eq!(orientation(&reversed(&SQUARE)), Orientation::Clockwise);
        // Point2 and references take the same path.
        let pts: Vec<Point2> = SQUARE.iter().map(|p| p.point2()).collect();
        assert_eq!(signed_area(&pts), 1.0);
        let refs: Vec<&[f64; 2]> = SQUARE.iter().collect();
        assert_eq!(signed_area(&refs), 1.0);
    }

    #[test]
    fn fewer_than_three_points_have_no_area() {
        let empty: [[f64; 2]; 0] = [];
        for ring in [&empty[..], &SQUARE[..1], &SQUARE[..2]] {
            assert_eq!(signed_area(ring), 0.0);
            assert_eq!(signed_area_from_first_vertex(ring), 0.0);
            assert_eq!(orientation(ring), Orientation::Degenerate);
        }
        // Two far-apart points: the two shoelace terms cancel exactly.
        let two = [[1e8 + 0.1, 3.3], [-7.7, 1e-3]];
        assert_eq!(signed_area(&two), 0.0);
    }

    #[test]
    fn collinear_points_are_degenerate() {
        let line = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
        assert_eq!(signed_area(&line), 0.0);
        assert_eq!(signed_area_from_first_vertex(&line), 0.0);
        assert_eq!(orientation(&line), Orientation::Degenerate);
        // A repeated point (zero-length edge) inside a proper ring changes nothing.
        let doubled = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(signed_area(&doubled), 1.0);
        assert_eq!(
            orientation(&[[0.0, 0.0], [f64::NAN, 1.0], [1.0, 1.0]]),
            Orientation::Degenerate
        );
    }

    #[test]
    fn repeated_closing_point_changes_nothing() {
        let mut closed = SQUARE.to_vec();
        closed.push(SQUARE[0]);
        assert_eq!(signed_area(&closed), 1.0);
        assert_eq!(signed_area_from_first_vertex(&closed), 1.0);
        assert_eq!(orientation(&closed), Orientation::CounterClockwise);
    }

    #[test]
    fn the_fan_keeps_digits_far_from_the_origin() {
        let far: Vec<[f64; 2]> = SQUARE.iter().map(|p| [p[0] + 1e9, p[1] + 1e9]).collect();
        assert_eq!(signed_area_from_first_vertex(&far), 1.0);
        // The shoelace products about the origin cancel completely there.
        assert_eq!(signed_area(&far), 0.0);
        // Triangle with a hole-like (clockwise) winding: −½.
        assert_eq!(signed_area(&[[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]), -0.5);
    }
}
