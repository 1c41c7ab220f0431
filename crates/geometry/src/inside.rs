//! Point in ring: crossing number (even-odd) and winding number (non-zero).

use crate::distance::distance_to_rings;
use crate::point::{AsPoint2, Norm, Point2};

/// The ring's edges (a, b) in the order its points come, the closing edge last → first
/// included: (p₀, p₁), …, (pₙ₋₂, pₙ₋₁), (pₙ₋₁, p₀). One point gives the single zero-length
/// edge (p₀, p₀); no point gives none.
#[inline]
fn edges<P: AsPoint2>(ring: impl IntoIterator<Item = P>) -> impl Iterator<Item = (Point2, Point2)> {
    let mut points = ring.into_iter().map(AsPoint2::point2);
    let first = points.next();
    points
        .chain(first)
        .scan(first, |prev, b| prev.replace(b).map(|a| (a, b)))
}

/// Whether edge a → b crosses the horizontal ray from p towards +x, half-open in y: the edge
/// counts when exactly one end lies strictly above p (so a vertex at p's height counts as
/// below, and a ray through a vertex is counted once), and its crossing abscissa
/// x = aₓ + (p_y − a_y)/(b_y − a_y)·(bₓ − aₓ), interpolated from a, lies strictly right of p.
#[inline]
fn crosses_ray(p: Point2, a: Point2, b: Point2) -> bool {
    (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x)
}

/// Whether p lies inside the ring by the crossing-number (even-odd) rule: the ray from p
/// towards +x crosses the ring's edges an odd number of times. The ring is any sequence of
/// points (slice, `&Vec`, iterator), closing edge implied.
///
/// **Boundary rule.** Each edge a → b counts when exactly one end lies strictly above p (a
/// vertex at p's height counts as below, so a ray through a vertex is counted once) and the
/// crossing abscissa aₓ + (p_y − a_y)/(b_y − a_y)·(bₓ − aₓ) lies strictly right of p. So a
/// point exactly on the boundary is classified like a point displaced infinitesimally to the
/// right (and, on a horizontal edge, upwards): on the left or bottom side of a region it is
/// inside, on the right or top side outside. For the
/// counter-clockwise unit square: (0, ½), (½, 0) and the corner (0, 0) are inside; (1, ½),
/// (½, 1), (1, 0), (1, 1), (0, 1) are outside. This is exact when the crossing abscissa is
/// computed exactly (axis-parallel edges, p at a vertex the abscissa is interpolated from);
/// otherwise a point within rounding of an edge may go either way. The abscissa is
/// interpolated from each edge's first point in walk order, so walking the ring backwards
/// (`ring.iter().rev()`) gives the same answer except within rounding of an edge.
///
/// Degenerate cases: fewer than 3 points, collinear points and zero-length edges (including a
/// repeated closing point) never cross, so a ring without area contains nothing.
pub fn point_in_ring_even_odd<P: AsPoint2>(
    p: impl AsPoint2,
    ring: impl IntoIterator<Item = P>,
) -> bool {
    let p = p.point2();
    edges(ring).fold(false, |inside, (a, b)| inside ^ crosses_ray(p, a, b))
}

/// Whether p lies inside the region bounded by all `rings` (outer contours and holes, in any
/// orientation) by the even-odd rule over all their edges: the parity of the crossing counts
/// of [`point_in_ring_even_odd`] summed over the rings, so a point in a hole of an outer ring
/// is outside, and a point in an island inside that hole is inside again. Same boundary rule.
///
/// Degenerate cases: no rings contain nothing.
pub fn point_in_rings_even_odd<P: AsPoint2, R: AsRef<[P]>>(p: impl AsPoint2, rings: &[R]) -> bool {
    let p = p.point2();
    rings.iter().fold(false, |inside, r| {
        inside ^ point_in_ring_even_odd(p, r.as_ref())
    })
}

/// Whether p lies inside the region of `rings` ([`point_in_rings_even_odd`]) or within `eps`
/// of one of their edges ([`distance_to_rings`], lengths rounded by `norm`): the even-odd test
/// with the boundary made inclusive by a tolerance, for points computed on the boundary.
///
/// Degenerate cases: no rings give false; `eps < 0` leaves only the even-odd test.
pub fn point_in_rings_or_near<P: AsPoint2, R: AsRef<[P]>>(
    p: impl AsPoint2,
    rings: &[R],
    eps: f64,
    norm: Norm,
) -> bool {
    let p = p.point2();
    point_in_rings_even_odd(p, rings) || distance_to_rings(p, rings, norm) <= eps
}

