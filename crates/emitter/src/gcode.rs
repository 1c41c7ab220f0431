//! G-code from a `Toolpath` for a profile's dialect.
//!
//! **Program layout.** A header comment; the modal line the emitter derives from the settings
//! (plane, units, absolute mode, feed mode; `M82`/`M83` for extrusion); the profile's start
//! lines; the moves; power off; `G94` after an inverse-time program; the end lines; `M2`
//! unless the end lines already end the program with M2 or M30 (not on Marlin, which has no
//! program end word).
//!
//! **Segments.** Travel segments are rapids (G0). Cut, lead and deposit segments are feed
//! moves (G1, or G2/G3 where arcs are fitted); zero-length moves, as where segments meet, are
//! dropped. Marlin has no rapid: its G0 moves at the modal feed like G1 (unless built with
//! `G0_FEEDRATE`, off in stock Marlin 2), so there every G0 carries the travel feed (the last
//! travel segment's, before any the first one's, else the profile's `max_feed_mm_s`) when it
//! differs from the modal F; without it a travel after a retract would crawl at the retract
//! feed. How power is switched depends on the profile:
//! - *continuous* (hot-wire; no `pierce`): power on with the first point's value and the
//!   pre-heat dwell before the first feed move, off after the last;
//! - *pierce* (sheet cutting): for each cut, power on, pierce dwell, cut, power off at the next
//!   travel; with pierce heights the head goes to the pierce height for the pierce, down to the
//!   cut height for the cut and up to the travel height for travel moves;
//! - *extrusion* (printing): no power words; deposit moves carry E (below), travel moves are
//!   wrapped in a retract and a Z-hop; with `z_hop_only_when_crossing` the Z-hop only where
//!   the travel crosses a deposit already made in its layer (the segments' `layer`;
//!   `cell_geometry::travel_crosses_polylines`, the rule `cell_wing::layers::moves` plans by).
//!
//! **Feeds.** G94: F = feed × 60 (mm/min), written when it changes. G93 (inverse time):
//! F = 1 / duration in minutes on every feed move, with the duration max(‖ΔXY‖, ‖ΔUV‖) / feed:
//! the `Toolpath` feed of a 4-axis hot-wire point is the speed of the carriage that moves
//! farther, so both carriages finish the move together.
//!
//! **Power.** `S` = power × `s_per_unit`, written on the power-on line and again on any move
//! whose rounded value differs from the last one written.
//!
//! **Extrusion.** A deposit move's `power` is the volumetric flow q (mm³/s), so it pushes
//! E = q · (length / feed) / (π d² / 4) of filament of diameter d: absolute (M82, running
//! total) or relative (M83).
//!
//! **Arcs.** With `arc_tolerance_mm`, runs of feed moves with one feed, power and height that
//! lie on a circle are written as G2/G3 with incremental I, J ([`crate::arcs`]).
//!
//! **Axes.** Primary x, y (and z where the profile maps it) and secondary x, y as the profile's
//! u, v letters (`U V` or `A B`). A toolpath without secondary points on a 4-axis profile is a
//! straight cut: both carriages follow the primary points. Secondary points on a profile
//! without u, v are accepted only when they equal the primary ones. With `units: inch` every
//! length is divided by 25.4.
//!
//! **Cutter compensation.** With `cutting.compensation: controller` (LinuxCNC), a sheet-cutting
//! program selects tool 1 (`T1 M6`, its diameter the kerf) after the start lines, switches
//! `G41`/`G42` on at each contour's entry move and `G40` after its lead-out
//! ([`crate::compensation`]).
//!
//! **User text** (the job id) goes only into comments and `{job}` template placeholders,
//! reduced to a safe character set, so no text can close a comment and inject a command.
//!
//! **Line length.** GRBL buffers at most 80 characters of a line and Marlin 96; lines longer
//! than the dialect's limit are an error (the header comment is shortened to fit).

use std::fmt::Write as _;

use cell_msgs::{Toolpath, ToolpathSegment};
use cell_profiles::{Dialect, ExtrusionMode, FeedMode, GcodeSettings, MachineProfile, Units};
use nalgebra::Vector2;

use crate::arcs::{self, Primitive};
use crate::compensation::{self, Compensator};
use crate::{EmitError, EmitOptions};

/// One checked point of the program.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pose {
    primary: [f64; 3],
    secondary: [f64; 2],
    feed_mm_s: f64,
    power: f64,
    kind: u8,
    segment: usize,
    point: usize,
    layer: u32,
}

impl Pose {
    fn xy(&self) -> Vector2<f64> {
        Vector2::new(self.primary[0], self.primary[1])
    }
}

/// The longest line each dialect's controller accepts (characters, without the newline):
/// GRBL's 80-byte line buffer (`LINE_BUFFER_SIZE`, its terminator included), Marlin's
/// `MAX_CMD_SIZE` 96, LinuxCNC's `LINELEN` 255; Mach3 is given LinuxCNC's.
pub fn max_line_length(dialect: Dialect) -> usize {
    match dialect {
        Dialect::Grbl => 79,
        Dialect::Marlin => 95,
        Dialect::Linuxcnc | Dialect::Mach3 => 255,
    }
}

