//! A G-code reader for the sheet acceptance check (`tests/sheet_acceptance.rs`): what a
//! sheet-cutting program makes the torch do, reconstructed from the text alone. It shares no
//! code with `cell_emitter` (which writes the programs) or `cell_grbl` (which streams them).
//!
//! **Words.** Comments `( … )` and `; …`, line numbers `N…`, `%` lines, spaces inside words
//! and lower case are accepted. G0/G1/G2/G3 (modal), G4 dwell, G17, G20/G21, G90/G91,
//! G90.1/G91.1 (absolute or incremental I, J), G93/G94, G40/G41/G42 (and G41.1/G42.1), G43/G49,
//! G54, G61/G61.1/G64, G80; M3/M4 (heat on), M5 (heat off), M2/M30, M0/M1, M6, M7/M8/M9;
//! F, S, T, D, H, P, Q. Anything else (G92 offsets, other planes, other coordinate systems,
//! parameters, subroutines, block delete) is an error naming the line: a reader that guessed
//! would check a different program from the one the machine runs.
//!
//! **Order within a line** follows LinuxCNC's order of execution: feed, speed, heat on/off,
//! dwell, plane, units, compensation, distance mode, then the motion, then the program end.
//!
//! **Heat.** The heat is on from M3/M4 (unless the last S was 0) to M5 or the program end.
//! Every XY move made with the heat on is cut: a `HeatRun` runs from the point where the heat
//! came on (the pierce) through every move until the heat goes off. Arcs are sampled into
//! chords at most [`ARC_SAMPLING_MM`] from the arc; lines stay whole. An arc whose end radius
//! differs from its start radius by more than [`ARC_RADIUS_TOLERANCE_MM`] is an error (as in
//! LinuxCNC), within it a spiral.
#![allow(dead_code)] // each test binary uses a different subset

use std::f64::consts::TAU;

/// Largest distance between a sampled chord and its arc, mm.
pub const ARC_SAMPLING_MM: f64 = 0.001;

/// Largest difference between an arc's start and end radius, mm.
pub const ARC_RADIUS_TOLERANCE_MM: f64 = 0.002;

/// Cutter radius compensation in force for a move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compensation {
    /// G40.
    Off,
    /// G41: the tool runs left of the programmed path.
    Left,
    /// G42: the tool runs right of the programmed path.
    Right,
}

/// One cut: from the heat coming on to it going off.
#[derive(Debug, Clone, PartialEq)]
pub struct HeatRun {
    /// Where the heat came on (the pierce), mm.
    pub pierce: [f64; 2],
    /// The 1-based line that switched the heat on.
    pub line: usize,
    /// The path, the pierce first; consecutive points are straight moves (arcs sampled).
    pub path: Vec<[f64; 2]>,
    /// The 1-based source line of each move `path[i]`–`path[i + 1]`.
    pub move_line: Vec<usize>,
    /// The compensation in force for each move.
    pub move_compensation: Vec<Compensation>,
    /// Rapid (G0) moves made with the heat on, by line.
    pub rapids_with_heat: Vec<usize>,
    /// Total dwell with the heat on before the first move, s.
    pub pierce_dwell_s: f64,
}

impl HeatRun {
    /// The path length, mm.
    pub fn length(&self) -> f64 {
        self.path
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum()
    }
}

/// What a program does, as far as the acceptance check needs it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Program {
    /// The cuts in program order.
    pub runs: Vec<HeatRun>,
    /// Rapids with the heat off, as (from, to), mm.
    pub rapids: Vec<([f64; 2], [f64; 2])>,
    /// Whether G41/G42 was ever in force, and the D and T words seen with it.
    pub compensation_used: bool,
    pub d_words: Vec<f64>,
    pub t_words: Vec<f64>,
    /// True if the program ends with M2 or M30.
    pub ended: bool,
}

/// A line the reader refuses, with the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadError {
    /// 1-based line.
    pub line: usize,
    pub message: String,
}

impl std::fmt::Display for ReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "program line {}: {}", self.line, self.message)
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Motion {
    Rapid,
    Line,
    Cw,
    Ccw,
}

/// The modal state of the machine while reading.
struct Machine {
    at: [f64; 3],
    motion: Option<Motion>,
    absolute: bool,
    absolute_ij: bool,
    inch: bool,
    heat: bool,
    s: Option<f64>,
    compensation: Compensation,
    run: Option<HeatRun>,
    program: Program,
}

/// One word: letter and value.
type Word = (char, f64);

