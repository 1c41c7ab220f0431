//! Distances on the sheet, mm.

use cell_geometry::{point_segment_distance, Norm};

use crate::problem::Point;

/// Euclidean distance without `hypot`'s overflow care (coordinates are mm on a sheet).
pub(super) fn dist(a: Point, b: Point) -> f64 {
    Norm::Sqrt.distance(a, b)
}

/// Distance from `p` to the segment `a–b`, mm.
pub(super) fn seg_dist(p: Point, a: Point, b: Point) -> f64 {
    point_segment_distance(p, a, b, Norm::Sqrt)
}
