//! The simulated machine: its state and the event loop that steps it. Between events nothing
//! happens but motion; at each event (a byte arriving, a block ending, a hold completing, a
//! delayed answer falling due) the machine settles: markers logged, moves started, lines read
//! and executed.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;
use tokio::time::Instant;

use crate::protocol::MachineState;

use super::clock::SimClock;
use super::faults::FiredFaults;
use super::gcode::Modal;
use super::link::{Inbox, Out};
use super::overrides::Overrides;
use super::planner::Entry;
use super::record::Record;
use super::report::ReportCounters;
use super::rx::PendingLine;
use super::{SimConfig, SimEvent, SimSnapshot};

/// The simulated controller: link, RX ring, protocol loop, planner and motion in one state
/// machine, stepped event by event in simulated time.
pub(super) struct Machine {
    pub(super) cfg: SimConfig,
    pub(super) clock: SimClock,
    pub(super) record: Arc<Mutex<Record>>,
    pub(super) snap_tx: watch::Sender<SimSnapshot>,
    /// Simulated time of the state (s).
    pub(super) t: f64,
    /// Seconds per byte on the wire (0 for an unthrottled link).
    pub(super) byte_time: f64,
    // Link.
    pub(super) connection: u64,
    pub(super) out: Option<mpsc::UnboundedSender<Out>>,
    pub(super) reader: Option<JoinHandle<()>>,
    /// Bytes on the wire with their arrival times.
    pub(super) wire: VecDeque<(f64, u8)>,
    pub(super) wire_free_at: f64,
    pub(super) out_free_at: f64,
    // RX ring and line buffer.
    pub(super) rx: VecDeque<u8>,
    pub(super) line: String,
    pub(super) raw: String,
    pub(super) line_overflow: bool,
    pub(super) in_paren: bool,
    pub(super) in_semicolon: bool,
    // Protocol loop.
    pub(super) pending: Option<PendingLine>,
    pub(super) busy_until: f64,
    /// Answers held back until `busy_until` (slow acks, dwell).
    pub(super) delayed: Vec<String>,
    /// Critical alarm: nothing is read until a reset.
    pub(super) critical_lock: bool,
    /// G-code lines received.
    pub(super) received: u64,
    // Machine.
    pub(super) state: MachineState,
    pub(super) check_mode: bool,
    pub(super) queue: VecDeque<Entry>,
    pub(super) planner_used: usize,
    pub(super) pos: Vec<f64>,
    pub(super) modal: Modal,
    /// Feed hold or jog cancel decelerating: (start time, speed then).
    pub(super) hold: Option<(f64, f64)>,
    pub(super) hold_complete: bool,
    pub(super) jog_cancel: bool,
    pub(super) overrides: Overrides,
    /// A completed hold switched the laser off (laser mode) until cycle start or reset.
    pub(super) spindle_stopped: bool,
    /// Laser mode, `M3`: the last move was a feed move, so the laser keeps its power at rest.
    pub(super) laser_rest_on: bool,
    /// `$N0`/`$N1` startup blocks (kept in EEPROM: they survive resets and connections).
    pub(super) startup_lines: [String; 2],
    /// When status reports carry `WCO:`, `Ov:` and `A:`.
    pub(super) report: ReportCounters,
    // Faults.
    pub(super) fired: FiredFaults,
    pub(super) frozen: bool,
}

impl Machine {
    /// A machine at power-up: idle at the origin, no host.
    pub(super) fn new(
        cfg: SimConfig,
        clock: SimClock,
        record: Arc<Mutex<Record>>,
        snap_tx: watch::Sender<SimSnapshot>,
    ) -> Machine {
        let n = cfg.axes.len();
        let byte_time = cfg.baud.map_or(0.0, |b| 10.0 / b as f64);
        Machine {
            modal: Modal::new(n, vec![0.0; n]),
            pos: vec![0.0; n],
            cfg,
            clock,
            record,
            snap_tx,
            t: 0.0,
            byte_time,
            connection: 0,
            out: None,
            reader: None,
            wire: VecDeque::new(),
            wire_free_at: 0.0,
            out_free_at: 0.0,
            rx: VecDeque::new(),
            line: String::new(),
            raw: String::new(),
            line_overflow: false,
            in_paren: false,
            in_semicolon: false,
            pending: None,
            busy_until: 0.0,
            delayed: Vec::new(),
            critical_lock: false,
            received: 0,
            state: MachineState::Idle,
            check_mode: false,
            queue: VecDeque::new(),
            planner_used: 0,
            hold: None,
            hold_complete: false,
            jog_cancel: false,
            overrides: Overrides::default(),
            spindle_stopped: false,
            laser_rest_on: false,
            startup_lines: Default::default(),
            report: ReportCounters::default(),
            fired: FiredFaults::default(),
            frozen: false,
        }
    }

