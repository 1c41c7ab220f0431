//! The GRBL streaming client.
//!
//! One tokio task (the *link task*) owns the connection. It writes program lines under the
//! chosen flow control, matches every `ok`/`error:N` to the line it answers (GRBL answers lines
//! strictly in order), polls `?` at a fixed period, and writes real-time bytes the moment they
//! are asked for (commands are served before anything else the task has to do). The
//! [`GrblClient`] handle is cheap to clone and can be used from any task: one task streams while
//! another holds, overrides or aborts.
//!
//! Flow control:
//! - [`FlowControl::CharacterCounting`]: keep sending while the bytes of all unanswered lines,
//!   `\n` included, fit in GRBL's RX buffer (`rx_buffer_bytes - 1` = 127 usable bytes of the
//!   128-byte ring). Each `ok`/`error` frees its line's bytes. This keeps the RX buffer fed and
//!   never overflows it ([`RxBudget`]).
//! - [`FlowControl::SendResponse`]: one line at a time.
//!
//! Faults: an `error:N` to a program line, an `ALARM:N`, an unexpected reset banner, a link drop
//! or [`GrblClient::abort`] stop the streaming at once (no further line is written). The link task
//! writes `!` (feed hold) immediately for every fault but a link drop; the stream call then runs
//! the configured [`FaultAction`], by default [`GrblClient::safe_stop`]:
//! 1. `!` feed hold (already sent), then wait (polling `?`) until the machine reports `Hold:0`,
//!    `Idle`, `Alarm` or `Door` (the controlled stop keeps the position);
//! 2. `0x18` soft reset, and wait for the banner (GRBL 1.1 `Grbl 1.1h …`, grblHAL `GrblHAL
//!    1.1f …`, FluidNC `Grbl 3.7 [FluidNC v3.7.8 …]`; see [`crate::firmware`]). GRBL flushes its
//!    RX buffer and planner and switches the spindle, which drives the heat, off. The answer
//!    queue is emptied the moment the reset byte goes out, and nothing is sent until the banner
//!    (or, for a controller that prints none, a second status report) shows the reset: an `ok`
//!    still on the wire from before belongs to a line that is gone and must not answer `M5`;
//! 3. only if the controller is not in alarm after the reset (or `unlock_after_reset` is set, in
//!    which case `$X` is sent first): `M5`, so the heat is off in the modal state as well;
//! 4. the heat is read back ([`GrblClient::heat_state`]): `$G` must report `M5` and a fresh
//!    status report `FS:…,0` with no `A:S`/`A:C`. Only then is it "heat off confirmed"
//!    ([`HeatState::Off`]); a missing answer leaves it [`HeatState::Unknown`], with the reason.
//!
//! After a link drop, [`GrblClient::reconnect_and_stop`] writes `!` as the first byte on the new
//! link and then runs the safe stop. Every command has a timeout
//! ([`ClientConfig::command_timeout`], which also bounds each connection attempt), so no step
//! waits for ever on a controller that went silent. A program line longer than the RX budget is
//! refused before anything is sent ([`Fault::LineTooLong`]): character counting could never send
//! it. With [`ClientConfig::detect_rx_buffer`] the budget comes from the controller's `$I`.
//!
//! A silent controller is a link loss too: a missing `ok` alone is not (GRBL withholds `ok`
//! while its planner is full during a long slow move), but GRBL answers `?` at once in every
//! state, so when `?` polls have gone out and nothing at all has come back for
//! [`ClientConfig::status_timeout`], the link task drops the link as if it had closed
//! ([`Fault::LinkLost`], same line accounting, same resume path).
//!
//! The returned [`StreamError`] names the fault, the original line number of the line GRBL
//! rejected, the last acknowledged line and the lines that were sent but never acknowledged.
//!
//! Resume after a link drop: [`GrblClient::reconnect`], then
//! [`GrblClient::stream_from`] with the operator-confirmed line. Lines up to
//! [`StreamError::last_acked_line`] were accepted into GRBL's planner; lines in
//! [`StreamError::unacked_lines`] are the ambiguous window: sent, but whether GRBL parsed them is
//! unknown (the `ok` may have been lost with the link). A controller that kept running (TCP
//! controllers, a serial GRBL whose board did not reset) executes what its planner held, so
//! the usual confirmed line is `last_acked_line + 1`; if the controller reset, its planner was
//! lost and the operator must pick the line from the machine's position (after a safe stop,
//! [`crate::resume_point`] counts back the moves the reset discarded). The client re-sends
//! exactly the lines from the confirmed one on, each once; a resume after a reset first
//! restores the program's modal state and position there ([`crate::resume::preamble`], which
//! the bridge sends).

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt, WriteHalf};
use tokio::sync::{broadcast, mpsc, oneshot, watch};
use tokio::task::JoinHandle;
use tokio::time::{Instant, MissedTickBehavior};

use crate::firmware::{gc_spindle, parse_build_options, Banner, Firmware, SpindleWord};
use crate::program::Program;
use crate::protocol::{
    alarm_message, error_message, override_steps, parse_response, MachineState, OverrideKind,
    Realtime, Response, StatusReport, RX_BUFFER_SIZE,
};
use crate::transport::{BoxedTransport, Connect};

/// Flow control for streaming.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlowControl {
    /// Fill GRBL's RX buffer, counting every byte of every unanswered line.
    CharacterCounting,
    /// Send one line, wait for its answer, send the next.
    SendResponse,
}

/// What a stream call does after a fault stopped it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultAction {
    /// [`GrblClient::safe_stop`]: feed hold, soft reset, `M5`.
    SafeStop,
    /// Leave the machine in feed hold for the operator (the hold is sent at once).
    HoldOnly,
}

/// Client settings.
#[derive(Debug, Clone, PartialEq)]
pub struct ClientConfig {
    /// Flow control.
    pub flow: FlowControl,
    /// The controller's serial RX buffer (GRBL 1.1 on an AVR: 128); character counting keeps
    /// at most `rx_buffer_bytes - 1` bytes unanswered.
    pub rx_buffer_bytes: usize,
    /// Status poll period (`?`); GRBL recommends at most 5 Hz.
    pub status_period: Duration,
    /// Status watchdog: when `?` has been sent and no line at all (status report, `ok`, push
    /// message) has arrived for this long, the link is dropped and a running stream ends with
    /// [`Fault::LinkLost`]. Until the controller's first line on a connection the longer of
    /// this and `connect_timeout` applies (a serial board may still be booting).
    pub status_timeout: Duration,
    /// How long to wait for the first status report after connecting.
    pub connect_timeout: Duration,
    /// What a stream call does after a fault.
    pub on_fault: FaultAction,
    /// Longest wait for a feed hold to come to a stop during a safe stop.
    pub hold_timeout: Duration,
    /// Longest wait for the banner after a soft reset.
    pub reset_timeout: Duration,
    /// Send `$X` after a safe stop's reset left the controller in alarm (then `M5`). Off by
    /// default: an alarm after a reset in motion means the position may be lost, which an
    /// operator should see before unlocking.
    pub unlock_after_reset: bool,
    /// Connection attempts in [`GrblClient::reconnect`].
    pub reconnect_attempts: u32,
    /// Pause between connection attempts.
    pub reconnect_delay: Duration,
    /// Longest wait for the answer to a command line ([`GrblClient::command`]); also bounds
    /// each connection attempt.
    pub command_timeout: Duration,
    /// Ask the controller for its RX buffer size (`$I`, the `[OPT:…]` line) on every connect and
    /// budget by what it says instead of [`ClientConfig::rx_buffer_bytes`] (grblHAL: 1024,
    /// FluidNC: larger). A controller that does not say keeps `rx_buffer_bytes`.
    pub detect_rx_buffer: bool,
}

impl Default for ClientConfig {
    fn default() -> Self {
        ClientConfig {
            flow: FlowControl::CharacterCounting,
            rx_buffer_bytes: RX_BUFFER_SIZE,
            status_period: Duration::from_millis(200),
            // Ten status periods.
            status_timeout: Duration::from_secs(2),
            connect_timeout: Duration::from_secs(10),
            on_fault: FaultAction::SafeStop,
            hold_timeout: Duration::from_secs(30),
            reset_timeout: Duration::from_secs(5),
            unlock_after_reset: false,
            reconnect_attempts: 5,
            reconnect_delay: Duration::from_millis(500),
            command_timeout: Duration::from_secs(10),
            detect_rx_buffer: false,
        }
    }
}

