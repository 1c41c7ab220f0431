//! An ABB robot behind the bridge, over Robot Web Services: upload and load the emitter's
//! RAPID, move the program pointer to `main`, start, follow the execution state until RAPID
//! stops. RWS reports no per-line progress here, so a run's feedback is 0 % until it ends.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use cell_msgs::{ExecuteProgramResult as R, MachineCommand, MachineProgram, MachineStatus};
use cell_rws::{ControllerConfig, RwsClient};

use crate::controller::{lock, JobInfo, RunOutcome};

/// How often the execution state is polled (RWS clients commonly poll at 5 Hz).
const POLL: Duration = Duration::from_millis(200);

/// Consecutive failed polls during a run after which the link counts as lost.
const LOST_AFTER_FAILED_POLLS: u32 = 10;

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
    busy: AtomicBool,
    held: AtomicBool,
    abort_requested: AtomicBool,
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
            held: AtomicBool::new(false),
            abort_requested: AtomicBool::new(false),
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
    /// RAPID stops. `start_line` must be 0: RAPID programs start at `main`.
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
        self.abort_requested.store(false, Ordering::SeqCst);
        self.held.store(false, Ordering::SeqCst);
        let lines = program.line_count as usize;
        *lock(&self.job) = Some(JobInfo::new(program, lines, lines));
        let outcome = self.run(&client, program).await;
        if let Some(job) = lock(&self.job).as_mut() {
            job.finished = Some(outcome.outcome);
            if outcome.success {
                job.acked_lines = job.sent_lines;
            }
        }
        self.busy.store(false, Ordering::SeqCst);
        RunOutcome {
            final_state: self.status().state,
            ..outcome
        }
    }

    async fn run(&self, client: &RwsClient, program: &MachineProgram) -> RunOutcome {
        let id = &self.cfg.id;
        let files: Vec<(&str, &[u8])> = program
            .files
            .iter()
            .map(|f| (f.name.as_str(), f.text.as_bytes()))
            .collect();
        let started = async {
            let installed = client.install_program(files).await?;
            client.set_pp_to_main().await?;
            client.start().await?;
            Ok::<_, cell_rws::RwsError>(installed)
        }
        .await;
        let installed = match started {
            Ok(i) => i,
            Err(e) => return RunOutcome::refused(format!("{id}: {e}"), 0),
        };
        tracing::info!("{id}: running {}", installed.program);
        lock(&self.seen).running = true;
        let t0 = tokio::time::Instant::now();
        let mut failed_polls = 0u32;
        loop {
            tokio::time::sleep(POLL).await;
            if self.abort_requested.load(Ordering::SeqCst) {
                let note = self.stop_and_heat_off(client).await;
                return RunOutcome {
                    success: false,
                    outcome: R::OUTCOME_ABORTED,
                    message: format!("{id}: aborted; {note}"),
                    line: 0,
                    last_acked_line: 0,
                    reconnects: 0,
                    final_state: 0,
                };
            }
            match client.execution_state().await {
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
                        return RunOutcome {
                            success: false,
                            outcome: R::OUTCOME_LINK_LOST,
                            message: format!(
                                "{id}: {e}; {failed_polls} polls failed in a row while RAPID ran: check the robot"
                            ),
                            line: 0,
                            last_acked_line: 0,
                            reconnects: 0,
                            final_state: 0,
                        };
                    }
                }
            }
        }
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

    /// Stops RAPID and writes the heat-off outputs; says what was done.
    async fn stop_and_heat_off(&self, client: &RwsClient) -> String {
        let mut notes = Vec::new();
        match client.stop().await {
            Ok(()) => notes.push("RAPID stopped".to_owned()),
            Err(e) => notes.push(format!("stop failed: {e}")),
        }
        for out in &self.cfg.heat_off_outputs {
            match client.write_signal(&out.signal, &out.value).await {
                Ok(()) => notes.push(format!("{} = {}", out.signal, out.value)),
                Err(e) => notes.push(format!("{} not written: {e}", out.signal)),
            }
        }
        self.held.store(false, Ordering::SeqCst);
        notes.join(", ")
    }

    /// Hold stops RAPID (the program pointer stays), resume starts it from there, abort stops
    /// it and writes the heat-off outputs. Overrides are not offered over RWS.
    pub async fn command(&self, command: &MachineCommand) -> Result<String, String> {
        let id = &self.cfg.id;
        let client = self.client.as_ref().map_err(|e| format!("{id}: {e}"))?;
        match command.command {
            MachineCommand::COMMAND_HOLD => {
                self.held.store(true, Ordering::SeqCst);
                client
                    .stop()
                    .await
                    .map(|_| format!("{id}: RAPID stopped (hold)"))
                    .map_err(|e| format!("{id}: hold: {e}"))
            }
            MachineCommand::COMMAND_RESUME => {
                let r = client.start().await;
                if r.is_ok() {
                    self.held.store(false, Ordering::SeqCst);
                }
                r.map(|_| format!("{id}: RAPID started from the program pointer"))
                    .map_err(|e| format!("{id}: resume: {e}"))
            }
            MachineCommand::COMMAND_ABORT => {
                if self.busy.load(Ordering::SeqCst) {
                    self.abort_requested.store(true, Ordering::SeqCst);
                    Ok(format!("{id}: abort: the run stops within {POLL:?}"))
                } else {
                    Ok(format!("{id}: {}", self.stop_and_heat_off(client).await))
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
        } else if seen.running {
            MachineStatus::STATE_RUNNING
        } else if job.and_then(|j| j.finished) == Some(R::OUTCOME_FINISHED) {
            MachineStatus::STATE_DONE
        } else {
            MachineStatus::STATE_IDLE
        };
        s
    }
}

/// Polls the execution state while no run does, so the status shows the robot's state.
async fn poll_state(controller: std::sync::Weak<RwsController>) {
    let mut logged: Option<String> = None;
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
                    }
                    Err(e) => {
                        let why = e.to_string();
                        if logged.as_deref() != Some(why.as_str()) {
                            tracing::warn!("{}: {why}", c.cfg.id);
                            logged = Some(why.clone());
                        }
                        c.saw(Err(why));
                    }
                }
            }
        }
        drop(c);
        tokio::time::sleep(POLL).await;
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
