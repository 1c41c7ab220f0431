//! The seed 001 hot-wire kerf model (Aitchison, Brooks, Bain, Pons: "Prediction of optimal
//! machining conditions for polystyrene foam cut with a taut hot-wire").
//!
//! Everything in this module is **SI** (A, Ω/m, m/s, kg/m³, J/kg, m), as in the paper; the
//! one exception is the planner-facing path API ([`offset_polyline`], [`current_schedule`]),
//! which takes mm and mm/s and converts once, here.
//!
//! The model, with R' the wire resistance **per metre** (see the note on eq. 1–2 below):
//!
//! | seed 001 | formula | here |
//! |---|---|---|
//! | eq. 1–2 | Q_L = I²·R' | [`linear_heat_flux_w_m`] |
//! | eq. 3 | Q_eff = Q_L / v_c | [`area_specific_energy_j_m2`] |
//! | eq. 4 | ^vol Q_eff = Q_eff / λ | (inside eq. 5) |
//! | eq. 5 | λ = I²R' / (v_c · ρ_f · ^mass Q_eff) | [`predict_kerf_m`] and the five inverses |
//! | eq. 6 | ^mass Q_eff = ^vol Q_eff / ρ_f | [`mass_specific_energy_j_kg`], [`volume_specific_energy_j_m3`] |
//!
//! Eq. 6 only carries across foams of one molecular structure that differ in density (S/H/VH
//! EPS); never carry an EPS value to XPS. The model is for steady cutting: lead-in kerf is
//! wider because the wire starts hot (seed 001 Fig. 5).

mod materials;
mod offset;

pub use materials::{Foam, MaterialError, MaterialLibrary, Wire};
pub use offset::offset_polyline;

/// A rejected model input or a failed path offset.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KerfError {
    /// A parameter is NaN, infinite or outside its domain; `name` is the parameter's name.
    #[error("{name} = {value} is invalid: must be {requirement}")]
    InvalidParameter {
        /// Parameter name, e.g. `feed_m_s` or `feeds_mm_s[3]`.
        name: String,
        /// The value given.
        value: f64,
        /// The accepted domain, e.g. "finite and > 0".
        requirement: &'static str,
    },
    /// The polyline cannot be offset (too few distinct points, zero area, no result).
    #[error("cannot offset polyline: {0}")]
    Offset(String),
}

/// The five known quantities of seed 001 eq. 5 when predicting the kerf.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KerfInputs {
    /// Wire current I (A).
    pub current_a: f64,
    /// Wire resistance per metre R' (Ω/m).
    pub resistance_ohm_per_m: f64,
    /// Cutting velocity v_c (m/s).
    pub feed_m_s: f64,
    /// Foam density ρ_f (kg/m³).
    pub density_kg_m3: f64,
    /// Mass-specific effective heat input ^mass Q_eff (J/kg).
    pub mass_specific_energy_j_kg: f64,
}

impl KerfInputs {
    /// Inputs for cutting `foam` with `wire` at `current_a` and `feed_m_s`, taking ρ_f and
    /// ^mass Q_eff from the foam ([`Foam::mass_energy_j_kg`]) and R' from the wire.
    pub fn for_cut(current_a: f64, feed_m_s: f64, wire: &Wire, foam: &Foam) -> Self {
        Self {
            current_a,
            resistance_ohm_per_m: wire.resistance_ohm_per_m,
            feed_m_s,
            density_kg_m3: foam.density_kg_m3,
            mass_specific_energy_j_kg: foam.mass_energy_j_kg(),
        }
    }
}

/// Nominal kerf with its one-SD band (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KerfBand {
    /// Kerf at ^mass Q_eff · (1 + SD).
    pub low_m: f64,
    /// Kerf from eq. 5.
    pub nominal_m: f64,
    /// Kerf at ^mass Q_eff · (1 − SD).
    pub high_m: f64,
}