/// Whether p lies strictly left of the directed line a → b: the cross product
/// (b − a) × (p − a) = (bₓ − aₓ)(p_y − a_y) − (b_y − a_y)(pₓ − aₓ) is positive.
#[inline]
fn is_left(a: Point2, b: Point2, p: Point2) -> bool {
    (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x) > 0.0
}

/// The winding number of the ring around p (Sunday's crossing rule, the same arithmetic as
/// `cavalier_contours`' `winding_number` on a polyline without arcs): every upward edge
/// (a_y ≤ p_y < b_y) with p strictly left of it adds 1, every downward edge
/// (b_y ≤ p_y < a_y) with p right of it or on its line subtracts 1. A counter-clockwise
/// simple ring winds +1 around its interior points, a clockwise one −1.
///
/// **Boundary rule.** Half-open in y like [`point_in_ring_even_odd`], but a point on an edge's
/// line counts as right of it, which a downward edge counts and an upward edge does not, so the
/// result on the boundary depends on orientation and is no displacement rule. For the
/// counter-clockwise unit square only the bottom edge's interior, e.g. (½, 0), gives 1, every
/// other boundary point (corners included) 0; for the clockwise square the left, bottom and
/// right edges and the corners (0, 0) and (1, 0) give −1, the top edge and its corners 0.
/// Callers that need a definite answer on the boundary test the distance to it first.
///
/// Degenerate cases: zero-length edges (including a repeated closing point) add nothing. A
/// ring without area (fewer than 3 points, or collinear points) winds 0 around every point off
/// its line, and −1 around the points of its segments that are not its topmost end: the
/// boundary rule counts the way down and not the way up.
pub fn winding_number<P: AsPoint2>(p: impl AsPoint2, ring: impl IntoIterator<Item = P>) -> i32 {
    let p = p.point2();
    edges(ring)
        .map(|(a, b)| {
            if a.y <= p.y {
                i32::from(b.y > p.y && is_left(a, b, p))
            } else if b.y <= p.y && !is_left(a, b, p) {
                -1
            } else {
                0
            }
        })
        .sum()
}