/// Filament the deposit moves of an extrusion program push, mm: the E of every `G` line that
/// also names X or Y, in the mode the program sets (`M82` absolute, the default, or `M83`
/// relative). E-only lines (retract and prime) move filament without depositing and are left
/// out; `G92 E…` sets the absolute origin; an E word that is not a number counts as 0. For
/// checks and reports of programs this module writes (seed 002: E = deposited volume /
/// filament cross-section).
pub fn extruded_length_mm(program: &str) -> f64 {
    let (mut total, mut at, mut relative) = (0.0, 0.0, false);
    for line in program.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first().copied() {
            Some("M82") => relative = false,
            Some("M83") => relative = true,
            Some(g) if g.starts_with('G') => {
                let Some(e) = words.iter().find_map(|w| w.strip_prefix('E')) else {
                    continue;
                };
                let e: f64 = e.parse().unwrap_or(0.0);
                if g == "G92" {
                    at = e;
                    continue;
                }
                let moves = words
                    .iter()
                    .any(|w| w.starts_with('X') || w.starts_with('Y'));
                let pushed = if relative { e } else { e - at };
                if moves {
                    total += pushed;
                }
                if !relative {
                    at = e;
                }
            }
            _ => {}
        }
    }
    total
}

/// The G-code program for `toolpath` on `profile` (module docs). `job_id` goes into the header
/// comment, sanitised. As [`emit_with`] with the default options.
///
/// # Errors
/// A profile without a `gcode` section; a non-finite value, a feed ≤ 0 or a per-point array of
/// the wrong length (naming segment and point); an axis the profile does not map; a position
/// outside the machine's travel; a line longer than the dialect allows; with controller
/// compensation, no kerf for the material or a contour without an entry move.
pub fn emit(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    job_id: &str,
) -> Result<String, EmitError> {
    emit_with(toolpath, profile, job_id, &EmitOptions::default())
}

/// As [`emit`], with the job's `options` (the material, for controller compensation's kerf).
///
/// # Errors
/// As [`emit`].
pub fn emit_with(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    job_id: &str,
    options: &EmitOptions,
) -> Result<String, EmitError> {
    let g = profile
        .gcode
        .as_ref()
        .ok_or_else(|| EmitError::MissingSection {
            profile: profile.name.clone(),
            section: "gcode",
        })?;
    let poses = poses(toolpath, profile, g)?;
    let kerf_mm = compensation::controller_kerf_mm(toolpath, profile, options)?;
    let mut w = Writer::new(profile, g);
    if let Some(first_travel) = poses
        .iter()
        .find(|p| p.kind == ToolpathSegment::KIND_TRAVEL)
    {
        w.travel_feed_mm_s = first_travel.feed_mm_s;
    }
    w.start(job_id);
    if let Some(kerf) = kerf_mm {
        w.select_kerf_tool(kerf);
        w.comp = Some(Compensator::new(toolpath, kerf));
    }
    for run in poses.chunk_by(|a, b| a.segment == b.segment) {
        let segment = run[0].segment;
        if let Some(g40) = w.comp.as_mut().and_then(|c| c.before(segment)) {
            w.push(g40.into());
        }
        match run[0].kind {
            ToolpathSegment::KIND_TRAVEL => w.travel(run)?,
            ToolpathSegment::KIND_DEPOSIT if g.extrusion.is_some() => w.deposit(run)?,
            _ => w.powered(run)?,
        }
        if let Some(c) = w.comp.as_mut() {
            c.after(segment, &mut w.lines)?;
        }
    }
    w.finish(job_id)
}