/// A kerf after the wire-diameter lower bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClampedKerf {
    /// max(λ, d_wire) (m).
    pub kerf_m: f64,
    /// True if the model predicted less than the wire diameter: the model is outside its range
    /// there (thermo-mechanical cutting), so warn the operator.
    pub clamped: bool,
}

/// Supply current limits for [`current_schedule`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurrentLimits {
    /// Lowest current the supply (or the process) allows (A), ≥ 0.
    pub min_a: f64,
    /// Highest current (A), ≥ `min_a` and > 0 (e.g. 10 A for the paper's ITECH IT6831).
    pub max_a: f64,
}

/// One current set-point of a [`current_schedule`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScheduledCurrent {
    /// Set-point (A), within the supply limits.
    pub current_a: f64,
    /// True if I(t) was clamped to a limit: the kerf will deviate from the target there.
    pub clamped: bool,
}

const POSITIVE: &str = "finite and > 0";

fn positive(name: &str, value: f64) -> Result<f64, KerfError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(KerfError::InvalidParameter {
            name: name.into(),
            value,
            requirement: POSITIVE,
        })
    }
}

/// Linear heat flux Q_L = I²·R' (W/m) (seed 001 eq. 1–2).
///
/// Eq. 1 is Q = I²R and eq. 2 Q_L = Q / L_e, with R the resistance of the in-cut wire length
/// L_e; R / L_e = R' is the resistance per metre, so Q_L = I²R'. The paper's worked example
/// uses R = 10.58 Ω/m this way; the whole wire's power is **not** divided by the cut length.
///
/// # Errors
/// Any input NaN, infinite or ≤ 0.
pub fn linear_heat_flux_w_m(current_a: f64, resistance_ohm_per_m: f64) -> Result<f64, KerfError> {
    let i = positive("current_a", current_a)?;
    Ok(i * i * positive("resistance_ohm_per_m", resistance_ohm_per_m)?)
}

/// Area-specific effective heat input Q_eff = Q_L / v_c (J/m²) (seed 001 eq. 3): the energy
/// spent per unit area of cut surface.
///
/// # Errors
/// Any input NaN, infinite or ≤ 0.
pub fn area_specific_energy_j_m2(
    linear_heat_flux_w_m: f64,
    feed_m_s: f64,
) -> Result<f64, KerfError> {
    Ok(positive("linear_heat_flux_w_m", linear_heat_flux_w_m)? / positive("feed_m_s", feed_m_s)?)
}

/// Mass-specific effective heat input ^mass Q_eff = ^vol Q_eff / ρ_f (J/kg) (seed 001 eq. 6).
///
/// # Errors
/// Any input NaN, infinite or ≤ 0.
pub fn mass_specific_energy_j_kg(
    volume_specific_energy_j_m3: f64,
    density_kg_m3: f64,
) -> Result<f64, KerfError> {
    Ok(
        positive("volume_specific_energy_j_m3", volume_specific_energy_j_m3)?
            / positive("density_kg_m3", density_kg_m3)?,
    )
}

/// Volume-specific effective heat input ^vol Q_eff = ^mass Q_eff · ρ_f (J/m³) (seed 001 eq. 6
/// solved for ^vol Q_eff).
///
/// # Errors
/// Any input NaN, infinite or ≤ 0.
pub fn volume_specific_energy_j_m3(
    mass_specific_energy_j_kg: f64,
    density_kg_m3: f64,
) -> Result<f64, KerfError> {
    Ok(
        positive("mass_specific_energy_j_kg", mass_specific_energy_j_kg)?
            * positive("density_kg_m3", density_kg_m3)?,
    )
}

