//! An ABB robot behind the bridge, over Robot Web Services: upload and load the emitter's
//! RAPID, move the program pointer to `main`, start, follow the execution state until RAPID
//! stops. RWS reports no per-line progress here, so a run's feedback is 0 % until it ends.
//!
//! Every stop ends in the same safe stop (`rws/safe_stop.rs`: RAPID stopped, the controller
//! file's heat-off outputs written, both read back) and says whether the heat is confirmed off:
//! - **hold** stops RAPID (the program pointer stays) and switches the heat off. **Resume**
//!   starts RAPID from the program pointer and switches nothing on: a `SetDO doWeld, 1` program
//!   goes on without heat until it sets the output again (the rest of a weld run cut by the
//!   hold is travelled cold), an `ArcL` program restarts its arc as the arc system does.
//! - **abort** and **cancel** are checked before `start()` and race the upload: one that comes
//!   while the program is uploaded or loaded ends the run before RAPID is started. During the
//!   run they take effect within one poll, a hung poll included (polls, stop and I/O are
//!   bounded by `timeouts.control_s`).
//! - **a lost link** (three polls in a row fail) is answered with the safe stop, tried
//!   `reconnect.attempts` times; the result says "heat off confirmed" or "heat state unknown"
//!   and why. An unconfirmed stop is done again as soon as the controller answers.
//! - **start-up and every reconnect** with no run of ours: a heat-off output that reads on
//!   (a bridge killed mid-run, a link lost for longer than the retries) gets the safe stop
//!   before anything else.

mod safe_stop;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use cell_msgs::{ExecuteProgramResult as R, MachineCommand, MachineProgram, MachineStatus};
use cell_rws::{ControllerConfig, RwsClient};

use crate::controller::{lock, JobInfo, RunOutcome};
use safe_stop::SafeStop;

/// How often the execution state is polled (RWS clients commonly poll at 5 Hz).
const POLL: Duration = Duration::from_millis(200);

/// Consecutive failed polls during a run after which the link counts as lost (each fails
/// within `timeouts.control_s`).
const LOST_AFTER_FAILED_POLLS: u32 = 3;

#[derive(Debug, Default, Clone)]
struct Seen {
    connected: bool,
    running: bool,
    error: Option<String>,
}

/// One RWS controller.
pub struct RwsController {
    cfg: ControllerConfig,
    /// The in-repo simulator behind a `simulator:` controller (stops with the controller).
    sim: Option<cell_rws::sim::RwsSim>,
    client: Result<Arc<RwsClient>, String>,
    job: Mutex<Option<JobInfo>>,
    seen: Mutex<Seen>,
    /// A run of ours is in progress (upload to end).
    busy: AtomicBool,
    /// The current run's start request is on its way.
    starting: AtomicBool,
    /// The current run has started RAPID.
    started: AtomicBool,
    held: AtomicBool,
    abort_requested: AtomicBool,
    /// Wakes a run waiting on a request when an abort comes.
    abort_signal: tokio::sync::Notify,
    /// A safe stop could not be confirmed: done again when the controller answers.
    pending_safe_stop: AtomicBool,
    /// Held by a run from its start and by the start-up/reconnect heat check, so the check
    /// never stops a run of ours.
    gate: tokio::sync::Mutex<()>,
}

impl std::fmt::Debug for RwsController {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RwsController")
            .field("id", &self.cfg.id)
            .field("url", &self.cfg.base_url())
            .finish_non_exhaustive()
    }
}

