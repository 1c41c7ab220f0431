//! GRBL 1.1 wire protocol: real-time command bytes, response and push-message parsing, real-time
//! status reports, and the error and alarm code tables with GRBL 1.1's own texts.
//!
//! Everything here is pure: no I/O, no clock. Lines arrive without their `\r\n`.

use std::fmt;

/// Size of GRBL 1.1's serial receive ring buffer (`RX_BUFFER_SIZE`, AVR build), in bytes.
///
/// The ring keeps one slot empty, so at most `RX_BUFFER_SIZE - 1` = 127 bytes can wait in it.
pub const RX_BUFFER_SIZE: usize = 128;

/// GRBL 1.1's line buffer (`LINE_BUFFER_SIZE`): a line may hold at most 79 characters once
/// spaces and comments are removed; a longer one is answered with `error:11`.
pub const LINE_BUFFER_SIZE: usize = 80;

/// Usable planner blocks in GRBL 1.1 on an AVR (`BLOCK_BUFFER_SIZE` 16, one slot kept empty).
pub const PLANNER_BLOCKS: usize = 15;

/// A GRBL 1.1 real-time command: one byte, picked off the serial stream as it arrives, never
/// stored in the RX buffer and never answered with `ok`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Realtime {
    /// `?`: ask for a real-time status report.
    StatusQuery,
    /// `!`: feed hold (controlled deceleration to a stop; position kept).
    FeedHold,
    /// `~`: cycle start / resume from a hold.
    CycleStart,
    /// 0x18 (Ctrl-X): soft reset. Flushes the RX buffer and the planner; an `ALARM:3` follows when
    /// the machine was moving.
    SoftReset,
    /// 0x84: safety door.
    SafetyDoor,
    /// 0x85: jog cancel (decelerate and flush the jog blocks).
    JogCancel,
    /// 0x90: feed override back to 100 %.
    FeedOverrideReset,
    /// 0x91: feed override +10 %.
    FeedOverridePlus10,
    /// 0x92: feed override -10 %.
    FeedOverrideMinus10,
    /// 0x93: feed override +1 %.
    FeedOverridePlus1,
    /// 0x94: feed override -1 %.
    FeedOverrideMinus1,
    /// 0x95: rapid override 100 %.
    RapidOverride100,
    /// 0x96: rapid override 50 %.
    RapidOverride50,
    /// 0x97: rapid override 25 %.
    RapidOverride25,
    /// 0x99: spindle override back to 100 %.
    SpindleOverrideReset,
    /// 0x9A: spindle override +10 %.
    SpindleOverridePlus10,
    /// 0x9B: spindle override -10 %.
    SpindleOverrideMinus10,
    /// 0x9C: spindle override +1 %.
    SpindleOverridePlus1,
    /// 0x9D: spindle override -1 %.
    SpindleOverrideMinus1,
    /// 0x9E: toggle spindle stop (only acted on during a hold).
    SpindleStopToggle,
    /// 0xA0: toggle flood coolant.
    FloodToggle,
    /// 0xA1: toggle mist coolant.
    MistToggle,
}

impl Realtime {
    /// Every real-time command, in byte order.
    pub const ALL: [Realtime; 22] = [
        Realtime::SoftReset,
        Realtime::FeedHold,
        Realtime::StatusQuery,
        Realtime::CycleStart,
        Realtime::SafetyDoor,
        Realtime::JogCancel,
        Realtime::FeedOverrideReset,
        Realtime::FeedOverridePlus10,
        Realtime::FeedOverrideMinus10,
        Realtime::FeedOverridePlus1,
        Realtime::FeedOverrideMinus1,
        Realtime::RapidOverride100,
        Realtime::RapidOverride50,
        Realtime::RapidOverride25,
        Realtime::SpindleOverrideReset,
        Realtime::SpindleOverridePlus10,
        Realtime::SpindleOverrideMinus10,
        Realtime::SpindleOverridePlus1,
        Realtime::SpindleOverrideMinus1,
        Realtime::SpindleStopToggle,
        Realtime::FloodToggle,
        Realtime::MistToggle,
    ];

