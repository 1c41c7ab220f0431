//! Bead model: width from travel and wire feed speed, the inverse, and bead height
//! (seed 004 eq. 14, eq. 25–28 and Chart 2).
//!
//! Units follow the thesis: travel speed TS in mm/s, wire feed speed WFS in m/min, widths and
//! heights in mm, wire diameter in mm.

use thiserror::Error;

/// Constant term of the width regression (seed 004 eq. 14).
const LW0_MM: f64 = 1.5;
/// Travel-speed pole of eq. 14 (mm/s).
const TS_POLE_MM_S: f64 = 14.1;
/// Travel-speed exponent of eq. 14.
const TS_EXP: f64 = 1.55;
/// Wire-feed offset of eq. 14 (m/min).
const WFS_POLE_M_MIN: f64 = 2.9;
/// Wire-feed exponent of eq. 14.
const WFS_EXP: f64 = 1.52;

/// Travel-speed range of the Chart 2 data, the validity range of eq. 14 (mm/s).
pub const TS_RANGE_MM_S: (f64, f64) = (2.2, 11.5);
/// Wire-feed range of the Chart 2 data, the validity range of eq. 14 (m/min).
pub const WFS_RANGE_M_MIN: (f64, f64) = (3.56, 5.53);

/// Errors of the bead model.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum BeadError {
    /// A parameter is NaN, infinite, non-positive or outside the range of the Chart 2 data.
    #[error("bead model: {field} = {value} is {requirement}")]
    OutOfRange {
        /// The parameter's name, with its unit.
        field: &'static str,
        /// The value given.
        value: f64,
        /// What the value must satisfy.
        requirement: String,
    },
}

/// One welding condition of seed 004 Chart 2 (University West data, ESAB OK Tubrod 14.03).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeadCondition {
    /// Experiment number (1–12).
    pub condition: u32,
    /// Mean current I_mean (A).
    pub current_a: f64,
    /// Actual wire feed speed WFS_act (m/min).
    pub wfs_m_min: f64,
    /// Travel speed TS (mm/s).
    pub ts_mm_s: f64,
    /// Measured external bead width LW_ext (mm).
    pub lw_ext_mm: f64,
}

/// Seed 004 Chart 2, verbatim: the 12 welding conditions behind eq. 14.
pub const CHART2: [BeadCondition; 12] = [
    cond(1, 125.1, 3.56, 2.20, 9.20),
    cond(2, 125.1, 3.56, 5.20, 6.60),
    cond(3, 125.1, 3.56, 7.00, 5.50),
    cond(4, 125.1, 3.56, 8.25, 4.60),
    cond(5, 155.0, 4.39, 3.70, 9.29),
    cond(6, 155.0, 4.39, 5.20, 7.88),
    cond(7, 155.0, 4.39, 7.00, 6.19),
    cond(8, 155.0, 4.39, 9.75, 5.04),
    cond(9, 181.5, 5.53, 5.20, 10.48),
    cond(10, 181.5, 5.53, 7.00, 9.18),
    cond(11, 181.5, 5.53, 9.75, 7.30),
    cond(12, 181.5, 5.53, 11.50, 6.53),
];

const fn cond(
    condition: u32,
    current_a: f64,
    wfs_m_min: f64,
    ts_mm_s: f64,
    lw_ext_mm: f64,
) -> BeadCondition {
    BeadCondition {
        condition,
        current_a,
        wfs_m_min,
        ts_mm_s,
        lw_ext_mm,
    }
}

/// Re(x^p) for real x: x^p for x ≥ 0, |x|^p·cos(pπ) for x < 0 (the principal complex power), as
/// the `Re(...)` of seed 004 eq. 14 requires.
fn re_pow(x: f64, p: f64) -> f64 {
    if x >= 0.0 {
        x.powf(p)
    } else {
        (-x).powf(p) * (p * std::f64::consts::PI).cos()
    }
}

