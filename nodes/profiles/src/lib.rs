//! Machine profiles: what a machine in the cell can do, read from `config/machines/*.yaml`.
//!
//! A profile names the machine's axes and their travel, its feed limit and the geometry of its
//! process (for a hot-wire cutter: the tower separation and where the foam block sits). The
//! planner checks its paths against it; the emitter and the bridge read the same file, so one
//! file describes one machine.
//!
//! Every key is checked: an unknown or mistyped key, or a value out of range, is an error that
//! names the file and the field (and the line, for YAML syntax and unknown keys).
//!
//! ```
//! let profile = cell_profiles::MachineProfile::resolve("linuxcnc-xyuv").unwrap();
//! assert!(profile.is_four_axis_hotwire());
//! assert!(profile.check_position(&[('X', 10.0), ('U', 700.0)]).is_err());
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub mod rapid;
pub use rapid::RapidSettings;

/// The profiles shipped in `config/machines/`, compiled in: (name, YAML text).
pub const EMBEDDED_PROFILES: &[(&str, &str)] = &[
    (
        "abb-irb1600-rw7-do",
        include_str!("../../../config/machines/abb-irb1600-rw7-do.yaml"),
    ),
    (
        "abb-irb2600-waam",
        include_str!("../../../config/machines/abb-irb2600-waam.yaml"),
    ),
    (
        "grbl-xy",
        include_str!("../../../config/machines/grbl-xy.yaml"),
    ),
    (
        "grbl-xyuv",
        include_str!("../../../config/machines/grbl-xyuv.yaml"),
    ),
    (
        "mach3-xyab",
        include_str!("../../../config/machines/mach3-xyab.yaml"),
    ),
    (
        "linuxcnc-xyuv",
        include_str!("../../../config/machines/linuxcnc-xyuv.yaml"),
    ),
    (
        "grbl-laser",
        include_str!("../../../config/machines/grbl-laser.yaml"),
    ),
    (
        "linuxcnc-plasma",
        include_str!("../../../config/machines/linuxcnc-plasma.yaml"),
    ),
    (
        "marlin-extruder",
        include_str!("../../../config/machines/marlin-extruder.yaml"),
    ),
];

/// A rejected or unreadable profile. Messages are one line and name the file.
#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// The path.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// YAML syntax, a missing or unknown key, or a value of the wrong type.
    #[error("{file}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// The file.
        file: String,
        /// 1-based line, when known.
        line: Option<usize>,
        /// The parser's message (names the key).
        message: String,
    },
    /// A value out of its domain.
    #[error("{file}: {field}: {reason}")]
    Invalid {
        /// The file.
        file: String,
        /// Dotted key path, e.g. `hotwire.tower_separation_mm`.
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// A name that is neither an embedded profile nor a file.
    #[error(
        "machine profile {name:?} is not a known name (known: {}) nor a .yaml path",
        EMBEDDED_PROFILES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
    )]
    Unknown {
        /// The name given.
        name: String,
    },
}

/// The process a machine runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Process {
    /// Hot-wire foam cutting (needs a `hotwire` section).
    Hotwire,
    /// Laser or plasma sheet cutting.
    SheetCut,
    /// Wire-arc additive manufacturing.
    Waam,
    /// Material-extrusion printing.
    Extrusion,
}

/// Hot-wire cutter geometry: two carriages (XY and, on a 4-axis machine, UV) hold the wire
/// ends in two parallel planes; the foam block sits between them.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct HotwireGeometry {
    /// Distance between the XY and UV carriage planes along the wire, mm.
    pub tower_separation_mm: f64,
    /// Distance from the XY plane to the block's root face, mm (the tip face is a panel span
    /// further).
    pub root_plane_mm: f64,
    /// Where the root section's leading edge sits in XY machine coordinates, mm.
    pub part_origin_mm: [f64; 2],
    /// Wire id in the material library (`config/materials/wires.yaml`).
    pub wire: String,
    /// The wire supply's current range [min, max], A.
    pub supply_a: [f64; 2],
    /// Axis letters of the second (UV) carriage: `[U, V]` (the default), or e.g. `[A, B]` on a
    /// Mach3 or GRBL board that drives the far tower on A and B. A machine without these axes
    /// is a 2-axis cutter.
    #[serde(default = "default_uv_axes")]
    pub uv_axes: [char; 2],
}

