//! Step 3 of a line: its value words (N, F, S, T, then the axes), its non-modal command and its
//! motion, applied to the modal state from step 2, in GRBL's order of checks so that a bad
//! line gives GRBL's first `error:N`.

use super::arc::arc_length;
use super::code::*;
use super::groups::{Groups, NonModal};
use super::lex::Words;
use super::modal::MM_PER_INCH;
use super::{Action, Modal, MotionMode, Speed, Spindle};

/// A line's words as the motion needs them, and which value words it used.
pub(super) struct Line<'a> {
    words: &'a Words,
    /// The configured axis letters.
    pub axes: &'a [char],
    /// Axis words, in configured axis order (programmed units).
    pub axis_words: Vec<Option<f64>>,
    /// Millimetres per programmed unit (25.4 under G20).
    pub unit: f64,
    /// Work coordinate offset in effect before the line's own G10/G92 (mm).
    wco: Vec<f64>,
    /// Value words the line uses; GRBL errors on the rest with 36. F, N, S, T always count.
    used: [bool; 26],
}

impl Line<'_> {
    /// The value of word `c`, if the line has one.
    pub fn value(&self, c: char) -> Option<f64> {
        self.words.value(c)
    }

    /// Marks word `c` as used.
    pub fn use_word(&mut self, c: char) {
        self.used[(c as u8 - b'A') as usize] = true;
    }

    /// True if the line has any axis word.
    fn has_axis(&self) -> bool {
        self.axis_words.iter().any(Option::is_some)
    }

    /// The point the axis words name from `pos`: relative to it (`incremental`), in machine
    /// coordinates (`machine`, G53) or in work coordinates; axes without a word stay at `pos`.
    fn target(&self, pos: &[f64], incremental: bool, machine: bool) -> Vec<f64> {
        (0..self.axes.len())
            .map(|k| match self.axis_words[k] {
                Some(x) => {
                    let mm = x * self.unit;
                    if incremental {
                        pos[k] + mm
                    } else if machine {
                        mm
                    } else {
                        mm + self.wco[k]
                    }
                }
                None => pos[k],
            })
            .collect()
    }

    /// The first value word the line has but did not use (axis words always count as used).
    fn unused_word(&self) -> Option<char> {
        (b'A'..=b'Z')
            .enumerate()
            .map(|(k, c)| (k, c as char))
            .find(|&(k, c)| {
                self.words.vals[k].is_some() && !self.used[k] && !self.axes.contains(&c)
            })
            .map(|(_, c)| c)
    }
}

