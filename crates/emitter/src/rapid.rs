//! ABB RAPID from a `Toolpath` (seed 004 §4.7), for a profile's `rapid` section
//! (`cell_profiles::RapidSettings`).
//!
//! Seed 004 §4.7 moves the tool centre point linearly through the toolpath points: every point
//! is a declared `robtarget` (position, orientation quaternion, robot configuration, external
//! axes), every move a `MoveL` with speed, zone, tool and work object, and because the bead
//! width depends on the travel speed, one `speeddata` is declared per distinct speed. The
//! thesis gives no orientation, zone, tool or arc on/off data; those come from the profile.
//! With the Arc option the welding data are the program's too (`weld: {mode: arc, data:
//! program}`, the default): one `welddata` per distinct bead, so the module is self-contained.
//!
//! # Output
//!
//! For job `job42` with `module_prefix: WAAM_` on RobotWare 6 (RobotWare 7: `.modx`):
//!
//! - `WAAM_job42.mod`: the main module, with `PROC main()`;
//! - `WAAM_job42_1.mod`, `WAAM_job42_2.mod`, …: only when the program has more than
//!   `max_targets_per_module` points; then `main` calls `WAAM_job42_1_run;`,
//!   `WAAM_job42_2_run;`, … in order and each part module declares its own targets, speeds
//!   and weld data;
//! - `WAAM_job42.pgf`: the program file listing every module.
//!
//! A small program (arc mode, `data: program`; two beads at 8 and 10 mm/s, wire feed 5.53
//! m/min, synergic job 1):
//!
//! ```text
//! MODULE WAAM_job42
//!     ! cellsuite emitter: job job42, profile abb-irb2600-waam
//!     LOCAL CONST string jobName := "job42";
//!     PERS tooldata tWAAM := [TRUE,[[0,0,400],[1,0,0,0]],[4.5,[0,0,150],[1,0,0,0],0,0,0]];
//!     LOCAL CONST speeddata vTS1 := [100,500,5000,1000];
//!     LOCAL CONST speeddata vTS2 := [8,500,5000,1000];
//!     LOCAL CONST speeddata vTS3 := [10,500,5000,1000];
//!     LOCAL PERS seamdata seamWAAM := [0.2,0.05,[0,0,0,0,0,0,0,0,0],0,0,0,0,0,…,0.05];
//!     LOCAL PERS welddata weldWAAM1 := [8,8,[1,0,0,5.53,0,0,0,0,0],[1,0,0,5.53,0,0,0,0,0]];
//!     LOCAL PERS welddata weldWAAM2 := [10,10,[1,0,0,5.53,0,0,0,0,0],[1,0,0,5.53,0,0,0,0,0]];
//!     LOCAL CONST robtarget p1 := [[10,20,5],[0,1,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
//!     …
//!     PROC main()
//!         TPWrite jobName;
//!         ConfL \Off;
//!         MoveL p1, vTS1, z1, tWAAM\WObj:=wobjPlate;
//!         ArcLStart p2, vTS1, seamWAAM, weldWAAM1, fine, tWAAM\WObj:=wobjPlate;
//!         ArcL p3, vTS2, seamWAAM, weldWAAM1, z1, tWAAM\WObj:=wobjPlate;
//!         ArcLEnd p4, vTS3, seamWAAM, weldWAAM2, fine, tWAAM\WObj:=wobjPlate;
//!     ENDPROC
//! ENDMODULE
//! ```
//!
//! ```
//! use cell_msgs::{geometry_msgs::Point, Toolpath, ToolpathSegment};
//! let profile = cell_profiles::MachineProfile::resolve("abb-irb2600-waam").unwrap();
//! let p = |x| Point { x, y: 100.0, z: 10.0 };
//! let toolpath = Toolpath {
//!     power_unit: Toolpath::POWER_WIRE_FEED_M_MIN,
//!     segments: vec![ToolpathSegment {
//!         kind: ToolpathSegment::KIND_DEPOSIT,
//!         points: vec![p(100.0), p(150.0)],
//!         feed_mm_s: vec![8.0, 8.0],
//!         power: vec![5.53, 5.53],
//!         ..Default::default()
//!     }],
//!     ..Default::default()
//! };
//! let files = cell_emitter::rapid::emit(&toolpath, &profile, "job42").unwrap();
//! assert_eq!(files[0].name, "WAAM_job42.mod");
//! let text = &files[0].text;
//! assert!(text.contains("LOCAL PERS welddata weldWAAM1 := [8,8,[1,0,0,5.53,0,0,0,0,0],"));
//! assert!(text.contains("ArcLStart p1, vTS1, seamWAAM, weldWAAM1, fine, tWAAM"));
//! assert_eq!(files.last().unwrap().name, "WAAM_job42.pgf");
//! ```
//!
//! # Motion and process
//!
//! - **Orientation** ([`orientation_from_normal`]): the tool z-axis points *against* the
//!   toolpath normal (the normal is the surface normal pointing away from the part, the torch
//!   points down onto it), tool x as close as possible to work-object +X. Points without
//!   normals use `default_orientation`.
//! - **Speeds**: the speed of the move *to* a point is that point's feed (travel segments:
//!   `travel_speed_mm_s` if set), rounded to `speed_decimals`; `speeddata` `vTS1`, `vTS2`, … are
//!   numbered in order of first use over the whole program, `[v_tcp, v_ori, 5000, 1000]`
//!   (mm/s, deg/s, and ABB's predefined external-axis speeds).
//! - **Process on** for cut, deposit and lead segments (a lead is part of the process run, as
//!   in the G-code writer), off for travel segments. Consecutive process segments form one
//!   weld run, which needs at least two points. Travel moves are `MoveL` (a controlled
//!   straight path near the part, not a joint move). The first and last point of a run are
//!   `fine` (the process switches there: a fly-by point would run `SetDO` early, since RAPID
//!   executes logical instructions ahead of the motion); the last move of the program is
//!   `fine`; every other point uses the profile's zone.
//!   - `arc`: `ArcLStart` to the run's first point, `ArcL` through, `ArcLEnd` at its last.
//!     While welding the TCP runs at the welddata's `weld_speed`, not the speeddata's.
//!     - `data: program` (default): a bead is (the move's speed, the toolpath's wire feed at
//!       the point, m/min to 3 decimals; the toolpath's `power` in
//!       `POWER_WIRE_FEED_M_MIN`, else an error); the move *to* a point welds that point's
//!       bead, `ArcLStart` carries the run's first bead. Welddata `weld1`, `weld2`, … (`weld`
//!       is the profile's prefix) are numbered in order of first use over the whole program,
//!       `[weld_speed, weld_speed, arc, arc]` with `arc` = `[sched, mode, voltage, wirefeed,
//!       control, current, 0, 0, 0]` from the profile's `arc` and the bead's wire feed; one
//!       `seamdata` (ABB's default with the profile's gas times). Both are `LOCAL PERS` in
//!       every module that welds (layouts and sources: `rapid/weld.rs`).
//!     - `data: controller`: every weld instruction names the profile's `seam` and `weld`,
//!       which the controller must declare (the RWS simulator checks this on load).
//!   - `digital_output`: `SetDO signal, 0;` at the start of `main`; `MoveL` to the first point,
//!     `SetDO signal, 1;`, `MoveL` through, `SetDO signal, 0;` after the last.
//! - **Splitting**: a program of more than `max_targets_per_module` points is cut into part
//!   modules of at most that many, preferably between weld runs (a run longer than the limit
//!   is cut inside; the process stays on across the call). Data in every module is `LOCAL`,
//!   so parts may reuse names; the tool, work object and zone (declared in the main module)
//!   and the part procedures are global. A welddata keeps its number (and value) in every
//!   module that uses it.
//!
//! # User text
//!
//! The job id becomes part of the module and procedure names reduced to letters, digits and
//! `_` (letter first, at most 32 characters, never a reserved word: `J_` is put in front of a
//! clash), a comment reduced to a safe character set (no line break can end it), and the
//! string `jobName`, escaped (`"` as `""`, `\` as `\\`, control characters as `\hh`, non-ASCII
//! as `?`) and cut to RAPID's 80 characters. No job id can add a statement to a module.

