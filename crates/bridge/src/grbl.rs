//! A GRBL-class controller behind the bridge: keeps the link up, runs programs with
//! [`cell_grbl::stream::GrblClient`], resumes after link drops when the controller file allows
//! it, and reports its state as a [`MachineStatus`].

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::protocol::{alarm_message, MachineState};
use cell_grbl::sim::{SimConfig, SimHandle};
use cell_grbl::stream::{
    Fault, GrblClient, HeatState, JobReport, Progress, SafeStopReport, StreamError,
};
use cell_grbl::transport::Connect;
use cell_msgs::{ExecuteProgramResult as R, MachineCommand, MachineProgram, MachineStatus};

use crate::config::{EndpointConfig, GrblControllerConfig, ResumePolicy, SimulatorFirmware};
use crate::controller::{lock, JobInfo, RunOutcome};

mod restore;

/// One GRBL-class controller.
pub struct GrblController {
    cfg: GrblControllerConfig,
    connector: Arc<dyn Connect>,
    sim: Option<SimHandle>,
    client: Mutex<Option<GrblClient>>,
    job: Arc<Mutex<Option<JobInfo>>>,
    /// A program is running (the keeper leaves reconnecting to it).
    busy: AtomicBool,
    abort_requested: AtomicBool,
    /// Why the last connection attempt failed, for `MachineStatus.alarm`.
    link_error: Mutex<Option<String>>,
    /// The last run's alarm or rejected line, for `MachineStatus.alarm` (a soft reset clears
    /// GRBL's own alarm code, not the reason the program stopped).
    last_fault: Mutex<Option<String>>,
    /// Held while the link keeper checks what it found on a (re)connect, so a program does
    /// not start in the middle of that check's safe stop.
    found_check: tokio::sync::Mutex<()>,
}

impl std::fmt::Debug for GrblController {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GrblController")
            .field("id", &self.cfg.id)
            .field("link", &self.connector.describe())
            .finish_non_exhaustive()
    }
}

impl GrblController {
    /// Sets the controller up (starting the simulator for a `simulator` endpoint) and spawns
    /// the task that connects and keeps the link up while no program runs. Never fails: an
    /// unreachable controller shows as disconnected, with the reason in its status.
    ///
    /// # Errors
    /// Only a simulator that cannot listen on loopback.
    pub async fn start(cfg: GrblControllerConfig) -> std::io::Result<Arc<Self>> {
        let (connector, sim): (Arc<dyn Connect>, _) = match (&cfg.endpoint, cfg.endpoint()) {
            (EndpointConfig::Simulator(s), _) => {
                let flavour = SimConfig::for_firmware(s.firmware.flavour());
                let sim = cell_grbl::sim::start(SimConfig {
                    time_scale: s.time_scale,
                    baud: (s.baud > 0).then_some(s.baud),
                    // GRBL 1.1's buffer is the file's; the larger firmwares keep their own
                    // (the file's value is then the client's safe fallback).
                    rx_buffer_bytes: if s.firmware == SimulatorFirmware::Grbl {
                        cfg.rx_buffer_bytes
                    } else {
                        flavour.rx_buffer_bytes
                    },
                    axes: cfg.axis_letters(),
                    rapid_mm_min: s.rapid_mm_min,
                    laser_mode: s.laser_mode,
                    ..flavour
                });
                let addr = sim.listen_tcp("127.0.0.1:0").await?;
                let endpoint = cell_grbl::transport::Endpoint::Tcp(addr.to_string());
                (Arc::new(endpoint), Some(sim))
            }
            (_, Some(endpoint)) => (Arc::new(endpoint), None),
            (_, None) => unreachable!("every endpoint but the simulator has an address"),
        };
        let controller = Arc::new(GrblController {
            cfg,
            connector,
            sim,
            client: Mutex::new(None),
            job: Arc::new(Mutex::new(None)),
            busy: AtomicBool::new(false),
            abort_requested: AtomicBool::new(false),
            link_error: Mutex::new(None),
            last_fault: Mutex::new(None),
            found_check: tokio::sync::Mutex::new(()),
        });
        tokio::spawn(keep_connected(Arc::downgrade(&controller)));
        Ok(controller)
    }

