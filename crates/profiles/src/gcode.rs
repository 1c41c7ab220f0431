//! G-code output settings: the emitter's part of a profile (the `gcode:` section), checked
//! against the machine's axes.

use std::collections::BTreeMap;

use cell_config::{Allowed, FieldError};

use crate::template::check_template;

/// A G-code dialect: what the controller accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Dialect {
    /// GRBL 1.1 (and FluidNC, grblHAL).
    Grbl,
    /// LinuxCNC's RS274NGC.
    Linuxcnc,
    /// Mach3.
    Mach3,
    /// Marlin (extrusion printers).
    Marlin,
}

/// How feeds are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FeedMode {
    /// G94: F in mm/min along the path.
    UnitsPerMinute,
    /// G93: F = 1 / (move duration in minutes), so 4-axis carriages arrive together.
    InverseTime,
}

/// Which axis letter each toolpath coordinate is written as.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct AxisWords {
    /// Primary point x (e.g. `X`).
    pub x: char,
    /// Primary point y (e.g. `Y`).
    pub y: char,
    /// Primary point z; absent on a 2-axis or 4-axis hot-wire machine.
    #[serde(default)]
    pub z: Option<char>,
    /// Secondary (UV carriage) x: `U` on LinuxCNC, often `Z` on a GRBL 4-axis board.
    #[serde(default)]
    pub u: Option<char>,
    /// Secondary y: `V`, or `A` on a GRBL 4-axis board.
    #[serde(default)]
    pub v: Option<char>,
}

/// The words that switch the process power (wire heat, laser, spindle).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct PowerWords {
    /// The word that turns power on, e.g. `M3`; the S value follows it.
    pub on: String,
    /// The word that turns power off, e.g. `M5`.
    pub off: String,
    /// S value per unit of the toolpath's power (e.g. 100 for S in centiamps).
    pub s_per_unit: f64,
    /// Decimal places of S.
    #[serde(default)]
    pub s_decimals: usize,
}

/// Length units of a program.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Units {
    /// Millimetres (G21).
    #[default]
    Mm,
    /// Inches (G20): coordinates and feeds are divided by 25.4.
    Inch,
}

/// Pierce handling for sheet cutting: power goes on at the start of every cut segment and off
/// at its end, instead of once for the whole program.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Pierce {
    /// Dwell with power on before the cut moves, s (the pierce time).
    pub dwell_s: f64,
    /// Torch or head height while piercing, mm on the `z` axis word; needs `z_cut_mm` and
    /// `z_travel_mm` too.
    #[serde(default)]
    pub z_pierce_mm: Option<f64>,
    /// Height while cutting, mm.
    #[serde(default)]
    pub z_cut_mm: Option<f64>,
    /// Height for travel moves between cuts, mm.
    #[serde(default)]
    pub z_travel_mm: Option<f64>,
}

/// Whether E words are positions or increments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExtrusionMode {
    /// M82: E is the filament position since the last reset.
    Absolute,
    /// M83: E is the filament pushed by this move.
    Relative,
}

/// Material extrusion (G-Wing-style printing): the toolpath's power on deposit segments is a
/// volumetric flow (mm³/s), written as filament length on the extruder axis.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Extrusion {
    /// The extruder's axis letter (`E` on Marlin).
    #[serde(default = "default_extruder_axis")]
    pub axis: char,
    /// Absolute or relative E.
    pub mode: ExtrusionMode,
    /// Filament diameter, mm (E = volume / filament cross-section).
    pub filament_diameter_mm: f64,
    /// Filament pulled back before each travel move, mm (0: none).
    #[serde(default)]
    pub retract_mm: f64,
    /// Speed of the retract and the un-retract, mm/s.
    #[serde(default = "default_retract_feed")]
    pub retract_feed_mm_s: f64,
    /// Lift of the nozzle during travel moves, mm (0: none; needs the `z` axis word).
    #[serde(default)]
    pub z_hop_mm: f64,
    /// Lift only for travel moves that cross a deposit already made in their layer (the
    /// segments' `layer`; `cell_geometry::travel_crosses_polylines` on the bead centre lines),
    /// as Cura's "Z Hop Only Over Printed Parts"; false: lift for every travel.
    #[serde(default)]
    pub z_hop_only_when_crossing: bool,
    /// The firmware's motion settings, for print-time estimates (absent: the estimator's
    /// defaults, Marlin 2's stock configuration).
    #[serde(default)]
    pub motion: Option<FirmwareMotion>,
}

