//! Spar locations X_sp (seed 002 Algorithm 1): a main spar at x_τmax, fore/aft spars for the
//! bending inertia the flight loads need, then the spacing capped by the AM skin-support rule
//! ([`crate::spacing`]).

use cell_airfoil::SurfaceFunctions;

use crate::spacing::{SkinCurvature, SpacingRule};

/// Structural inputs (seed 002 Alg. 1 "machine settings" and the notes' structural formulas).
#[derive(Debug, Clone, PartialEq)]
pub struct StructureParams {
    /// Extrusion (spar and skin wall) width w_e \[mm\].
    pub extrusion_width_mm: f64,
    /// Yield strength σ_y \[MPa\].
    pub yield_strength_mpa: f64,
    /// Factor of safety FS: σ = σ_y/FS.
    pub safety_factor: f64,
    /// Hinge chord fraction: only spars ahead of it carry bending (notes, "Only spars ahead of
    /// the hinge count").
    pub hinge_x_over_c: f64,
    /// AM skin-support limit on spar spacing (step 5; r*·w_e = 30 mm is Table 2's spacing).
    pub spacing: SpacingRule,
    /// Spars are placed only where the section is at least this thick \[mm\] (room for a
    /// line between the skins).
    pub min_spar_height_mm: f64,
}

/// Spar locations per station: the columns of X_sp (seed 002 §Structural Design), each sorted
/// ascending in x/c. Stations may differ in spar count, so the matrix is stored ragged.
#[derive(Debug, Clone, PartialEq)]
pub struct SparLayout {
    /// Station centres y/b.
    pub y_over_b: Vec<f64>,
    /// x/c of every spar at each station, ascending (the main spar included).
    pub x_over_c: Vec<Vec<f64>>,
    /// Continuous spar parameter m per station (0: main spar only).
    pub m: Vec<f64>,
    /// Required bending inertia I_req per station \[mm⁴\].
    pub required_inertia_mm4: Vec<f64>,
    /// Inertia of the load-driven spars plus skin per station \[mm⁴\] (before the AM cap).
    pub provided_inertia_mm4: Vec<f64>,
}

impl SparLayout {
    /// Spar x/c at spanwise y/b: linear between the two nearest stations when they have the
    /// same spar count, otherwise the nearer station's spars; ends held.
    pub fn at(&self, y_over_b: f64) -> Vec<f64> {
        let y = &self.y_over_b;
        let i = y.partition_point(|v| *v < y_over_b);
        if i == 0 {
            return self.x_over_c[0].clone();
        }
        if i == y.len() {
            return self.x_over_c[y.len() - 1].clone();
        }
        let t = (y_over_b - y[i - 1]) / (y[i] - y[i - 1]);
        let (a, b) = (&self.x_over_c[i - 1], &self.x_over_c[i]);
        if a.len() == b.len() {
            a.iter().zip(b).map(|(p, q)| p + (q - p) * t).collect()
        } else if t < 0.5 {
            a.clone()
        } else {
            b.clone()
        }
    }
}

/// Spanwise bending moment \[N·mm\] of a free–free balanced beam: lift `lift_n_mm` (N/mm per
/// station, stations `span_mm/n` wide) against the aircraft weight (= total lift) as a point
/// load at the centre: M_j = ½Σ_k F_k|y_j − y_k| − ½W|y_j| (seed 002 notes: M = K(ℓ − w),
/// K_jk = ½(b/n)²|j − k|).
pub fn bending_moment_n_mm(lift_n_mm: &[f64], span_mm: f64) -> Vec<f64> {
    let n = lift_n_mm.len();
    let dy = span_mm / n as f64;
    let y: Vec<f64> = (0..n)
        .map(|j| (j as f64 + 0.5) * dy - 0.5 * span_mm)
        .collect();
    let force: Vec<f64> = lift_n_mm.iter().map(|l| l * dy).collect();
    let weight: f64 = force.iter().sum();
    (0..n)
        .map(|j| {
            let lift: f64 = (0..n).map(|k| force[k] * (y[j] - y[k]).abs()).sum();
            0.5 * lift - 0.5 * weight * y[j].abs()
        })
        .collect()
}