use std::collections::HashMap;
use std::fmt::Write as _;

use cell_msgs::{ProgramFile, Toolpath, ToolpathSegment};
use cell_profiles::rapid::{
    check_identifier, is_generated_name, is_welddata_name, welddata_name, RobotWare,
    WeldDataSource, WeldMode, MAX_IDENTIFIER_LEN, MAX_STRING_LEN, RESERVED_WORDS,
};
use cell_profiles::{MachineProfile, RapidSettings};
use nalgebra::{Rotation3, UnitQuaternion, Vector3};

use crate::EmitError;

pub mod reach;
mod weld;

/// Decimal places of positions, mm (1 µm).
const POSITION_DECIMALS: usize = 3;
/// Decimal places of quaternion components (RAPID wants them normalised; 6 places keep the
/// norm within 2e-6 of 1).
const QUATERNION_DECIMALS: usize = 6;
/// Longest job-derived base name: room for `_NNNNN_run` within 32 characters.
const MAX_BASE_LEN: usize = 22;
/// Most part modules (five digits in the names).
pub const MAX_PART_MODULES: usize = 99_999;
/// External-axis speeds of every speeddata, `v_leax` (mm/s) and `v_reax` (deg/s), as ABB's
/// predefined speeddata.
const EXTERNAL_AXIS_SPEEDS: &str = "5000,1000";
/// External axes of every robtarget: none (9E9 = not used).
const NO_EXTERNAL_AXES: &str = "[9E9,9E9,9E9,9E9,9E9,9E9]";

/// One checked point of the program.
#[derive(Debug, Clone, PartialEq)]
struct Move {
    position: [f64; 3],
    quat: [f64; 4],
    /// Speed as written (rounded).
    speed: String,
    welded: bool,
    run_start: bool,
    run_end: bool,
    /// The bead welded on the way to this point (a run's first point: the run's first bead),
    /// when the program declares its welddata.
    bead: Option<weld::Bead>,
    /// The computed `[cf1, cf4, cf6, cfx]` when the profile has a robot ([`reach`]).
    robconf: Option<[i32; 4]>,
}

