//! The WAAM process profile: wire, bead, speeds, patterns, dwell and cost rates, loadable from
//! YAML (`config/processes/waam.yaml`). Defaults are seed 004's values where the thesis has one
//! and documented choices otherwise.

use std::path::Path;

use cell_config::{Allowed, ParseError, Place, Problem};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::bead;
use crate::cost::CostRates;
use crate::torch::TorchPose;

/// Errors loading or checking a process profile.
#[derive(Debug, Error)]
pub enum ProcessError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Bad YAML, an unknown key or a mistyped value, with its line and dotted field path.
    #[error(transparent)]
    Parse(#[from] ParseError),
    /// A value out of its allowed range.
    #[error("{}{reason}", Place::field(file, field))]
    Invalid {
        /// The file (or a label).
        file: String,
        /// The field.
        field: &'static str,
        /// The value, its unit and the range it must lie in (or the rule it breaks).
        reason: Problem,
    },
}

/// How the bead width of deposit paths is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum WidthMode {
    /// One width for every bead: eq. 14 at `travel_speed_mm_s` and `wire_feed_m_min`; the layer
    /// is filled by perimeters and infill.
    #[default]
    Fixed,
    /// The thesis's mode (seed 004 §4.4–4.5, notes B4): one bead along the middle of the wall,
    /// its width measured wall to wall along the path normal and clamped to
    /// [`WaamProcess::width_limits_mm`], the speed set by the inverse of eq. 14. No infill.
    WallDriven,
}

/// A WAAM process profile (serde, unknown keys rejected; every field has a default).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WaamProcess {
    /// d_w, wire diameter (mm). Default 1.2: the thesis never states it, but its eq. 24
    /// (2.94 kg/h) and Chart 4 require 1.2 mm (notes B5).
    pub wire_diameter_mm: f64,
    /// WFS, wire feed speed (m/min). Default 5.53, Chart 2's highest (conditions 9–12) and the
    /// one Chart 4's toolpath implies.
    pub wire_feed_m_min: f64,
    /// Nominal layer height (mm), what the slicer should step by. Default 1.6 (thesis §4.5).
    pub layer_height_mm: f64,
    /// TS, deposition travel speed in [`WidthMode::Fixed`] (mm/s). Default 7.0 (Chart 2,
    /// condition 10: LW 9.11 mm by eq. 14, h 1.62 mm by eq. 28, matching the 1.6 mm layer).
    pub travel_speed_mm_s: f64,
    /// Width mode. Default [`WidthMode::Fixed`].
    pub width_mode: WidthMode,
    /// Lower clamp of the bead width LW_min (mm) in wall-driven mode; `None` (default) = the
    /// narrowest bead eq. 14 supports at this WFS (TS = 11.5 mm/s).
    pub width_min_mm: Option<f64>,
    /// Upper clamp LW_max (mm); `None` (default) = the widest bead eq. 14 supports (TS = 2.2).
    pub width_max_mm: Option<f64>,
    /// Number of perimeter loops per contour in fixed mode. Default 1.
    pub perimeters: usize,
    /// Whether fixed mode fills the inside of the perimeters with infill. Default true.
    pub infill: bool,
    /// Infill line spacing as a fraction of the bead width (≥ 0.1). Default 1.0: rectangular
    /// beads side by side (the thesis's rectangular cross-section, eq. 25).
    pub infill_spacing_ratio: f64,
    /// Infill angle of layer 0 (degrees from +X). Default 0.
    pub infill_angle_deg: f64,
    /// Infill angle added per layer (degrees). Default 90: layers alternate angle, angle + 90°.
    pub infill_layer_rotation_deg: f64,
    /// Longest zig-zag link between consecutive infill lines, as a multiple of the spacing; a
    /// longer gap (or one leaving the region) becomes a travel. Default 3.
    pub infill_link_max_ratio: f64,
    /// Arc length (mm) by which the start of every closed loop moves along it per layer, so weld
    /// starts do not stack. Default 25.
    pub start_shift_mm: f64,
    /// Speed of non-depositing travel moves (mm/s). Default 50.
    pub travel_move_speed_mm_s: f64,
    /// Height (mm) by which travel moves rise above the higher of their two ends, to clear the
    /// beads. Default 0 (the thesis moves straight; its travel is only costed, eq. 19).
    pub travel_lift_mm: f64,
    /// Time per arc start/stop pair (s), added to a layer's travel time. Default 2.0 (Chart 4's
    /// 10 min for 302 starts/stops, notes B7).
    pub arc_start_stop_s: f64,
    /// Interlayer dwell (cooling) time after each layer (s). Default 0, as in the thesis's
    /// costing (t_wait = 0: the robot prints other parts meanwhile).
    pub dwell_s: f64,
    /// Chord tolerance for flattening the round joins of offsets (mm, ≥ 1e-4). Default 0.05.
    pub arc_tolerance_mm: f64,
    /// Longest spacing of wall-width samples along a wall-driven path (mm, ≥ 0.05); the thesis
    /// inserts points where the wall geometry changes (Fig. 15). Default 2.
    pub wall_sample_mm: f64,
    /// Machining allowance per side (mm, ≥ 0): the deposit must contain the part grown by this
    /// much (walls outwards, holes inwards, tops upwards), since WAAM is near-net and the part is
    /// machined to its net shape afterwards (seed 004 §1, eq. 5–6). Default 1.0.
    pub machining_allowance_mm: f64,
    /// Torch pose: lead and work angles, contact-tip-to-work distance ([`TorchPose`];
    /// applied by [`crate::to_msg::toolpath_msg_for`]). Default upright, TCP at the wire tip.
    pub torch: TorchPose,
    /// Cost rates (seed 004 Chart 3).
    pub cost: CostRates,
}

