//! The lifting line against a vortex-lattice solution of the same wing (issue 24, seed 002:
//! "output the wing geometry to AVL" to verify the lifting-line design).
//!
//! The vortex lattice (AeroSandbox's `VortexLatticeMethod` in `tests/vlm/compare.py`, reading
//! the [`crate::avl`] file) reports its lift, lift slope, induced drag and the bound
//! circulation of each spanwise strip; [`Agreement::of`] sets them beside the lifting line's.
//! Span loading is compared as shape, Γ̂/c_L (lift per span for unit wing lift), so a small
//! difference in c_L does not count twice.

use serde::Deserialize;

use crate::llt::Solution;

/// A vortex-lattice solution of the wing at its design point (the JSON `compare.py` prints).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct VlmSolution {
    /// Wing lift coefficient at the design point.
    pub c_l_design: f64,
    /// Lift slope dC_L/dα \[1/rad\].
    pub lift_slope_per_rad: f64,
    /// Induced drag coefficient (Trefftz plane).
    pub cdi_trefftz: f64,
    /// Span efficiency e = C_L²/(πAR·C_Di).
    pub span_efficiency: f64,
    /// Per spanwise strip.
    pub strips: VlmStrips,
}

/// The strips of a vortex-lattice solution, root to tip over the whole span.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct VlmStrips {
    /// Strip centre y/b.
    pub y_over_b: Vec<f64>,
    /// Bound circulation Γ/(V∞b).
    pub gamma_hat: Vec<f64>,
}

/// The lifting line's Γ̂ at `y_over_b`: Γ̂/√(1 − (2y/b)²) interpolated linearly between
/// stations (held beyond the outer ones), times √(1 − (2y/b)²), so the loading goes to zero at
/// the tips like every finite wing's instead of being held at its last station's value.
pub fn gamma_hat_at(llt: &Solution, y_over_b: f64) -> f64 {
    let n = llt.gamma_hat.len();
    let root = |y: f64| (1.0 - 4.0 * y * y).max(0.0).sqrt();
    let station = |j: usize| -0.5 + (j as f64 + 0.5) / n as f64;
    let scaled = |j: usize| llt.gamma_hat[j] / root(station(j));
    let s = (y_over_b + 0.5) * n as f64 - 0.5;
    let g = if s <= 0.0 {
        scaled(0)
    } else if s >= (n - 1) as f64 {
        scaled(n - 1)
    } else {
        let i = s.floor() as usize;
        let t = s - i as f64;
        scaled(i) * (1.0 - t) + scaled(i + 1) * t
    };
    g * root(y_over_b)
}

/// Strips with |2y/b| above this are the tips, where the two models part by construction: the
/// lifting line's outermost station is half a station (b/2n) in from the tip and its chord is
/// held there, while the lattice resolves the tip vortex over the last chord (there the strips'
/// loading stays a few % of the peak higher). The span loading is compared inboard of it, and
/// reported with the tips as well.
pub const TIP_ZONE: f64 = 0.95;

/// The lifting line and the vortex lattice side by side.
#[derive(Debug, Clone, PartialEq)]
pub struct Agreement {
    /// c_Lα \[1/rad\]: lifting line, vortex lattice.
    pub lift_slope: (f64, f64),
    /// c_L at the design point: lifting line, vortex lattice.
    pub c_l: (f64, f64),
    /// Largest |Γ̂/c_L| difference over the strips inboard of [`TIP_ZONE`], in % of the
    /// lifting line's largest.
    pub span_loading_max_diff_pct: f64,
    /// Where (y/b) the inboard difference is largest.
    pub span_loading_max_diff_at: f64,
    /// The same over every strip, the tips included.
    pub span_loading_max_diff_with_tips_pct: f64,
    /// C_Di: lifting line, vortex lattice.
    pub cdi: (f64, f64),
    /// Span efficiency e: lifting line, vortex lattice.
    pub span_efficiency: (f64, f64),
}

/// (b − a)/a in %.
pub fn pct(pair: (f64, f64)) -> f64 {
    100.0 * (pair.1 - pair.0) / pair.0
}