/// The profile's `rapid` section, or [`EmitError::MissingSection`] naming the profile.
pub(crate) fn rapid_section(profile: &MachineProfile) -> Result<&RapidSettings, EmitError> {
    profile
        .rapid
        .as_ref()
        .ok_or_else(|| EmitError::MissingSection {
            profile: profile.name.clone(),
            section: "rapid",
        })
}

/// The RAPID files for `toolpath` on `profile` (module docs): the main module first, then the
/// part modules (if split), then the `.pgf`.
///
/// # Errors
/// A profile without a `rapid` section or without axes X, Y, Z; a non-finite value, a feed
/// ≤ 0 (after rounding) or above `max_feed_mm_s`, a zero-length normal or a per-point array of
/// the wrong length (naming segment and point); secondary points that differ from the primary
/// ones; a weld run of one point; a position outside the robot's travel; more than
/// [`MAX_PART_MODULES`] modules. Nothing is returned unless the whole program was written.
pub fn emit(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    job_id: &str,
) -> Result<Vec<ProgramFile>, EmitError> {
    let r = rapid_section(profile)?;
    if !['X', 'Y', 'Z'].iter().all(|a| profile.axes.contains_key(a)) {
        return Err(EmitError::NoAxis {
            profile: profile.name.clone(),
            what: "robot positions (X, Y and Z in the work object frame)",
        });
    }
    let moves = moves(toolpath, profile, r)?;
    let parts = split(&moves, r.max_targets_per_module);
    if parts.len() > MAX_PART_MODULES {
        return Err(EmitError::TooManyModules {
            modules: parts.len(),
            max: MAX_PART_MODULES,
        });
    }
    let base = base_name(r, job_id)?;
    let ext = match r.robotware {
        RobotWare::Rw6 => "mod",
        RobotWare::Rw7 => "modx",
    };
    // Speeddata names in order of first use over the whole program.
    let mut speed_names: HashMap<&str, String> = HashMap::new();
    for m in &moves {
        let next = speed_names.len() + 1;
        speed_names
            .entry(m.speed.as_str())
            .or_insert_with(|| format!("vTS{next}"));
    }
    // Welddata names (data: program), in order of first use like the speeds.
    let mut weld_names: HashMap<&weld::Bead, String> = HashMap::new();
    if let WeldMode::Arc { weld: prefix, .. } = &r.weld {
        for b in moves.iter().filter_map(|m| m.bead.as_ref()) {
            let next = weld_names.len() + 1;
            weld_names
                .entry(b)
                .or_insert_with(|| welddata_name(prefix, next));
        }
    }
    if let Some(name) = weld_names.values().find(|n| check_identifier(n).is_err()) {
        return Err(EmitError::Identifier {
            name: name.clone(),
            reason: format!(
                "{} distinct beads: more welddata than RAPID names allow (at most {} characters)",
                weld_names.len(),
                MAX_IDENTIFIER_LEN
            ),
        });
    }
    let w = Writer {
        r,
        moves: &moves,
        speed_names: &speed_names,
        weld_names: &weld_names,
    };
    let header = format!(
        "! cellsuite emitter: job {}, profile {}",
        crate::gcode::sanitise(job_id),
        crate::gcode::sanitise(&profile.name)
    );
    let mut files = Vec::new();
    if parts.len() == 1 {
        let mut text = String::new();
        let _ = writeln!(text, "MODULE {base}");
        let _ = writeln!(text, "    {header}");
        let _ = writeln!(
            text,
            "    ! {} targets, {} speeds",
            moves.len(),
            speed_names.len()
        );
        w.shared_declarations(&mut text, job_id);
        w.part_declarations(&mut text, 0..moves.len());
        let _ = writeln!(text);
        let _ = writeln!(text, "    PROC main()");
        w.main_start(&mut text);
        w.part_moves(&mut text, 0..moves.len());
        let _ = writeln!(text, "    ENDPROC");
        let _ = writeln!(text, "ENDMODULE");
        files.push(ProgramFile {
            name: format!("{base}.{ext}"),
            text,
        });
    } else {
        let n = parts.len();
        let mut main = String::new();
        let _ = writeln!(main, "MODULE {base}");
        let _ = writeln!(main, "    {header}");
        let _ = writeln!(
            main,
            "    ! {} targets, {} speeds, in {n} part modules {base}_1 .. {base}_{n}",
            moves.len(),
            speed_names.len()
        );
        w.shared_declarations(&mut main, job_id);
        let _ = writeln!(main);
        let _ = writeln!(main, "    PROC main()");
        w.main_start(&mut main);
        for i in 1..=n {
            let _ = writeln!(main, "        {base}_{i}_run;");
        }
        let _ = writeln!(main, "    ENDPROC");
        let _ = writeln!(main, "ENDMODULE");
        files.push(ProgramFile {
            name: format!("{base}.{ext}"),
            text: main,
        });
        for (i, range) in parts.iter().enumerate() {
            let i = i + 1;
            let mut text = String::new();
            let _ = writeln!(text, "MODULE {base}_{i}");
            let _ = writeln!(text, "    {header}");
            let _ = writeln!(
                text,
                "    ! part {i} of {n}: targets p{} .. p{}",
                range.start + 1,
                range.end
            );
            w.part_declarations(&mut text, range.clone());
            let _ = writeln!(text);
            let _ = writeln!(text, "    PROC {base}_{i}_run()");
            w.part_moves(&mut text, range.clone());
            let _ = writeln!(text, "    ENDPROC");
            let _ = writeln!(text, "ENDMODULE");
            files.push(ProgramFile {
                name: format!("{base}_{i}.{ext}"),
                text,
            });
        }
    }
    let modules: Vec<String> = files.iter().map(|f| f.name.clone()).collect();
    files.push(ProgramFile {
        name: format!("{base}.pgf"),
        text: pgf(r.robotware, &modules),
    });
    Ok(files)
}

