//! The AM spar spacing rule (seed 002 Algorithm 1 step 5, "Limit spar spacing based on AM
//! limits based on \[8\]"; \[8\]: Valenti, Bartolai, Yukish, "Experimental Study of Wing
//! Structure Geometry to Mitigate Process-Induced Deformation", SFF 2022): how far apart two
//! spars may stand and still hold the printed skin between them in shape.
//!
//! The rule (the notes' structural formulas, after the G-Wing reference implementation):
//!
//! ```text
//! Δx_max = max( min(κ_US, κ_LS) · w_e² / η* ,  r* · w_e )     η* = 2·10⁻⁵, r* = 60
//! ```
//!
//! - κ_US, κ_LS: the curvature \[1/mm\] of the upper and lower skin *of the printed section* at
//!   the spar the gap starts from, κ = |z''|/(1 + z'²)^{3/2}: the unit-chord airfoil's curvature
//!   divided by the local chord c. The sign is dropped (concave and convex skins alike).
//! - w_e: the extrusion (skin wall) width \[mm\]; η* is dimensionless, so
//!   κ·w_e²/η* = w_e²/(η*·R) with R = 1/κ the skin's radius of curvature: a length, in the
//!   units of w_e and R (mm here, m in the reference code; the result is the same).
//! - Reading: a curved skin is a shell and resists the warping of the cooling print, so the
//!   more curved *both* skins are, the wider the gap may be; a flat skin (κ → 0) is held only
//!   by the floor r*·w_e (60 × 0.5 mm = 30 mm, Table 2's spar spacing). `max` makes r*·w_e a
//!   floor, not a cap: the rule never asks for spars closer than 30 mm at w_e = 0.5 mm.
//!   On AG24 the lower skin is nearly flat aft of 20 % chord, so the floor governs there; near
//!   the leading edge both skins curve hard and gaps of several chords would be allowed.
//!
//! Applied sequentially outward from the main spar (the notes; [`crate::structure`]): each gap's
//! limit is the rule at the spar the gap starts from, and a spar is inserted there whenever the
//! next one is farther away.

use cell_airfoil::SurfaceFunctions;
use nalgebra::Point2;

/// The rule's constants and the optional hard cap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpacingRule {
    /// Extrusion (skin wall) width w_e \[mm\].
    pub extrusion_width_mm: f64,
    /// η* (dimensionless; 2·10⁻⁵ in the G-Wing example).
    pub eta_star: f64,
    /// r* (dimensionless; 60 in the G-Wing example): the floor is r*·w_e.
    pub r_star: f64,
    /// An explicit upper bound on every gap \[mm\], over the rule (None: the rule alone).
    pub max_mm: Option<f64>,
}

impl SpacingRule {
    /// Δx_max \[mm\] for skin curvatures `kappa_upper` and `kappa_lower` \[1/mm\] (signs dropped),
    /// then capped by [`SpacingRule::max_mm`].
    pub fn max_gap_mm(&self, kappa_upper: f64, kappa_lower: f64) -> f64 {
        let w = self.extrusion_width_mm;
        let kappa = kappa_upper.abs().min(kappa_lower.abs());
        let rule = (kappa * w * w / self.eta_star).max(self.r_star * w);
        self.max_mm.map_or(rule, |cap| rule.min(cap))
    }

    /// The smallest gap the rule can ask for \[mm\]: the floor r*·w_e, or the cap if lower.
    pub fn least_gap_mm(&self) -> f64 {
        let floor = self.r_star * self.extrusion_width_mm;
        self.max_mm.map_or(floor, |cap| floor.min(cap))
    }
}

/// The curvature of both skins of a unit-chord section, as functions of x/c.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinCurvature {
    upper: Vec<(f64, f64)>,
    lower: Vec<(f64, f64)>,
}

impl SkinCurvature {
    /// The curvature of `surf`'s surface points: at each vertex the curvature of the circle
    /// through it and its two neighbours (Menger curvature 4·area/(|ab|·|bc|·|ca|), exact on a
    /// circle, no uniform spacing needed), the end vertices taking their neighbour's value.
    pub fn new(surf: &SurfaceFunctions) -> Self {
        Self {
            upper: vertex_curvature(surf.upper_points()),
            lower: vertex_curvature(surf.lower_points()),
        }
    }

    /// κ_US at x/c, unit chord (multiply by 1/c for the printed section), linear between
    /// vertices, end values held.
    pub fn upper(&self, x: f64) -> f64 {
        interpolate(&self.upper, x)
    }

    /// κ_LS at x/c, unit chord.
    pub fn lower(&self, x: f64) -> f64 {
        interpolate(&self.lower, x)
    }

