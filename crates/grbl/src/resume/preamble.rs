//! The preamble's lines from the rebuilt state, in the order the module documentation of
//! [`crate::resume`] gives.

use crate::program::ProgramLine;
use crate::words::Words;

use super::state::{resumed_line_words, HeatOn, ModalState, Motion, Position, Spindle, AXES, Z};

/// A failed step: the line whose state cannot be restored, and why.
type Refusal = (usize, String);

/// The preamble for resuming at `rest[0]` (`rest`: the program from there on) from `state`.
pub(super) fn lines(state: &ModalState, rest: &[ProgramLine]) -> Result<Vec<String>, Refusal> {
    let line = rest[0].number;
    let resumed = resumed_line_words(&rest[0].text).map_err(|r| (line, r))?;
    if let Some(g92) = state.g92_line {
        return Err((
            g92,
            "the G92 offset set here is still in effect; a reset clears it and the resume does \
             not rebuild it: resume from a line after a G92.1"
                .into(),
        ));
    }
    check_start(state, &resumed, line)?;
    let mut w = Writer {
        state,
        unit: state.unit(),
        out: vec!["M5 M9".into()],
    };
    w.frame();
    let z = w.move_into_place();
    w.heat(z, line)?;
    w.modal_words(&resumed, rest)?;
    Ok(w.out)
}

/// Line N starts where the lines before it left the axes it moves; an axis it does not move
/// stays where the machine has it, which is where the program left it. Where line N starts
/// does not matter for an absolute straight move with the heat off: it ends at the same place
/// from anywhere and cuts nothing on the way.
fn check_start(state: &ModalState, resumed: &Words, line: usize) -> Result<(), Refusal> {
    let motion = named_motion(resumed).unwrap_or(state.motion);
    let incremental = if resumed.has_g(91, 0) || resumed.has_g(90, 0) {
        resumed.has_g(91, 0)
    } else {
        state.incremental
    };
    let start_matters = incremental
        || matches!(motion, Motion::ArcCw | Motion::ArcCcw)
        || state.spindle != Spindle::Off
        || resumed.m.iter().any(|&m| m == 3 || m == 4);
    if !start_matters {
        return Ok(());
    }
    for (&a, p) in AXES.iter().zip(&state.positions) {
        if resumed.value(a).is_none() {
            continue;
        }
        match *p {
            Position::At(_) => {}
            Position::Unknown { line: lost, why } => {
                return Err((
                    lost,
                    format!(
                        "after this line the position of {a} is not known ({why}), and line \
                         {line} moves {a}: resume from a line after an absolute move of {a}"
                    ),
                ))
            }
            Position::Untouched => {
                return Err((
                    line,
                    format!(
                        "this line moves {a}, and no line before it says where {a} starts (it \
                         is wherever the machine had it when the program started)"
                    ),
                ))
            }
        }
    }
    Ok(())
}

/// The preamble being written.
struct Writer<'a> {
    state: &'a ModalState,
    /// Millimetres per programmed unit at line N.
    unit: f64,
    out: Vec<String>,
}