/// The program file listing `modules` in order.
///
/// Both generations use the same `<Program>` element with one `<Module>` line per file, main
/// module first. What differs is the modules' encoding, and so their extension and the
/// declared encoding: RobotWare 6 (IRC5) reads modules as ISO-8859-1, and RobotStudio writes
/// an RW6 `.pgf` as `<?xml version="1.0" encoding="ISO-8859-1" ?>`; RobotWare 7 (OmniCore)
/// keeps UTF-8 modules under the extension `.modx`, so the RW7 variant lists `.modx` files and
/// declares UTF-8, which every XML parser must accept. (Sources: ABB's RobotWare 7 RAPID
/// documentation on `.modx` UTF-8 modules, and the `.mod`/`.modx` split of the open-source
/// Robots post-processor for IRC5 and OmniCore.) Module names are identifiers, so nothing
/// needs XML escaping, and every file the emitter writes is ASCII, so the two encodings agree
/// byte for byte.
pub fn pgf(robotware: RobotWare, modules: &[String]) -> String {
    let encoding = match robotware {
        RobotWare::Rw6 => "ISO-8859-1",
        RobotWare::Rw7 => "UTF-8",
    };
    let mut out = format!("<?xml version=\"1.0\" encoding=\"{encoding}\" ?>\n<Program>\n");
    for m in modules {
        let _ = writeln!(out, "    <Module>{m}</Module>");
    }
    out.push_str("</Program>\n");
    out
}

struct Writer<'a> {
    r: &'a RapidSettings,
    moves: &'a [Move],
    speed_names: &'a HashMap<&'a str, String>,
    weld_names: &'a HashMap<&'a weld::Bead, String>,
}

