//! Thickness and surface functions of a section (seed 002 §5 "Airfoil I/O"): z_US(x), z_LS(x),
//! τ(x) = z_US − z_LS and x_τmax, in the chord-normalised frame (LE at 0, TE at 1).

use nalgebra::Point2;

use crate::{Airfoil, AirfoilError};

/// The upper and lower surfaces of a section as functions of chordwise x, chord-normalised
/// (built from [`Airfoil::normalised`]: LE at (0, 0), TE at (1, 0)).
///
/// Each surface is the piecewise-linear interpolant of the section's points, LE → TE; outside
/// 0 … 1 the end values are held. Points that double back in x (rare, at a blunt LE) are
/// skipped so each surface is a function of x.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceFunctions {
    upper: Vec<Point2<f64>>,
    lower: Vec<Point2<f64>>,
}

impl SurfaceFunctions {
    /// The surfaces of `foil` (any scale or pose; it is normalised first).
    ///
    /// # Errors
    /// [`AirfoilError::Degenerate`] if, after normalising, a surface has fewer than two points
    /// with increasing x, or the upper surface lies below the lower one (negative thickness
    /// over more than rounding).
    pub fn new(foil: &Airfoil) -> Result<Self, AirfoilError> {
        let n = foil.normalised();
        let upper = monotone(n.upper_surface().iter().rev().copied());
        let lower = monotone(n.lower_surface().iter().copied());
        if upper.len() < 2 || lower.len() < 2 {
            return Err(AirfoilError::Degenerate {
                file: foil.name().to_string(),
                reason: "a surface has fewer than two points with increasing x".into(),
            });
        }
        let s = Self { upper, lower };
        let t_max = s.max_thickness();
        if s.breakpoints().iter().any(|&x| s.thickness(x) < -1e-9) || t_max <= 0.0 {
            return Err(AirfoilError::Degenerate {
                file: foil.name().to_string(),
                reason: "upper surface below the lower surface".into(),
            });
        }
        Ok(s)
    }

    /// Upper surface z_US(x), chord-normalised.
    pub fn z_upper(&self, x: f64) -> f64 {
        interpolate(&self.upper, x)
    }

    /// Lower surface z_LS(x), chord-normalised.
    pub fn z_lower(&self, x: f64) -> f64 {
        interpolate(&self.lower, x)
    }

    /// Thickness τ(x) = z_US(x) − z_LS(x), chord-normalised (seed 002, Alg. 1 step 1).
    pub fn thickness(&self, x: f64) -> f64 {
        self.z_upper(x) - self.z_lower(x)
    }

    /// x/c of the maximum thickness, x_τmax: where G-Wing puts the main spar (seed 002,
    /// Alg. 1 step 1, Fig. 6). Both surfaces are piecewise linear, so τ is too and its maximum
    /// is at one of the surfaces' breakpoints; the first one on a tie.
    pub fn x_max_thickness(&self) -> f64 {
        let mut best = (0.0, f64::NEG_INFINITY);
        for x in self.breakpoints() {
            let t = self.thickness(x);
            if t > best.1 {
                best = (x, t);
            }
        }
        best.0
    }

    /// The maximum thickness τ_max = τ(x_τmax), chord-normalised.
    pub fn max_thickness(&self) -> f64 {
        self.thickness(self.x_max_thickness())
    }

    /// The upper surface points LE → TE (x increasing).
    pub fn upper_points(&self) -> &[Point2<f64>] {
        &self.upper
    }

    /// The lower surface points LE → TE (x increasing).
    pub fn lower_points(&self) -> &[Point2<f64>] {
        &self.lower
    }

    /// Every x at which either surface has a point, ascending.
    fn breakpoints(&self) -> Vec<f64> {
        let mut xs: Vec<f64> = self.upper.iter().chain(&self.lower).map(|p| p.x).collect();
        xs.sort_by(f64::total_cmp);
        xs.dedup();
        xs
    }
}

/// The points with strictly increasing x (later points that do not advance are dropped).
fn monotone(points: impl Iterator<Item = Point2<f64>>) -> Vec<Point2<f64>> {
    let mut out: Vec<Point2<f64>> = Vec::new();
    for p in points {
        if out.last().is_none_or(|q| p.x > q.x) {
            out.push(p);
        }
    }
    out
}

/// Linear interpolation in a polyline with strictly increasing x; end values held outside.
fn interpolate(points: &[Point2<f64>], x: f64) -> f64 {
    let i = points.partition_point(|p| p.x < x);
    if i == 0 {
        return points[0].y;
    }
    if i == points.len() {
        return points[points.len() - 1].y;
    }
    let (a, b) = (points[i - 1], points[i]);
    a.y + (b.y - a.y) * (x - a.x) / (b.x - a.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config_foil(name: &str) -> Airfoil {
        let path = format!(
            "{}/../../config/airfoils/{name}.dat",
            env!("CARGO_MANIFEST_DIR")
        );
        Airfoil::load(&path).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn naca0012_thickness_is_twelve_percent_at_thirty_percent_chord() {
        let s = SurfaceFunctions::new(&config_foil("naca0012")).unwrap();
        // NACA 4-digit: t = 0.12 at x/c = 0.2966 (analytic maximum of the thickness form).
        assert!(
            (s.max_thickness() - 0.12).abs() < 0.002,
            "NACA 0012 τ_max = 0.12, got {}",
            s.max_thickness()
        );
        assert!(
            (s.x_max_thickness() - 0.30).abs() < 0.03,
            "NACA 0012 x_τmax ≈ 0.30, got {}",
            s.x_max_thickness()
        );
        // Symmetric: z_US = −z_LS.
        for x in [0.05, 0.3, 0.7, 0.95] {
            assert!((s.z_upper(x) + s.z_lower(x)).abs() < 1e-3, "x = {x}");
        }
    }

    #[test]
    fn ag24_surfaces_bracket_and_thin_out_at_the_te() {
        let s = SurfaceFunctions::new(&config_foil("ag24")).unwrap();
        // UIUC lists AG24 at 8.4 % thickness.
        assert!(
            (0.07..0.10).contains(&s.max_thickness()),
            "AG24 τ_max ≈ 0.084, got {}",
            s.max_thickness()
        );
        assert!((0.15..0.40).contains(&s.x_max_thickness()));
        for k in 1..100 {
            let x = k as f64 / 100.0;
            assert!(s.thickness(x) > 0.0, "x = {x}");
        }
        assert!(s.thickness(1.0) < 0.01);
        assert!(
            s.thickness(0.0).abs() < 1e-12,
            "LE is a vertex of both surfaces"
        );
        assert!(s.z_upper(-1.0) == s.z_upper(0.0) && s.z_lower(2.0) == s.z_lower(1.0));
    }

    #[test]
    fn scale_and_pose_do_not_matter() {
        let f = config_foil("clarky");
        let a = SurfaceFunctions::new(&f).unwrap();
        let g = f
            .scaled(180.0)
            .unwrap()
            .twisted(4.0, Point2::new(10.0, 3.0))
            .unwrap();
        let b = SurfaceFunctions::new(&g).unwrap();
        assert!((a.max_thickness() - b.max_thickness()).abs() < 1e-3);
        assert!((a.x_max_thickness() - b.x_max_thickness()).abs() < 0.02);
    }
}