/// Applies `words` to the modal state of `groups` (checked against the `modal` state before
/// the line); returns the new modal state and what the line does. `jog` as in
/// [`execute`](super::execute).
pub(super) fn apply(
    modal: &Modal,
    words: &Words,
    groups: Groups,
    axes: &[char],
    jog: bool,
) -> Result<(Modal, Action), u8> {
    let Groups {
        mut new,
        non_modal,
        absolute_override,
        explicit_motion,
        mut action,
    } = groups;
    let unit = values(modal, words, &mut new, &mut action, jog)?;

    // Axis words.
    let mut line = Line {
        words,
        axes,
        axis_words: axes.iter().map(|&a| words.value(a)).collect(),
        unit,
        wco: Vec::new(),
        used: [false; 26],
    };
    let has_axis = line.has_axis();
    let uses_axes = matches!(
        non_modal,
        NonModal::SetCoord | NonModal::Home(_) | NonModal::G92
    );
    if uses_axes && explicit_motion && has_axis {
        return Err(AXIS_COMMAND_CONFLICT);
    }
    let motion_uses_axes = has_axis && !uses_axes;
    if motion_uses_axes && new.motion == MotionMode::Cancel {
        return Err(AXIS_WORDS_EXIST);
    }
    if absolute_override && !matches!(new.motion, MotionMode::Rapid | MotionMode::Linear) {
        return Err(G53_INVALID_MOTION_MODE);
    }
    for c in ['F', 'N', 'S', 'T'] {
        line.use_word(c);
    }
    line.wco = new.wco();

    non_modal_command(non_modal, &mut line, &mut new, &mut action)?;
    if motion_uses_axes
        || (matches!(new.motion, MotionMode::ArcCw | MotionMode::ArcCcw)
            && explicit_motion
            && !uses_axes)
    {
        motion(&mut line, absolute_override, &mut new, &mut action)?;
    }
    if new.inverse_time {
        // F is the reciprocal of the move's duration in minutes, for every feed move.
        for m in &mut action.moves {
            if let Speed::Feed(_) = m.speed {
                m.speed = Speed::Feed(m.length_mm * new.feed_mm_min / 60.0);
            }
        }
    }
    if line.unused_word().is_some() {
        return Err(UNUSED_WORDS);
    }
    if jog {
        // A jog leaves the modal state alone; only the parser position follows it.
        let mut kept = modal.clone();
        kept.position = new.position;
        return Ok((kept, action));
    }
    if action.program_end {
        // M2/M30: back to GRBL's program-end defaults.
        new.motion = MotionMode::Linear;
        new.plane = 0;
        new.incremental = false;
        new.inverse_time = false;
        new.coord = 0;
        new.spindle = Spindle::Off;
        new.flood = false;
        new.mist = false;
    }
    Ok((new, action))
}

/// The N, T, S and F words: range checks, tool, spindle speed and feed. Returns millimetres
/// per programmed unit.
fn values(
    modal: &Modal,
    words: &Words,
    new: &mut Modal,
    action: &mut Action,
    jog: bool,
) -> Result<f64, u8> {
    let v = |c: char| words.value(c);
    // GRBL 1.1 gcode.c, step 2: "Check for invalid negative values for words F, N, P, T, and
    // S" (`STATUS_NEGATIVE_VALUE`, error:4) as each word is read, before any other check.
    for c in ['F', 'N', 'P', 'S', 'T'] {
        if v(c).is_some_and(|x| x < 0.0) {
            return Err(NEGATIVE_VALUE);
        }
    }
    if v('N').is_some_and(|n| n > 9_999_999.0) {
        return Err(INVALID_LINE_NUMBER);
    }
    if let Some(t) = v('T') {
        if t > 255.0 {
            return Err(MAX_VALUE_EXCEEDED);
        }
        new.tool = t as u32;
    }
    let unit = if new.inches { MM_PER_INCH } else { 1.0 };
    if let Some(s) = v('S') {
        if s != new.spindle_speed && new.spindle != Spindle::Off && !action.sync {
            // A new S with the spindle on and no motion takes effect in sync (no laser mode).
            action.sync = true;
        }
        new.spindle_speed = s;
    }
    // Feed: G93 needs F on every feed move; G94 keeps the last F (unless coming from G93).
    let feed_word = v('F').map(|f| f * if new.inverse_time { 1.0 } else { unit });
    if new.inverse_time {
        new.feed_mm_min = feed_word.unwrap_or(0.0);
    } else if let Some(f) = feed_word {
        new.feed_mm_min = f;
    } else if modal.inverse_time {
        new.feed_mm_min = 0.0;
    }
    if jog && feed_word.is_none() {
        return Err(UNDEFINED_FEED_RATE);
    }
    Ok(unit)
}

