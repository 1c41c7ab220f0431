//! ABB RAPID output settings: the emitter's part of a robot profile (the `rapid:` section of
//! `config/machines/*.yaml`), read by `cell_emitter::rapid` (seed 004 §4.7).
//!
//! Seed 004 gives no zone, tool, work object, orientation or arc on/off data, so every one of
//! them is a setting here, with a documented default where one is safe.
//!
//! ```yaml
//! rapid:
//!   robotware: rw6                 # rw6 (IRC5) | rw7 (OmniCore)
//!   module_prefix: WAAM_           # module names: prefix + job id
//!   max_targets_per_module: 5000   # split above this many robtargets
//!   tool: {name: tWAAM, value: {tcp_mm: [0, 0, 250], mass_kg: 5.0, cog_mm: [0, 0, 100]}}
//!   wobj: {name: wobjTable, value: {uframe_mm: [900, 0, 300]}}
//!   zone: {name: z1}
//!   weld: {mode: arc, data: program, seam: seamWAAM, weld: weldWAAM, arc: {sched: 1}}
//!   # or the controller's data, by name: {mode: arc, data: controller, seam: …, weld: …}
//! ```
//!
//! Every name that goes into the program is checked against RAPID's identifier rules
//! ([`check_identifier`]), so a profile cannot smuggle code into a module.

use cell_config::{Allowed, Bound, FieldError};

/// RAPID's longest identifier, characters. ABB, *Technical reference manual - RAPID kernel*,
/// §"Identifiers": "The maximum length of an identifier is 32 characters, all of them
/// significant" (RobotWare 6 and 7 alike).
pub const MAX_IDENTIFIER_LEN: usize = 32;

/// RAPID's longest string value, characters. ABB, *Technical reference manual - RAPID kernel*,
/// §"String literals" and data type `string`: "a string can have 0 to 80 characters" (a `""`
/// or `\\` escape counts as one).
pub const MAX_STRING_LEN: usize = 80;

/// RAPID's reserved words (ABB, *Technical reference manual - RAPID kernel*, §"Reserved
/// words"; `TASK` from `TASK PERS`). RAPID is not case-sensitive: compare upper-cased.
pub const RESERVED_WORDS: &[&str] = &[
    "ALIAS",
    "AND",
    "BACKWARD",
    "CASE",
    "CONNECT",
    "CONST",
    "DEFAULT",
    "DIV",
    "DO",
    "ELSE",
    "ELSEIF",
    "ENDFOR",
    "ENDFUNC",
    "ENDIF",
    "ENDMODULE",
    "ENDPROC",
    "ENDRECORD",
    "ENDTEST",
    "ENDTRAP",
    "ENDWHILE",
    "ERROR",
    "EXIT",
    "FALSE",
    "FOR",
    "FROM",
    "FUNC",
    "GOTO",
    "IF",
    "INOUT",
    "LOCAL",
    "MOD",
    "MODULE",
    "NOSTEPIN",
    "NOT",
    "NOVIEW",
    "OR",
    "PERS",
    "PROC",
    "RAISE",
    "READONLY",
    "RECORD",
    "RETRY",
    "RETURN",
    "STEP",
    "SYSMODULE",
    "TASK",
    "TEST",
    "THEN",
    "TO",
    "TRAP",
    "TRUE",
    "TRYNEXT",
    "UNDO",
    "VAR",
    "VIEWONLY",
    "WHILE",
    "WITH",
    "XOR",
];

/// Checks a RAPID identifier: an ASCII letter first, then letters, digits and `_`, at most
/// [`MAX_IDENTIFIER_LEN`] characters, not a reserved word (any case).
///
/// # Errors
/// A one-line reason naming the rule broken.
pub fn check_identifier(name: &str) -> Result<(), String> {
    let mut chars = name.chars();
    match chars.next() {
        None => return Err("an identifier may not be empty".into()),
        Some(c) if !c.is_ascii_alphabetic() => {
            return Err(format!("{name:?}: a RAPID identifier starts with a letter"))
        }
        _ => {}
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '_'))
    {
        return Err(format!(
            "{name:?}: {c:?} is not allowed (letters, digits and _ only)"
        ));
    }
    let len = name.chars().count();
    if len > MAX_IDENTIFIER_LEN {
        return Err(format!(
            "{name:?} has {len} characters; RAPID identifiers have at most {MAX_IDENTIFIER_LEN}"
        ));
    }
    if RESERVED_WORDS.contains(&name.to_ascii_uppercase().as_str()) {
        return Err(format!("{name:?} is a RAPID reserved word"));
    }
    Ok(())
}

/// True if `name` (any case) has the form of a name the emitter declares itself: `main`,
/// `jobName`, robtargets `p1`, `p2`, … and speeddata `vTS1`, `vTS2`, … A profile name of this
/// form would be hidden by the emitter's declaration.
pub fn is_generated_name(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    let numbered = |prefix: &str| {
        lower
            .strip_prefix(prefix)
            .is_some_and(|rest| !rest.is_empty() && rest.chars().all(|c| c.is_ascii_digit()))
    };
    lower == "main" || lower == "jobname" || numbered("p") || numbered("vts")
}