/// Character-counting bookkeeping: the bytes of every line sent and not yet answered.
///
/// GRBL answers lines in order, so answers free the oldest line first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RxBudget {
    capacity: usize,
    lines: VecDeque<usize>,
    used: usize,
}

impl RxBudget {
    /// A budget of `capacity` bytes (for GRBL: `rx_buffer_bytes - 1`).
    pub fn new(capacity: usize) -> RxBudget {
        RxBudget {
            capacity,
            lines: VecDeque::new(),
            used: 0,
        }
    }

    /// Whether a line of `wire_len` bytes (`\n` included) may be sent now.
    pub fn fits(&self, wire_len: usize) -> bool {
        self.used + wire_len <= self.capacity
    }

    /// Records a line of `wire_len` bytes as sent.
    pub fn sent(&mut self, wire_len: usize) {
        self.lines.push_back(wire_len);
        self.used += wire_len;
    }

    /// Records the answer to the oldest line; returns its length, or `None` if nothing was
    /// outstanding.
    pub fn answered(&mut self) -> Option<usize> {
        let n = self.lines.pop_front()?;
        self.used -= n;
        Some(n)
    }

    /// Changes the capacity (the controller reported another RX buffer size); lines in flight
    /// stay counted.
    pub fn set_capacity(&mut self, capacity: usize) {
        self.capacity = capacity;
    }

    /// Forgets every outstanding line (after a reset GRBL's buffer is empty).
    pub fn clear(&mut self) {
        self.lines.clear();
        self.used = 0;
    }

    /// Bytes outstanding.
    pub fn used(&self) -> usize {
        self.used
    }

    /// Lines outstanding.
    pub fn outstanding(&self) -> usize {
        self.lines.len()
    }

    /// The capacity in bytes.
    pub fn capacity(&self) -> usize {
        self.capacity
    }
}

/// What the link task publishes for the node's feedback (through a `watch`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Progress {
    /// A link is up.
    pub connected: bool,
    /// Connections made so far (1 after the first connect).
    pub connections: u64,
    /// A program is being streamed.
    pub streaming: bool,
    /// Lines in the current (or last) job.
    pub lines_total: usize,
    /// Lines of that job written to the link.
    pub lines_sent: usize,
    /// Lines of that job acknowledged with `ok`.
    pub lines_acked: usize,
    /// Original line number of the last line written.
    pub last_sent_line: Option<usize>,
    /// Original line number of the last line acknowledged with `ok`.
    pub last_acked_line: Option<usize>,
    /// Bytes sent and not yet answered (character counting's view of GRBL's RX buffer).
    pub rx_bytes_in_flight: usize,
    /// The character-counting budget (bytes).
    pub rx_budget: usize,
    /// Latest status report.
    pub status: Option<StatusReport>,
    /// Status reports received so far.
    pub status_count: u64,
    /// Latest work coordinate offset seen (`WCO:`).
    pub wco: Option<Vec<f64>>,
    /// Machine position from the latest report (mm).
    pub machine_position: Option<Vec<f64>>,
    /// Work position from the latest report (mm).
    pub work_position: Option<Vec<f64>>,
    /// Reset banners seen so far.
    pub resets: u64,
    /// Last `ALARM:N` code since the last reset or unlock.
    pub alarm: Option<u8>,
    /// Version from the last banner (`1.1h`).
    pub version: Option<String>,
    /// Firmware from the last banner.
    pub firmware: Option<Firmware>,
    /// The planner's size in blocks: the most `Bf:` has shown free (0 until a report with
    /// `Bf:` came).
    pub planner_blocks: u16,
}

/// A discrete event from the controller or the link (through a `broadcast`).
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A link came up.
    Connected,
    /// The link went down.
    Disconnected(String),
    /// Reset banner: firmware and version.
    Banner(Banner),
    /// `ALARM:N`.
    Alarm(u8),
    /// `error:N` to a line; `line` is the original program line number when it was a program
    /// line.
    Error {
        /// The code.
        code: u8,
        /// Original program line number, if a program line.
        line: Option<usize>,
    },
    /// `[MSG:...]`.
    Message(String),
    /// Another push message or an unrecognised line.
    Other(String),
}

/// What stopped a stream.
#[derive(Debug, Clone, PartialEq)]
pub enum Fault {
    /// GRBL answered a program line with `error:code`.
    Rejected {
        /// Original line number.
        line: usize,
        /// The line as sent.
        text: String,
        /// Error code.
        code: u8,
        /// GRBL 1.1's message for the code.
        message: &'static str,
    },
    /// GRBL raised `ALARM:code`.
    Alarm {
        /// Alarm code.
        code: u8,
        /// GRBL 1.1's message for the code.
        message: &'static str,
    },
    /// A reset banner arrived that this client did not ask for.
    UnexpectedReset,
    /// The link closed or failed.
    LinkLost(String),
    /// [`GrblClient::abort`] was called.
    Aborted,
    /// The link task has ended (every client handle was dropped).
    ClientGone,
    /// Another stream is in progress.
    Busy,
    /// The start line is past the program's last line.
    NoSuchLine(usize),
    /// A line does not fit in the controller's RX buffer, so character counting could never
    /// send it (found before anything was sent).
    LineTooLong {
        /// Original line number.
        line: usize,
        /// Its bytes on the wire, `\n` included.
        bytes: usize,
        /// The RX budget (bytes).
        budget: usize,
    },
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fault::Rejected {
                line,
                text,
                code,
                message,
            } => write!(f, "line {line} ({text}): error:{code} {message}"),
            Fault::Alarm { code, message } => write!(f, "ALARM:{code} {message}"),
            Fault::UnexpectedReset => write!(f, "the controller reset unexpectedly"),
            Fault::LinkLost(why) => write!(f, "link lost: {why}"),
            Fault::Aborted => write!(f, "aborted"),
            Fault::ClientGone => write!(f, "the link task has ended"),
            Fault::Busy => write!(f, "another program is streaming"),
            Fault::NoSuchLine(l) => write!(f, "line {l} is past the program's last line"),
            Fault::LineTooLong {
                line,
                bytes,
                budget,
            } => write!(
                f,
                "line {line} is {bytes} bytes on the wire; the controller's RX buffer takes {budget}"
            ),
        }
    }
}

/// What [`GrblClient::safe_stop`] did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SafeStopReport {
    /// Everything written, in order: `"!"`, `"0x18"`, `"$X"`, `"M5"`.
    pub sent: Vec<String>,
    /// The hold came to a stop (`Hold:0`/`Idle`/`Alarm`/`Door`) before the reset.
    pub stopped_before_reset: bool,
    /// The reset banner arrived.
    pub reset_confirmed: bool,
    /// `M5` was acknowledged with `ok`.
    pub heat_off_acked: bool,
    /// State reported after the reset.
    pub state_after: Option<MachineState>,
    /// Steps that failed, in words.
    pub problems: Vec<String>,
    /// The heat as the controller reports it after the stop ([`GrblClient::heat_state`]).
    pub heat: HeatState,
    /// Motion blocks still queued in the hold, which the reset discarded (from `Bf:`; `None`
    /// when the controller does not report it).
    pub pending_blocks: Option<u16>,
}

impl SafeStopReport {
    /// One line for the operator: what was sent, the heat state and any problem.
    pub fn summary(&self) -> String {
        let mut s = format!("safe stop sent {}; {}", self.sent.join(" "), self.heat);
        for p in &self.problems {
            s.push_str("; ");
            s.push_str(p);
        }
        s
    }
}

/// The heat (spindle output: hot wire, laser, torch) as the controller itself reports it.
#[derive(Debug, Clone, PartialEq)]
pub enum HeatState {
    /// Off, confirmed from the controller's own answers.
    Off {
        /// What showed it (`$G M5, FS:0,0`).
        evidence: String,
    },
    /// On.
    On {
        /// What showed it (`$G M3`, `FS:0,1000`, `A:S`).
        evidence: String,
    },
    /// Not known (the link is down, the controller did not answer).
    Unknown {
        /// Why.
        why: String,
    },
}