/// Checks every segment and flattens it into poses.
fn poses(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    g: &GcodeSettings,
) -> Result<Vec<Pose>, EmitError> {
    let w = &g.axis_words;
    let mut out = Vec::new();
    for (si, seg) in toolpath.segments.iter().enumerate() {
        crate::check_lengths(seg, si, false)?;
        for (pi, p) in seg.points.iter().enumerate() {
            let s = seg.secondary_points.get(pi).copied().unwrap_or(*p);
            let feed = f64::from(seg.feed_mm_s[pi]);
            let power = seg.power.get(pi).map_or(0.0, |&v| f64::from(v));
            for (what, v) in [
                ("x", p.x),
                ("y", p.y),
                ("z", p.z),
                ("secondary x", s.x),
                ("secondary y", s.y),
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
            if feed <= 0.0 {
                return Err(EmitError::Feed {
                    segment: si,
                    point: pi,
                    feed_mm_s: seg.feed_mm_s[pi],
                });
            }
            if power < 0.0 {
                return Err(EmitError::Power {
                    segment: si,
                    point: pi,
                    power: seg.power[pi],
                });
            }
            if w.u.is_none() && (s.x != p.x || s.y != p.y) {
                return Err(EmitError::NoAxis {
                    profile: profile.name.clone(),
                    what: "the secondary (UV) carriage",
                });
            }
            out.push(Pose {
                primary: [p.x, p.y, p.z],
                secondary: [s.x, s.y],
                feed_mm_s: feed,
                power,
                kind: seg.kind,
                segment: si,
                point: pi,
                layer: seg.layer,
            });
        }
    }
    Ok(out)
}

/// How a move writes the z axis word.
#[derive(Debug, Clone, Copy, PartialEq)]
enum ZWord {
    /// The pose's own z (if the profile maps z).
    Pose,
    /// The pose's z plus a lift (extrusion Z-hop).
    Lifted(f64),
    /// Not written (pierce heights own the z axis; XY moves leave it).
    Omit,
}

/// The program being written, with the modal state it has set so far.
struct Writer<'a> {
    profile: &'a MachineProfile,
    g: &'a GcodeSettings,
    lines: Vec<String>,
    /// Where the last move ended, and the coordinate words written for it.
    at: Option<(Pose, String)>,
    power_on: bool,
    last_s: Option<String>,
    last_f: Option<String>,
    /// Extruder: running E position (absolute mode), and whether the filament is pulled back.
    e_position: f64,
    retracted: bool,
    /// Extrusion Z-hop in force (the nozzle is lifted by this much).
    lift: Option<f64>,
    /// Extrusion: the layer of the last deposit and the XY centre lines of its deposits so far
    /// (for `z_hop_only_when_crossing`).
    walls: (Option<u32>, Vec<Vec<[f64; 2]>>),
    /// Controller cutter compensation, when the profile asks for it.
    comp: Option<Compensator>,
    /// The feed G0 moves run at where G0 is not a rapid (Marlin) \[mm/s\].
    travel_feed_mm_s: f64,
}

impl<'a> Writer<'a> {
    fn new(profile: &'a MachineProfile, g: &'a GcodeSettings) -> Self {
        Self {
            profile,
            g,
            lines: Vec::new(),
            at: None,
            power_on: false,
            last_s: None,
            last_f: None,
            e_position: 0.0,
            retracted: false,
            lift: None,
            walls: (None, Vec::new()),
            comp: None,
            travel_feed_mm_s: profile.max_feed_mm_s,
        }
    }

    /// `G0 words`, with the travel feed on Marlin (see the module doc).
    fn rapid_line(&mut self, words: &str) -> String {
        if self.g.dialect != Dialect::Marlin {
            return format!("G0 {words}");
        }
        let f = number(self.len(self.travel_feed_mm_s * 60.0), 3);
        if self.last_f.as_ref() == Some(&f) {
            format!("G0 {words}")
        } else {
            self.last_f = Some(f.clone());
            format!("G0 {words} F{f}")
        }
    }

    /// Controller compensation: tool 1, whose diameter is the kerf (the tool table beside the
    /// program), selected before the first move.
    fn select_kerf_tool(&mut self, kerf_mm: f64) {
        let unit = match self.g.units {
            Units::Mm => "mm",
            Units::Inch => "inch",
        };
        let note = self.comment(&format!(
            "cutter compensation: G41/G42 with tool {}, diameter {} {unit} = the kerf, in {}",
            compensation::TOOL,
            self.coord(kerf_mm),
            compensation::TOOL_TABLE_FILE
        ));
        self.push(note);
        self.push(format!("T{} M6", compensation::TOOL));
    }

    /// Controller compensation: `G40` at the end of a contour.
    fn compensation_off(&mut self) {
        if let Some(g40) = self.comp.as_mut().and_then(Compensator::off) {
            self.push(g40.into());
        }
    }

    fn push(&mut self, line: String) {
        self.lines.push(line);
    }

    fn comment(&self, text: &str) -> String {
        // Shortened so the line fits the dialect's limit.
        let room = max_line_length(self.g.dialect) - 2;
        let text: String = text.chars().take(room).collect();
        match self.g.dialect {
            Dialect::Marlin => format!("; {text}"),
            _ => format!("({text})"),
        }
    }

    /// Pierce heights (pierce, cut, travel), when the profile sets them.
    fn heights(&self) -> Option<(f64, f64, f64)> {
        let p = self.g.pierce.as_ref()?;
        Some((p.z_pierce_mm?, p.z_cut_mm?, p.z_travel_mm?))
    }

    fn default_z(&self) -> ZWord {
        if self.heights().is_some() {
            ZWord::Omit
        } else if let Some(hop) = self.lift {
            ZWord::Lifted(hop)
        } else {
            ZWord::Pose
        }
    }

    /// A length in program units.
    fn len(&self, mm: f64) -> f64 {
        match self.g.units {
            Units::Mm => mm,
            Units::Inch => mm / 25.4,
        }
    }

    fn coord(&self, mm: f64) -> String {
        number(self.len(mm), self.g.decimals)
    }