/// The RobotWare generation of the controller.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RobotWare {
    /// RobotWare 6 (IRC5): modules `.mod`, ISO-8859-1; the `.pgf` declares ISO-8859-1.
    #[default]
    Rw6,
    /// RobotWare 7 (OmniCore): modules `.modx`, UTF-8; the `.pgf` declares UTF-8.
    Rw7,
}

/// The value of a `tooldata` the emitter declares (`PERS tooldata name := [robhold, tframe,
/// tload]`).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ToolValue {
    /// True if the robot holds the tool (a torch); false for a stationary tool.
    #[serde(default = "yes")]
    pub robhold: bool,
    /// Tool centre point in the wrist (tool0) frame, mm.
    pub tcp_mm: [f64; 3],
    /// Orientation of the tool frame in the wrist frame, quaternion [q1, q2, q3, q4] =
    /// [w, x, y, z], unit length (within 1e-3; written normalised).
    #[serde(default = "identity")]
    pub tcp_quat: [f64; 4],
    /// Mass of the tool, kg (> 0: RAPID refuses a tool without load).
    pub mass_kg: f64,
    /// Centre of gravity of the tool in the wrist frame, mm.
    pub cog_mm: [f64; 3],
}

/// The value of a `wobjdata` the emitter declares (`PERS wobjdata name := [robhold, ufprog,
/// ufmec, uframe, oframe]`).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct WobjValue {
    /// True if the robot holds the work object (stationary tool); usually false.
    #[serde(default)]
    pub robhold: bool,
    /// Mechanical unit that moves the user frame (a positioner), e.g. `STN1`; absent: a fixed
    /// user frame (`ufprog` TRUE, `ufmec` "").
    #[serde(default)]
    pub ufmec: Option<String>,
    /// User frame origin in the world frame, mm.
    #[serde(default)]
    pub uframe_mm: [f64; 3],
    /// User frame orientation, quaternion [w, x, y, z], unit length.
    #[serde(default = "identity")]
    pub uframe_quat: [f64; 4],
    /// Object frame origin in the user frame, mm.
    #[serde(default)]
    pub oframe_mm: [f64; 3],
    /// Object frame orientation, quaternion [w, x, y, z], unit length.
    #[serde(default = "identity")]
    pub oframe_quat: [f64; 4],
}

/// The value of a `zonedata` the emitter declares (`CONST zonedata name := [finep,
/// pzone_tcp, pzone_ori, pzone_eax, zone_ori, zone_leax, zone_reax]`). Absent fields follow
/// ABB's predefined zones (`z1` = `[FALSE,1,1,1,0.1,1,0.1]`): distances equal
/// `pzone_tcp_mm`, angles a tenth of it in degrees.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ZoneValue {
    /// Radius of the TCP zone, mm (> 0; for a stop point use the predefined `fine`).
    pub pzone_tcp_mm: f64,
    /// Zone radius for tool reorientation, mm.
    #[serde(default)]
    pub pzone_ori_mm: Option<f64>,
    /// Zone radius for external axes, mm.
    #[serde(default)]
    pub pzone_eax_mm: Option<f64>,
    /// Zone size for tool reorientation, degrees.
    #[serde(default)]
    pub zone_ori_deg: Option<f64>,
    /// Zone size for linear external axes, mm.
    #[serde(default)]
    pub zone_leax_mm: Option<f64>,
    /// Zone size for rotating external axes, degrees.
    #[serde(default)]
    pub zone_reax_deg: Option<f64>,
}

impl ZoneValue {
    /// The seven `zonedata` components: `[pzone_tcp, pzone_ori, pzone_eax, zone_ori,
    /// zone_leax, zone_reax]` after `finep` = FALSE, defaults filled in.
    pub fn components(&self) -> [f64; 6] {
        let d = self.pzone_tcp_mm;
        [
            d,
            self.pzone_ori_mm.unwrap_or(d),
            self.pzone_eax_mm.unwrap_or(d),
            self.zone_ori_deg.unwrap_or(d / 10.0),
            self.zone_leax_mm.unwrap_or(d),
            self.zone_reax_deg.unwrap_or(d / 10.0),
        ]
    }
}

/// A named RAPID data object with an optional value: with a value the emitter declares it in
/// the main module; without, it must exist on the controller (`tool0`, `wobj0`, `z1`, `fine`,
/// or data in a system module).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Named<T> {
    /// RAPID identifier ([`check_identifier`]).
    pub name: String,
    /// The value to declare; absent: use the controller's.
    #[serde(default = "none")]
    pub value: Option<T>,
}