/// Kerf width λ = I²R' / (v_c · ρ_f · ^mass Q_eff) (m) (seed 001 eq. 5 in the combined HCC
/// form: eq. 5 with ^vol Q_eff = ρ_f · ^mass Q_eff from eq. 6).
///
/// Worked example (seed 001 §4.5): XPS, R' = 10.58 Ω/m, I = 3 A, v_c = 0.015 m/s,
/// ^vol Q_eff = 10.1 MJ/m³ gives λ = 0.62851 mm (paper: 0.63 mm).
///
/// # Errors
/// Any input NaN, infinite or ≤ 0 (the error names the field).
pub fn predict_kerf_m(inputs: &KerfInputs) -> Result<f64, KerfError> {
    let q_eff = area_specific_energy_j_m2(
        linear_heat_flux_w_m(inputs.current_a, inputs.resistance_ohm_per_m)?,
        inputs.feed_m_s,
    )?;
    Ok(
        q_eff
            / volume_specific_energy_j_m3(inputs.mass_specific_energy_j_kg, inputs.density_kg_m3)?,
    )
}

/// Kerf with its band for a relative standard deviation `sd_fraction` of ^mass Q_eff (seed 001
/// §4.5–4.6: 10 % for XPS and EPS).
///
/// The SD is on the energy, and λ ∝ 1/Q, so the band is λ/(1 + SD) … λ/(1 − SD): slightly
/// asymmetric, ≈ ±SD·λ to first order (0.909λ … 1.111λ at 10 %).
///
/// # Errors
/// As [`predict_kerf_m`]; `sd_fraction` must be finite and in [0, 1).
pub fn predict_kerf_band(inputs: &KerfInputs, sd_fraction: f64) -> Result<KerfBand, KerfError> {
    if !(sd_fraction.is_finite() && (0.0..1.0).contains(&sd_fraction)) {
        return Err(KerfError::InvalidParameter {
            name: "sd_fraction".into(),
            value: sd_fraction,
            requirement: "finite and in [0, 1)",
        });
    }
    let nominal_m = predict_kerf_m(inputs)?;
    Ok(KerfBand {
        low_m: nominal_m / (1.0 + sd_fraction),
        nominal_m,
        high_m: nominal_m / (1.0 - sd_fraction),
    })
}

/// Wire current for a target kerf: I = √(λ·v_c·ρ_f·^mass Q_eff / R') (A) (seed 001 eq. 5
/// solved for I; the positive root).
///
/// # Errors
/// Any input NaN, infinite or ≤ 0.
pub fn current_for_kerf_a(
    kerf_m: f64,
    resistance_ohm_per_m: f64,
    feed_m_s: f64,
    density_kg_m3: f64,
    mass_specific_energy_j_kg: f64,
) -> Result<f64, KerfError> {
    let demand = kerf_energy_w_m(kerf_m, feed_m_s, density_kg_m3, mass_specific_energy_j_kg)?;
    Ok((demand / positive("resistance_ohm_per_m", resistance_ohm_per_m)?).sqrt())
}

/// Feed for a target kerf: v_c = I²R' / (λ·ρ_f·^mass Q_eff) (m/s) (seed 001 eq. 5 solved for
/// v_c). Raising feed acts like lowering current (the paper's "anti-symmetry").
///
/// # Errors
/// Any input NaN, infinite or ≤ 0.
pub fn feed_for_kerf_m_s(
    kerf_m: f64,
    current_a: f64,
    resistance_ohm_per_m: f64,
    density_kg_m3: f64,
    mass_specific_energy_j_kg: f64,
) -> Result<f64, KerfError> {
    let q_l = linear_heat_flux_w_m(current_a, resistance_ohm_per_m)?;
    Ok(q_l
        / (positive("kerf_m", kerf_m)?
            * volume_specific_energy_j_m3(mass_specific_energy_j_kg, density_kg_m3)?))
}

/// Wire resistance per metre for a target kerf: R' = λ·v_c·ρ_f·^mass Q_eff / I² (Ω/m)
/// (seed 001 eq. 5 solved for R'): picks the wire for a given supply current.
///
/// # Errors
/// Any input NaN, infinite or ≤ 0.
pub fn resistance_for_kerf_ohm_per_m(
    kerf_m: f64,
    current_a: f64,
    feed_m_s: f64,
    density_kg_m3: f64,
    mass_specific_energy_j_kg: f64,
) -> Result<f64, KerfError> {
    let demand = kerf_energy_w_m(kerf_m, feed_m_s, density_kg_m3, mass_specific_energy_j_kg)?;
    let i = positive("current_a", current_a)?;
    Ok(demand / (i * i))
}

