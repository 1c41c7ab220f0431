//! The `machine_bridge` node: the ROS adapter over [`cell_bridge::controller::Controller`].
//!
//! - Serves `execute_program` (`cell_msgs/action/ExecuteProgram`) through
//!   [`cell_runtime::goal_server`], goals side by side: the goal's program goes to the
//!   controller named by `machine_id` (else the one whose `machine_profile` matches the
//!   program's, else `default_controller`). A goal naming an unknown controller, or whose
//!   program that controller cannot take (dialect, machine profile, files, G-code text, start
//!   line), is rejected before it is accepted; the reason is logged and goes to `/machine/log`
//!   (ROS 2 rejections carry no text). Feedback (acknowledged line, % done, state) every
//!   `feedback_period_s`; the result says finished, aborted, alarm, rejected line, link lost
//!   or refused (not connected, busy, credentials), with the line. A cancel aborts the run with
//!   a safe stop (heat off) and the goal ends as canceled.
//! - Publishes `MachineStatus` for every controller on `status_topic` at `status_rate_hz`
//!   (≥ 5 Hz) and logs it to Rerun (position, trace, buffer fill, feed, acknowledged line).
//!   A printer's heaters (`MachineStatus` has no temperature fields) go to Rerun and, with
//!   `standard_views`, to `<machine>/temperature/<heater>` as `sensor_msgs/Temperature` and
//!   into `/diagnostics`.
//! - Takes `MachineCommand`s (hold, resume, abort, overrides) on `command_topic` and in the
//!   `machine_command` service (`cell_msgs/srv/SendMachineCommand`), and acts on them at once:
//!   a GRBL feed hold is one real-time byte written before anything else the link has queued,
//!   so it lands well within one status cycle. Commands run in the order they came, off the
//!   node's loop (abort beside them, at once); a GRBL resume waits for the hold to complete
//!   (`Hold:0`) before it sends `~` and answers from the state the controller reports after it.
//! - With `program_topic` set, runs every `MachineProgram` published there (the emitter's
//!   output), one at a time per controller.
//!
//! - On SIGINT or SIGTERM, before the process exits, every machine is brought to a safe state
//!   within `shutdown_budget_s`: running programs are aborted (their safe stop runs), a machine
//!   found moving, held or hot is safe-stopped, and the heat is read back from each controller
//!   and logged ("heat off confirmed", or why it could not be).
//!
//! Bad input (an unknown controller, a program in the wrong dialect or for another machine, a
//! line GRBL cannot take) gets an answer or a log line naming it; the node keeps running.
//!
//! Access ([`access`]): goals, commands and topic programs are taken only from `allowed_peers`
//! (default: this host), and motion starts (a run, resume, an override) only while the bridge is
//! armed. Arming is a local act over a Unix socket (`arm_socket`; `cell machine arm`) and ends
//! after `arm_idle_timeout_s` without machine activity; hold and abort never need it. Every
//! refusal is logged at WARN with the peer: a goal is rejected (the reason in the log and
//! `/machine/log`), a service command answers `success: false` with it.

use std::sync::Arc;
use std::time::Duration;

use cell_msgs::std_msgs::Header;
use cell_msgs::{
    ExecuteProgramFeedback, ExecuteProgramGoal, ExecuteProgramResult, MachineCommand,
    MachineProgram, MachineStatus, SendMachineCommandRequest, SendMachineCommandResponse,
};
use cell_runtime::action::GoalEndStatus;
use cell_runtime::goal_server::{self, GoalContext, GoalEnd, GoalHandler, ServeOptions};
use cell_runtime::service::RequestId;
use cell_runtime::views::{HeaterReading, MachineViews};
use cell_runtime::{CellNode, MachineStatusLogger, NodeParamError, QosPreset};
use serde::{Deserialize, Serialize};
use tokio::sync::mpsc;

use cell_bridge::arming::{self, Arming, MachineAct};
use cell_bridge::config::ControllerSpec;
use cell_bridge::controller::{choose, Controller, RunOutcome};
use cell_runtime::peers::AllowedPeers;

pub mod access;
use access::{profile_refusal, Access};

/// The action the node serves.
pub const ACTION: &str = "execute_program";