impl RwsController {
    /// Sets the controller up and spawns the task that polls its execution state. Credentials
    /// that cannot be read do not stop the bridge: the controller shows as disconnected with
    /// the reason, and goals for it are refused with it.
    ///
    /// # Errors
    /// None today; the signature leaves room for set-up that can fail.
    pub async fn start(mut cfg: ControllerConfig) -> anyhow::Result<Arc<Self>> {
        let sim = match cfg.simulator.clone() {
            Some(endpoint) => {
                let (sim, port, credentials) = start_simulator(&cfg, &endpoint).await?;
                cfg.port = Some(port);
                cfg.credentials = Some(credentials);
                tracing::info!("{}: RWS simulator on {}", cfg.id, sim.url());
                Some(sim)
            }
            None => None,
        };
        let client = RwsClient::new(cfg.clone())
            .map(Arc::new)
            .map_err(|e| e.to_string());
        if let Err(e) = &client {
            tracing::warn!("{}: {e}", cfg.id);
        }
        let seen = Seen {
            error: client.as_ref().err().cloned(),
            ..Seen::default()
        };
        let controller = Arc::new(RwsController {
            cfg,
            sim,
            client,
            job: Mutex::new(None),
            seen: Mutex::new(seen),
            busy: AtomicBool::new(false),
            starting: AtomicBool::new(false),
            started: AtomicBool::new(false),
            held: AtomicBool::new(false),
            abort_requested: AtomicBool::new(false),
            abort_signal: tokio::sync::Notify::new(),
            pending_safe_stop: AtomicBool::new(false),
            gate: tokio::sync::Mutex::new(()),
        });
        if controller.client.is_ok() {
            tokio::spawn(poll_state(Arc::downgrade(&controller)));
        }
        Ok(controller)
    }

    /// The controller file (for a `simulator:` controller, with its port and login filled in).
    pub fn config(&self) -> &ControllerConfig {
        &self.cfg
    }

    /// The simulator behind a `simulator:` controller.
    pub fn simulator(&self) -> Option<&cell_rws::sim::RwsSim> {
        self.sim.as_ref()
    }

    /// The execution-state poll period.
    pub fn poll_period(&self) -> Duration {
        POLL
    }

    /// The current (or last) job.
    pub fn job(&self) -> Option<JobInfo> {
        lock(&self.job).clone()
    }

    /// Why `program` cannot run here from `start_line`, before anything is sent: not RAPID,
    /// or a start line other than 0.
    pub(crate) fn refuse_reason(
        &self,
        program: &MachineProgram,
        start_line: u32,
    ) -> Option<String> {
        if program.dialect != "rapid" {
            return Some(format!(
                "controller {} runs RAPID; the program is in the {:?} dialect (emit it for an ABB profile)",
                self.cfg.id, program.dialect
            ));
        }
        if start_line != 0 {
            return Some(format!(
                "start_line {start_line}: a RAPID program starts at main (start_line is for G-code)"
            ));
        }
        None
    }

    /// Uploads, loads and runs `program` (RAPID modules and a `.pgf`) and follows it until
    /// RAPID stops, or until an abort or a lost link ends it with the safe stop (module docs).
    /// `start_line` must be 0: RAPID programs start at `main`.
    pub async fn execute(&self, program: &MachineProgram, start_line: u32) -> RunOutcome {
        let refuse = |message: String| RunOutcome::refused(message, self.status().state);
        if let Some(why) = self.refuse_reason(program, start_line) {
            return refuse(why);
        }
        let client = match &self.client {
            Ok(c) => c.clone(),
            Err(e) => return refuse(format!("controller {}: {e}", self.cfg.id)),
        };
        if self.busy.swap(true, Ordering::SeqCst) {
            return refuse(format!(
                "controller {} is running another program",
                self.cfg.id
            ));
        }
        let gate = self.gate.lock().await;
        self.abort_requested.store(false, Ordering::SeqCst);
        self.started.store(false, Ordering::SeqCst);
        self.held.store(false, Ordering::SeqCst);
        let lines = program.line_count as usize;
        *lock(&self.job) = Some(JobInfo::new(program, lines, lines));
        let outcome = self.run(&client, program).await;
        drop(gate);
        if let Some(job) = lock(&self.job).as_mut() {
            job.finished = Some(outcome.outcome);
            if outcome.success {
                job.acked_lines = job.sent_lines;
            }
        }
        self.started.store(false, Ordering::SeqCst);
        self.busy.store(false, Ordering::SeqCst);
        RunOutcome {
            final_state: self.status().state,
            ..outcome
        }
    }