    /// The controller file.
    pub fn config(&self) -> &GrblControllerConfig {
        &self.cfg
    }

    /// The simulator behind a `simulator` endpoint.
    pub fn simulator(&self) -> Option<&SimHandle> {
        self.sim.as_ref()
    }

    /// The current (or last) job.
    pub fn job(&self) -> Option<JobInfo> {
        lock(&self.job).clone()
    }

    fn client(&self) -> Option<GrblClient> {
        lock(&self.client).clone()
    }

    /// Waits until the link is up, or `timeout`; returns whether it is.
    pub async fn wait_connected(&self, timeout: Duration) -> bool {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            if self
                .client()
                .is_some_and(|c| c.progress().borrow().connected)
            {
                return true;
            }
            if tokio::time::Instant::now() >= deadline {
                return false;
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }

    /// Why a program cannot run here, before anything is sent.
    fn refuse_reason(&self, program: &MachineProgram) -> Option<String> {
        crate::program_fit::gcode_refusal(&self.cfg.id, "grbl", &self.cfg.machine_profile, program)
    }

    /// The lines to send and the original line to start from, or why `program` cannot run
    /// here from `start_line` (0: the first): wrong dialect, machine profile or file count, text
    /// that does not parse, no G-code line, a start line past the end or one whose machine state
    /// a resume cannot restore ([`cell_grbl::resume`]). Nothing is sent.
    pub(crate) fn prepare(
        &self,
        program: &MachineProgram,
        start_line: u32,
    ) -> Result<(Program, usize), String> {
        if let Some(why) = self.refuse_reason(program) {
            return Err(why);
        }
        let file = &program.files[0];
        let options = CleanOptions {
            allowed_commands: self.cfg.allowed_commands.clone(),
            ..CleanOptions::default()
        };
        let parsed =
            Program::parse(&file.text, options).map_err(|e| format!("{}: {e}", file.name))?;
        let Some(first) = parsed.lines().first().map(|l| l.number) else {
            return Err(format!("{}: no G-code line in the program", file.name));
        };
        // Character counting could never send a line longer than the RX buffer: the stream
        // would stall on it, mid-program, heat on.
        if self.cfg.flow == crate::config::FlowConfig::CharacterCounting {
            let budget = self
                .client()
                .filter(|c| c.progress().borrow().connected)
                .map_or(self.cfg.rx_buffer_bytes.saturating_sub(1), |c| {
                    c.rx_budget()
                });
            if let Some(l) = parsed.lines().iter().find(|l| l.wire_len() > budget) {
                return Err(format!(
                    "{}:{}: line is {} bytes on the wire; controller {} takes at most {budget} (its RX buffer less one): split it",
                    file.name,
                    l.number,
                    l.wire_len(),
                    self.cfg.id
                ));
            }
        }
        let from = if start_line == 0 {
            first
        } else {
            match parsed.index_of_line(start_line as usize) {
                Some(i) => parsed.lines()[i].number,
                None => {
                    return Err(format!(
                        "start_line {start_line} is past the program's last line ({})",
                        parsed.lines().last().map_or(0, |l| l.number)
                    ))
                }
            }
        };
        if let Some(why) = self.resume_refusal(&parsed, from) {
            return Err(format!("{}: {why}", file.name));
        }
        Ok((parsed, from))
    }

    /// Runs `program` from original line `start_line` (0: the first), resuming after link
    /// drops when the controller file says `resume_after_link_drop: auto`.
    pub async fn execute(&self, program: &MachineProgram, start_line: u32) -> RunOutcome {
        let refuse = |message: String| RunOutcome::refused(message, self.state_now());
        let (parsed, from) = match self.prepare(program, start_line) {
            Ok(prepared) => prepared,
            Err(why) => return refuse(why),
        };
        let file = &program.files[0];
        let Some(client) = self.client().filter(|c| c.progress().borrow().connected) else {
            let why = lock(&self.link_error)
                .clone()
                .unwrap_or_else(|| "not connected yet".into());
            return refuse(format!(
                "controller {} is not connected: {why}",
                self.cfg.id
            ));
        };
        if self.busy.swap(true, Ordering::SeqCst) {
            return refuse(format!(
                "controller {} is running another program",
                self.cfg.id
            ));
        }
        // A check of what the link keeper found on connecting finishes first (it sees `busy`
        // and skips once this run is registered).
        drop(self.found_check.lock().await);
        self.abort_requested.store(false, Ordering::SeqCst);
        *lock(&self.job) = Some(JobInfo::new(
            program,
            file.text.lines().count(),
            parsed.len(),
        ));
        *lock(&self.last_fault) = None;
        // An operator's resume: the state the program had at `from` goes first.
        let outcome = match self.restore_state(&client, &parsed, from).await {
            Ok(()) => self.run(&client, &parsed, from).await,
            Err(stopped) => stopped,
        };
        if matches!(outcome.outcome, R::OUTCOME_ALARM | R::OUTCOME_REJECTED_LINE) {
            *lock(&self.last_fault) = Some(outcome.message.clone());
        }
        if let Some(job) = lock(&self.job).as_mut() {
            job.finished = Some(outcome.outcome);
        }
        self.busy.store(false, Ordering::SeqCst);
        RunOutcome {
            final_state: self.state_now(),
            ..outcome
        }
    }

    async fn run(&self, client: &GrblClient, program: &Program, mut from: usize) -> RunOutcome {
        let mut reconnects = 0u32;
        let mut last_acked: Option<usize> = None;
        let set_progress = |acked: Option<usize>| {
            if let (Some(job), Some(a)) = (lock(&self.job).as_mut(), acked) {
                job.acked_line = a as u32;
                job.acked_lines = program.index_of_line(a).map_or(0, |i| i + 1);
            }
        };
        // Feedback comes from the link task's progress while the stream runs.
        let watcher = {
            let mut rx = client.progress();
            let job = self.job.clone();
            let program = program.clone();
            tokio::spawn(async move {
                while rx.changed().await.is_ok() {
                    // The link task keeps the last acknowledged line across streams; it
                    // belongs to this one once this one has an `ok`.
                    let acked = {
                        let p = rx.borrow_and_update();
                        p.last_acked_line
                            .filter(|_| p.streaming && p.lines_acked > 0)
                    };
                    if let Some(a) = acked {
                        if let Some(j) = lock(&job).as_mut() {
                            j.acked_line = a as u32;
                            j.acked_lines = program.index_of_line(a).map_or(0, |i| i + 1);
                        }
                    }
                }
            })
        };
        let outcome = loop {
            match client.stream_from(program, from).await {
                Ok(report) => {
                    set_progress(Some(report.last_line));
                    break self.finished(program, &report, reconnects);
                }
                Err(e) => {
                    // Lines rise through a program: an acknowledged line before `from` is the
                    // link task's memory of an earlier stream, not this one's.
                    let acked_here = e.last_acked_line.filter(|&a| a >= from);
                    last_acked = acked_here.or(last_acked);
                    set_progress(last_acked);
                    let link_lost = matches!(e.fault, Fault::LinkLost(_));
                    let resumable = link_lost
                        && self.cfg.resume_after_link_drop == ResumePolicy::Auto
                        && reconnects < self.cfg.reconnect.max_resumes
                        && !self.abort_requested.load(Ordering::SeqCst);
                    if link_lost && !resumable {
                        // The controller may still be running what its planner held, heat on:
                        // the first thing on the new link is the safe stop.
                        tracing::warn!("{}: {e}; reconnecting to stop the machine", self.cfg.id);
                        let stop = client.reconnect_and_stop().await;
                        break self.failed(
                            program,
                            &StreamError {
                                safe_stop: Some(Box::new(stop)),
                                ..e
                            },
                            last_acked,
                            reconnects,
                        );
                    }
                    if !resumable {
                        break self.failed(program, &e, last_acked, reconnects);
                    }
                    reconnects += 1;
                    tracing::warn!("{}: {e}; reconnecting (drop {reconnects})", self.cfg.id);
                    // A banner on connect is normal (FluidNC greets every telnet client), so only
                    // an alarm tells that the controller lost its state with the link.
                    match client.reconnect().await {
                        Ok(p)
                            if p.alarm.is_some()
                                || p.status.as_ref().and_then(|s| s.state)
                                    == Some(MachineState::Alarm) =>
                        {
                            let mut out = self.failed(program, &e, last_acked, reconnects);
                            out.message = format!(
                                "{}; the controller is in alarm after reconnecting, so its planner may be lost: check the machine and resume from the line it stopped at",
                                out.message
                            );
                            break out;
                        }
                        Ok(_) => {}
                        Err(re) => {
                            let mut out = self.failed(program, &e, last_acked, reconnects);
                            out.message = format!("{}; reconnect failed: {re}", out.message);
                            break out;
                        }
                    }
                    if self.abort_requested.load(Ordering::SeqCst) {
                        // Aborted while the link was down: stop on the new link.
                        let stop = client.safe_stop().await;
                        break self.failed(
                            program,
                            &StreamError {
                                fault: Fault::Aborted,
                                safe_stop: Some(Box::new(stop)),
                                ..e
                            },
                            last_acked,
                            reconnects,
                        );
                    }
                    // Go on after the last acknowledged line; with none acknowledged in this
                    // stream, nothing of it reached the planner and it starts again.
                    if let Some(a) = acked_here {
                        let next = program.index_of_line(a).map(|i| i + 1);
                        match next.and_then(|i| program.lines().get(i)) {
                            Some(l) => from = l.number,
                            None => {
                                // Every line was acknowledged before the drop.
                                let report = JobReport {
                                    lines: program.len(),
                                    bytes: program.wire_bytes(),
                                    first_line: from,
                                    last_line: a,
                                    stream_time: Duration::ZERO,
                                    total_time: Duration::ZERO,
                                };
                                break self.finished(program, &report, reconnects);
                            }
                        }
                    }
                    tracing::info!("{}: resuming at line {from}", self.cfg.id);
                }
            }
        };
        watcher.abort();
        outcome
    }

    fn finished(&self, program: &Program, report: &JobReport, reconnects: u32) -> RunOutcome {
        let mut message = format!(
            "{} lines streamed to {} in {:.1} s",
            program.len(),
            self.cfg.id,
            report.total_time.as_secs_f64()
        );
        if reconnects > 0 {
            message.push_str(&format!(
                ", resumed after {reconnects} link drop{}",
                if reconnects == 1 { "" } else { "s" }
            ));
        }
        RunOutcome {
            success: true,
            outcome: R::OUTCOME_FINISHED,
            message,
            line: report.last_line as u32,
            last_acked_line: report.last_line as u32,
            reconnects,
            final_state: MachineStatus::STATE_DONE,
        }
    }

    fn failed(
        &self,
        program: &Program,
        e: &StreamError,
        last_acked: Option<usize>,
        reconnects: u32,
    ) -> RunOutcome {
        let acked = last_acked.unwrap_or(0) as u32;
        let (outcome, line) = match &e.fault {
            Fault::Rejected { line, .. } => (R::OUTCOME_REJECTED_LINE, *line as u32),
            Fault::Alarm { .. } | Fault::UnexpectedReset => (R::OUTCOME_ALARM, acked),
            Fault::LinkLost(_) | Fault::ClientGone => (R::OUTCOME_LINK_LOST, acked),
            Fault::Aborted => (R::OUTCOME_ABORTED, acked),
            Fault::Busy | Fault::NoSuchLine(_) | Fault::LineTooLong { .. } => {
                (R::OUTCOME_REFUSED, acked)
            }
        };
        let mut message = format!("{}: {e}", self.cfg.id);
        match &e.safe_stop {
            Some(stop) => {
                message.push_str("; ");
                message.push_str(&stop.summary());
            }
            // Nothing was sent, so nothing was switched on.
            None if outcome == R::OUTCOME_REFUSED => {}
            None => message.push_str("; no safe stop was run: heat state unknown"),
        }
        let mut resume_at = None;
        if outcome == R::OUTCOME_LINK_LOST {
            let pending = e.safe_stop.as_ref().and_then(|s| s.pending_blocks);
            let acked_index = last_acked.and_then(|a| program.index_of_line(a));
            match (pending, acked_index) {
                (Some(n), Some(i)) if n > 0 => {
                    let texts: Vec<&str> =
                        program.lines().iter().map(|l| l.text.as_str()).collect();
                    let at = cell_grbl::resume_point::first_unfinished(&texts, i, n.into());
                    resume_at = program.lines().get(at).map(|l| l.number as u32);
                    message.push_str(&format!(
                        "; the reset discarded {n} queued move{}: resume with start_line {} (the first move not finished; lines sent but not acknowledged may have run too: check the machine's position)",
                        if n == 1 { "" } else { "s" },
                        resume_at.unwrap_or(acked + 1)
                    ));
                }
                _ => message.push_str(&format!(
                    "; resume with start_line {} once the machine is checked",
                    acked + 1
                )),
            }
        }
        RunOutcome {
            success: false,
            outcome,
            message,
            // After a link loss whose safe stop discarded queued moves: the line to resume from.
            line: resume_at.unwrap_or(line),
            last_acked_line: acked,
            reconnects,
            final_state: MachineStatus::STATE_UNKNOWN,
        }
    }

    /// Acts on an operator command now: real-time bytes go out ahead of anything queued.
    pub async fn command(&self, command: &MachineCommand) -> Result<String, String> {
        if command.command == MachineCommand::COMMAND_ABORT {
            // Noted before anything else: a run waiting for its link to come back stops with
            // a safe stop on the new link instead of resuming.
            self.abort_requested.store(true, Ordering::SeqCst);
        }
        let client = self
            .client()
            .filter(|c| c.progress().borrow().connected)
            .ok_or_else(|| {
                if command.command == MachineCommand::COMMAND_ABORT
                    && self.busy.load(Ordering::SeqCst)
                {
                    format!(
                        "{}: abort: the link is down; the safe stop goes out first once it is back",
                        self.cfg.id
                    )
                } else {
                    format!("{}: not connected", self.cfg.id)
                }
            })?;
        let id = &self.cfg.id;
        let done = |what: &str| Ok(format!("{id}: {what}"));
        let r = match command.command {
            MachineCommand::COMMAND_HOLD => client.hold().await.map(|_| "feed hold (!) sent"),
            MachineCommand::COMMAND_RESUME => {
                // GRBL drops a `~` while the hold still decelerates (`Hold:1`): wait for
                // `Hold:0`, send it, and answer from the state the controller reports after.
                let timeout = Duration::from_secs_f64(self.cfg.resume_timeout_s);
                return match client.cycle_start_confirmed(timeout).await {
                    Ok(resumed) => Ok(format!("{id}: {resumed}")),
                    Err(e) => Err(format!("{id}: resume: {e}")),
                };
            }
            MachineCommand::COMMAND_ABORT => {
                self.abort_requested.store(true, Ordering::SeqCst);
                return match client.abort().await {
                    Ok(None) => done("abort: feed hold sent; the program stops with a safe stop"),
                    Ok(Some(report)) => done(&format!("abort: {}", report.summary())),
                    Err(e) => Err(format!("{id}: abort: {e}")),
                };
            }
            MachineCommand::COMMAND_FEED_OVERRIDE | MachineCommand::COMMAND_SPINDLE_OVERRIDE => {
                if !(10..=200).contains(&command.value) {
                    return Err(format!(
                        "{id}: override {}%: GRBL takes 10..200 %",
                        command.value
                    ));
                }
                if command.command == MachineCommand::COMMAND_FEED_OVERRIDE {
                    client.feed_override(command.value).await
                } else {
                    client.spindle_override(command.value).await
                }
                .map(|_| "override sent")
            }
            other => return Err(format!("{id}: unknown command {other}")),
        };
        r.map_err(|e| format!("{id}: {e}")).and_then(done)
    }

    /// Brings the machine to a safe state within about `budget` (the process is about to
    /// exit): a running program is aborted (its safe stop runs), a machine left running, in
    /// hold or with the heat on is safe-stopped, and the heat is read back from the
    /// controller. Returns one line for the log.
    pub async fn stop_for_shutdown(&self, budget: Duration) -> String {
        let id = &self.cfg.id;
        let deadline = tokio::time::Instant::now() + budget;
        self.abort_requested.store(true, Ordering::SeqCst);
        let Some(client) = self.client().filter(|c| c.progress().borrow().connected) else {
            return if self.busy.load(Ordering::SeqCst) {
                format!("{id}: the link is down: heat state unknown; check the machine")
            } else {
                format!("{id}: not connected")
            };
        };
        if self.busy.load(Ordering::SeqCst) {
            let _ = client.abort().await;
            while self.busy.load(Ordering::SeqCst) && tokio::time::Instant::now() < deadline {
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
        }
        let left = deadline.saturating_duration_since(tokio::time::Instant::now());
        let heat = client.heat_state().await;
        if heat.is_confirmed_off() && !machine_moving(&client) {
            return format!("{id}: {heat}");
        }
        let stop = client.safe_stop_within(left).await;
        format!("{id}: {}", stop.summary())
    }

    /// What the link keeper does on every (re)connect while no program of ours runs: a
    /// controller found moving, in hold or with the heat on (a bridge that was killed, a
    /// program someone else started) gets the safe stop before anything else.
    async fn check_found_state(&self, client: &GrblClient) -> Option<SafeStopReport> {
        let _checking = self.found_check.lock().await;
        if self.busy.load(Ordering::SeqCst) {
            return None;
        }
        let heat = client.heat_state().await;
        let moving = machine_moving(client);
        if !moving && !matches!(heat, HeatState::On { .. }) {
            return None;
        }
        tracing::warn!(
            "{}: found the machine {} with no program of ours running ({heat}): safe stop",
            self.cfg.id,
            client
                .progress()
                .borrow()
                .status
                .as_ref()
                .and_then(|s| s.state)
                .map_or("in an unknown state".to_string(), |s| format!("in {s:?}"))
        );
        let stop = client.safe_stop().await;
        let line = format!("{}: {}", self.cfg.id, stop.summary());
        if stop.heat.is_confirmed_off() {
            tracing::warn!("{line}");
        } else {
            tracing::error!("{line}");
        }
        *lock(&self.last_fault) = Some(line);
        Some(stop)
    }

    fn state_now(&self) -> u8 {
        self.status().state
    }

    /// The controller's state now (the node stamps the header).
    pub fn status(&self) -> MachineStatus {
        let progress = self.client().map(|c| c.progress().borrow().clone());
        let job = lock(&self.job).clone();
        let link_error = lock(&self.link_error).clone();
        let mut s = status_from(&self.cfg, progress.as_ref(), job.as_ref(), link_error);
        if s.alarm.is_empty() {
            s.alarm = lock(&self.last_fault).clone().unwrap_or_default();
        }
        s
    }
}

/// The controller reports motion or a paused motion (hold and door count: a `~` would go on).
fn machine_moving(client: &GrblClient) -> bool {
    matches!(
        client
            .progress()
            .borrow()
            .status
            .as_ref()
            .and_then(|s| s.state),
        Some(
            MachineState::Run
                | MachineState::Jog
                | MachineState::Hold(_)
                | MachineState::Door(_)
                | MachineState::Home
        )
    )
}

/// `MachineStatus` from the link task's progress and the current job.
fn status_from(
    cfg: &GrblControllerConfig,
    progress: Option<&Progress>,
    job: Option<&JobInfo>,
    link_error: Option<String>,
) -> MachineStatus {
    let mut s = MachineStatus {
        machine_id: cfg.id.clone(),
        axis_names: cfg.axis_letters().iter().map(|c| c.to_string()).collect(),
        ..MachineStatus::default()
    };
    if let Some(job) = job {
        s.job_id = job.job_id.clone();
        s.acked_line = job.acked_line;
        s.total_lines = job.total_lines;
    }
    let Some(p) = progress.filter(|p| p.connected) else {
        s.state = MachineStatus::STATE_DISCONNECTED;
        s.alarm = link_error.unwrap_or_default();
        return s;
    };
    let report = p.status.as_ref();
    let grbl_state = report.and_then(|r| r.state);
    s.state = match grbl_state {
        Some(MachineState::Alarm) => MachineStatus::STATE_ALARM,
        Some(MachineState::Hold(_) | MachineState::Door(_)) => MachineStatus::STATE_HOLD,
        Some(MachineState::Run | MachineState::Jog | MachineState::Home) => {
            MachineStatus::STATE_RUNNING
        }
        Some(MachineState::Idle | MachineState::Check | MachineState::Sleep) => {
            match job.and_then(|j| j.finished) {
                Some(cell_msgs::ExecuteProgramResult::OUTCOME_FINISHED) => {
                    MachineStatus::STATE_DONE
                }
                // Streaming, but the planner has not started moving yet.
                None if job.is_some() && p.streaming => MachineStatus::STATE_RUNNING,
                _ => MachineStatus::STATE_IDLE,
            }
        }
        None => MachineStatus::STATE_UNKNOWN,
    };
    if let Some(pos) = &p.machine_position {
        s.axis_positions = pos.iter().copied().take(s.axis_names.len()).collect();
        s.axis_names.truncate(s.axis_positions.len());
    } else {
        s.axis_names.clear();
    }
    // Planner fill when the controller reports `Bf:` (what is buffered ahead of the tool),
    // else the RX bytes character counting has in flight.
    let planner_blocks = cell_grbl::protocol::PLANNER_BLOCKS as f32;
    s.buffer_fill = match report.and_then(|r| r.buffer) {
        Some(b) => (1.0 - f32::from(b.planner_free) / planner_blocks).clamp(0.0, 1.0),
        None if p.rx_budget > 0 && p.rx_budget < usize::MAX => {
            (p.rx_bytes_in_flight as f32 / p.rx_budget as f32).clamp(0.0, 1.0)
        }
        None => 0.0,
    };
    s.feed_mm_s = report
        .and_then(|r| r.feed)
        .map_or(0.0, |f| (f / 60.0) as f32);
    if let Some(code) = p.alarm {
        s.alarm = format!("ALARM:{code} {}", alarm_message(code));
    }
    s
}

/// Connects, and reconnects after a drop while no program runs, until the controller is
/// dropped.
async fn keep_connected(controller: std::sync::Weak<GrblController>) {
    let mut logged: Option<String> = None;
    loop {
        let Some(c) = controller.upgrade() else {
            return;
        };
        let delay = Duration::from_secs_f64(c.cfg.reconnect.delay_s.max(0.05));
        let client = c.client();
        let result = match client {
            None => match GrblClient::connect(c.connector.clone(), c.cfg.client_config()).await {
                Ok(client) => {
                    tracing::info!("{}: connected ({})", c.cfg.id, c.connector.describe());
                    *lock(&c.client) = Some(client.clone());
                    c.check_found_state(&client).await;
                    Ok(())
                }
                Err(e) => Err(e),
            },
            Some(client)
                if !client.progress().borrow().connected && !c.busy.load(Ordering::SeqCst) =>
            {
                match client.reconnect().await {
                    Ok(_) => {
                        tracing::info!("{}: reconnected", c.cfg.id);
                        c.check_found_state(&client).await;
                        Ok(())
                    }
                    Err(e) => Err(e),
                }
            }
            Some(_) => Ok(()),
        };
        match result {
            Ok(()) => {
                *lock(&c.link_error) = None;
                logged = None;
            }
            Err(e) => {
                let why = e.to_string();
                if logged.as_deref() != Some(why.as_str()) {
                    tracing::warn!("{}: {why}; retrying every {delay:?}", c.cfg.id);
                    logged = Some(why.clone());
                }
                *lock(&c.link_error) = Some(why);
            }
        }
        drop(c);
        tokio::time::sleep(delay).await;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_grbl::protocol::{BufferState, StatusReport};

    fn cfg() -> GrblControllerConfig {
        match crate::config::ControllerSpec::resolve("grbl-sim").unwrap() {
            crate::config::ControllerSpec::Grbl(g) => g,
            _ => unreachable!(),
        }
    }

    #[test]
    fn status_maps_grbl_reports() {
        let cfg = cfg();
        let s = status_from(&cfg, None, None, Some("refused".into()));
        assert_eq!(s.state, MachineStatus::STATE_DISCONNECTED);
        assert_eq!(s.alarm, "refused");
        let mut p = Progress {
            connected: true,
            rx_budget: 127,
            rx_bytes_in_flight: 0,
            machine_position: Some(vec![1.0, 2.0, 3.0, 4.0]),
            status: Some(StatusReport {
                state: Some(MachineState::Run),
                buffer: Some(BufferState {
                    planner_free: 5,
                    rx_free: 100,
                }),
                feed: Some(600.0),
                ..StatusReport::default()
            }),
            ..Progress::default()
        };
        let s = status_from(&cfg, Some(&p), None, None);
        assert_eq!(s.state, MachineStatus::STATE_RUNNING);
        assert_eq!(s.axis_names, ["X", "Y", "U", "V"]);
        assert_eq!(s.axis_positions, [1.0, 2.0, 3.0, 4.0]);
        assert!((s.buffer_fill - 10.0 / 15.0).abs() < 1e-6);
        assert_eq!(s.feed_mm_s, 10.0);
        p.status.as_mut().unwrap().state = Some(MachineState::Hold(0));
        assert_eq!(
            status_from(&cfg, Some(&p), None, None).state,
            MachineStatus::STATE_HOLD
        );
        p.status.as_mut().unwrap().state = Some(MachineState::Alarm);
        p.alarm = Some(2);
        let s = status_from(&cfg, Some(&p), None, None);
        assert_eq!(s.state, MachineStatus::STATE_ALARM);
        assert!(s.alarm.starts_with("ALARM:2 "), "{}", s.alarm);
        p.status.as_mut().unwrap().state = Some(MachineState::Idle);
        p.alarm = None;
        let mut job = JobInfo::new(&MachineProgram::default(), 10, 8);
        job.finished = Some(R::OUTCOME_FINISHED);
        let s = status_from(&cfg, Some(&p), Some(&job), None);
        assert_eq!(s.state, MachineStatus::STATE_DONE);
        job.finished = Some(R::OUTCOME_ABORTED);
        let s = status_from(&cfg, Some(&p), Some(&job), None);
        assert_eq!(s.state, MachineStatus::STATE_IDLE);
    }
}