impl HeatState {
    /// Off, confirmed.
    pub fn is_confirmed_off(&self) -> bool {
        matches!(self, HeatState::Off { .. })
    }
}

impl Default for HeatState {
    fn default() -> Self {
        HeatState::Unknown {
            why: "not checked".into(),
        }
    }
}

impl std::fmt::Display for HeatState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HeatState::Off { evidence } => write!(f, "heat off confirmed ({evidence})"),
            HeatState::On { evidence } => write!(f, "HEAT ON ({evidence})"),
            HeatState::Unknown { why } => write!(f, "heat state unknown: {why}"),
        }
    }
}

/// Why a stream stopped, with the line accounting an operator needs to resume.
#[derive(Debug, Clone, PartialEq)]
pub struct StreamError {
    /// What happened.
    pub fault: Fault,
    /// Original line number of the last line acknowledged with `ok`.
    pub last_acked_line: Option<usize>,
    /// Original line numbers of lines written but not acknowledged when the fault hit (the
    /// ambiguous window after a link drop).
    pub unacked_lines: Vec<usize>,
    /// What the fault action did, when one ran.
    pub safe_stop: Option<Box<SafeStopReport>>,
}

impl std::fmt::Display for StreamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.fault)?;
        match self.last_acked_line {
            Some(l) => write!(f, "; last acknowledged line {l}")?,
            None => write!(f, "; no line acknowledged")?,
        }
        if let (Some(a), Some(b)) = (self.unacked_lines.first(), self.unacked_lines.last()) {
            write!(f, "; lines {a}-{b} sent but not acknowledged")?;
        }
        Ok(())
    }
}

impl std::error::Error for StreamError {}

/// Errors other than stream faults.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// Opening the link failed.
    #[error("cannot connect to {target}: {source}")]
    Connect {
        /// Where.
        target: String,
        /// Why.
        source: std::io::Error,
    },
    /// No status report came back in time.
    #[error("no status report from {target} within {timeout:?}")]
    NoResponse {
        /// Where.
        target: String,
        /// How long we waited.
        timeout: Duration,
    },
    /// A job is already streaming.
    #[error("a program is already streaming")]
    Busy,
    /// The link is down.
    #[error("not connected")]
    NotConnected,
    /// The start line is past the program's end.
    #[error("line {0} is past the program's last line")]
    NoSuchLine(usize),
    /// GRBL answered a command with `error:N`.
    #[error("{command}: error:{code} {message}")]
    Rejected {
        /// The command.
        command: String,
        /// Code.
        code: u8,
        /// GRBL 1.1's message.
        message: &'static str,
    },
    /// The command's line holds a real-time byte or a newline.
    #[error("command {0:?} holds a newline or real-time byte")]
    BadCommand(String),
    /// The link task ended.
    #[error("the link task has ended")]
    Gone,
    /// No answer to a command in time.
    #[error("{command}: no answer within {after:?}")]
    Timeout {
        /// The command.
        command: String,
        /// How long we waited.
        after: Duration,
    },
}

/// The answer to a command line.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CommandReply {
    /// Push lines received while the command was the oldest unanswered line (`[GC:...]`,
    /// `$n=v`, `[MSG:...]`), in order.
    pub lines: Vec<String>,
}

/// A finished stream.
#[derive(Debug, Clone, PartialEq)]
pub struct JobReport {
    /// Lines streamed.
    pub lines: usize,
    /// Bytes written for them (`\n` included).
    pub bytes: usize,
    /// First and last original line numbers.
    pub first_line: usize,
    /// Last original line number.
    pub last_line: usize,
    /// Time from the first byte to the last `ok` (tokio clock).
    pub stream_time: Duration,
    /// Time until the machine was idle again.
    pub total_time: Duration,
}

enum Cmd {
    Stream {
        program: Arc<Program>,
        start: usize,
        reply: oneshot::Sender<Result<JobReport, StreamError>>,
    },
    Line {
        text: String,
        reply: oneshot::Sender<Result<CommandReply, ClientError>>,
    },
    Realtime(Vec<Realtime>),
    Abort,
    /// One connection attempt; `first` is written before anything else on the new link.
    Reconnect {
        first: Vec<u8>,
        reply: oneshot::Sender<Result<(), ClientError>>,
    },
    /// The controller's RX buffer size, as it reported it; answered once the budget is set.
    RxBuffer(usize, oneshot::Sender<()>),
}

/// Opens a link, giving up after `wait` (a TCP connect to a host that went away can otherwise
/// hang for minutes).
async fn connect_within(
    connector: &dyn Connect,
    wait: Duration,
) -> std::io::Result<BoxedTransport> {
    match tokio::time::timeout(wait, connector.connect()).await {
        Ok(r) => r,
        Err(_) => Err(std::io::Error::new(
            std::io::ErrorKind::TimedOut,
            format!("no connection within {wait:?}"),
        )),
    }
}

enum Incoming {
    Line(String),
    Closed(String),
}

/// Handle to a GRBL link. Clone it freely; the link task stops when the last handle is dropped.
#[derive(Clone)]
pub struct GrblClient {
    cmd: mpsc::Sender<Cmd>,
    progress: watch::Receiver<Progress>,
    events: broadcast::Sender<Event>,
    config: Arc<ClientConfig>,
    target: String,
}

impl std::fmt::Debug for GrblClient {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GrblClient")
            .field("target", &self.target)
            .finish_non_exhaustive()
    }
}

impl GrblClient {
    /// Connects through `connector` and waits for the first status report (`?` is sent; nothing
    /// is reset).
    pub async fn connect(
        connector: Arc<dyn Connect>,
        config: ClientConfig,
    ) -> Result<GrblClient, ClientError> {
        let target = connector.describe();
        let link = connect_within(connector.as_ref(), config.command_timeout)
            .await
            .map_err(|source| ClientError::Connect {
                target: target.clone(),
                source,
            })?;
        let budget = match config.flow {
            FlowControl::CharacterCounting => config.rx_buffer_bytes.saturating_sub(1),
            FlowControl::SendResponse => usize::MAX,
        };
        let (cmd_tx, cmd_rx) = mpsc::channel(64);
        let (progress_tx, progress_rx) = watch::channel(Progress {
            rx_budget: budget,
            ..Progress::default()
        });
        let (events, _) = broadcast::channel(256);
        let (in_tx, in_rx) = mpsc::unbounded_channel();
        let config = Arc::new(config);
        let mut task = LinkTask {
            config: config.clone(),
            connector,
            cmd_rx,
            in_tx,
            in_rx,
            generation: 0,
            writer: None,
            reader: None,
            progress: progress_tx,
            events: events.clone(),
            budget: RxBudget::new(budget),
            sent: VecDeque::new(),
            queued_cmds: VecDeque::new(),
            job: None,
            planner_size: 0,
            out: Vec::new(),
            hold_pending: false,
            next_job: 1,
            polled_at: None,
            heard: false,
            awaiting_reset: None,
        };
        task.attach(link);
        tokio::spawn(task.run());
        let client = GrblClient {
            cmd: cmd_tx,
            progress: progress_rx,
            events,
            config,
            target,
        };
        client.await_first_status(0).await?;
        client.learn_rx_buffer().await;
        Ok(client)
    }

    async fn await_first_status(&self, after: u64) -> Result<(), ClientError> {
        let timeout = self.config.connect_timeout;
        let mut rx = self.progress.clone();
        let wait = async {
            loop {
                let _ = self
                    .cmd
                    .send(Cmd::Realtime(vec![Realtime::StatusQuery]))
                    .await;
                let got = tokio::time::timeout(
                    Duration::from_millis(500),
                    rx.wait_for(|p| p.status_count > after),
                )
                .await;
                match got {
                    Ok(Ok(_)) => return Ok(()),
                    Ok(Err(_)) => return Err(ClientError::Gone),
                    Err(_) => continue,
                }
            }
        };
        match tokio::time::timeout(timeout, wait).await {
            Ok(r) => r,
            Err(_) => Err(ClientError::NoResponse {
                target: self.target.clone(),
                timeout,
            }),
        }
    }