impl Writer<'_> {
    /// The job string, tool, work object and zone (main module; global except `jobName`).
    fn shared_declarations(&self, out: &mut String, job_id: &str) {
        let r = self.r;
        let _ = writeln!(
            out,
            "    LOCAL CONST string jobName := \"{}\";",
            string_literal(job_id)
        );
        if let Some(t) = &r.tool.value {
            let q = normalised(t.tcp_quat);
            let _ = writeln!(
                out,
                "    PERS tooldata {} := [{},[{},{}],[{},{},[1,0,0,0],0,0,0]];",
                r.tool.name,
                boolean(t.robhold),
                vector(&t.tcp_mm, POSITION_DECIMALS),
                vector(&q, QUATERNION_DECIMALS),
                num(t.mass_kg, POSITION_DECIMALS),
                vector(&t.cog_mm, POSITION_DECIMALS),
            );
        }
        if let Some(w) = &r.wobj.value {
            let _ = writeln!(
                out,
                "    PERS wobjdata {} := [{},{},\"{}\",[{},{}],[{},{}]];",
                r.wobj.name,
                boolean(w.robhold),
                boolean(w.ufmec.is_none()),
                // An identifier (checked by the profile), so nothing to escape.
                w.ufmec.as_deref().unwrap_or(""),
                vector(&w.uframe_mm, POSITION_DECIMALS),
                vector(&normalised(w.uframe_quat), QUATERNION_DECIMALS),
                vector(&w.oframe_mm, POSITION_DECIMALS),
                vector(&normalised(w.oframe_quat), QUATERNION_DECIMALS),
            );
        }
        if let Some(z) = &r.zone.value {
            let _ = writeln!(
                out,
                "    CONST zonedata {} := [FALSE,{}];",
                r.zone.name,
                z.components()
                    .iter()
                    .map(|v| num(*v, POSITION_DECIMALS))
                    .collect::<Vec<_>>()
                    .join(",")
            );
        }
    }

    /// The speeddata and robtargets the moves in `range` use (LOCAL to their module).
    fn part_declarations(&self, out: &mut String, range: std::ops::Range<usize>) {
        let mut declared: Vec<&str> = Vec::new();
        let mut speeds: Vec<(&str, &str)> = Vec::new();
        for m in &self.moves[range.clone()] {
            if !declared.contains(&m.speed.as_str()) {
                declared.push(&m.speed);
                speeds.push((&m.speed, self.speed_name(&m.speed)));
            }
        }
        speeds.sort_by_key(|(_, name)| name[3..].parse::<usize>().unwrap_or(usize::MAX));
        for (speed, name) in speeds {
            let _ = writeln!(
                out,
                "    LOCAL CONST speeddata {name} := [{speed},{},{EXTERNAL_AXIS_SPEEDS}];",
                num(self.r.orientation_speed_deg_s, 1)
            );
        }
        self.weld_declarations(out, range.clone());
        for i in range {
            let m = &self.moves[i];
            let [cf1, cf4, cf6, cfx] = m.robconf.unwrap_or(self.r.robconf);
            let _ = writeln!(
                out,
                "    LOCAL CONST robtarget p{} := [{},{},[{cf1},{cf4},{cf6},{cfx}],{NO_EXTERNAL_AXES}];",
                i + 1,
                vector(&m.position, POSITION_DECIMALS),
                vector(&m.quat, QUATERNION_DECIMALS),
            );
        }
    }

    /// With `data: program`: the seamdata and the welddata the moves in `range` weld with
    /// (`LOCAL PERS`, [`weld`]), welddata in the order of their numbers.
    fn weld_declarations(&self, out: &mut String, range: std::ops::Range<usize>) {
        let WeldMode::Arc {
            data: WeldDataSource::Program,
            seam,
            arc: Some(arc),
            seam_value,
            ..
        } = &self.r.weld
        else {
            return;
        };
        let mut used: Vec<(&weld::Bead, &str)> = Vec::new();
        for b in self.moves[range].iter().filter_map(|m| m.bead.as_ref()) {
            if !used.iter().any(|(u, _)| *u == b) {
                used.push((b, self.weld_names.get(b).map_or("", String::as_str)));
            }
        }
        if used.is_empty() {
            return;
        }
        let _ = writeln!(
            out,
            "    LOCAL PERS seamdata {seam} := {};",
            weld::seamdata(&seam_value.clone().unwrap_or_default())
        );
        let number = |name: &str| {
            name.trim_start_matches(|c: char| !c.is_ascii_digit())
                .parse::<usize>()
                .unwrap_or(usize::MAX)
        };
        used.sort_by_key(|(_, name)| number(name));
        for (bead, name) in used {
            let _ = writeln!(
                out,
                "    LOCAL PERS welddata {name} := {};",
                weld::welddata(bead, arc)
            );
        }
    }

    /// The first statements of `main`.
    fn main_start(&self, out: &mut String) {
        let _ = writeln!(out, "        TPWrite jobName;");
        // Computed configurations are enforced (`reach`); fixed ones are a hint.
        if self.moves.iter().any(|m| m.robconf.is_some()) {
            let _ = writeln!(out, "        ConfL \\On;");
        } else if self.r.confl_off {
            let _ = writeln!(out, "        ConfL \\Off;");
        }
        if let WeldMode::DigitalOutput { signal } = &self.r.weld {
            let _ = writeln!(out, "        SetDO {signal}, 0;");
        }
    }

    fn speed_name(&self, speed: &str) -> &str {
        self.speed_names.get(speed).map_or("v100", String::as_str)
    }

    /// One move instruction per point in `range` (plus `SetDO` in digital-output mode).
    fn part_moves(&self, out: &mut String, range: std::ops::Range<usize>) {
        let r = self.r;
        let tool = format!("{}\\WObj:={}", r.tool.name, r.wobj.name);
        let last = self.moves.len().saturating_sub(1);
        for i in range {
            let m = &self.moves[i];
            let target = format!("p{}", i + 1);
            let speed = self.speed_name(&m.speed);
            let zone = if m.run_start || m.run_end || i == last {
                "fine"
            } else {
                r.zone.name.as_str()
            };
            match (&r.weld, m.welded) {
                (WeldMode::Arc { seam, weld, .. }, true) => {
                    let weld = m
                        .bead
                        .as_ref()
                        .and_then(|b| self.weld_names.get(b))
                        .unwrap_or(weld);
                    let instruction = if m.run_start {
                        "ArcLStart"
                    } else if m.run_end {
                        "ArcLEnd"
                    } else {
                        "ArcL"
                    };
                    let _ = writeln!(
                        out,
                        "        {instruction} {target}, {speed}, {seam}, {weld}, {zone}, {tool};"
                    );
                }
                (WeldMode::DigitalOutput { signal }, true) => {
                    let _ = writeln!(out, "        MoveL {target}, {speed}, {zone}, {tool};");
                    if m.run_start {
                        let _ = writeln!(out, "        SetDO {signal}, 1;");
                    }
                    if m.run_end {
                        let _ = writeln!(out, "        SetDO {signal}, 0;");
                    }
                }
                (_, false) => {
                    let _ = writeln!(out, "        MoveL {target}, {speed}, {zone}, {tool};");
                }
            }
        }
    }
}

