//! The simulator's G-code parser: GRBL 1.1's `gc_execute_line` checks for a useful subset of
//! RS274/NGC, returning the same `error:N` codes, and the motion a line commands.
//!
//! Input is a line as GRBL stores it: spaces and comments already removed, upper case.
//! Positions are in millimetres, machine coordinates.

use std::f64::consts::PI;

/// GRBL 1.1 status codes the parser returns.
pub(crate) mod code {
    pub const EXPECTED_COMMAND_LETTER: u8 = 1;
    pub const BAD_NUMBER_FORMAT: u8 = 2;
    pub const NEGATIVE_VALUE: u8 = 4;
    pub const UNSUPPORTED_COMMAND: u8 = 20;
    pub const MODAL_GROUP_VIOLATION: u8 = 21;
    pub const UNDEFINED_FEED_RATE: u8 = 22;
    pub const COMMAND_VALUE_NOT_INTEGER: u8 = 23;
    pub const AXIS_COMMAND_CONFLICT: u8 = 24;
    pub const WORD_REPEATED: u8 = 25;
    pub const NO_AXIS_WORDS: u8 = 26;
    pub const INVALID_LINE_NUMBER: u8 = 27;
    pub const VALUE_WORD_MISSING: u8 = 28;
    pub const UNSUPPORTED_COORD_SYS: u8 = 29;
    pub const G53_INVALID_MOTION_MODE: u8 = 30;
    pub const AXIS_WORDS_EXIST: u8 = 31;
    pub const NO_AXIS_WORDS_IN_PLANE: u8 = 32;
    pub const INVALID_TARGET: u8 = 33;
    pub const ARC_RADIUS_ERROR: u8 = 34;
    pub const NO_OFFSETS_IN_PLANE: u8 = 35;
    pub const UNUSED_WORDS: u8 = 36;
    pub const MAX_VALUE_EXCEEDED: u8 = 38;
}
use code::*;

const MM_PER_INCH: f64 = 25.4;

/// Motion modes (modal group 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MotionMode {
    Rapid,
    Linear,
    ArcCw,
    ArcCcw,
    Cancel,
}

/// Spindle state (M3/M4/M5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Spindle {
    Off,
    Cw,
    Ccw,
}

/// The parser's modal state (GRBL's `gc_state`).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Modal {
    pub motion: MotionMode,
    /// 0 = G17 (XY), 1 = G18 (ZX), 2 = G19 (YZ).
    pub plane: u8,
    pub inches: bool,
    pub incremental: bool,
    pub inverse_time: bool,
    /// 0..=5 for G54..G59.
    pub coord: usize,
    /// mm/min; 0 = undefined.
    pub feed_mm_min: f64,
    pub spindle: Spindle,
    pub spindle_speed: f64,
    pub flood: bool,
    pub mist: bool,
    pub tool: u32,
    /// Work coordinate offsets G54..G59 (mm), one per axis.
    pub offsets: [Vec<f64>; 6],
    /// G92 offset (mm).
    pub g92: Vec<f64>,
    /// Where the parser is: the end of the last planned move (mm, machine coordinates).
    pub position: Vec<f64>,
}

impl Modal {
    /// GRBL's power-up / reset state for `n_axes` axes at `position`.
    pub fn new(n_axes: usize, position: Vec<f64>) -> Modal {
        Modal {
            motion: MotionMode::Rapid,
            plane: 0,
            inches: false,
            incremental: false,
            inverse_time: false,
            coord: 0,
            feed_mm_min: 0.0,
            spindle: Spindle::Off,
            spindle_speed: 0.0,
            flood: false,
            mist: false,
            tool: 0,
            offsets: std::array::from_fn(|_| vec![0.0; n_axes]),
            g92: vec![0.0; n_axes],
            position,
        }
    }

    /// After a reset: modal state back to defaults, work offsets kept (they live in EEPROM),
    /// G92 cleared, parser position synced to the machine.
    pub fn reset(&self, position: Vec<f64>) -> Modal {
        let mut m = Modal::new(self.position.len(), position);
        m.offsets = self.offsets.clone();
        m
    }

    /// Work coordinate offset currently in effect (G54..G59 plus G92), mm.
    pub fn wco(&self) -> Vec<f64> {
        self.offsets[self.coord]
            .iter()
            .zip(&self.g92)
            .map(|(a, b)| a + b)
            .collect()
    }