/// Splits a line into words, after dropping comments, spaces and the line number.
fn words(raw: &str, line: usize) -> Result<Vec<Word>, ReadError> {
    let err = |message: String| ReadError { line, message };
    let mut text = String::new();
    let mut in_paren = false;
    for ch in raw.chars() {
        match ch {
            '(' if !in_paren => in_paren = true,
            ')' if in_paren => in_paren = false,
            _ if in_paren => {}
            ';' => break,
            c if c.is_whitespace() => {}
            c => text.push(c.to_ascii_uppercase()),
        }
    }
    if in_paren {
        return Err(err("unclosed comment".into()));
    }
    if text.starts_with('%') && text.chars().all(|c| c == '%') {
        return Ok(Vec::new());
    }
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let letter = chars[i];
        if !letter.is_ascii_alphabetic() {
            return Err(err(format!(
                "{letter:?} is not a word letter (parameters, expressions and block delete are not supported)"
            )));
        }
        i += 1;
        let start = i;
        while i < chars.len() && (chars[i].is_ascii_digit() || matches!(chars[i], '.' | '+' | '-'))
        {
            i += 1;
        }
        let number: String = chars[start..i].iter().collect();
        let value: f64 = number
            .parse()
            .map_err(|_| err(format!("word {letter}{number}: not a number")))?;
        if !value.is_finite() {
            return Err(err(format!("word {letter}{number}: not finite")));
        }
        out.push((letter, value));
    }
    // The line number is a label, nothing else.
    if out.first().is_some_and(|w| w.0 == 'N') {
        out.remove(0);
    }
    Ok(out)
}

/// The code of a G or M word as tenths (G91.1 → 911), so codes compare exactly.
fn code(value: f64) -> i64 {
    (value * 10.0).round() as i64
}

/// Reads a whole program (module docs).
///
/// # Errors
/// The first line the reader cannot follow, with the reason.
pub fn read(text: &str) -> Result<Program, ReadError> {
    let mut m = Machine {
        at: [0.0; 3],
        motion: None,
        absolute: true,
        absolute_ij: false,
        inch: false,
        heat: false,
        s: None,
        compensation: Compensation::Off,
        run: None,
        program: Program::default(),
    };
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let ws = words(raw, line)?;
        if m.program.ended {
            if ws.is_empty() {
                continue;
            }
            return Err(ReadError {
                line,
                message: "a command after the program end".into(),
            });
        }
        m.execute(&ws, line)?;
    }
    m.heat_off();
    Ok(m.program)
}

impl Machine {
    fn mm(&self, v: f64) -> f64 {
        if self.inch {
            v * 25.4
        } else {
            v
        }
    }

    fn heat_on(&mut self, line: usize) {
        if self.heat {
            return;
        }
        self.heat = true;
        let at = [self.at[0], self.at[1]];
        self.run = Some(HeatRun {
            pierce: at,
            line,
            path: vec![at],
            move_line: Vec::new(),
            move_compensation: Vec::new(),
            rapids_with_heat: Vec::new(),
            pierce_dwell_s: 0.0,
        });
    }

    fn heat_off(&mut self) {
        self.heat = false;
        if let Some(run) = self.run.take() {
            self.program.runs.push(run);
        }
    }

    /// Moves the XY position to `to` along straight pieces (already sampled), recording them
    /// when the heat is on.
    fn travel_xy(&mut self, points: &[[f64; 2]], line: usize, rapid: bool) {
        let from = [self.at[0], self.at[1]];
        if let Some(run) = self.run.as_mut() {
            for &p in points {
                if p != *run.path.last().expect("a run starts with its pierce") {
                    run.path.push(p);
                    run.move_line.push(line);
                    run.move_compensation.push(self.compensation);
                }
            }
            if rapid && points.last() != Some(&from) {
                run.rapids_with_heat.push(line);
            }
        } else if rapid {
            if let Some(&to) = points.last() {
                if to != from {
                    self.program.rapids.push((from, to));
                }
            }
        }
        if let Some(&p) = points.last() {
            self.at[0] = p[0];
            self.at[1] = p[1];
        }
    }

