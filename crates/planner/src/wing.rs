//! Beyond seed 000's 2-D cut (its own limitation 3): a tapered wing panel on a 4-axis cutter.
//!
//! The wire is a straight line between two carriages, XY at z = 0 and UV at z = W (the tower
//! separation). The block's root face sits at z = z_r, its tip face at z_t = z_r + span. To cut
//! a root section and a different tip section at once, the wire must pass matching root and
//! tip points at the same moment, so:
//!
//! 1. both wire paths (each planned in its section's own frame) are resampled to the same
//!    number of points, matched by normalised arc length on each side of the leading edge
//!    ([`synchronise_paths`]);
//! 2. the tip is placed relative to the root: swept back by `sweep_mm` along the chord line
//!    and twisted about a pivot on its chord ([`Placement`]);
//! 3. each matched pair (R, T) is projected along the wire line onto the two carriage planes,
//!    P(z) = R + (T − R)·(z − z_r)/(z_t − z_r) ([`Towers::project`]);
//! 4. each move lasts long enough for the faster of the two *foam faces* to run at the cutting
//!    feed ([`move_durations`]), so both carriages arrive together and the kerf model sees the
//!    face speeds.

use nalgebra::{Point2, Vector2};

use crate::airfoil::{synchronise, Airfoil, AirfoilError, SyncedPoints};

/// Where a section sits relative to the root section's frame (LE at the origin, chord along
/// +x): translated by `sweep_mm` along x, then twisted by `twist_deg` (positive nose up) about
/// the point at `pivot_chord_fraction` of its own chord.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Leading-edge offset along the chord line, mm (positive: swept back).
    pub sweep_mm: f64,
    /// Twist, degrees, positive nose up ([`Airfoil::twisted`]).
    pub twist_deg: f64,
    /// Twist pivot as a fraction of the section's chord from its LE (0.25: quarter chord).
    pub pivot_chord_fraction: f64,
}

impl Placement {
    /// No sweep, no twist.
    pub const ROOT: Placement = Placement {
        sweep_mm: 0.0,
        twist_deg: 0.0,
        pivot_chord_fraction: 0.25,
    };

    /// Maps a point of a section of chord `chord_mm` from its own frame (LE at the origin,
    /// chord along +x) into the root frame.
    pub fn apply(&self, chord_mm: f64, p: Point2<f64>) -> Point2<f64> {
        if self.twist_deg == 0.0 {
            // Exact: an untwisted, unswept tip must coincide with the root bit for bit.
            return p + Vector2::new(self.sweep_mm, 0.0);
        }
        let pivot = Point2::new(self.sweep_mm + self.pivot_chord_fraction * chord_mm, 0.0);
        // Nose up is clockwise in the x-right, y-up frame (as Airfoil::twisted).
        let rot = nalgebra::Rotation2::new(-self.twist_deg.to_radians());
        pivot + rot * (p + Vector2::new(self.sweep_mm, 0.0) - pivot)
    }
}

/// The two carriage planes and the block between them (mm along the wire, from the XY plane).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Towers {
    /// UV plane position W (the tower separation).
    pub separation_mm: f64,
    /// Root face position z_r.
    pub root_plane_mm: f64,
    /// Tip face position z_t (> z_r).
    pub tip_plane_mm: f64,
}

impl Towers {
    /// The carriage positions (XY, UV) that put the wire through `root` on the root face and
    /// `tip` on the tip face: the wire line evaluated at z = 0 and z = W.
    pub fn project(&self, root: Point2<f64>, tip: Point2<f64>) -> (Point2<f64>, Point2<f64>) {
        let at = |z: f64| root + (tip - root) * ((z - self.root_plane_mm) / self.span_mm());
        (at(0.0), at(self.separation_mm))
    }

    /// z_t − z_r.
    pub fn span_mm(&self) -> f64 {
        self.tip_plane_mm - self.root_plane_mm
    }
}

/// Resamples two closed wire paths (each in its own section frame: LE side at min x, starting
/// and ending at the trailing edge, anticlockwise) to `n` points each that correspond one to
/// one: split at the min-x point, the k-th point of each side sits at the same cosine-spaced
/// normalised arc length of that side on both paths ([`synchronise`]). Index 0 and n − 1 are
/// the paths' first and last points.
///
/// # Errors
/// `n` < 5, or a path that is not a valid closed section-like polygon (fewer than 5 distinct
/// points, zero area, min-x point at an end).
pub fn synchronise_paths(
    root: &[Point2<f64>],
    tip: &[Point2<f64>],
    n: usize,
) -> Result<SyncedPoints, AirfoilError> {
    let as_section = |name: &str, path: &[Point2<f64>]| Airfoil::new(name, path.to_vec());
    synchronise(
        &as_section("root path", root)?,
        &as_section("tip path", tip)?,
        n,
    )
}