/// Checks every segment and flattens it into moves.
fn moves(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    r: &RapidSettings,
) -> Result<Vec<Move>, EmitError> {
    let mut out: Vec<Move> = Vec::new();
    // (segment, point) of each move, for the weld-run check.
    let mut at: Vec<(usize, usize)> = Vec::new();
    let default_quat = canonical(normalised(r.default_orientation));
    let program_weld_data = matches!(
        r.weld,
        WeldMode::Arc {
            data: WeldDataSource::Program,
            ..
        }
    );
    for (si, seg) in toolpath.segments.iter().enumerate() {
        crate::check_lengths(seg, si, true)?;
        let welded = seg.kind != ToolpathSegment::KIND_TRAVEL;
        for (pi, p) in seg.points.iter().enumerate() {
            let feed = f64::from(seg.feed_mm_s[pi]);
            let power = seg.power.get(pi).map_or(0.0, |&v| f64::from(v));
            let normal = seg.normals.get(pi).map(|v| [v.x, v.y, v.z]);
            let [nx, ny, nz] = normal.unwrap_or([0.0, 0.0, 1.0]);
            for (what, v) in [
                ("x", p.x),
                ("y", p.y),
                ("z", p.z),
                ("normal x", nx),
                ("normal y", ny),
                ("normal z", nz),
                ("feed", feed),
                ("power", power),
            ] {
                if !v.is_finite() {
                    return Err(EmitError::NonFinite {
                        segment: si,
                        point: pi,
                        what,
                    });
                }
            }
            if let Some(s) = seg.secondary_points.get(pi) {
                if (s.x, s.y, s.z) != (p.x, p.y, p.z) {
                    return Err(EmitError::NoAxis {
                        profile: profile.name.clone(),
                        what: "secondary points (a robot has one tool centre point)",
                    });
                }
            }
            if feed <= 0.0 {
                return Err(EmitError::Feed {
                    segment: si,
                    point: pi,
                    feed_mm_s: seg.feed_mm_s[pi],
                });
            }
            let speed_mm_s = match r.travel_speed_mm_s {
                Some(v) if !welded => v,
                _ => feed,
            };
            if speed_mm_s > profile.max_feed_mm_s {
                return Err(EmitError::FeedLimit {
                    segment: si,
                    point: pi,
                    feed_mm_s: speed_mm_s,
                    max_feed_mm_s: profile.max_feed_mm_s,
                });
            }
            let speed = num(speed_mm_s, r.speed_decimals);
            if speed == "0" {
                return Err(EmitError::Feed {
                    segment: si,
                    point: pi,
                    feed_mm_s: seg.feed_mm_s[pi],
                });
            }
            let quat = match normal {
                Some(n) => orientation_from_normal(n).ok_or(EmitError::Normal {
                    segment: si,
                    point: pi,
                })?,
                None => default_quat,
            };
            profile
                .check_position(&[('X', p.x), ('Y', p.y), ('Z', p.z)])
                .map_err(|violation| EmitError::Envelope {
                    segment: si,
                    point: pi,
                    violation,
                })?;
            let bead = if welded && program_weld_data {
                Some(weld::Bead {
                    speed: speed.clone(),
                    wire_feed: wire_feed(toolpath, si, pi)?,
                })
            } else {
                None
            };
            out.push(Move {
                position: [p.x, p.y, p.z],
                quat,
                speed,
                welded,
                run_start: false,
                run_end: false,
                bead,
                robconf: None,
            });
            at.push((si, pi));
        }
    }
    // A move to where the robot already is (same position and orientation) is dropped: a
    // travel point on a weld start (the weld start moves there) or on a weld end, or a
    // repeated point inside a run or a travel.
    let mut keep = vec![true; out.len()];
    for i in 0..out.len().saturating_sub(1) {
        let (a, b) = (&out[i], &out[i + 1]);
        let same = a.position == b.position && a.quat == b.quat;
        if same && a.welded && !b.welded {
            keep[i + 1] = false; // a travel starting where the weld ended
        } else if same {
            keep[i] = false;
        }
    }
    // A travel whose every point was dropped (a two-point travel from a weld end straight to
    // the next weld start) still switches the process off: the kept move after it starts a
    // new run, approached at that travel's speed.
    let mut travel_before: Vec<Option<String>> = Vec::with_capacity(out.len());
    let mut dropped_travel: Option<String> = None;
    for (m, &kept) in out.iter().zip(&keep) {
        if kept {
            travel_before.push(dropped_travel.take());
        } else if !m.welded {
            dropped_travel = Some(m.speed.clone());
        }
    }
    let mut flags = keep.iter();
    out.retain(|_| *flags.next().unwrap_or(&true));
    let mut flags = keep.iter();
    at.retain(|_| *flags.next().unwrap_or(&true));
    let len = out.len();
    for i in 0..len {
        if !out[i].welded {
            continue;
        }
        let start = i == 0 || !out[i - 1].welded || travel_before[i].is_some();
        let end = i + 1 == len || !out[i + 1].welded || travel_before[i + 1].is_some();
        if start && end {
            let (segment, point) = at[i];
            return Err(EmitError::ShortRun { segment, point });
        }
        out[i].run_start = start;
        out[i].run_end = end;
        if start {
            // The arc starts at the run's first point with the run's first bead.
            out[i].bead = out[i + 1].bead.clone();
        }
        if let Some(speed) = travel_before[i].take() {
            out[i].speed = speed;
        } else if start && i > 0 {
            // The move to a weld start is the approach, before the process starts: it runs at
            // the travel speed it comes from, not the bead speed.
            out[i].speed = out[i - 1].speed.clone();
        }
    }
    reach::assign_robconf(&mut out, &at, toolpath, profile)?;
    Ok(out)
}

