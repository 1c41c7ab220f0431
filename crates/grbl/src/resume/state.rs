//! The modal state a program builds up line by line, as far as a resume needs it, applied in
//! GRBL's order of execution within a line (feed mode, F, S, T, spindle, coolant, plane,
//! units, distance, coordinate system, non-modal command, motion, program end).

use crate::program::is_controller_command;
use crate::words::Words;

/// Millimetres per inch (G20).
const MM_PER_INCH: f64 = 25.4;

/// The axis letters a line may move, in the order the preamble writes them.
pub(super) const AXES: [char; 9] = ['X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W'];

/// Index of Z in [`AXES`].
pub(super) const Z: usize = 2;

/// Value words other than axes that GRBL reads.
const OTHER_VALUES: &str = "FIJKLNPRST";

/// Motion mode (modal group 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Motion {
    Rapid,
    Linear,
    ArcCw,
    ArcCcw,
    Cancel,
}

impl Motion {
    pub(super) fn word(self) -> &'static str {
        match self {
            Motion::Rapid => "G0",
            Motion::Linear => "G1",
            Motion::ArcCw => "G2",
            Motion::ArcCcw => "G3",
            Motion::Cancel => "G80",
        }
    }
}

/// Spindle: the heat (hot wire, laser, torch) on `M3`/`M4`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Spindle {
    Off,
    Cw,
    Ccw,
}

/// Where an axis is, in the program's work coordinates (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Position {
    /// No line moved it: it is where it was when the program started.
    Untouched,
    At(f64),
    /// Line `line` left it where the text does not tell, for the reason `why`.
    Unknown {
        line: usize,
        why: &'static str,
    },
}

/// The feed of a plunge to the cut height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Plunge {
    pub inverse_time: bool,
    /// mm/min under G94, the inverse-time F under G93.
    pub feed: f64,
}

/// How the program switched the heat on for the cut in progress: what a resume repeats.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct HeatOn {
    /// The line with the `M3`/`M4`.
    pub line: usize,
    /// Z when the heat went on (the pierce height), if Z is known.
    pub z: Option<f64>,
    /// S when the heat went on.
    pub speed: f64,
    /// The dwell after it (s).
    pub dwell_s: Option<f64>,
    /// The first move after it, when Z-only at feed.
    pub plunge: Option<Plunge>,
    /// A move followed the heat-on: later dwells and moves belong to the cut.
    pub settled: bool,
}

/// What GRBL's parser holds after a run of lines, plus what a resume must repeat.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ModalState {
    pub motion: Motion,
    /// 17, 18 or 19.
    pub plane: u16,
    pub inches: bool,
    pub incremental: bool,
    /// 54..=59.
    pub coord: u16,
    pub inverse_time: bool,
    /// GRBL's feed: mm/min under G94, the last line's inverse-time F (or 0) under G93.
    pub feed: f64,
    pub spindle: Spindle,
    pub speed: f64,
    pub mist: bool,
    pub flood: bool,
    pub tool: Option<u32>,
    /// Per letter of [`AXES`].
    pub positions: [Position; 9],
    /// The line that set a G92 offset still in effect.
    pub g92_line: Option<usize>,
    /// The program used G92.
    pub used_g92: bool,
    /// The heat-on of the cut in progress (None while the heat is off).
    pub heat: Option<HeatOn>,
    /// Z at the last rapid that moved other axes (the travel height).
    pub travel_z: Option<f64>,
}

/// The non-modal command of a line.
#[derive(Debug, Clone, Copy, PartialEq)]
enum NonModal {
    Dwell,
    SetCoord,
    Home,
    G92,
    G92Reset,
}

impl ModalState {
    /// GRBL's reset state, every axis untouched.
    pub(super) fn new() -> Self {
        ModalState {
            motion: Motion::Rapid,
            plane: 17,
            inches: false,
            incremental: false,
            coord: 54,
            inverse_time: false,
            feed: 0.0,
            spindle: Spindle::Off,
            speed: 0.0,
            mist: false,
            flood: false,
            tool: None,
            positions: [Position::Untouched; 9],
            g92_line: None,
            used_g92: false,
            heat: None,
            travel_z: None,
        }
    }

    /// Millimetres per programmed unit.
    pub(super) fn unit(&self) -> f64 {
        if self.inches {
            MM_PER_INCH
        } else {
            1.0
        }
    }

    /// Every known or untouched axis becomes unknown after `line` (`why`).
    fn lose_positions(&mut self, line: usize, why: &'static str, untouched_too: bool) {
        for p in &mut self.positions {
            if untouched_too || matches!(p, Position::At(_)) {
                *p = Position::Unknown { line, why };
            }
        }
    }

