//! Arc fitting: runs of polyline points that lie on one circle become a single G2/G3 move.
//!
//! Hand-written: the geometry crates we use (`geo`, `cavalier_contours`) offset and boolean
//! polylines but none fits arcs to a point sequence; the ArcWelder-style greedy fit below is
//! short.
//!
//! **Greedy fit.** From point `i`, the run `i..=j` grows (doubling, then bisecting: O(L log L)
//! for an arc of L points) while the circle through points `i`,
//! `(i + j) / 2` and `j` (the circumcircle) keeps
//! - every point of the run within `tolerance` of the circle (radial error),
//! - every chord within `tolerance` of the arc (sagitta r − √(r² − (c/2)²)), so the arc never
//!   strays from the polyline it replaces by more than `tolerance`,
//! - the points turning one way round the centre, each step under 90° and the whole run
//!   under 350° (a full circle is written as two arcs, never one ambiguous one),
//! - a radius under [`MAX_RADIUS_MM`] (beyond that the run is straight for any controller),
//! - at most [`MAX_ARC_POINTS`] points.
//!
//! A run of at least three points that passes becomes an arc; otherwise the next point is a
//! straight move.

use nalgebra::Vector2;

/// Radii above this are left as straight moves (mm).
pub const MAX_RADIUS_MM: f64 = 5000.0;

/// Most points one arc may replace (bounds the work per arc on a long, finely sampled curve).
pub const MAX_ARC_POINTS: usize = 2000;

/// One move of a fitted polyline, ending at point index `end`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Primitive {
    /// A straight move to point `end`.
    Line {
        /// Index of the end point.
        end: usize,
    },
    /// An arc through the points up to `end`.
    Arc {
        /// Index of the end point.
        end: usize,
        /// The circle's centre.
        centre: Vector2<f64>,
        /// True for counter-clockwise (G3), false for clockwise (G2).
        ccw: bool,
    },
}

/// Fits `points` (consecutive points distinct) into lines and arcs (module docs). The
/// primitives start after point 0 and end at the last point.
pub fn fit(points: &[Vector2<f64>], tolerance: f64) -> Vec<Primitive> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < points.len() {
        // Galloping search for the longest run that passes: double the run while it passes,
        // then bisect between the last pass and the first failure. Each candidate is checked
        // whole, so whatever is chosen passes every test.
        let last = (points.len() - 1).min(i + MAX_ARC_POINTS - 1);
        let mut best = None;
        let mut step = 2;
        let mut fail = None;
        while i + step <= last {
            match arc_through(&points[i..=i + step], tolerance) {
                Some(arc) => best = Some((i + step, arc)),
                None => {
                    fail = Some(i + step);
                    break;
                }
            }
            step *= 2;
        }
        if let Some((good, _)) = best {
            let mut hi = fail.unwrap_or(last + 1);
            let mut lo = good;
            while hi - lo > 1 {
                let mid = (lo + hi) / 2;
                match arc_through(&points[i..=mid], tolerance) {
                    Some(arc) => {
                        best = Some((mid, arc));
                        lo = mid;
                    }
                    None => hi = mid,
                }
            }
        }
        match best {
            Some((end, (centre, ccw))) => {
                out.push(Primitive::Arc { end, centre, ccw });
                i = end;
            }
            None => {
                out.push(Primitive::Line { end: i + 1 });
                i += 1;
            }
        }
    }
    out
}

/// The circle (centre, counter-clockwise) through `run` if it passes every test of the module
/// docs.
fn arc_through(run: &[Vector2<f64>], tolerance: f64) -> Option<(Vector2<f64>, bool)> {
    let (a, b, c) = (run[0], run[run.len() / 2], run[run.len() - 1]);
    let centre = circumcentre(a, b, c)?;
    let r = (a - centre).norm();
    if r > MAX_RADIUS_MM {
        return None;
    }
    let angle = |p: Vector2<f64>| (p.y - centre.y).atan2(p.x - centre.x);
    let mut direction = 0.0f64;
    let mut total = 0.0;
    for pair in run.windows(2) {
        if ((pair[1] - centre).norm() - r).abs() > tolerance {
            return None;
        }
        let chord = (pair[1] - pair[0]).norm();
        if chord > 2.0 * r {
            return None;
        }
        let sagitta = r - (r * r - chord * chord / 4.0).max(0.0).sqrt();
        if sagitta > tolerance {
            return None;
        }
        let mut step = angle(pair[1]) - angle(pair[0]);
        if step > std::f64::consts::PI {
            step -= std::f64::consts::TAU;
        } else if step < -std::f64::consts::PI {
            step += std::f64::consts::TAU;
        }
        if step == 0.0 || step.abs() >= std::f64::consts::FRAC_PI_2 {
            return None;
        }
        if direction == 0.0 {
            direction = step.signum();
        } else if step.signum() != direction {
            return None;
        }
        total += step.abs();
    }
    if total >= 350f64.to_radians() {
        return None;
    }
    Some((centre, direction > 0.0))
}