    /// The byte sent on the wire.
    pub fn byte(self) -> u8 {
        match self {
            Realtime::StatusQuery => b'?',
            Realtime::FeedHold => b'!',
            Realtime::CycleStart => b'~',
            Realtime::SoftReset => 0x18,
            Realtime::SafetyDoor => 0x84,
            Realtime::JogCancel => 0x85,
            Realtime::FeedOverrideReset => 0x90,
            Realtime::FeedOverridePlus10 => 0x91,
            Realtime::FeedOverrideMinus10 => 0x92,
            Realtime::FeedOverridePlus1 => 0x93,
            Realtime::FeedOverrideMinus1 => 0x94,
            Realtime::RapidOverride100 => 0x95,
            Realtime::RapidOverride50 => 0x96,
            Realtime::RapidOverride25 => 0x97,
            Realtime::SpindleOverrideReset => 0x99,
            Realtime::SpindleOverridePlus10 => 0x9A,
            Realtime::SpindleOverrideMinus10 => 0x9B,
            Realtime::SpindleOverridePlus1 => 0x9C,
            Realtime::SpindleOverrideMinus1 => 0x9D,
            Realtime::SpindleStopToggle => 0x9E,
            Realtime::FloodToggle => 0xA0,
            Realtime::MistToggle => 0xA1,
        }
    }

    /// The command a byte stands for, if it is a real-time byte.
    pub fn from_byte(byte: u8) -> Option<Realtime> {
        Realtime::ALL.into_iter().find(|r| r.byte() == byte)
    }
}

/// Which override a sequence of real-time bytes adjusts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OverrideKind {
    /// Feed override (10-200 %).
    Feed,
    /// Spindle override (10-200 %).
    Spindle,
}

/// The real-time bytes that take an override from `current_pct` to `target_pct` (clamped to
/// GRBL's 10-200 %): a reset to 100 when that is shorter, then ±10 steps, then ±1 steps.
pub fn override_steps(kind: OverrideKind, current_pct: u16, target_pct: u16) -> Vec<Realtime> {
    let target = target_pct.clamp(10, 200) as i32;
    let mut cur = current_pct.clamp(10, 200) as i32;
    let (reset, p10, m10, p1, m1) = match kind {
        OverrideKind::Feed => (
            Realtime::FeedOverrideReset,
            Realtime::FeedOverridePlus10,
            Realtime::FeedOverrideMinus10,
            Realtime::FeedOverridePlus1,
            Realtime::FeedOverrideMinus1,
        ),
        OverrideKind::Spindle => (
            Realtime::SpindleOverrideReset,
            Realtime::SpindleOverridePlus10,
            Realtime::SpindleOverrideMinus10,
            Realtime::SpindleOverridePlus1,
            Realtime::SpindleOverrideMinus1,
        ),
    };
    let cost = |from: i32| {
        let d = (target - from).abs();
        d / 10 + d % 10
    };
    let mut out = Vec::new();
    if cur != 100 && 1 + cost(100) < cost(cur) {
        out.push(reset);
        cur = 100;
    }
    while (target - cur).abs() >= 10 {
        if target > cur {
            out.push(p10);
            cur += 10;
        } else {
            out.push(m10);
            cur -= 10;
        }
    }
    while cur != target {
        if target > cur {
            out.push(p1);
            cur += 1;
        } else {
            out.push(m1);
            cur -= 1;
        }
    }
    out
}

