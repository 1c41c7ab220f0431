//! A Marlin printer behind the bridge: keeps the link up, streams programs ping-pong with line
//! numbers and checksums ([`cell_marlin::client`]), polls `M105`/`M114`, and reports its state
//! as a [`MachineStatus`].
//!
//! The heat rule: every stop ends with the heaters off by the printer's own word. A finished
//! program, an abort, a shutdown, a fault (kill, timeout, reset) and a lost link all end in
//! [`MarlinLink::heat_off`] (`M108`/`M410` for a running command, `M104 S0`, `M140 S0`, then
//! `M105` must show both targets at 0), on the link it ran on or, when that link is gone or
//! the printer halted, on a new one (an 8-bit board resets when its port opens: the reset
//! switches its heaters off, and `M105` confirms it). When no confirmation can be had, the
//! outcome says so. On connecting with no program of ours running, a printer found heating is
//! switched off first (a bridge that crashed mid-job).

pub mod config;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use cell_grbl::transport::Connect;
use cell_marlin::client::{LinkError, LinkState, MarlinLink, Sent};
use cell_marlin::protocol::Temps;
use cell_marlin::sim::SimHandle;
use cell_msgs::{ExecuteProgramResult as R, MachineCommand, MachineProgram, MachineStatus};
use tokio::sync::watch;

use crate::controller::{lock, JobInfo, RunOutcome};
pub use config::MarlinControllerConfig;
use config::MarlinEndpoint;

/// Marlin's `MAX_CMD_SIZE`: longer lines are cut off by the firmware.
const MAX_CMD_SIZE: usize = 96;

/// One Marlin printer.
pub struct MarlinController {
    cfg: MarlinControllerConfig,
    connector: Arc<dyn Connect>,
    sim: Option<SimHandle>,
    link: tokio::sync::Mutex<Option<MarlinLink>>,
    state: watch::Sender<LinkState>,
    job: Mutex<Option<JobInfo>>,
    busy: AtomicBool,
    stop: watch::Sender<bool>,
    hold: watch::Sender<bool>,
    /// Override commands (`M220`, `M221`) to send before the next line.
    pending: Mutex<Vec<String>>,
    link_error: Mutex<Option<String>>,
    /// The last stop's or fault's line, for `MachineStatus.alarm` and the operator.
    last_fault: Mutex<Option<String>>,
    /// The last heat check: the `M105` report that showed both targets at 0.
    last_heat_off: Mutex<Option<Temps>>,
}

impl std::fmt::Debug for MarlinController {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MarlinController")
            .field("id", &self.cfg.id)
            .field("link", &self.connector.describe())
            .finish_non_exhaustive()
    }
}

/// A program's lines as sent: (original 1-based line number, command without comment).
type Lines = Vec<(usize, String)>;

impl MarlinController {
    /// Sets the controller up (starting the simulator for a `simulator` endpoint) and spawns
    /// the task that connects, polls and keeps the link up while no program runs.
    ///
    /// # Errors
    /// Only a simulator that cannot listen on loopback.
    pub async fn start(cfg: MarlinControllerConfig) -> std::io::Result<Arc<Self>> {
        let (connector, sim): (Arc<dyn Connect>, _) = match (&cfg.endpoint, cfg.endpoint()) {
            (MarlinEndpoint::Simulator(s), _) => {
                let sim = cell_marlin::sim::start(s.sim_config());
                let addr = sim.listen_tcp("127.0.0.1:0").await?;
                (
                    Arc::new(cell_grbl::transport::Endpoint::Tcp(addr.to_string())),
                    Some(sim),
                )
            }
            (_, Some(e)) => (Arc::new(e), None),
            (_, None) => unreachable!("every endpoint but the simulator has an address"),
        };
        let c = Arc::new(MarlinController {
            cfg,
            connector,
            sim,
            link: tokio::sync::Mutex::new(None),
            state: watch::channel(LinkState::default()).0,
            job: Mutex::new(None),
            busy: AtomicBool::new(false),
            stop: watch::channel(false).0,
            hold: watch::channel(false).0,
            pending: Mutex::new(Vec::new()),
            link_error: Mutex::new(None),
            last_fault: Mutex::new(None),
            last_heat_off: Mutex::new(None),
        });
        tokio::spawn(keep_connected(Arc::downgrade(&c)));
        Ok(c)
    }