    /// A receiver of the link task's progress (for the node's feedback and `MachineStatus`).
    pub fn progress(&self) -> watch::Receiver<Progress> {
        self.progress.clone()
    }

    /// A receiver of discrete events (alarms, errors, messages, link changes).
    pub fn events(&self) -> broadcast::Receiver<Event> {
        self.events.subscribe()
    }

    /// The configuration in use.
    pub fn config(&self) -> &ClientConfig {
        &self.config
    }

    /// Streams the whole program; see [`GrblClient::stream_from`].
    pub async fn stream(&self, program: &Program) -> Result<JobReport, StreamError> {
        match program.lines().first() {
            Some(l) => self.stream_from(program, l.number).await,
            None => Ok(JobReport {
                lines: 0,
                bytes: 0,
                first_line: 0,
                last_line: 0,
                stream_time: Duration::ZERO,
                total_time: Duration::ZERO,
            }),
        }
    }

    /// Streams the program from original line `from_line` (a dropped comment/blank line starts
    /// at the next kept line) to the end, and returns once every line is acknowledged and the
    /// machine is idle again. On a fault, runs [`ClientConfig::on_fault`] and returns the fault
    /// with its line accounting.
    pub async fn stream_from(
        &self,
        program: &Program,
        from_line: usize,
    ) -> Result<JobReport, StreamError> {
        let plain = |fault: Fault| StreamError {
            fault,
            last_acked_line: None,
            unacked_lines: Vec::new(),
            safe_stop: None,
        };
        let Some(start) = program.index_of_line(from_line) else {
            return Err(plain(Fault::NoSuchLine(from_line)));
        };
        let (tx, rx) = oneshot::channel();
        let cmd = Cmd::Stream {
            program: Arc::new(program.clone()),
            start,
            reply: tx,
        };
        if self.cmd.send(cmd).await.is_err() {
            return Err(plain(Fault::ClientGone));
        }
        let result = rx.await.unwrap_or_else(|_| Err(plain(Fault::ClientGone)));
        match result {
            Ok(r) => Ok(r),
            Err(mut e) => {
                let act = !matches!(
                    e.fault,
                    Fault::LinkLost(_)
                        | Fault::ClientGone
                        | Fault::Busy
                        | Fault::NoSuchLine(_)
                        | Fault::LineTooLong { .. }
                ) && self.config.on_fault == FaultAction::SafeStop;
                if act {
                    e.safe_stop = Some(Box::new(self.safe_stop().await));
                }
                Err(e)
            }
        }
    }

    /// Sends one command line (`$X`, `$G`, `M5`, `G0 X0`) and waits for its `ok`, at most
    /// [`ClientConfig::command_timeout`].
    pub async fn command(&self, text: &str) -> Result<CommandReply, ClientError> {
        self.command_within(text, self.config.command_timeout).await
    }

    async fn command_within(
        &self,
        text: &str,
        wait: Duration,
    ) -> Result<CommandReply, ClientError> {
        let t = text.trim();
        if t.bytes()
            .any(|b| b == b'\n' || b == b'\r' || Realtime::from_byte(b).is_some())
        {
            return Err(ClientError::BadCommand(t.to_string()));
        }
        let (tx, rx) = oneshot::channel();
        self.cmd
            .send(Cmd::Line {
                text: t.to_string(),
                reply: tx,
            })
            .await
            .map_err(|_| ClientError::Gone)?;
        // On a timeout the line stays in the answer queue, so its late answer is still matched
        // to it and not to a later line.
        match tokio::time::timeout(wait, rx).await {
            Ok(answer) => answer.unwrap_or(Err(ClientError::Gone)),
            Err(_) => Err(ClientError::Timeout {
                command: t.to_string(),
                after: wait,
            }),
        }
    }

    /// Writes real-time bytes now, ahead of anything else the link task has to do.
    ///
    /// # Errors
    /// [`ClientError::NotConnected`] while the link is down: the bytes would go nowhere.
    pub async fn realtime(&self, commands: &[Realtime]) -> Result<(), ClientError> {
        if !self.progress.borrow().connected {
            return Err(ClientError::NotConnected);
        }
        self.cmd
            .send(Cmd::Realtime(commands.to_vec()))
            .await
            .map_err(|_| ClientError::Gone)
    }

    /// Feed hold (`!`).
    pub async fn hold(&self) -> Result<(), ClientError> {
        self.realtime(&[Realtime::FeedHold]).await
    }

    /// Cycle start / resume (`~`), written at once. GRBL drops it while a feed hold is still
    /// decelerating (`Hold:1`); [`GrblClient::cycle_start_confirmed`] waits for the hold to
    /// complete and confirms the resume was taken.
    pub async fn resume(&self) -> Result<(), ClientError> {
        self.realtime(&[Realtime::CycleStart]).await
    }

    /// Soft reset (0x18). A stream in progress ends with [`Fault::UnexpectedReset`] unless the
    /// reset is part of [`GrblClient::abort`] or [`GrblClient::safe_stop`].
    pub async fn soft_reset(&self) -> Result<(), ClientError> {
        self.realtime(&[Realtime::SoftReset]).await
    }

    /// Jog cancel (0x85).
    pub async fn jog_cancel(&self) -> Result<(), ClientError> {
        self.realtime(&[Realtime::JogCancel]).await
    }

    /// Sets the feed override to `pct` (10-200 %), stepping from the last reported value.
    pub async fn feed_override(&self, pct: u16) -> Result<(), ClientError> {
        let cur = self.current_override(|o| o.feed_pct);
        self.realtime(&override_steps(OverrideKind::Feed, cur, pct))
            .await
    }

    /// Sets the spindle (heat) override to `pct` (10-200 %).
    pub async fn spindle_override(&self, pct: u16) -> Result<(), ClientError> {
        let cur = self.current_override(|o| o.spindle_pct);
        self.realtime(&override_steps(OverrideKind::Spindle, cur, pct))
            .await
    }

    fn current_override(&self, pick: impl Fn(&crate::protocol::Overrides) -> u16) -> u16 {
        self.progress
            .borrow()
            .status
            .as_ref()
            .and_then(|s| s.overrides.as_ref())
            .map_or(100, pick)
    }

    /// Emergency stop of a stream: writes `!` at once and stops sending; the stream call then
    /// returns [`Fault::Aborted`] after its fault action. Without a stream, runs
    /// [`GrblClient::safe_stop`] directly.
    pub async fn abort(&self) -> Result<Option<SafeStopReport>, ClientError> {
        let streaming = self.progress.borrow().streaming;
        self.cmd
            .send(Cmd::Abort)
            .await
            .map_err(|_| ClientError::Gone)?;
        if streaming {
            Ok(None)
        } else {
            Ok(Some(self.safe_stop().await))
        }
    }

    /// Feed hold, soft reset, heat off, and the heat state read back from the controller (see
    /// the module documentation for the exact sequence).
    pub async fn safe_stop(&self) -> SafeStopReport {
        self.stop_sequence(StopLimits {
            hold: self.config.hold_timeout,
            reset: self.config.reset_timeout,
            command: self.config.command_timeout,
        })
        .await
    }

    /// [`GrblClient::safe_stop`] done within about `budget` (a process that must exit soon:
    /// the launcher's kill timeout): each wait gets a share of it.
    pub async fn safe_stop_within(&self, budget: Duration) -> SafeStopReport {
        self.stop_sequence(StopLimits {
            hold: self.config.hold_timeout.min(budget.mul_f64(0.4)),
            reset: self.config.reset_timeout.min(budget.mul_f64(0.2)),
            command: self.config.command_timeout.min(budget.mul_f64(0.2)),
        })
        .await
    }