/// G4 dwell, G10 L2/L20 work offsets, G28/G30 homing moves, G92/G92.1 offsets.
fn non_modal_command(
    non_modal: NonModal,
    line: &mut Line<'_>,
    new: &mut Modal,
    action: &mut Action,
) -> Result<(), u8> {
    let n = line.axes.len();
    let has_axis = line.has_axis();
    let unit = line.unit;
    match non_modal {
        NonModal::Dwell => {
            let p = line.value('P').ok_or(VALUE_WORD_MISSING)?;
            line.use_word('P');
            action.dwell_s = Some(p);
            action.sync = true;
        }
        NonModal::SetCoord => {
            // GRBL 1.1 gcode.c, "[19. Remaining non-modal actions]", NON_MODAL_SET_COORDINATE_DATA:
            // no axis words → 26; P or L missing → 28; `coord_select = trunc(p)` above
            // N_COORDINATE_SYSTEM (6) → STATUS_GCODE_UNSUPPORTED_COORD_SYS, 29; L (read as its
            // integer part) neither 2 nor 20 → 20. P below 0 never gets here (error:4 in
            // `values`), so P0..=P6 index G54..G59 or, P0, the active system.
            if !has_axis {
                return Err(NO_AXIS_WORDS);
            }
            let (l, p) = (
                line.value('L').ok_or(VALUE_WORD_MISSING)?.trunc(),
                line.value('P').ok_or(VALUE_WORD_MISSING)?.trunc(),
            );
            line.use_word('L');
            line.use_word('P');
            let coord = match p {
                0.0 => new.coord,
                1.0..=6.0 => p as usize - 1,
                _ => return Err(UNSUPPORTED_COORD_SYS),
            };
            if !(l == 2.0 || l == 20.0) {
                return Err(UNSUPPORTED_COMMAND);
            }
            let idx = coord;
            for (k, w) in line.axis_words.iter().enumerate() {
                if let Some(x) = *w {
                    let mm = x * unit;
                    new.offsets[idx][k] = if l == 2.0 {
                        mm
                    } else {
                        new.position[k] - mm - new.g92[k]
                    };
                }
            }
            action.sync = true;
        }
        NonModal::G92 => {
            if !has_axis {
                return Err(NO_AXIS_WORDS);
            }
            for (k, w) in line.axis_words.iter().enumerate() {
                if let Some(x) = *w {
                    new.g92[k] = new.position[k] - new.offsets[new.coord][k] - x * unit;
                }
            }
            action.sync = true;
        }
        NonModal::G92Reset => {
            new.g92 = vec![0.0; n];
            action.sync = true;
        }
        NonModal::Home(_) => {
            // Through the (optional) intermediate point, then to the stored position (machine
            // zero in this simulator).
            let mut pos = new.position.clone();
            if has_axis {
                let mid = line.target(&pos, new.incremental, false);
                action.push_line(&pos, &mid, Speed::Rapid);
                pos = mid;
            }
            let home = vec![0.0; n];
            action.push_line(&pos, &home, Speed::Rapid);
            new.position = home;
            action.sync = true;
        }
        NonModal::None => {}
    }
    Ok(())
}

/// The line's move in the current motion mode (G0, G1, G2/G3; nothing for G80), from the
/// parser position to the axis words' target, which becomes the new parser position.
fn motion(
    line: &mut Line<'_>,
    absolute_override: bool,
    new: &mut Modal,
    action: &mut Action,
) -> Result<(), u8> {
    let start = new.position.clone();
    let target = line.target(&start, new.incremental, absolute_override);
    let feed_speed = || -> Result<Speed, u8> {
        if new.feed_mm_min <= 0.0 {
            return Err(UNDEFINED_FEED_RATE);
        }
        Ok(Speed::Feed(new.feed_mm_min / 60.0))
    };
    match new.motion {
        MotionMode::Rapid => action.push_line(&start, &target, Speed::Rapid),
        MotionMode::Linear => {
            let speed = feed_speed()?;
            action.push_line(&start, &target, speed);
        }
        MotionMode::ArcCw | MotionMode::ArcCcw => {
            let speed = feed_speed()?;
            if !line.has_axis() {
                return Err(NO_AXIS_WORDS);
            }
            let length = arc_length(line, new.motion, new.plane, &start, &target)?;
            action.push_move(target.clone(), length, speed);
        }
        MotionMode::Cancel => {}
    }
    new.position = target;
    Ok(())
}