/// GRBL 1.1 error codes: (code, short message, description), from GRBL's
/// `doc/csv/error_codes_en_US.csv`.
pub const ERROR_CODES: &[(u8, &str, &str)] = &[
    (1, "Expected command letter", "G-code words consist of a letter and a value. Letter was not found."),
    (2, "Bad number format", "Missing the expected G-code word value or numeric value format is not valid."),
    (3, "Invalid statement", "Grbl '$' system command was not recognized or supported."),
    (4, "Value < 0", "Negative value received for an expected positive value."),
    (5, "Setting disabled", "Homing cycle failure. Homing is not enabled via settings."),
    (6, "Value < 3 usec", "Minimum step pulse time must be greater than 3usec."),
    (7, "EEPROM read fail. Using defaults", "An EEPROM read failed. Auto-restoring affected EEPROM to default values."),
    (8, "Not idle", "Grbl '$' command cannot be used unless Grbl is IDLE. Ensures smooth operation during a job."),
    (9, "G-code lock", "G-code commands are locked out during alarm or jog state."),
    (10, "Homing not enabled", "Soft limits cannot be enabled without homing also enabled."),
    (11, "Line overflow", "Max characters per line exceeded. Received command line was not executed."),
    (12, "Step rate > 30kHz", "Grbl '$' setting value cause the step rate to exceed the maximum supported."),
    (13, "Check Door", "Safety door detected as opened and door state initiated."),
    (14, "Line length exceeded", "Build info or startup line exceeded EEPROM line length limit. Line not stored."),
    (15, "Travel exceeded", "Jog target exceeds machine travel. Jog command has been ignored."),
    (16, "Invalid jog command", "Jog command has no '=' or contains prohibited g-code."),
    (17, "Setting disabled", "Laser mode requires PWM output."),
    (20, "Unsupported command", "Unsupported or invalid g-code command found in block."),
    (21, "Modal group violation", "More than one g-code command from same modal group found in block."),
    (22, "Undefined feed rate", "Feed rate has not yet been set or is undefined."),
    (23, "Invalid gcode ID:23", "G-code command in block requires an integer value."),
    (24, "Invalid gcode ID:24", "More than one g-code command that requires axis words found in block."),
    (25, "Invalid gcode ID:25", "Repeated g-code word found in block."),
    (26, "Invalid gcode ID:26", "No axis words found in block for g-code command or current modal state which requires them."),
    (27, "Invalid gcode ID:27", "Line number value is invalid."),
    (28, "Invalid gcode ID:28", "G-code command is missing a required value word."),
    (29, "Invalid gcode ID:29", "G59.x work coordinate systems are not supported."),
    (30, "Invalid gcode ID:30", "G53 only allowed with G0 and G1 motion modes."),
    (31, "Invalid gcode ID:31", "Axis words found in block when no command or current modal state uses them."),
    (32, "Invalid gcode ID:32", "G2 and G3 arcs require at least one in-plane axis word."),
    (33, "Invalid gcode ID:33", "Motion command target is invalid."),
    (34, "Invalid gcode ID:34", "Arc radius value is invalid."),
    (35, "Invalid gcode ID:35", "G2 and G3 arcs require at least one in-plane offset word."),
    (36, "Invalid gcode ID:36", "Unused value words found in block."),
    (37, "Invalid gcode ID:37", "G43.1 dynamic tool length offset is not assigned to configured tool length axis."),
    (38, "Invalid gcode ID:38", "Tool number greater than max supported value."),
];

/// GRBL 1.1 alarm codes: (code, short message, description), from GRBL's
/// `doc/csv/alarm_codes_en_US.csv`.
pub const ALARM_CODES: &[(u8, &str, &str)] = &[
    (1, "Hard limit", "Hard limit has been triggered. Machine position is likely lost due to sudden halt. Re-homing is highly recommended."),
    (2, "Soft limit", "Soft limit alarm. G-code motion target exceeds machine travel. Machine position retained. Alarm may be safely unlocked."),
    (3, "Abort during cycle", "Reset while in motion. Machine position is likely lost due to sudden halt. Re-homing is highly recommended."),
    (4, "Probe fail", "Probe fail. Probe is not in the expected initial state before starting probe cycle when G38.2 and G38.3 is not triggered and G38.4 and G38.5 is triggered."),
    (5, "Probe fail", "Probe fail. Probe did not contact the workpiece within the programmed travel for G38.2 and G38.4."),
    (6, "Homing fail", "Homing fail. The active homing cycle was reset."),
    (7, "Homing fail", "Homing fail. Safety door was opened during homing cycle."),
    (8, "Homing fail", "Homing fail. Pull off travel failed to clear limit switch. Try increasing pull-off setting or check wiring."),
    (9, "Homing fail", "Homing fail. Could not find limit switch within search distances. Try increasing max travel, decreasing pull-off distance, or check wiring."),
];

/// GRBL 1.1's short message for `error:code` (`"Unknown error"` for a code not in the table).
pub fn error_message(code: u8) -> &'static str {
    ERROR_CODES
        .iter()
        .find(|(c, _, _)| *c == code)
        .map_or("Unknown error", |(_, m, _)| m)
}

