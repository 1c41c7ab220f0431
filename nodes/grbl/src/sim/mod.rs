//! A GRBL 1.1 protocol simulator: a tokio task that behaves like GRBL on the wire.
//!
//! What it models, and how faithfully:
//! - **The link.** Bytes travel at the configured baud (115 200 8N1 = 11 520 bytes/s) in both
//!   directions, plus an optional one-way latency (a USB-serial adapter's), in simulated time.
//!   A reader task drains the host's socket at once, so the socket never acts as a hidden buffer.
//! - **The 128-byte RX ring** (127 usable bytes). Real-time bytes (`?`, `!`, `~`, 0x18, 0x84,
//!   0x85, 0x90-0xA1) are picked off as they arrive and never stored. A byte arriving while the
//!   ring is full is lost, as on the AVR, and the loss is recorded ([`SimEvent::RxOverflow`],
//!   [`SimHandle::overflowed`]).
//! - **The protocol loop.** Characters are moved from the ring into the 80-byte line buffer with
//!   GRBL's preprocessing (spaces and comments dropped, upper case, overflow flag → `error:11`).
//!   A motion line waits, holding the ring, while the 15-block planner is full; `ok` is sent when
//!   the line is in the planner, not when it has run. Spindle/coolant changes, `G4`, `M0/M1/M2/M30`,
//!   `G10`, `G28/G30` and `G92` wait for the planner to empty first, as GRBL does.
//! - **Motion** runs in simulated time at the commanded feed (times the feed override) or the
//!   rapid rate, with instant acceleration except for a feed hold, which decelerates at the
//!   configured acceleration (`Hold:1`, then `Hold:0`). Arcs run at their true length.
//! - **Real-time commands**: status reports (`MPos`, `Bf`, `FS`, `WCO` and `Ov` every 10th
//!   report), feed hold, cycle start (after the hold completes), soft reset (`ALARM:3` when reset
//!   in motion, the `Grbl 1.1h ['$' for help]` banner, `[MSG:'$H'|'$X' to unlock]`), jog cancel,
//!   feed/rapid/spindle overrides.
//! - **`$` commands**: `$`, `$$`, `$#`, `$G`, `$I`, `$N`, `$X`, `$H` (`error:5`: homing is
//!   disabled), `$C`, `$J=` jogging, `$n=v` (only `$10`, the status mask, changes behaviour).
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

pub(crate) mod gcode;

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;
use tokio::time::Instant;

use crate::protocol::{MachineState, Realtime, LINE_BUFFER_SIZE, PLANNER_BLOCKS, RX_BUFFER_SIZE};
use gcode::{Modal, Speed, Spindle};

/// The banner GRBL 1.1h prints after a reset.
pub const BANNER: &str = "Grbl 1.1h ['$' for help]";

/// Faults the simulator injects. Line numbers count G-code lines received since the simulator
/// started (1-based, `$` commands not counted), across connections; each fault fires once.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Faults {
    /// For each N listed, when G-code line N has been received, drop the link: line N and
    /// everything still in the RX buffer or on the wire are lost, output already queued is
    /// delivered, and the connection closes. The planner keeps running what it holds (as a
    /// controller whose host went away). Each entry fires once; the order does not matter.
    pub drop_at_lines: Vec<u64>,
    /// When G-code line N has been received, the controller freezes: line N and everything
    /// still in the RX buffer or on the wire are lost, and from then on nothing is read or
    /// answered (real-time bytes included, so `?` gets no status report), but the connection
    /// stays open. The planner keeps running what it holds. The next host to attach finds the
    /// controller answering again (a hung USB-serial bridge or network stack that recovers on a
    /// new connection).
    pub freeze_at_line: Option<u64>,
    /// When the move of G-code line N starts, raise `ALARM:code` (1 or 2 behave like GRBL's
    /// critical hard/soft-limit alarms: motion killed, `[MSG:Reset to continue]`, nothing read
    /// until a reset).
    pub alarm_at_line: Option<(u64, u8)>,
    /// Answer G-code line N with `error:code` instead of executing it.
    pub error_at_line: Option<(u64, u8)>,
    /// Simulated seconds the controller spends on each line before answering (slow acks). The
    /// protocol loop is busy meanwhile, as on a slow controller.
    pub ack_delay_s: f64,
}

/// Simulator settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Simulated seconds per second of tokio time (10.0 runs ten times faster than real time).
    pub time_scale: f64,
    /// Serial baud rate (8N1: baud/10 bytes/s in each direction); `None` for an unthrottled
    /// link.
    pub baud: Option<u32>,
    /// One-way link latency (s), added to every byte in both directions (USB-serial adapters
    /// add 1-16 ms).
    pub latency_s: f64,
    /// Serial RX ring size (GRBL: 128; one slot stays empty).
    pub rx_buffer_bytes: usize,
    /// Usable planner blocks (GRBL on an AVR: 15).
    pub planner_blocks: usize,
    /// Axis letters, in report order (GRBL 1.1: `XYZ`; grblHAL-style `XYUV` etc. also work).
    pub axes: Vec<char>,
    /// Rapid rate for every axis (mm/min).
    pub rapid_mm_min: f64,
    /// Deceleration for feed holds and jog cancels (mm/s²).
    pub accel_mm_s2: f64,
    /// `$10` status report mask: bit 0 MPos (else WPos), bit 1 `Bf:` buffer data.
    pub status_mask: u8,
    /// Print the banner when a host connects (as an Arduino does when the port opens), without
    /// resetting anything.
    pub banner_on_connect: bool,
    /// Events and output due within this much tokio time are handled at once instead of
    /// sleeping for them: tokio's timer has a 1 ms resolution, which would otherwise delay every
    /// answer by up to 1 ms of real time (10 ms of simulated time at `time_scale` 10). The
    /// simulation then runs ahead of the clock by at most this much. Use zero under a paused
    /// clock for exact timing.
    pub timer_slack: std::time::Duration,
    /// Injected faults.
    pub faults: Faults,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            time_scale: 1.0,
            baud: Some(115_200),
            latency_s: 0.0,
            rx_buffer_bytes: RX_BUFFER_SIZE,
            planner_blocks: PLANNER_BLOCKS,
            axes: vec!['X', 'Y', 'Z'],
            rapid_mm_min: 3000.0,
            accel_mm_s2: 200.0,
            status_mask: 3,
            banner_on_connect: true,
            timer_slack: std::time::Duration::from_millis(1),
            faults: Faults::default(),
        }
    }
}