/// Whether p lies inside the ring by the non-zero rule: [`winding_number`] ≠ 0 (on a
/// self-intersecting ring, also inside where it winds twice). Same boundary rule and degenerate
/// cases as [`winding_number`] (so points on a ring without area can count as inside it).
pub fn point_in_ring_nonzero<P: AsPoint2>(
    p: impl AsPoint2,
    ring: impl IntoIterator<Item = P>,
) -> bool {
    winding_number(p, ring) != 0
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

    fn cw() -> Vec<[f64; 2]> {
        SQUARE.iter().rev().copied().collect()
    }

    #[test]
    fn interior_and_exterior_points() {
        for ring in [SQUARE.to_vec(), cw()] {
            assert!(point_in_ring_even_odd([0.5, 0.5], &ring));
            assert!(point_in_ring_nonzero([0.5, 0.5], &ring));
            for out in [[1.5, 0.5], [-0.5, 0.5], [0.5, 1.5], [0.5, -0.5]] {
                assert!(!point_in_ring_even_odd(out, &ring), "{out:?}");
                assert_eq!(winding_number(out, &ring), 0, "{out:?}");
            }
        }
        assert_eq!(winding_number([0.5, 0.5], SQUARE), 1);
        assert_eq!(winding_number([0.5, 0.5], cw()), -1);
        // Point2 rings and points, iterators of them.
        let pts: Vec<Point2> = SQUARE.iter().map(|p| p.point2()).collect();
        assert!(point_in_ring_even_odd(Point2::new(0.5, 0.5), &pts));
        assert!(point_in_ring_even_odd([0.5, 0.5], pts.iter().rev()));
    }

    #[test]
    fn even_odd_boundary_is_in_on_the_left_and_bottom() {
        for ring in [SQUARE.to_vec(), cw()] {
            for on in [[0.0, 0.5], [0.5, 0.0], [0.0, 0.0]] {
                assert!(point_in_ring_even_odd(on, &ring), "{on:?}");
                assert!(
                    point_in_ring_even_odd(on, ring.iter().rev()),
                    "{on:?} backwards"
                );
            }
            for on in [[1.0, 0.5], [0.5, 1.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
                assert!(!point_in_ring_even_odd(on, &ring), "{on:?}");
                assert!(
                    !point_in_ring_even_odd(on, ring.iter().rev()),
                    "{on:?} backwards"
                );
            }
        }
    }

    #[test]
    fn winding_boundary_depends_on_orientation() {
        let ccw_in = [[0.5, 0.0]];
        let cw_in = [[0.0, 0.5], [0.5, 0.0], [1.0, 0.5], [0.0, 0.0], [1.0, 0.0]];
        let boundary = [
            [0.0, 0.5],
            [0.5, 0.0],
            [1.0, 0.5],
            [0.5, 1.0],
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
        ];
        for on in boundary {
            let want = i32::from(ccw_in.contains(&on));
            assert_eq!(winding_number(on, SQUARE), want, "ccw {on:?}");
            let want = -i32::from(cw_in.contains(&on));
            assert_eq!(winding_number(on, cw()), want, "cw {on:?}");
        }
    }

    #[test]
    fn degenerate_rings_contain_nothing() {
        let empty: [[f64; 2]; 0] = [];
        let p = [0.0, 0.0];
        for ring in [&empty[..], &[[0.0, 0.0]][..]] {
            assert!(!point_in_ring_even_odd(p, ring));
            assert_eq!(winding_number(p, ring), 0);
        }
        // Two points and three collinear points: nothing inside by even-odd; the winding
        // number is 0 off the line and −1 on it below the top end.
        let segment = [[-1.0, -1.0], [1.0, 1.0]];
        let line = [[-1.0, -1.0], [0.0, 0.0], [1.0, 1.0]];
        for q in [
            [0.5, 0.0],
            [-0.5, 0.0],
            [2.0, 2.0],
            [1.0, 1.0],
            [0.0, 0.0],
            [-0.5, -0.5],
        ] {
            assert!(!point_in_ring_even_odd(q, segment), "{q:?}");
            assert!(!point_in_ring_even_odd(q, line), "{q:?}");
            let on_below_top = q[0] == q[1] && q[1] < 1.0;
            let want = -i32::from(on_below_top);
            assert_eq!(winding_number(q, segment), want, "{q:?}");
            assert_eq!(winding_number(q, line), want, "{q:?}");
        }
    }

    #[test]
    fn repeated_closing_point_changes_nothing() {
        let mut closed = SQUARE.to_vec();
        closed.push(SQUARE[0]);
        let probes = [
            [0.5, 0.5],
            [1.5, 0.5],
            [0.0, 0.5],
            [0.5, 0.0],
            [1.0, 0.5],
            [0.0, 0.0],
        ];
        for q in probes {
            assert_eq!(
                point_in_ring_even_odd(q, &closed),
                point_in_ring_even_odd(q, SQUARE),
                "{q:?}"
            );
            assert_eq!(
                winding_number(q, &closed),
                winding_number(q, SQUARE),
                "{q:?}"
            );
        }
    }

    #[test]
    fn self_intersecting_rings_split_the_rules() {
        // A ring that goes twice round the square: winding 2, even crossing count.
        let twice: Vec<[f64; 2]> = SQUARE.iter().chain(SQUARE.iter()).copied().collect();
        assert_eq!(winding_number([0.5, 0.5], &twice), 2);
        assert!(point_in_ring_nonzero([0.5, 0.5], &twice));
        assert!(!point_in_ring_even_odd([0.5, 0.5], &twice));
    }

    #[test]
    fn region_with_a_hole_and_an_island() {
        let outer = vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        let hole = vec![[2.0, 2.0], [2.0, 8.0], [8.0, 8.0], [8.0, 2.0]];
        let island = vec![[4.0, 4.0], [6.0, 4.0], [6.0, 6.0], [4.0, 6.0]];
        let rings = [outer, hole, island];
        assert!(point_in_rings_even_odd([1.0, 5.0], &rings));
        assert!(!point_in_rings_even_odd([3.0, 5.0], &rings));
        assert!(point_in_rings_even_odd([5.0, 5.0], &rings));
        assert!(!point_in_rings_even_odd([11.0, 5.0], &rings));
        let none: [Vec<[f64; 2]>; 0] = [];
        assert!(!point_in_rings_even_odd([5.0, 5.0], &none));
        // On the hole's right edge: outside by the half-open rule, inside within a tolerance.
        assert!(!point_in_rings_even_odd([2.0, 5.0], &rings));
        assert!(point_in_rings_or_near(
            [2.0, 5.0],
            &rings,
            1e-9,
            Norm::Hypot
        ));
        assert!(point_in_rings_or_near([3.0, 5.0], &rings, 1.0, Norm::Sqrt));
        assert!(!point_in_rings_or_near([3.0, 5.0], &rings, 0.5, Norm::Sqrt));
        assert!(!point_in_rings_or_near([5.0, 5.0], &none, 1.0, Norm::Sqrt));
    }
}