/// A printer firmware's planner settings, as Marlin 2 names them (`Configuration.h`; M201,
/// M203, M204, `JUNCTION_DEVIATION_MM`, `MINIMUM_PLANNER_SPEED`, `BLOCK_BUFFER_SIZE`). Axis
/// arrays are X, Y, Z, E.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct FirmwareMotion {
    /// `DEFAULT_MAX_FEEDRATE` (M203), mm/s.
    pub max_feedrate_mm_s: [f64; 4],
    /// `DEFAULT_MAX_ACCELERATION` (M201), mm/s².
    pub max_acceleration_mm_s2: [f64; 4],
    /// `DEFAULT_ACCELERATION` (M204 P), moves that extrude, mm/s².
    pub print_acceleration_mm_s2: f64,
    /// `DEFAULT_RETRACT_ACCELERATION` (M204 R), E-only moves, mm/s².
    pub retract_acceleration_mm_s2: f64,
    /// `DEFAULT_TRAVEL_ACCELERATION` (M204 T), moves without E, mm/s².
    pub travel_acceleration_mm_s2: f64,
    /// `JUNCTION_DEVIATION_MM`, mm.
    pub junction_deviation_mm: f64,
    /// `MINIMUM_PLANNER_SPEED`, mm/s.
    pub minimum_planner_speed_mm_s: f64,
    /// `BLOCK_BUFFER_SIZE`, blocks (one slot stays free, so the look-ahead is one less).
    pub block_buffer_size: usize,
}

impl FirmwareMotion {
    /// Marlin 2's stock configuration: max feed {300, 300, 5, 25} mm/s, max acceleration
    /// {3000, 3000, 100, 10000} mm/s², print/retract/travel acceleration 3000 mm/s², junction
    /// deviation 0.013 mm, minimum planner speed 0.05 mm/s, 16 blocks.
    pub const MARLIN_2_DEFAULTS: Self = Self {
        max_feedrate_mm_s: [300.0, 300.0, 5.0, 25.0],
        max_acceleration_mm_s2: [3000.0, 3000.0, 100.0, 10000.0],
        print_acceleration_mm_s2: 3000.0,
        retract_acceleration_mm_s2: 3000.0,
        travel_acceleration_mm_s2: 3000.0,
        junction_deviation_mm: 0.013,
        minimum_planner_speed_mm_s: 0.05,
        block_buffer_size: 16,
    };
}

fn default_extruder_axis() -> char {
    'E'
}

fn default_retract_feed() -> f64 {
    40.0
}

/// G-code output settings (the emitter's part of a profile).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct GcodeSettings {
    /// The controller's dialect.
    pub dialect: Dialect,
    /// Axis letters.
    pub axis_words: AxisWords,
    /// Length units of the program.
    #[serde(default)]
    pub units: Units,
    /// Decimal places of coordinates.
    pub decimals: usize,
    /// Feed mode.
    pub feed_mode: FeedMode,
    /// Lines after the emitter's modal line (units, absolute mode, feed mode) and before the
    /// first move. `{job}` and `{profile}` are replaced by the (sanitised) job id and profile
    /// name. The modal words G20/G21, G90/G91 and G93/G94 come from `units` and `feed_mode`
    /// and may not appear here.
    #[serde(default)]
    pub program_start: Vec<String>,
    /// Lines after the last move (before the program end word), with the same placeholders.
    #[serde(default)]
    pub program_end: Vec<String>,
    /// Power words; absent: the program switches no power.
    #[serde(default)]
    pub power: Option<PowerWords>,
    /// Dwell after switching power on, before the first move, s (wire pre-heat). Without
    /// `pierce` the power stays on for the whole program.
    #[serde(default)]
    pub preheat_dwell_s: f64,
    /// Sheet cutting: power on and off around every cut segment (needs `power`).
    #[serde(default)]
    pub pierce: Option<Pierce>,
    /// Extrusion printing: E words from the deposit segments' flow.
    #[serde(default)]
    pub extrusion: Option<Extrusion>,
    /// Fit G2/G3 arcs to runs of points that lie within this distance of one circle, mm
    /// (absent: straight moves only). Only on machines without a second carriage.
    #[serde(default)]
    pub arc_tolerance_mm: Option<f64>,
}