    /// Applies original line `line` with text `text`; `Err` says why the resume cannot follow
    /// it.
    pub(super) fn apply(&mut self, line: usize, text: &str) -> Result<(), String> {
        if is_controller_command(text) {
            let upper = text.to_ascii_uppercase();
            let upper = upper.trim_start();
            if upper.starts_with("$H") || upper.starts_with("$J") {
                self.lose_positions(line, "homing or jogging moves the machine", true);
            }
            return Ok(());
        }
        let w = Words::scan(text).map_err(|e| e.to_string())?;
        check_letters(&w)?;
        let mut explicit_motion = None;
        let mut non_modal = None;
        let mut machine_coords = false;
        for &(g, tenths) in &w.g {
            match (g, tenths) {
                (0, 0) => explicit_motion = Some(Motion::Rapid),
                (1, 0) => explicit_motion = Some(Motion::Linear),
                (2, 0) => explicit_motion = Some(Motion::ArcCw),
                (3, 0) => explicit_motion = Some(Motion::ArcCcw),
                (80, 0) => explicit_motion = Some(Motion::Cancel),
                (4, 0) => non_modal = Some(NonModal::Dwell),
                (10, 0) => non_modal = Some(NonModal::SetCoord),
                (28, 0) | (30, 0) => non_modal = Some(NonModal::Home),
                (92, 0) => non_modal = Some(NonModal::G92),
                (92, 1) => non_modal = Some(NonModal::G92Reset),
                (53, 0) => machine_coords = true,
                // Stored home positions; incremental arc centres (GRBL's only mode); cutter
                // compensation off, tool length offset off, exact path: GRBL's fixed state.
                (28, 1) | (30, 1) | (91, 1) | (40, 0) | (49, 0) | (61, 0) => {}
                (17..=21 | 54..=59 | 90 | 91 | 93 | 94, 0) => {}
                _ => return Err(unsupported(&format!("G{}", g_text(g, tenths)))),
            }
        }
        for &m in &w.m {
            if !matches!(m, 0..=5 | 7..=9 | 30) {
                return Err(unsupported(&format!("M{m}")));
            }
        }
        let has_g = |g: u16| w.has_g(g, 0);

        // Feed mode, units (they scale F and the axes), F, S, T.
        let was_inverse = self.inverse_time;
        if has_g(93) || has_g(94) {
            self.inverse_time = has_g(93);
        }
        if has_g(20) || has_g(21) {
            self.inches = has_g(20);
        }
        let unit = self.unit();
        let f = w.value('F');
        if self.inverse_time {
            self.feed = f.unwrap_or(0.0);
        } else if let Some(f) = f {
            self.feed = f * unit;
        } else if was_inverse {
            self.feed = 0.0;
        }
        if let Some(s) = w.value('S') {
            self.speed = s;
            if let Some(h) = self.heat.as_mut().filter(|h| !h.settled) {
                h.speed = s;
            }
        }
        if let Some(t) = w.value('T') {
            self.tool = Some(t as u32);
        }

        // Spindle and coolant.
        for &m in &w.m {
            match m {
                3 | 4 => {
                    if self.spindle == Spindle::Off {
                        self.heat = Some(HeatOn {
                            line,
                            z: match self.positions[Z] {
                                Position::At(z) => Some(z),
                                _ => None,
                            },
                            speed: self.speed,
                            dwell_s: None,
                            plunge: None,
                            settled: false,
                        });
                    }
                    self.spindle = if m == 3 { Spindle::Cw } else { Spindle::Ccw };
                }
                5 => {
                    self.spindle = Spindle::Off;
                    self.heat = None;
                }
                7 => self.mist = true,
                8 => self.flood = true,
                9 => (self.mist, self.flood) = (false, false),
                _ => {}
            }
        }

        // Plane, distance, coordinate system.
        for g in 17..=19 {
            if has_g(g) {
                self.plane = g;
            }
        }
        if has_g(90) || has_g(91) {
            self.incremental = has_g(91);
        }
        if let Some(c) = (54..=59).find(|&c| has_g(c)) {
            if c != self.coord {
                self.lose_positions(line, "the work coordinate system changed", false);
                self.coord = c;
            }
        }

        // The non-modal command.
        let axis_words: Vec<(usize, f64)> = AXES
            .iter()
            .enumerate()
            .filter_map(|(k, &a)| w.value(a).map(|v| (k, v)))
            .collect();
        match non_modal {
            Some(NonModal::Dwell) => {
                let p = w.value('P').unwrap_or(0.0);
                if let Some(h) = self.heat.as_mut().filter(|h| !h.settled) {
                    h.dwell_s = Some(p);
                }
            }
            Some(NonModal::SetCoord) => self.set_coord(line, &w, &axis_words),
            Some(NonModal::Home) => {
                self.lose_positions(line, "G28/G30 go to a stored position", true);
            }
            Some(NonModal::G92) => {
                self.used_g92 = true;
                if !axis_words.is_empty() {
                    self.g92_line = Some(line);
                }
                for &(k, v) in &axis_words {
                    self.positions[k] = Position::At(v * unit);
                }
            }
            Some(NonModal::G92Reset) => {
                self.used_g92 = true;
                if self.g92_line.take().is_some() {
                    self.lose_positions(line, "clearing a G92 offset moves the frame", false);
                }
            }
            None => {}
        }

        // Motion.
        if let Some(m) = explicit_motion {
            self.motion = m;
        }
        let moves = !axis_words.is_empty()
            && !matches!(
                non_modal,
                Some(NonModal::SetCoord | NonModal::Home | NonModal::G92)
            )
            && self.motion != Motion::Cancel;
        if moves {
            self.motion_to(line, &axis_words, machine_coords);
        }

        // Program end: GRBL's defaults for the next program.
        if w.m.iter().any(|&m| m == 2 || m == 30) {
            self.motion = Motion::Linear;
            self.plane = 17;
            self.incremental = false;
            self.inverse_time = false;
            if self.coord != 54 {
                self.lose_positions(line, "the work coordinate system changed", false);
                self.coord = 54;
            }
            self.spindle = Spindle::Off;
            self.heat = None;
            (self.mist, self.flood) = (false, false);
        }
        Ok(())
    }