    /// The controller file.
    pub fn config(&self) -> &MarlinControllerConfig {
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

    /// What the link knows (temperatures, position, kill reason, counters).
    pub fn link_state(&self) -> LinkState {
        self.state.borrow().clone()
    }

    /// The last `M105` report that confirmed the heaters off.
    pub fn last_heat_off(&self) -> Option<Temps> {
        *lock(&self.last_heat_off)
    }

    /// The last stop's or fault's line.
    pub fn last_fault(&self) -> Option<String> {
        lock(&self.last_fault).clone()
    }

    /// Waits until the link is up, or `timeout`.
    pub async fn wait_connected(&self, timeout: Duration) -> bool {
        let deadline = tokio::time::Instant::now() + timeout;
        while tokio::time::Instant::now() < deadline {
            if self.state.borrow().connected {
                return true;
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        self.state.borrow().connected
    }

    fn period(&self) -> Duration {
        Duration::from_secs_f64(self.cfg.status_period_s)
    }

    /// The lines to send from `start_line`, or why `program` cannot run here.
    pub(crate) fn prepare(
        &self,
        program: &MachineProgram,
        start_line: u32,
    ) -> Result<(Lines, usize), String> {
        let refusal = crate::program_fit::gcode_refusal(
            &self.cfg.id,
            "marlin",
            &self.cfg.machine_profile,
            program,
        );
        if let Some(why) = refusal {
            return Err(why);
        }
        let file = &program.files[0];
        let mut lines = Lines::new();
        for (i, raw) in file.text.lines().enumerate() {
            let text = raw.split(';').next().unwrap_or("").trim();
            if text.is_empty() {
                continue;
            }
            if text.contains('*') || !text.is_ascii() {
                return Err(format!(
                    "{}:{}: `*` and non-ASCII text cannot go on Marlin's checksummed lines",
                    file.name,
                    i + 1
                ));
            }
            // N<n> , space, `*`, up to three checksum digits.
            if text.len() + 16 > MAX_CMD_SIZE {
                return Err(format!(
                    "{}:{}: line is {} bytes; Marlin takes {} with its line number and checksum",
                    file.name,
                    i + 1,
                    text.len(),
                    MAX_CMD_SIZE - 16
                ));
            }
            lines.push((i + 1, text.to_owned()));
        }
        if lines.is_empty() {
            return Err(format!("{}: no G-code line in the program", file.name));
        }
        let from = if start_line == 0 {
            0
        } else {
            lines
                .iter()
                .position(|(n, _)| *n >= start_line as usize)
                .ok_or_else(|| {
                    format!(
                        "start_line {start_line} is past the program's last line ({})",
                        lines.last().map_or(0, |l| l.0)
                    )
                })?
        };
        Ok((lines, from))
    }

    /// Runs `program` from original line `start_line` (0: the first) and ends with the heat off,
    /// confirmed by `M105`, however it ends.
    pub async fn execute(&self, program: &MachineProgram, start_line: u32) -> RunOutcome {
        let refuse = |m: String| RunOutcome::refused(m, self.status().state);
        let (lines, from) = match self.prepare(program, start_line) {
            Ok(p) => p,
            Err(why) => return refuse(why),
        };
        if self.busy.swap(true, Ordering::SeqCst) {
            return refuse(format!(
                "controller {} is running another program",
                self.cfg.id
            ));
        }
        let mut guard = self.link.lock().await;
        let Some(link) = guard.as_mut() else {
            self.busy.store(false, Ordering::SeqCst);
            let why = lock(&self.link_error)
                .clone()
                .unwrap_or_else(|| "not connected yet".into());
            return refuse(format!(
                "controller {} is not connected: {why}",
                self.cfg.id
            ));
        };
        self.stop.send_replace(false);
        self.hold.send_replace(false);
        *lock(&self.job) = Some(JobInfo::new(
            program,
            program.files[0].text.lines().count(),
            lines.len() - from,
        ));
        *lock(&self.last_fault) = None;
        let t0 = Instant::now();
        let ran = self.stream(link, &lines[from..]).await;
        let acked = lock(&self.job).as_ref().map_or(0, |j| j.acked_line);
        let outcome = match ran {
            Ok(Streamed::Finished) => match link.heat_off().await {
                Ok(t) => {
                    *lock(&self.last_heat_off) = Some(t);
                    RunOutcome {
                        success: true,
                        outcome: R::OUTCOME_FINISHED,
                        message: {
                            let st = link.state();
                            format!(
                                "{} lines streamed to {} in {:.1} s ({} resent), heated to \
                                 T:{:.1} B:{:.1}; heaters off, confirmed by M105: {t}",
                                lines.len() - from,
                                self.cfg.id,
                                t0.elapsed().as_secs_f64(),
                                st.resent,
                                st.peak_c.0,
                                st.peak_c.1
                            )
                        },
                        line: acked,
                        last_acked_line: acked,
                        reconnects: 0,
                        final_state: MachineStatus::STATE_DONE,
                    }
                }
                Err(e) => {
                    let heat = self.recover(&mut guard, &e).await;
                    self.ended(
                        R::OUTCOME_ALARM,
                        format!("the program ran, but {e}"),
                        acked,
                        heat,
                    )
                }
            },
            Ok(Streamed::Stopped) => {
                let link = guard.as_mut().expect("held");
                let heat = match link.heat_off().await {
                    Ok(t) => Ok(t),
                    Err(e) => {
                        // The printer does not obey: the emergency stop, then a fresh link.
                        let _ = link.emergency_stop().await;
                        Err(self.recover(&mut guard, &e).await)
                    }
                };
                let heat = heat.map_or_else(|h| h, |t| Heat::Confirmed(t, false));
                self.ended(R::OUTCOME_ABORTED, "aborted".into(), acked, heat)
            }
            Err(e) => {
                if matches!(e, LinkError::Timeout(_)) {
                    if let Some(link) = guard.as_mut() {
                        let _ = link.emergency_stop().await;
                    }
                }
                let heat = self.recover(&mut guard, &e).await;
                let outcome = match e {
                    LinkError::Closed(_) => R::OUTCOME_LINK_LOST,
                    _ => R::OUTCOME_ALARM,
                };
                self.ended(outcome, e.to_string(), acked, heat)
            }
        };
        if let Some(job) = lock(&self.job).as_mut() {
            job.finished = Some(outcome.outcome);
        }
        if !outcome.success {
            *lock(&self.last_fault) = Some(outcome.message.clone());
        }
        drop(guard);
        self.busy.store(false, Ordering::SeqCst);
        RunOutcome {
            final_state: if outcome.success {
                MachineStatus::STATE_DONE
            } else {
                self.status().state
            },
            ..outcome
        }
    }

    fn ended(&self, outcome: u8, what: String, acked: u32, heat: Heat) -> RunOutcome {
        if let Heat::Confirmed(t, _) = &heat {
            *lock(&self.last_heat_off) = Some(*t);
        }
        RunOutcome {
            success: false,
            outcome,
            message: format!(
                "{}: {what} after line {acked}; {heat}; resume with start_line {} once the printer is checked",
                self.cfg.id,
                acked + 1
            ),
            line: acked,
            last_acked_line: acked,
            reconnects: u32::from(matches!(heat, Heat::Confirmed(_, true))),
            final_state: MachineStatus::STATE_UNKNOWN,
        }
    }

    /// The lines, one in flight; polls between lines; honours hold, abort and overrides.
    async fn stream(
        &self,
        link: &mut MarlinLink,
        lines: &[(usize, String)],
    ) -> Result<Streamed, LinkError> {
        let mut stop = self.stop.subscribe();
        let mut hold = self.hold.subscribe();
        let mut last_poll = Instant::now();
        let period = self.period();
        for (number, text) in lines {
            while *hold.borrow_and_update() && !*stop.borrow() {
                // Held: nothing more is sent; the printer finishes what it planned.
                link.temps().await?;
                tokio::select! {
                    _ = tokio::time::sleep(period) => {}
                    _ = hold.changed() => {}
                    _ = stop.changed() => {}
                }
            }
            if *stop.borrow_and_update() {
                return Ok(Streamed::Stopped);
            }
            let injected = std::mem::take(&mut *lock(&self.pending));
            for c in injected {
                link.send(&c).await?;
            }
            if last_poll.elapsed() >= period {
                last_poll = Instant::now();
                link.temps().await?;
                link.position().await?;
            }
            match link.send_until(text, &mut stop).await? {
                Sent::Acked(_) => {
                    if let Some(j) = lock(&self.job).as_mut() {
                        j.acked_line = *number as u32;
                        j.acked_lines += 1;
                    }
                }
                Sent::Interrupted => return Ok(Streamed::Stopped),
            }
        }
        // Finished means moved: the planner runs dry before the end is reported.
        match link.send_until("M400", &mut stop).await? {
            Sent::Acked(_) => Ok(Streamed::Finished),
            Sent::Interrupted => Ok(Streamed::Stopped),
        }
    }

    /// After a fault: a new link (the old one is dropped), then the heat off and read back.
    async fn recover(
        &self,
        guard: &mut tokio::sync::MutexGuard<'_, Option<MarlinLink>>,
        fault: &LinkError,
    ) -> Heat {
        **guard = None;
        let mut last = fault.to_string();
        for attempt in 0..self.cfg.reconnect.attempts.max(1) {
            if attempt > 0 {
                tokio::time::sleep(Duration::from_secs_f64(self.cfg.reconnect.delay_s)).await;
            }
            match MarlinLink::connect(
                &self.connector,
                self.cfg.client_config(),
                self.state.clone(),
            )
            .await
            {
                Ok(mut link) => match link.heat_off().await {
                    Ok(t) => {
                        **guard = Some(link);
                        return Heat::Confirmed(t, true);
                    }
                    Err(e) => last = e.to_string(),
                },
                Err(e) => last = e.to_string(),
            }
        }
        *lock(&self.link_error) = Some(last.clone());
        Heat::Unknown(last)
    }

    /// Acts on an operator command now.
    pub async fn command(&self, command: &MachineCommand) -> Result<String, String> {
        let id = &self.cfg.id;
        let busy = self.busy.load(Ordering::SeqCst);
        match command.command {
            MachineCommand::COMMAND_HOLD if busy => {
                self.hold.send_replace(true);
                Ok(format!("{id}: hold: no more lines are sent; the printer finishes its planned moves, heaters stay on"))
            }
            MachineCommand::COMMAND_RESUME if busy => {
                self.hold.send_replace(false);
                Ok(format!("{id}: resumed"))
            }
            MachineCommand::COMMAND_HOLD | MachineCommand::COMMAND_RESUME => {
                Err(format!("{id}: no program is running"))
            }
            MachineCommand::COMMAND_ABORT if busy => {
                self.stop.send_replace(true);
                Ok(format!(
                    "{id}: abort: the program stops with the heaters off (M105 confirms)"
                ))
            }
            MachineCommand::COMMAND_ABORT => {
                let mut guard = self.link.lock().await;
                let Some(link) = guard.as_mut() else {
                    return Err(format!("{id}: not connected"));
                };
                match link.heat_off().await {
                    Ok(t) => {
                        *lock(&self.last_heat_off) = Some(t);
                        Ok(format!("{id}: abort: heaters off, confirmed by M105: {t}"))
                    }
                    Err(e) => {
                        let heat = self.recover(&mut guard, &e).await;
                        Err(format!("{id}: abort: {e}; {heat}"))
                    }
                }
            }
            MachineCommand::COMMAND_FEED_OVERRIDE | MachineCommand::COMMAND_SPINDLE_OVERRIDE => {
                if !(10..=200).contains(&command.value) {
                    return Err(format!("{id}: override {}%: 10..200 %", command.value));
                }
                // Marlin: M220 feedrate percentage; the "spindle" of a printer is its flow (M221).
                let code = if command.command == MachineCommand::COMMAND_FEED_OVERRIDE {
                    "M220"
                } else {
                    "M221"
                };
                let line = format!("{code} S{}", command.value);
                if busy {
                    lock(&self.pending).push(line.clone());
                    return Ok(format!("{id}: {line} goes out before the next line"));
                }
                let mut guard = self.link.lock().await;
                let link = guard
                    .as_mut()
                    .ok_or_else(|| format!("{id}: not connected"))?;
                link.send(&line).await.map_err(|e| format!("{id}: {e}"))?;
                Ok(format!("{id}: {line} sent"))
            }
            other => Err(format!("{id}: unknown command {other}")),
        }
    }

    /// Brings the printer to a safe state within about `budget` before the process exits: a
    /// running program is aborted (it ends with the heat off), an idle printer gets the heat
    /// off; one line for the log.
    pub async fn stop_for_shutdown(&self, budget: Duration) -> String {
        let id = &self.cfg.id;
        let deadline = tokio::time::Instant::now() + budget;
        self.stop.send_replace(true);
        while self.busy.load(Ordering::SeqCst) && tokio::time::Instant::now() < deadline {
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        if self.busy.load(Ordering::SeqCst) {
            return format!("{id}: the abort did not finish within {budget:?}: heat state unknown; check the printer");
        }
        let left = deadline.saturating_duration_since(tokio::time::Instant::now());
        let Ok(mut guard) = tokio::time::timeout(left, self.link.lock()).await else {
            return format!("{id}: heat state unknown: the link is busy");
        };
        let Some(link) = guard.as_mut() else {
            return format!("{id}: not connected: heat state unknown; check the printer");
        };
        match tokio::time::timeout(left.max(Duration::from_millis(500)), link.heat_off()).await {
            Ok(Ok(t)) => {
                *lock(&self.last_heat_off) = Some(t);
                format!("{id}: heaters off, confirmed by M105: {t}")
            }
            Ok(Err(e)) => format!("{id}: heat off failed: {e}; check the printer"),
            Err(_) => {
                format!("{id}: no M105 within {left:?}: heat state unknown; check the printer")
            }
        }
    }

    /// The last temperatures the printer reported, hotend then bed.
    pub fn heaters(&self) -> Vec<crate::controller::HeaterStatus> {
        let Some(t) = self.state.borrow().temps else {
            return Vec::new();
        };
        let reading =
            |name, r: cell_marlin::protocol::HeaterReading| crate::controller::HeaterStatus {
                name,
                current_c: r.current,
                target_c: r.target,
            };
        std::iter::once(reading("hotend", t.hotend))
            .chain(t.bed.map(|b| reading("bed", b)))
            .collect()
    }

    /// The printer's state now (the node stamps the header).
    pub fn status(&self) -> MachineStatus {
        let st = self.state.borrow().clone();
        let job = lock(&self.job).clone();
        let mut s = MachineStatus {
            machine_id: self.cfg.id.clone(),
            ..MachineStatus::default()
        };
        if let Some(j) = &job {
            s.job_id = j.job_id.clone();
            s.acked_line = j.acked_line;
            s.total_lines = j.total_lines;
        }
        let busy = self.busy.load(Ordering::SeqCst);
        s.state = if !st.connected {
            s.alarm = lock(&self.link_error).clone().unwrap_or_default();
            MachineStatus::STATE_DISCONNECTED
        } else if st.killed.is_some() {
            MachineStatus::STATE_ALARM
        } else if busy && *self.hold.borrow() {
            MachineStatus::STATE_HOLD
        } else if busy {
            MachineStatus::STATE_RUNNING
        } else if job.and_then(|j| j.finished) == Some(R::OUTCOME_FINISHED) {
            MachineStatus::STATE_DONE
        } else {
            MachineStatus::STATE_IDLE
        };
        for (axis, v) in &st.position {
            s.axis_names.push(axis.to_string());
            s.axis_positions.push(*v);
        }
        if let Some(k) = st.killed {
            s.alarm = format!("printer halted: {k}");
        } else if s.alarm.is_empty() {
            s.alarm = lock(&self.last_fault).clone().unwrap_or_default();
        }
        s
    }

    /// Connects if needed; polls; a printer found heating with no program of ours is switched
    /// off first.
    async fn keep(&self) {
        if self.busy.load(Ordering::SeqCst) {
            return;
        }
        let Ok(mut guard) = self.link.try_lock() else {
            return;
        };
        if self.busy.load(Ordering::SeqCst) {
            return;
        }
        if guard.is_none() {
            match MarlinLink::connect(
                &self.connector,
                self.cfg.client_config(),
                self.state.clone(),
            )
            .await
            {
                Ok(mut link) => {
                    tracing::info!("{}: connected ({})", self.cfg.id, self.connector.describe());
                    *lock(&self.link_error) = None;
                    match link.temps().await {
                        Ok(t) if !t.targets_off() => {
                            tracing::warn!(
                                "{}: found the printer heating ({t}) with no program of ours: heaters off",
                                self.cfg.id
                            );
                            match link.heat_off().await {
                                Ok(off) => {
                                    *lock(&self.last_heat_off) = Some(off);
                                    *lock(&self.last_fault) = Some(format!(
                                        "found heating ({t}) with no program running: heaters off, confirmed by M105: {off}"
                                    ));
                                    *guard = Some(link);
                                }
                                Err(e) => *lock(&self.link_error) = Some(e.to_string()),
                            }
                        }
                        Ok(_) => *guard = Some(link),
                        Err(e) => *lock(&self.link_error) = Some(e.to_string()),
                    }
                }
                Err(e) => *lock(&self.link_error) = Some(e.to_string()),
            }
            return;
        }
        let link = guard.as_mut().expect("checked");
        let polled = async {
            link.temps().await?;
            link.position().await
        }
        .await;
        if let Err(e) = polled {
            tracing::warn!("{}: {e}", self.cfg.id);
            *lock(&self.link_error) = Some(e.to_string());
            *guard = None;
        }
    }
}

/// How a stream ended, short of a fault.
enum Streamed {
    Finished,
    Stopped,
}

/// What is known of the heat after a stop.
enum Heat {
    /// `M105` showed both targets at 0 (after reconnecting: `true`).
    Confirmed(Temps, bool),
    /// No confirmation: why.
    Unknown(String),
}

impl std::fmt::Display for Heat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Heat::Confirmed(t, false) => write!(f, "heaters off, confirmed by M105: {t}"),
            Heat::Confirmed(t, true) => {
                write!(f, "reconnected; heaters off, confirmed by M105: {t}")
            }
            Heat::Unknown(why) => write!(
                f,
                "heat state UNKNOWN ({why}): check the printer; a halted Marlin has its heaters off but needs a reset"
            ),
        }
    }
}

async fn keep_connected(c: std::sync::Weak<MarlinController>) {
    loop {
        let Some(me) = c.upgrade() else {
            return;
        };
        let period = me.period();
        me.keep().await;
        drop(me);
        tokio::time::sleep(period).await;
    }
}