impl Writer<'_> {
    /// A length in the units of line N.
    fn len(&self, mm: f64) -> String {
        number(mm / self.unit)
    }

    /// Step 2: plane, units, absolute distance, work coordinate system.
    fn frame(&mut self) {
        let s = self.state;
        let mut frame = format!(
            "G{} {} G90 G{}",
            s.plane,
            if s.inches { "G20" } else { "G21" },
            s.coord
        );
        if s.used_g92 {
            frame += " G92.1";
        }
        self.out.push(frame);
    }

    /// Step 3: into place with the heat off; returns Z at line N, when known.
    fn move_into_place(&mut self) -> Option<f64> {
        let s = self.state;
        let z = match s.positions[Z] {
            Position::At(z) => Some(z),
            _ => None,
        };
        let mut z_now = None;
        if let (Some(_), Some(travel)) = (z, s.travel_z) {
            self.out.push(format!("G0 Z{}", self.len(travel)));
            z_now = Some(travel);
        }
        let others: Vec<String> = AXES
            .iter()
            .zip(&s.positions)
            .enumerate()
            .filter(|&(k, _)| k != Z)
            .filter_map(|(_, (a, p))| match p {
                Position::At(v) => Some(format!("{a}{}", self.len(*v))),
                _ => None,
            })
            .collect();
        if !others.is_empty() {
            self.out.push(format!("G0 {}", others.join(" ")));
        }
        if let Some(target) = z.map(|z| self.pierce_z().unwrap_or(z)) {
            if z_now != Some(target) {
                self.out.push(format!("G0 Z{}", self.len(target)));
            }
        }
        z
    }

    /// The heat-on of the cut in progress at line N, if the heat is on there.
    fn heat_on(&self) -> Option<&HeatOn> {
        self.state
            .heat
            .as_ref()
            .filter(|_| self.state.spindle != Spindle::Off)
    }

    /// Z where the heat went on for the cut in progress (the pierce height).
    fn pierce_z(&self) -> Option<f64> {
        self.heat_on().and_then(|h| h.z)
    }

    /// Step 4: coolant, and the heat as the program switched it on for the cut in progress:
    /// `M3`/`M4` with its S, its dwell, the plunge from the pierce height to `z` (line N's).
    fn heat(&mut self, z: Option<f64>, line: usize) -> Result<(), Refusal> {
        let s = self.state;
        if s.mist {
            self.out.push("M7".into());
        }
        if s.flood {
            self.out.push("M8".into());
        }
        if s.spindle == Spindle::Off {
            return Ok(());
        }
        let heat = self.heat_on();
        let word = if s.spindle == Spindle::Cw { "M3" } else { "M4" };
        let speed = number(heat.map_or(s.speed, |h| h.speed));
        let dwell = heat.and_then(|h| h.dwell_s).filter(|&d| d > 0.0);
        let heat_line = heat.map_or(line, |h| h.line);
        let plunge = heat.and_then(|h| h.plunge);
        let pierce = self.pierce_z();
        self.out.push(format!("{word} S{speed}"));
        if let Some(d) = dwell {
            self.out.push(format!("G4 P{}", number(d)));
        }
        let (Some(cut), Some(pierce)) = (z, pierce) else {
            return Ok(());
        };
        if cut == pierce {
            return Ok(());
        }
        let (inverse, feed) = match plunge {
            Some(p) => (p.inverse_time, p.feed),
            None if !s.inverse_time && s.feed > 0.0 => (false, s.feed),
            None => {
                return Err((
                    heat_line,
                    "the height changes after the heat goes on here, and no Z-only feed move \
                     tells the feed to go down with"
                        .into(),
                ))
            }
        };
        let (mode, f) = if inverse {
            ("G93", number(feed))
        } else {
            ("G94", self.len(feed))
        };
        self.out.push(format!("G1 {mode} Z{} F{f}", self.len(cut)));
        Ok(())
    }

    /// Step 5: the modal words line N (`resumed`, first of `rest`) relies on.
    fn modal_words(&mut self, resumed: &Words, rest: &[ProgramLine]) -> Result<(), Refusal> {
        let s = self.state;
        let line = rest[0].number;
        let mut last: Vec<String> = Vec::new();
        let mut f_word = (!s.inverse_time && s.feed > 0.0).then(|| self.len(s.feed));
        if named_motion(resumed).is_none() {
            match s.motion {
                Motion::Rapid | Motion::Cancel => last.push(s.motion.word().into()),
                Motion::ArcCw | Motion::ArcCcw => {
                    if let Some(user) = modal_motion_user(rest) {
                        let who = if user == line {
                            "this line".to_string()
                        } else {
                            format!("line {user}")
                        };
                        return Err((
                            line,
                            format!(
                                "{who} moves in the arc mode {} of the lines before without \
                                 naming it, and no arc mode can be set without moving: resume \
                                 from a line that names its motion",
                                s.motion.word()
                            ),
                        ));
                    }
                }
                Motion::Linear if s.inverse_time => {
                    // Any F makes `G1` legal under G93; line N carries its own.
                    last.push("G1".into());
                    f_word = Some(number(resumed.value('F').unwrap_or(1.0)));
                }
                Motion::Linear if s.feed > 0.0 => last.push("G1".into()),
                Motion::Linear => {
                    // G94 with no feed yet: `G1` needs an F, and leaving G93 clears it again.
                    self.out.push("G1 G93 F1".into());
                }
            }
        }
        last.push(if s.incremental { "G91" } else { "G90" }.into());
        last.push(if s.inverse_time { "G93" } else { "G94" }.into());
        if let Some(f) = f_word {
            last.push(format!("F{f}"));
        }
        last.push(format!("S{}", number(s.speed)));
        if let Some(t) = s.tool {
            last.push(format!("T{t}"));
        }
        self.out.push(last.join(" "));
        Ok(())
    }
}

/// The motion mode a line names, if it names one.
fn named_motion(w: &Words) -> Option<Motion> {
    w.g.iter().find_map(|&(g, t)| match (g, t) {
        (0, 0) => Some(Motion::Rapid),
        (1, 0) => Some(Motion::Linear),
        (2, 0) => Some(Motion::ArcCw),
        (3, 0) => Some(Motion::ArcCcw),
        (80, 0) => Some(Motion::Cancel),
        _ => None,
    })
}

/// The first line from `rest[0]` on that moves in the motion mode of the lines before it
/// (axis words, no motion word of its own, before any line names one).
fn modal_motion_user(rest: &[ProgramLine]) -> Option<usize> {
    for l in rest {
        let w = resumed_line_words(&l.text).ok()?;
        if named_motion(&w).is_some() {
            return None;
        }
        let axis_setting =
            w.g.iter()
                .any(|&(g, t)| t == 0 && matches!(g, 10 | 28 | 30 | 92));
        if !axis_setting && AXES.iter().any(|&a| w.value(a).is_some()) {
            return Some(l.number);
        }
    }
    None
}

/// `v` with at most six decimals, no trailing zeros, never `-0`.
fn number(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}