/// GRBL 1.1's description of `error:code` (empty for a code not in the table).
pub fn error_description(code: u8) -> &'static str {
    ERROR_CODES
        .iter()
        .find(|(c, _, _)| *c == code)
        .map_or("", |(_, _, d)| d)
}

/// GRBL 1.1's short message for `ALARM:code` (`"Unknown alarm"` for a code not in the table).
pub fn alarm_message(code: u8) -> &'static str {
    ALARM_CODES
        .iter()
        .find(|(c, _, _)| *c == code)
        .map_or("Unknown alarm", |(_, m, _)| m)
}

/// GRBL 1.1's description of `ALARM:code` (empty for a code not in the table).
pub fn alarm_description(code: u8) -> &'static str {
    ALARM_CODES
        .iter()
        .find(|(c, _, _)| *c == code)
        .map_or("", |(_, _, d)| d)
}

/// The machine state word that opens a status report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MachineState {
    /// `Idle`.
    Idle,
    /// `Run`: executing motion.
    Run,
    /// `Hold:0` (hold complete, ready to resume) or `Hold:1` (decelerating).
    Hold(u8),
    /// `Jog`.
    Jog,
    /// `Alarm`: locked out until `$X`, `$H` or a reset.
    Alarm,
    /// `Door:n`: safety door states 0-3.
    Door(u8),
    /// `Check`: G-code check mode (`$C`).
    Check,
    /// `Home`: homing cycle.
    Home,
    /// `Sleep`.
    Sleep,
}

impl MachineState {
    /// Parses `Idle`, `Run`, `Hold:0`, `Door:2`, ... (a bare `Hold` or `Door` counts as substate 0).
    pub fn parse(s: &str) -> Option<MachineState> {
        let (word, sub) = match s.split_once(':') {
            Some((w, n)) => (w, Some(n.parse::<u8>().ok()?)),
            None => (s, None),
        };
        Some(match word {
            "Idle" => MachineState::Idle,
            "Run" => MachineState::Run,
            "Hold" => MachineState::Hold(sub.unwrap_or(0)),
            "Jog" => MachineState::Jog,
            "Alarm" => MachineState::Alarm,
            "Door" => MachineState::Door(sub.unwrap_or(0)),
            "Check" => MachineState::Check,
            "Home" => MachineState::Home,
            "Sleep" => MachineState::Sleep,
            _ => return None,
        })
    }

    /// True while the machine is (or may still be) moving: `Run`, `Jog`, `Home`, `Hold:1`.
    pub fn is_moving(self) -> bool {
        matches!(
            self,
            MachineState::Run | MachineState::Jog | MachineState::Home | MachineState::Hold(1)
        )
    }
}

impl fmt::Display for MachineState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MachineState::Idle => write!(f, "Idle"),
            MachineState::Run => write!(f, "Run"),
            MachineState::Hold(n) => write!(f, "Hold:{n}"),
            MachineState::Jog => write!(f, "Jog"),
            MachineState::Alarm => write!(f, "Alarm"),
            MachineState::Door(n) => write!(f, "Door:{n}"),
            MachineState::Check => write!(f, "Check"),
            MachineState::Home => write!(f, "Home"),
            MachineState::Sleep => write!(f, "Sleep"),
        }
    }
}

/// The `Bf:` field: free space GRBL reports in its buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BufferState {
    /// Free planner blocks (15 when empty on an AVR).
    pub planner_free: u16,
    /// Free bytes in the serial RX buffer.
    pub rx_free: u16,
}

/// The `Ov:` field: override values in percent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Overrides {
    /// Feed override (%).
    pub feed_pct: u16,
    /// Rapid override (%).
    pub rapid_pct: u16,
    /// Spindle override (%).
    pub spindle_pct: u16,
}