    /// The `$G` report body.
    pub fn gc_report(&self) -> String {
        let motion = match self.motion {
            MotionMode::Rapid => "G0",
            MotionMode::Linear => "G1",
            MotionMode::ArcCw => "G2",
            MotionMode::ArcCcw => "G3",
            MotionMode::Cancel => "G80",
        };
        let spindle = match self.spindle {
            Spindle::Off => "M5",
            Spindle::Cw => "M3",
            Spindle::Ccw => "M4",
        };
        let coolant = match (self.flood, self.mist) {
            (false, false) => "M9".to_string(),
            (true, false) => "M8".to_string(),
            (false, true) => "M7".to_string(),
            (true, true) => "M7 M8".to_string(),
        };
        let feed = if self.inches {
            self.feed_mm_min / MM_PER_INCH
        } else {
            self.feed_mm_min
        };
        format!(
            "{motion} G{} G{} {} {} {} {spindle} {coolant} T{} F{} S{}",
            54 + self.coord,
            17 + self.plane,
            if self.inches { "G20" } else { "G21" },
            if self.incremental { "G91" } else { "G90" },
            if self.inverse_time { "G93" } else { "G94" },
            self.tool,
            fmt_num(feed),
            fmt_num(self.spindle_speed)
        )
    }
}

fn fmt_num(x: f64) -> String {
    if x.fract() == 0.0 {
        format!("{}", x as i64)
    } else {
        format!("{x:.3}")
    }
}

/// How fast a move goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Speed {
    /// At the rapid rate (times the rapid override).
    Rapid,
    /// At a feed (mm/s, before the feed override).
    Feed(f64),
}

/// A move the line commands.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Move {
    pub target: Vec<f64>,
    pub length_mm: f64,
    pub speed: Speed,
}

/// What executing a line does, besides the modal state it leaves.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Action {
    /// Moves for the planner, in order (empty moves already dropped).
    pub moves: Vec<Move>,
    /// G4 dwell (s).
    pub dwell_s: Option<f64>,
    /// The line must wait for the planner to empty (spindle/coolant changes, M0/M1/M2/M30,
    /// dwell, G10, G28/G30, G92).
    pub sync: bool,
    /// M2/M30.
    pub program_end: bool,
    /// M0/M1 (feed hold after the planner empties).
    pub pause: bool,
}