    /// Returns once an abort is requested (at once if it already is).
    async fn abort_signalled(&self) {
        loop {
            if self.abort_requested.load(Ordering::SeqCst) {
                return;
            }
            self.abort_signal.notified().await;
        }
    }

    /// The safe stop, tried `reconnect.attempts` times; an unconfirmed one is left for the
    /// state poll to do again.
    async fn safe_stop_retrying(&self, client: &RwsClient, why: &str) -> SafeStop {
        let id = &self.cfg.id;
        let stop = safe_stop::retrying(
            client,
            &self.cfg.heat_off_outputs,
            self.cfg.reconnect,
            |attempt, unknown| {
                let text = format!(
                    "{why}: safe stop attempt {attempt} of {} not confirmed: {unknown}",
                    self.cfg.reconnect.attempts
                );
                tracing::warn!("{id}: {text}");
                lock(&self.seen).error = Some(text);
            },
        )
        .await;
        self.after_safe_stop(&stop);
        stop
    }

    fn after_safe_stop(&self, stop: &SafeStop) {
        self.pending_safe_stop
            .store(!stop.confirmed(), Ordering::SeqCst);
    }

    fn ended(&self, outcome: u8, message: String) -> RunOutcome {
        RunOutcome {
            success: outcome == R::OUTCOME_FINISHED,
            outcome,
            message,
            line: 0,
            last_acked_line: 0,
            reconnects: 0,
            final_state: 0,
        }
    }

    async fn run(&self, client: &RwsClient, program: &MachineProgram) -> RunOutcome {
        let id = &self.cfg.id;
        let files: Vec<(&str, &[u8])> = program
            .files
            .iter()
            .map(|f| (f.name.as_str(), f.text.as_bytes()))
            .collect();
        let prepared = async {
            let installed = client.install_program(files).await?;
            client.set_pp_to_main().await?;
            Ok::<_, cell_rws::RwsError>(installed)
        };
        // An abort during the upload drops it (and its request) and RAPID is never started.
        let prepared = tokio::select! {
            biased;
            () = self.abort_signalled() => None,
            r = prepared => Some(r),
        };
        let installed = match prepared {
            Some(Ok(i)) if !self.abort_requested.load(Ordering::SeqCst) => i,
            Some(Err(e)) => return RunOutcome::refused(format!("{id}: {e}"), 0),
            Some(Ok(_)) | None => return self.aborted_before_start(client).await,
        };
        self.starting.store(true, Ordering::SeqCst);
        let start = client.start().await;
        self.starting.store(false, Ordering::SeqCst);
        match start {
            Ok(()) => {}
            // The controller said no (motors off, manual mode): nothing runs.
            Err(e @ cell_rws::RwsError::Controller { .. }) => {
                return RunOutcome::refused(format!("{id}: {e}"), 0)
            }
            // No answer: RAPID may have started.
            Err(e) => {
                return self
                    .link_lost(client, format!("link lost while starting RAPID ({e})"))
                    .await
            }
        }
        self.started.store(true, Ordering::SeqCst);
        tracing::info!("{id}: running {}", installed.program);
        lock(&self.seen).running = true;
        let t0 = tokio::time::Instant::now();
        let mut failed_polls = 0u32;
        loop {
            // An abort wakes the run at once, also out of a poll that hangs.
            let polled = tokio::select! {
                biased;
                () = self.abort_signalled() => None,
                r = async {
                    tokio::time::sleep(POLL).await;
                    client.execution_state().await
                } => Some(r),
            };
            let Some(polled) = polled else {
                let stop = self.safe_stop_retrying(client, "abort").await;
                self.held.store(false, Ordering::SeqCst);
                return self.ended(
                    R::OUTCOME_ABORTED,
                    format!("{id}: aborted; {}", stop.note()),
                );
            };
            match polled {
                Ok(s) => {
                    failed_polls = 0;
                    self.saw(Ok(s.is_running()));
                    if !s.is_running() && !self.held.load(Ordering::SeqCst) {
                        return RunOutcome {
                            success: true,
                            outcome: R::OUTCOME_FINISHED,
                            message: format!(
                                "{id}: {} ran to its end in {:.1} s",
                                installed.program,
                                t0.elapsed().as_secs_f64()
                            ),
                            line: program.line_count,
                            last_acked_line: program.line_count,
                            reconnects: 0,
                            final_state: 0,
                        };
                    }
                }
                Err(e) => {
                    failed_polls += 1;
                    self.saw(Err(e.to_string()));
                    if failed_polls >= LOST_AFTER_FAILED_POLLS {
                        let lost = format!(
                            "link lost while RAPID ran ({failed_polls} polls failed in a row, the last: {e})"
                        );
                        return self.link_lost(client, lost).await;
                    }
                }
            }
        }
    }