    fn execute(&mut self, ws: &[Word], line: usize) -> Result<(), ReadError> {
        let err = |message: String| ReadError { line, message };
        let mut motion: Option<Motion> = None;
        let mut dwell = false;
        let mut end = false;
        let mut heat_on = false;
        let mut heat_off = false;
        let mut modal_groups_seen: Vec<&str> = Vec::new();
        let mut group = |name: &'static str| -> Result<(), ReadError> {
            if modal_groups_seen.contains(&name) {
                return Err(ReadError {
                    line,
                    message: format!("two {name} words on one line"),
                });
            }
            modal_groups_seen.push(name);
            Ok(())
        };
        let mut axes: [Option<f64>; 3] = [None; 3];
        let (mut i, mut j, mut r, mut p) = (None, None, None, None);
        // What the line sets, applied below in the order of execution.
        let mut set_absolute = None;
        let mut set_absolute_ij = None;
        let mut set_inch = None;
        let mut set_compensation = None;
        for &(letter, value) in ws {
            match letter {
                'G' => match code(value) {
                    0 | 10 | 20 | 30 => {
                        group("motion")?;
                        motion = Some(match code(value) {
                            0 => Motion::Rapid,
                            10 => Motion::Line,
                            20 => Motion::Cw,
                            _ => Motion::Ccw,
                        });
                    }
                    800 => {
                        group("motion")?;
                        self.motion = None;
                    }
                    40 => dwell = true,
                    170 => group("plane")?,
                    200 | 210 => {
                        group("units")?;
                        set_inch = Some(code(value) == 200);
                    }
                    900 | 910 => {
                        group("distance")?;
                        set_absolute = Some(code(value) == 900);
                    }
                    901 | 911 => {
                        group("arc distance")?;
                        set_absolute_ij = Some(code(value) == 901);
                    }
                    930 | 940 => group("feed mode")?,
                    400 | 410 | 420 | 411 | 421 => {
                        group("cutter compensation")?;
                        set_compensation = Some(match code(value) {
                            400 => Compensation::Off,
                            410 | 411 => Compensation::Left,
                            _ => Compensation::Right,
                        });
                    }
                    430 | 490 => group("tool length")?,
                    540 => group("coordinate system")?,
                    610 | 611 | 640 => group("path control")?,
                    other => {
                        return Err(err(format!(
                            "G{} is not supported by this reader",
                            other as f64 / 10.0
                        )))
                    }
                },
                'M' => match code(value) {
                    30 | 40 => {
                        group("spindle")?;
                        heat_on = true;
                    }
                    50 => {
                        group("spindle")?;
                        heat_off = true;
                    }
                    20 | 300 => {
                        group("stop")?;
                        end = true;
                    }
                    0 | 10 | 60 | 70 | 80 | 90 => {}
                    other => {
                        return Err(err(format!(
                            "M{} is not supported by this reader",
                            other as f64 / 10.0
                        )))
                    }
                },
                'X' => axes[0] = Some(value),
                'Y' => axes[1] = Some(value),
                'Z' => axes[2] = Some(value),
                'I' => i = Some(value),
                'J' => j = Some(value),
                'K' => {}
                'R' => r = Some(value),
                'P' => p = Some(value),
                'S' => self.s = Some(value),
                'D' => self.program.d_words.push(value),
                'T' => self.program.t_words.push(value),
                'F' | 'H' | 'Q' => {}
                other => return Err(err(format!("word letter {other} is not supported"))),
            }
        }
        // Heat on/off, then dwell (M3 G4 on one line pierces before dwelling).
        if heat_on && self.s != Some(0.0) {
            self.heat_on(line);
        }
        if heat_off || (self.heat && self.s == Some(0.0)) {
            self.heat_off();
        }
        if dwell {
            let seconds = p.ok_or_else(|| err("G4 without P".into()))?;
            if let Some(run) = self.run.as_mut() {
                if run.move_line.is_empty() {
                    run.pierce_dwell_s += seconds;
                }
            }
        }
        if let Some(v) = set_inch {
            self.inch = v;
        }
        if let Some(v) = set_compensation {
            self.compensation = v;
            if v != Compensation::Off {
                self.program.compensation_used = true;
            }
        }
        if let Some(v) = set_absolute {
            self.absolute = v;
        }
        if let Some(v) = set_absolute_ij {
            self.absolute_ij = v;
        }
        if motion.is_some() {
            self.motion = motion;
        }
        let moves = axes.iter().any(Option::is_some);
        if moves && !dwell {
            let Some(motion) = self.motion else {
                return Err(err("axis words without a motion mode".into()));
            };
            let mut to = self.at;
            for (k, v) in axes.iter().enumerate() {
                if let Some(v) = *v {
                    let v = self.mm(v);
                    to[k] = if self.absolute { v } else { self.at[k] + v };
                }
            }
            let from = [self.at[0], self.at[1]];
            let end_xy = [to[0], to[1]];
            match motion {
                Motion::Rapid | Motion::Line => {
                    self.travel_xy(&[end_xy], line, motion == Motion::Rapid);
                }
                Motion::Cw | Motion::Ccw => {
                    let ccw = motion == Motion::Ccw;
                    let centre = match (i.or(j), r) {
                        (Some(_), None) => {
                            let (ci, cj) = (self.mm(i.unwrap_or(0.0)), self.mm(j.unwrap_or(0.0)));
                            if self.absolute_ij {
                                [ci, cj]
                            } else {
                                [from[0] + ci, from[1] + cj]
                            }
                        }
                        (None, Some(radius)) => {
                            centre_from_radius(from, end_xy, self.mm(radius), ccw).map_err(&err)?
                        }
                        (Some(_), Some(_)) => return Err(err("an arc with both I/J and R".into())),
                        (None, None) => return Err(err("an arc without I, J or R".into())),
                    };
                    let turns = match p {
                        Some(t) if t >= 1.0 && t.fract() == 0.0 => t as usize,
                        Some(t) => {
                            return Err(err(format!("arc P{t}: turns must be a whole number ≥ 1")))
                        }
                        None => 1,
                    };
                    let points = sample_arc(from, end_xy, centre, ccw, turns).map_err(&err)?;
                    self.travel_xy(&points, line, false);
                }
            }
            self.at[2] = to[2];
        } else if motion.is_some_and(|m| m != Motion::Rapid && m != Motion::Line) {
            return Err(err("an arc without an end point".into()));
        }
        if end {
            self.heat_off();
            self.program.ended = true;
        }
        Ok(())
    }
}