    async fn stop_sequence(&self, limits: StopLimits) -> SafeStopReport {
        let mut report = SafeStopReport::default();
        let mut rx = self.progress.clone();
        // Only a report that answers a `?` sent after the hold counts: an `Idle` from before
        // it (a dwell between two moves) would let the reset hit a moving machine.
        let before_hold = rx.borrow().status_count + 1;
        if let Err(e) = self.hold().await {
            report.problems.push(format!("feed hold: {e}"));
            report.heat = HeatState::Unknown {
                why: format!("the safe stop could not be sent: {e}"),
            };
            return report;
        }
        report.sent.push("!".into());
        // 1. Wait for the hold to stop the machine.
        let stopped = self
            .poll_until(limits.hold, |p| {
                p.status_count > before_hold
                    && matches!(
                        p.status.as_ref().and_then(|s| s.state),
                        Some(
                            MachineState::Hold(0)
                                | MachineState::Idle
                                | MachineState::Alarm
                                | MachineState::Door(_)
                                | MachineState::Check
                        )
                    )
            })
            .await;
        report.stopped_before_reset = stopped;
        report.pending_blocks = {
            let p = rx.borrow();
            p.status
                .as_ref()
                .and_then(|s| s.buffer)
                .filter(|_| p.planner_blocks > 0)
                .map(|b| p.planner_blocks.saturating_sub(b.planner_free))
        };
        if !stopped {
            report
                .problems
                .push("no stop reported before the reset".into());
        }
        // 2. Soft reset: the answer queue is forgotten as the byte goes out, so no `ok` sent
        // before it can be taken for the `M5`'s.
        let resets = rx.borrow_and_update().resets;
        let _ = self.cmd.send(Cmd::Abort).await;
        if let Err(e) = self.soft_reset().await {
            report.problems.push(format!("soft reset: {e}"));
            report.heat = HeatState::Unknown {
                why: format!("the reset could not be sent: {e}"),
            };
            return report;
        }
        report.sent.push("0x18".into());
        report.reset_confirmed = matches!(
            tokio::time::timeout(limits.reset, rx.wait_for(|p| p.resets > resets)).await,
            Ok(Ok(_))
        );
        if !report.reset_confirmed {
            report.problems.push("no banner after the reset".into());
        }
        let seen = rx.borrow_and_update().status_count;
        let _ = self
            .poll_until(limits.reset, |p| p.status_count > seen)
            .await;
        let mut state = rx.borrow().status.as_ref().and_then(|s| s.state);
        // 3. Heat off.
        if state == Some(MachineState::Alarm) && self.config.unlock_after_reset {
            report.sent.push("$X".into());
            match self.command_within("$X", limits.command).await {
                Ok(_) => state = Some(MachineState::Idle),
                Err(e) => report.problems.push(format!("$X: {e}")),
            }
        }
        if state != Some(MachineState::Alarm) {
            report.sent.push("M5".into());
            match self.command_within("M5", limits.command).await {
                Ok(_) => report.heat_off_acked = true,
                Err(e) => report.problems.push(format!("M5: {e}")),
            }
        } else {
            report
                .problems
                .push("controller in alarm after the reset: M5 not sent (the reset already switched the spindle off)".into());
        }
        report.state_after = state;
        // 4. Read the heat back from the controller.
        report.heat = self.heat_state_within(limits.command).await;
        report
    }

    /// The heat as the controller reports it: its parser state (`$G`: `M3`/`M4` on, `M5` off)
    /// and a fresh status report (`FS:` spindle speed 0, no `A:S`/`A:C`). Off only when both
    /// say so; on when either says on; unknown when the link is down or an answer is missing.
    /// `$G` is answered in every state, alarm and hold included.
    pub async fn heat_state(&self) -> HeatState {
        self.heat_state_within(self.config.command_timeout).await
    }

    async fn heat_state_within(&self, wait: Duration) -> HeatState {
        if !self.progress.borrow().connected {
            return HeatState::Unknown {
                why: "the link is down".into(),
            };
        }
        let word = match self.command_within("$G", wait).await {
            Ok(reply) => reply.lines.iter().find_map(|l| {
                l.strip_prefix("[GC:")
                    .and_then(|b| b.strip_suffix(']'))
                    .and_then(gc_spindle)
            }),
            Err(e) => {
                return HeatState::Unknown {
                    why: format!("$G: {e}"),
                }
            }
        };
        let seen = self.progress.borrow().status_count;
        if !self.poll_until(wait, |p| p.status_count > seen).await {
            return HeatState::Unknown {
                why: format!("no status report within {wait:?}"),
            };
        }
        let status = self.progress.borrow().status.clone().unwrap_or_default();
        let speed = status.spindle.unwrap_or(0.0);
        let accessories = status.accessories.clone().unwrap_or_default();
        let mut on = Vec::new();
        match word {
            Some(SpindleWord::M3) => on.push("$G M3".to_string()),
            Some(SpindleWord::M4) => on.push("$G M4".to_string()),
            _ => {}
        }
        if speed > 0.0 {
            on.push(format!("FS:{},{speed}", status.feed.unwrap_or(0.0)));
        }
        if accessories.contains('S') || accessories.contains('C') {
            on.push(format!("A:{accessories}"));
        }
        if !on.is_empty() {
            return HeatState::On {
                evidence: on.join(", "),
            };
        }
        match word {
            Some(SpindleWord::M5) => HeatState::Off {
                evidence: match status.spindle {
                    Some(_) => format!("$G M5, FS:{},0", status.feed.unwrap_or(0.0)),
                    None => "$G M5".into(),
                },
            },
            _ => HeatState::Unknown {
                why: "$G did not report the spindle state".into(),
            },
        }
    }

    /// After a link drop: connects again writing `!` (feed hold) before anything else, then
    /// runs the safe stop and reads the heat back. When no link comes back the report says
    /// the heat state is unknown, and why.
    pub async fn reconnect_and_stop(&self) -> SafeStopReport {
        match self.reconnect_sending(&[Realtime::FeedHold]).await {
            Ok(_) => {
                let mut report = self.safe_stop().await;
                report
                    .sent
                    .insert(0, "! (first byte on the new link)".into());
                report
            }
            Err(e) => SafeStopReport {
                problems: vec![format!("reconnect: {e}")],
                heat: HeatState::Unknown {
                    why: format!("the link did not come back ({e}); check the machine"),
                },
                ..SafeStopReport::default()
            },
        }
    }

    /// Sends `?` every 50 ms (tokio time) until `pred` holds or `timeout` passes.
    async fn poll_until(&self, timeout: Duration, pred: impl Fn(&Progress) -> bool) -> bool {
        let mut rx = self.progress.clone();
        let deadline = Instant::now() + timeout;
        loop {
            if pred(&rx.borrow_and_update()) {
                return true;
            }
            if Instant::now() >= deadline {
                return false;
            }
            if self.realtime(&[Realtime::StatusQuery]).await.is_err() {
                return false;
            }
            let _ = tokio::time::timeout(Duration::from_millis(50), rx.changed()).await;
        }
    }

    /// Re-opens the link after a drop (or at any time) and waits for a status report. The
    /// controller is not reset; the returned progress holds the last acknowledged line. Tries
    /// [`ClientConfig::reconnect_attempts`] times, each bounded by
    /// [`ClientConfig::command_timeout`]; commands are served between attempts.
    pub async fn reconnect(&self) -> Result<Progress, ClientError> {
        self.reconnect_sending(&[]).await
    }

    async fn reconnect_sending(&self, first: &[Realtime]) -> Result<Progress, ClientError> {
        let mut last = None;
        for attempt in 0..self.config.reconnect_attempts.max(1) {
            if attempt > 0 {
                tokio::time::sleep(self.config.reconnect_delay).await;
            }
            let seen = self.progress.borrow().status_count;
            let (tx, rx) = oneshot::channel();
            self.cmd
                .send(Cmd::Reconnect {
                    first: first.iter().map(|r| r.byte()).collect(),
                    reply: tx,
                })
                .await
                .map_err(|_| ClientError::Gone)?;
            match rx.await.unwrap_or(Err(ClientError::Gone)) {
                Ok(()) => {
                    self.await_first_status(seen).await?;
                    self.learn_rx_buffer().await;
                    return Ok(self.progress.borrow().clone());
                }
                Err(ClientError::Gone) => return Err(ClientError::Gone),
                Err(e) => last = Some(e),
            }
        }
        Err(last.unwrap_or(ClientError::NotConnected))
    }