    /// Δx_max \[mm\] for a gap starting at x/c on a section of chord `chord_mm`.
    pub fn max_gap_mm(&self, rule: &SpacingRule, x: f64, chord_mm: f64) -> f64 {
        rule.max_gap_mm(self.upper(x) / chord_mm, self.lower(x) / chord_mm)
    }
}

/// (x, κ) at every vertex of a polyline ordered in x.
fn vertex_curvature(points: &[Point2<f64>]) -> Vec<(f64, f64)> {
    let n = points.len();
    let mut out: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            let k = if i == 0 || i + 1 == n {
                0.0
            } else {
                menger(points[i - 1], points[i], points[i + 1])
            };
            (points[i].x, k)
        })
        .collect();
    if n >= 3 {
        out[0].1 = out[1].1;
        out[n - 1].1 = out[n - 2].1;
    }
    out
}

/// Curvature of the circle through a, b, c (0 for collinear or coincident points).
fn menger(a: Point2<f64>, b: Point2<f64>, c: Point2<f64>) -> f64 {
    let (ab, bc, ca) = (b - a, c - b, a - c);
    let twice_area = (ab.x * (c - a).y - ab.y * (c - a).x).abs();
    let d = ab.norm() * bc.norm() * ca.norm();
    if d > 0.0 {
        2.0 * twice_area / d
    } else {
        0.0
    }
}

fn interpolate(table: &[(f64, f64)], x: f64) -> f64 {
    let i = table.partition_point(|p| p.0 < x);
    if i == 0 {
        return table.first().map_or(0.0, |p| p.1);
    }
    if i == table.len() {
        return table[i - 1].1;
    }
    let ((x0, k0), (x1, k1)) = (table[i - 1], table[i]);
    if x1 > x0 {
        k0 + (k1 - k0) * (x - x0) / (x1 - x0)
    } else {
        k1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE2: SpacingRule = SpacingRule {
        extrusion_width_mm: 0.5,
        eta_star: 2e-5,
        r_star: 60.0,
        max_mm: None,
    };

    #[test]
    fn flat_skin_gets_the_floor_r_star_w_e() {
        assert_eq!(TABLE2.max_gap_mm(0.0, 0.0), 30.0, "r*·w_e = 60 × 0.5 mm");
        // One flat skin is enough: min(κ_US, κ_LS).
        assert_eq!(TABLE2.max_gap_mm(1.0, 0.0), 30.0);
        assert_eq!(TABLE2.least_gap_mm(), 30.0);
    }

    #[test]
    fn curved_skins_allow_wider_gaps() {
        // R = 100 mm on both skins: w_e²/(η*·R) = 0.25/(2e-5 · 100) = 125 mm.
        let k = 1.0 / 100.0;
        assert!((TABLE2.max_gap_mm(k, -k) - 125.0).abs() < 1e-9);
        // The less curved skin governs: R = 100 and 200 mm → 62.5 mm.
        assert!((TABLE2.max_gap_mm(k, 0.5 * k) - 62.5).abs() < 1e-9);
        // Tight curvature (R = 5 mm): 2.5 m; a cap bounds it.
        assert!((TABLE2.max_gap_mm(0.2, 0.2) - 2500.0).abs() < 1e-6);
        let capped = SpacingRule {
            max_mm: Some(40.0),
            ..TABLE2
        };
        assert_eq!(capped.max_gap_mm(0.2, 0.2), 40.0);
        assert_eq!(
            capped.max_gap_mm(0.0, 0.0),
            30.0,
            "the cap never lifts the floor"
        );
        let tight = SpacingRule {
            max_mm: Some(10.0),
            ..TABLE2
        };
        assert_eq!(tight.max_gap_mm(0.0, 0.0), 10.0);
        assert_eq!(tight.least_gap_mm(), 10.0);
    }

    #[test]
    fn menger_curvature_is_exact_on_a_circle() {
        let r = 3.0;
        let arc: Vec<Point2<f64>> = (0..20)
            .map(|i| {
                let t = 0.3 + 0.05 * f64::from(i) + 0.01 * f64::from(i * i % 3);
                Point2::new(r * t.cos(), r * t.sin())
            })
            .collect();
        let mut arc = arc;
        arc.sort_by(|a, b| a.x.total_cmp(&b.x));
        for (_, k) in vertex_curvature(&arc) {
            assert!((k - 1.0 / r).abs() < 1e-9, "{k}");
        }
        let line: Vec<Point2<f64>> = (0..5).map(|i| Point2::new(f64::from(i), 0.5)).collect();
        assert!(vertex_curvature(&line).iter().all(|p| p.1 == 0.0));
    }
}