/// The command service the node serves.
pub const COMMAND_SERVICE: &str = "machine_command";

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct BridgeParams {
    /// Controllers to drive: ids of the shipped files under `config/controllers` or paths to
    /// controller YAML files.
    pub controllers: Vec<String>,
    /// Controller for goals that name none and match no controller's machine profile; empty:
    /// the first of `controllers`.
    pub default_controller: String,
    /// `MachineStatus` goes out here.
    pub status_topic: String,
    /// `MachineCommand`s come in here.
    pub command_topic: String,
    /// Run every `MachineProgram` published here; empty: only goals run programs.
    pub program_topic: String,
    /// `MachineStatus` rate per controller (Hz), 5..50.
    pub status_rate_hz: f64,
    /// Feedback period of a running goal (s).
    pub feedback_period_s: f64,
    /// How long a finished goal's result waits for its client to ask for it (s).
    pub result_timeout_s: f64,
    /// On SIGINT/SIGTERM, how long the node spends bringing every machine to a safe state
    /// (abort, safe stop, heat read back) before it exits (s), 0.5..30. Keep it under the
    /// launcher's kill timeout (`cell launch`: 5 s; `ros2 launch`: `sigterm_timeout`, 5 s).
    pub shutdown_budget_s: f64,
    /// Also publish the standard-type views for RViz and Foxglove (default true): each
    /// machine's axes on `joint_states` (`sensor_msgs/JointState`, m and rad), its tool frame
    /// `<machine_id>/tool` on `/tf`, each printer heater's temperature on
    /// `<machine>/temperature/{hotend,bed}` (`sensor_msgs/Temperature`, °C, every status tick
    /// while connected), and the machines' health on `/diagnostics` (1 Hz, with the heaters'
    /// current and target °C); see `cell_runtime::views`.
    pub standard_views: bool,
    /// Who may send goals, commands and topic programs: `this_host` (loopback, this host's
    /// addresses, this node's own participant), IP addresses, or DDS participant GUID prefixes
    /// (`01.0f.ab.…`, 12 bytes as `ros2 node info`-style GIDs print them). A peer passes when
    /// its prefix is listed or every address it announces is.
    pub allowed_peers: Vec<String>,
    /// An arming ends after this long without machine activity (s), 1..86400; `cell machine
    /// arm --idle SECONDS` may ask for less.
    pub arm_idle_timeout_s: f64,
    /// Arm at start (logged): for a simulator cell or a launch file that stands for the local
    /// act; a real cell arms at the machine (`cell machine arm`).
    pub arm_at_start: bool,
    /// The arm service's Unix socket; empty: `$XDG_RUNTIME_DIR/cellsuite` (else
    /// `/tmp/cellsuite-<uid>`) `/arm-d<domain>-<node>.sock`, where `cell machine arm` looks.
    pub arm_socket: String,
}

impl Default for BridgeParams {
    fn default() -> Self {
        BridgeParams {
            controllers: vec!["grbl-sim".into()],
            default_controller: String::new(),
            status_topic: "machine_status".into(),
            command_topic: "machine_command".into(),
            program_topic: String::new(),
            status_rate_hz: 10.0,
            feedback_period_s: 0.1,
            result_timeout_s: 600.0,
            shutdown_budget_s: 4.0,
            standard_views: true,
            allowed_peers: vec!["this_host".into()],
            arm_idle_timeout_s: 300.0,
            arm_at_start: false,
            arm_socket: String::new(),
        }
    }
}