    /// With [`ClientConfig::detect_rx_buffer`], asks `$I` for the RX buffer size and budgets by
    /// it. A controller that is busy (`$I` answers `error:8` outside idle) or does not say keeps
    /// the configured size.
    async fn learn_rx_buffer(&self) {
        if !self.config.detect_rx_buffer || self.config.flow != FlowControl::CharacterCounting {
            return;
        }
        let Ok(reply) = self.command("$I").await else {
            return;
        };
        let size = reply.lines.iter().find_map(|l| {
            l.strip_prefix("[OPT:")
                .and_then(|b| b.strip_suffix(']'))
                .and_then(parse_build_options)
        });
        if let Some(options) = size.filter(|o| o.rx_buffer_bytes >= 16) {
            let (tx, rx) = oneshot::channel();
            if self
                .cmd
                .send(Cmd::RxBuffer(options.rx_buffer_bytes, tx))
                .await
                .is_ok()
            {
                let _ = rx.await;
            }
        }
    }

    /// The character-counting budget in bytes (`usize::MAX` under send-response).
    pub fn rx_budget(&self) -> usize {
        self.progress.borrow().rx_budget
    }
}

/// How long each step of a safe stop may wait.
struct StopLimits {
    hold: Duration,
    reset: Duration,
    command: Duration,
}

enum Sent {
    Program {
        index: usize,
        job: u64,
    },
    Command {
        text: String,
        reply: Option<oneshot::Sender<Result<CommandReply, ClientError>>>,
        lines: Vec<String>,
    },
}

struct SentEntry {
    what: Sent,
}

struct Job {
    id: u64,
    program: Arc<Program>,
    start: usize,
    next: usize,
    acked: usize,
    bytes: usize,
    reply: Option<oneshot::Sender<Result<JobReport, StreamError>>>,
    started: Instant,
    all_acked_at: Option<(Instant, u64)>,
    resetting: bool,
    /// Lines that were unanswered when a soft reset went out.
    unacked_at_reset: Vec<usize>,
}

struct LinkTask {
    config: Arc<ClientConfig>,
    connector: Arc<dyn Connect>,
    cmd_rx: mpsc::Receiver<Cmd>,
    in_tx: mpsc::UnboundedSender<(u64, Incoming)>,
    in_rx: mpsc::UnboundedReceiver<(u64, Incoming)>,
    generation: u64,
    writer: Option<WriteHalf<BoxedTransport>>,
    reader: Option<JoinHandle<()>>,
    progress: watch::Sender<Progress>,
    events: broadcast::Sender<Event>,
    budget: RxBudget,
    sent: VecDeque<SentEntry>,
    queued_cmds: VecDeque<(String, oneshot::Sender<Result<CommandReply, ClientError>>)>,
    job: Option<Job>,
    planner_size: u16,
    out: Vec<u8>,
    hold_pending: bool,
    next_job: u64,
    /// When the oldest `?` still without any line after it was written.
    polled_at: Option<Instant>,
    /// A line has arrived on this connection.
    heard: bool,
    /// A soft reset was written and neither its banner nor a second status report has come
    /// yet (the count of status reports since): nothing is sent meanwhile.
    awaiting_reset: Option<u32>,
}

impl LinkTask {
    fn attach(&mut self, link: BoxedTransport) {
        if let Some(r) = self.reader.take() {
            r.abort();
        }
        self.generation += 1;
        let generation = self.generation;
        let (mut rd, wr) = tokio::io::split(link);
        self.writer = Some(wr);
        let tx = self.in_tx.clone();
        self.reader = Some(tokio::spawn(async move {
            let mut buf = vec![0u8; 4096];
            let mut line: Vec<u8> = Vec::with_capacity(128);
            loop {
                match rd.read(&mut buf).await {
                    Ok(0) => {
                        let _ = tx.send((generation, Incoming::Closed("end of stream".into())));
                        return;
                    }
                    Err(e) => {
                        let _ = tx.send((generation, Incoming::Closed(e.to_string())));
                        return;
                    }
                    Ok(n) => {
                        for &b in &buf[..n] {
                            if b == b'\n' {
                                let text = String::from_utf8_lossy(&line)
                                    .trim_end_matches('\r')
                                    .to_string();
                                line.clear();
                                if tx.send((generation, Incoming::Line(text))).is_err() {
                                    return;
                                }
                            } else if line.len() < 4096 {
                                line.push(b);
                            }
                        }
                    }
                }
            }
        }));
        self.budget.clear();
        self.polled_at = None;
        self.heard = false;
        self.progress.send_modify(|p| {
            p.connected = true;
            p.connections += 1;
            p.rx_bytes_in_flight = 0;
        });
        let _ = self.events.send(Event::Connected);
    }

    async fn run(mut self) {
        let mut poll = tokio::time::interval(self.config.status_period);
        poll.set_missed_tick_behavior(MissedTickBehavior::Delay);
        loop {
            self.pump().await;
            let watchdog = self.watchdog();
            tokio::select! {
                biased;
                cmd = self.cmd_rx.recv() => match cmd {
                    None => break,
                    Some(c) => self.on_cmd(c).await,
                },
                msg = self.in_rx.recv() => match msg {
                    None => break,
                    Some((g, m)) if g == self.generation => self.on_incoming(m).await,
                    Some(_) => {}
                },
                _ = poll.tick() => {
                    if self.writer.is_some() {
                        self.write_now(&[Realtime::StatusQuery.byte()]).await;
                        self.polled();
                    }
                }
                _ = async {
                    match watchdog {
                        Some((at, _)) => tokio::time::sleep_until(at).await,
                        None => std::future::pending().await,
                    }
                } => {
                    if let Some((_, waited)) = watchdog {
                        self.link_lost(format!(
                            "no answer from the controller for {:.1} s",
                            waited.as_secs_f64()
                        ));
                    }
                }
            }
        }
        if let Some(r) = self.reader.take() {
            r.abort();
        }
    }

    /// Notes that `?` went out: the watchdog runs from the first poll nothing has answered.
    fn polled(&mut self) {
        if self.writer.is_some() && self.polled_at.is_none() {
            self.polled_at = Some(Instant::now());
        }
    }

    /// When the watchdog fires, and the silence it will have waited for.
    fn watchdog(&self) -> Option<(Instant, Duration)> {
        let since = self.polled_at.filter(|_| self.writer.is_some())?;
        let mut wait = self.config.status_timeout;
        if !self.heard {
            wait = wait.max(self.config.connect_timeout);
        }
        Some((since + wait, wait))
    }

    /// Writes bytes now; a write failure is a link loss.
    async fn write_now(&mut self, bytes: &[u8]) {
        let Some(w) = self.writer.as_mut() else {
            return;
        };
        let r = async {
            w.write_all(bytes).await?;
            w.flush().await
        }
        .await;
        if let Err(e) = r {
            self.link_lost(e.to_string());
        }
    }

