//! The path the tool follows round a contour, and points along a polyline.

use cell_geometry::{closest_point_on_segment, point_at_arc_length, Norm};

use crate::problem::{distance, Contour, Point};

/// The closed cut path of `contour` from `pierce` round and back to it: the pierce point is
/// projected onto the nearest polyline edge (seed 003 §A1: a cut starts and ends at its
/// pierce point). Degenerate contours (fewer than 2 points) give `[pierce, pierce]`.
pub fn cut_path(contour: &Contour, pierce: Point) -> Vec<Point> {
    let pts = &contour.points;
    let n = pts.len();
    if n < 2 {
        return vec![pierce, pierce];
    }
    let mut best = (f64::INFINITY, 0usize, pierce);
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        let q: Point = closest_point_on_segment(pierce, a, b).into();
        let d = distance(q, pierce);
        if d < best.0 {
            best = (d, i, q);
        }
    }
    let (_, i, q) = best;
    let mut path = Vec::with_capacity(n + 3);
    path.push(pierce);
    if distance(q, pierce) > 0.0 {
        path.push(q);
    }
    for k in 1..=n {
        path.push(pts[(i + k) % n]);
    }
    path.push(q);
    if distance(q, pierce) > 0.0 {
        path.push(pierce);
    }
    path
}

/// The point at arc length `s` along a polyline (its end if `s` is past it).
pub(crate) fn point_along(path: &[Point], s: f64) -> Point {
    point_at_arc_length(path, s, Norm::Hypot)
}