impl Default for WaamProcess {
    fn default() -> Self {
        Self {
            wire_diameter_mm: 1.2,
            wire_feed_m_min: 5.53,
            layer_height_mm: 1.6,
            travel_speed_mm_s: 7.0,
            width_mode: WidthMode::Fixed,
            width_min_mm: None,
            width_max_mm: None,
            perimeters: 1,
            infill: true,
            infill_spacing_ratio: 1.0,
            infill_angle_deg: 0.0,
            infill_layer_rotation_deg: 90.0,
            infill_link_max_ratio: 3.0,
            start_shift_mm: 25.0,
            travel_move_speed_mm_s: 50.0,
            travel_lift_mm: 0.0,
            arc_start_stop_s: 2.0,
            dwell_s: 0.0,
            arc_tolerance_mm: 0.05,
            wall_sample_mm: 2.0,
            machining_allowance_mm: 1.0,
            torch: TorchPose::default(),
            cost: CostRates::default(),
        }
    }
}

/// Most perimeter loops per contour (issue 23: every size has a limit; the loop over them
/// runs once per count, even after the region is used up). The thesis uses 1, walls rarely
/// take more than 5; the limit is 10× that.
pub const MAX_PERIMETERS: usize = 50;

impl WaamProcess {
    /// Parses and checks a YAML profile; `file` labels errors.
    ///
    /// # Errors
    /// Bad YAML, unknown or mistyped keys (with line and dotted path), invalid values.
    pub fn from_yaml_str(text: &str, file: &str) -> Result<Self, ProcessError> {
        let p: WaamProcess = cell_config::from_yaml_str(text, file)?;
        p.check(file)?;
        Ok(p)
    }