fn check(field: &'static str, value: f64, range: (f64, f64)) -> Result<(), BeadError> {
    // A small slack so that the range ends themselves (and round-off near them) pass.
    let slack = 1e-9 * range.1;
    if value.is_finite() && value >= range.0 - slack && value <= range.1 + slack {
        Ok(())
    } else {
        Err(BeadError::OutOfRange {
            field,
            value,
            requirement: format!(
                "outside {}..={} (the Chart 2 data behind eq. 14)",
                range.0, range.1
            ),
        })
    }
}

/// External bead width LW_ext (mm) for travel speed `ts_mm_s` and wire feed `wfs_m_min`
/// (seed 004 eq. 14): `LW = 1.5 + Re((TS − 14.1)^1.55) + Re((WFS − 2.9)^1.52)`.
///
/// For TS < 14.1 the first term is `cos(1.55π)·(14.1 − TS)^1.55` = 0.156434·(14.1 − TS)^1.55.
///
/// # Errors
/// TS outside [`TS_RANGE_MM_S`] or WFS outside [`WFS_RANGE_M_MIN`]: the regression is only fitted
/// there (use [`bead_width_unchecked_mm`] to extrapolate deliberately).
pub fn bead_width_mm(ts_mm_s: f64, wfs_m_min: f64) -> Result<f64, BeadError> {
    check("ts_mm_s", ts_mm_s, TS_RANGE_MM_S)?;
    check("wfs_m_min", wfs_m_min, WFS_RANGE_M_MIN)?;
    Ok(bead_width_unchecked_mm(ts_mm_s, wfs_m_min))
}

/// Seed 004 eq. 14 without the validity check (NaN in, NaN out).
pub fn bead_width_unchecked_mm(ts_mm_s: f64, wfs_m_min: f64) -> f64 {
    LW0_MM + re_pow(ts_mm_s - TS_POLE_MM_S, TS_EXP) + re_pow(wfs_m_min - WFS_POLE_M_MIN, WFS_EXP)
}

/// The range of widths (min, max) in mm that eq. 14 gives at wire feed `wfs_m_min` over the
/// fitted travel-speed range: min at TS = 11.5 mm/s, max at TS = 2.2 mm/s (seed 004 B4's
/// LW_min / LW_max, "what the data supports").
///
/// # Errors
/// WFS outside [`WFS_RANGE_M_MIN`].
pub fn width_range_mm(wfs_m_min: f64) -> Result<(f64, f64), BeadError> {
    check("wfs_m_min", wfs_m_min, WFS_RANGE_M_MIN)?;
    Ok((
        bead_width_unchecked_mm(TS_RANGE_MM_S.1, wfs_m_min),
        bead_width_unchecked_mm(TS_RANGE_MM_S.0, wfs_m_min),
    ))
}

/// Travel speed TS (mm/s) that gives bead width `lw_mm` at wire feed `wfs_m_min`: the inverse of
/// seed 004 eq. 14 ("calculating the travel speed", §4.5):
/// `TS = 14.1 − ((LW − 1.5 − (WFS − 2.9)^1.52) / 0.156434)^(1/1.55)`.
///
/// # Errors
/// WFS outside [`WFS_RANGE_M_MIN`], or a width outside [`width_range_mm`] for that WFS (the
/// speed would fall outside [`TS_RANGE_MM_S`]).
pub fn travel_speed_for_width_mm_s(lw_mm: f64, wfs_m_min: f64) -> Result<f64, BeadError> {
    let (lo, hi) = width_range_mm(wfs_m_min)?;
    check("lw_mm", lw_mm, (lo, hi))?;
    let cos_term = (TS_EXP * std::f64::consts::PI).cos();
    let rest = (lw_mm - LW0_MM - re_pow(wfs_m_min - WFS_POLE_M_MIN, WFS_EXP)) / cos_term;
    Ok(TS_POLE_MM_S - rest.max(0.0).powf(1.0 / TS_EXP))
}

/// Wire deposition rate (mm³/s) for wire feed `wfs_m_min` and wire diameter `wire_diameter_mm`:
/// `WFS·(d_w/2)²·π` (seed 004 eq. 27 per unit time).
pub fn deposition_rate_mm3_s(wfs_m_min: f64, wire_diameter_mm: f64) -> f64 {
    wfs_m_min * 1000.0 / 60.0 * (wire_diameter_mm / 2.0).powi(2) * std::f64::consts::PI
}