/// How welding (or cutting) is switched on and off along deposit and cut segments.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(tag = "mode", rename_all = "snake_case", deny_unknown_fields)]
pub enum WeldMode {
    /// RobotWare Arc option: `ArcLStart` to the first point of a weld run, `ArcL` through it,
    /// `ArcLEnd` at its last point. Note: during the weld the TCP speed is the `weld_speed`
    /// of the welddata, not the speeddata (RobotWare Arc manual, `ArcL`, argument `Speed`);
    /// the per-point speeddata still govern the approach (`ArcLStart`). So with
    /// `data: program` every distinct bead (travel speed, wire feed) gets its own welddata:
    /// a width change in the plan is a weld speed change on the robot (seed 004 eq. 14).
    Arc {
        /// Where the seamdata and welddata live. Default `program`.
        #[serde(default)]
        data: WeldDataSource,
        /// `seamdata` name (ignition, fill, gas times): declared by the program (`program`)
        /// or on the controller (`controller`).
        seam: String,
        /// `controller`: the `welddata` declared on the controller. `program`: the prefix of
        /// the welddata the program declares, one per bead, `weld1`, `weld2`, … (at most
        /// [`MAX_WELD_PREFIX_LEN`] characters).
        weld: String,
        /// `program` only (required there): the power source settings of every bead's
        /// `arcdata`; the wire feed comes from the toolpath.
        #[serde(default)]
        arc: Option<ArcValue>,
        /// `program` only: the seamdata's gas times. Default ABB's default seamdata.
        #[serde(default)]
        seam_value: Option<SeamValue>,
    },
    /// A digital output switches the process: `MoveL` to the start point (`fine`),
    /// `SetDO signal, 1;`, `MoveL` through the run, `SetDO signal, 0;` after its last point
    /// (`fine`).
    DigitalOutput {
        /// The output's name in the controller's I/O configuration, e.g. `doWeld`.
        signal: String,
    },
}

/// Where the arc-welding data (`seamdata`, `welddata`) of an `arc` weld mode live.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WeldDataSource {
    /// The program declares them (`LOCAL PERS` in each module that welds): one welddata per
    /// distinct bead, from the toolpath's travel speed and wire feed and the profile's `arc`.
    /// The program is self-contained.
    #[default]
    Program,
    /// The controller holds them (a system module or a loaded data module): the program only
    /// names `seam` and `weld`, and every bead runs at that one welddata's `weld_speed`.
    Controller,
}

/// The power source part of every bead's `arcdata` (RobotWare Arc: `arcdata := [sched,
/// mode, voltage, wirefeed, control, current, voltage2, wirefeed2, control2]`); the wire
/// feed is the toolpath's. Which components a power source reads depends on its
/// configuration: a synergic one takes the job (`sched`) and the wire feed and sets voltage
/// and current itself (leave them 0).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ArcValue {
    /// Schedule: the power source's synergic job / program number (0: none).
    #[serde(default)]
    pub sched: u32,
    /// The power source's weld mode (e.g. Fronius: 0 standard, 1 pulse).
    #[serde(default)]
    pub mode: u32,
    /// Arc voltage, V (0: set by the synergic job).
    #[serde(default)]
    pub voltage_v: f64,
    /// Weld current, A (0: set by the synergic job).
    #[serde(default)]
    pub current_a: f64,
    /// Arc control (arc length correction, inductance: power source specific).
    #[serde(default)]
    pub control: f64,
}

/// The gas times of the declared `seamdata`, s. Defaults: ABB's default seamdata (`purge`
/// 0.2, `preflow` 0.05, `postflow` 0.05); the other components (ignition, heat, fill and
/// burnback arcs) are 0 = not used.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct SeamValue {
    /// Gas purge time before the first weld, s.
    #[serde(default = "default_purge_s")]
    pub purge_s: f64,
    /// Gas preflow before ignition, s.
    #[serde(default = "default_flow_s")]
    pub preflow_s: f64,
    /// Gas postflow after the arc is off, s.
    #[serde(default = "default_flow_s")]
    pub postflow_s: f64,
}

impl Default for SeamValue {
    fn default() -> Self {
        SeamValue {
            purge_s: default_purge_s(),
            preflow_s: default_flow_s(),
            postflow_s: default_flow_s(),
        }
    }
}

fn default_purge_s() -> f64 {
    0.2
}

fn default_flow_s() -> f64 {
    0.05
}

/// Longest welddata prefix (`weld` with `data: program`): room for five digits within
/// [`MAX_IDENTIFIER_LEN`].
pub const MAX_WELD_PREFIX_LEN: usize = MAX_IDENTIFIER_LEN - 5;

/// The name of the `n`th (1-based) welddata a program declares with prefix `weld`.
pub fn welddata_name(weld: &str, n: usize) -> String {
    format!("{weld}{n}")
}

/// True if `name` (any case) is `weld` followed by digits: a welddata name the program
/// declares with that prefix.
pub fn is_welddata_name(weld: &str, name: &str) -> bool {
    name.len() > weld.len()
        && name.is_char_boundary(weld.len())
        && name[..weld.len()].eq_ignore_ascii_case(weld)
        && name[weld.len()..].chars().all(|c| c.is_ascii_digit())
}