    async fn on_cmd(&mut self, cmd: Cmd) {
        match cmd {
            Cmd::Realtime(rts) => {
                let bytes: Vec<u8> = rts.iter().map(|r| r.byte()).collect();
                let reset = rts.contains(&Realtime::SoftReset);
                if reset {
                    if let Some(job) = self.job.as_mut() {
                        job.resetting = true;
                    }
                }
                self.write_now(&bytes).await;
                if reset && self.writer.is_some() {
                    self.reset_written();
                }
                if rts.contains(&Realtime::StatusQuery) {
                    self.polled();
                }
            }
            Cmd::RxBuffer(bytes, done) => {
                if self.config.flow == FlowControl::CharacterCounting {
                    let budget = bytes.saturating_sub(1);
                    self.budget.set_capacity(budget);
                    self.progress.send_modify(|p| p.rx_budget = budget);
                }
                let _ = done.send(());
            }
            Cmd::Line { text, reply } => {
                if self.writer.is_none() {
                    let _ = reply.send(Err(ClientError::NotConnected));
                } else {
                    self.queued_cmds.push_back((text, reply));
                }
            }
            Cmd::Stream {
                program,
                start,
                reply,
            } => {
                if self.job.as_ref().is_some_and(|j| j.reply.is_some()) {
                    let _ = reply.send(Err(StreamError {
                        fault: Fault::Busy,
                        last_acked_line: None,
                        unacked_lines: vec![],
                        safe_stop: None,
                    }));
                    return;
                }
                if self.writer.is_none() {
                    let _ = reply.send(Err(StreamError {
                        fault: Fault::LinkLost("not connected".into()),
                        last_acked_line: self.progress.borrow().last_acked_line,
                        unacked_lines: vec![],
                        safe_stop: None,
                    }));
                    return;
                }
                if self.config.flow == FlowControl::CharacterCounting {
                    let budget = self.budget.capacity();
                    if let Some(l) = program.lines()[start..]
                        .iter()
                        .find(|l| l.wire_len() > budget)
                    {
                        let _ = reply.send(Err(StreamError {
                            fault: Fault::LineTooLong {
                                line: l.number,
                                bytes: l.wire_len(),
                                budget,
                            },
                            last_acked_line: None,
                            unacked_lines: vec![],
                            safe_stop: None,
                        }));
                        return;
                    }
                }
                let id = self.next_job;
                self.next_job += 1;
                let total = program.len() - start;
                self.progress.send_modify(|p| {
                    p.streaming = true;
                    p.lines_total = total;
                    p.lines_sent = 0;
                    p.lines_acked = 0;
                    p.last_sent_line = None;
                });
                self.job = Some(Job {
                    id,
                    program,
                    start,
                    next: start,
                    acked: 0,
                    bytes: 0,
                    reply: Some(reply),
                    started: Instant::now(),
                    all_acked_at: None,
                    resetting: false,
                    unacked_at_reset: Vec::new(),
                });
            }
            Cmd::Abort => {
                if self.job.as_ref().is_some_and(|j| j.reply.is_some()) {
                    self.write_now(&[Realtime::FeedHold.byte()]).await;
                    self.fail_job(Fault::Aborted);
                }
                if let Some(job) = self.job.as_mut() {
                    job.resetting = true;
                }
            }
            Cmd::Reconnect { first, reply } => {
                if let Some(r) = self.reader.take() {
                    r.abort();
                }
                if let Some(mut w) = self.writer.take() {
                    let _ = w.shutdown().await;
                }
                let wait = self.config.command_timeout;
                let answer = match connect_within(self.connector.as_ref(), wait).await {
                    Ok(link) => {
                        self.link_lost_cleanup();
                        self.awaiting_reset = None;
                        self.attach(link);
                        if !first.is_empty() {
                            self.write_now(&first).await;
                        }
                        Ok(())
                    }
                    Err(source) => {
                        self.progress.send_modify(|p| p.connected = false);
                        Err(ClientError::Connect {
                            target: self.connector.describe(),
                            source,
                        })
                    }
                };
                let _ = reply.send(answer);
            }
        }
    }

    /// Writes as many queued commands and program lines as the flow control allows.
    async fn pump(&mut self) {
        if self.writer.is_none() {
            return;
        }
        if std::mem::take(&mut self.hold_pending) {
            self.write_now(&[Realtime::FeedHold.byte()]).await;
        }
        if self.awaiting_reset.is_some() {
            return;
        }
        self.out.clear();
        let char_counting = self.config.flow == FlowControl::CharacterCounting;
        loop {
            let can = |budget: &RxBudget, sent: usize, len: usize| {
                if char_counting {
                    budget.fits(len)
                } else {
                    sent == 0
                }
            };
            if let Some((text, _)) = self.queued_cmds.front() {
                let len = text.len() + 1;
                if !can(&self.budget, self.sent.len(), len) {
                    break;
                }
                let Some((text, reply)) = self.queued_cmds.pop_front() else {
                    break;
                };
                self.out.extend_from_slice(text.as_bytes());
                self.out.push(b'\n');
                self.budget.sent(len);
                self.sent.push_back(SentEntry {
                    what: Sent::Command {
                        text,
                        reply: Some(reply),
                        lines: Vec::new(),
                    },
                });
                continue;
            }
            let Some(job) = self.job.as_mut() else { break };
            if job.reply.is_none() || job.next >= job.program.len() {
                break;
            }
            let line = &job.program.lines()[job.next];
            let len = line.wire_len();
            if !can(&self.budget, self.sent.len(), len) {
                break;
            }
            self.out.extend_from_slice(line.text.as_bytes());
            self.out.push(b'\n');
            self.budget.sent(len);
            self.sent.push_back(SentEntry {
                what: Sent::Program {
                    index: job.next,
                    job: job.id,
                },
            });
            job.bytes += len;
            let number = line.number;
            job.next += 1;
            let sent_count = job.next - job.start;
            self.progress.send_modify(|p| {
                p.lines_sent = sent_count;
                p.last_sent_line = Some(number);
            });
        }
        if !self.out.is_empty() {
            let out = std::mem::take(&mut self.out);
            self.write_now(&out).await;
            self.out = out;
            let used = self.budget.used();
            self.progress.send_modify(|p| p.rx_bytes_in_flight = used);
        }
    }

    fn unacked_lines(&self) -> Vec<usize> {
        let Some(job) = &self.job else {
            return vec![];
        };
        let in_queue = self.sent.iter().filter_map(|e| match e.what {
            Sent::Program { index, job: id } if id == job.id => {
                Some(job.program.lines()[index].number)
            }
            _ => None,
        });
        job.unacked_at_reset
            .iter()
            .copied()
            .chain(in_queue)
            .collect()
    }

    /// Ends the current job with `fault` (no further line is sent). The entries already sent
    /// stay in the answer queue, so later answers are still matched to their lines.
    fn fail_job(&mut self, fault: Fault) {
        let unacked = self.unacked_lines();
        let last = self.progress.borrow().last_acked_line;
        if let Some(job) = self.job.as_mut() {
            if let Some(reply) = job.reply.take() {
                let _ = reply.send(Err(StreamError {
                    fault,
                    last_acked_line: last,
                    unacked_lines: unacked,
                    safe_stop: None,
                }));
            }
        }
        self.progress.send_modify(|p| p.streaming = false);
    }

    fn link_lost(&mut self, why: String) {
        if self.writer.is_none() {
            return;
        }
        self.writer = None;
        self.polled_at = None;
        if let Some(r) = self.reader.take() {
            r.abort();
        }
        let _ = self.events.send(Event::Disconnected(why.clone()));
        self.fail_job(Fault::LinkLost(why));
        self.link_lost_cleanup();
        self.progress.send_modify(|p| {
            p.connected = false;
            p.rx_bytes_in_flight = 0;
        });
    }

    fn link_lost_cleanup(&mut self) {
        self.job = None;
        self.budget.clear();
        for e in self.sent.drain(..) {
            if let Sent::Command { reply: Some(r), .. } = e.what {
                let _ = r.send(Err(ClientError::NotConnected));
            }
        }
        for (_, r) in self.queued_cmds.drain(..) {
            let _ = r.send(Err(ClientError::NotConnected));
        }
    }

    async fn on_incoming(&mut self, msg: Incoming) {
        let line = match msg {
            Incoming::Closed(why) => {
                self.link_lost(why);
                return;
            }
            Incoming::Line(l) => l,
        };
        // Any line at all shows the controller is alive.
        self.polled_at = None;
        self.heard = true;
        if line.trim().is_empty() {
            return;
        }
        match parse_response(&line) {
            Response::Ok => self.answered(None),
            Response::Error(code) => self.answered(Some(code)),
            Response::Alarm(code) => {
                let _ = self.events.send(Event::Alarm(code));
                self.progress.send_modify(|p| p.alarm = Some(code));
                if self.job.as_ref().is_some_and(|j| !j.resetting) {
                    self.write_now(&[Realtime::FeedHold.byte()]).await;
                }
                if self.job.as_ref().is_some_and(|j| j.reply.is_some()) {
                    self.fail_job(Fault::Alarm {
                        code,
                        message: alarm_message(code),
                    });
                }
            }
            Response::Status(s) => self.on_status(s),
            Response::Banner(banner) => {
                let _ = self.events.send(Event::Banner(banner.clone()));
                self.controller_was_reset();
                self.progress.send_modify(|p| {
                    p.resets += 1;
                    p.version = Some(banner.version);
                    p.firmware = Some(banner.firmware);
                    if p.alarm != Some(3) {
                        p.alarm = None;
                    }
                });
            }
            Response::Message(m) => {
                if m.contains("Unlocked") {
                    self.progress.send_modify(|p| p.alarm = None);
                }
                self.collect(&line);
                let _ = self.events.send(Event::Message(m));
            }
            Response::Feedback { .. } | Response::Setting { .. } | Response::StartupLine(_) => {
                self.collect(&line);
            }
            Response::Other(o) => {
                let _ = self.events.send(Event::Other(o));
            }
        }
    }

