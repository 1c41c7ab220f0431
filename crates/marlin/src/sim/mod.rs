//! A Marlin 2.1 protocol simulator: a tokio task that answers on the wire as a Marlin printer
//! does, with heaters, a planner and Marlin's failure modes.
//!
//! What it models:
//! - **The command queue** (`BUFSIZE` 4) fed from a 128-byte RX buffer by
//!   `get_serial_commands`: numbered lines are checked (`N` = last + 1, checksum); a bad line
//!   gets `Error:…, Last Line: n`, the RX buffer is emptied, then `Resend: n+1` and `ok`.
//!   `M110 N<n>` sets the line number. A line arriving while the RX buffer is full is lost.
//! - **`ok` per command** once its handler returns: a move once it is in the planner (16
//!   blocks), `M400` once the planner is empty, `M109`/`M190` once the temperature settled in
//!   its window for the residency time, with a wait report (` T:… /… B:… /… @:… B@:… W:…`)
//!   every second. `M105` answers `ok T:… /… B:… /… @:… B@:…`; `M114` the position.
//! - **Host keepalive**: `echo:busy: processing` every 2 s while a handler blocks.
//! - **Heaters**: a first-order model with Marlin's thermal protection (`heater`): heating
//!   watch, thermal runaway, MINTEMP, MAXTEMP each end in `kill()`.
//! - **EMERGENCY_PARSER**: `M108` ends a heating wait, `M112` kills, `M410` drops the planner,
//!   as the bytes arrive.
//! - **`kill()`**: heaters off, `Error:Printer halted. kill() called!`, then nothing is read
//!   until a reset (a new connection with [`OnConnect::Reset`], or [`SimHandle::reset`]).
//! - **A new host**: an 8-bit board resets when its port opens (DTR), printing `start`; a board
//!   on native USB or a network bridge does not ([`OnConnect`]).
//! - **HOTEND_IDLE_TIMEOUT** (optional): heaters off after a time with no command or motion.
//! - **Faults** ([`Faults`]): link drops, line noise (a flipped bit → checksum error), a frozen
//!   board, a heater that loses power, an open thermistor.
//!
//! Simulated time runs at `time_scale` times tokio's clock.

mod firmware;
pub mod heater;
mod link;

pub use heater::ThermalError;
pub use link::SimHandle;

use crate::protocol::HeaterReading;

/// What a newly connected host sees.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnConnect {
    /// A reset (8-bit boards: opening the port pulls DTR): heaters off, `start`.
    Reset,
    /// Nothing: the printer keeps doing what it did.
    Silent,
}

/// Faults to inject; line positions count received lines since the simulator started (1-based).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Faults {
    /// Close the link when these lines arrive (the line is lost).
    pub drop_at_lines: Vec<u64>,
    /// Flip a bit in these lines (line noise): the checksum no longer matches.
    pub corrupt_at_lines: Vec<u64>,
    /// Freeze (read and answer nothing, heaters as they were) from this line on.
    pub freeze_at_line: Option<u64>,
    /// The hotend heater loses power at this line (thermal protection trips).
    pub heater_fail_at_line: Option<u64>,
    /// The hotend thermistor opens at this line (MINTEMP).
    pub thermistor_open_at_line: Option<u64>,
}

/// The simulator's settings (Marlin 2.1's stock `Configuration.h`/`_adv.h` values).
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Simulated seconds per real second.
    pub time_scale: f64,
    /// `BUFSIZE`: commands in the queue.
    pub bufsize: usize,
    /// The serial RX buffer (`RX_BUFFER_SIZE`), bytes.
    pub rx_buffer_bytes: usize,
    /// `BLOCK_BUFFER_SIZE`: planner blocks.
    pub block_buffer_size: usize,
    /// What a new host sees.
    pub on_connect: OnConnect,
    /// `DEFAULT_KEEPALIVE_INTERVAL`, s.
    pub keepalive_interval_s: f64,
    /// `TEMP_RESIDENCY_TIME`, s.
    pub temp_residency_s: f64,
    /// `TEMP_BED_RESIDENCY_TIME`, s.
    pub bed_residency_s: f64,
    /// `TEMP_WINDOW` (and the bed's), K.
    pub temp_window_k: f64,
    /// `TEMP_HYSTERESIS`, K.
    pub temp_hysteresis_k: f64,
    /// `HOTEND_IDLE_TIMEOUT_SEC`, if enabled.
    pub hotend_idle_timeout_s: Option<f64>,
    /// The fastest move, mm/s (`DEFAULT_MAX_FEEDRATE`).
    pub max_feed_mm_s: f64,
    /// Faults to inject.
    pub faults: Faults,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            time_scale: 1.0,
            bufsize: 4,
            rx_buffer_bytes: 128,
            block_buffer_size: 16,
            on_connect: OnConnect::Reset,
            keepalive_interval_s: 2.0,
            temp_residency_s: 10.0,
            bed_residency_s: 10.0,
            temp_window_k: 1.0,
            temp_hysteresis_k: 3.0,
            hotend_idle_timeout_s: None,
            max_feed_mm_s: 150.0,
            faults: Faults::default(),
        }
    }
}

/// Something the simulator did, for tests and the operator.
#[derive(Debug, Clone, PartialEq)]
pub enum SimEvent {
    /// A reset (`start`).
    Reset,
    /// A new connection.
    Connected,
    /// `kill()` ran.
    Killed {
        /// Why.
        reason: String,
    },
    /// Thermal protection tripped.
    Thermal {
        /// The bed (else the hotend).
        bed: bool,
        /// Which check.
        error: ThermalError,
        /// When, simulated s.
        at_s: f64,
    },
    /// `Resend:` was asked.
    ResendRequested {
        /// The line asked for.
        line: u64,
        /// The error.
        why: String,
    },
    /// A line was lost to a full RX buffer.
    RxOverflow {
        /// Received-line count.
        at_line: u64,
    },
    /// A fault dropped the link.
    LinkDropped {
        /// Received-line count.
        at_line: u64,
    },
    /// A fault corrupted a line.
    Corrupted {
        /// Received-line count.
        at_line: u64,
    },
    /// A fault froze the board.
    Frozen {
        /// Received-line count.
        at_line: u64,
    },
    /// An emergency-parser command acted.
    Emergency(String),
    /// HOTEND_IDLE_TIMEOUT switched the heaters off.
    IdleTimeout {
        /// When, simulated s.
        at_s: f64,
    },
}

/// The simulator's state at one moment.
#[derive(Debug, Clone, PartialEq)]
pub struct SimSnapshot {
    /// Simulated time, s.
    pub now_s: f64,
    /// The hotend (reading and target).
    pub hotend: HeaterReading,
    /// The bed.
    pub bed: HeaterReading,
    /// The kill reason, while halted.
    pub halted: Option<String>,
    /// The last accepted line number.
    pub last_line_number: i64,
    /// Blocks in the planner.
    pub planned_blocks: usize,
    /// A handler runs, or commands wait.
    pub busy: bool,
    /// Stepper position X, Y, Z, E.
    pub position: [f64; 4],
    /// Moves completed.
    pub moves_done: u64,
    /// Commands processed.
    pub commands_executed: usize,
    /// Feed and flow override, %.
    pub overrides: (f64, f64),
}

/// Starts a simulator (no link yet: [`SimHandle::listen_tcp`], [`SimHandle::attach`]). Must be
/// called inside a tokio runtime. It powers up as after a reset.
pub fn start(config: SimConfig) -> SimHandle {
    let mut fw = firmware::Firmware::new(config);
    fw.reset();
    fw.out.clear();
    link::spawn(fw)
}