    /// A run whose link is gone: the safe stop, retried; the result says whether the heat is
    /// confirmed off.
    async fn link_lost(&self, client: &RwsClient, lost: String) -> RunOutcome {
        let id = &self.cfg.id;
        tracing::warn!("{id}: {lost}: stopping RAPID and switching the heat off");
        lock(&self.seen).error = Some(format!("{lost}: stopping RAPID and switching the heat off"));
        let stop = self.safe_stop_retrying(client, "link lost").await;
        self.held.store(false, Ordering::SeqCst);
        let check = if stop.confirmed() {
            ""
        } else {
            "; check the robot: the bridge stops it and switches the heat off as soon as it answers"
        };
        self.ended(
            R::OUTCOME_LINK_LOST,
            format!("{id}: {lost}; {}{check}", stop.note()),
        )
    }

    /// An abort that came before RAPID was started: nothing ran; the heat-off outputs are
    /// still written (one may be on from before) and mastership given back.
    async fn aborted_before_start(&self, client: &RwsClient) -> RunOutcome {
        if client.holds_mastership() {
            let release = client.release_mastership();
            match tokio::time::timeout(self.cfg.timeouts.control(), release).await {
                Ok(Ok(())) => {}
                Ok(Err(e)) => tracing::warn!("{}: releasing mastership: {e}", self.cfg.id),
                Err(_) => tracing::warn!("{}: releasing mastership: no answer", self.cfg.id),
            }
        }
        let stop = self.safe_stop_retrying(client, "abort").await;
        self.ended(
            R::OUTCOME_ABORTED,
            format!(
                "{}: aborted before RAPID was started (nothing ran); {}",
                self.cfg.id,
                stop.note()
            ),
        )
    }

    fn saw(&self, state: Result<bool, String>) {
        let mut seen = lock(&self.seen);
        match state {
            Ok(running) => {
                *seen = Seen {
                    connected: true,
                    running,
                    error: None,
                }
            }
            Err(e) => {
                seen.connected = false;
                seen.error = Some(e);
            }
        }
    }