/// One line the simulated machine executed.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecutedLine {
    /// The line as received (without its `\n`).
    pub text: String,
    /// G-code line count when it was received (1-based, see [`Faults`]).
    pub seq: u64,
    /// Connection it came in on (1 for the first).
    pub connection: u64,
    /// Simulated time it took effect (s).
    pub at_s: f64,
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
    /// The controller froze ([`Faults::freeze_at_line`]): from here until the next host
    /// attaches it reads and answers nothing.
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
    /// The controller is frozen ([`Faults::freeze_at_line`]).
    pub frozen: bool,
    /// Spindle (heat) on.
    pub spindle_on: bool,
    /// Executed lines so far.
    pub executed: usize,
    /// G-code lines received so far.
    pub received: u64,
}

#[derive(Debug, Default)]
struct Record {
    log: Vec<ExecutedLine>,
    events: Vec<SimEvent>,
    rx_high_water: usize,
    overflow_bytes: u64,
}

/// Handle to a running simulator: attach hosts, read the executed-line log, the events and the
/// machine state. Cloning gives another handle to the same simulator; dropping the last one stops
/// it.
#[derive(Clone)]
pub struct SimHandle {
    inbox: mpsc::UnboundedSender<Inbox>,
    record: Arc<Mutex<Record>>,
    snapshot: watch::Receiver<SimSnapshot>,
    clock: SimClock,
    slack: std::time::Duration,
    next_conn: Arc<std::sync::atomic::AtomicU64>,
}

impl std::fmt::Debug for SimHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimHandle").finish_non_exhaustive()
    }
}

#[derive(Debug, Clone, Copy)]
struct SimClock {
    origin: Instant,
    scale: f64,
}

impl SimClock {
    fn now(&self) -> f64 {
        self.origin.elapsed().as_secs_f64() * self.scale
    }
    fn instant_at(&self, t: f64) -> Instant {
        self.origin + std::time::Duration::from_secs_f64((t / self.scale).max(0.0))
    }
}

enum Inbox {
    Attach {
        connection: u64,
        out: mpsc::UnboundedSender<Out>,
        reader: JoinHandle<()>,
    },
    Bytes {
        connection: u64,
        at_s: f64,
        data: Vec<u8>,
    },
    Closed {
        connection: u64,
    },
}

enum Out {
    Data { at_s: f64, bytes: Vec<u8> },
    Close,
}