/// How the emitter writes RAPID for one robot (module docs).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RapidSettings {
    /// Controller generation: file extensions, encodings and the `.pgf` form.
    #[serde(default)]
    pub robotware: RobotWare,
    /// Prefix of the module names (letters, digits, `_`; at most 10 characters); the job id
    /// follows, reduced to letters, digits and `_`. Default: none.
    #[serde(default)]
    pub module_prefix: String,
    /// Most robtargets in one module; a longer program is split into modules of at most this
    /// many, called in order from the main module. Default 5000. This is not an ABB
    /// constant: RAPID limits a program by the controller's program memory, not by a count,
    /// and 5000 targets (about 0.5 MB of source) load and edit comfortably on IRC5 and
    /// OmniCore; lower it if the controller reports that program memory is full.
    #[serde(default = "default_max_targets")]
    pub max_targets_per_module: usize,
    /// The tool (`tooldata`) every move uses.
    pub tool: Named<ToolValue>,
    /// The work object (`wobjdata`) the toolpath coordinates are in. Default `wobj0` (the
    /// world frame).
    #[serde(default = "default_wobj")]
    pub wobj: Named<WobjValue>,
    /// The zone (`zonedata`) of path points inside a run; the first and last point of a weld
    /// run are always `fine` (the process switches there). Default `z1`.
    #[serde(default = "default_zone")]
    pub zone: Named<ZoneValue>,
    /// Weld on/off.
    pub weld: WeldMode,
    /// Robot configuration of every robtarget, [cf1, cf4, cf6, cfx] (quadrants of axes 1, 4
    /// and 6 in -4..=3, cfx 0..=7). The emitter solves no kinematics. Default [0, 0, 0, 0].
    #[serde(default)]
    pub robconf: [i32; 4],
    /// Write `ConfL \Off;` at the start (the controller picks the configuration nearest the
    /// fixed `robconf` instead of stopping on a mismatch). Default true.
    #[serde(default = "yes")]
    pub confl_off: bool,
    /// Tool orientation for points without normals, quaternion [w, x, y, z] in the work
    /// object frame. Default [0, 1, 0, 0]: the tool z-axis points down (-Z), tool x along +X,
    /// the same as a normal (0, 0, 1).
    #[serde(default = "default_quat")]
    pub default_orientation: [f64; 4],
    /// Reorientation speed of every speeddata (`v_ori`), deg/s. Default 500 (as ABB's
    /// predefined speeddata).
    #[serde(default = "default_ori_speed")]
    pub orientation_speed_deg_s: f64,
    /// TCP speed of travel moves (segments of kind travel), mm/s; absent: the toolpath's feed.
    #[serde(default)]
    pub travel_speed_mm_s: Option<f64>,
    /// Decimal places of speeds (mm/s): speeds equal when rounded share one speeddata.
    /// Default 1, at most 3.
    #[serde(default = "default_speed_decimals")]
    pub speed_decimals: usize,
}

fn yes() -> bool {
    true
}

fn none<T>() -> Option<T> {
    None
}

fn identity() -> [f64; 4] {
    [1.0, 0.0, 0.0, 0.0]
}

fn default_quat() -> [f64; 4] {
    [0.0, 1.0, 0.0, 0.0]
}

fn default_max_targets() -> usize {
    5000
}

fn default_ori_speed() -> f64 {
    500.0
}

fn default_speed_decimals() -> usize {
    1
}

fn default_wobj() -> Named<WobjValue> {
    Named {
        name: "wobj0".into(),
        value: None,
    }
}

fn default_zone() -> Named<ZoneValue> {
    Named {
        name: "z1".into(),
        value: None,
    }
}

/// Longest `module_prefix`, characters (room for the job id and the `_N_run` suffixes within
/// [`MAX_IDENTIFIER_LEN`]).
pub const MAX_PREFIX_LEN: usize = 10;

/// Names ABB predefines on every controller; a declaration would clash with them.
const PREDEFINED: &[&str] = &["tool0", "wobj0", "load0", "fine"];

fn check_quat(q: &[f64; 4]) -> Result<(), String> {
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if q.iter().all(|v| v.is_finite()) && (norm - 1.0).abs() <= 1e-3 {
        Ok(())
    } else {
        Err(format!(
            "{q:?} must be a unit quaternion [w, x, y, z] (norm {norm})"
        ))
    }
}

fn check_finite(v: &[f64]) -> Result<(), String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("{v:?} must be finite"))
    }
}

impl RapidSettings {
    /// Checks the values, part by part in this order: module names and size, the declared
    /// names, the tool, work object and zone data, the motion settings. Fields are named
    /// relative to `rapid`.
    ///
    /// # Errors
    /// The first field with a problem.
    pub fn validate(&self, profile: &crate::MachineProfile) -> Result<(), FieldError> {
        self.validate_modules()?;
        self.validate_names()?;
        self.validate_weld()?;
        self.validate_data()?;
        self.validate_motion(profile)
    }

    /// `module_prefix` an identifier of at most [`MAX_PREFIX_LEN`] characters (or empty); at
    /// least one target per module.
    fn validate_modules(&self) -> Result<(), FieldError> {
        if !self.module_prefix.is_empty() {
            check_identifier(&self.module_prefix)
                .map_err(|r| FieldError::new("module_prefix", r))?;
        }
        if self.module_prefix.len() > MAX_PREFIX_LEN {
            return Err(FieldError::new(
                "module_prefix",
                format!(
                    "{:?} is longer than {MAX_PREFIX_LEN} characters",
                    self.module_prefix
                ),
            ));
        }
        Allowed::at_least(1.0).whole().check_field(
            "max_targets_per_module",
            self.max_targets_per_module as f64,
            "",
        )
    }