impl GcodeSettings {
    /// Checks the section against the machine's `axes`, part by part in this order: axis
    /// words, number format and power, templates, pierce, feed mode, extrusion, arcs. Fields
    /// are named relative to `gcode`.
    ///
    /// # Errors
    /// The first field with a problem.
    pub fn validate(&self, axes: &BTreeMap<char, [f64; 2]>) -> Result<(), FieldError> {
        self.validate_axis_words(axes)?;
        self.validate_numbers()?;
        self.validate_templates()?;
        if let Some(pierce) = &self.pierce {
            self.validate_pierce(pierce, axes)
                .map_err(|e| e.within("pierce"))?;
        }
        if self.dialect == Dialect::Marlin && self.feed_mode == FeedMode::InverseTime {
            return Err(FieldError::new(
                "feed_mode",
                "Marlin has no inverse-time feed (G93); use units_per_minute",
            ));
        }
        if let Some(e) = &self.extrusion {
            self.validate_extrusion(e, axes)
                .map_err(|e| e.within("extrusion"))?;
        }
        self.validate_arcs()
    }

    /// Axis words are machine axes; `u` and `v` come together.
    fn validate_axis_words(&self, axes: &BTreeMap<char, [f64; 2]>) -> Result<(), FieldError> {
        let w = &self.axis_words;
        for (field, letter) in [
            ("x", Some(w.x)),
            ("y", Some(w.y)),
            ("z", w.z),
            ("u", w.u),
            ("v", w.v),
        ] {
            if let Some(l) = letter {
                if !axes.contains_key(&l) {
                    return Err(FieldError::new(
                        format!("axis_words.{field}"),
                        format!("axis {l} is not one of the machine's axes"),
                    ));
                }
            }
        }
        if w.u.is_some() != w.v.is_some() {
            return Err(FieldError::new(
                "axis_words",
                "u and v come together (the second carriage)",
            ));
        }
        Ok(())
    }

    /// At most 6 decimals, a pre-heat dwell ≥ 0 and an S scale > 0.
    fn validate_numbers(&self) -> Result<(), FieldError> {
        Allowed::at_most(6.0)
            .whole()
            .check_field("decimals", self.decimals as f64, "")?;
        Allowed::NON_NEGATIVE.check_field("preheat_dwell_s", self.preheat_dwell_s, "s")?;
        if let Some(p) = &self.power {
            Allowed::POSITIVE.check_field("power.s_per_unit", p.s_per_unit, "")?;
        }
        Ok(())
    }

    /// Every start and end line passes [`check_template`].
    fn validate_templates(&self) -> Result<(), FieldError> {
        for (field, lines) in [
            ("program_start", &self.program_start),
            ("program_end", &self.program_end),
        ] {
            for (i, line) in lines.iter().enumerate() {
                check_template(line)
                    .map_err(|reason| FieldError::new(format!("{field}[{i}]"), reason))?;
            }
        }
        Ok(())
    }