    /// `G10 L2`/`L20`: an offset of the current system changes where its axes are.
    fn set_coord(&mut self, line: usize, w: &Words, axis_words: &[(usize, f64)]) {
        let p = w.value('P').unwrap_or(0.0) as u16;
        let current = p == 0 || p + 53 == self.coord;
        if !current {
            return;
        }
        let unit = self.unit();
        for &(k, v) in axis_words {
            self.positions[k] = match w.value('L') {
                // L20: the current position is `v` in the system.
                Some(20.0) => Position::At(v * unit),
                _ => Position::Unknown {
                    line,
                    why: "G10 L2 moved the work coordinate system",
                },
            };
        }
    }

    /// A move in the current motion mode to the axis words (original line `line`).
    fn motion_to(&mut self, line: usize, axis_words: &[(usize, f64)], machine_coords: bool) {
        let unit = self.unit();
        for &(k, v) in axis_words {
            self.positions[k] = match (machine_coords, self.incremental, self.positions[k]) {
                (true, _, _) => Position::Unknown {
                    line,
                    why: "a G53 move is in machine coordinates",
                },
                (false, false, _) => Position::At(v * unit),
                (false, true, Position::At(p)) => Position::At(p + v * unit),
                (false, true, Position::Unknown { line, why }) => Position::Unknown { line, why },
                (false, true, Position::Untouched) => Position::Unknown {
                    line,
                    why: "an incremental move from where the program started",
                },
            };
        }
        let z_only = axis_words.iter().all(|&(k, _)| k == Z);
        if let Some(h) = self.heat.as_mut().filter(|h| !h.settled) {
            h.settled = true;
            if z_only && self.motion == Motion::Linear {
                h.plunge = Some(Plunge {
                    inverse_time: self.inverse_time,
                    feed: self.feed,
                });
            }
        }
        if self.motion == Motion::Rapid && !z_only {
            if let Position::At(z) = self.positions[Z] {
                self.travel_z = Some(z);
            }
        }
    }
}

/// The words of the resumed line (a controller command has none that matter).
pub(super) fn resumed_line_words(text: &str) -> Result<Words, String> {
    if is_controller_command(text) {
        return Ok(Words::default());
    }
    let w = Words::scan(text).map_err(|e| e.to_string())?;
    check_letters(&w)?;
    Ok(w)
}

/// Every value word is one GRBL reads.
fn check_letters(w: &Words) -> Result<(), String> {
    match w
        .values()
        .find(|&(c, _)| !AXES.contains(&c) && !OTHER_VALUES.contains(c))
    {
        Some((c, _)) => Err(format!("word {c} is not GRBL G-code")),
        None => Ok(()),
    }
}

/// `92.1` for (92, 1), `17` for (17, 0).
fn g_text(g: u16, tenths: u8) -> String {
    if tenths == 0 {
        g.to_string()
    } else {
        format!("{g}.{tenths}")
    }
}

fn unsupported(word: &str) -> String {
    format!(
        "{word} sets a state the resume cannot rebuild (it follows G0-G4, G10 L2/L20, G17-G21, \
         G28/G30, G53, G54-G59, G80, G90/G91, G92/G92.1, G93/G94, M0-M5, M7-M9, M30); \
         restart the program instead"
    )
}