/// Controllers from the parameters, checked before anything starts.
///
/// # Errors
/// An unknown or broken controller file, a duplicate id, an empty list, a
/// `default_controller` that is not among them, rates out of range ([`NodeParamError`]s).
pub fn controller_specs(p: &BridgeParams) -> Result<(Vec<ControllerSpec>, usize), NodeParamError> {
    if p.controllers.is_empty() {
        return Err(NodeParamError(
            "controllers: empty; name at least one".into(),
        ));
    }
    let mut specs: Vec<ControllerSpec> = Vec::new();
    for (i, c) in p.controllers.iter().enumerate() {
        let spec = ControllerSpec::resolve(c)
            .map_err(|e| NodeParamError(format!("controllers[{i}]: {e}")))?;
        if specs.iter().any(|s| s.id().eq_ignore_ascii_case(spec.id())) {
            return Err(NodeParamError(format!(
                "controllers[{i}]: id {:?} appears twice",
                spec.id()
            )));
        }
        specs.push(spec);
    }
    let default = if p.default_controller.is_empty() {
        0
    } else {
        specs
            .iter()
            .position(|s| s.id().eq_ignore_ascii_case(&p.default_controller))
            .ok_or_else(|| {
                NodeParamError(format!(
                    "default_controller: {:?} is not among controllers",
                    p.default_controller
                ))
            })?
    };
    if !(p.status_rate_hz.is_finite() && (5.0..=50.0).contains(&p.status_rate_hz)) {
        return Err(NodeParamError(format!(
            "status_rate_hz: {}: expected 5..50",
            p.status_rate_hz
        )));
    }
    if !(p.shutdown_budget_s.is_finite() && (0.5..=30.0).contains(&p.shutdown_budget_s)) {
        return Err(NodeParamError(format!(
            "shutdown_budget_s: {}: expected 0.5..30 s",
            p.shutdown_budget_s
        )));
    }
    if !(p.feedback_period_s.is_finite() && (0.01..=10.0).contains(&p.feedback_period_s)) {
        return Err(NodeParamError(format!(
            "feedback_period_s: {}: expected 0.01..10 s",
            p.feedback_period_s
        )));
    }
    if !(p.arm_idle_timeout_s.is_finite() && (1.0..=86400.0).contains(&p.arm_idle_timeout_s)) {
        return Err(NodeParamError(format!(
            "arm_idle_timeout_s: {}: expected 1..86400 s",
            p.arm_idle_timeout_s
        )));
    }
    Ok((specs, default))
}

/// `allowed_peers`, checked before anything starts.
///
/// # Errors
/// An empty list or an entry that is no host or participant ([`NodeParamError`]).
pub fn allowed_peers(p: &BridgeParams) -> Result<AllowedPeers, NodeParamError> {
    AllowedPeers::parse(&p.allowed_peers).map_err(|e| {
        let sep = if e.starts_with('[') { "" } else { ": " };
        NodeParamError(format!("allowed_peers{sep}{e}"))
    })
}

/// The `execute_program` goals: a controller that can take the program is chosen before the
/// goal is accepted, and the run streams it there.
struct Goals {
    node: CellNode,
    access: Arc<Access>,
    controllers: Arc<Vec<Controller>>,
    default: usize,
    feedback_period: Duration,
    /// Tells the node's loop a run ended (to draw where it ended).
    ended: mpsc::UnboundedSender<()>,
}

impl GoalHandler for Goals {
    type Goal = ExecuteProgramGoal;
    type Result = ExecuteProgramResult;
    type Feedback = ExecuteProgramFeedback;
    /// The controller that runs the goal, and the goal.
    type Job = (Controller, ExecuteProgramGoal);

    fn job_id(&self, goal: &ExecuteProgramGoal, _served: u64) -> String {
        goal.program.job_id.clone()
    }

    fn admit(
        &self,
        _goal: &ExecuteProgramGoal,
        job_id: &str,
        from: &[u8; 16],
    ) -> Result<(), String> {
        self.access.check(from, MachineAct::Run).inspect_err(|why| {
            let line = format!("{job_id}: rejected: {why}");
            self.node.rerun().log_text("/machine/log", &line);
        })
    }

    fn validate(
        &self,
        goal: &ExecuteProgramGoal,
        job_id: &str,
    ) -> Result<(Controller, ExecuteProgramGoal), String> {
        let (controllers, program) = (&self.controllers, &goal.program);
        choose(controllers, self.default, &goal.machine_id, program)
            .and_then(|c| profile_refusal(c, program).map_or(Ok(c), Err))
            .and_then(|c| {
                c.check_program(program, goal.start_line)
                    .map(|()| c.clone())
            })
            .map(|c| (c, goal.clone()))
            .inspect_err(|why| {
                let line = format!("{job_id}: rejected: {why}");
                self.node.rerun().log_text("/machine/log", &line);
            })
    }