    /// Hold stops RAPID (the program pointer stays) and switches the heat off; resume starts
    /// RAPID from the program pointer and switches nothing on (module docs); abort ends a run
    /// with the safe stop, or does the safe stop when nothing runs. An answer is an error when
    /// the heat could not be confirmed off. Overrides are not offered over RWS.
    pub async fn command(&self, command: &MachineCommand) -> Result<String, String> {
        let id = &self.cfg.id;
        let client = self.client.as_ref().map_err(|e| format!("{id}: {e}"))?;
        match command.command {
            MachineCommand::COMMAND_HOLD => {
                if self.busy.load(Ordering::SeqCst) && !self.started.load(Ordering::SeqCst) {
                    return Err(format!(
                        "{id}: hold: the program is still being uploaded and RAPID has not started; abort stops it before it starts"
                    ));
                }
                // Held before the stop, so a run does not take the stop for its end.
                self.held.store(true, Ordering::SeqCst);
                let stop = safe_stop::once(client, &self.cfg.heat_off_outputs).await;
                self.after_safe_stop(&stop);
                if !stop.rapid_stopped {
                    self.held.store(false, Ordering::SeqCst);
                }
                let note = format!("{id}: hold: {}", stop.note());
                if stop.confirmed() {
                    tracing::info!("{note}");
                    Ok(format!(
                        "{note}; resume starts RAPID from the program pointer and switches nothing on (the program sets its outputs again)"
                    ))
                } else {
                    tracing::warn!("{note}");
                    Err(note)
                }
            }
            MachineCommand::COMMAND_RESUME => {
                let r = client.start().await;
                if r.is_ok() {
                    self.held.store(false, Ordering::SeqCst);
                }
                r.map(|_| {
                    format!(
                        "{id}: RAPID started from the program pointer; the heat stays off until the program switches it on again"
                    )
                })
                .map_err(|e| format!("{id}: resume: {e}"))
            }
            MachineCommand::COMMAND_ABORT => {
                if self.busy.load(Ordering::SeqCst) {
                    self.abort_requested.store(true, Ordering::SeqCst);
                    self.abort_signal.notify_one();
                    // The run stops too, but its task may not run again (a node shutting down,
                    // or a caller that polls the run itself): the safe stop is done here as well.
                    let mut stop = safe_stop::once(client, &self.cfg.heat_off_outputs).await;
                    if self.starting.load(Ordering::SeqCst) {
                        // A start request on its way may land after that stop.
                        let deadline = tokio::time::Instant::now() + self.cfg.timeouts.control();
                        while self.starting.load(Ordering::SeqCst)
                            && tokio::time::Instant::now() < deadline
                        {
                            tokio::time::sleep(Duration::from_millis(20)).await;
                        }
                        stop = safe_stop::once(client, &self.cfg.heat_off_outputs).await;
                    }
                    self.after_safe_stop(&stop);
                    let note = format!("{id}: abort: {}; the run ends", stop.note());
                    if stop.confirmed() {
                        Ok(note)
                    } else {
                        Err(note)
                    }
                } else {
                    let stop = self.safe_stop_retrying(client, "abort").await;
                    self.held.store(false, Ordering::SeqCst);
                    let note = format!("{id}: abort: {}", stop.note());
                    if stop.confirmed() {
                        Ok(note)
                    } else {
                        Err(note)
                    }
                }
            }
            MachineCommand::COMMAND_FEED_OVERRIDE | MachineCommand::COMMAND_SPINDLE_OVERRIDE => {
                Err(format!(
                    "{id}: overrides are set on the FlexPendant, not over RWS"
                ))
            }
            other => Err(format!("{id}: unknown command {other}")),
        }
    }

    /// The controller's state now.
    pub fn status(&self) -> MachineStatus {
        let seen = lock(&self.seen).clone();
        let job = lock(&self.job).clone();
        let mut s = MachineStatus {
            machine_id: self.cfg.id.clone(),
            ..MachineStatus::default()
        };
        if let Some(j) = &job {
            s.job_id = j.job_id.clone();
            s.total_lines = j.total_lines;
            s.acked_line = if j.finished == Some(R::OUTCOME_FINISHED) {
                j.total_lines
            } else {
                0
            };
        }
        s.state = if !seen.connected {
            s.alarm = seen.error.unwrap_or_default();
            MachineStatus::STATE_DISCONNECTED
        } else if self.held.load(Ordering::SeqCst) {
            MachineStatus::STATE_HOLD
        } else if seen.running || self.busy.load(Ordering::SeqCst) {
            // Uploading counts as running: a job of ours is under way.
            MachineStatus::STATE_RUNNING
        } else if job.and_then(|j| j.finished) == Some(R::OUTCOME_FINISHED) {
            MachineStatus::STATE_DONE
        } else {
            MachineStatus::STATE_IDLE
        };
        s
    }
}