fn default_uv_axes() -> [char; 2] {
    ['U', 'V']
}

/// One machine (module docs).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct MachineProfile {
    /// Profile name (what goals and parameters refer to).
    pub name: String,
    /// One line for people.
    #[serde(default)]
    pub description: String,
    /// The process this machine runs.
    pub process: Process,
    /// Axis letter → travel [min, max] in machine coordinates, mm (degrees for rotary axes).
    pub axes: BTreeMap<char, [f64; 2]>,
    /// Fastest programmed feed of any axis, mm/s.
    pub max_feed_mm_s: f64,
    /// Hot-wire geometry; required when `process` is `hotwire`.
    #[serde(default)]
    pub hotwire: Option<HotwireGeometry>,
    /// How the emitter writes G-code for this machine; absent: the machine takes no G-code.
    #[serde(default)]
    pub gcode: Option<GcodeSettings>,
    /// How the emitter writes ABB RAPID for this robot; exclusive with `gcode`.
    #[serde(default)]
    pub rapid: Option<RapidSettings>,
}

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

/// `Err(reason)` unless `v` is finite and ≥ 0.
fn non_negative(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!("{name} = {v} must be finite and >= 0"))
    }
}

/// Placeholders a start or end template may use.
pub const TEMPLATE_PLACEHOLDERS: &[&str] = &["{job}", "{profile}"];

/// Checks one start/end template line: known placeholders only, and none of the modal words
/// the emitter writes itself (a template that switched to G91 or G20 would silently change
/// every move after it).
fn check_template(line: &str) -> Result<(), String> {
    let mut rest = line;
    while let Some(open) = rest.find('{') {
        let close = rest[open..]
            .find('}')
            .ok_or_else(|| format!("{line:?}: unclosed '{{'"))?;
        let placeholder = &rest[open..open + close + 1];
        if !TEMPLATE_PLACEHOLDERS.contains(&placeholder) {
            return Err(format!(
                "{line:?}: unknown placeholder {placeholder} (known: {})",
                TEMPLATE_PLACEHOLDERS.join(", ")
            ));
        }
        rest = &rest[open + close + 1..];
    }
    let upper = line.to_ascii_uppercase();
    // Words only: text inside (...) or after ';' is a comment.
    let code: String = {
        let mut depth = 0;
        let mut out = String::new();
        for c in upper.chars() {
            match c {
                ';' if depth == 0 => break,
                '(' => depth += 1,
                ')' => depth -= 1,
                _ if depth == 0 => out.push(c),
                _ => {}
            }
        }
        out
    };
    let compact: String = code.chars().filter(|c| !c.is_whitespace()).collect();
    for word in ["G20", "G21", "G90", "G91", "G93", "G94"] {
        let mut from = 0;
        while let Some(i) = compact[from..].find(word) {
            let end = from + i + word.len();
            // G90 but not G90.1 (arc-centre mode), and not G901 etc.
            let next = compact[end..].chars().next();
            if !matches!(next, Some(c) if c.is_ascii_digit() || c == '.') {
                return Err(format!(
                    "{line:?}: {word} is written by the emitter from units and feed_mode; remove it"
                ));
            }
            from = end;
        }
    }
    Ok(())
}

/// A position outside a machine's travel.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{axis} = {value:.3} mm is outside the travel {min}..{max} mm of machine {machine:?}")]
pub struct EnvelopeViolation {
    /// The machine.
    pub machine: String,
    /// The axis letter.
    pub axis: char,
    /// The commanded value.
    pub value: f64,
    /// Travel minimum.
    pub min: f64,
    /// Travel maximum.
    pub max: f64,
}

