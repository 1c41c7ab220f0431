//! What the simulator records for its handle: the executed-line log, notable events and
//! machine snapshots.

use crate::protocol::{MachineState, Realtime};

use super::ParserState;

/// One line the simulated machine executed.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecutedLine {
    /// The line as received (without its `\n`).
    pub text: String,
    /// G-code line count when it was received (1-based, see [`Faults`](super::Faults)).
    pub seq: u64,
    /// Connection it came in on (1 for the first).
    pub connection: u64,
    /// Simulated time it took effect (s).
    pub at_s: f64,
    /// The parser's state right after the line (what `$G` would have said then).
    pub parser: ParserState,
}

/// Something notable that happened in the simulator, with its simulated time (s).
#[derive(Debug, Clone, PartialEq)]
pub enum SimEvent {
    /// A host connected.
    Connected {
        /// Connection number.
        connection: u64,
        /// Time (s).
        at_s: f64,
    },
    /// The connection closed (host side or an injected drop).
    Disconnected {
        /// Connection number.
        connection: u64,
        /// True for an injected link drop.
        injected: bool,
        /// Time (s).
        at_s: f64,
    },
    /// The controller froze ([`Faults::freeze_at_line`](super::Faults::freeze_at_line)):
    /// from here until the next host attaches it reads and answers nothing.
    Frozen {
        /// Connection that froze.
        connection: u64,
        /// Time (s).
        at_s: f64,
    },
    /// A byte arrived while the RX ring was full and was lost.
    RxOverflow {
        /// The lost byte.
        byte: u8,
        /// Time (s).
        at_s: f64,
    },
    /// A real-time command arrived.
    Realtime {
        /// Which one.
        command: Realtime,
        /// State when it arrived.
        state: MachineState,
        /// Time (s).
        at_s: f64,
    },
    /// A feed hold finished decelerating (`Hold:0`).
    HoldComplete {
        /// Time (s).
        at_s: f64,
    },
    /// The controller answered `error:code` to a line.
    Error {
        /// The line as received.
        line: String,
        /// Error code.
        code: u8,
        /// Time (s).
        at_s: f64,
    },
    /// The controller raised `ALARM:code`.
    Alarm {
        /// Alarm code.
        code: u8,
        /// Time (s).
        at_s: f64,
    },
    /// A soft reset was carried out.
    Reset {
        /// True when the machine was moving (`ALARM:3` follows).
        in_motion: bool,
        /// Time (s).
        at_s: f64,
    },
    /// A hardware reset: a host attached to a board that resets when its port opens
    /// ([`OnConnect::Reset`](super::OnConnect::Reset)).
    HardwareReset {
        /// Time (s).
        at_s: f64,
    },
    /// A `$` line reached the line buffer (GRBL executes it as a system command: settings,
    /// startup blocks, homing, jogging, ...).
    SystemCommand {
        /// The line as received.
        line: String,
        /// Time (s).
        at_s: f64,
    },
}

/// A snapshot of the simulated machine.
#[derive(Debug, Clone, PartialEq)]
pub struct SimSnapshot {
    /// Simulated time of the snapshot (s).
    pub at_s: f64,
    /// State as a status report would give it.
    pub state: MachineState,
    /// Machine position (mm).
    pub position: Vec<f64>,
    /// Planner blocks in use.
    pub planner_used: usize,
    /// Bytes waiting in the RX ring.
    pub rx_used: usize,
    /// Whether a host is connected.
    pub connected: bool,
    /// The controller is frozen ([`Faults::freeze_at_line`](super::Faults::freeze_at_line)).
    pub frozen: bool,
    /// Spindle (heat) on.
    pub spindle_on: bool,
    /// Executed lines so far.
    pub executed: usize,
    /// G-code lines received so far.
    pub received: u64,
}

#[derive(Debug, Default)]
pub(super) struct Record {
    pub(super) log: Vec<ExecutedLine>,
    pub(super) events: Vec<SimEvent>,
    pub(super) rx_high_water: usize,
    pub(super) overflow_bytes: u64,
    /// The parser's state now.
    pub(super) parser: ParserState,
}