impl Agreement {
    /// Compares the lifting-line solution `llt` (lift slope `llt_lift_slope` of its planform)
    /// with `vlm`.
    pub fn of(llt: &Solution, llt_lift_slope: f64, vlm: &VlmSolution) -> Self {
        let shape_max = llt.gamma_hat.amax() / llt.c_l.abs();
        // (largest difference in % of the peak, where)
        let diff = |inboard_of: f64| {
            vlm.strips
                .y_over_b
                .iter()
                .zip(&vlm.strips.gamma_hat)
                .filter(|(y, _)| 2.0 * y.abs() <= inboard_of)
                .map(|(y, g)| {
                    let d = (g / vlm.c_l_design - gamma_hat_at(llt, *y) / llt.c_l).abs();
                    (d / shape_max * 100.0, *y)
                })
                .fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a })
        };
        let (inboard, at) = diff(TIP_ZONE);
        Self {
            lift_slope: (llt_lift_slope, vlm.lift_slope_per_rad),
            c_l: (llt.c_l, vlm.c_l_design),
            span_loading_max_diff_pct: inboard,
            span_loading_max_diff_at: at,
            span_loading_max_diff_with_tips_pct: diff(f64::INFINITY).0,
            cdi: (llt.induced_drag_coefficient(), vlm.cdi_trefftz),
            span_efficiency: (llt.span_efficiency(), vlm.span_efficiency),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::llt::LiftingLine;
    use nalgebra::DVector;

    #[test]
    fn interpolation_keeps_the_elliptic_load_and_closes_at_the_tips() {
        let ll = LiftingLine::new(200, 8.0, 2.0 * std::f64::consts::PI).unwrap();
        let c = ll.chord_from_shape(&ll.elliptic_shape()).unwrap();
        let s = ll.direct(&c, &DVector::repeat(200, 0.1)).unwrap();
        let g0 = gamma_hat_at(&s, 0.0);
        // Inboard the discrete ellipse Q⁻¹e follows √(1 − 4y²) closely; past the last station
        // (y/b = 0.4975) the scaled value is held, where the discrete load is 1.6 % of its
        // peak above the continuous ellipse.
        for (y, tolerance) in [
            (0.0f64, 5e-3),
            (0.2, 5e-3),
            (0.45, 5e-3),
            (0.499, 0.02),
            (0.4999, 0.02),
        ] {
            let ellipse = g0 * (1.0 - 4.0 * y * y).sqrt();
            let got = gamma_hat_at(&s, y);
            assert!(
                (got - ellipse).abs() < tolerance * g0,
                "y/b = {y}: {got} vs {ellipse} (root {g0})"
            );
        }
        assert!(gamma_hat_at(&s, 0.4999) < gamma_hat_at(&s, 0.499));
        assert_eq!(gamma_hat_at(&s, 0.5), 0.0);
    }

    #[test]
    fn an_identical_solution_agrees_and_a_scaled_one_differs_in_c_l_only() {
        let ll = LiftingLine::new(100, 8.0, 2.0 * std::f64::consts::PI).unwrap();
        let y = ll.stations();
        let c = ll.chord_from_shape(&y.map(|y| 1.0 - y.abs())).unwrap();
        let s = ll.direct(&c, &y.map(|y| 0.1 - 0.1 * y.abs())).unwrap();
        let slope = ll.lift_curve_slope(&c).unwrap();
        let vlm = |k: f64| VlmSolution {
            c_l_design: k * s.c_l,
            lift_slope_per_rad: slope,
            cdi_trefftz: s.induced_drag_coefficient(),
            span_efficiency: s.span_efficiency(),
            strips: VlmStrips {
                y_over_b: y.iter().copied().collect(),
                gamma_hat: s.gamma_hat.iter().map(|g| k * g).collect(),
            },
        };
        let same = Agreement::of(&s, slope, &vlm(1.0));
        assert!(same.span_loading_max_diff_pct < 1e-9);
        assert_eq!(pct(same.lift_slope), 0.0);
        let more = Agreement::of(&s, slope, &vlm(1.05));
        assert!((pct(more.c_l) - 5.0).abs() < 1e-9);
        assert!(more.span_loading_max_diff_pct < 1e-9, "same shape");
        let mut skewed = vlm(1.0);
        skewed.strips.gamma_hat[50] *= 1.1;
        let d = Agreement::of(&s, slope, &skewed).span_loading_max_diff_pct;
        assert!(d > 5.0 && d < 10.1, "{d}");
    }
}