    async fn run(
        &self,
        (controller, goal): (Controller, ExecuteProgramGoal),
        ctx: GoalContext<ExecuteProgramFeedback>,
    ) -> anyhow::Result<GoalEnd<ExecuteProgramResult>> {
        let outcome = run_goal(&ctx, &controller, &goal, self.feedback_period).await;
        report(&self.node, ctx.job_id(), &outcome);
        let status = match outcome.outcome {
            ExecuteProgramResult::OUTCOME_FINISHED => GoalEndStatus::Succeeded,
            ExecuteProgramResult::OUTCOME_ABORTED => GoalEndStatus::Canceled,
            _ => GoalEndStatus::Aborted,
        };
        let _ = self.ended.send(());
        Ok(GoalEnd {
            status,
            result: outcome.to_result(),
        })
    }
}

/// Runs the bridge until shutdown.
///
/// # Errors
/// At start-up: bad parameters ([`NodeParamError`], exit status 64), a simulator that cannot
/// listen, topics or services that cannot be set up.
pub async fn run(node: CellNode, p: BridgeParams) -> anyhow::Result<()> {
    let (specs, default) = controller_specs(&p)?;
    let allowed = allowed_peers(&p)?;
    let arming = Arc::new(Arming::new(Duration::from_secs_f64(p.arm_idle_timeout_s)));
    let socket = if p.arm_socket.is_empty() {
        arming::default_socket_path(node.domain_id(), &node.fully_qualified_name())
    } else {
        p.arm_socket.clone().into()
    };
    let _arm_service = arming::serve(&socket, arming.clone()).await?;
    if p.arm_at_start {
        let armed = arming.arm(None);
        tracing::warn!("{armed} (arm_at_start: true)");
    }
    tracing::info!(
        "taking goals and commands from {}; arm service on {}",
        p.allowed_peers.join(", "),
        socket.display()
    );
    let access = Arc::new(Access::new(node.clone(), allowed, arming.clone()));
    let mut controllers = Vec::new();
    for spec in specs {
        controllers.push(Controller::start(spec).await?);
    }
    let controllers = Arc::new(controllers);
    let status_pub = node.publisher::<MachineStatus>(&p.status_topic, QosPreset::Status)?;
    let views = MachineViews::new(&node, p.standard_views)?;
    let mut commands = node.subscriber::<MachineCommand>(&p.command_topic, QosPreset::Status)?;
    let command_server = node
        .service_server::<SendMachineCommandRequest, SendMachineCommandResponse>(COMMAND_SERVICE)?;
    let mut programs = if p.program_topic.is_empty() {
        None
    } else {
        Some(node.subscriber::<MachineProgram>(&p.program_topic, QosPreset::Plan)?)
    };
    let (ended_tx, mut ended_rx) = mpsc::unbounded_channel::<()>();
    // Goals run side by side, one per controller (a busy controller refuses a second).
    let goals = Goals {
        node: node.clone(),
        access: access.clone(),
        controllers: controllers.clone(),
        default,
        feedback_period: Duration::from_secs_f64(p.feedback_period_s),
        ended: ended_tx.clone(),
    };
    let mut goal_server = tokio::spawn(goal_server::serve(
        node.clone(),
        ACTION,
        goals,
        ServeOptions::concurrent(p.result_timeout_s),
    ));
    tracing::info!(
        "bridging {} ({} default); serving {} and {}; status on {} at {} Hz",
        controllers
            .iter()
            .map(Controller::id)
            .collect::<Vec<_>>()
            .join(", "),
        controllers[default].id(),
        node.resolve_topic(ACTION),
        command_server.name(),
        status_pub.topic(),
        p.status_rate_hz
    );

    let mut command_queue = CommandQueue::start(controllers.clone());
    let mut status_tick = tokio::time::interval(Duration::from_secs_f64(1.0 / p.status_rate_hz));
    status_tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut rerun_logger = MachineStatusLogger::default();
    let mut frame = 0i64;
    let mut serving = true;

    loop {
        tokio::select! {
            _ = status_tick.tick() => {
                let stamp = node.now();
                let mut statuses = Vec::with_capacity(controllers.len());
                let mut heater_readings = Vec::new();
                let mut busy = false;
                for c in controllers.iter() {
                    let mut s = c.status();
                    busy |= matches!(s.state, MachineStatus::STATE_RUNNING | MachineStatus::STATE_HOLD);
                    s.header = Header { stamp, frame_id: s.machine_id.clone() };
                    node.rerun().set_time(&stamp, frame);
                    rerun_logger.log(node.rerun(), &s);
                    let heaters: Vec<_> = c
                        .heaters()
                        .iter()
                        .map(|h| (h.name, h.current_c, h.target_c))
                        .collect();
                    rerun_logger.log_heaters(node.rerun(), &s.machine_id, &heaters);
                    // A lost link's last reading is old news: no view presents it as current.
                    if s.state != MachineStatus::STATE_DISCONNECTED {
                        heater_readings.extend(heaters.iter().map(|&(heater, current_c, target_c)| HeaterReading {
                            machine_id: s.machine_id.clone(),
                            heater: heater.to_owned(),
                            current_c,
                            target_c,
                        }));
                    }
                    if let Err(e) = status_pub.publish(s.clone()).await {
                        tracing::warn!("{}: {e:#}", status_pub.topic());
                    }
                    statuses.push(s);
                }
                views.publish(&statuses, &heater_readings).await;
                frame += 1;
                // A machine that moves or holds keeps an arming alive; an idle one lets it
                // expire (and the expiry is logged now rather than at the next request).
                if busy { access.arming.touch() } else { access.arming.is_armed(); }
            }
            received = commands.recv() => {
                let Some(r) = received else { anyhow::bail!("{}: the subscription ended", p.command_topic) };
                match access.check_command(&r.writer_gid, &r.message) {
                    Ok(()) => command_queue.push(None, r.message),
                    Err(why) => refused(&node, &p.command_topic, &why),
                }
            }
            (id, request) = command_server.receive() => {
                match access.check_command(&id.writer_gid.to_bytes16(), &request.command) {
                    Ok(()) => command_queue.push(Some(id), request.command),
                    Err(why) => {
                        refused(&node, command_server.name(), &why);
                        let answer = SendMachineCommandResponse { success: false, message: why };
                        if let Err(e) = command_server.respond(id, answer).await {
                            tracing::warn!("{e:#}");
                        }
                    }
                }
            }
            Some(done) = command_queue.done.recv() => {
                let CommandDone { request, success, message } = done;
                node.rerun().log_text("/machine/log", &message);
                match request {
                    Some(id) => {
                        if let Err(e) = command_server.respond(id, SendMachineCommandResponse { success, message }).await {
                            tracing::warn!("{e:#}");
                        }
                    }
                    None if success => tracing::info!("{message}"),
                    None => tracing::warn!("{message}"),
                }
            }
            served = &mut goal_server, if serving => {
                // The goal server ends only at shutdown, or on an error the node cannot go on after.
                serving = false;
                served.map_err(|e| anyhow::anyhow!("{ACTION}: {e}"))??;
            }
            Some(()) = ended_rx.recv() => {
                // Draw where the job ended now, not at the next tick: the node may be told
                // to stop before it.
                log_statuses_to_rerun(&node, &controllers, &mut rerun_logger, frame);
                frame += 1;
            }
            received = async { programs.as_mut().expect("guarded").recv().await }, if programs.is_some() => {
                let Some(r) = received else { anyhow::bail!("{}: the subscription ended", p.program_topic) };
                let program = r.message;
                let chosen = access
                    .check(&r.writer_gid, MachineAct::Run)
                    .and_then(|()| choose(&controllers, default, "", &program))
                    .and_then(|c| profile_refusal(c, &program).map_or(Ok(c), Err));
                match chosen {
                    Ok(c) => {
                        let (c, node, ended) = (c.clone(), node.clone(), ended_tx.clone());
                        tokio::spawn(async move {
                            tracing::info!("{}: running {} from the program topic", c.id(), program.job_id);
                            let outcome = c.execute(&program, 0).await;
                            report(&node, &program.job_id, &outcome);
                            let _ = ended.send(());
                        });
                    }
                    Err(why) => refused(&node, &p.program_topic, &format!("{}: {why}", program.job_id)),
                }
            }
            _ = node.shutdown().requested() => {
                // Nothing may keep cutting once the bridge is gone: every machine is brought
                // to a safe state, read back from its controller, before the process exits.
                let budget = Duration::from_secs_f64(p.shutdown_budget_s);
                let stops = futures::future::join_all(
                    controllers.iter().map(|c| c.stop_for_shutdown(budget)),
                )
                .await;
                for line in stops {
                    tracing::warn!("shutting down: {line}");
                    node.rerun().log_text("/machine/log", &format!("shutting down: {line}"));
                }
                log_statuses_to_rerun(&node, &controllers, &mut rerun_logger, frame);
                rerun_logger.flush(node.rerun());
                node.rerun().flush();
                return Ok(());
            }
        }
    }
}