/// Bending inertia of a section with spars at `spars` (x/c) and chord `chord_mm`:
/// Σ w_e(τ(x)c)³/12 over spars ahead of the hinge plus the skin w_e·c³·Î (notes, structural
/// formulas), with Î = ∮(z − z̄)²ds of the unit-chord perimeter.
pub fn section_inertia_mm4(
    surf: &SurfaceFunctions,
    skin_inertia_unit: f64,
    spars: &[f64],
    chord_mm: f64,
    p: &StructureParams,
) -> f64 {
    let w = p.extrusion_width_mm;
    let spar: f64 = spars
        .iter()
        .filter(|x| **x <= p.hinge_x_over_c)
        .map(|&x| w * (surf.thickness(x) * chord_mm).powi(3) / 12.0)
        .sum();
    spar + w * chord_mm.powi(3) * skin_inertia_unit
}

/// Î = ∮(z − z̄)²ds over the unit-chord perimeter (both surfaces), z̄ the perimeter's centroid.
pub fn skin_inertia_unit(surf: &SurfaceFunctions) -> f64 {
    let segs: Vec<_> = [surf.upper_points(), surf.lower_points()]
        .into_iter()
        .flat_map(|s| s.windows(2).map(|w| (w[0], w[1])))
        .collect();
    let len: f64 = segs.iter().map(|(a, b)| (b - a).norm()).sum();
    let zbar = segs
        .iter()
        .map(|(a, b)| (b - a).norm() * 0.5 * (a.y + b.y))
        .sum::<f64>()
        / len;
    segs.iter()
        .map(|(a, b)| {
            let (za, zb) = (a.y - zbar, b.y - zbar);
            // Exact ∫z² along a straight segment.
            (b - a).norm() * (za * za + za * zb + zb * zb) / 3.0
        })
        .sum()
}

/// Spars for the continuous parameter m: the main spar at x_τ, ⌈m⌉ fore spars at
/// x_τ − k·x_τ/(m+1) and ⌈m⌉ aft at x_τ + k(1 − x_τ)/(m+1) (notes, spar placement).
pub fn spars_for(m: f64, x_tau: f64) -> Vec<f64> {
    let count = m.max(0.0).ceil() as usize;
    let mut xs = vec![x_tau];
    for k in 1..=count {
        let k = k as f64;
        xs.push((x_tau - k * x_tau / (m + 1.0)).clamp(0.0, 1.0));
        xs.push((x_tau + k * (1.0 - x_tau) / (m + 1.0)).clamp(0.0, 1.0));
    }
    xs.sort_by(f64::total_cmp);
    xs
}