/// One real-time status report, `<Idle|MPos:0.000,0.000,0.000|Bf:15,128|FS:0,0>`.
///
/// Positions are in the report's units (mm unless `$13=1`). GRBL prints either `MPos` or `WPos`
/// (per `$10`) and a `WCO` only every 10-30 reports; [`StatusReport::machine_position`] and
/// [`StatusReport::work_position`] combine them with a remembered work offset.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StatusReport {
    /// The machine state (`None` only for a [`StatusReport::default`]).
    pub state: Option<MachineState>,
    /// `MPos:` machine position, one value per axis.
    pub mpos: Option<Vec<f64>>,
    /// `WPos:` work position, one value per axis.
    pub wpos: Option<Vec<f64>>,
    /// `WCO:` work coordinate offset (WPos = MPos - WCO).
    pub wco: Option<Vec<f64>>,
    /// `Bf:` planner blocks and RX bytes free.
    pub buffer: Option<BufferState>,
    /// `Ln:` line number of the executing block (only with line numbers compiled in).
    pub line_number: Option<u32>,
    /// `FS:` or `F:` current feed rate (units/min).
    pub feed: Option<f64>,
    /// `FS:` current spindle speed.
    pub spindle: Option<f64>,
    /// `Ov:` overrides.
    pub overrides: Option<Overrides>,
    /// `Pn:` active input pins (letters from `XYZPDHRS`).
    pub pins: Option<String>,
    /// `A:` accessory state (`S` spindle CW, `C` CCW, `F` flood, `M` mist).
    pub accessories: Option<String>,
    /// Fields this parser does not know, kept verbatim.
    pub other: Vec<String>,
}

impl StatusReport {
    /// The machine position: `MPos` if reported, else `WPos + wco` using this report's `WCO` or
    /// the last one seen (`last_wco`).
    pub fn machine_position(&self, last_wco: Option<&[f64]>) -> Option<Vec<f64>> {
        if let Some(m) = &self.mpos {
            return Some(m.clone());
        }
        let w = self.wpos.as_ref()?;
        let wco = self.wco.as_deref().or(last_wco)?;
        Some(w.iter().zip(wco).map(|(a, b)| a + b).collect())
    }

    /// The work position: `WPos` if reported, else `MPos - wco` using this report's `WCO` or the
    /// last one seen (`last_wco`).
    pub fn work_position(&self, last_wco: Option<&[f64]>) -> Option<Vec<f64>> {
        if let Some(w) = &self.wpos {
            return Some(w.clone());
        }
        let m = self.mpos.as_ref()?;
        let wco = self.wco.as_deref().or(last_wco)?;
        Some(m.iter().zip(wco).map(|(a, b)| a - b).collect())
    }
}

/// Why a line from GRBL could not be parsed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProtocolError {
    /// A status report is not enclosed in `<...>`.
    #[error("status report not enclosed in <>: {0:?}")]
    NotAStatusReport(String),
    /// The state word is unknown.
    #[error("unknown machine state {0:?}")]
    UnknownState(String),
    /// A field's value is not a number list of the expected shape.
    #[error("bad value in status field {field:?}: {value:?}")]
    BadField {
        /// The field name (`MPos`, `Bf`, ...).
        field: String,
        /// The value as received.
        value: String,
    },
    /// `error:` or `ALARM:` is not followed by a code number.
    #[error("bad code in {0:?}")]
    BadCode(String),
}

fn numbers(field: &str, value: &str) -> Result<Vec<f64>, ProtocolError> {
    value
        .split(',')
        .map(|v| {
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| ProtocolError::BadField {
                    field: field.to_string(),
                    value: value.to_string(),
                })
        })
        .collect()
}

fn fixed<const N: usize>(field: &str, value: &str) -> Result<[f64; N], ProtocolError> {
    let v = numbers(field, value)?;
    v.try_into().map_err(|_| ProtocolError::BadField {
        field: field.to_string(),
        value: value.to_string(),
    })
}

fn small(field: &str, value: &str, x: f64) -> Result<u16, ProtocolError> {
    if (0.0..=65535.0).contains(&x) && x.fract() == 0.0 {
        Ok(x as u16)
    } else {
        Err(ProtocolError::BadField {
            field: field.to_string(),
            value: value.to_string(),
        })
    }
}