    /// Every name that goes into the program: an identifier ([`check_identifier`]), not of
    /// the emitter's own forms ([`is_generated_name`]), distinct from the others in any case,
    /// and not a predefined name when its value is declared.
    fn validate_names(&self) -> Result<(), FieldError> {
        let mut names: Vec<(&str, &str)> = vec![
            ("tool.name", &self.tool.name),
            ("wobj.name", &self.wobj.name),
            ("zone.name", &self.zone.name),
        ];
        match &self.weld {
            WeldMode::Arc { seam, weld, .. } => {
                names.push(("weld.seam", seam));
                names.push(("weld.weld", weld));
            }
            WeldMode::DigitalOutput { signal } => names.push(("weld.signal", signal)),
        }
        if let Some(ufmec) = self.wobj.value.as_ref().and_then(|w| w.ufmec.as_ref()) {
            names.push(("wobj.value.ufmec", ufmec));
        }
        for (i, &(field, name)) in names.iter().enumerate() {
            check_identifier(name).map_err(|r| FieldError::new(field, r))?;
            if is_generated_name(name) {
                return Err(FieldError::new(
                    field,
                    format!("{name:?} has the form of a name the emitter declares (main, jobName, pN, vTSN)"),
                ));
            }
            if let Some((other, _)) = names[..i]
                .iter()
                .find(|(_, n)| n.eq_ignore_ascii_case(name))
            {
                return Err(FieldError::new(
                    field,
                    format!("{name:?} is already used by {other} (RAPID names ignore case)"),
                ));
            }
        }
        for (field, name, declared) in [
            ("tool.name", &self.tool.name, self.tool.value.is_some()),
            ("wobj.name", &self.wobj.name, self.wobj.value.is_some()),
            ("zone.name", &self.zone.name, self.zone.value.is_some()),
        ] {
            let predefined =
                PREDEFINED.iter().any(|p| p.eq_ignore_ascii_case(name)) || is_predefined_zone(name);
            if declared && predefined {
                return Err(FieldError::new(
                    field,
                    format!("{name:?} is predefined by ABB; declare the value under another name or drop `value`"),
                ));
            }
        }
        Ok(())
    }

    /// The arc weld data: with `data: program` an `arc` that sets the arc (a synergic job,
    /// a voltage or a current; none negative), gas times ≥ 0, and a `weld` prefix whose
    /// numbered names fit RAPID and clash with no other name; with `data: controller` neither
    /// `arc` nor `seam_value` (the controller's data hold them).
    fn validate_weld(&self) -> Result<(), FieldError> {
        let WeldMode::Arc {
            data,
            seam,
            weld,
            arc,
            seam_value,
        } = &self.weld
        else {
            return Ok(());
        };
        if *data == WeldDataSource::Controller {
            for (field, given) in [
                ("weld.arc", arc.is_some()),
                ("weld.seam_value", seam_value.is_some()),
            ] {
                if given {
                    return Err(FieldError::new(
                        field,
                        "only with data: program (with data: controller the controller's seamdata and welddata hold these)",
                    ));
                }
            }
            return Ok(());
        }
        let Some(arc) = arc else {
            return Err(FieldError::new(
                "weld.arc",
                "data: program declares the welddata, so it needs the power source's settings: arc: {sched: JOB} for a synergic job, or voltage_v / current_a (or use data: controller)",
            ));
        };
        Allowed::NON_NEGATIVE.check_field("weld.arc.voltage_v", arc.voltage_v, "V")?;
        Allowed::NON_NEGATIVE.check_field("weld.arc.current_a", arc.current_a, "A")?;
        Allowed::FINITE.check_field("weld.arc.control", arc.control, "")?;
        if arc.sched == 0 && arc.voltage_v == 0.0 && arc.current_a == 0.0 {
            return Err(FieldError::new(
                "weld.arc",
                "nothing sets the arc: give sched (the synergic job) or voltage_v / current_a",
            ));
        }
        if let Some(sv) = seam_value {
            for (field, v) in [
                ("weld.seam_value.purge_s", sv.purge_s),
                ("weld.seam_value.preflow_s", sv.preflow_s),
                ("weld.seam_value.postflow_s", sv.postflow_s),
            ] {
                Allowed::NON_NEGATIVE.check_field(field, v, "s")?;
            }
        }
        if weld.len() > MAX_WELD_PREFIX_LEN {
            return Err(FieldError::new(
                "weld.weld",
                format!("{weld:?} is longer than {MAX_WELD_PREFIX_LEN} characters (with data: program it is the prefix of weld1, weld2, …)"),
            ));
        }
        if is_generated_name(&welddata_name(weld, 1)) {
            return Err(FieldError::new(
                "weld.weld",
                format!("{weld:?}: the welddata {} would have the form of a name the emitter declares (pN, vTSN)", welddata_name(weld, 1)),
            ));
        }
        let others = [
            ("tool.name", &self.tool.name),
            ("wobj.name", &self.wobj.name),
            ("zone.name", &self.zone.name),
            ("weld.seam", seam),
        ];
        if let Some((field, name)) = others.iter().find(|(_, n)| is_welddata_name(weld, n)) {
            return Err(FieldError::new(
                *field,
                format!("{name:?} has the form of a welddata name the program declares ({weld}1, {weld}2, …)"),
            ));
        }
        Ok(())
    }