    /// A soft reset went out: GRBL flushes its RX buffer and planner, so nothing sent before it
    /// will be answered, and an `ok` still on its way belongs to a line that is gone. The
    /// answer queue is emptied now and nothing is sent until the reset shows (its banner, or a
    /// second status report for a controller that prints none).
    fn reset_written(&mut self) {
        // The job ends when the controller shows the reset (an `ALARM:3` for a reset in motion
        // comes first and names the fault); its unanswered lines are remembered for that.
        let unacked = self.unacked_lines();
        if let Some(job) = self.job.as_mut() {
            job.unacked_at_reset = unacked;
        }
        self.forget_answers();
        self.awaiting_reset = Some(0);
    }

    /// The controller reset (asked for or not): the current job ends, every unanswered line is
    /// forgotten.
    fn controller_was_reset(&mut self) {
        self.awaiting_reset = None;
        if let Some(resetting) = self
            .job
            .as_ref()
            .filter(|j| j.reply.is_some())
            .map(|j| j.resetting)
        {
            self.fail_job(if resetting {
                Fault::Aborted
            } else {
                Fault::UnexpectedReset
            });
        }
        self.forget_answers();
        self.job = None;
    }

    /// Every unanswered line is forgotten (command callers get an error now).
    fn forget_answers(&mut self) {
        for e in self.sent.drain(..) {
            if let Sent::Command {
                reply: Some(r),
                text,
                ..
            } = e.what
            {
                let _ = r.send(Err(ClientError::Rejected {
                    command: text,
                    code: 0,
                    message: "controller reset before answering",
                }));
            }
        }
        self.budget.clear();
        let streaming = self.job.as_ref().is_some_and(|j| j.reply.is_some());
        self.progress.send_modify(|p| {
            p.rx_bytes_in_flight = 0;
            p.streaming = streaming;
        });
    }

    /// Push lines belong to the command at the head of the answer queue, if any.
    fn collect(&mut self, line: &str) {
        if let Some(SentEntry {
            what: Sent::Command { lines, .. },
            ..
        }) = self.sent.front_mut()
        {
            lines.push(line.to_string());
        }
    }

    fn answered(&mut self, error: Option<u8>) {
        let Some(entry) = self.sent.pop_front() else {
            let _ = self.events.send(Event::Other(format!(
                "answer with nothing outstanding: {}",
                error.map_or("ok".to_string(), |c| format!("error:{c}"))
            )));
            return;
        };
        self.budget.answered();
        let used = self.budget.used();
        match entry.what {
            Sent::Command { text, reply, lines } => {
                if let Some(r) = reply {
                    let _ = r.send(match error {
                        None => Ok(CommandReply { lines }),
                        Some(code) => Err(ClientError::Rejected {
                            command: text,
                            code,
                            message: error_message(code),
                        }),
                    });
                }
                if let Some(code) = error {
                    let _ = self.events.send(Event::Error { code, line: None });
                }
                self.progress.send_modify(|p| p.rx_bytes_in_flight = used);
            }
            Sent::Program { index, job } => {
                let Some(j) = self.job.as_mut().filter(|j| j.id == job) else {
                    self.progress.send_modify(|p| p.rx_bytes_in_flight = used);
                    return;
                };
                let line = &j.program.lines()[index];
                let number = line.number;
                match error {
                    None => {
                        j.acked += 1;
                        let acked = j.acked;
                        let all = j.next >= j.program.len() && acked == j.next - j.start;
                        if all && j.all_acked_at.is_none() {
                            let seq = self.progress.borrow().status_count;
                            j.all_acked_at = Some((Instant::now(), seq));
                        }
                        self.progress.send_modify(|p| {
                            p.lines_acked = acked;
                            p.last_acked_line = Some(number);
                            p.rx_bytes_in_flight = used;
                        });
                    }
                    Some(code) => {
                        let text = line.text.clone();
                        let _ = self.events.send(Event::Error {
                            code,
                            line: Some(number),
                        });
                        self.progress.send_modify(|p| p.rx_bytes_in_flight = used);
                        if j.reply.is_some() {
                            // Hold at once: the link task writes `!` before anything else.
                            self.hold_pending = true;
                            self.fail_job(Fault::Rejected {
                                line: number,
                                text,
                                code,
                                message: error_message(code),
                            });
                        }
                    }
                }
            }
        }
    }

    fn on_status(&mut self, s: StatusReport) {
        // The first report may have been on its way before the reset; the second answers a `?`
        // written after it.
        if let Some(n) = self.awaiting_reset.as_mut() {
            *n += 1;
            if *n >= 2 {
                self.controller_was_reset();
            }
        }
        if let Some(b) = s.buffer {
            self.planner_size = self.planner_size.max(b.planner_free);
        }
        let state = s.state;
        let planner_empty = s.buffer.is_none_or(|b| b.planner_free >= self.planner_size);
        let planner_size = self.planner_size;
        self.progress.send_modify(|p| {
            p.planner_blocks = planner_size;
            if let Some(w) = &s.wco {
                p.wco = Some(w.clone());
            }
            p.machine_position = s.machine_position(p.wco.as_deref());
            p.work_position = s.work_position(p.wco.as_deref());
            p.status_count += 1;
            p.status = Some(s);
        });
        let count = self.progress.borrow().status_count;
        // A finished job ends at the first report after its last `ok` that shows the machine
        // idle with an empty planner.
        let done = self.job.as_ref().is_some_and(|j| {
            j.reply.is_some()
                && j.all_acked_at.is_some_and(|(_, seq)| count > seq)
                && state == Some(MachineState::Idle)
                && planner_empty
        });
        if done {
            if let Some(mut j) = self.job.take() {
                let (acked_at, _) = j.all_acked_at.unwrap_or((Instant::now(), 0));
                let lines = j.next - j.start;
                let report = JobReport {
                    lines,
                    bytes: j.bytes,
                    first_line: j.program.lines()[j.start].number,
                    last_line: j.program.lines()[j.next - 1].number,
                    stream_time: acked_at.duration_since(j.started),
                    total_time: j.started.elapsed(),
                };
                if let Some(r) = j.reply.take() {
                    let _ = r.send(Ok(report));
                }
            }
            self.progress.send_modify(|p| p.streaming = false);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_counts_every_byte_and_frees_in_order() {
        // GRBL's 128-byte ring holds 127 bytes.
        let mut b = RxBudget::new(RX_BUFFER_SIZE - 1);
        assert!(b.fits(127));
        assert!(!b.fits(128));
        b.sent(60); // "G1 X..." 59 characters + \n
        b.sent(60);
        assert_eq!(b.used(), 120);
        assert!(b.fits(7));
        assert!(!b.fits(8), "one byte more would overflow GRBL's buffer");
        assert_eq!(b.answered(), Some(60));
        assert_eq!(b.outstanding(), 1);
        assert!(b.fits(67));
        b.sent(67);
        assert_eq!(b.used(), 127);
        assert_eq!(b.answered(), Some(60));
        assert_eq!(b.answered(), Some(67));
        assert_eq!(
            b.answered(),
            None,
            "an answer with nothing outstanding is not counted"
        );
        assert_eq!(b.used(), 0);
        b.sent(10);
        b.clear();
        assert_eq!((b.used(), b.outstanding(), b.capacity()), (0, 0, 127));
    }

    #[test]
    fn stream_errors_read_as_one_line() {
        let e = StreamError {
            fault: Fault::Rejected {
                line: 42,
                text: "G1 X5 Q3".into(),
                code: 20,
                message: error_message(20),
            },
            last_acked_line: Some(41),
            unacked_lines: vec![43, 44, 45],
            safe_stop: None,
        };
        assert_eq!(
            e.to_string(),
            "line 42 (G1 X5 Q3): error:20 Unsupported command; last acknowledged line 41; lines 43-45 sent but not acknowledged"
        );
    }
}