    /// The record, also after a panic elsewhere poisoned its lock.
    pub(super) fn rec(&self) -> MutexGuard<'_, Record> {
        self.record.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records an event.
    pub(super) fn event(&self, e: SimEvent) {
        self.rec().events.push(e);
    }

    /// The event loop: steps the machine to the clock, sleeps until the next event or message.
    pub(super) async fn run(mut self, mut inbox: mpsc::UnboundedReceiver<Inbox>) {
        loop {
            let now = self.clock.now().max(self.t);
            self.advance(now);
            // Events due within the clock's resolution are run now: sleeping until an instant
            // that has (after rounding) already passed would spin without time advancing.
            for _ in 0..1000 {
                match self.next_event() {
                    Some(t)
                        if self.clock.instant_at(t) <= Instant::now() + self.cfg.timer_slack =>
                    {
                        self.advance(t.max(self.t))
                    }
                    _ => break,
                }
            }
            self.publish();
            let next = self.next_event();
            let sleep = next.map(|t| self.clock.instant_at(t));
            tokio::select! {
                msg = inbox.recv() => match msg {
                    None => break,
                    Some(m) => self.inbox(m),
                },
                _ = async {
                    match sleep {
                        Some(s) => tokio::time::sleep_until(s).await,
                        None => std::future::pending().await,
                    }
                } => {}
            }
        }
        if let Some(r) = self.reader.take() {
            r.abort();
        }
    }

    /// When the next event is due (s): a byte arriving, a delayed answer, a block ending.
    pub(super) fn next_event(&self) -> Option<f64> {
        let mut next: Option<f64> = None;
        let mut consider = |t: f64| {
            next = Some(next.map_or(t, |n: f64| n.min(t)));
        };
        if let Some(&(a, _)) = self.wire.front() {
            consider(a);
        }
        if self.busy_until > self.t {
            consider(self.busy_until);
        }
        if let Some(t) = self.motion_event() {
            consider(t);
        }
        next
    }

    /// Runs the simulation up to `now`, event by event.
    pub(super) fn advance(&mut self, now: f64) {
        loop {
            self.settle();
            let mut next = f64::INFINITY;
            if let Some(&(a, _)) = self.wire.front() {
                next = next.min(a);
            }
            if self.busy_until > self.t {
                next = next.min(self.busy_until);
            }
            if let Some(m) = self.motion_event() {
                next = next.min(m);
            }
            if next > now {
                break;
            }
            let t = next.max(self.t);
            self.integrate(t);
            while let Some(&(a, b)) = self.wire.front() {
                if a > t {
                    break;
                }
                self.wire.pop_front();
                self.receive_byte(b);
            }
        }
        self.integrate(now);
    }

    /// Everything that happens at `self.t` without time passing: markers reached, moves started,
    /// lines read and executed, state changes.
    pub(super) fn settle(&mut self) {
        loop {
            let mut progressed = false;
            // Markers at the head run at once.
            while let Some(Entry::Marker(_)) = self.queue.front() {
                if let Some(Entry::Marker(l)) = self.queue.pop_front() {
                    self.log(l);
                }
            }
            // Start or note the head move.
            if let Some(Entry::Motion(b)) = self.queue.front_mut() {
                if !b.started && !self.hold_complete && self.hold.is_none() {
                    b.started = true;
                    let seq = b.log.as_ref().map(|l| l.seq);
                    let jog = b.jog;
                    if !matches!(self.state, MachineState::Alarm) {
                        self.state = if jog {
                            MachineState::Jog
                        } else {
                            MachineState::Run
                        };
                    }
                    if seq.is_some_and(|seq| self.alarm_fault(seq)) {
                        continue;
                    }
                }
            } else if self.queue.is_empty()
                && matches!(self.state, MachineState::Run | MachineState::Jog)
            {
                self.state = MachineState::Idle;
            }
            // The protocol loop.
            if !self.critical_lock && !self.frozen && self.t >= self.busy_until {
                for d in std::mem::take(&mut self.delayed) {
                    self.emit(&d);
                }
                if self.pending.is_some() {
                    if self.try_execute() {
                        progressed = true;
                        // Each line's spindle/coolant/offset change counts, even if the next
                        // line undoes it before a report.
                        self.track_report_changes();
                    }
                } else if self.read_line() {
                    progressed = true;
                }
            }
            if !progressed {
                break;
            }
        }
        self.track_report_changes();
        let used = self.rx.len();
        let mut r = self.rec();
        r.rx_high_water = r.rx_high_water.max(used);
    }
}