    /// The axis words of `p`, after checking them against the travel.
    fn words(&self, p: &Pose, z: ZWord) -> Result<String, EmitError> {
        let w = &self.g.axis_words;
        let mut values = vec![(w.x, p.primary[0]), (w.y, p.primary[1])];
        if let Some(letter) = w.z {
            match z {
                ZWord::Pose => values.push((letter, p.primary[2])),
                ZWord::Lifted(hop) => values.push((letter, p.primary[2] + hop)),
                ZWord::Omit => {}
            }
        }
        if let (Some(u), Some(v)) = (w.u, w.v) {
            values.push((u, p.secondary[0]));
            values.push((v, p.secondary[1]));
        }
        self.profile
            .check_position(&values)
            .map_err(|violation| EmitError::Envelope {
                segment: p.segment,
                point: p.point,
                violation,
            })?;
        Ok(values
            .iter()
            .map(|(letter, v)| format!("{letter}{}", self.coord(*v)))
            .collect::<Vec<_>>()
            .join(" "))
    }

    fn start(&mut self, job_id: &str) {
        let header = self.comment(&format!(
            "cellsuite emitter: job {}, profile {}",
            sanitise(job_id),
            sanitise(&self.profile.name)
        ));
        self.push(header);
        self.push(modal_line(self.g));
        if let Some(e) = &self.g.extrusion {
            self.push(
                match e.mode {
                    ExtrusionMode::Absolute => "M82",
                    ExtrusionMode::Relative => "M83",
                }
                .into(),
            );
            if e.mode == ExtrusionMode::Absolute {
                self.push(format!("G92 {}0", e.axis));
            }
        }
        for line in &self.g.program_start {
            self.lines
                .push(fill_template(line, job_id, &self.profile.name));
        }
        if let (Some((_, _, travel)), Some(z)) = (self.heights(), self.g.axis_words.z) {
            let line = format!("G0 {z}{}", self.coord(travel));
            self.push(line);
        }
    }

    /// A rapid to `p` unless already there.
    fn rapid_to(&mut self, p: &Pose) -> Result<(), EmitError> {
        let words = self.words(p, self.default_z())?;
        if self.at.as_ref().is_some_and(|(_, w)| *w == words) {
            return Ok(());
        }
        let length_mm = self
            .at
            .as_ref()
            .map_or(0.0, |(from, _)| (p.xy() - from.xy()).norm());
        let line = self.rapid_line(&words);
        self.push(line);
        if let Some(c) = self.comp.as_mut() {
            c.rapid(self.lines.len() - 1, length_mm);
        }
        self.at = Some((*p, words));
        Ok(())
    }

    /// The F word for a feed move of `primary_mm` / `secondary_mm` carriage travel at `p`'s
    /// feed: `None` when G94 and unchanged.
    fn feed_word(&mut self, primary_mm: f64, secondary_mm: f64, feed_mm_s: f64) -> Option<String> {
        let word = match self.g.feed_mode {
            FeedMode::UnitsPerMinute => number(self.len(feed_mm_s * 60.0), 3),
            FeedMode::InverseTime => {
                let minutes = primary_mm.max(secondary_mm) / feed_mm_s / 60.0;
                // Enough significant digits that F × duration stays 1 to 1e-6 for short moves.
                return Some(number(1.0 / minutes, 4));
            }
        };
        if self.last_f.as_ref() == Some(&word) {
            None
        } else {
            self.last_f = Some(word.clone());
            Some(word)
        }
    }

    /// The ` S…` suffix when power is on and its rounded value changed.
    fn s_suffix(&mut self, power: f64) -> String {
        if !self.power_on || self.g.power.is_none() {
            return String::new();
        }
        let s = s_value(self.g, power);
        if self.last_s.as_ref() == Some(&s) {
            String::new()
        } else {
            self.last_s = Some(s.clone());
            format!(" S{s}")
        }
    }

    /// The ` E…` suffix of a deposit move of `length_mm` at `p`.
    fn e_suffix(&mut self, p: &Pose, length_mm: f64, extrude: bool) -> String {
        let Some(e) = self.g.extrusion.as_ref().filter(|_| extrude) else {
            return String::new();
        };
        let area = std::f64::consts::PI * e.filament_diameter_mm.powi(2) / 4.0;
        let filament = p.power * (length_mm / p.feed_mm_s) / area;
        let value = match e.mode {
            ExtrusionMode::Relative => filament,
            ExtrusionMode::Absolute => {
                self.e_position += filament;
                self.e_position
            }
        };
        format!(" {}{}", e.axis, number(self.len(value), 5))
    }