    /// The declared tool, work object and zone values: finite frames, unit quaternions, tool
    /// mass > 0, zone radii ≥ 0 with a TCP zone > 0.
    fn validate_data(&self) -> Result<(), FieldError> {
        fn rule(field: &'static str) -> impl Fn(String) -> FieldError {
            move |reason| FieldError::new(field, reason)
        }
        if let Some(t) = &self.tool.value {
            check_finite(&t.tcp_mm).map_err(rule("tool.value.tcp_mm"))?;
            check_quat(&t.tcp_quat).map_err(rule("tool.value.tcp_quat"))?;
            Allowed::POSITIVE.check_field("tool.value.mass_kg", t.mass_kg, "kg")?;
            check_finite(&t.cog_mm).map_err(rule("tool.value.cog_mm"))?;
        }
        if let Some(w) = &self.wobj.value {
            check_finite(&w.uframe_mm).map_err(rule("wobj.value.uframe_mm"))?;
            check_quat(&w.uframe_quat).map_err(rule("wobj.value.uframe_quat"))?;
            check_finite(&w.oframe_mm).map_err(rule("wobj.value.oframe_mm"))?;
            check_quat(&w.oframe_quat).map_err(rule("wobj.value.oframe_quat"))?;
        }
        if let Some(z) = &self.zone.value {
            Allowed::POSITIVE.check(z.pzone_tcp_mm, "mm").map_err(|e| {
                e.because("use the predefined `fine` for stop points")
                    .at("zone.value.pzone_tcp_mm")
            })?;
            for v in z.components() {
                Allowed::NON_NEGATIVE.check_field("zone.value", v, "")?;
            }
        }
        Ok(())
    }

    /// Robot configuration quadrants in range, a unit default orientation, a reorientation
    /// speed > 0, a travel speed in (0, `max_feed_mm_s`], at most 3 speed decimals.
    fn validate_motion(&self, profile: &crate::MachineProfile) -> Result<(), FieldError> {
        let [cf1, cf4, cf6, cfx] = self.robconf;
        if ![cf1, cf4, cf6].iter().all(|c| (-4..=3).contains(c)) || !(0..=7).contains(&cfx) {
            return Err(FieldError::new(
                "robconf",
                format!(
                    "{:?}: cf1, cf4, cf6 must lie in -4..=3 and cfx in 0..=7",
                    self.robconf
                ),
            ));
        }
        check_quat(&self.default_orientation)
            .map_err(|r| FieldError::new("default_orientation", r))?;
        Allowed::POSITIVE.check_field(
            "orientation_speed_deg_s",
            self.orientation_speed_deg_s,
            "deg/s",
        )?;
        if let Some(v) = self.travel_speed_mm_s {
            Allowed::between(
                Bound::Exclusive(0.0),
                Bound::Inclusive(profile.max_feed_mm_s),
            )
            .check(v, "mm/s")
            .map_err(|e| e.because("max_feed_mm_s").at("travel_speed_mm_s"))?;
        }
        Allowed::at_most(3.0)
            .whole()
            .check_field("speed_decimals", self.speed_decimals as f64, "")
    }
}