/// The wire feed (m/min, as written) of point `pi` of segment `si`, for program-side
/// welddata: the toolpath must carry it as its power ([`Toolpath::POWER_WIRE_FEED_M_MIN`],
/// what `cell_waam::to_msg` writes), > 0 on every welded point.
fn wire_feed(toolpath: &Toolpath, si: usize, pi: usize) -> Result<String, EmitError> {
    let at = |reason: String| EmitError::WeldData {
        segment: si,
        point: pi,
        reason,
    };
    if toolpath.power_unit != Toolpath::POWER_WIRE_FEED_M_MIN {
        return Err(at(format!(
            "the program declares its welddata (rapid.weld.data: program) and needs the wire feed, but the toolpath's power_unit is {} (not POWER_WIRE_FEED_M_MIN = {}); plan it with the WAAM slicer or use data: controller",
            toolpath.power_unit,
            Toolpath::POWER_WIRE_FEED_M_MIN
        )));
    }
    let v = toolpath.segments[si].power.get(pi).copied();
    let text = v.map(|v| num(f64::from(v), weld::WIRE_FEED_DECIMALS));
    match (v, text) {
        (Some(v), Some(text)) if v > 0.0 && text != "0" => Ok(text),
        (v, _) => Err(at(format!(
            "wire feed {} m/min on a weld point; it must be > 0",
            v.map_or("missing".to_string(), |v| v.to_string())
        ))),
    }
}

/// The tool orientation for a toolpath normal `n`, as a RAPID quaternion [q1, q2, q3, q4] =
/// [w, x, y, z], unit length, q1 ≥ 0 (for q1 = 0 the first non-zero component is positive).
///
/// The tool frame, in the work object frame: z_t = −n/‖n‖ (the tool points against the
/// normal, into the surface); x_t = the projection of +X onto the plane normal to z_t,
/// normalised (the tool x-axis as close as possible to +X); y_t = z_t × x_t. Degenerate
/// case: when z_t is within 1e-9 of ±X, +Y is projected instead. The quaternion is that of
/// the rotation whose columns are (x_t, y_t, z_t). n = (0, 0, 1) gives [0, 1, 0, 0] (a half
/// turn about X: tool z down, tool x along +X).
///
/// `None` for a normal that is not finite or shorter than 1e-9.
pub fn orientation_from_normal(n: [f64; 3]) -> Option<[f64; 4]> {
    let n = Vector3::from(n);
    let norm = n.norm();
    if !(norm.is_finite() && norm > 1e-9) {
        return None;
    }
    let z = -n / norm;
    let reference = if Vector3::x().cross(&z).norm() > 1e-9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let x = (reference - z * reference.dot(&z)).normalize();
    let y = z.cross(&x);
    let rotation = Rotation3::from_basis_unchecked(&[x, y, z]);
    let q = UnitQuaternion::from_rotation_matrix(&rotation);
    Some(canonical([q.w, q.i, q.j, q.k]))
}

/// `q` or `−q` (the same rotation), whichever has q1 > 0 or, for q1 = 0, its first non-zero
/// component > 0.
fn canonical(q: [f64; 4]) -> [f64; 4] {
    let first = q.iter().copied().find(|v| *v != 0.0).unwrap_or(1.0);
    if first < 0.0 {
        q.map(|v| -v)
    } else {
        q
    }
}

fn normalised(q: [f64; 4]) -> [f64; 4] {
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if norm > 0.0 && norm.is_finite() {
        q.map(|v| v / norm)
    } else {
        [1.0, 0.0, 0.0, 0.0]
    }
}

/// Part ranges of at most `limit` moves (module docs, splitting); one range if all fit.
fn split(moves: &[Move], limit: usize) -> Vec<std::ops::Range<usize>> {
    let limit = limit.max(1);
    let mut parts = Vec::new();
    let mut start = 0;
    let mut block_start = 0;
    for (i, m) in moves.iter().enumerate() {
        // A block is one travel move or one whole weld run.
        let block_ends = !m.welded || m.run_end;
        if !block_ends {
            continue;
        }
        let block_end = i + 1;
        // Break before a block that would not fit, unless it is too long for any module.
        if block_end - start > limit && block_start > start && block_end - block_start <= limit {
            parts.push(start..block_start);
            start = block_start;
        }
        while block_end - start > limit {
            parts.push(start..start + limit);
            start += limit;
        }
        block_start = block_end;
    }
    if start < moves.len() || parts.is_empty() {
        parts.push(start..moves.len());
    }
    parts
}