/// Starts a simulator task on the current tokio runtime.
pub fn start(config: SimConfig) -> SimHandle {
    let clock = SimClock {
        origin: Instant::now(),
        scale: if config.time_scale > 0.0 {
            config.time_scale
        } else {
            1.0
        },
    };
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

impl SimHandle {
    /// Attaches a host on any byte stream (TCP socket, pty master, in-memory pipe). A new host
    /// replaces the current one, whose link is closed.
    pub fn attach<S>(&self, stream: S) -> u64
    where
        S: AsyncRead + AsyncWrite + Send + 'static,
    {
        let connection = self
            .next_conn
            .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        let (mut rd, wr) = tokio::io::split(stream);
        let (out_tx, out_rx) = mpsc::unbounded_channel();
        let inbox = self.inbox.clone();
        let clock = self.clock;
        let reader = tokio::spawn(async move {
            let mut buf = vec![0u8; 4096];
            loop {
                match rd.read(&mut buf).await {
                    Ok(0) | Err(_) => break,
                    Ok(n) => {
                        let msg = Inbox::Bytes {
                            connection,
                            at_s: clock.now(),
                            data: buf[..n].to_vec(),
                        };
                        if inbox.send(msg).is_err() {
                            return;
                        }
                    }
                }
            }
            let _ = inbox.send(Inbox::Closed { connection });
        });
        let _ = self.inbox.send(Inbox::Attach {
            connection,
            out: out_tx.clone(),
            reader,
        });
        tokio::spawn(writer(wr, out_rx, clock, self.slack));
        connection
    }

    /// Accepts hosts on a TCP listener bound to `addr` (`127.0.0.1:0` for a free port) and
    /// returns the bound address. Each accepted connection replaces the previous one.
    pub async fn listen_tcp(&self, addr: &str) -> std::io::Result<std::net::SocketAddr> {
        let listener = tokio::net::TcpListener::bind(addr).await?;
        let local = listener.local_addr()?;
        let me = self.clone();
        tokio::spawn(async move {
            while let Ok((sock, _)) = listener.accept().await {
                let _ = sock.set_nodelay(true);
                me.attach(sock);
                if me.inbox.is_closed() {
                    break;
                }
            }
        });
        Ok(local)
    }

    /// Creates a pseudo-terminal, attaches its master side, and returns the slave's device path
    /// for a sender to open. The pty stays open as long as the simulator runs.
    pub fn open_pty(&self) -> std::io::Result<std::path::PathBuf> {
        let (master, path, slave) = crate::transport::open_pty()?.into_parts();
        self.attach(master);
        let inbox = self.inbox.clone();
        tokio::spawn(async move {
            inbox.closed().await;
            drop(slave);
        });
        Ok(path)
    }

    /// A [`Connect`](crate::transport::Connect) that opens an in-memory link to this simulator
    /// (each connect replaces the previous host, like a new TCP connection).
    pub fn connector(&self) -> Arc<dyn crate::transport::Connect> {
        Arc::new(InProcess(self.clone()))
    }

    /// Simulated time now (s).
    pub fn now_s(&self) -> f64 {
        self.clock.now()
    }

    fn record(&self) -> MutexGuard<'_, Record> {
        self.record.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Every executed line so far.
    pub fn executed(&self) -> Vec<ExecutedLine> {
        self.record().log.clone()
    }

    /// The text of every executed line so far.
    pub fn executed_lines(&self) -> Vec<String> {
        self.record().log.iter().map(|l| l.text.clone()).collect()
    }

    /// Every event so far.
    pub fn events(&self) -> Vec<SimEvent> {
        self.record().events.clone()
    }

    /// True when any byte was lost to a full RX ring.
    pub fn overflowed(&self) -> bool {
        self.record().overflow_bytes > 0
    }

    /// Bytes lost to a full RX ring.
    pub fn overflow_bytes(&self) -> u64 {
        self.record().overflow_bytes
    }

    /// Most bytes ever waiting in the RX ring at once.
    pub fn rx_high_water(&self) -> usize {
        self.record().rx_high_water
    }

    /// The latest machine snapshot.
    pub fn snapshot(&self) -> SimSnapshot {
        self.snapshot.borrow().clone()
    }

    /// Waits until `pred` holds for a snapshot (snapshots are published after every step of the
    /// simulation), for at most `timeout` of tokio time. `Err` carries the latest snapshot when
    /// the time ran out or the simulator stopped first, so a test can fail with it instead of
    /// hanging.
    pub async fn wait_for(
        &self,
        timeout: std::time::Duration,
        mut pred: impl FnMut(&SimSnapshot) -> bool,
    ) -> Result<SimSnapshot, SimSnapshot> {
        let mut rx = self.snapshot.clone();
        let got = tokio::time::timeout(timeout, rx.wait_for(|s| pred(s)))
            .await
            .map(|r| r.map(|s| s.clone()));
        match got {
            Ok(Ok(s)) => Ok(s),
            Ok(Err(_)) | Err(_) => Err(self.snapshot()),
        }
    }
}

struct InProcess(SimHandle);

impl crate::transport::Connect for InProcess {
    fn connect(&self) -> crate::transport::ConnectFuture<'_> {
        Box::pin(async move {
            let (host, sim) = tokio::io::duplex(1 << 16);
            self.0.attach(sim);
            Ok(Box::new(host) as crate::transport::BoxedTransport)
        })
    }

    fn describe(&self) -> String {
        "in-process grbl_sim".into()
    }
}

async fn writer<W: AsyncWrite + Send + 'static>(
    wr: tokio::io::WriteHalf<W>,
    rx: mpsc::UnboundedReceiver<Out>,
    clock: SimClock,
    slack: std::time::Duration,
) {
    let mut wr = wr;
    let mut rx = rx;
    while let Some(msg) = rx.recv().await {
        match msg {
            Out::Data { at_s, bytes } => {
                // The machine computed the delivery time; wait for it unless it is (nearly) due.
                let due = clock.instant_at(at_s);
                if due > Instant::now() + slack {
                    tokio::time::sleep_until(due).await;
                }
                if wr.write_all(&bytes).await.is_err() {
                    break;
                }
            }
            Out::Close => {
                let _ = wr.flush().await;
                let _ = wr.shutdown().await;
                break;
            }
        }
    }
}

/// An entry in the execution queue (the planner plus the non-motion lines between its blocks).
#[derive(Debug)]
enum Entry {
    Motion(Block),
    Marker(LogLine),
}

#[derive(Debug, Clone)]
struct LogLine {
    text: String,
    seq: u64,
    connection: u64,
}

#[derive(Debug)]
struct Block {
    start: Vec<f64>,
    target: Vec<f64>,
    length_mm: f64,
    remaining_mm: f64,
    speed: Speed,
    jog: bool,
    started: bool,
    /// The last move of a line carries the line for the log.
    log: Option<LogLine>,
}

#[derive(Debug)]
struct PendingLine {
    stored: String,
    raw: String,
    overflow: bool,
    seq: u64,
    connection: u64,
}

struct Machine {
    cfg: SimConfig,
    clock: SimClock,
    record: Arc<Mutex<Record>>,
    snap_tx: watch::Sender<SimSnapshot>,
    t: f64,
    byte_time: f64,
    // Link.
    connection: u64,
    out: Option<mpsc::UnboundedSender<Out>>,
    reader: Option<JoinHandle<()>>,
    wire: VecDeque<(f64, u8)>,
    wire_free_at: f64,
    out_free_at: f64,
    // Protocol loop.
    rx: VecDeque<u8>,
    line: String,
    raw: String,
    line_overflow: bool,
    in_paren: bool,
    in_semicolon: bool,
    pending: Option<PendingLine>,
    busy_until: f64,
    delayed: Vec<String>,
    critical_lock: bool,
    received: u64,
    // Machine.
    state: MachineState,
    check_mode: bool,
    queue: VecDeque<Entry>,
    planner_used: usize,
    pos: Vec<f64>,
    modal: Modal,
    hold: Option<(f64, f64)>,
    hold_complete: bool,
    jog_cancel: bool,
    feed_ovr: u16,
    rapid_ovr: u16,
    spindle_ovr: u16,
    reports: u64,
    fired_drops: Vec<u64>,
    frozen: bool,
    fired_freeze: bool,
    fired_alarm: bool,
    fired_error: bool,
}