/// Algorithm 1: spar locations for every station.
///
/// Per station: I_req = τ_max·c·M/(2σ) with σ = σ_y/FS (steps 2–3); m by 20 bisection steps
/// on \[0, 20\] for the smallest m whose spars and skin reach I_req (step 4; m = 20 if even that
/// falls short, visible in `provided_inertia_mm4`); then, walking outward from the main spar,
/// spars are inserted so no gap exceeds the AM rule's Δx_max at the spar it starts from
/// (step 5, [`crate::spacing`]), as far as the section is `min_spar_height_mm` thick.
pub fn place_spars(
    surf: &SurfaceFunctions,
    y_over_b: &[f64],
    chord_mm: &[f64],
    moment_n_mm: &[f64],
    p: &StructureParams,
) -> SparLayout {
    let x_tau = surf.x_max_thickness();
    let sigma = p.yield_strength_mpa / p.safety_factor;
    let i_hat = skin_inertia_unit(surf);
    let curvature = SkinCurvature::new(surf);
    let mut out = SparLayout {
        y_over_b: y_over_b.to_vec(),
        x_over_c: Vec::new(),
        m: Vec::new(),
        required_inertia_mm4: Vec::new(),
        provided_inertia_mm4: Vec::new(),
    };
    for (&c, &moment) in chord_mm.iter().zip(moment_n_mm) {
        let i_req = surf.max_thickness() * c * moment.abs() / (2.0 * sigma);
        let inertia = |m: f64| section_inertia_mm4(surf, i_hat, &spars_for(m, x_tau), c, p);
        let m = if inertia(0.0) >= i_req {
            0.0
        } else {
            let (mut lo, mut hi) = (0.0, 20.0);
            for _ in 0..20 {
                let mid = 0.5 * (lo + hi);
                if inertia(mid) >= i_req {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            hi
        };
        let load = spars_for(m, x_tau);
        out.provided_inertia_mm4.push(inertia(m));
        out.required_inertia_mm4.push(i_req);
        out.m.push(m);
        out.x_over_c
            .push(cap_spacing(surf, &curvature, &load, x_tau, c, p));
    }
    out
}

/// Step 5: insert spars outward from the main spar so no gap exceeds the AM rule, each gap's
/// limit taken at the spar it starts from (the skin curvature there). Load spars keep their
/// places (the reference code moves them inward instead; inserting keeps I ≥ I_req).
fn cap_spacing(
    surf: &SurfaceFunctions,
    curvature: &SkinCurvature,
    load: &[f64],
    x_tau: f64,
    chord_mm: f64,
    p: &StructureParams,
) -> Vec<f64> {
    let cap = |x: f64| curvature.max_gap_mm(&p.spacing, x, chord_mm) / chord_mm;
    let fits = |x: f64| surf.thickness(x) * chord_mm >= p.min_spar_height_mm;
    let mut xs = vec![x_tau];
    for dir in [-1.0, 1.0] {
        let mut prev = x_tau;
        let mut ahead: Vec<f64> = load
            .iter()
            .copied()
            .filter(|x| (x - x_tau) * dir > 0.0)
            .collect();
        ahead.sort_by(|a, b| ((a - x_tau) * dir).total_cmp(&((b - x_tau) * dir)));
        // The section end (LE or TE) closes the last gap.
        let end = if dir < 0.0 { 0.0 } else { 1.0 };
        for x in ahead.into_iter().chain(std::iter::once(end)) {
            while (x - prev) * dir > cap(prev) * (1.0 + 1e-9) {
                prev += dir * cap(prev);
                if fits(prev) {
                    xs.push(prev);
                }
            }
            if x != end && fits(x) {
                xs.push(x);
            }
            prev = x;
        }
    }
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    xs
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_airfoil::Airfoil;

    fn ag24() -> SurfaceFunctions {
        let path = format!(
            "{}/../../config/airfoils/ag24.dat",
            env!("CARGO_MANIFEST_DIR")
        );
        SurfaceFunctions::new(&Airfoil::load(path).unwrap()).unwrap()
    }

    /// The G-Wing example's rule (η* = 2e-5, r* = 60 at w_e = 0.5 mm) under a hard cap.
    fn params(cap: f64) -> StructureParams {
        StructureParams {
            extrusion_width_mm: 0.5,
            yield_strength_mpa: 26.0,
            safety_factor: 20.0,
            hinge_x_over_c: 0.8,
            spacing: SpacingRule {
                extrusion_width_mm: 0.5,
                eta_star: 2e-5,
                r_star: 60.0,
                max_mm: Some(cap),
            },
            min_spar_height_mm: 1.1,
        }
    }

    /// Every gap between neighbouring spars, walking outward from the main spar, against the
    /// rule at the gap's inner spar: (gap, limit) in mm.
    pub(crate) fn gaps_and_limits(
        surf: &SurfaceFunctions,
        xs: &[f64],
        chord_mm: f64,
        rule: &SpacingRule,
    ) -> Vec<(f64, f64)> {
        let curvature = SkinCurvature::new(surf);
        let main = xs
            .iter()
            .position(|x| *x == surf.x_max_thickness())
            .expect("main spar at x_τmax");
        let limit = |x: f64| curvature.max_gap_mm(rule, x, chord_mm);
        let aft = xs[main..].windows(2).map(|w| (w[1] - w[0], limit(w[0])));
        let fore = xs[..=main].windows(2).map(|w| (w[1] - w[0], limit(w[1])));
        aft.chain(fore).map(|(g, l)| (g * chord_mm, l)).collect()
    }

    #[test]
    fn spacing_follows_the_am_rule_and_widens_where_the_skin_curves() {
        let s = ag24();
        let rule = params(f64::INFINITY).spacing;
        let p = StructureParams {
            spacing: SpacingRule {
                max_mm: None,
                ..rule
            },
            ..params(0.0)
        };
        for chord in [60.0, 120.0, 175.0, 272.5] {
            let layout = place_spars(&s, &[0.0], &[chord], &[0.0], &p);
            let gaps = gaps_and_limits(&s, &layout.x_over_c[0], chord, &p.spacing);
            for (gap, limit) in &gaps {
                assert!(
                    gap <= &(limit + 1e-6),
                    "c = {chord}: gap {gap} > Δx_max {limit}"
                );
                assert!(*limit >= 30.0 - 1e-9, "r*·w_e = 30 mm is a floor");
            }
        }
        // A small chord's skins curve more per mm (κ/c): the LE needs no spar 30 mm ahead of
        // the main spar, and the section gets fewer spars than a constant 30 mm would give.
        let c = 60.0;
        let rule_spars = place_spars(&s, &[0.0], &[c], &[0.0], &p).x_over_c[0].len();
        let flat_spars = place_spars(&s, &[0.0], &[c], &[0.0], &params(30.0)).x_over_c[0].len();
        assert!(rule_spars < flat_spars, "{rule_spars} vs {flat_spars}");
    }

    #[test]
    fn uniform_load_moment_matches_the_cantilever_formula() {
        // Uniform lift q on a span b, weight at the centre: root moment q(b/2)²/2.
        let (q, b, n) = (0.01, 1000.0, 400);
        let m = bending_moment_n_mm(&vec![q; n], b);
        let root = 0.5 * (m[n / 2 - 1] + m[n / 2]);
        let exact = q * (b / 2.0f64).powi(2) / 2.0;
        assert!((root - exact).abs() < 0.01 * exact, "{root} vs {exact}");
        assert!(
            m[0].abs() < 0.01 * exact && m[n - 1].abs() < 0.01 * exact,
            "free tips"
        );
    }

    #[test]
    fn spacing_cap_and_main_spar() {
        let s = ag24();
        let x_tau = s.x_max_thickness();
        let layout = place_spars(&s, &[0.0], &[150.0], &[0.0], &params(30.0));
        let xs = &layout.x_over_c[0];
        assert!(xs.contains(&x_tau), "main spar at x_τmax");
        for w in xs.windows(2) {
            assert!(
                (w[1] - w[0]) * 150.0 <= 30.0 + 1e-9,
                "Table 2 spar spacing 30 mm: {xs:?}"
            );
        }
        // No load: m = 0, only the cap adds spars; a 150 mm chord needs several.
        assert_eq!(layout.m[0], 0.0);
        assert!(xs.len() >= 4, "{xs:?}");
    }

    #[test]
    fn heavier_loads_need_more_spars() {
        let s = ag24();
        let p = params(1000.0);
        let c = 150.0;
        let i0 = section_inertia_mm4(
            &s,
            skin_inertia_unit(&s),
            &spars_for(0.0, s.x_max_thickness()),
            c,
            &p,
        );
        // The moment whose I_req = τ_max·c·M/(2σ) is 300 mm⁴ above the main spar and skin.
        let sigma = 26.0 / 20.0;
        let moment = (i0 + 300.0) * 2.0 * sigma / (s.max_thickness() * c);
        let light = place_spars(&s, &[0.0], &[c], &[0.5 * moment], &p);
        let heavy = place_spars(&s, &[0.0], &[c], &[moment], &p);
        assert_eq!(light.m[0], 0.0, "main spar and skin carry half the load");
        assert!(heavy.m[0] > 0.0);
        assert!(heavy.x_over_c[0].len() > light.x_over_c[0].len());
        assert!(heavy.provided_inertia_mm4[0] >= heavy.required_inertia_mm4[0]);
        assert!((heavy.required_inertia_mm4[0] - (i0 + 300.0)).abs() < 1e-6);
    }
}