/// The base of the module names: prefix + job id reduced to letters, digits and `_`, a
/// letter first (`J` put in front otherwise), at most 22 characters; `J_` in front if it
/// clashes (any case) with a reserved word, a generated name or a profile name.
fn base_name(r: &RapidSettings, job_id: &str) -> Result<String, EmitError> {
    let job: String = job_id
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let job = if job.trim_matches('_').is_empty() {
        "job".to_string()
    } else {
        job
    };
    let mut base = format!("{}{job}", r.module_prefix);
    if !base.starts_with(|c: char| c.is_ascii_alphabetic()) {
        base.insert(0, 'J');
    }
    base.truncate(MAX_BASE_LEN);
    let mut profile_names = vec![
        r.tool.name.as_str(),
        r.wobj.name.as_str(),
        r.zone.name.as_str(),
    ];
    let mut welddata_prefix = None;
    match &r.weld {
        WeldMode::Arc {
            seam, weld, data, ..
        } => {
            profile_names.extend([seam.as_str(), weld.as_str()]);
            if *data == WeldDataSource::Program {
                welddata_prefix = Some(weld.as_str());
            }
        }
        WeldMode::DigitalOutput { signal } => profile_names.push(signal),
    }
    // A module or procedure name of this base (`b`, `b_N`, `b_N_run`) that has the form of a
    // declared welddata name (prefix + digits).
    let is_welddata = |b: &str| {
        welddata_prefix.is_some_and(|w| {
            is_welddata_name(w, b)
                || (w.len() > b.len()
                    && w.is_char_boundary(b.len())
                    && w[..b.len()].eq_ignore_ascii_case(b)
                    && w[b.len()..].starts_with('_')
                    && w[b.len() + 1..].chars().all(|c| c.is_ascii_digit()))
        })
    };
    let clashes = |b: &str| {
        RESERVED_WORDS.contains(&b.to_ascii_uppercase().as_str())
            || is_generated_name(b)
            || is_welddata(b)
            || profile_names.iter().any(|n| n.eq_ignore_ascii_case(b))
            // A part module or procedure name of this base would equal a profile name.
            || profile_names.iter().any(|n| {
                n.len() > b.len()
                    && n[..b.len()].eq_ignore_ascii_case(b)
                    && n.as_bytes()[b.len()] == b'_'
            })
    };
    if clashes(&base) {
        base.insert_str(0, "J_");
        base.truncate(MAX_BASE_LEN);
    }
    if clashes(&base) {
        return Err(EmitError::Identifier {
            name: base,
            reason: "clashes with a name of the profile".into(),
        });
    }
    check_identifier(&base).map_err(|reason| EmitError::Identifier {
        name: base.clone(),
        reason,
    })?;
    debug_assert!(base.len() + "_99999_run".len() <= MAX_IDENTIFIER_LEN);
    Ok(base)
}

/// The inside of a RAPID string literal holding `text`: at most 80 characters of value
/// (ABB, RAPID kernel, data type `string`), `"` written `""` and `\` written `\\` (RAPID
/// kernel, "String literals"), control characters as `\hh` (two hex digits, the character
/// code) and non-ASCII characters as `?`, so the literal is one ASCII line.
pub fn string_literal(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars().take(MAX_STRING_LEN) {
        match c {
            '"' => out.push_str("\"\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_ascii_control() => {
                let _ = write!(out, "\\{:02X}", c as u32);
            }
            c if c.is_ascii() => out.push(c),
            _ => out.push('?'),
        }
    }
    out
}

/// `v` with at most `decimals` places, trailing zeros dropped, never `-0`.
fn num(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

fn vector(v: &[f64], decimals: usize) -> String {
    format!(
        "[{}]",
        v.iter()
            .map(|x| num(*x, decimals))
            .collect::<Vec<_>>()
            .join(",")
    )
}

fn boolean(b: bool) -> &'static str {
    if b {
        "TRUE"
    } else {
        "FALSE"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short_and_never_negative_zero() {
        assert_eq!(num(-0.0001, 3), "0");
        assert_eq!(num(250.0, 3), "250");
        assert_eq!(num(-1.5, 1), "-1.5");
        assert_eq!(num(0.12345678, 6), "0.123457");
    }

    #[test]
    fn string_literals_escape_quotes_backslashes_and_controls() {
        assert_eq!(string_literal(r#"a"b\c"#), r#"a""b\\c"#);
        assert_eq!(string_literal("a\nb\r"), "a\\0Ab\\0D");
        assert_eq!(string_literal("é"), "?");
        assert_eq!(string_literal(&"x".repeat(100)).len(), 80);
    }

    #[test]
    fn canonical_quaternions_have_a_non_negative_first_component() {
        assert_eq!(canonical([-0.5, 0.5, -0.5, 0.5]), [0.5, -0.5, 0.5, -0.5]);
        assert_eq!(canonical([0.0, -1.0, 0.0, 0.0]), [0.0, 1.0, 0.0, 0.0]);
    }
}