    /// A feed move to `p` (G1), or an arc (G2/G3) about `centre`.
    fn feed_to(
        &mut self,
        p: &Pose,
        arc: Option<(Vector2<f64>, bool)>,
        extrude: bool,
    ) -> Result<(), EmitError> {
        let words = self.words(p, self.default_z())?;
        let Some((from, from_words)) = self.at.clone() else {
            let line = self.rapid_line(&words);
            self.push(line);
            self.at = Some((*p, words));
            return Ok(());
        };
        if from_words == words {
            return Ok(());
        }
        let secondary = if self.g.axis_words.u.is_some() {
            (Vector2::from(p.secondary) - Vector2::from(from.secondary)).norm()
        } else {
            0.0
        };
        let (code, centre_words, primary) = match arc {
            None => {
                let z = if self.default_z() == ZWord::Omit {
                    0.0
                } else {
                    p.primary[2] - from.primary[2]
                };
                let d = (p.xy() - from.xy()).norm();
                ("G1", String::new(), (d * d + z * z).sqrt())
            }
            Some((centre, ccw)) => {
                // The centre as the rounded ends need it, I and J from the (rounded) start.
                let rounded = |v: Vector2<f64>| {
                    let r = |c: f64| self.len(c);
                    Vector2::new(
                        round_to(r(v.x), self.g.decimals),
                        round_to(r(v.y), self.g.decimals),
                    )
                };
                let (s, e) = (rounded(from.xy()), rounded(p.xy()));
                let c = arcs::centre_for_rounded_ends(
                    s,
                    e,
                    Vector2::new(self.len(centre.x), self.len(centre.y)),
                );
                let ij = c - s;
                let sweep = sweep(s - c, e - c, ccw);
                let length_mm = (s - c).norm() * sweep * self.len(1.0).recip();
                (
                    if ccw { "G3" } else { "G2" },
                    format!(
                        " I{} J{}",
                        number(ij.x, self.g.decimals),
                        number(ij.y, self.g.decimals)
                    ),
                    length_mm,
                )
            }
        };
        let mut line = format!("{code} {words}{centre_words}");
        if let Some(f) = self.feed_word(primary, secondary, p.feed_mm_s) {
            let _ = write!(line, " F{f}");
        }
        line += &self.s_suffix(p.power);
        line += &self.e_suffix(p, primary, extrude);
        self.push(line);
        if let Some(c) = self.comp.as_mut() {
            // An entry move qualifies by its length (a line) or its radius (an arc).
            let size_mm = arc.map_or((p.xy() - from.xy()).norm(), |(centre, _)| {
                (from.xy() - centre).norm()
            });
            c.feed(compensation::Move {
                line: self.lines.len() - 1,
                size_mm,
                arc_ccw: arc.map(|(_, ccw)| ccw),
            });
        }
        self.at = Some((*p, words));
        Ok(())
    }

    /// Feed moves through `run` (the current position first), arcs fitted where allowed.
    fn moves_through(&mut self, run: &[Pose], extrude: bool) -> Result<(), EmitError> {
        let Some(tolerance) = self.g.arc_tolerance_mm else {
            for p in run {
                self.feed_to(p, None, extrude)?;
            }
            return Ok(());
        };
        // Distinct points after the current one, grouped by what an arc must keep constant.
        let mut distinct: Vec<Pose> = Vec::new();
        let mut last = self.at.as_ref().map(|(_, w)| w.clone());
        for p in run {
            let w = self.words(p, self.default_z())?;
            if last.as_ref() != Some(&w) {
                distinct.push(*p);
                last = Some(w);
            }
        }
        let height_matters = self.default_z() != ZWord::Omit;
        for group in distinct.chunk_by(|a, b| {
            a.feed_mm_s == b.feed_mm_s
                && a.power == b.power
                && (!height_matters || a.primary[2] == b.primary[2])
        }) {
            let Some((from, _)) = self.at.clone() else {
                for p in group {
                    self.feed_to(p, None, extrude)?;
                }
                continue;
            };
            let same_height = !height_matters || from.primary[2] == group[0].primary[2];
            if !same_height {
                self.feed_to(&group[0], None, extrude)?;
            }
            let rest = if same_height { group } else { &group[1..] };
            let mut points = vec![self.at.as_ref().map_or(from.xy(), |(p, _)| p.xy())];
            points.extend(rest.iter().map(Pose::xy));
            for primitive in arcs::fit(&points, tolerance) {
                match primitive {
                    Primitive::Line { end } => self.feed_to(&rest[end - 1], None, extrude)?,
                    Primitive::Arc { end, centre, ccw } => {
                        self.feed_to(&rest[end - 1], Some((centre, ccw)), extrude)?;
                    }
                }
            }
        }
        Ok(())
    }