    /// Reads, parses and checks a YAML profile.
    ///
    /// # Errors
    /// As [`WaamProcess::from_yaml_str`], plus I/O errors.
    pub fn from_path(path: &Path) -> Result<Self, ProcessError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ProcessError::Io {
            file: file.clone(),
            source,
        })?;
        Self::from_yaml_str(&text, &file)
    }

    /// Checks every value's range.
    ///
    /// # Errors
    /// The first invalid field.
    pub fn check(&self, file: &str) -> Result<(), ProcessError> {
        let invalid = |field: &'static str, reason: Problem| ProcessError::Invalid {
            file: file.into(),
            field,
            reason,
        };
        let check = |field: &'static str, v: f64, allowed: Allowed, unit: &'static str| {
            allowed.check(v, unit).map_err(|e| invalid(field, e.into()))
        };
        for (field, v, unit) in [
            ("wire_diameter_mm", self.wire_diameter_mm, "mm"),
            ("layer_height_mm", self.layer_height_mm, "mm"),
            ("infill_spacing_ratio", self.infill_spacing_ratio, ""),
            ("infill_link_max_ratio", self.infill_link_max_ratio, ""),
            (
                "travel_move_speed_mm_s",
                self.travel_move_speed_mm_s,
                "mm/s",
            ),
            ("arc_tolerance_mm", self.arc_tolerance_mm, "mm"),
            ("wall_sample_mm", self.wall_sample_mm, "mm"),
        ] {
            check(field, v, Allowed::POSITIVE, unit)?;
        }
        // Lower bounds that keep the line and sample counts finite (no hang on a typo).
        for (field, v, min, unit) in [
            ("infill_spacing_ratio", self.infill_spacing_ratio, 0.1, ""),
            ("wall_sample_mm", self.wall_sample_mm, 0.05, "mm"),
            ("arc_tolerance_mm", self.arc_tolerance_mm, 1e-4, "mm"),
        ] {
            check(field, v, Allowed::at_least(min), unit)?;
        }
        for (field, v, unit) in [
            ("start_shift_mm", self.start_shift_mm, "mm"),
            ("travel_lift_mm", self.travel_lift_mm, "mm"),
            ("arc_start_stop_s", self.arc_start_stop_s, "s"),
            ("dwell_s", self.dwell_s, "s"),
            ("machining_allowance_mm", self.machining_allowance_mm, "mm"),
        ] {
            check(field, v, Allowed::NON_NEGATIVE, unit)?;
        }
        Allowed::closed(0.0, MAX_PERIMETERS as f64)
            .whole()
            .check(self.perimeters as f64, "")
            .map_err(|e| invalid("perimeters", e.because("MAX_PERIMETERS").into()))?;
        for (field, v) in [
            ("infill_angle_deg", self.infill_angle_deg),
            ("infill_layer_rotation_deg", self.infill_layer_rotation_deg),
        ] {
            check(field, v, Allowed::FINITE, "deg")?;
        }
        // The bead model decides (with its round-off slack); the message gives its fitted range.
        bead::bead_width_mm(self.travel_speed_mm_s, self.wire_feed_m_min).map_err(|e| {
            let bead::BeadError::OutOfRange { field, value, .. } = e;
            let (field, (lo, hi), unit) = if field == "ts_mm_s" {
                ("travel_speed_mm_s", bead::TS_RANGE_MM_S, "mm/s")
            } else {
                ("wire_feed_m_min", bead::WFS_RANGE_M_MIN, "m/min")
            };
            let range = cell_config::OutOfRange::new(value, Allowed::closed(lo, hi), unit)
                .because("the Chart 2 data behind eq. 14");
            invalid(field, range.into())
        })?;
        let (lo, hi) = self.width_limits_mm();
        if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi) {
            return Err(invalid(
                "width_min_mm",
                format!("[{lo}, {hi}] mm: width limits must satisfy 0 < min <= max").into(),
            ));
        }
        if let Some((field, reason)) = self.torch.problem() {
            return Err(invalid(field, reason.into()));
        }
        let r = &self.cost;
        for (field, v, unit) in [
            ("cost.wire_sek_kg", r.wire_sek_kg, "SEK/kg"),
            ("cost.material_sek_kg", r.material_sek_kg, "SEK/kg"),
            ("cost.waam_sek_h", r.waam_sek_h, "SEK/h"),
            ("cost.machining_sek_h", r.machining_sek_h, "SEK/h"),
            ("cost.substrate_h", r.substrate_h, "h"),
        ] {
            check(field, v, Allowed::NON_NEGATIVE, unit)?;
        }
        for (field, v, unit) in [
            ("cost.deposition_kg_h", r.deposition_kg_h, "kg/h"),
            ("cost.removal_kg_h", r.removal_kg_h, "kg/h"),
            ("cost.density_kg_m3", r.density_kg_m3, "kg/m³"),
            ("cost.buy_to_fly", r.buy_to_fly, ""),
            ("cost.cooling_ratio", r.cooling_ratio, ""),
        ] {
            check(field, v, Allowed::POSITIVE, unit)?;
        }
        Ok(())
    }

    /// Bead width (mm) in fixed mode: eq. 14 at `travel_speed_mm_s`, `wire_feed_m_min`.
    pub fn fixed_width_mm(&self) -> f64 {
        bead::bead_width_unchecked_mm(self.travel_speed_mm_s, self.wire_feed_m_min)
    }

    /// Bead height (mm) in fixed mode: eq. 28 with [`WaamProcess::fixed_width_mm`].
    pub fn fixed_height_mm(&self) -> f64 {
        bead::deposition_rate_mm3_s(self.wire_feed_m_min, self.wire_diameter_mm)
            / (self.travel_speed_mm_s * self.fixed_width_mm())
    }

    /// (LW_min, LW_max) in mm for wall-driven mode: the configured clamps intersected with what
    /// eq. 14 supports at this WFS (so the inverse speed always stays in Chart 2's range).
    pub fn width_limits_mm(&self) -> (f64, f64) {
        let (lo, hi) = bead::width_range_mm(self.wire_feed_m_min).unwrap_or((f64::NAN, f64::NAN));
        (
            self.width_min_mm.map_or(lo, |m| m.max(lo)),
            self.width_max_mm.map_or(hi, |m| m.min(hi)),
        )
    }
}

#[cfg(test)]
mod size_limits {
    use super::*;

    #[test]
    fn perimeters_at_the_limit_pass_and_one_more_is_refused() {
        assert!(WaamProcess::from_yaml_str("perimeters: 50\n", "p.yaml").is_ok());
        let e = WaamProcess::from_yaml_str("perimeters: 51\n", "p.yaml")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "p.yaml: field `perimeters`: 51 is out of range: must be in [0, 50] (MAX_PERIMETERS)"
        );
    }
}