/// Foam density that a measured kerf implies: ρ_f = I²R' / (λ·v_c·^mass Q_eff) (kg/m³)
/// (seed 001 eq. 5 solved for ρ_f). Valid only within one foam family (eq. 6).
///
/// # Errors
/// Any input NaN, infinite or ≤ 0.
pub fn density_for_kerf_kg_m3(
    kerf_m: f64,
    current_a: f64,
    resistance_ohm_per_m: f64,
    feed_m_s: f64,
    mass_specific_energy_j_kg: f64,
) -> Result<f64, KerfError> {
    let q_eff = area_specific_energy_j_m2(
        linear_heat_flux_w_m(current_a, resistance_ohm_per_m)?,
        feed_m_s,
    )?;
    Ok(q_eff
        / (positive("kerf_m", kerf_m)?
            * positive("mass_specific_energy_j_kg", mass_specific_energy_j_kg)?))
}

/// Mass-specific energy that a measured kerf implies: ^mass Q_eff = I²R' / (λ·v_c·ρ_f) (J/kg)
/// (seed 001 eq. 5 solved for ^mass Q_eff): how a material is calibrated from kerf tests.
///
/// # Errors
/// Any input NaN, infinite or ≤ 0.
pub fn mass_specific_energy_for_kerf_j_kg(
    kerf_m: f64,
    current_a: f64,
    resistance_ohm_per_m: f64,
    feed_m_s: f64,
    density_kg_m3: f64,
) -> Result<f64, KerfError> {
    let q_eff = area_specific_energy_j_m2(
        linear_heat_flux_w_m(current_a, resistance_ohm_per_m)?,
        feed_m_s,
    )?;
    Ok(q_eff / (positive("kerf_m", kerf_m)? * positive("density_kg_m3", density_kg_m3)?))
}

/// λ·v_c·ρ_f·^mass Q_eff (W/m): the heat flux a kerf demands (the left side of eq. 5).
fn kerf_energy_w_m(
    kerf_m: f64,
    feed_m_s: f64,
    density_kg_m3: f64,
    mass_specific_energy_j_kg: f64,
) -> Result<f64, KerfError> {
    Ok(positive("kerf_m", kerf_m)?
        * positive("feed_m_s", feed_m_s)?
        * volume_specific_energy_j_m3(mass_specific_energy_j_kg, density_kg_m3)?)
}

/// The kerf bounded below by the wire diameter: λ ≥ d_wire (seed 001 §4.3: at low current the
/// kerf approached the wire diameter, 0.64 mm in Fig. 5). Returns max(λ, d) and whether the
/// bound applied; a clamped value means eq. 5 is outside its range, so warn.
///
/// # Errors
/// Either input NaN, infinite or ≤ 0.
pub fn clamp_kerf_to_wire(kerf_m: f64, wire_diameter_m: f64) -> Result<ClampedKerf, KerfError> {
    let (k, d) = (
        positive("kerf_m", kerf_m)?,
        positive("wire_diameter_m", wire_diameter_m)?,
    );
    Ok(ClampedKerf {
        kerf_m: k.max(d),
        clamped: k < d,
    })
}

/// Wire-centre offset from the finished surface: λ / 2 (m) (seed 001 §4.4: a 1.1 mm kerf
/// needs a 0.55 mm offset). It covers the wire radius and the melt gap together.
///
/// # Errors
/// `kerf_m` NaN, infinite or ≤ 0.
pub fn offset_m(kerf_m: f64) -> Result<f64, KerfError> {
    Ok(positive("kerf_m", kerf_m)? / 2.0)
}