impl MachineProfile {
    /// An embedded profile by name (case-insensitive), else a file path (a name containing a
    /// path separator or ending in `.yaml`/`.yml`, or an existing file).
    ///
    /// # Errors
    /// [`ProfileError::Unknown`] for an unknown name; as [`MachineProfile::load`] for a file.
    pub fn resolve(name_or_path: &str) -> Result<Self, ProfileError> {
        let lower = name_or_path.to_ascii_lowercase();
        let looks_like_path = name_or_path.contains('/')
            || name_or_path.contains(std::path::MAIN_SEPARATOR)
            || lower.ends_with(".yaml")
            || lower.ends_with(".yml");
        if let Some((name, text)) = EMBEDDED_PROFILES
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name_or_path))
            .filter(|_| !looks_like_path)
        {
            return Self::from_yaml_str(text, &format!("config/machines/{name}.yaml"));
        }
        if looks_like_path || Path::new(name_or_path).is_file() {
            return Self::load(PathBuf::from(name_or_path));
        }
        Err(ProfileError::Unknown {
            name: name_or_path.into(),
        })
    }

    /// Reads and checks a profile file.
    ///
    /// # Errors
    /// [`ProfileError::Io`], or as [`MachineProfile::from_yaml_str`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ProfileError> {
        let file = path.as_ref().display().to_string();
        let text = std::fs::read_to_string(path.as_ref()).map_err(|source| ProfileError::Io {
            file: file.clone(),
            source,
        })?;
        Self::from_yaml_str(&text, &file)
    }

    /// Parses and checks a profile; `source_name` names it in errors.
    ///
    /// # Errors
    /// [`ProfileError::Parse`] (syntax, unknown or missing keys, wrong types) or
    /// [`ProfileError::Invalid`] (see [`MachineProfile::validate`]).
    pub fn from_yaml_str(text: &str, source_name: &str) -> Result<Self, ProfileError> {
        let profile: Self = serde_norway::from_str(text).map_err(|e| ProfileError::Parse {
            file: source_name.into(),
            line: e.location().map(|l| l.line()),
            message: e.to_string(),
        })?;
        profile.validate(source_name)?;
        Ok(profile)
    }

    /// Checks the values: axis letters A–Z with finite min < max, a positive feed limit; for a
    /// hot-wire machine a `hotwire` section with axes X and Y (plus both or neither of U and
    /// V), a positive tower separation, the root face between the towers and a supply range
    /// 0 ≤ min ≤ max; for G-code, axis words that are machine axes (u and v together), at most
    /// 6 decimals, a non-negative pre-heat dwell and a positive S scale.
    ///
    /// # Errors
    /// [`ProfileError::Invalid`] naming `source_name` and the field.
    pub fn validate(&self, source_name: &str) -> Result<(), ProfileError> {
        let invalid = |field: &str, reason: String| ProfileError::Invalid {
            file: source_name.into(),
            field: field.into(),
            reason,
        };
        if self.axes.is_empty() {
            return Err(invalid("axes", "at least one axis is needed".into()));
        }
        for (&axis, &[min, max]) in &self.axes {
            if !axis.is_ascii_uppercase() {
                return Err(invalid(
                    &format!("axes.{axis}"),
                    "axis letters are A-Z".into(),
                ));
            }
            if !(min.is_finite() && max.is_finite() && min < max) {
                return Err(invalid(
                    &format!("axes.{axis}"),
                    format!("[{min}, {max}] must be finite with min < max"),
                ));
            }
        }
        if !(self.max_feed_mm_s.is_finite() && self.max_feed_mm_s > 0.0) {
            return Err(invalid(
                "max_feed_mm_s",
                format!("{} must be finite and > 0", self.max_feed_mm_s),
            ));
        }
        match (&self.hotwire, self.process) {
            (None, Process::Hotwire) => {
                return Err(invalid(
                    "hotwire",
                    "a hot-wire machine needs a hotwire section".into(),
                ))
            }
            (Some(_), p) if p != Process::Hotwire => {
                return Err(invalid(
                    "hotwire",
                    format!("only a hot-wire machine has a hotwire section (process is {p:?})"),
                ))
            }
            _ => {}
        }
        if let Some(h) = &self.hotwire {
            for axis in ['X', 'Y'] {
                if !self.axes.contains_key(&axis) {
                    return Err(invalid(
                        "axes",
                        format!("a hot-wire machine needs axis {axis}"),
                    ));
                }
            }
            let [u, v] = h.uv_axes;
            if self.axes.contains_key(&u) != self.axes.contains_key(&v) {
                return Err(invalid(
                    "axes",
                    format!("a 4-axis hot-wire machine needs both {u} and {v} (hotwire.uv_axes)"),
                ));
            }
            if let Some(g) = &self.gcode {
                let words = (g.axis_words.u, g.axis_words.v);
                if self.axes.contains_key(&u) && words != (Some(u), Some(v)) {
                    return Err(invalid(
                        "gcode.axis_words",
                        format!(
                            "the second carriage is on {u} {v} (hotwire.uv_axes): u: {u}, v: {v}"
                        ),
                    ));
                }
            }
            if !(h.tower_separation_mm.is_finite() && h.tower_separation_mm > 0.0) {
                return Err(invalid(
                    "hotwire.tower_separation_mm",
                    format!("{} must be finite and > 0", h.tower_separation_mm),
                ));
            }
            if !(h.root_plane_mm.is_finite()
                && (0.0..h.tower_separation_mm).contains(&h.root_plane_mm))
            {
                return Err(invalid(
                    "hotwire.root_plane_mm",
                    format!(
                        "{} must lie in [0, tower_separation_mm = {})",
                        h.root_plane_mm, h.tower_separation_mm
                    ),
                ));
            }
            if !h.part_origin_mm.iter().all(|v| v.is_finite()) {
                return Err(invalid("hotwire.part_origin_mm", "must be finite".into()));
            }
            let [lo, hi] = h.supply_a;
            if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi && hi > 0.0) {
                return Err(invalid(
                    "hotwire.supply_a",
                    format!("[{lo}, {hi}] must satisfy 0 <= min <= max, max > 0"),
                ));
            }
        }
        if let Some(g) = &self.gcode {
            let w = &g.axis_words;
            for (field, letter) in [
                ("x", Some(w.x)),
                ("y", Some(w.y)),
                ("z", w.z),
                ("u", w.u),
                ("v", w.v),
            ] {
                if let Some(l) = letter {
                    if !self.axes.contains_key(&l) {
                        return Err(invalid(
                            &format!("gcode.axis_words.{field}"),
                            format!("axis {l} is not one of the machine's axes"),
                        ));
                    }
                }
            }
            if w.u.is_some() != w.v.is_some() {
                return Err(invalid(
                    "gcode.axis_words",
                    "u and v come together (the second carriage)".into(),
                ));
            }
            if g.decimals > 6 {
                return Err(invalid(
                    "gcode.decimals",
                    format!("{} is more than 6", g.decimals),
                ));
            }
            if !(g.preheat_dwell_s.is_finite() && g.preheat_dwell_s >= 0.0) {
                return Err(invalid(
                    "gcode.preheat_dwell_s",
                    format!("{} must be finite and >= 0", g.preheat_dwell_s),
                ));
            }
            if let Some(p) = &g.power {
                if !(p.s_per_unit.is_finite() && p.s_per_unit > 0.0) {
                    return Err(invalid(
                        "gcode.power.s_per_unit",
                        format!("{} must be finite and > 0", p.s_per_unit),
                    ));
                }
            }
            for (field, lines) in [
                ("gcode.program_start", &g.program_start),
                ("gcode.program_end", &g.program_end),
            ] {
                for (i, line) in lines.iter().enumerate() {
                    check_template(line)
                        .map_err(|reason| invalid(&format!("{field}[{i}]"), reason))?;
                }
            }
            if let Some(pierce) = &g.pierce {
                if g.power.is_none() {
                    return Err(invalid(
                        "gcode.pierce",
                        "pierce handling switches power: a power section is needed".into(),
                    ));
                }
                non_negative("gcode.pierce.dwell_s", pierce.dwell_s)
                    .map_err(|r| invalid("gcode.pierce.dwell_s", r))?;
                let heights = [pierce.z_pierce_mm, pierce.z_cut_mm, pierce.z_travel_mm];
                if heights.iter().any(Option::is_some) {
                    if heights.iter().any(Option::is_none) {
                        return Err(invalid(
                            "gcode.pierce",
                            "z_pierce_mm, z_cut_mm and z_travel_mm come together".into(),
                        ));
                    }
                    let Some(z) = w.z else {
                        return Err(invalid(
                            "gcode.pierce",
                            "pierce heights need the z axis word".into(),
                        ));
                    };
                    let [lo, hi] = self.axes[&z];
                    for (name, h) in [
                        ("z_pierce_mm", pierce.z_pierce_mm),
                        ("z_cut_mm", pierce.z_cut_mm),
                        ("z_travel_mm", pierce.z_travel_mm),
                    ] {
                        let h = h.unwrap_or_default();
                        if !(h.is_finite() && lo <= h && h <= hi) {
                            return Err(invalid(
                                &format!("gcode.pierce.{name}"),
                                format!("{h} is outside the {z} travel {lo}..{hi}"),
                            ));
                        }
                    }
                }
            }
            if g.dialect == Dialect::Marlin && g.feed_mode == FeedMode::InverseTime {
                return Err(invalid(
                    "gcode.feed_mode",
                    "Marlin has no inverse-time feed (G93); use units_per_minute".into(),
                ));
            }
            if let Some(e) = &g.extrusion {
                if g.power.is_some() {
                    return Err(invalid(
                        "gcode.extrusion",
                        "an extrusion profile's power is the flow: remove the power section".into(),
                    ));
                }
                if !self.axes.contains_key(&e.axis) {
                    return Err(invalid(
                        "gcode.extrusion.axis",
                        format!("axis {} is not one of the machine's axes", e.axis),
                    ));
                }
                if !(e.filament_diameter_mm.is_finite() && e.filament_diameter_mm > 0.0) {
                    return Err(invalid(
                        "gcode.extrusion.filament_diameter_mm",
                        format!("{} must be finite and > 0", e.filament_diameter_mm),
                    ));
                }
                for (name, v) in [("retract_mm", e.retract_mm), ("z_hop_mm", e.z_hop_mm)] {
                    non_negative(name, v)
                        .map_err(|r| invalid(&format!("gcode.extrusion.{name}"), r))?;
                }
                if !(e.retract_feed_mm_s.is_finite() && e.retract_feed_mm_s > 0.0) {
                    return Err(invalid(
                        "gcode.extrusion.retract_feed_mm_s",
                        format!("{} must be finite and > 0", e.retract_feed_mm_s),
                    ));
                }
                if e.z_hop_mm > 0.0 && w.z.is_none() {
                    return Err(invalid(
                        "gcode.extrusion.z_hop_mm",
                        "a Z-hop needs the z axis word".into(),
                    ));
                }
            }
            if let Some(t) = g.arc_tolerance_mm {
                if !(t.is_finite() && t > 0.0) {
                    return Err(invalid(
                        "gcode.arc_tolerance_mm",
                        format!("{t} must be finite and > 0"),
                    ));
                }
                if w.u.is_some() {
                    return Err(invalid(
                        "gcode.arc_tolerance_mm",
                        "arcs are not fitted on a machine with a second carriage (u, v)".into(),
                    ));
                }
            }
        }
        if let Some(r) = &self.rapid {
            if self.gcode.is_some() {
                return Err(invalid(
                    "rapid",
                    "a machine takes G-code or RAPID, not both (remove gcode or rapid)".into(),
                ));
            }
            r.validate(self)
                .map_err(|(field, reason)| invalid(&format!("rapid.{field}"), reason))?;
        }
        Ok(())
    }

    /// True for a hot-wire machine with a UV carriage (tapered panels possible).
    pub fn is_four_axis_hotwire(&self) -> bool {
        self.second_carriage_axes().is_some()
    }

    /// The second (UV) carriage's axis letters on a 4-axis hot-wire machine.
    pub fn second_carriage_axes(&self) -> Option<[char; 2]> {
        let h = self.hotwire.as_ref()?;
        self.axes.contains_key(&h.uv_axes[0]).then_some(h.uv_axes)
    }

    /// Checks one position given as (axis, value) pairs against the travel. Axes the machine
    /// does not have are an error too (reported with an empty travel 0..0).
    ///
    /// # Errors
    /// The first axis out of travel.
    pub fn check_position(&self, position: &[(char, f64)]) -> Result<(), EnvelopeViolation> {
        for &(axis, value) in position {
            let travel = self.axes.get(&axis).copied();
            let [min, max] = travel.unwrap_or([0.0, 0.0]);
            // A thousandth of a millimetre of slack: values that round onto the limit pass.
            let slack = 1e-3;
            if !(travel.is_some() && value >= min - slack && value <= max + slack) {
                return Err(EnvelopeViolation {
                    machine: self.name.clone(),
                    axis,
                    value,
                    min,
                    max,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_profiles_load_and_resolve_case_insensitively() {
        for (name, _) in EMBEDDED_PROFILES {
            let p = MachineProfile::resolve(name).unwrap();
            assert_eq!(&p.name, name);
        }
        assert!(MachineProfile::resolve("LINUXCNC-XYUV")
            .unwrap()
            .is_four_axis_hotwire());
        assert!(!MachineProfile::resolve("grbl-xy")
            .unwrap()
            .is_four_axis_hotwire());
        let e = MachineProfile::resolve("nope").unwrap_err();
        assert!(e.to_string().contains("linuxcnc-xyuv"), "{e}");
        let e = MachineProfile::resolve("/nonexistent/m.yaml").unwrap_err();
        assert!(e.to_string().starts_with("/nonexistent/m.yaml"), "{e}");
    }

    fn base() -> String {
        EMBEDDED_PROFILES
            .iter()
            .find(|(n, _)| *n == "linuxcnc-xyuv")
            .unwrap()
            .1
            .to_string()
    }

    #[test]
    fn a_mistyped_key_names_the_key_and_line() {
        let text = base().replace("root_plane_mm:", "root_plane:");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("m.yaml:"), "{msg}");
        assert!(msg.contains("root_plane"), "{msg}");
        assert!(matches!(e, ProfileError::Parse { line: Some(_), .. }));
    }

    #[test]
    fn out_of_range_values_name_the_field() {
        for (from, to, field) in [
            (
                "tower_separation_mm: 1000.0",
                "tower_separation_mm: -1",
                "hotwire.tower_separation_mm",
            ),
            (
                "root_plane_mm: 200.0",
                "root_plane_mm: 1200.0",
                "hotwire.root_plane_mm",
            ),
            ("X: [0.0, 600.0]", "X: [600.0, 0.0]", "axes.X"),
            ("max_feed_mm_s: 25.0", "max_feed_mm_s: 0", "max_feed_mm_s"),
            (
                "supply_a: [0.0, 10.0]",
                "supply_a: [5.0, 1.0]",
                "hotwire.supply_a",
            ),
            ("  V: [0.0, 300.0]\n", "", "axes"),
        ] {
            let text = base().replace(from, to);
            assert_ne!(text, base(), "{from}");
            let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
            assert!(
                matches!(&e, ProfileError::Invalid { field: f, .. } if f == field),
                "{from}: {e}"
            );
        }
        let text = base().replace("process: hotwire", "process: waam");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(e.to_string().contains("hotwire"), "{e}");
    }

    #[test]
    fn gcode_sections_are_checked_against_the_axes() {
        let p = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
        let g = p.gcode.as_ref().unwrap();
        assert_eq!(
            (g.dialect, g.feed_mode),
            (Dialect::Linuxcnc, FeedMode::InverseTime)
        );
        let text = base().replace("u: U, v: V", "u: W, v: V");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(
            e.to_string()
                .contains("gcode.axis_words: the second carriage is on U V"),
            "{e}"
        );
        let text = base().replace("u: U, v: V", "u: U");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(e.to_string().contains("gcode.axis_words:"), "{e}");
        let text = base().replace("feed_mode: inverse_time", "feed_mode: inverse");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(e.to_string().contains("feed_mode"), "{e}");
    }

    fn embedded(name: &str) -> String {
        EMBEDDED_PROFILES
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap()
            .1
            .to_string()
    }

    #[test]
    fn process_settings_are_checked_and_name_their_field() {
        for (profile, from, to, field) in [
            (
                "linuxcnc-plasma",
                "program_start: [\"G64 P0.05\"]",
                "program_start: [\"G64 P0.05\", \"G91\"]",
                "gcode.program_start[1]",
            ),
            (
                "linuxcnc-plasma",
                "program_start: [\"G64 P0.05\"]",
                "program_start: [\"(job {jobid})\"]",
                "gcode.program_start[0]",
            ),
            ("linuxcnc-plasma", "z_pierce_mm: 3.8, ", "", "gcode.pierce"),
            (
                "linuxcnc-plasma",
                "z_travel_mm: 10.0",
                "z_travel_mm: 150.0",
                "gcode.pierce.z_travel_mm",
            ),
            (
                "grbl-laser",
                "arc_tolerance_mm: 0.01",
                "arc_tolerance_mm: 0",
                "gcode.arc_tolerance_mm",
            ),
            (
                "linuxcnc-xyuv",
                "preheat_dwell_s: 2.0",
                "preheat_dwell_s: 2.0\n  arc_tolerance_mm: 0.01",
                "gcode.arc_tolerance_mm",
            ),
            (
                "marlin-extruder",
                "feed_mode: units_per_minute",
                "feed_mode: inverse_time",
                "gcode.feed_mode",
            ),
            (
                "marlin-extruder",
                "filament_diameter_mm: 1.75",
                "filament_diameter_mm: -1.75",
                "gcode.extrusion.filament_diameter_mm",
            ),
            (
                "marlin-extruder",
                "  arc_tolerance_mm: 0.01",
                "  arc_tolerance_mm: 0.01\n  power: {on: M3, off: M5, s_per_unit: 1.0}",
                "gcode.extrusion",
            ),
            ("mach3-xyab", "uv_axes: [A, B]", "uv_axes: [A, C]", "axes"),
        ] {
            let text = embedded(profile).replace(from, to);
            assert_ne!(text, embedded(profile), "{from}");
            let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
            assert!(
                matches!(&e, ProfileError::Invalid { field: f, .. } if f == field),
                "{profile} {to}: {e}"
            );
        }
        // Placeholders and the arc-centre mode word are fine in templates; G91 inside a comment too.
        let text = embedded("linuxcnc-plasma").replace(
            "program_start: [\"G64 P0.05\"]",
            "program_start: [\"(job {job} on {profile}, not G91)\", \"G91.1\"]",
        );
        MachineProfile::from_yaml_str(&text, "m.yaml").unwrap();
        // A mistyped key in a nested section names it with its line.
        let text = embedded("marlin-extruder").replace("retract_mm:", "retract:");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(
            matches!(e, ProfileError::Parse { line: Some(_), .. }),
            "{e}"
        );
        assert!(e.to_string().contains("retract"), "{e}");
    }

    #[test]
    fn envelope_check_names_the_axis() {
        let p = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
        assert!(p
            .check_position(&[('X', 0.0), ('Y', 300.0), ('U', 600.0), ('V', 0.0)])
            .is_ok());
        let e = p.check_position(&[('X', 10.0), ('V', -0.5)]).unwrap_err();
        assert_eq!((e.axis, e.value), ('V', -0.5));
        assert!(e.to_string().contains("V = -0.500"), "{e}");
        assert!(p.check_position(&[('Z', 1.0)]).is_err());
        assert!(p.check_position(&[('X', f64::NAN)]).is_err());
    }
}
