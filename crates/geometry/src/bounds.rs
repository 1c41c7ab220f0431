//! Axis-aligned bounding box.

use crate::point::{AsPoint2, Point2};

/// The axis-aligned bounding box `(min, max)` of the points: componentwise minimum and maximum.
///
/// Degenerate cases: no points give `(+∞, +∞)` and `(−∞, −∞)` (an empty box every point is
/// outside of); NaN coordinates are ignored (`f64::min` and `max` skip NaN).
pub fn bounding_box<P: AsPoint2>(points: impl IntoIterator<Item = P>) -> (Point2, Point2) {
    let mut lo = Point2::new(f64::INFINITY, f64::INFINITY);
    let mut hi = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in points {
        let p = p.point2();
        lo = Point2::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point2::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_of_points_and_of_nothing() {
        let (lo, hi) = bounding_box([[1.0, -2.0], [-3.0, 4.0], [0.5, f64::NAN]]);
        assert_eq!((lo, hi), (Point2::new(-3.0, -2.0), Point2::new(1.0, 4.0)));
        let (lo, hi) = bounding_box(std::iter::empty::<[f64; 2]>());
        assert!(lo.x == f64::INFINITY && lo.y == f64::INFINITY);
        assert!(hi.x == f64::NEG_INFINITY && hi.y == f64::NEG_INFINITY);
        // One point: a zero-size box at the point.
        assert_eq!(
            bounding_box([[2.0, 3.0]]),
            (Point2::new(2.0, 3.0), Point2::new(2.0, 3.0))
        );
    }
}
