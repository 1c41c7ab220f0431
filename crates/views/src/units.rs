//! The one conversion from the cell's units to SI (REP-103: metres, radians).

use cell_msgs::geometry_msgs::Point;

/// Millimetres per metre. Dividing by it (rather than multiplying by 1e-3) gives the correctly
/// rounded metre value, so 100 mm is exactly `0.1`.
pub const MM_PER_M: f64 = 1000.0;

/// A length in millimetres in metres.
pub fn mm_to_m(mm: f64) -> f64 {
    mm / MM_PER_M
}

/// A point in millimetres as the same point in metres.
pub fn point_m(p: &Point) -> Point {
    Point {
        x: mm_to_m(p.x),
        y: mm_to_m(p.y),
        z: mm_to_m(p.z),
    }
}

/// An angle in degrees in radians.
pub fn deg_to_rad(deg: f64) -> f64 {
    deg.to_radians()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn millimetres_become_metres() {
        let p = point_m(&Point {
            x: 1500.0,
            y: -2.5,
            z: 0.0,
        });
        assert_eq!((p.x, p.y, p.z), (1.5, -0.0025, 0.0));
        assert!((deg_to_rad(180.0) - std::f64::consts::PI).abs() < 1e-15);
    }
}