/// Constant-kerf current schedule: I(t) = √(Q_eff · v_c(t) / R') for each planned feed
/// (seed 001 §4.7 proposal, procedure C; equivalently Q_L(t) = Q_eff · v_c(t)), clamped to the
/// supply limits.
///
/// Holding Q_eff constant holds λ = Q_eff / ^vol Q_eff (eq. 4) and the surface texture
/// constant while the robot speeds up and slows down. Feeds are mm/s (converted to m/s here);
/// a zero feed (a stop) asks for 0 A, so it is raised to `min_a` and flagged if `min_a > 0`.
/// Clamped entries have `clamped = true`: the kerf deviates from the target there.
///
/// # Errors
/// A feed that is NaN, infinite or negative (named `feeds_mm_s[i]`); `area_energy_j_m2` or
/// `resistance_ohm_per_m` NaN, infinite or ≤ 0; limits not finite with 0 ≤ min_a ≤ max_a,
/// max_a > 0.
pub fn current_schedule(
    feeds_mm_s: &[f64],
    area_energy_j_m2: f64,
    resistance_ohm_per_m: f64,
    supply: CurrentLimits,
) -> Result<Vec<ScheduledCurrent>, KerfError> {
    let q_eff = positive("area_energy_j_m2", area_energy_j_m2)?;
    let r = positive("resistance_ohm_per_m", resistance_ohm_per_m)?;
    let max_a = positive("supply.max_a", supply.max_a)?;
    let min_a = supply.min_a;
    if !(min_a.is_finite() && (0.0..=max_a).contains(&min_a)) {
        return Err(KerfError::InvalidParameter {
            name: "supply.min_a".into(),
            value: min_a,
            requirement: "finite and in [0, max_a]",
        });
    }
    feeds_mm_s
        .iter()
        .enumerate()
        .map(|(i, &feed_mm_s)| {
            if !(feed_mm_s.is_finite() && feed_mm_s >= 0.0) {
                return Err(KerfError::InvalidParameter {
                    name: format!("feeds_mm_s[{i}]"),
                    value: feed_mm_s,
                    requirement: "finite and >= 0",
                });
            }
            let ideal_a = (q_eff * feed_mm_s * 1e-3 / r).sqrt();
            let current_a = ideal_a.clamp(min_a, max_a);
            Ok(ScheduledCurrent {
                current_a,
                clamped: current_a != ideal_a,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Seed 001 §4.5 worked example: XPS, 0.36 mm Nichrome, R' = 10.58 Ω/m, I = 3 A,
    /// v_c = 0.0150 m/s, ^vol Q_eff = 10.1 MJ/m³, ρ_f = 30 kg/m³.
    fn worked_example() -> KerfInputs {
        KerfInputs {
            current_a: 3.0,
            resistance_ohm_per_m: 10.58,
            feed_m_s: 0.0150,
            density_kg_m3: 30.0,
            mass_specific_energy_j_kg: mass_specific_energy_j_kg(10.1e6, 30.0).unwrap(),
        }
    }

    fn eps(density_kg_m3: f64) -> KerfInputs {
        KerfInputs {
            density_kg_m3,
            mass_specific_energy_j_kg: 297e3,
            ..worked_example()
        }
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs()
    }

    #[test]
    fn golden_worked_example_xps() {
        let q_l = linear_heat_flux_w_m(3.0, 10.58).unwrap();
        assert!(
            close(q_l, 95.22, 1e-12),
            "Q_L = {q_l} W/m (derived: 95.22 W/m)"
        );
        let q_eff = area_specific_energy_j_m2(q_l, 0.0150).unwrap();
        assert!(
            close(q_eff, 6348.0, 1e-12),
            "Q_eff = {q_eff} J/m² (derived: 6348 J/m²)"
        );
        let kerf_mm = predict_kerf_m(&worked_example()).unwrap() * 1e3;
        assert!(
            close(kerf_mm, 0.62851, 1e-5),
            "λ = {kerf_mm} mm (paper: 0.63 mm, exact 0.62851)"
        );
        assert_eq!(
            (kerf_mm * 100.0).round() / 100.0,
            0.63,
            "paper: λ = 0.63 mm"
        );
    }

    #[test]
    fn golden_eps_densities() {
        let h = predict_kerf_m(&eps(26.0)).unwrap() * 1e3;
        assert!(
            close(h, 0.822, 1e-3),
            "EPS 26 kg/m³: λ = {h} mm (derived: 0.822 mm)"
        );
        let s = predict_kerf_m(&eps(15.0)).unwrap() * 1e3;
        assert!(
            close(s, 1.425, 1e-3),
            "EPS 15 kg/m³: λ = {s} mm (derived: 1.425 mm)"
        );
        let v = volume_specific_energy_j_m3(297e3, 26.0).unwrap();
        assert!(
            close(v, 7.71e6, 2e-3),
            "297 kJ/kg × 26 = {v} (paper: 7.71 MJ/m³)"
        );
    }

    #[test]
    fn golden_offset() {
        let o = offset_m(1.1e-3).unwrap();
        assert!(
            close(o, 0.55e-3, 1e-12),
            "offset {o} m (paper §4.4: 0.55 mm for 1.1 mm)"
        );
    }

    #[test]
    fn band_brackets_nominal() {
        let b = predict_kerf_band(&worked_example(), 0.10).unwrap();
        assert!(b.low_m < b.nominal_m && b.nominal_m < b.high_m);
        assert!(close(b.low_m, b.nominal_m / 1.1, 1e-12));
        assert!(close(b.high_m, b.nominal_m / 0.9, 1e-12));
        assert!(predict_kerf_band(&worked_example(), 1.0).is_err());
        assert!(predict_kerf_band(&worked_example(), f64::NAN).is_err());
    }

    #[test]
    fn clamp_to_wire_diameter() {
        let c = clamp_kerf_to_wire(0.5e-3, 0.64e-3).unwrap();
        assert_eq!(
            c,
            ClampedKerf {
                kerf_m: 0.64e-3,
                clamped: true
            }
        );
        let c = clamp_kerf_to_wire(0.62851e-3, 0.36e-3).unwrap();
        assert_eq!(
            c,
            ClampedKerf {
                kerf_m: 0.62851e-3,
                clamped: false
            }
        );
    }

    #[test]
    fn rejects_bad_inputs_naming_the_parameter() {
        for (field, inputs) in [
            (
                "current_a",
                KerfInputs {
                    current_a: 0.0,
                    ..worked_example()
                },
            ),
            (
                "resistance_ohm_per_m",
                KerfInputs {
                    resistance_ohm_per_m: -1.0,
                    ..worked_example()
                },
            ),
            (
                "feed_m_s",
                KerfInputs {
                    feed_m_s: f64::NAN,
                    ..worked_example()
                },
            ),
            (
                "density_kg_m3",
                KerfInputs {
                    density_kg_m3: f64::INFINITY,
                    ..worked_example()
                },
            ),
            (
                "mass_specific_energy_j_kg",
                KerfInputs {
                    mass_specific_energy_j_kg: 0.0,
                    ..worked_example()
                },
            ),
        ] {
            let e = predict_kerf_m(&inputs).unwrap_err();
            assert!(
                matches!(&e, KerfError::InvalidParameter { name, .. } if name == field),
                "{e}"
            );
            assert!(e.to_string().starts_with(field), "{e}");
        }
        assert!(current_for_kerf_a(-1.0, 10.58, 0.015, 30.0, 3e5).is_err());
        assert!(offset_m(0.0).is_err());
        assert!(clamp_kerf_to_wire(1e-3, f64::NAN).is_err());
    }

    #[test]
    fn schedule_holds_area_energy_and_clamps() {
        let limits = CurrentLimits {
            min_a: 0.5,
            max_a: 4.0,
        };
        // Worked example: 15 mm/s at Q_eff 6348 J/m² needs exactly 3 A.
        let s = current_schedule(&[15.0, 0.0, 7.5, 1000.0], 6348.0, 10.58, limits).unwrap();
        assert!(close(s[0].current_a, 3.0, 1e-12) && !s[0].clamped, "{s:?}");
        assert_eq!(
            s[1],
            ScheduledCurrent {
                current_a: 0.5,
                clamped: true
            }
        );
        let q = linear_heat_flux_w_m(s[2].current_a, 10.58).unwrap() / 7.5e-3;
        assert!(
            close(q, 6348.0, 1e-12) && !s[2].clamped,
            "Q_eff held at half feed"
        );
        assert_eq!(
            s[3],
            ScheduledCurrent {
                current_a: 4.0,
                clamped: true
            }
        );
        let e = current_schedule(&[10.0, -1.0], 6348.0, 10.58, limits).unwrap_err();
        assert!(e.to_string().starts_with("feeds_mm_s[1]"), "{e}");
        let bad = CurrentLimits {
            min_a: 5.0,
            max_a: 4.0,
        };
        assert!(current_schedule(&[10.0], 6348.0, 10.58, bad).is_err());
        assert!(current_schedule(&[10.0], 0.0, 10.58, limits).is_err());
    }

    #[test]
    fn for_cut_uses_library_values() {
        let lib = MaterialLibrary::builtin();
        let inputs = KerfInputs::for_cut(
            3.0,
            0.015,
            lib.wire("nichrome_0_36mm").unwrap(),
            lib.foam("xps").unwrap(),
        );
        let kerf_mm = predict_kerf_m(&inputs).unwrap() * 1e3;
        assert!(
            close(kerf_mm, 0.62851, 1e-5),
            "λ = {kerf_mm} mm (paper: 0.63 mm)"
        );
    }

    proptest! {
        #[test]
        fn inverse_forms_round_trip(
            current_a in 0.2f64..12.0,
            resistance_ohm_per_m in 0.5f64..40.0,
            feed_m_s in 1e-4f64..0.1,
            density_kg_m3 in 5.0f64..100.0,
            energy_j_kg in 5e4f64..2e6,
        ) {
            let inputs = KerfInputs {
                current_a, resistance_ohm_per_m, feed_m_s, density_kg_m3,
                mass_specific_energy_j_kg: energy_j_kg,
            };
            let k = predict_kerf_m(&inputs).unwrap();
            let tol = 1e-12;
            prop_assert!(close(current_for_kerf_a(k, resistance_ohm_per_m, feed_m_s, density_kg_m3, energy_j_kg).unwrap(), current_a, tol));
            prop_assert!(close(feed_for_kerf_m_s(k, current_a, resistance_ohm_per_m, density_kg_m3, energy_j_kg).unwrap(), feed_m_s, tol));
            prop_assert!(close(resistance_for_kerf_ohm_per_m(k, current_a, feed_m_s, density_kg_m3, energy_j_kg).unwrap(), resistance_ohm_per_m, tol));
            prop_assert!(close(density_for_kerf_kg_m3(k, current_a, resistance_ohm_per_m, feed_m_s, energy_j_kg).unwrap(), density_kg_m3, tol));
            prop_assert!(close(mass_specific_energy_for_kerf_j_kg(k, current_a, resistance_ohm_per_m, feed_m_s, density_kg_m3).unwrap(), energy_j_kg, tol));
            let v = volume_specific_energy_j_m3(energy_j_kg, density_kg_m3).unwrap();
            prop_assert!(close(mass_specific_energy_j_kg(v, density_kg_m3).unwrap(), energy_j_kg, tol));
            // Eq. 4: ^vol Q_eff = Q_eff / λ.
            let q_eff = area_specific_energy_j_m2(linear_heat_flux_w_m(current_a, resistance_ohm_per_m).unwrap(), feed_m_s).unwrap();
            prop_assert!(close(q_eff / k, v, tol));
            // The schedule inverts eq. 3 for the current.
            let s = current_schedule(&[feed_m_s * 1e3], q_eff, resistance_ohm_per_m,
                CurrentLimits { min_a: 0.0, max_a: 1e3 }).unwrap();
            prop_assert!(close(s[0].current_a, current_a, tol) && !s[0].clamped);
        }
    }
}