/// The centre of an R-format arc: the shorter arc for R > 0, the longer for R < 0.
fn centre_from_radius(
    from: [f64; 2],
    to: [f64; 2],
    radius: f64,
    ccw: bool,
) -> Result<[f64; 2], String> {
    let chord = [to[0] - from[0], to[1] - from[1]];
    let d = chord[0].hypot(chord[1]);
    if d == 0.0 {
        return Err("an R arc cannot be a full circle".into());
    }
    let half = d / 2.0;
    let r = radius.abs();
    if r < half - 1e-6 {
        return Err(format!(
            "arc radius {r} is shorter than half the chord {half}"
        ));
    }
    let h = (r * r - half * half).max(0.0).sqrt();
    // The centre of the shorter arc lies left of the chord for G3, right for G2.
    let left = [-chord[1] / d, chord[0] / d];
    let side = if ccw == (radius > 0.0) { 1.0 } else { -1.0 };
    let mid = [(from[0] + to[0]) / 2.0, (from[1] + to[1]) / 2.0];
    Ok([mid[0] + side * h * left[0], mid[1] + side * h * left[1]])
}

/// Points along an arc (the start excluded, the end included), chords within
/// [`ARC_SAMPLING_MM`]; `turns` > 1 adds full turns (LinuxCNC's P word).
fn sample_arc(
    from: [f64; 2],
    to: [f64; 2],
    centre: [f64; 2],
    ccw: bool,
    turns: usize,
) -> Result<Vec<[f64; 2]>, String> {
    let r0 = (from[0] - centre[0]).hypot(from[1] - centre[1]);
    let r1 = (to[0] - centre[0]).hypot(to[1] - centre[1]);
    if (r1 - r0).abs() > ARC_RADIUS_TOLERANCE_MM {
        return Err(format!(
            "arc end radius {r1:.4} differs from its start radius {r0:.4} by more than {ARC_RADIUS_TOLERANCE_MM} mm"
        ));
    }
    if r0 == 0.0 {
        return Err("an arc of radius 0".into());
    }
    let a0 = (from[1] - centre[1]).atan2(from[0] - centre[0]);
    let a1 = (to[1] - centre[1]).atan2(to[0] - centre[0]);
    let mut sweep = if ccw { a1 - a0 } else { a0 - a1 };
    sweep = sweep.rem_euclid(TAU);
    if from == to {
        sweep = TAU;
    }
    sweep += (turns - 1) as f64 * TAU;
    let r_max = r0.max(r1);
    let step = if r_max > ARC_SAMPLING_MM {
        2.0 * (1.0 - ARC_SAMPLING_MM / r_max).acos()
    } else {
        std::f64::consts::FRAC_PI_2
    };
    let n = ((sweep / step).ceil() as usize).max(1);
    let sign = if ccw { 1.0 } else { -1.0 };
    let mut out = Vec::with_capacity(n);
    for k in 1..n {
        let t = k as f64 / n as f64;
        let a = a0 + sign * sweep * t;
        let r = r0 + (r1 - r0) * t;
        out.push([centre[0] + r * a.cos(), centre[1] + r * a.sin()]);
    }
    out.push(to);
    Ok(out)
}