/// Parses and checks one stored line against `modal`; on success returns the new modal state
/// and what the line does. `axes` are the configured axis letters; `rapid_mm_min` is the rapid
/// rate. `jog` applies `$J=` rules (G91/G90/G20/G21/G53/F/axes only, feed required, modal
/// state left untouched except the parser position).
pub(crate) fn execute(
    modal: &Modal,
    line: &str,
    axes: &[char],
    jog: bool,
) -> Result<(Modal, Action), u8> {
    let bytes = line.as_bytes();
    let mut i = 0;
    let mut gs: Vec<(u16, u8)> = Vec::new();
    let mut ms: Vec<(u16, u8)> = Vec::new();
    let mut vals: [Option<f64>; 26] = [None; 26];
    while i < bytes.len() {
        let letter = bytes[i];
        if !letter.is_ascii_uppercase() {
            return Err(EXPECTED_COMMAND_LETTER);
        }
        i += 1;
        let start = i;
        if i < bytes.len() && (bytes[i] == b'-' || bytes[i] == b'+') {
            i += 1;
        }
        let mut digits = 0;
        let mut dot = false;
        while i < bytes.len() && (bytes[i].is_ascii_digit() || (bytes[i] == b'.' && !dot)) {
            if bytes[i] == b'.' {
                dot = true;
            } else {
                digits += 1;
            }
            i += 1;
        }
        if digits == 0 {
            return Err(BAD_NUMBER_FORMAT);
        }
        let value: f64 = line[start..i].parse().map_err(|_| BAD_NUMBER_FORMAT)?;
        match letter {
            b'G' | b'M' => {
                let int = value.trunc();
                if !(0.0..=999.0).contains(&int) {
                    return Err(UNSUPPORTED_COMMAND);
                }
                let mantissa = ((value - int) * 100.0).round() as u8;
                if letter == b'G' {
                    gs.push((int as u16, mantissa));
                } else {
                    if mantissa > 0 {
                        return Err(COMMAND_VALUE_NOT_INTEGER);
                    }
                    ms.push((int as u16, 0));
                }
            }
            _ => {
                let c = letter as char;
                let known = "FIJKLNPRST".contains(c) || axes.contains(&c);
                if !known {
                    return Err(UNSUPPORTED_COMMAND);
                }
                let slot = &mut vals[(letter - b'A') as usize];
                if slot.is_some() {
                    return Err(WORD_REPEATED);
                }
                *slot = Some(value);
            }
        }
    }
    let v = |c: char| vals[(c as u8 - b'A') as usize];

    // Modal groups.
    let mut new = modal.clone();
    let mut groups_seen = [false; 16];
    let mut seen = |g: usize| -> Result<(), u8> {
        if groups_seen[g] {
            Err(MODAL_GROUP_VIOLATION)
        } else {
            groups_seen[g] = true;
            Ok(())
        }
    };
    #[derive(PartialEq, Clone, Copy)]
    enum NonModal {
        None,
        Dwell,
        SetCoord,
        Home(u8),
        G92,
        G92Reset,
    }
    let mut non_modal = NonModal::None;
    let mut absolute_override = false; // G53
    let mut explicit_motion = false;
    for &(g, mantissa) in &gs {
        match (g, mantissa) {
            (0..=3, 0) | (80, 0) => {
                seen(1)?;
                explicit_motion = true;
                new.motion = match g {
                    0 => MotionMode::Rapid,
                    1 => MotionMode::Linear,
                    2 => MotionMode::ArcCw,
                    3 => MotionMode::ArcCcw,
                    _ => MotionMode::Cancel,
                };
            }
            (4, 0) | (10, 0) | (28, 0) | (30, 0) | (92, 0) | (92, 10) | (53, 0) => {
                seen(0)?;
                match (g, mantissa) {
                    (4, _) => non_modal = NonModal::Dwell,
                    (10, _) => non_modal = NonModal::SetCoord,
                    (28, _) => non_modal = NonModal::Home(28),
                    (30, _) => non_modal = NonModal::Home(30),
                    (92, 0) => non_modal = NonModal::G92,
                    (92, _) => non_modal = NonModal::G92Reset,
                    _ => absolute_override = true,
                }
            }
            (17..=19, 0) => {
                seen(2)?;
                new.plane = (g - 17) as u8;
            }
            (90, 0) | (91, 0) => {
                seen(3)?;
                new.incremental = g == 91;
            }
            (91, 10) => seen(4)?,
            (93, 0) | (94, 0) => {
                seen(5)?;
                new.inverse_time = g == 93;
            }
            (20, 0) | (21, 0) => {
                seen(6)?;
                new.inches = g == 20;
            }
            (40, 0) => seen(7)?,
            (43, 10) | (49, 0) => seen(8)?,
            (54..=59, 0) => {
                seen(12)?;
                new.coord = (g - 54) as usize;
            }
            (59, _) => return Err(UNSUPPORTED_COORD_SYS),
            (61, 0) => seen(13)?,
            _ => return Err(UNSUPPORTED_COMMAND),
        }
    }
    let mut action = Action::default();
    for &(m, _) in &ms {
        match m {
            0 | 1 | 2 | 30 => {
                seen(9)?;
                action.sync = true;
                if m <= 1 {
                    action.pause = true;
                } else {
                    action.program_end = true;
                }
            }
            3..=5 => {
                seen(10)?;
                let s = match m {
                    3 => Spindle::Cw,
                    4 => Spindle::Ccw,
                    _ => Spindle::Off,
                };
                if s != new.spindle {
                    action.sync = true;
                }
                new.spindle = s;
            }
            7..=9 => {
                seen(11)?;
                match m {
                    7 => new.mist = true,
                    8 => new.flood = true,
                    _ => {
                        new.mist = false;
                        new.flood = false;
                    }
                }
                action.sync = true;
            }
            _ => return Err(UNSUPPORTED_COMMAND),
        }
    }
    if jog {
        let allowed = non_modal == NonModal::None
            && !explicit_motion
            && ms.is_empty()
            && gs.iter().all(|g| {
                matches!(
                    g,
                    (20, 0) | (21, 0) | (90, 0) | (91, 0) | (53, 0) | (93..=94, 0)
                )
            });
        if !allowed {
            return Err(16); // Invalid jog command
        }
        new.motion = MotionMode::Linear;
    }

    // Values.
    if let Some(n) = v('N') {
        if !(0.0..=9_999_999.0).contains(&n) {
            return Err(INVALID_LINE_NUMBER);
        }
    }
    for c in ['F', 'P', 'S', 'T'] {
        if v(c).is_some_and(|x| x < 0.0) {
            return Err(NEGATIVE_VALUE);
        }
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

    // Axis words.
    let axis_words: Vec<Option<f64>> = axes.iter().map(|&a| v(a)).collect();
    let has_axis = axis_words.iter().any(Option::is_some);
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

    // Which value words the block uses (GRBL errors on the rest with 36).
    let mut used = [false; 26];
    for c in ['F', 'N', 'S', 'T'] {
        used[(c as u8 - b'A') as usize] = true;
    }
    let mut use_word = |c: char| used[(c as u8 - b'A') as usize] = true;

    let n = axes.len();
    let wco = new.wco();
    let to_target = |pos: &[f64], incremental: bool, machine: bool| -> Vec<f64> {
        (0..n)
            .map(|k| match axis_words[k] {
                Some(x) => {
                    let mm = x * unit;
                    if incremental {
                        pos[k] + mm
                    } else if machine {
                        mm
                    } else {
                        mm + wco[k]
                    }
                }
                None => pos[k],
            })
            .collect()
    };

    match non_modal {
        NonModal::Dwell => {
            let p = v('P').ok_or(VALUE_WORD_MISSING)?;
            use_word('P');
            action.dwell_s = Some(p);
            action.sync = true;
        }
        NonModal::SetCoord => {
            let (l, p) = (
                v('L').ok_or(VALUE_WORD_MISSING)?,
                v('P').ok_or(VALUE_WORD_MISSING)?,
            );
            use_word('L');
            use_word('P');
            if l.fract() != 0.0 || p.fract() != 0.0 {
                return Err(COMMAND_VALUE_NOT_INTEGER);
            }
            if !(l == 2.0 || l == 20.0) || p > 6.0 {
                return Err(UNSUPPORTED_COMMAND);
            }
            if !has_axis {
                return Err(NO_AXIS_WORDS);
            }
            let idx = if p == 0.0 { new.coord } else { p as usize - 1 };
            for (k, w) in axis_words.iter().enumerate() {
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
            for (k, w) in axis_words.iter().enumerate() {
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
                let mid = to_target(&pos, new.incremental, false);
                push_line(&mut action, &pos, &mid, Speed::Rapid);
                pos = mid;
            }
            let home = vec![0.0; n];
            push_line(&mut action, &pos, &home, Speed::Rapid);
            new.position = home;
            action.sync = true;
        }
        NonModal::None => {}
    }

    if motion_uses_axes
        || (matches!(new.motion, MotionMode::ArcCw | MotionMode::ArcCcw)
            && explicit_motion
            && !uses_axes)
    {
        let start = new.position.clone();
        let target = to_target(&start, new.incremental, absolute_override);
        let feed_speed = || -> Result<Speed, u8> {
            if new.feed_mm_min <= 0.0 {
                return Err(UNDEFINED_FEED_RATE);
            }
            Ok(Speed::Feed(new.feed_mm_min / 60.0))
        };
        match new.motion {
            MotionMode::Rapid => push_line(&mut action, &start, &target, Speed::Rapid),
            MotionMode::Linear => {
                let speed = feed_speed()?;
                push_line(&mut action, &start, &target, speed);
            }
            MotionMode::ArcCw | MotionMode::ArcCcw => {
                let speed = feed_speed()?;
                if !has_axis {
                    return Err(NO_AXIS_WORDS);
                }
                let (a0, a1, lin) = match new.plane {
                    0 => ('X', 'Y', 'Z'),
                    1 => ('Z', 'X', 'Y'),
                    _ => ('Y', 'Z', 'X'),
                };
                let idx = |c: char| axes.iter().position(|&a| a == c);
                let (Some(i0), Some(i1)) = (idx(a0), idx(a1)) else {
                    return Err(UNSUPPORTED_COMMAND);
                };
                if axis_words[i0].is_none() && axis_words[i1].is_none() {
                    return Err(NO_AXIS_WORDS_IN_PLANE);
                }
                let off_letter = |c: char| match c {
                    'X' => 'I',
                    'Y' => 'J',
                    _ => 'K',
                };
                let x = target[i0] - start[i0];
                let y = target[i1] - start[i1];
                let (o0, o1);
                if let Some(r_word) = v('R') {
                    use_word('R');
                    if x == 0.0 && y == 0.0 {
                        return Err(INVALID_TARGET);
                    }
                    let mut r = r_word * unit;
                    let mut h = 4.0 * r * r - x * x - y * y;
                    if h < 0.0 {
                        return Err(ARC_RADIUS_ERROR);
                    }
                    h = -h.sqrt() / x.hypot(y);
                    if new.motion == MotionMode::ArcCcw {
                        h = -h;
                    }
                    if r < 0.0 {
                        h = -h;
                        r = -r;
                    }
                    let _ = r;
                    o0 = 0.5 * (x - y * h);
                    o1 = 0.5 * (y + x * h);
                } else {
                    let (w0, w1) = (v(off_letter(a0)), v(off_letter(a1)));
                    if w0.is_none() && w1.is_none() {
                        return Err(NO_OFFSETS_IN_PLANE);
                    }
                    use_word(off_letter(a0));
                    use_word(off_letter(a1));
                    o0 = w0.unwrap_or(0.0) * unit;
                    o1 = w1.unwrap_or(0.0) * unit;
                    let r_start = o0.hypot(o1);
                    let r_end = (x - o0).hypot(y - o1);
                    let delta = (r_end - r_start).abs();
                    if delta > 0.005 && (delta > 0.5 || delta > 0.001 * r_start) {
                        return Err(INVALID_TARGET);
                    }
                }
                let radius = o0.hypot(o1);
                let (rs0, rs1) = (-o0, -o1);
                let (rt0, rt1) = (x - o0, y - o1);
                let mut travel = (rs0 * rt1 - rs1 * rt0).atan2(rs0 * rt0 + rs1 * rt1);
                const EPS: f64 = 5e-7;
                if new.motion == MotionMode::ArcCw {
                    if travel >= -EPS {
                        travel -= 2.0 * PI;
                    }
                } else if travel <= EPS {
                    travel += 2.0 * PI;
                }
                let linear = idx(lin).map_or(0.0, |k| target[k] - start[k]);
                let others: f64 = (0..n)
                    .filter(|&k| k != i0 && k != i1 && Some(k) != idx(lin))
                    .map(|k| (target[k] - start[k]).powi(2))
                    .sum();
                let length = ((travel.abs() * radius).powi(2) + linear * linear + others).sqrt();
                push_move(&mut action, target.clone(), length, speed);
            }
            MotionMode::Cancel => {}
        }
        new.position = target;
    }
    if new.inverse_time {
        // F is the reciprocal of the move's duration in minutes, for every feed move.
        for m in &mut action.moves {
            if let Speed::Feed(_) = m.speed {
                m.speed = Speed::Feed(m.length_mm * new.feed_mm_min / 60.0);
            }
        }
    }
    for (k, c) in (b'A'..=b'Z').enumerate() {
        let c = c as char;
        if vals[k].is_some() && !used[k] && !axes.contains(&c) {
            return Err(UNUSED_WORDS);
        }
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

fn push_line(action: &mut Action, from: &[f64], to: &[f64], speed: Speed) {
    let length = from
        .iter()
        .zip(to)
        .map(|(a, b)| (b - a).powi(2))
        .sum::<f64>()
        .sqrt();
    push_move(action, to.to_vec(), length, speed);
}

fn push_move(action: &mut Action, target: Vec<f64>, length_mm: f64, speed: Speed) {
    if length_mm > 1e-9 {
        action.moves.push(Move {
            target,
            length_mm,
            speed,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const XYZ: [char; 3] = ['X', 'Y', 'Z'];

    fn run(modal: &Modal, line: &str) -> Result<(Modal, Action), u8> {
        execute(modal, line, &XYZ, false)
    }

    #[test]
    fn error_codes_match_grbl() {
        let m = Modal::new(3, vec![0.0; 3]);
        assert_eq!(run(&m, "G1X10").unwrap_err(), 22, "G1 with no feed yet");
        assert_eq!(run(&m, "G5X1").unwrap_err(), 20);
        assert_eq!(run(&m, "G0G1X1").unwrap_err(), 21);
        assert_eq!(run(&m, "G0X1X2").unwrap_err(), 25);
        assert_eq!(run(&m, "1X").unwrap_err(), 1);
        assert_eq!(run(&m, "G0X").unwrap_err(), 2);
        assert_eq!(run(&m, "G1X1F-5").unwrap_err(), 4);
        assert_eq!(run(&m, "G4").unwrap_err(), 28);
        assert_eq!(run(&m, "G0X1P2").unwrap_err(), 36);
        assert_eq!(run(&m, "G2X1F100").unwrap_err(), 35);
        assert_eq!(run(&m, "G2Z1I1F100").unwrap_err(), 32);
        assert_eq!(run(&m, "G80X1").unwrap_err(), 31);
        assert_eq!(run(&m, "G53G2X1I1F10").unwrap_err(), 30);
        assert_eq!(run(&m, "G59.1").unwrap_err(), 29);
        assert_eq!(run(&m, "M3.5").unwrap_err(), 23);
        assert_eq!(
            run(&m, "G0U1").unwrap_err(),
            20,
            "no U axis on a 3-axis GRBL"
        );
        assert_eq!(run(&m, "T300").unwrap_err(), 38);
        assert_eq!(run(&m, "G2X10Y0R4F100").unwrap_err(), 34);
        assert_eq!(run(&m, "G2X10Y0I1J0F100").unwrap_err(), 33);
    }

    #[test]
    fn moves_arcs_and_inverse_time() {
        let m = Modal::new(3, vec![0.0; 3]);
        let (m, a) = run(&m, "G21G90G1X3Y4F600").unwrap();
        assert_eq!(a.moves.len(), 1);
        assert!((a.moves[0].length_mm - 5.0).abs() < 1e-12);
        assert_eq!(a.moves[0].speed, Speed::Feed(10.0));
        // Half circle of radius 5 from (3,4) about (3,-1): length 5*pi.
        let (m, a) = run(&m, "G2X3Y-6I0J-5").unwrap();
        assert!(
            (a.moves[0].length_mm - 5.0 * PI).abs() < 1e-9,
            "{:?}",
            a.moves
        );
        // Full circle when start == end.
        let (m, a) = run(&m, "G3X3Y-6I0J5").unwrap();
        assert!((a.moves[0].length_mm - 10.0 * PI).abs() < 1e-9);
        // G93: F = 1/minutes; a 10 mm move with F6 takes 10 s: 1 mm/s.
        let (m, a) = run(&m, "G93G1X13Y-6F6").unwrap();
        assert_eq!(a.moves[0].speed, Speed::Feed(1.0));
        assert_eq!(
            run(&m, "G1X0").unwrap_err(),
            22,
            "G93 needs F on every move"
        );
        // Back to G94 the feed is undefined until given.
        assert_eq!(run(&m, "G94G1X0").unwrap_err(), 22);
        let (m, a) = run(&m, "G20G91G0X1").unwrap();
        assert!((a.moves[0].target[0] - (13.0 + 25.4)).abs() < 1e-9);
        assert_eq!(m.gc_report(), "G0 G54 G17 G20 G91 G93 M5 M9 T0 F0 S0");
        let (_, a) = run(&m, "M3S1000").unwrap();
        assert!(a.sync);
        let (_, a) = run(&m, "G4P0.5").unwrap();
        assert_eq!(a.dwell_s, Some(0.5));
    }

    #[test]
    fn extra_axes_when_configured() {
        let axes = ['X', 'Y', 'U', 'V'];
        let m = Modal::new(4, vec![0.0; 4]);
        let (_, a) = execute(&m, "G1X3Y0U0V4F60", &axes, false).unwrap();
        assert!((a.moves[0].length_mm - 5.0).abs() < 1e-12);
    }

    #[test]
    fn jog_rules() {
        let m = Modal::new(3, vec![0.0; 3]);
        let (kept, a) = execute(&m, "G91X10F600", &XYZ, true).unwrap();
        assert_eq!(a.moves.len(), 1);
        assert!(!kept.incremental, "jog leaves modal state alone");
        assert_eq!(kept.position, vec![10.0, 0.0, 0.0]);
        assert_eq!(execute(&m, "G91X10", &XYZ, true).unwrap_err(), 22);
        assert_eq!(execute(&m, "G0X10F10", &XYZ, true).unwrap_err(), 16);
    }
}