/// Logs every controller's status to Rerun now, outside the status tick.
fn log_statuses_to_rerun(
    node: &CellNode,
    controllers: &[Controller],
    logger: &mut MachineStatusLogger,
    frame: i64,
) {
    let stamp = node.now();
    node.rerun().set_time(&stamp, frame);
    for c in controllers {
        let mut s = c.status();
        s.header = Header {
            stamp,
            frame_id: s.machine_id.clone(),
        };
        logger.log(node.rerun(), &s);
    }
}

/// Runs a goal on its controller, sending feedback while it runs; a cancel aborts the run
/// with a safe stop (heat off), and the run then ends as aborted.
async fn run_goal(
    ctx: &GoalContext<ExecuteProgramFeedback>,
    controller: &Controller,
    goal: &ExecuteProgramGoal,
    feedback_period: Duration,
) -> RunOutcome {
    let run = controller.execute(&goal.program, goal.start_line);
    tokio::pin!(run);
    let mut tick = tokio::time::interval(feedback_period);
    let mut last: Option<(u32, u8)> = None;
    let mut aborting = false;
    loop {
        tokio::select! {
            outcome = &mut run => return outcome,
            _ = ctx.canceled(), if !aborting => {
                aborting = true;
                let abort = MachineCommand { machine_id: controller.id().into(), command: MachineCommand::COMMAND_ABORT, value: 0 };
                match controller.command(&abort).await {
                    Ok(m) => tracing::info!("{ACTION}: cancel: {m}"),
                    Err(m) => tracing::warn!("{ACTION}: cancel: {m}"),
                }
            }
            _ = tick.tick() => {
                let s = controller.status();
                if last == Some((s.acked_line, s.state)) { continue; }
                last = Some((s.acked_line, s.state));
                ctx.feedback(ExecuteProgramFeedback {
                    acked_line: s.acked_line,
                    total_lines: s.total_lines,
                    state: s.state,
                    percent_done: controller.percent_done(),
                });
            }
        }
    }
}

