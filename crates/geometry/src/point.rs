//! The point types, the conversion every routine accepts, and the two roundings of a length.

/// A point in the plane (mm in every caller): nalgebra's `Point2<f64>`.
pub type Point2 = nalgebra::Point2<f64>;

/// A point in space (mm in every caller): nalgebra's `Point3<f64>`.
pub type Point3 = nalgebra::Point3<f64>;

/// Anything the routines accept as a plane point: [`Point2`], `[f64; 2]` (`[x, y]`), and
/// references to either (so slices and their iterators can be passed as they are).
pub trait AsPoint2: Copy {
    /// The point as a [`Point2`] (a copy of its two coordinates, nothing computed).
    fn point2(self) -> Point2;
}

impl AsPoint2 for Point2 {
    #[inline]
    fn point2(self) -> Point2 {
        self
    }
}

impl AsPoint2 for [f64; 2] {
    #[inline]
    fn point2(self) -> Point2 {
        Point2::new(self[0], self[1])
    }
}

impl<T: AsPoint2> AsPoint2 for &T {
    #[inline]
    fn point2(self) -> Point2 {
        (*self).point2()
    }
}

/// How the length √(dx² + dy²) of a difference vector is rounded. Both are the Euclidean norm;
/// they can differ in the last bit, and each caller keeps the one its results were pinned with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Norm {
    /// `(dx·dx + dy·dy).sqrt()`: what nalgebra's `norm()` and `distance` compute. The squares
    /// overflow to ∞ beyond about 1e154.
    #[default]
    Sqrt,
    /// `dx.hypot(dy)` (libm): no overflow or underflow in the squares.
    Hypot,
}

impl Norm {
    /// The length of the vector (dx, dy), rounded this way; non-finite components propagate as
    /// they do through `sqrt` and `hypot`.
    #[inline]
    pub fn length(self, dx: f64, dy: f64) -> f64 {
        match self {
            Norm::Sqrt => (dx * dx + dy * dy).sqrt(),
            Norm::Hypot => dx.hypot(dy),
        }
    }

    /// The distance ‖a − b‖ between two points, rounded this way; symmetric in a and b
    /// (negating both components changes neither rounding).
    #[inline]
    pub fn distance(self, a: impl AsPoint2, b: impl AsPoint2) -> f64 {
        let (a, b) = (a.point2(), b.point2());
        self.length(a.x - b.x, a.y - b.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_points_and_references_convert_alike() {
        let p = Point2::new(1.5, -2.0);
        assert_eq!([1.5, -2.0].point2(), p);
        assert_eq!((&[1.5, -2.0]).point2(), p);
        assert_eq!((&p).point2(), p);
        assert_eq!(<[f64; 2]>::from(p), [1.5, -2.0]);
    }

    #[test]
    fn both_norms_measure_the_same_length() {
        for norm in [Norm::Sqrt, Norm::Hypot] {
            assert_eq!(norm.distance([0.0, 0.0], [3.0, 4.0]), 5.0);
            assert_eq!(norm.distance([3.0, 4.0], [0.0, 0.0]), 5.0);
            // Zero-length: the same point twice.
            assert_eq!(norm.distance([7.0, -1.0], [7.0, -1.0]), 0.0);
            assert!(norm.distance([f64::NAN, 0.0], [0.0, 0.0]).is_nan());
        }
        // Sqrt matches nalgebra's distance bit for bit, both ways round.
        let (a, b) = (Point2::new(0.1, 0.7), Point2::new(2.3, -1.9));
        assert_eq!(Norm::Sqrt.distance(a, b), nalgebra::distance(&a, &b));
        assert_eq!(Norm::Sqrt.distance(b, a), nalgebra::distance(&a, &b));
        // Only hypot survives squares beyond f64's range.
        let big = 2f64.powi(600);
        assert_eq!(Norm::Hypot.length(3.0 * big, 4.0 * big), 5.0 * big);
        assert_eq!(Norm::Sqrt.length(3.0 * big, 4.0 * big), f64::INFINITY);
    }
}
