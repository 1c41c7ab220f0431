//! One machine: its process, axes (the travel) and feed limit, read and checked section by
//! section.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use cell_config::{Allowed, FieldError};

use crate::{
    Compensation, CuttingSection, Dialect, GcodeSettings, HotwireGeometry, ProfileError,
    RapidSettings, RobotSection, EMBEDDED_PROFILES,
};

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
    /// The robot arm (kinematic model, joint ranges, base frame) for a RAPID machine; absent:
    /// the emitter writes the fixed `rapid.robconf` (see `robot.rs`).
    #[serde(default)]
    pub robot: Option<RobotSection>,
    /// Sheet cutting: kerf compensation, lead-ins and the kerf table (`sheet_cut` machines
    /// only).
    #[serde(default)]
    pub cutting: Option<CuttingSection>,
}

impl MachineProfile {
    /// An embedded profile by name (case-insensitive), else a file path (a name containing a
    /// path separator or ending in `.yaml`/`.yml`, or an existing file).
    ///
    /// # Errors
    /// [`ProfileError::Unknown`] for an unknown name; as [`MachineProfile::load`] for a file.
    pub fn resolve(name_or_path: &str) -> Result<Self, ProfileError> {
        let looks_like_path = Self::looks_like_path(name_or_path);
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

    /// A name containing a path separator or ending in `.yaml`/`.yml`: always a file.
    fn looks_like_path(name_or_path: &str) -> bool {
        let lower = name_or_path.to_ascii_lowercase();
        name_or_path.contains('/')
            || name_or_path.contains(std::path::MAIN_SEPARATOR)
            || lower.ends_with(".yaml")
            || lower.ends_with(".yml")
    }

    /// Whether [`MachineProfile::resolve`] reads a file for `name_or_path` (rather than an
    /// embedded profile or an unknown name), so a caller can read it under its own rules and
    /// use [`MachineProfile::from_yaml_str`].
    pub fn names_a_file(name_or_path: &str) -> bool {
        let embedded = EMBEDDED_PROFILES
            .iter()
            .any(|(n, _)| n.eq_ignore_ascii_case(name_or_path));
        Self::looks_like_path(name_or_path) || (!embedded && Path::new(name_or_path).is_file())
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
    /// [`ProfileError::Parse`] (syntax, unknown or missing keys, wrong types, with the line and
    /// field) or [`ProfileError::Invalid`] (see [`MachineProfile::validate`]).
    pub fn from_yaml_str(text: &str, source_name: &str) -> Result<Self, ProfileError> {
        let profile: Self = cell_config::from_yaml_str(text, source_name)?;
        profile.validate(source_name)?;
        Ok(profile)
    }

    /// Checks the values, section by section: the axes (letters A–Z, finite min < max), the
    /// feed limit (> 0), the process's sections (a `hotwire` section exactly on a hot-wire
    /// machine), the hot-wire towers (`hotwire.rs`), the G-code
    /// settings ([`GcodeSettings::validate`]), the RAPID settings
    /// ([`RapidSettings::validate`], exclusive with G-code) and the sheet cutting settings
    /// ([`CuttingSection::validate`]).
    ///
    /// # Errors
    /// [`ProfileError::Invalid`] naming `source_name` and the field of the first problem.
    pub fn validate(&self, source_name: &str) -> Result<(), ProfileError> {
        self.validate_sections()
            .map_err(|e| ProfileError::invalid(source_name, e))
    }

    /// The sections in the order they are checked; the first problem is the one reported.
    fn validate_sections(&self) -> Result<(), FieldError> {
        self.validate_axes()?;
        self.validate_feed()?;
        self.validate_process()?;
        if let Some(h) = &self.hotwire {
            self.validate_hotwire(h)?;
        }
        if let Some(g) = &self.gcode {
            g.validate(&self.axes).map_err(|e| e.within("gcode"))?;
        }
        if let Some(r) = &self.rapid {
            if self.gcode.is_some() {
                return Err(FieldError::new(
                    "rapid",
                    "a machine takes G-code or RAPID, not both (remove gcode or rapid)",
                ));
            }
            r.validate(self).map_err(|e| e.within("rapid"))?;
        }
        if let Some(robot) = &self.robot {
            robot
                .validate(self.rapid.as_ref())
                .map_err(|e| e.within("robot"))?;
        }
        if let Some(c) = &self.cutting {
            self.validate_cutting(c)?;
        }
        Ok(())
    }

    /// The `cutting` section: on a sheet-cutting machine only, its values
    /// ([`CuttingSection::validate`]), and controller compensation only where the program is
    /// LinuxCNC G-code (the dialect with `G41`/`G42` and a tool table the emitter writes).
    fn validate_cutting(&self, c: &CuttingSection) -> Result<(), FieldError> {
        if self.process != Process::SheetCut {
            return Err(FieldError::new(
                "cutting",
                format!(
                    "only a sheet-cutting machine has a cutting section (process is {:?})",
                    self.process
                ),
            ));
        }
        c.validate().map_err(|e| e.within("cutting"))?;
        let dialect = self.gcode.as_ref().map(|g| g.dialect);
        if c.compensation == Compensation::Controller && dialect != Some(Dialect::Linuxcnc) {
            let program = dialect.map_or("no G-code".to_string(), |d| {
                let name = format!("{d:?}").to_ascii_lowercase();
                format!("G-code dialect {name}")
            });
            return Err(FieldError::new(
                "cutting.compensation",
                format!(
                    "controller compensation (G41/G42 with the kerf in the tool table) needs the \
                     linuxcnc G-code dialect; this machine takes {program}: use geometric"
                ),
            ));
        }
        Ok(())
    }

    /// The `axes` section, the travel: at least one axis, letters A–Z, finite min < max.
    fn validate_axes(&self) -> Result<(), FieldError> {
        if self.axes.is_empty() {
            return Err(FieldError::new("axes", "at least one axis is needed"));
        }
        for (&axis, &[min, max]) in &self.axes {
            let field = format!("axes.{axis}");
            if !axis.is_ascii_uppercase() {
                return Err(FieldError::new(field, "axis letters are A-Z"));
            }
            if !(min.is_finite() && max.is_finite() && min < max) {
                return Err(FieldError::new(
                    field,
                    format!("[{min}, {max}] must be finite with min < max"),
                ));
            }
        }
        Ok(())
    }

    /// `max_feed_mm_s`: finite and > 0.
    fn validate_feed(&self) -> Result<(), FieldError> {
        Allowed::POSITIVE.check_field("max_feed_mm_s", self.max_feed_mm_s, "mm/s")
    }

    /// A `hotwire` section on a hot-wire machine and on no other.
    fn validate_process(&self) -> Result<(), FieldError> {
        match (&self.hotwire, self.process) {
            (None, Process::Hotwire) => Err(FieldError::new(
                "hotwire",
                "a hot-wire machine needs a hotwire section",
            )),
            (Some(_), p) if p != Process::Hotwire => Err(FieldError::new(
                "hotwire",
                format!("only a hot-wire machine has a hotwire section (process is {p:?})"),
            )),
            _ => Ok(()),
        }
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
}