/// Logs a refused request (WARN, and `/machine/log`).
fn refused(node: &CellNode, at: &str, why: &str) {
    tracing::warn!("{at}: {why}");
    node.rerun()
        .log_text("/machine/log", &format!("{at}: {why}"));
}

/// Logs how a run ended.
fn report(node: &CellNode, job_id: &str, outcome: &RunOutcome) {
    let line = format!("{job_id}: {}", outcome.message);
    if outcome.success {
        tracing::info!("{line}");
    } else {
        tracing::warn!("{line}");
    }
    node.rerun().log_text("/machine/log", &line);
}

/// A command's answer, for the service's caller (`request`) or the log (from the topic).
struct CommandDone {
    request: Option<RequestId>,
    success: bool,
    message: String,
}

/// Commands run off the node's loop, so a slow one (a resume waits for the feed hold to
/// complete) holds up neither the status nor the service. They run one after another in the
/// order they came (a hold then a resume stays in that order), except abort, which runs at
/// once beside them: an e-stop waits for nothing.
struct CommandQueue {
    controllers: Arc<Vec<Controller>>,
    in_order: mpsc::UnboundedSender<(Option<RequestId>, MachineCommand)>,
    done_tx: mpsc::UnboundedSender<CommandDone>,
    done: mpsc::UnboundedReceiver<CommandDone>,
}

impl CommandQueue {
    fn start(controllers: Arc<Vec<Controller>>) -> CommandQueue {
        let (in_order, mut queued) = mpsc::unbounded_channel();
        let (done_tx, done) = mpsc::unbounded_channel();
        let (worker_controllers, worker_done) = (controllers.clone(), done_tx.clone());
        tokio::spawn(async move {
            while let Some((request, command)) = queued.recv().await {
                let (success, message) = act(&worker_controllers, &command).await;
                let answer = CommandDone {
                    request,
                    success,
                    message,
                };
                if worker_done.send(answer).is_err() {
                    return;
                }
            }
        });
        CommandQueue {
            controllers,
            in_order,
            done_tx,
            done,
        }
    }