/// True for ABB's predefined zonedata `z0` … `z200` (and `fine`).
pub fn is_predefined_zone(name: &str) -> bool {
    const ZONES: &[&str] = &[
        "fine", "z0", "z1", "z5", "z10", "z15", "z20", "z30", "z40", "z50", "z60", "z80", "z100",
        "z150", "z200",
    ];
    ZONES.iter().any(|z| z.eq_ignore_ascii_case(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_follow_the_rapid_rules() {
        assert!(check_identifier("tWAAM_1").is_ok());
        assert!(check_identifier(&"a".repeat(32)).is_ok());
        for bad in ["", "1abc", "_a", "a-b", "a b", "a\"b", "endproc", "Module"] {
            assert!(check_identifier(bad).is_err(), "{bad:?}");
        }
        let e = check_identifier(&"a".repeat(33)).unwrap_err();
        assert!(e.contains("at most 32"), "{e}");
        assert!(is_generated_name("P12") && is_generated_name("vts3") && is_generated_name("MAIN"));
        assert!(!is_generated_name("p") && !is_generated_name("pX1") && !is_generated_name("vTS"));
    }

    fn yaml(name: &str) -> String {
        crate::EMBEDDED_PROFILES
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap()
            .1
            .to_string()
    }

    fn field_of(text: &str) -> String {
        match crate::MachineProfile::from_yaml_str(text, "m.yaml").unwrap_err() {
            crate::ProfileError::Invalid { field, .. } => field,
            e => panic!("not a value error: {e}"),
        }
    }

    #[test]
    fn robot_profiles_load_with_their_rapid_sections() {
        let p = crate::MachineProfile::resolve("abb-irb2600-waam").unwrap();
        let r = p.rapid.as_ref().unwrap();
        assert_eq!(r.robotware, RobotWare::Rw6);
        assert!(matches!(&r.weld, WeldMode::Arc { seam, .. } if seam == "seamWAAM"));
        assert_eq!(r.tool.value.as_ref().unwrap().tcp_mm, [0.0, 0.0, 400.0]);
        let p = crate::MachineProfile::resolve("abb-irb1600-rw7-do").unwrap();
        let r = p.rapid.as_ref().unwrap();
        assert_eq!(r.robotware, RobotWare::Rw7);
        assert_eq!(
            (r.wobj.name.as_str(), r.wobj.value.is_none()),
            ("wobj0", true)
        );
        assert_eq!(r.zone.value.as_ref().unwrap().pzone_tcp_mm, 0.5);
        // Defaults.
        assert_eq!(r.robconf, [0, 0, 0, 0]);
        assert_eq!(r.default_orientation, [0.0, 1.0, 0.0, 0.0]);
        assert!(r.confl_off);
        assert_eq!((r.max_targets_per_module, r.speed_decimals), (5000, 1));
    }

    #[test]
    fn bad_rapid_values_name_the_field() {
        let base = yaml("abb-irb2600-waam");
        for (from, to, field) in [
            ("name: tWAAM", "name: 1tool", "rapid.tool.name"),
            ("name: tWAAM", "name: \"t;ENDPROC\"", "rapid.tool.name"),
            ("name: tWAAM", "name: PROC", "rapid.tool.name"),
            ("name: tWAAM", "name: p7", "rapid.tool.name"),
            ("name: tWAAM", "name: WOBJPLATE", "rapid.wobj.name"),
            ("name: wobjPlate", "name: wobj0", "rapid.wobj.name"),
            ("name: z1", "name: z1x-", "rapid.zone.name"),
            ("seam: seamWAAM", "seam: seam WAAM", "rapid.weld.seam"),
            ("weld: weldWAAM", "weld: seamWAAM", "rapid.weld.weld"),
            (
                "module_prefix: WAAM_",
                "module_prefix: 9_",
                "rapid.module_prefix",
            ),
            (
                "module_prefix: WAAM_",
                "module_prefix: ABCDEFGHIJK",
                "rapid.module_prefix",
            ),
            (
                "max_targets_per_module: 5000",
                "max_targets_per_module: 0",
                "rapid.max_targets_per_module",
            ),
            ("mass_kg: 4.5", "mass_kg: 0.0", "rapid.tool.value.mass_kg"),
            (
                "tcp_quat: [1.0, 0.0, 0.0, 0.0]",
                "tcp_quat: [1.0, 1.0, 0.0, 0.0]",
                "rapid.tool.value.tcp_quat",
            ),
            (
                "uframe_quat: [1.0, 0.0, 0.0, 0.0]",
                "uframe_quat: [0.0, 0.0, 0.0, 0.0]",
                "rapid.wobj.value.uframe_quat",
            ),
            (
                "robconf: [0, 0, 0, 0]",
                "robconf: [0, 0, 0, 8]",
                "rapid.robconf",
            ),
            (
                "robconf: [0, 0, 0, 0]",
                "robconf: [5, 0, 0, 0]",
                "rapid.robconf",
            ),
            (
                "default_orientation: [0.0, 1.0, 0.0, 0.0]",
                "default_orientation: [0.0, 2.0, 0.0, 0.0]",
                "rapid.default_orientation",
            ),
            (
                "orientation_speed_deg_s: 500.0",
                "orientation_speed_deg_s: -1.0",
                "rapid.orientation_speed_deg_s",
            ),
            (
                "travel_speed_mm_s: 100.0",
                "travel_speed_mm_s: 300.0",
                "rapid.travel_speed_mm_s",
            ),
            (
                "speed_decimals: 1",
                "speed_decimals: 4",
                "rapid.speed_decimals",
            ),
        ] {
            let text = base.replacen(from, to, 1);
            assert_ne!(text, base, "{from}");
            assert_eq!(field_of(&text), field, "{from} -> {to}");
        }
        let zone = base.replace(
            "    name: z1\n",
            "    name: zW\n    value: {pzone_tcp_mm: 0.0}\n",
        );
        assert_eq!(field_of(&zone), "rapid.zone.value.pzone_tcp_mm");
        let zone = base.replace(
            "    name: z1\n",
            "    name: z10\n    value: {pzone_tcp_mm: 1.0}\n",
        );
        assert_eq!(field_of(&zone), "rapid.zone.name");
        let ufmec = base.replace(
            "      uframe_mm:",
            "      ufmec: \"STN1\\\"\"\n      uframe_mm:",
        );
        assert_eq!(field_of(&ufmec), "rapid.wobj.value.ufmec");
        let both = format!(
            "{base}gcode:\n  dialect: grbl\n  axis_words: {{x: X, y: Y}}\n  decimals: 3\n  feed_mode: units_per_minute\n"
        );
        assert_eq!(field_of(&both), "rapid");
        // Unknown keys and unknown modes are parse errors that name them.
        for (from, to, key) in [
            ("speed_decimals: 1", "speed_decimal: 1", "speed_decimal"),
            ("mode: arc", "mode: laser", "laser"),
            (
                "seam: seamWAAM",
                "seam: seamWAAM\n    signal: doWeld",
                "signal",
            ),
            ("mass_kg: 4.5", "mass_kg: 4.5\n      masss: 1", "masss"),
        ] {
            let text = base.replace(from, to);
            let e = crate::MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
            assert!(
                matches!(
                    &e,
                    crate::ProfileError::Parse(cell_config::ParseError { line: Some(_), .. })
                ) && e.to_string().contains(key),
                "{to}: {e}"
            );
        }
    }

    #[test]
    fn weld_data_source_is_validated_by_field() {
        let base = yaml("abb-irb2600-waam");
        let p = crate::MachineProfile::from_yaml_str(&base, "m.yaml").unwrap();
        match &p.rapid.as_ref().unwrap().weld {
            WeldMode::Arc {
                data, arc, weld, ..
            } => {
                assert_eq!(*data, WeldDataSource::Program);
                assert_eq!(arc.as_ref().unwrap().sched, 1);
                assert_eq!(welddata_name(weld, 3), "weldWAAM3");
            }
            w => panic!("{w:?}"),
        }
        // Controller-side data by name: no arc, no seam_value.
        let arc_block =
            "    arc:\n      sched: 1\n      mode: 0\n      voltage_v: 0.0\n      current_a: 0.0\n";
        let seam_block =
            "    seam_value:\n      purge_s: 0.2\n      preflow_s: 0.05\n      postflow_s: 0.05\n";
        assert!(base.contains(arc_block) && base.contains(seam_block));
        let controller = base
            .replace("data: program", "data: controller")
            .replace(arc_block, "")
            .replace(seam_block, "");
        let p = crate::MachineProfile::from_yaml_str(&controller, "m.yaml").unwrap();
        assert!(matches!(
            &p.rapid.as_ref().unwrap().weld,
            WeldMode::Arc {
                data: WeldDataSource::Controller,
                arc: None,
                ..
            }
        ));
        // `data` absent: program, which needs arc.
        let no_data = base.replace("    data: program\n", "");
        assert!(crate::MachineProfile::from_yaml_str(&no_data, "m.yaml").is_ok());
        for (text, field) in [
            (base.replace(arc_block, ""), "rapid.weld.arc"),
            (
                base.replace("data: program", "data: controller"),
                "rapid.weld.arc",
            ),
            (
                base.replace("data: program", "data: controller")
                    .replace(arc_block, ""),
                "rapid.weld.seam_value",
            ),
            (base.replace("sched: 1", "sched: 0"), "rapid.weld.arc"),
            (
                base.replace("voltage_v: 0.0", "voltage_v: -1.0"),
                "rapid.weld.arc.voltage_v",
            ),
            (
                base.replace("current_a: 0.0", "current_a: .nan"),
                "rapid.weld.arc.current_a",
            ),
            (
                base.replace("preflow_s: 0.05", "preflow_s: -0.1"),
                "rapid.weld.seam_value.preflow_s",
            ),
            (
                base.replace("weld: weldWAAM", &format!("weld: w{}", "x".repeat(27))),
                "rapid.weld.weld",
            ),
            (
                base.replace("weld: weldWAAM", "weld: vTS"),
                "rapid.weld.weld",
            ),
            (base.replace("weld: weldWAAM", "weld: p"), "rapid.weld.weld"),
            (
                base.replace("name: tWAAM", "name: weldWAAM7"),
                "rapid.tool.name",
            ),
            (
                base.replace("seam: seamWAAM", "seam: WELDwaam12"),
                "rapid.weld.seam",
            ),
        ] {
            assert_ne!(text, base, "{field}");
            assert_eq!(field_of(&text), field, "{text}");
        }
        // A synergic job is not needed when the voltage is given.
        let manual = base
            .replace("sched: 1", "sched: 0")
            .replace("voltage_v: 0.0", "voltage_v: 19.5");
        assert!(crate::MachineProfile::from_yaml_str(&manual, "m.yaml").is_ok());
        // Unknown data sources and keys are parse errors naming them.
        for (from, to, key) in [
            ("data: program", "data: module", "module"),
            ("sched: 1", "shed: 1", "shed"),
        ] {
            let e = crate::MachineProfile::from_yaml_str(&base.replace(from, to), "m.yaml")
                .unwrap_err();
            assert!(e.to_string().contains(key), "{e}");
        }
        assert!(is_welddata_name("weldWAAM", "WELDWAAM12"));
        assert!(
            !is_welddata_name("weldWAAM", "weldWAAM")
                && !is_welddata_name("weldWAAM", "weldWAAMx1")
        );
    }

    #[test]
    fn zone_defaults_follow_abb_predefined_zones() {
        let z = ZoneValue {
            pzone_tcp_mm: 1.0,
            pzone_ori_mm: None,
            pzone_eax_mm: None,
            zone_ori_deg: None,
            zone_leax_mm: None,
            zone_reax_deg: None,
        };
        // z1 = [FALSE,1,1,1,0.1,1,0.1] (ABB, zonedata, predefined data).
        assert_eq!(z.components(), [1.0, 1.0, 1.0, 0.1, 1.0, 0.1]);
    }
}
