//! `cell_emitter`: turns a `Toolpath` into a `MachineProgram` for a machine profile.
//!
//! - [`arcs`]: G2/G3 arc fitting within a tolerance.
//! - [`gcode`]: G-code for the profile's dialect (`cell_profiles::GcodeSettings`): axis words,
//!   decimals, G94 or G93 inverse-time feeds, power words, pre-heat dwell, start and end lines.
//! - [`compensation`]: controller cutter compensation for sheet cutting (`G41`/`G42`, the kerf
//!   in LinuxCNC's tool table), for profiles with `cutting.compensation: controller`.
//! - [`rapid`]: ABB RAPID modules (`.mod`, `.modx` on RobotWare 7) and program files (`.pgf`)
//!   for a robot profile (seed 004 §4.7): robtargets, speeddata per speed, arc or digital-output
//!   weld on/off, module splitting.
//! - [`program`]: the `MachineProgram` message (files, line count, SHA-256) and atomic file
//!   output.
//!
//! Everything here is pure and synchronous: it knows nothing of ROS (the `emitter` node in
//! `nodes/emitter` serves it: topic in, topic out, the `emit_program` service). Every input is
//! checked first, so a bad toolpath gives an error naming the segment and point and never a
//! partial program.

#![warn(missing_docs)]

pub mod arcs;
pub mod compensation;
pub mod gcode;
pub mod program;
pub mod rapid;

use cell_msgs::{MachineProgram, ProgramFile, Toolpath};
use cell_profiles::MachineProfile;

/// What a job adds to the profile for one program.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EmitOptions {
    /// The sheet's material and thickness, for the kerf of controller compensation; `None`:
    /// the profile's `cutting.default_material`.
    pub material: Option<cell_profiles::MaterialRef>,
}

/// The program for `toolpath` on `profile`: G-code (one `.ngc` file) if the profile has a
/// `gcode` section, RAPID modules if it has a `rapid` section. `job_id` names the files and
/// goes into their header comments, sanitised. As [`emit_program_with`] with the default
/// options.
///
/// # Errors
/// A profile with neither section, or any error of [`gcode::emit`] / [`rapid::emit`]. Nothing
/// is returned unless the whole program was written.
pub fn emit_program(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    job_id: &str,
) -> Result<MachineProgram, EmitError> {
    emit_program_with(toolpath, profile, job_id, &EmitOptions::default())
}

/// As [`emit_program`], with the job's `options`. A sheet-cutting program with controller
/// compensation gets a second file, the tool table [`compensation::TOOL_TABLE_FILE`] with the
/// kerf as tool 1's diameter.
///
/// # Errors
/// As [`emit_program`].
pub fn emit_program_with(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    job_id: &str,
    options: &EmitOptions,
) -> Result<MachineProgram, EmitError> {
    let (dialect, files) = if let Some(g) = &profile.gcode {
        let text = gcode::emit_with(toolpath, profile, job_id, options)?;
        let dialect = serde_dialect_name(g.dialect);
        let mut files = vec![ProgramFile {
            name: format!("{}.{}", file_stem(job_id), program_extension(g.dialect)),
            text,
        }];
        if let Some(kerf) = compensation::controller_kerf_mm(toolpath, profile, options)? {
            let (kerf, unit) = match g.units {
                cell_profiles::Units::Mm => (kerf, "mm"),
                cell_profiles::Units::Inch => (kerf / 25.4, "inch"),
            };
            files.push(ProgramFile {
                name: compensation::TOOL_TABLE_FILE.into(),
                text: compensation::tool_table(kerf, unit),
            });
        }
        (dialect, files)
    } else if profile.rapid.is_some() {
        ("rapid".to_string(), rapid::emit(toolpath, profile, job_id)?)
    } else {
        return Err(EmitError::MissingSection {
            profile: profile.name.clone(),
            section: "gcode or rapid",
        });
    };
    Ok(program::machine_program(
        job_id,
        &dialect,
        &profile.name,
        files,
    ))
}

/// The G-code file's extension: `gcode` for Marlin (its SD card lists only `.gcode`, `.gco` and
/// `.g` files, and printer hosts look for them), `ngc` (RS274NGC) for the CNC dialects.
pub fn program_extension(dialect: cell_profiles::Dialect) -> &'static str {
    match dialect {
        cell_profiles::Dialect::Marlin => "gcode",
        _ => "ngc",
    }
}