/// Bead height h (mm) of a rectangular bead: `h = WFS·(d_w/2)²·π / (TS·LW)` (seed 004 eq. 28,
/// from eq. 25–27), with WFS converted from m/min to mm/s.
///
/// # Errors
/// A non-finite or non-positive argument.
pub fn bead_height_mm(
    wfs_m_min: f64,
    ts_mm_s: f64,
    lw_mm: f64,
    wire_diameter_mm: f64,
) -> Result<f64, BeadError> {
    for (field, v) in [
        ("wfs_m_min", wfs_m_min),
        ("ts_mm_s", ts_mm_s),
        ("lw_mm", lw_mm),
        ("wire_diameter_mm", wire_diameter_mm),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(BeadError::OutOfRange {
                field,
                value: v,
                requirement: "not finite and > 0".into(),
            });
        }
    }
    Ok(deposition_rate_mm3_s(wfs_m_min, wire_diameter_mm) / (ts_mm_s * lw_mm))
}

/// Maximum deposition rate DR_max (kg/h) at wire feed `wfs_m_min`, wire diameter
/// `wire_diameter_mm` and density `density_kg_m3`: `WFS·60·(d_w²/4)·π·ρ` (seed 004 eq. 24; the
/// thesis's 2.94 kg/h is WFS 5.53 m/min, d_w 1.2 mm, steel).
pub fn deposition_rate_kg_h(wfs_m_min: f64, wire_diameter_mm: f64, density_kg_m3: f64) -> f64 {
    let d_m = wire_diameter_mm / 1000.0;
    wfs_m_min * 60.0 * d_m * d_m / 4.0 * std::f64::consts::PI * density_kg_m3
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Derived eq. 14 values for conditions 1–12 (notes B5).
    const MODEL_LW: [f64; 12] = [
        9.300, 6.665, 5.296, 4.450, 9.232, 7.967, 6.598, 4.861, 10.482, 9.113, 7.376, 6.536,
    ];
    /// Derived eq. 28 heights with d_w = 1.2 mm and the measured LW (notes B5).
    const HEIGHT: [f64; 12] = [
        3.315, 1.955, 1.743, 1.768, 2.407, 2.019, 1.910, 1.684, 1.913, 1.622, 1.465, 1.388,
    ];

    /// One test per Chart 2 condition: eq. 14 width, eq. 28 height, and the inverse of eq. 14
    /// back to the condition's travel speed.
    fn check_condition(n: usize) {
        let c = CHART2[n - 1];
        assert_eq!(c.condition as usize, n);
        let lw = bead_width_mm(c.ts_mm_s, c.wfs_m_min).unwrap();
        assert!(
            (lw - MODEL_LW[n - 1]).abs() < 1.5e-3,
            "condition {n} (TS {} mm/s, WFS {} m/min): eq. 14 gives {lw:.4} mm, thesis-derived \
             {} mm, measured LW_ext {} mm",
            c.ts_mm_s,
            c.wfs_m_min,
            MODEL_LW[n - 1],
            c.lw_ext_mm
        );
        let h = bead_height_mm(c.wfs_m_min, c.ts_mm_s, c.lw_ext_mm, 1.2).unwrap();
        assert!(
            (h - HEIGHT[n - 1]).abs() < 1.5e-3,
            "condition {n}: eq. 28 with measured LW {} gives h {h:.4} mm, thesis-derived {} mm",
            c.lw_ext_mm,
            HEIGHT[n - 1]
        );
        let ts = travel_speed_for_width_mm_s(lw, c.wfs_m_min).unwrap();
        assert!(
            (ts - c.ts_mm_s).abs() < 1e-9,
            "condition {n}: inverse of eq. 14 gives TS {ts}, Chart 2 {}",
            c.ts_mm_s
        );
    }

    macro_rules! condition_tests {
        ($($name:ident => $n:expr),* $(,)?) => {
            $(#[test] fn $name() { check_condition($n); })*
        };
    }
    condition_tests!(
        chart2_condition_01 => 1, chart2_condition_02 => 2, chart2_condition_03 => 3,
        chart2_condition_04 => 4, chart2_condition_05 => 5, chart2_condition_06 => 6,
        chart2_condition_07 => 7, chart2_condition_08 => 8, chart2_condition_09 => 9,
        chart2_condition_10 => 10, chart2_condition_11 => 11, chart2_condition_12 => 12,
    );

    #[test]
    fn eq14_width_all_twelve_conditions() {
        let mut max_err: f64 = 0.0;
        for (c, &want) in CHART2.iter().zip(&MODEL_LW) {
            let lw = bead_width_mm(c.ts_mm_s, c.wfs_m_min).unwrap();
            assert!(
                (lw - want).abs() < 1.5e-3,
                "condition {}: eq. 14 gives {lw:.4} mm, thesis-derived {want} mm (measured {})",
                c.condition,
                c.lw_ext_mm
            );
            max_err = max_err.max(lw - c.lw_ext_mm);
        }
        assert!(
            (max_err - 0.408).abs() < 2e-3,
            "largest model − measured error {max_err:.4}, notes: +0.408 mm (condition 7)"
        );
    }

    #[test]
    fn eq28_height_all_twelve_conditions() {
        for (c, &want) in CHART2.iter().zip(&HEIGHT) {
            let h = bead_height_mm(c.wfs_m_min, c.ts_mm_s, c.lw_ext_mm, 1.2).unwrap();
            assert!(
                (h - want).abs() < 1.5e-3,
                "condition {}: eq. 28 gives {h:.4} mm, thesis-derived {want} mm",
                c.condition
            );
        }
    }

    #[test]
    fn inverse_matches_fixtures_and_round_trips() {
        let ts = travel_speed_for_width_mm_s(7.0, 5.53).unwrap();
        assert!(
            (ts - 10.475).abs() < 2e-3,
            "LW 7, WFS 5.53: TS {ts}, notes 10.475"
        );
        let ts = travel_speed_for_width_mm_s(6.0, 4.39).unwrap();
        assert!(
            (ts - 7.868).abs() < 2e-3,
            "LW 6, WFS 4.39: TS {ts}, notes 7.868"
        );
        for c in &CHART2 {
            let lw = bead_width_mm(c.ts_mm_s, c.wfs_m_min).unwrap();
            let ts = travel_speed_for_width_mm_s(lw, c.wfs_m_min).unwrap();
            assert!((ts - c.ts_mm_s).abs() < 1e-9, "condition {}", c.condition);
        }
    }

    #[test]
    fn floor_values_and_range_errors() {
        for (wfs, want) in [(3.56, 2.03), (4.39, 3.33), (5.53, 5.85)] {
            let lw = bead_width_unchecked_mm(14.1, wfs);
            assert!(
                (lw - want).abs() < 6e-3,
                "floor at WFS {wfs}: {lw}, notes {want}"
            );
        }
        assert!(bead_width_mm(1.0, 4.0).is_err());
        assert!(bead_width_mm(5.0, 6.0).is_err());
        assert!(bead_width_mm(f64::NAN, 4.0).is_err());
        let (lo, hi) = width_range_mm(5.53).unwrap();
        assert!(
            (lo - 6.536).abs() < 2e-3,
            "LW_min at WFS 5.53 = condition 12's model value"
        );
        assert!(travel_speed_for_width_mm_s(lo - 0.1, 5.53).is_err());
        assert!(travel_speed_for_width_mm_s(hi + 0.1, 5.53).is_err());
        assert!(bead_height_mm(4.0, 0.0, 5.0, 1.2).is_err());
    }

    #[test]
    fn eq24_deposition_rate() {
        let dr = deposition_rate_kg_h(5.53, 1.2, 7850.0);
        assert!((dr - 2.946).abs() < 2e-3, "DR_max {dr}, thesis 2.94 kg/h");
        let q = deposition_rate_mm3_s(5.53, 1.2);
        assert!((q - 104.24).abs() < 0.01, "{q} mm³/s, notes 104.24");
    }
}