/// How long each move of a synchronised pair of paths takes (s): move k runs from point k to
/// point k + 1, and lasts max(‖ΔR‖, ‖ΔT‖) / `feed_mm_s`, so the faster face cuts at the feed.
/// Zero-length moves last 0.
pub fn move_durations(root: &[Point2<f64>], tip: &[Point2<f64>], feed_mm_s: f64) -> Vec<f64> {
    root.windows(2)
        .zip(tip.windows(2))
        .map(|(r, t)| (r[1] - r[0]).norm().max((t[1] - t[0]).norm()) / feed_mm_s)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airfoil::test_foil;
    use crate::trajectory::Baseline;

    #[test]
    fn projection_puts_the_wire_through_both_faces() {
        let towers = Towers {
            separation_mm: 1000.0,
            root_plane_mm: 200.0,
            tip_plane_mm: 700.0,
        };
        let (r, t) = (Point2::new(100.0, 50.0), Point2::new(80.0, 60.0));
        let (xy, uv) = towers.project(r, t);
        // Back-interpolate the wire line from the carriages to both faces.
        let at = |z: f64| xy + (uv - xy) * (z / 1000.0);
        assert!((at(200.0) - r).norm() < 1e-9);
        assert!((at(700.0) - t).norm() < 1e-9);
        // A straight (untapered) cut leaves both carriages on the section.
        let (xy, uv) = towers.project(r, r);
        assert_eq!((xy, uv), (r, r));
    }

    #[test]
    fn placement_sweeps_then_twists_about_the_pivot() {
        let p = Placement {
            sweep_mm: 30.0,
            twist_deg: 90.0,
            pivot_chord_fraction: 0.5,
        };
        // The pivot (half of a 100 mm chord, swept) stays put.
        let pivot = p.apply(100.0, Point2::new(50.0, 0.0));
        assert!((pivot - Point2::new(80.0, 0.0)).norm() < 1e-9);
        // Nose up by 90°: the LE goes straight above the pivot.
        let le = p.apply(100.0, Point2::origin());
        assert!((le - Point2::new(80.0, 50.0)).norm() < 1e-9, "{le}");
        assert_eq!(
            Placement::ROOT.apply(100.0, Point2::new(3.0, 4.0)),
            Point2::new(3.0, 4.0)
        );
    }

    #[test]
    fn synchronised_paths_match_le_and_te_and_keep_the_shape() {
        let root = test_foil("s1223", 200.0);
        let tip = test_foil("e387", 120.0);
        let rp = Baseline::fixed_offset(&root, 0.6, 120).unwrap();
        let tp = Baseline::fixed_offset(&tip, 0.9, 80).unwrap();
        let n = 301;
        let (r, t) = synchronise_paths(rp.points(), tp.points(), n).unwrap();
        assert_eq!((r.len(), t.len()), (n, n));
        assert_eq!((r[0], t[0]), (rp.points()[0], tp.points()[0]));
        assert_eq!((r[n - 1], t[n - 1]), (r[0], t[0]));
        // The middle index is each path's min-x (LE side) point.
        let min_x = |p: &[Point2<f64>]| p.iter().map(|q| q.x).fold(f64::INFINITY, f64::min);
        assert_eq!(r[n / 2].x, min_x(rp.points()));
        assert_eq!(t[n / 2].x, min_x(tp.points()));
        // Resampled points lie on the original polylines: clearance from the foil is kept to
        // within the sagitta of a chord of the finer sampling.
        let before = crate::trajectory::clearance_mm(rp.points(), root.points(), f64::INFINITY);
        let clear = crate::trajectory::clearance_mm(&r, root.points(), f64::INFINITY);
        assert!(clear > before - 0.01, "{clear} vs {before}");
    }

    #[test]
    fn durations_follow_the_faster_face() {
        let r = [Point2::new(0.0, 0.0), Point2::new(10.0, 0.0)];
        let t = [Point2::new(0.0, 0.0), Point2::new(5.0, 0.0)];
        assert_eq!(move_durations(&r, &t, 5.0), vec![2.0]);
        assert_eq!(move_durations(&t, &r, 5.0), vec![2.0]);
    }
}
