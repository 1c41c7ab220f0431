//! A GRBL 1.1 protocol simulator: a tokio task that behaves like GRBL on the wire, and like
//! grblHAL or FluidNC where those differ in what a sender sees ([`SimFirmware`]: banners, `$I`,
//! buffer sizes, messages, when `Ov:`/`A:` are reported, what a new connection sees).
//!
//! What it models, and how faithfully:
//! - **The link.** Bytes travel at the configured baud (115 200 8N1 = 11 520 bytes/s) in both
//!   directions, plus an optional one-way latency (a USB-serial adapter's), in simulated time.
//!   A reader task drains the host's socket at once, so the socket never acts as a hidden buffer.
//! - **The RX ring** (GRBL: 128 bytes, 127 usable; grblHAL 1024; FluidNC 1200). Real-time
//!   bytes (`?`, `!`, `~`, 0x18, 0x84, 0x85, 0x90-0xA1) are picked off as they arrive and never
//!   stored. A byte arriving while the ring is full is lost, as on the AVR, and the loss is
//!   recorded ([`SimEvent::RxOverflow`], [`SimHandle::overflowed`]).
//! - **The protocol loop.** Characters are moved from the ring into the line buffer (GRBL: 80
//!   bytes) with GRBL's preprocessing (spaces and comments dropped, upper case, overflow flag →
//!   `error:11`; FluidNC cuts the line off instead). A motion line waits, holding the ring,
//!   while the planner (GRBL: 15 blocks) is full; `ok` is sent when the line is in the
//!   planner, not when it has run. Spindle/coolant changes, `G4`, `M0/M1/M2/M30`, `G10`,
//!   `G28/G30` and `G92` wait for the planner to empty first, as GRBL does.
//! - **Motion** runs in simulated time at the commanded feed (times the feed override) or the
//!   rapid rate, with instant acceleration except for a feed hold, which decelerates at the
//!   configured acceleration (`Hold:1`, then `Hold:0`). Arcs run at their true length.
//! - **Real-time commands**: status reports (`MPos`, `Bf`, `FS`; `WCO`, `Ov` and `A` as the
//!   firmware refreshes them, see `report`), feed hold, cycle start (after the hold completes),
//!   soft reset (`ALARM:3` when reset in motion, the firmware's banner, `[MSG:'$H'|'$X' to
//!   unlock]` in alarm, else the `$N` startup blocks), jog cancel, feed/rapid/spindle overrides.
//! - **The spindle output** (the heat): `FS:` and `A:` report what the output does, with `$30`
//!   capping the speed and `$32` laser mode (laser on during feed moves only, off in a
//!   completed hold); see `spindle`.
//! - **`$` commands**: `$`, `$$`, `$#`, `$G`, `$I`, `$N`, `$Nx=line` (run when stored and after
//!   every reset), `$X`, `$H` (`error:5`: homing is disabled), `$C`, `$RST=`, `$J=` jogging,
//!   `$n=v` (`$10` status mask, `$30`, `$32`). Each is recorded ([`SimEvent::SystemCommand`]).
//! - **A new host** sees the banner, a hardware reset (an Arduino whose port opens) or nothing
//!   (FluidNC over telnet), per [`OnConnect`]; the machine keeps running otherwise.
//! - **G-code errors**: GRBL's `error:N` codes for a useful subset of bad or unsupported
//!   G-code (1, 2, 4, 20-36, 38), and
//!   `error:9` while in alarm or jog.
//! - **Faults** ([`Faults`]): link drops at lines N1, N2, ..., a controller that freezes at
//!   line N (silent, link open), alarm at line N, forced `error:N` at line N, slow
//!   acknowledgements.
//!
//! Every G-code line is recorded in the executed-line log when it takes effect: motion lines
//! when their move completes, other lines when the planner reaches them (in program order). The
//! log lives as long as the simulator, across connections.
//!
//! Simulated time runs at `time_scale` times tokio's clock; under a paused tokio clock
//! (`start_paused`) the whole simulation is deterministic and as fast as the CPU allows.
//!
//! One file per part: `link` (the serial link and the host side's tasks), `rx` (RX ring and
//! line buffer), `execute` (the protocol loop's G-code lines), `system` (`$` commands),
//! `realtime` (real-time commands and resets), `planner` (the block queue), `motion` (motion and
//! holds in simulated time), `spindle` (the spindle/laser output), `overrides`, `faults`,
//! `report` (status reports and snapshots), `machine` (the state and the event loop), `gcode`
//! (the G-code parser), `firmware` (what each firmware says), `clock`, `config`, `record` and
//! `handle` (the public side).

mod clock;
mod config;
mod execute;
mod faults;
mod firmware;
mod gcode;
mod handle;
mod link;
mod machine;
mod motion;
mod overrides;
mod parser_state;
mod planner;
mod realtime;
mod record;
mod report;
mod rx;
mod spindle;
mod system;

use std::sync::{Arc, Mutex};

use tokio::sync::{mpsc, watch};

use crate::protocol::MachineState;

use clock::SimClock;
use machine::Machine;
use record::Record;

pub use config::{OnConnect, SimConfig};
pub use faults::Faults;
pub use firmware::{
    SimFirmware, BUILD_INFO, FLUIDNC_BANNER, FLUIDNC_BUILD_INFO, GRBLHAL_BANNER,
    GRBLHAL_BUILD_INFO, GRBL_BANNER, GRBL_BUILD_INFO,
};
pub use handle::SimHandle;
pub use parser_state::ParserState;
pub use record::{ExecutedLine, SimEvent, SimSnapshot};

/// The banner GRBL 1.1h prints after a reset (the default firmware's; see [`SimFirmware`]).
pub const BANNER: &str = GRBL_BANNER;

/// Starts a simulator task on the current tokio runtime.
pub fn start(config: SimConfig) -> SimHandle {
    let clock = SimClock::start(config.time_scale);
    let (tx, rx) = mpsc::unbounded_channel();
    let record = Arc::new(Mutex::new(Record::default()));
    let n = config.axes.len();
    let snap = SimSnapshot {
        at_s: 0.0,
        state: MachineState::Idle,
        position: vec![0.0; n],
        planner_used: 0,
        rx_used: 0,
        connected: false,
        frozen: false,
        spindle_on: false,
        executed: 0,
        received: 0,
    };
    let (snap_tx, snap_rx) = watch::channel(snap);
    let slack = config.timer_slack;
    let machine = Machine::new(config, clock, record.clone(), snap_tx);
    tokio::spawn(machine.run(rx));
    SimHandle {
        inbox: tx,
        record,
        snapshot: snap_rx,
        clock,
        slack,
        next_conn: Arc::new(std::sync::atomic::AtomicU64::new(1)),
    }
}