/// Centre of the circle through three points; `None` if they are (nearly) collinear.
fn circumcentre(a: Vector2<f64>, b: Vector2<f64>, c: Vector2<f64>) -> Option<Vector2<f64>> {
    let (ab, ac) = (b - a, c - a);
    let d = 2.0 * (ab.x * ac.y - ab.y * ac.x);
    let scale = ab.norm() * ac.norm();
    if scale == 0.0 || d.abs() < 1e-12 * scale {
        return None;
    }
    let (ab2, ac2) = (ab.norm_squared(), ac.norm_squared());
    Some(a + Vector2::new(ac.y * ab2 - ab.y * ac2, ab.x * ac2 - ac.x * ab2) / d)
}

/// The centre to write for an arc from `start` to `end` (both as rounded in the program):
/// `centre` moved onto their perpendicular bisector, so the start and end radii agree exactly
/// and a controller's radius check (LinuxCNC, GRBL: 0.005 mm) sees only the rounding of I, J.
pub fn centre_for_rounded_ends(
    start: Vector2<f64>,
    end: Vector2<f64>,
    centre: Vector2<f64>,
) -> Vector2<f64> {
    let mid = (start + end) / 2.0;
    let chord = end - start;
    if chord.norm() == 0.0 {
        return centre;
    }
    let normal = Vector2::new(-chord.y, chord.x).normalize();
    mid + normal * (centre - mid).dot(&normal)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize, r: f64, from_deg: f64, to_deg: f64) -> Vec<Vector2<f64>> {
        (0..n)
            .map(|k| {
                let t = (from_deg + (to_deg - from_deg) * k as f64 / (n - 1) as f64).to_radians();
                Vector2::new(10.0 + r * t.cos(), 20.0 + r * t.sin())
            })
            .collect()
    }

    #[test]
    fn points_on_a_circle_become_one_arc_with_its_centre_and_direction() {
        // 2° steps on r = 25: chords 0.87 mm, sagitta 0.004 mm.
        let pts = circle(91, 25.0, 0.0, 180.0);
        let fitted = fit(&pts, 0.01);
        assert_eq!(fitted.len(), 1, "{fitted:?}");
        let Primitive::Arc { end, centre, ccw } = fitted[0] else {
            panic!("{fitted:?}")
        };
        assert_eq!(end, 90);
        assert!((centre - Vector2::new(10.0, 20.0)).norm() < 1e-9);
        assert!(ccw);
        let rev: Vec<_> = pts.iter().rev().copied().collect();
        assert!(matches!(
            fit(&rev, 0.01)[0],
            Primitive::Arc { ccw: false, .. }
        ));
    }

    #[test]
    fn a_full_circle_is_split_and_a_square_stays_straight() {
        let pts = circle(181, 10.0, 0.0, 360.0);
        let fitted = fit(&pts, 0.01);
        assert!(fitted.len() >= 2, "{fitted:?}");
        assert!(fitted.iter().all(|p| matches!(p, Primitive::Arc { .. })));
        let square = [
            (0.0, 0.0),
            (10.0, 0.0),
            (10.0, 10.0),
            (0.0, 10.0),
            (0.0, 0.0),
        ]
        .map(|(x, y)| Vector2::new(x, y));
        assert_eq!(
            fit(&square, 0.01),
            (1..5)
                .map(|end| Primitive::Line { end })
                .collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_coarse_polygon_is_not_an_arc_when_its_chords_stray_beyond_the_tolerance() {
        // A hexagon on r = 10: chords of 10 mm have a sagitta of 1.34 mm.
        let pts = circle(7, 10.0, 0.0, 300.0);
        assert!(fit(&pts, 0.1)
            .iter()
            .all(|p| matches!(p, Primitive::Line { .. })));
        assert!(fit(&pts, 1.5)
            .iter()
            .any(|p| matches!(p, Primitive::Arc { .. })));
    }

    #[test]
    fn noise_beyond_the_tolerance_breaks_the_arc() {
        let mut pts = circle(20, 30.0, 0.0, 90.0);
        pts[10].x += 0.2;
        for p in fit(&pts, 0.05) {
            if let Primitive::Arc { end, .. } = p {
                assert!(end <= 9 || end > 10, "an arc may not span the bumped point");
            }
        }
    }

    #[test]
    fn the_written_centre_is_equidistant_from_the_rounded_ends() {
        let s = Vector2::new(0.0004, 10.0);
        let e = Vector2::new(10.0, -0.0003);
        let c = centre_for_rounded_ends(s, e, Vector2::new(0.0001, 0.0002));
        assert!(((s - c).norm() - (e - c).norm()).abs() < 1e-12);
    }
}