/// Polls the execution state while no run does, so the status shows the robot's state. On the
/// first answer and on every answer after a failure it checks the heat first (module docs).
async fn poll_state(controller: std::sync::Weak<RwsController>) {
    let mut logged: Option<String> = None;
    let mut heat_logged: Option<String> = None;
    let mut check_heat = true;
    loop {
        let Some(c) = controller.upgrade() else {
            return;
        };
        if !c.busy.load(Ordering::SeqCst) {
            if let Ok(client) = &c.client {
                match client.execution_state().await {
                    Ok(s) => {
                        c.saw(Ok(s.is_running()));
                        if logged.take().is_some() {
                            tracing::info!("{}: reachable again", c.cfg.id);
                        }
                        if check_heat || c.pending_safe_stop.load(Ordering::SeqCst) {
                            check_heat = !c.heat_check(client, &mut heat_logged).await;
                        }
                    }
                    Err(e) => {
                        let why = e.to_string();
                        if logged.as_deref() != Some(why.as_str()) {
                            tracing::warn!("{}: {why}", c.cfg.id);
                            logged = Some(why.clone());
                        }
                        c.saw(Err(why));
                        check_heat = true;
                    }
                }
            }
        }
        drop(c);
        tokio::time::sleep(POLL).await;
    }
}

impl RwsController {
    /// With no run of ours: a safe stop left unconfirmed is done now, and a heat-off output
    /// that reads on gets the safe stop. True when done: the heat reads off or is confirmed
    /// off, or the outputs cannot be read (the next reconnect checks again); false to check
    /// again at the next poll. `logged` keeps a failure from being logged at every poll.
    async fn heat_check(&self, client: &RwsClient, logged: &mut Option<String>) -> bool {
        let id = &self.cfg.id;
        let mut warn_once = |text: String| {
            if logged.as_deref() != Some(text.as_str()) {
                tracing::warn!("{id}: {text}");
                *logged = Some(text);
            }
        };
        let Ok(_gate) = self.gate.try_lock() else {
            return false;
        };
        if self.busy.load(Ordering::SeqCst) {
            return false;
        }
        let why = if self.pending_safe_stop.load(Ordering::SeqCst) {
            "the last safe stop was not confirmed".to_owned()
        } else {
            match safe_stop::heat_on(client, &self.cfg.heat_off_outputs).await {
                Ok(None) => return true,
                Ok(Some(on)) => format!("{on} with no run of this bridge"),
                Err(e) => {
                    warn_once(format!("heat check: {e}"));
                    return true;
                }
            }
        };
        let stop = safe_stop::once(client, &self.cfg.heat_off_outputs).await;
        self.after_safe_stop(&stop);
        if stop.confirmed() {
            tracing::warn!("{id}: {why}: {}", stop.note());
        } else {
            warn_once(format!("{why}: {}", stop.note()));
        }
        stop.confirmed()
    }
}

/// Starts the in-repo RWS simulator for a `simulator:` controller, with a login made up here
/// (nothing secret is written anywhere): the simulator, its port and the credentials.
async fn start_simulator(
    cfg: &ControllerConfig,
    endpoint: &cell_rws::SimulatorEndpoint,
) -> anyhow::Result<(cell_rws::sim::RwsSim, u16, cell_rws::CredentialsSource)> {
    use std::hash::{BuildHasher, Hasher};
    // A per-run password from the standard library's randomly keyed hasher.
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(u64::from(std::process::id()));
    let password = format!("{:016x}", h.finish());
    let user = "cellsuite";
    let mut sim_cfg = cell_rws::sim::SimConfig::new(cfg.rws, user, &password);
    sim_cfg.run_time = Duration::from_secs_f64(endpoint.run_s);
    sim_cfg.task = cfg.task.clone();
    let sim = cell_rws::sim::RwsSim::start(sim_cfg)
        .await
        .map_err(|e| anyhow::anyhow!("{}: the RWS simulator cannot listen: {e}", cfg.id))?;
    let port = sim.addr().port();
    let credentials = cell_rws::CredentialsSource::Given(cell_rws::Credentials {
        user: user.into(),
        password,
    });
    Ok((sim, port, credentials))
}