/// Parses a real-time status report line, `<...>`.
pub fn parse_status(line: &str) -> Result<StatusReport, ProtocolError> {
    let line = line.trim();
    let body = line
        .strip_prefix('<')
        .and_then(|l| l.strip_suffix('>'))
        .ok_or_else(|| ProtocolError::NotAStatusReport(line.to_string()))?;
    let mut parts = body.split('|');
    let state_word = parts.next().unwrap_or_default();
    let state = MachineState::parse(state_word)
        .ok_or_else(|| ProtocolError::UnknownState(state_word.to_string()))?;
    let mut r = StatusReport {
        state: Some(state),
        ..StatusReport::default()
    };
    for part in parts {
        let Some((name, value)) = part.split_once(':') else {
            r.other.push(part.to_string());
            continue;
        };
        match name {
            "MPos" => r.mpos = Some(numbers(name, value)?),
            "WPos" => r.wpos = Some(numbers(name, value)?),
            "WCO" => r.wco = Some(numbers(name, value)?),
            "Bf" => {
                let [p, rx] = fixed::<2>(name, value)?;
                r.buffer = Some(BufferState {
                    planner_free: small(name, value, p)?,
                    rx_free: small(name, value, rx)?,
                });
            }
            "Ln" => {
                r.line_number = Some(value.parse().map_err(|_| ProtocolError::BadField {
                    field: name.to_string(),
                    value: value.to_string(),
                })?)
            }
            "FS" => {
                let [f, s] = fixed::<2>(name, value)?;
                r.feed = Some(f);
                r.spindle = Some(s);
            }
            "F" => {
                let [f] = fixed::<1>(name, value)?;
                r.feed = Some(f);
            }
            "Ov" => {
                let [f, ra, s] = fixed::<3>(name, value)?;
                r.overrides = Some(Overrides {
                    feed_pct: small(name, value, f)?,
                    rapid_pct: small(name, value, ra)?,
                    spindle_pct: small(name, value, s)?,
                });
            }
            "Pn" => r.pins = Some(value.to_string()),
            "A" => r.accessories = Some(value.to_string()),
            _ => r.other.push(part.to_string()),
        }
    }
    Ok(r)
}

/// One line received from GRBL, classified.
#[derive(Debug, Clone, PartialEq)]
pub enum Response {
    /// `ok`: the oldest unanswered line was accepted.
    Ok,
    /// `error:N`: the oldest unanswered line was rejected with code N.
    Error(u8),
    /// `ALARM:N`: the controller entered the alarm state.
    Alarm(u8),
    /// `<...>` real-time status report.
    Status(StatusReport),
    /// The welcome banner after a reset: `Grbl 1.1h ['$' for help]`, grblHAL's and FluidNC's
    /// ([`crate::firmware::parse_banner`]).
    Banner(crate::firmware::Banner),
    /// `[MSG:text]` feedback message; holds `text`.
    Message(String),
    /// Other bracketed push messages (`[GC:...]`, `[VER:...]`, `[OPT:...]`, `[G54:...]`,
    /// `[PRB:...]`, `[HLP:...]`, `[echo:...]`): the tag and the body.
    Feedback {
        /// The tag before the colon (`GC`, `VER`, ...).
        tag: String,
        /// Everything after the colon.
        body: String,
    },
    /// `$n=value` setting line (answer to `$$`).
    Setting {
        /// Setting number.
        number: u16,
        /// Value as printed.
        value: String,
    },
    /// `>line:ok` / `>line:error:N` startup-line echo.
    StartupLine(String),
    /// A line the protocol does not define (kept for logging); also malformed status reports.
    Other(String),
}