    fn power_on(&mut self, first: &Pose) -> Result<(), EmitError> {
        let Some(words) = self.g.power.clone() else {
            return Ok(());
        };
        let z = self.g.axis_words.z;
        let heights = self.heights();
        if let (Some((pierce, _, _)), Some(z)) = (heights, z) {
            let line = format!("G0 {z}{}", self.coord(pierce));
            self.push(line);
        }
        let s = s_value(self.g, first.power);
        self.push(format!("{} S{s}", words.on));
        self.last_s = Some(s);
        self.power_on = true;
        let dwell_s = self
            .g
            .pierce
            .as_ref()
            .map_or(self.g.preheat_dwell_s, |p| p.dwell_s);
        if dwell_s > 0.0 {
            self.push(dwell(self.g.dialect, dwell_s));
        }
        if let (Some((pierce, cut, _)), Some(z)) = (heights, z) {
            let mut line = format!("G1 {z}{}", self.coord(cut));
            if let Some(f) = self.feed_word((pierce - cut).abs(), 0.0, first.feed_mm_s) {
                let _ = write!(line, " F{f}");
            }
            self.push(line);
        }
        Ok(())
    }

    fn power_off(&mut self) {
        if !self.power_on {
            return;
        }
        if let Some(words) = &self.g.power {
            let off = words.off.clone();
            self.push(off);
        }
        self.power_on = false;
        self.last_s = None;
        if let (Some((_, _, travel)), Some(z)) = (self.heights(), self.g.axis_words.z) {
            let line = format!("G0 {z}{}", self.coord(travel));
            self.push(line);
        }
    }

    /// True if `p` is where the program already is.
    fn is_at(&self, p: &Pose) -> Result<bool, EmitError> {
        let words = self.words(p, self.default_z())?;
        Ok(self.at.as_ref().is_some_and(|(_, w)| *w == words))
    }

    fn travel(&mut self, run: &[Pose]) -> Result<(), EmitError> {
        let mut moves = false;
        for p in run {
            moves |= !self.is_at(p)?;
        }
        if !moves {
            return Ok(());
        }
        self.compensation_off();
        if self.g.pierce.is_some() {
            self.power_off();
        }
        if let Some(last) = run.last() {
            self.travel_feed_mm_s = last.feed_mm_s;
        }
        if self.at.is_some() {
            self.retract_and_lift(run)?;
        }
        for p in run {
            self.rapid_to(p)?;
        }
        Ok(())
    }

    /// Extrusion: retract and Z-hop before a travel move through `run` (once); without the
    /// lift when the profile lifts only over deposits and the move crosses none of its layer's.
    fn retract_and_lift(&mut self, run: &[Pose]) -> Result<(), EmitError> {
        let Some(e) = self.g.extrusion.clone() else {
            return Ok(());
        };
        if e.retract_mm > 0.0 && !self.retracted {
            self.filament(-e.retract_mm, e.retract_feed_mm_s);
            self.retracted = true;
        }
        if e.z_hop_only_when_crossing && !self.crosses_walls(run) {
            return Ok(());
        }
        if e.z_hop_mm > 0.0 && self.lift.is_none() {
            if let (Some(z), Some((p, _))) = (self.g.axis_words.z, self.at.clone()) {
                self.lift = Some(e.z_hop_mm);
                let words = self.words(&p, self.default_z())?;
                let hop = words
                    .split(' ')
                    .find(|w| w.starts_with(z))
                    .unwrap_or_default();
                let line = self.rapid_line(hop);
                self.push(line);
                self.at = Some((p, words));
            }
        }
        Ok(())
    }

    /// Whether the travel from the current position through `run` crosses a deposit already
    /// made in the layer of its last point.
    fn crosses_walls(&self, run: &[Pose]) -> bool {
        let (Some((from, _)), Some(to)) = (&self.at, run.last()) else {
            return false;
        };
        let (layer, walls) = &self.walls;
        if *layer != Some(to.layer) {
            return false;
        }
        let xy = |p: &Pose| [p.primary[0], p.primary[1]];
        let mut a = xy(from);
        run.iter().any(|p| {
            let b = xy(p);
            let crosses = cell_geometry::travel_crosses_polylines(a, b, walls);
            a = b;
            crosses
        })
    }

    /// Extrusion: back down and un-retract before depositing at `first`.
    fn lower_and_prime(&mut self, first: &Pose) -> Result<(), EmitError> {
        let Some(e) = self.g.extrusion.clone() else {
            return Ok(());
        };
        if self.lift.take().is_some() {
            if let (Some(z), Some((p, _))) = (self.g.axis_words.z, self.at.clone()) {
                let words = self.words(&p, ZWord::Pose)?;
                let down = format!("{z}{}", self.coord(first.primary[2]));
                let line = self.rapid_line(&down);
                self.push(line);
                self.at = Some((p, words));
            }
        }
        if self.retracted {
            self.filament(e.retract_mm, e.retract_feed_mm_s);
            self.retracted = false;
        }
        Ok(())
    }

    /// A filament-only move of `mm` (negative: retract).
    fn filament(&mut self, mm: f64, feed_mm_s: f64) {
        let Some(e) = self.g.extrusion.clone() else {
            return;
        };
        let value = match e.mode {
            ExtrusionMode::Relative => mm,
            ExtrusionMode::Absolute => {
                self.e_position += mm;
                self.e_position
            }
        };
        let f = number(self.len(feed_mm_s * 60.0), 3);
        self.last_f = Some(f.clone());
        let line = format!("G1 {}{} F{f}", e.axis, number(self.len(value), 5));
        self.push(line);
    }