    fn push(&self, request: Option<RequestId>, command: MachineCommand) {
        if command.command == MachineCommand::COMMAND_ABORT {
            let (controllers, done) = (self.controllers.clone(), self.done_tx.clone());
            tokio::spawn(async move {
                let (success, message) = act(&controllers, &command).await;
                let _ = done.send(CommandDone {
                    request,
                    success,
                    message,
                });
            });
        } else {
            let _ = self.in_order.send((request, command));
        }
    }
}

/// Acts on a command for the controllers it addresses; (all took it, what each said).
async fn act(controllers: &[Controller], command: &MachineCommand) -> (bool, String) {
    let addressed: Vec<&Controller> = controllers
        .iter()
        .filter(|c| {
            command.machine_id.is_empty() || c.id().eq_ignore_ascii_case(&command.machine_id)
        })
        .collect();
    if addressed.is_empty() {
        return (
            false,
            format!("machine command: no controller {:?}", command.machine_id),
        );
    }
    // All at once: an e-stop for every machine must not wait for one machine's answer.
    let answers = futures::future::join_all(addressed.iter().map(|c| c.command(command))).await;
    let ok = answers.iter().all(Result::is_ok);
    let text = answers
        .into_iter()
        .map(|a| a.unwrap_or_else(|e| e))
        .collect::<Vec<_>>()
        .join("; ");
    (ok, text)
}

/// The `machine_bridge` binary (also `cell node machine_bridge`).
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("machine_bridge", argv, run)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_params_file_parses_and_matches_the_defaults() {
        let mut sources = cell_runtime::params::ParamSources::default();
        let file = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../config/machine_bridge.yaml"
        );
        sources
            .merge_file(std::path::Path::new(file), "/", "machine_bridge")
            .unwrap();
        let p: BridgeParams = sources.parse().unwrap();
        assert_eq!(p, BridgeParams::default());
    }

    #[test]
    fn bad_parameters_are_named() {
        let err = |p: BridgeParams| controller_specs(&p).unwrap_err().0;
        let e = err(BridgeParams {
            controllers: vec![],
            ..BridgeParams::default()
        });
        assert!(e.starts_with("controllers"), "{e}");
        let e = err(BridgeParams {
            controllers: vec!["grbl-sim".into(), "nope".into()],
            ..BridgeParams::default()
        });
        assert!(e.starts_with("controllers[1]") && e.contains("nope"), "{e}");
        let e = err(BridgeParams {
            controllers: vec!["grbl-sim".into(), "GRBL-SIM".into()],
            ..BridgeParams::default()
        });
        assert!(e.contains("twice"), "{e}");
        let e = err(BridgeParams {
            default_controller: "abb-irb2600-waam".into(),
            ..BridgeParams::default()
        });
        assert!(e.starts_with("default_controller"), "{e}");
        let e = err(BridgeParams {
            status_rate_hz: 2.0,
            ..BridgeParams::default()
        });
        assert!(e.starts_with("status_rate_hz"), "{e}");
        let e = err(BridgeParams {
            arm_idle_timeout_s: 0.0,
            ..BridgeParams::default()
        });
        assert!(e.starts_with("arm_idle_timeout_s"), "{e}");
        let peers = |list: &[&str]| {
            allowed_peers(&BridgeParams {
                allowed_peers: list.iter().map(|s| s.to_string()).collect(),
                ..BridgeParams::default()
            })
        };
        assert!(peers(&[])
            .unwrap_err()
            .0
            .starts_with("allowed_peers: empty"));
        let e = peers(&["this_host", "cell-pc"]).unwrap_err().0;
        assert!(
            e.starts_with("allowed_peers[1]") && e.contains("cell-pc"),
            "{e}"
        );
        assert!(peers(&["this_host", "10.0.0.5", "010fab123456789abcdef011"]).is_ok());
        let (specs, default) = controller_specs(&BridgeParams {
            controllers: vec!["grbl-sim".into(), "abb-irb2600-waam".into()],
            default_controller: "abb-irb2600-waam".into(),
            ..BridgeParams::default()
        })
        .unwrap();
        assert_eq!((specs.len(), default), (2, 1));
    }
}