/// Classifies one line from GRBL (without its `\r\n`).
pub fn parse_response(line: &str) -> Response {
    let line = line.trim_matches(|c: char| c == '\r' || c == '\n' || c == ' ' || c == '\0');
    if line == "ok" {
        return Response::Ok;
    }
    if let Some(code) = line.strip_prefix("error:") {
        return match code.trim().parse::<u8>() {
            Ok(c) => Response::Error(c),
            Err(_) => Response::Other(line.to_string()),
        };
    }
    if let Some(code) = line.strip_prefix("ALARM:") {
        return match code.trim().parse::<u8>() {
            Ok(c) => Response::Alarm(c),
            Err(_) => Response::Other(line.to_string()),
        };
    }
    if line.starts_with('<') {
        return match parse_status(line) {
            Ok(s) => Response::Status(s),
            Err(_) => Response::Other(line.to_string()),
        };
    }
    if let Some(banner) = crate::firmware::parse_banner(line) {
        return Response::Banner(banner);
    }
    if let Some(inner) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
        if let Some(msg) = inner.strip_prefix("MSG:") {
            return Response::Message(msg.to_string());
        }
        if let Some((tag, body)) = inner.split_once(':') {
            return Response::Feedback {
                tag: tag.to_string(),
                body: body.to_string(),
            };
        }
        return Response::Other(line.to_string());
    }
    if let Some(rest) = line.strip_prefix('$') {
        if let Some((n, v)) = rest.split_once('=') {
            if let Ok(number) = n.parse::<u16>() {
                return Response::Setting {
                    number,
                    value: v.to_string(),
                };
            }
        }
    }
    if let Some(rest) = line.strip_prefix('>') {
        return Response::StartupLine(rest.to_string());
    }
    Response::Other(line.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_reports_from_grbl_1_1_documentation() {
        let r = parse_status("<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>").unwrap();
        assert_eq!(r.state, Some(MachineState::Idle));
        assert_eq!(r.mpos, Some(vec![0.0, 0.0, 0.0]));
        assert_eq!(r.wco, Some(vec![0.0, 0.0, 0.0]));
        assert_eq!((r.feed, r.spindle), (Some(0.0), Some(0.0)));

        let r =
            parse_status("<Run|MPos:-1.250,12.500,-3.000|Bf:15,128|FS:500,8000|Ov:100,100,100>")
                .unwrap();
        assert_eq!(r.state, Some(MachineState::Run));
        assert_eq!(r.mpos, Some(vec![-1.25, 12.5, -3.0]));
        assert_eq!(
            r.buffer,
            Some(BufferState {
                planner_free: 15,
                rx_free: 128
            })
        );
        assert_eq!((r.feed, r.spindle), (Some(500.0), Some(8000.0)));
        assert_eq!(
            r.overrides,
            Some(Overrides {
                feed_pct: 100,
                rapid_pct: 100,
                spindle_pct: 100
            })
        );

        let r =
            parse_status("<Hold:1|WPos:10.000,0.000,5.000|Bf:0,62|Ln:99999|F:500|Pn:XZP|A:SFM>")
                .unwrap();
        assert_eq!(r.state, Some(MachineState::Hold(1)));
        assert!(r.state.unwrap().is_moving());
        assert_eq!(r.wpos, Some(vec![10.0, 0.0, 5.0]));
        assert_eq!(r.line_number, Some(99999));
        assert_eq!(r.feed, Some(500.0));
        assert_eq!(r.spindle, None);
        assert_eq!(r.pins.as_deref(), Some("XZP"));
        assert_eq!(r.accessories.as_deref(), Some("SFM"));

        let r = parse_status("<Door:2|MPos:1,2,3,4|FS:0,0>").unwrap();
        assert_eq!(r.state, Some(MachineState::Door(2)));
        assert_eq!(r.mpos.unwrap().len(), 4, "4-axis (grblHAL) positions");
    }

    #[test]
    fn positions_combine_with_the_remembered_work_offset() {
        let r = parse_status("<Idle|MPos:10.000,20.000,30.000|FS:0,0>").unwrap();
        let wco = [1.0, 2.0, 3.0];
        assert_eq!(r.work_position(Some(&wco)), Some(vec![9.0, 18.0, 27.0]));
        assert_eq!(r.work_position(None), None);
        let r = parse_status("<Idle|WPos:9.000,18.000,27.000|WCO:1,2,3>").unwrap();
        assert_eq!(r.machine_position(None), Some(vec![10.0, 20.0, 30.0]));
    }

    #[test]
    fn malformed_status_reports_are_errors_not_panics() {
        assert!(matches!(
            parse_status("<Idle|MPos:0.000,abc,0.000>"),
            Err(ProtocolError::BadField { .. })
        ));
        assert!(matches!(
            parse_status("<Flying|MPos:0,0,0>"),
            Err(ProtocolError::UnknownState(_))
        ));
        assert!(parse_status("<Idle|Bf:15>").is_err());
        assert!(parse_status("<Idle|Bf:-1,3>").is_err());
        assert!(parse_status("Idle|MPos:0,0,0").is_err());
        assert!(matches!(
            parse_response("<Idle|MPos:x>"),
            Response::Other(_)
        ));
        // Unknown fields are kept.
        let r = parse_status("<Idle|MPos:0,0,0|Foo:1>").unwrap();
        assert_eq!(r.other, vec!["Foo:1".to_string()]);
    }

    #[test]
    fn responses_are_classified() {
        assert_eq!(parse_response("ok\r"), Response::Ok);
        assert_eq!(parse_response("error:22"), Response::Error(22));
        assert_eq!(parse_response("ALARM:3"), Response::Alarm(3));
        assert!(matches!(parse_response("error:x"), Response::Other(_)));
        assert_eq!(
            parse_response("Grbl 1.1h ['$' for help]"),
            Response::Banner(crate::firmware::Banner {
                firmware: crate::firmware::Firmware::Grbl,
                version: "1.1h".into()
            })
        );
        assert!(matches!(
            parse_response("GrblHAL 1.1f ['$' or '$HELP' for help]"),
            Response::Banner(b) if b.firmware == crate::firmware::Firmware::GrblHal
        ));
        assert_eq!(
            parse_response("[MSG:'$H'|'$X' to unlock]"),
            Response::Message("'$H'|'$X' to unlock".into())
        );
        assert_eq!(
            parse_response("[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]"),
            Response::Feedback {
                tag: "GC".into(),
                body: "G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0".into()
            }
        );
        assert_eq!(
            parse_response("$110=500.000"),
            Response::Setting {
                number: 110,
                value: "500.000".into()
            }
        );
        assert_eq!(
            parse_response(">G54G20:ok"),
            Response::StartupLine("G54G20:ok".into())
        );
    }

    #[test]
    fn code_tables_hold_grbl_1_1_texts() {
        assert_eq!(error_message(22), "Undefined feed rate");
        assert_eq!(error_message(20), "Unsupported command");
        assert_eq!(error_message(11), "Line overflow");
        assert_eq!(error_message(9), "G-code lock");
        assert_eq!(error_message(99), "Unknown error");
        assert_eq!(alarm_message(1), "Hard limit");
        assert_eq!(alarm_message(3), "Abort during cycle");
        assert!(alarm_description(3).starts_with("Reset while in motion."));
        assert!(error_description(36).contains("Unused value words"));
        // Codes 18 and 19 are unassigned in GRBL 1.1; the tables are sorted and unique.
        assert!(ERROR_CODES.iter().all(|(c, _, _)| *c != 18 && *c != 19));
        assert!(ERROR_CODES.windows(2).all(|w| w[0].0 < w[1].0));
        assert_eq!(ALARM_CODES.len(), 9);
    }

    #[test]
    fn realtime_bytes_round_trip() {
        for r in Realtime::ALL {
            assert_eq!(Realtime::from_byte(r.byte()), Some(r));
        }
        assert_eq!(Realtime::from_byte(b'G'), None);
        assert_eq!(Realtime::SoftReset.byte(), 0x18);
        assert_eq!(Realtime::JogCancel.byte(), 0x85);
    }

    #[test]
    fn override_steps_reach_the_target() {
        let apply = |cur: u16, steps: &[Realtime]| {
            steps.iter().fold(cur as i32, |v, s| match s {
                Realtime::FeedOverrideReset => 100,
                Realtime::FeedOverridePlus10 => v + 10,
                Realtime::FeedOverrideMinus10 => v - 10,
                Realtime::FeedOverridePlus1 => v + 1,
                Realtime::FeedOverrideMinus1 => v - 1,
                _ => unreachable!(),
            })
        };
        for (cur, target) in [
            (100, 150),
            (100, 37),
            (180, 100),
            (200, 99),
            (10, 10),
            (55, 200),
        ] {
            let s = override_steps(OverrideKind::Feed, cur, target);
            assert_eq!(apply(cur, &s), target as i32, "{cur} -> {target}: {s:?}");
        }
        assert_eq!(
            override_steps(OverrideKind::Feed, 187, 100),
            vec![Realtime::FeedOverrideReset]
        );
        assert_eq!(override_steps(OverrideKind::Feed, 100, 300).len(), 10);
    }
}