    /// A cut or lead segment (or a deposit without an extruder): power on, then feed moves.
    fn powered(&mut self, run: &[Pose]) -> Result<(), EmitError> {
        let first = &run[0];
        if !self.is_at(first)? {
            if self.g.pierce.is_some() {
                self.power_off();
            }
            if self.power_on {
                // Continuous power (a hot wire): getting there cuts, so feed, don't rapid.
                self.feed_to(first, None, false)?;
            } else {
                self.retract_and_lift(&run[..1])?;
                self.rapid_to(first)?;
            }
        }
        self.lower_and_prime(first)?;
        if !self.power_on {
            self.power_on(first)?;
        }
        self.moves_through(&run[1..], false)
    }

    /// An extrusion deposit segment: into position, primed, then moves with E.
    fn deposit(&mut self, run: &[Pose]) -> Result<(), EmitError> {
        let first = &run[0];
        if !self.is_at(first)? {
            self.retract_and_lift(&run[..1])?;
            self.rapid_to(first)?;
        }
        self.lower_and_prime(first)?;
        self.moves_through(&run[1..], true)?;
        let (layer, walls) = &mut self.walls;
        if *layer != Some(first.layer) {
            *layer = Some(first.layer);
            walls.clear();
        }
        walls.push(run.iter().map(|p| [p.primary[0], p.primary[1]]).collect());
        Ok(())
    }

    fn finish(mut self, job_id: &str) -> Result<String, EmitError> {
        self.compensation_off();
        self.power_off();
        if self.g.feed_mode == FeedMode::InverseTime {
            // Leave the controller in the usual mode for whatever is run next.
            self.push("G94".into());
        }
        for line in &self.g.program_end {
            self.lines
                .push(fill_template(line, job_id, &self.profile.name));
        }
        let ends_program = |l: &String| {
            let word = l
                .split_whitespace()
                .next()
                .unwrap_or_default()
                .to_ascii_uppercase();
            ["M2", "M02", "M30"].contains(&word.as_str())
        };
        if self.g.dialect != Dialect::Marlin && !self.lines.last().is_some_and(ends_program) {
            self.push("M2".into());
        }
        let limit = max_line_length(self.g.dialect);
        if let Some((i, l)) = self.lines.iter().enumerate().find(|(_, l)| l.len() > limit) {
            return Err(EmitError::LineTooLong {
                line: i + 1,
                length: l.len(),
                limit,
            });
        }
        let mut out = String::with_capacity(self.lines.iter().map(|l| l.len() + 1).sum());
        for l in &self.lines {
            out.push_str(l);
            out.push('\n');
        }
        Ok(out)
    }
}

/// Swept angle (radians, in (0, 2π)) from `a` to `b` about the origin, counter-clockwise or
/// clockwise.
fn sweep(a: Vector2<f64>, b: Vector2<f64>, ccw: bool) -> f64 {
    let t = b.y.atan2(b.x) - a.y.atan2(a.x);
    let t = if ccw { t } else { -t };
    t.rem_euclid(std::f64::consts::TAU)
}

fn round_to(v: f64, decimals: usize) -> f64 {
    number(v, decimals).parse().unwrap_or(v)
}

/// The modal words the program relies on, from the settings (never from a template).
fn modal_line(g: &GcodeSettings) -> String {
    let units = match g.units {
        Units::Mm => "G21",
        Units::Inch => "G20",
    };
    let feed = match g.feed_mode {
        FeedMode::UnitsPerMinute => "G94",
        FeedMode::InverseTime => "G93",
    };
    match g.dialect {
        Dialect::Marlin => format!("{units} G90"),
        Dialect::Grbl => format!("G17 {units} G90 {feed}"),
        // Arc centres incremental (I, J from the start point), as the fitter writes them.
        Dialect::Linuxcnc | Dialect::Mach3 => format!("G17 {units} G90 G91.1 {feed}"),
    }
}

/// A start/end template line with `{job}` and `{profile}` filled in, sanitised.
fn fill_template(line: &str, job_id: &str, profile: &str) -> String {
    line.replace("{job}", &sanitise(job_id))
        .replace("{profile}", &sanitise(profile))
}

fn s_value(g: &GcodeSettings, power: f64) -> String {
    let p = g.power.as_ref().map_or(1.0, |p| p.s_per_unit);
    number(power * p, g.power.as_ref().map_or(0, |p| p.s_decimals))
}

fn dwell(dialect: Dialect, seconds: f64) -> String {
    match dialect {
        // Marlin: P is milliseconds, S seconds.
        Dialect::Marlin => format!("G4 S{}", number(seconds, 3)),
        // GRBL, LinuxCNC and Mach3 (its default setting): P in seconds.
        _ => format!("G4 P{}", number(seconds, 3)),
    }
}