impl Machine {
    fn new(
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
            feed_ovr: 100,
            rapid_ovr: 100,
            spindle_ovr: 100,
            reports: 0,
            fired_drops: Vec::new(),
            frozen: false,
            fired_freeze: false,
            fired_alarm: false,
            fired_error: false,
        }
    }

    fn rec(&self) -> MutexGuard<'_, Record> {
        self.record.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn event(&self, e: SimEvent) {
        self.rec().events.push(e);
    }

    async fn run(mut self, mut inbox: mpsc::UnboundedReceiver<Inbox>) {
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

    fn inbox(&mut self, msg: Inbox) {
        match msg {
            Inbox::Attach {
                connection,
                out,
                reader,
            } => {
                self.close_link(false);
                // A new host finds a frozen controller answering again.
                self.frozen = false;
                self.connection = connection;
                self.out = Some(out);
                self.reader = Some(reader);
                self.out_free_at = self.t;
                self.event(SimEvent::Connected {
                    connection,
                    at_s: self.t,
                });
                if self.cfg.banner_on_connect {
                    self.emit(&format!("\r\n{BANNER}"));
                }
            }
            Inbox::Bytes {
                connection,
                at_s,
                data,
            } => {
                // A frozen controller reads nothing: the bytes are lost.
                if connection != self.connection || self.out.is_none() || self.frozen {
                    return;
                }
                let enter = (at_s + self.cfg.latency_s).max(self.t);
                for b in data {
                    let start = enter.max(self.wire_free_at);
                    let arrival = start + self.byte_time;
                    self.wire_free_at = arrival;
                    self.wire.push_back((arrival, b));
                }
            }
            Inbox::Closed { connection } => {
                if connection == self.connection && self.out.is_some() {
                    self.close_link(false);
                }
            }
        }
    }

    /// Closes the current link: output already queued is still delivered, input is discarded.
    fn close_link(&mut self, injected: bool) {
        if let Some(out) = self.out.take() {
            let _ = out.send(Out::Close);
            self.event(SimEvent::Disconnected {
                connection: self.connection,
                injected,
                at_s: self.t,
            });
        }
        if let Some(r) = self.reader.take() {
            r.abort();
        }
        self.wire.clear();
        self.rx.clear();
        self.clear_line();
        self.pending = None;
        self.delayed.clear();
    }

    /// Stops reading and answering with the link left open; the next attach ends it.
    fn freeze(&mut self) {
        self.frozen = true;
        self.event(SimEvent::Frozen {
            connection: self.connection,
            at_s: self.t,
        });
        self.wire.clear();
        self.rx.clear();
        self.clear_line();
        self.pending = None;
        self.delayed.clear();
    }

    fn clear_line(&mut self) {
        self.line.clear();
        self.raw.clear();
        self.line_overflow = false;
        self.in_paren = false;
        self.in_semicolon = false;
    }

    /// Queues `text` + `\r\n` for the host at the current simulated time.
    fn emit(&mut self, text: &str) {
        if self.frozen {
            return;
        }
        let Some(out) = &self.out else { return };
        let mut bytes = text.as_bytes().to_vec();
        bytes.extend_from_slice(b"\r\n");
        let start = self.t.max(self.out_free_at);
        let done = start + self.byte_time * bytes.len() as f64;
        self.out_free_at = done;
        let _ = out.send(Out::Data {
            at_s: done + self.cfg.latency_s,
            bytes,
        });
    }

    fn publish(&self) {
        let executed = self.rec().log.len();
        let snap = SimSnapshot {
            at_s: self.t,
            state: self.state,
            position: self.pos.clone(),
            planner_used: self.planner_used,
            rx_used: self.rx.len(),
            connected: self.out.is_some(),
            frozen: self.frozen,
            spindle_on: self.modal.spindle != Spindle::Off,
            executed,
            received: self.received,
        };
        self.snap_tx.send_if_modified(|s| {
            if *s != snap {
                *s = snap;
                true
            } else {
                false
            }
        });
    }

    // ---- time ----

    /// Current speed of the head block (mm/s), before any hold deceleration.
    fn block_speed(&self, b: &Block) -> f64 {
        match b.speed {
            Speed::Rapid => self.cfg.rapid_mm_min / 60.0 * self.rapid_ovr as f64 / 100.0,
            Speed::Feed(v) => {
                if b.jog {
                    v
                } else {
                    v * self.feed_ovr as f64 / 100.0
                }
            }
        }
    }

    fn moving(&self) -> bool {
        matches!(self.queue.front(), Some(Entry::Motion(_))) && !self.hold_complete
    }

    /// Speed now, and whether it is decelerating.
    fn speed_at(&self, t: f64) -> (f64, bool) {
        let Some(Entry::Motion(b)) = self.queue.front() else {
            return (0.0, false);
        };
        if self.hold_complete {
            return (0.0, false);
        }
        match self.hold {
            Some((t0, v0)) => ((v0 - self.cfg.accel_mm_s2 * (t - t0)).max(0.0), true),
            None => (self.block_speed(b), false),
        }
    }

    fn next_event(&self) -> Option<f64> {
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

    /// When the head block ends or a hold finishes decelerating.
    fn motion_event(&self) -> Option<f64> {
        if !self.moving() {
            return None;
        }
        let Some(Entry::Motion(b)) = self.queue.front() else {
            return None;
        };
        let (v, decel) = self.speed_at(self.t);
        let a = self.cfg.accel_mm_s2;
        let r = b.remaining_mm;
        if decel {
            if v * v >= 2.0 * a * r {
                // (v - sqrt(v² - 2ar)) / a, in the form that does not cancel for small r.
                Some(self.t + 2.0 * r / (v + (v * v - 2.0 * a * r).max(0.0).sqrt()))
            } else {
                Some(self.t + v / a)
            }
        } else if v > 0.0 {
            Some(self.t + r / v)
        } else {
            None
        }
    }

    /// Runs the simulation up to `now`, event by event.
    fn advance(&mut self, now: f64) {
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

    /// Moves the machine from `self.t` to `t` (no event lies strictly between them).
    fn integrate(&mut self, t: f64) {
        let dt = t - self.t;
        if dt <= 0.0 {
            return;
        }
        if self.moving() {
            let (v, decel) = self.speed_at(self.t);
            let a = self.cfg.accel_mm_s2;
            let dist = if decel {
                let dt_eff = dt.min(v / a);
                v * dt_eff - 0.5 * a * dt_eff * dt_eff
            } else {
                v * dt
            };
            let mut done = false;
            if let Some(Entry::Motion(b)) = self.queue.front_mut() {
                b.remaining_mm -= dist;
                if b.remaining_mm <= 1e-9 {
                    b.remaining_mm = 0.0;
                    done = true;
                }
                let f = if b.length_mm > 0.0 {
                    1.0 - b.remaining_mm / b.length_mm
                } else {
                    1.0
                };
                self.pos = b
                    .start
                    .iter()
                    .zip(&b.target)
                    .map(|(s, e)| s + (e - s) * f)
                    .collect();
            }
            self.t = t;
            if done {
                self.finish_head();
            }
            if decel {
                if let Some((t0, v0)) = self.hold {
                    if t >= t0 + v0 / a - 1e-12 {
                        self.hold_stopped();
                    }
                }
            }
        } else {
            self.t = t;
        }
    }

    fn finish_head(&mut self) {
        if let Some(Entry::Motion(b)) = self.queue.pop_front() {
            self.planner_used -= 1;
            self.pos = b.target.clone();
            if let Some(l) = b.log {
                self.log(l);
            }
        }
    }

    fn hold_stopped(&mut self) {
        if self.jog_cancel {
            self.flush_motion();
            self.jog_cancel = false;
            self.hold = None;
            self.state = MachineState::Idle;
            return;
        }
        self.hold_complete = true;
        self.state = MachineState::Hold(0);
        self.event(SimEvent::HoldComplete { at_s: self.t });
    }

    fn flush_motion(&mut self) {
        self.queue.clear();
        self.planner_used = 0;
        self.modal.position = self.pos.clone();
    }

    fn log(&mut self, l: LogLine) {
        let at_s = self.t;
        self.rec().log.push(ExecutedLine {
            text: l.text,
            seq: l.seq,
            connection: l.connection,
            at_s,
        });
    }

    /// Everything that happens at `self.t` without time passing: markers reached, moves started,
    /// lines read and executed, state changes.
    fn settle(&mut self) {
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
                    if let (Some(seq), Some((n, code))) = (seq, self.cfg.faults.alarm_at_line) {
                        if seq == n && !self.fired_alarm {
                            self.fired_alarm = true;
                            self.raise_alarm(code);
                            continue;
                        }
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
                    }
                } else if self.read_line() {
                    progressed = true;
                }
            }
            if !progressed {
                break;
            }
        }
        let used = self.rx.len();
        let mut r = self.rec();
        r.rx_high_water = r.rx_high_water.max(used);
    }

    fn receive_byte(&mut self, b: u8) {
        if self.frozen {
            return;
        }
        if let Some(rt) = Realtime::from_byte(b) {
            self.realtime(rt);
            return;
        }
        if self.rx.len() >= self.cfg.rx_buffer_bytes.saturating_sub(1) {
            let at_s = self.t;
            let mut r = self.rec();
            r.overflow_bytes += 1;
            r.events.push(SimEvent::RxOverflow { byte: b, at_s });
            return;
        }
        self.rx.push_back(b);
        let used = self.rx.len();
        let mut r = self.rec();
        r.rx_high_water = r.rx_high_water.max(used);
    }

    /// Moves characters from the RX ring into the line buffer until a line is complete.
    fn read_line(&mut self) -> bool {
        while let Some(c) = self.rx.pop_front() {
            if c == b'\n' || c == b'\r' {
                let stored = std::mem::take(&mut self.line);
                let raw = std::mem::take(&mut self.raw);
                let overflow = self.line_overflow;
                self.clear_line();
                let is_gcode = !stored.is_empty() && !stored.starts_with('$') && !overflow;
                if is_gcode {
                    self.received += 1;
                }
                self.pending = Some(PendingLine {
                    stored,
                    raw,
                    overflow,
                    seq: if is_gcode { self.received } else { 0 },
                    connection: self.connection,
                });
                return true;
            }
            self.raw.push(c as char);
            if self.line_overflow || self.in_paren || self.in_semicolon {
                if c == b')' && self.in_paren {
                    self.in_paren = false;
                }
                continue;
            }
            if c <= b' ' || c == b'/' {
                continue;
            }
            if c == b'(' {
                self.in_paren = true;
            } else if c == b';' {
                self.in_semicolon = true;
            } else if self.line.len() >= LINE_BUFFER_SIZE - 1 {
                self.line_overflow = true;
            } else {
                self.line.push((c as char).to_ascii_uppercase());
            }
        }
        false
    }

    fn respond(&mut self, text: String) {
        if self.cfg.faults.ack_delay_s > 0.0 {
            self.busy_until = self.t + self.cfg.faults.ack_delay_s;
            self.delayed.push(text);
        } else {
            self.emit(&text);
        }
    }

    fn error(&mut self, line: &str, code: u8) {
        self.event(SimEvent::Error {
            line: line.to_string(),
            code,
            at_s: self.t,
        });
        self.respond(format!("error:{code}"));
    }

    /// Executes the pending line if it can go now; false when it must wait (planner full, or
    /// the planner must empty first).
    fn try_execute(&mut self) -> bool {
        let Some(p) = self.pending.take() else {
            return false;
        };
        if p.overflow {
            self.error(&p.raw, 11);
            return true;
        }
        if p.stored.is_empty() {
            self.respond("ok".into());
            return true;
        }
        if p.stored.starts_with('$') {
            let done = self.system_command(&p);
            if !done {
                self.pending = Some(p);
            }
            return done;
        }
        if self.cfg.faults.drop_at_lines.contains(&p.seq) && !self.fired_drops.contains(&p.seq) {
            self.fired_drops.push(p.seq);
            self.close_link(true);
            return true;
        }
        if self.cfg.faults.freeze_at_line == Some(p.seq) && !self.fired_freeze {
            self.fired_freeze = true;
            self.freeze();
            return true;
        }
        if let Some((n, code)) = self.cfg.faults.error_at_line {
            if n == p.seq && !self.fired_error {
                self.fired_error = true;
                self.error(&p.raw, code);
                return true;
            }
        }
        if matches!(self.state, MachineState::Alarm | MachineState::Jog) {
            self.error(&p.raw, 9);
            return true;
        }
        let (modal, action) = match gcode::execute(&self.modal, &p.stored, &self.cfg.axes, false) {
            Ok(x) => x,
            Err(code) => {
                self.error(&p.raw, code);
                return true;
            }
        };
        let log = LogLine {
            text: p.raw.clone(),
            seq: p.seq,
            connection: p.connection,
        };
        if self.check_mode {
            self.modal = modal;
            self.modal.position = self.pos.clone();
            self.respond("ok".into());
            return true;
        }
        if action.sync && !self.queue.is_empty() {
            self.pending = Some(p);
            return false;
        }
        if self.planner_used + action.moves.len() > self.cfg.planner_blocks {
            self.pending = Some(p);
            return false;
        }
        self.modal = modal;
        if action.moves.is_empty() {
            if self.queue.is_empty() {
                self.log(log);
            } else {
                self.queue.push_back(Entry::Marker(log));
            }
        } else {
            let n = action.moves.len();
            let mut start = self.queue_end_position();
            for (i, m) in action.moves.into_iter().enumerate() {
                let b = Block {
                    start: start.clone(),
                    target: m.target.clone(),
                    length_mm: m.length_mm,
                    remaining_mm: m.length_mm,
                    speed: m.speed,
                    jog: false,
                    started: false,
                    log: (i + 1 == n).then(|| log.clone()),
                };
                start = m.target;
                self.queue.push_back(Entry::Motion(b));
                self.planner_used += 1;
            }
        }
        if action.program_end {
            self.feed_ovr = 100;
            self.rapid_ovr = 100;
            self.spindle_ovr = 100;
            self.emit("[MSG:Pgm End]");
        }
        if action.pause {
            self.feed_hold();
        }
        match action.dwell_s {
            Some(d) if d > 0.0 => {
                self.busy_until = self.t + d;
                self.delayed.push("ok".into());
                if self.cfg.faults.ack_delay_s > 0.0 {
                    self.busy_until += self.cfg.faults.ack_delay_s;
                }
            }
            _ => self.respond("ok".into()),
        }
        true
    }

    fn queue_end_position(&self) -> Vec<f64> {
        self.queue
            .iter()
            .rev()
            .find_map(|e| match e {
                Entry::Motion(b) => Some(b.target.clone()),
                Entry::Marker(_) => None,
            })
            .unwrap_or_else(|| self.pos.clone())
    }

    fn system_command(&mut self, p: &PendingLine) -> bool {
        let cmd = p.stored.as_str();
        let idle_or_alarm = matches!(self.state, MachineState::Idle | MachineState::Alarm);
        let need_idle = |me: &mut Machine| -> bool {
            if !idle_or_alarm {
                me.error(&p.raw, 8);
                return false;
            }
            true
        };
        match cmd {
            "$" => {
                self.emit(
                    "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]",
                );
                self.respond("ok".into());
            }
            "$$" => {
                if need_idle(self) {
                    let settings = [
                        (0, "10".to_string()),
                        (1, "25".to_string()),
                        (10, self.cfg.status_mask.to_string()),
                        (13, "0".to_string()),
                        (22, "0".to_string()),
                        (30, "1000".to_string()),
                        (32, "0".to_string()),
                        (110, format!("{:.3}", self.cfg.rapid_mm_min)),
                        (
                            120,
                            format!("{:.3}", self.cfg.accel_mm_s2 * 3600.0 / 3600.0),
                        ),
                    ];
                    for (n, v) in settings {
                        self.emit(&format!("${n}={v}"));
                    }
                    self.respond("ok".into());
                }
            }
            "$G" => {
                let r = self.modal.gc_report();
                self.emit(&format!("[GC:{r}]"));
                self.respond("ok".into());
            }
            "$#" => {
                if need_idle(self) {
                    for (k, off) in self.modal.offsets.clone().iter().enumerate() {
                        self.emit(&format!("[G{}:{}]", 54 + k, fmt_pos(off)));
                    }
                    let zeros = vec![0.0; self.cfg.axes.len()];
                    self.emit(&format!("[G28:{}]", fmt_pos(&zeros)));
                    self.emit(&format!("[G30:{}]", fmt_pos(&zeros)));
                    let g92 = self.modal.g92.clone();
                    self.emit(&format!("[G92:{}]", fmt_pos(&g92)));
                    self.emit("[TLO:0.000]");
                    self.emit(&format!("[PRB:{}:0]", fmt_pos(&zeros)));
                    self.respond("ok".into());
                }
            }
            "$I" => {
                if need_idle(self) {
                    self.emit("[VER:1.1h.20190830:cellsuite grbl_sim]");
                    let opt = format!(
                        "[OPT:V,{},{}]",
                        self.cfg.planner_blocks, self.cfg.rx_buffer_bytes
                    );
                    self.emit(&opt);
                    self.respond("ok".into());
                }
            }
            "$N" => {
                if need_idle(self) {
                    self.emit("$N0=");
                    self.emit("$N1=");
                    self.respond("ok".into());
                }
            }
            "$X" => {
                if self.state == MachineState::Alarm {
                    self.state = MachineState::Idle;
                    self.critical_lock = false;
                    self.emit("[MSG:Caution: Unlocked]");
                }
                self.respond("ok".into());
            }
            "$H" => self.error(&p.raw, 5),
            "$C" => {
                if need_idle(self) && self.state != MachineState::Alarm {
                    self.check_mode = !self.check_mode;
                    self.state = if self.check_mode {
                        MachineState::Check
                    } else {
                        MachineState::Idle
                    };
                    self.emit(if self.check_mode {
                        "[MSG:Enabled]"
                    } else {
                        "[MSG:Disabled]"
                    });
                    self.respond("ok".into());
                }
            }
            "$SLP" => self.respond("ok".into()),
            _ if cmd.starts_with("$J=") => return self.jog(p),
            _ if cmd.starts_with("$RST=") => self.respond("ok".into()),
            _ => {
                let setting = cmd[1..]
                    .split_once('=')
                    .and_then(|(n, v)| Some((n.parse::<u16>().ok()?, v.parse::<f64>().ok()?)));
                match setting {
                    Some((n, v)) => {
                        if need_idle(self) {
                            if n == 10 && (0.0..=255.0).contains(&v) {
                                self.cfg.status_mask = v as u8;
                            }
                            self.respond("ok".into());
                        }
                    }
                    None => self.error(&p.raw, 3),
                }
            }
        }
        true
    }

    fn jog(&mut self, p: &PendingLine) -> bool {
        if !matches!(self.state, MachineState::Idle | MachineState::Jog) {
            self.error(&p.raw, 8);
            return true;
        }
        let mut base = self.modal.clone();
        base.position = self.queue_end_position();
        let (modal, action) = match gcode::execute(&base, &p.stored[3..], &self.cfg.axes, true) {
            Ok(x) => x,
            Err(code) => {
                self.error(&p.raw, code);
                return true;
            }
        };
        if self.planner_used + action.moves.len() > self.cfg.planner_blocks {
            return false;
        }
        let mut start = base.position.clone();
        for m in action.moves {
            self.queue.push_back(Entry::Motion(Block {
                start: start.clone(),
                target: m.target.clone(),
                length_mm: m.length_mm,
                remaining_mm: m.length_mm,
                speed: m.speed,
                jog: true,
                started: false,
                log: None,
            }));
            start = m.target;
            self.planner_used += 1;
        }
        self.modal.position = modal.position;
        self.respond("ok".into());
        true
    }

    fn raise_alarm(&mut self, code: u8) {
        self.flush_motion();
        self.hold = None;
        self.hold_complete = false;
        self.state = MachineState::Alarm;
        self.modal.spindle = Spindle::Off;
        self.modal.flood = false;
        self.modal.mist = false;
        self.event(SimEvent::Alarm { code, at_s: self.t });
        self.emit(&format!("ALARM:{code}"));
        if code == 1 || code == 2 {
            self.critical_lock = true;
            self.emit("[MSG:Reset to continue]");
        }
    }

    fn feed_hold(&mut self) {
        match self.state {
            MachineState::Run if self.hold.is_none() && !self.hold_complete => {
                let (v, _) = self.speed_at(self.t);
                self.hold = Some((self.t, v));
                self.state = MachineState::Hold(1);
                if v <= 0.0 {
                    self.hold_stopped();
                }
            }
            MachineState::Idle => {
                self.hold_complete = true;
                self.state = MachineState::Hold(0);
                self.event(SimEvent::HoldComplete { at_s: self.t });
            }
            MachineState::Jog => self.jog_cancel(),
            _ => {}
        }
    }

    fn jog_cancel(&mut self) {
        if self.state == MachineState::Jog && self.hold.is_none() {
            let (v, _) = self.speed_at(self.t);
            self.jog_cancel = true;
            self.hold = Some((self.t, v));
            if v <= 0.0 {
                self.hold_stopped();
            }
        }
    }

    fn realtime(&mut self, rt: Realtime) {
        self.event(SimEvent::Realtime {
            command: rt,
            state: self.state,
            at_s: self.t,
        });
        match rt {
            Realtime::StatusQuery => {
                let r = self.status_report();
                self.emit(&r);
            }
            Realtime::FeedHold => self.feed_hold(),
            Realtime::CycleStart => {
                if self.hold_complete && matches!(self.state, MachineState::Hold(_)) {
                    self.hold = None;
                    self.hold_complete = false;
                    self.state = if self.queue.is_empty() {
                        MachineState::Idle
                    } else {
                        MachineState::Run
                    };
                }
            }
            Realtime::SoftReset => self.soft_reset(),
            Realtime::JogCancel => self.jog_cancel(),
            Realtime::FeedOverrideReset => self.feed_ovr = 100,
            Realtime::FeedOverridePlus10 => self.feed_ovr = (self.feed_ovr + 10).min(200),
            Realtime::FeedOverrideMinus10 => {
                self.feed_ovr = self.feed_ovr.saturating_sub(10).max(10)
            }
            Realtime::FeedOverridePlus1 => self.feed_ovr = (self.feed_ovr + 1).min(200),
            Realtime::FeedOverrideMinus1 => self.feed_ovr = self.feed_ovr.saturating_sub(1).max(10),
            Realtime::RapidOverride100 => self.rapid_ovr = 100,
            Realtime::RapidOverride50 => self.rapid_ovr = 50,
            Realtime::RapidOverride25 => self.rapid_ovr = 25,
            Realtime::SpindleOverrideReset => self.spindle_ovr = 100,
            Realtime::SpindleOverridePlus10 => self.spindle_ovr = (self.spindle_ovr + 10).min(200),
            Realtime::SpindleOverrideMinus10 => {
                self.spindle_ovr = self.spindle_ovr.saturating_sub(10).max(10)
            }
            Realtime::SpindleOverridePlus1 => self.spindle_ovr = (self.spindle_ovr + 1).min(200),
            Realtime::SpindleOverrideMinus1 => {
                self.spindle_ovr = self.spindle_ovr.saturating_sub(1).max(10)
            }
            Realtime::SafetyDoor
            | Realtime::SpindleStopToggle
            | Realtime::FloodToggle
            | Realtime::MistToggle => {}
        }
    }

    fn soft_reset(&mut self) {
        // Moving: a block executing (not held to a stop) or decelerating into a hold.
        let in_motion = self.moving();
        self.event(SimEvent::Reset {
            in_motion,
            at_s: self.t,
        });
        self.flush_motion();
        self.rx.clear();
        self.clear_line();
        self.pending = None;
        self.delayed.clear();
        self.busy_until = self.t;
        self.hold = None;
        self.hold_complete = false;
        self.jog_cancel = false;
        self.check_mode = false;
        self.feed_ovr = 100;
        self.rapid_ovr = 100;
        self.spindle_ovr = 100;
        self.modal = self.modal.reset(self.pos.clone());
        if in_motion {
            self.state = MachineState::Alarm;
            self.event(SimEvent::Alarm {
                code: 3,
                at_s: self.t,
            });
            self.emit("ALARM:3");
        }
        self.critical_lock = false;
        if self.state != MachineState::Alarm {
            self.state = MachineState::Idle;
        }
        self.emit(&format!("\r\n{BANNER}"));
        if self.state == MachineState::Alarm {
            self.emit("[MSG:'$H'|'$X' to unlock]");
        }
    }

    fn status_report(&mut self) -> String {
        let wco = self.modal.wco();
        let mut s = format!("<{}", self.state);
        if self.cfg.status_mask & 1 != 0 {
            s += &format!("|MPos:{}", fmt_pos(&self.pos));
        } else {
            let w: Vec<f64> = self.pos.iter().zip(&wco).map(|(p, o)| p - o).collect();
            s += &format!("|WPos:{}", fmt_pos(&w));
        }
        if self.cfg.status_mask & 2 != 0 {
            let planner_free = self.cfg.planner_blocks.saturating_sub(self.planner_used);
            // GRBL's serial_get_rx_buffer_available(): 128 when empty.
            let rx_free = self.cfg.rx_buffer_bytes.saturating_sub(self.rx.len());
            s += &format!("|Bf:{planner_free},{rx_free}");
        }
        let (v, _) = self.speed_at(self.t);
        let spindle = if self.modal.spindle == Spindle::Off {
            0.0
        } else {
            self.modal.spindle_speed * self.spindle_ovr as f64 / 100.0
        };
        s += &format!("|FS:{},{}", fmt_int(v * 60.0), fmt_int(spindle));
        if self.reports.is_multiple_of(10) {
            s += &format!("|WCO:{}", fmt_pos(&wco));
        } else if self.reports % 10 == 1 {
            s += &format!(
                "|Ov:{},{},{}",
                self.feed_ovr, self.rapid_ovr, self.spindle_ovr
            );
            let mut acc = String::new();
            match self.modal.spindle {
                Spindle::Cw => acc.push('S'),
                Spindle::Ccw => acc.push('C'),
                Spindle::Off => {}
            }
            if self.modal.flood {
                acc.push('F');
            }
            if self.modal.mist {
                acc.push('M');
            }
            if !acc.is_empty() {
                s += &format!("|A:{acc}");
            }
        }
        self.reports += 1;
        s.push('>');
        s
    }
}

fn fmt_pos(p: &[f64]) -> String {
    p.iter()
        .map(|x| format!("{x:.3}"))
        .collect::<Vec<_>>()
        .join(",")
}

fn fmt_int(x: f64) -> String {
    format!("{}", x.round() as i64)
}