    /// Pierce handling needs a power section; heights come together, need the `z` axis word
    /// and lie within its travel. Fields relative to `pierce`.
    fn validate_pierce(
        &self,
        pierce: &Pierce,
        axes: &BTreeMap<char, [f64; 2]>,
    ) -> Result<(), FieldError> {
        if self.power.is_none() {
            return Err(FieldError::new(
                "",
                "pierce handling switches power: a power section is needed",
            ));
        }
        Allowed::NON_NEGATIVE.check_field("dwell_s", pierce.dwell_s, "s")?;
        let heights = [pierce.z_pierce_mm, pierce.z_cut_mm, pierce.z_travel_mm];
        if heights.iter().all(Option::is_none) {
            return Ok(());
        }
        if heights.iter().any(Option::is_none) {
            return Err(FieldError::new(
                "",
                "z_pierce_mm, z_cut_mm and z_travel_mm come together",
            ));
        }
        let Some(z) = self.axis_words.z else {
            return Err(FieldError::new("", "pierce heights need the z axis word"));
        };
        let [lo, hi] = axes[&z];
        for (name, h) in [
            ("z_pierce_mm", pierce.z_pierce_mm),
            ("z_cut_mm", pierce.z_cut_mm),
            ("z_travel_mm", pierce.z_travel_mm),
        ] {
            Allowed::closed(lo, hi)
                .check(h.unwrap_or_default(), "mm")
                .map_err(|e| e.because(format!("the {z} travel")).at(name))?;
        }
        Ok(())
    }

    /// Extrusion replaces power; its axis is a machine axis; filament diameter and retract
    /// speed > 0, retract and Z-hop ≥ 0, a Z-hop needs the `z` axis word. Fields relative to
    /// `extrusion`.
    fn validate_extrusion(
        &self,
        e: &Extrusion,
        axes: &BTreeMap<char, [f64; 2]>,
    ) -> Result<(), FieldError> {
        if self.power.is_some() {
            return Err(FieldError::new(
                "",
                "an extrusion profile's power is the flow: remove the power section",
            ));
        }
        if !axes.contains_key(&e.axis) {
            return Err(FieldError::new(
                "axis",
                format!("axis {} is not one of the machine's axes", e.axis),
            ));
        }
        Allowed::POSITIVE.check_field("filament_diameter_mm", e.filament_diameter_mm, "mm")?;
        for (name, v) in [("retract_mm", e.retract_mm), ("z_hop_mm", e.z_hop_mm)] {
            Allowed::NON_NEGATIVE.check_field(name, v, "mm")?;
        }
        Allowed::POSITIVE.check_field("retract_feed_mm_s", e.retract_feed_mm_s, "mm/s")?;
        if e.z_hop_mm > 0.0 && self.axis_words.z.is_none() {
            return Err(FieldError::new("z_hop_mm", "a Z-hop needs the z axis word"));
        }
        if let Some(m) = &e.motion {
            let rates =
                (m.max_feedrate_mm_s.iter()).map(|v| ("motion.max_feedrate_mm_s", *v, "mm/s"));
            let accels = (m.max_acceleration_mm_s2.iter())
                .map(|v| ("motion.max_acceleration_mm_s2", *v, "mm/s²"));
            for (name, v, unit) in rates.chain(accels).chain([
                (
                    "motion.print_acceleration_mm_s2",
                    m.print_acceleration_mm_s2,
                    "mm/s²",
                ),
                (
                    "motion.retract_acceleration_mm_s2",
                    m.retract_acceleration_mm_s2,
                    "mm/s²",
                ),
                (
                    "motion.travel_acceleration_mm_s2",
                    m.travel_acceleration_mm_s2,
                    "mm/s²",
                ),
                (
                    "motion.junction_deviation_mm",
                    m.junction_deviation_mm,
                    "mm",
                ),
                (
                    "motion.minimum_planner_speed_mm_s",
                    m.minimum_planner_speed_mm_s,
                    "mm/s",
                ),
            ]) {
                Allowed::POSITIVE.check_field(name, v, unit)?;
            }
            if m.block_buffer_size < 2 {
                return Err(FieldError::new(
                    "motion.block_buffer_size",
                    "at least 2 blocks (one stays free)",
                ));
            }
        }
        Ok(())
    }

    /// An arc tolerance > 0, and only on a machine without a second carriage.
    fn validate_arcs(&self) -> Result<(), FieldError> {
        if let Some(t) = self.arc_tolerance_mm {
            Allowed::POSITIVE.check_field("arc_tolerance_mm", t, "mm")?;
            if self.axis_words.u.is_some() {
                return Err(FieldError::new(
                    "arc_tolerance_mm",
                    "arcs are not fitted on a machine with a second carriage (u, v)",
                ));
            }
        }
        Ok(())
    }
}