/// `v` with `decimals` places, never `-0`.
fn number(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// User text reduced to letters, digits, space and `_ - . : /`, at most 64 characters: it
/// cannot end a comment or start a command in any dialect.
pub fn sanitise(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || " _-.:/".contains(c) {
                c
            } else {
                '_'
            }
        })
        .take(64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_msgs::geometry_msgs::Point;

    #[test]
    fn extruded_length_counts_deposit_moves_in_either_mode() {
        // Absolute: a retract and prime around a travel, then a reset origin.
        let absolute = "M82\nG1 X1 Y0 E1.5 F600\nG1 E0.7\nG0 X5 Y5\nG1 E1.5\n\
                        G1 X6 Y5 E2.0\nG92 E0\nG1 X7 Y5 E0.25\n";
        assert!((extruded_length_mm(absolute) - 2.25).abs() < 1e-12);
        let relative = "M83\nG1 X1 Y0 E1.5\nG1 E-0.8\nG0 X5 Y5\nG1 E0.8\nG1 X6 E0.5\n";
        assert!((extruded_length_mm(relative) - 2.0).abs() < 1e-12);
        assert_eq!(extruded_length_mm("; nothing\nG0 X1\n"), 0.0);
    }

    fn seg(kind: u8, pts: &[(f64, f64)], feed: f32, power: f32) -> ToolpathSegment {
        ToolpathSegment {
            kind,
            points: pts.iter().map(|&(x, y)| Point { x, y, z: 0.0 }).collect(),
            feed_mm_s: vec![feed; pts.len()],
            power: vec![power; pts.len()],
            ..Default::default()
        }
    }

    fn toolpath(segments: Vec<ToolpathSegment>) -> Toolpath {
        Toolpath {
            segments,
            ..Default::default()
        }
    }

    #[test]
    fn straight_cut_on_the_four_axis_profile_in_inverse_time() {
        let profile = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
        let tp = toolpath(vec![
            seg(
                ToolpathSegment::KIND_LEAD,
                &[(100.0, 50.0), (90.0, 50.0)],
                10.0,
                3.0,
            ),
            seg(
                ToolpathSegment::KIND_CUT,
                &[(90.0, 50.0), (90.0, 60.0)],
                5.0,
                2.5,
            ),
        ]);
        let text = emit(&tp, &profile, "job (1); M2").unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines,
            [
                "(cellsuite emitter: job job _1__ M2, profile linuxcnc-xyuv)",
                "G17 G21 G90 G91.1 G93",
                "G0 X100.000 Y50.000 U100.000 V50.000",
                "M3 S300",
                "G4 P2.000",
                "G1 X90.000 Y50.000 U90.000 V50.000 F60.0000",
                "G1 X90.000 Y60.000 U90.000 V60.000 F30.0000 S250",
                "M5",
                "G94",
                "M2",
            ]
        );
    }

    #[test]
    fn bad_input_is_named_and_gives_no_program() {
        let profile = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
        let mut tp = toolpath(vec![seg(0, &[(10.0, 10.0), (20.0, 10.0)], 5.0, 3.0)]);
        tp.segments[0].points[1].y = f64::NAN;
        let e = emit(&tp, &profile, "j").unwrap_err();
        assert_eq!(e.to_string(), "segment 0 point 1: y is not finite");
        let mut tp = toolpath(vec![seg(0, &[(10.0, 10.0), (20.0, 10.0)], 5.0, 3.0)]);
        tp.segments[0].feed_mm_s[1] = 0.0;
        assert!(matches!(
            emit(&tp, &profile, "j"),
            Err(EmitError::Feed {
                segment: 0,
                point: 1,
                ..
            })
        ));
        let tp = toolpath(vec![seg(0, &[(10.0, 10.0), (700.0, 10.0)], 5.0, 3.0)]);
        let e = emit(&tp, &profile, "j").unwrap_err();
        assert!(
            e.to_string().starts_with("segment 0 point 1: X = 700.000"),
            "{e}"
        );
        let two_axis = MachineProfile::resolve("grbl-xy").unwrap();
        let mut tp = toolpath(vec![seg(0, &[(10.0, 10.0), (20.0, 10.0)], 5.0, 3.0)]);
        tp.segments[0].secondary_points = tp.segments[0].points.clone();
        tp.segments[0].secondary_points[1].x = 15.0;
        assert!(matches!(
            emit(&tp, &two_axis, "j"),
            Err(EmitError::NoAxis { .. })
        ));
    }

    #[test]
    fn numbers_never_print_negative_zero_and_text_is_sanitised() {
        assert_eq!(number(-0.0001, 3), "0.000");
        assert_eq!(number(-1.5, 1), "-1.5");
        assert_eq!(sanitise("a(b)c;d\nM3 S9000"), "a_b_c_d_M3 S9000");
        assert_eq!(sanitise(&"x".repeat(100)).len(), 64);
    }
}