/// The dialect's name as profiles spell it (`grbl`, `linuxcnc`, `mach3`, `marlin`).
fn serde_dialect_name(d: cell_profiles::Dialect) -> String {
    format!("{d:?}").to_ascii_lowercase()
}

/// A file name stem from a job id: letters, digits, `_` and `-` only (others become `_`), at
/// most 64 characters, `program` if nothing is left.
pub fn file_stem(job_id: &str) -> String {
    let stem: String = job_id
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .take(64)
        .collect();
    if stem.trim_matches('_').is_empty() {
        "program".into()
    } else {
        stem
    }
}

/// A toolpath or profile the emitter cannot turn into a program. One line, naming the segment
/// and point (0-based) where it applies.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EmitError {
    /// The profile has no section for the requested output.
    #[error("machine profile {profile:?} has no {section} section")]
    MissingSection {
        /// Profile name.
        profile: String,
        /// The section, e.g. `gcode`.
        section: &'static str,
    },
    /// A coordinate, feed or power that is NaN or infinite.
    #[error("segment {segment} point {point}: {what} is not finite")]
    NonFinite {
        /// Segment index.
        segment: usize,
        /// Point index within the segment.
        point: usize,
        /// Which value.
        what: &'static str,
    },
    /// A feed that is not > 0 on a move that goes somewhere.
    #[error("segment {segment} point {point}: feed {feed_mm_s} mm/s must be > 0")]
    Feed {
        /// Segment index.
        segment: usize,
        /// Point index within the segment.
        point: usize,
        /// The feed given.
        feed_mm_s: f32,
    },
    /// A negative power (current, laser power or flow).
    #[error("segment {segment} point {point}: power {power} must be >= 0")]
    Power {
        /// Segment index.
        segment: usize,
        /// Point index within the segment.
        point: usize,
        /// The power given.
        power: f32,
    },
    /// A program line longer than the controller accepts.
    #[error("program line {line} has {length} characters; the controller takes at most {limit}")]
    LineTooLong {
        /// 1-based line number in the program.
        line: usize,
        /// Its length.
        length: usize,
        /// The dialect's limit.
        limit: usize,
    },
    /// Per-point arrays of a segment with the wrong length.
    #[error("segment {segment}: {what} has {found} entries, the segment has {expected} points")]
    Length {
        /// Segment index.
        segment: usize,
        /// Which array.
        what: &'static str,
        /// Points in the segment.
        expected: usize,
        /// Entries given.
        found: usize,
    },
    /// The toolpath needs an axis the profile does not map (e.g. UV points on an XY machine).
    #[error("machine profile {profile:?} has no axis for {what}")]
    NoAxis {
        /// Profile name.
        profile: String,
        /// What needed the axis.
        what: &'static str,
    },
    /// A robtarget the profile's robot cannot reach within its joint ranges in the program's
    /// one arm configuration (RAPID with a `robot` section; `rapid/reach.rs`).
    #[error("layer {layer}, segment {segment} point {point} at ({x:.3}, {y:.3}, {z:.3}) mm in the work object: {problem}")]
    Reach {
        /// Layer of the segment.
        layer: u32,
        /// Segment index (a bead or a travel).
        segment: usize,
        /// Point index within the segment.
        point: usize,
        /// The robtarget position, mm.
        x: f64,
        /// The robtarget position, mm.
        y: f64,
        /// The robtarget position, mm.
        z: f64,
        /// Why (out of reach, a joint range, a configuration change).
        problem: cell_kinematics::ReachProblem,
    },
    /// A position outside the machine's travel.
    #[error("segment {segment} point {point}: {violation}")]
    Envelope {
        /// Segment index.
        segment: usize,
        /// Point index within the segment.
        point: usize,
        /// Which axis and value.
        violation: cell_profiles::EnvelopeViolation,
    },
    /// A feed above the machine's `max_feed_mm_s` (RAPID: the speed of a move, travel speed
    /// included).
    #[error("segment {segment} point {point}: speed {feed_mm_s} mm/s is above the machine's max_feed_mm_s = {max_feed_mm_s}")]
    FeedLimit {
        /// Segment index.
        segment: usize,
        /// Point index within the segment.
        point: usize,
        /// The speed asked for, mm/s.
        feed_mm_s: f64,
        /// The profile's limit, mm/s.
        max_feed_mm_s: f64,
    },
    /// A tool-axis normal of (nearly) zero length: no orientation can be derived from it.
    #[error("segment {segment} point {point}: the normal has zero length")]
    Normal {
        /// Segment index.
        segment: usize,
        /// Point index within the segment.
        point: usize,
    },
    /// A process run (cut, deposit or lead points between travel moves) of a single point:
    /// the process would switch on and off at one place.
    #[error(
        "segment {segment} point {point}: a weld run needs at least two points, this one has one"
    )]
    ShortRun {
        /// Segment index.
        segment: usize,
        /// Point index within the segment.
        point: usize,
    },
    /// Program-side arc welding data (RAPID `data: program`) the toolpath cannot give: no
    /// wire feed, or none > 0 on a weld point.
    #[error("segment {segment} point {point}: {reason}")]
    WeldData {
        /// Segment index.
        segment: usize,
        /// Point index within the segment.
        point: usize,
        /// What is missing.
        reason: String,
    },
    /// More part modules than the names allow (RAPID: raise `max_targets_per_module`).
    #[error("the program needs {modules} modules, more than {max}; raise max_targets_per_module")]
    TooManyModules {
        /// Modules needed.
        modules: usize,
        /// The most the emitter writes.
        max: usize,
    },
    /// A name built from user text that is not a valid identifier of the output language.
    #[error("identifier {name:?}: {reason}")]
    Identifier {
        /// The name.
        name: String,
        /// The rule broken.
        reason: String,
    },
    /// Controller compensation without a kerf: no material, or none the profile's kerf table
    /// has.
    #[error("machine profile {profile:?}: controller compensation: {reason}")]
    Kerf {
        /// Profile name.
        profile: String,
        /// What is missing.
        reason: String,
    },
    /// Controller compensation on a contour without a lead-in from its scrap side: the
    /// controller's entry move would end in the part.
    #[error(
        "segment {segment}: controller compensation needs a lead-in onto this contour from its \
         scrap side (entering from the rapid would cut into the part)"
    )]
    NoLeadIn {
        /// The contour's cut segment.
        segment: usize,
    },
    /// A contour where controller compensation cannot be switched on: no lead-in move nor
    /// rapid longer than the tool radius (LinuxCNC refuses a shorter entry move).
    #[error(
        "segment {segment}: no lead-in move or rapid to the pierce longer than the kerf radius \
         {radius_mm} mm to switch cutter compensation on"
    )]
    CompensationEntry {
        /// The contour's lead-in segment.
        segment: usize,
        /// Half the kerf, mm.
        radius_mm: f64,
    },
    /// Controller compensation of an arc that curves round the tool with a radius no larger
    /// than the tool's (half the kerf): LinuxCNC refuses it, the hole or lead is too small.
    #[error(
        "segment {segment}: an arc of radius {arc_radius_mm:.3} mm curves round the tool, which \
         needs more than the kerf radius {radius_mm} mm: too small for controller compensation"
    )]
    CompensationArc {
        /// The segment (lead-in, cut or lead-out).
        segment: usize,
        /// The arc's radius, mm.
        arc_radius_mm: f64,
        /// Half the kerf, mm.
        radius_mm: f64,
    },
    /// Writing the output failed.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        message: String,
    },
}

/// Checks that a segment's per-point arrays each hold one entry per point (`secondary_points`,
/// `power` and, if `with_normals`, `normals` may also be empty).
fn check_lengths(
    seg: &cell_msgs::ToolpathSegment,
    segment: usize,
    with_normals: bool,
) -> Result<(), EmitError> {
    let n = seg.points.len();
    let mut arrays = vec![
        ("secondary_points", seg.secondary_points.len(), true),
        ("feed_mm_s", seg.feed_mm_s.len(), false),
        ("power", seg.power.len(), true),
    ];
    if with_normals {
        arrays.push(("normals", seg.normals.len(), true));
    }
    for (what, len, may_be_empty) in arrays {
        if len != n && !(may_be_empty && len == 0) {
            return Err(EmitError::Length {
                segment,
                what,
                expected: n,
                found: len,
            });
        }
    }
    Ok(())
}
