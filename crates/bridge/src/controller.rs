//! One face for every controller kind: run a program, act on a command, report a status.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use cell_msgs::{ExecuteProgramResult, MachineCommand, MachineProgram, MachineStatus};

use crate::config::ControllerSpec;
use crate::grbl::GrblController;
use crate::marlin::MarlinController;
use crate::rws::RwsController;

/// One heater's reading, °C.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeaterStatus {
    /// `hotend` or `bed`.
    pub name: &'static str,
    /// Measured temperature.
    pub current_c: f64,
    /// Target (0: off).
    pub target_c: f64,
}

/// Locks a mutex, taking it over if a panicking thread poisoned it: every value behind these
/// locks is replaced whole, so none can be left half-written.
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The program a controller is running (or ran last).
#[derive(Debug, Clone, PartialEq)]
pub struct JobInfo {
    /// The program's job id.
    pub job_id: String,
    /// Lines of the program's text (the numbering `acked_line` uses).
    pub total_lines: u32,
    /// Lines actually sent to the controller (no comments or blank lines).
    pub sent_lines: usize,
    /// Original number of the last acknowledged line; 0 = none.
    pub acked_line: u32,
    /// How many of the sent lines are acknowledged.
    pub acked_lines: usize,
    /// The outcome (`ExecuteProgramResult::OUTCOME_*`) once it ended.
    pub finished: Option<u8>,
}

impl JobInfo {
    /// A job starting on `program`.
    pub fn new(program: &MachineProgram, total_lines: usize, sent_lines: usize) -> Self {
        JobInfo {
            job_id: program.job_id.clone(),
            total_lines: total_lines as u32,
            sent_lines,
            acked_line: 0,
            acked_lines: 0,
            finished: None,
        }
    }

    /// Acknowledged share, 0..100.
    pub fn percent_done(&self) -> f32 {
        if self.finished == Some(ExecuteProgramResult::OUTCOME_FINISHED) {
            return 100.0;
        }
        if self.sent_lines == 0 {
            return 0.0;
        }
        (100.0 * self.acked_lines as f64 / self.sent_lines as f64).min(100.0) as f32
    }
}

/// How a program run ended.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOutcome {
    /// Every line ran.
    pub success: bool,
    /// `ExecuteProgramResult::OUTCOME_*`.
    pub outcome: u8,
    /// One line for the operator.
    pub message: String,
    /// The line the outcome concerns.
    pub line: u32,
    /// The last acknowledged line.
    pub last_acked_line: u32,
    /// Link drops survived.
    pub reconnects: u32,
    /// `MachineStatus::STATE_*` at the end.
    pub final_state: u8,
}

impl RunOutcome {
    /// Refused before anything was sent.
    pub fn refused(message: String, final_state: u8) -> Self {
        RunOutcome {
            success: false,
            outcome: ExecuteProgramResult::OUTCOME_REFUSED,
            message,
            line: 0,
            last_acked_line: 0,
            reconnects: 0,
            final_state,
        }
    }

    /// The action result.
    pub fn to_result(&self) -> ExecuteProgramResult {
        ExecuteProgramResult {
            success: self.success,
            message: self.message.clone(),
            final_state: self.final_state,
            outcome: self.outcome,
            line: self.line,
            last_acked_line: self.last_acked_line,
            reconnects: self.reconnects,
        }
    }
}

/// A controller of any kind.
#[derive(Debug, Clone)]
pub enum Controller {
    /// GRBL-class.
    Grbl(Arc<GrblController>),
    /// ABB RWS.
    Rws(Arc<RwsController>),
    /// Marlin.
    Marlin(Arc<MarlinController>),
}

impl Controller {
    /// Starts driving the controller a file describes (connecting happens in the background).
    ///
    /// # Errors
    /// A simulator endpoint that cannot listen; RWS credentials that cannot be read.
    pub async fn start(spec: ControllerSpec) -> anyhow::Result<Self> {
        Ok(match spec {
            ControllerSpec::Grbl(g) => Controller::Grbl(GrblController::start(g).await?),
            ControllerSpec::Rws(r) => Controller::Rws(RwsController::start(r).await?),
            ControllerSpec::Marlin(m) => Controller::Marlin(MarlinController::start(m).await?),
        })
    }

    /// The controller id.
    pub fn id(&self) -> &str {
        match self {
            Controller::Grbl(g) => &g.config().id,
            Controller::Rws(r) => &r.config().id,
            Controller::Marlin(m) => &m.config().id,
        }
    }

    /// The machine profile the controller runs (empty: any).
    pub fn machine_profile(&self) -> &str {
        match self {
            Controller::Grbl(g) => &g.config().machine_profile,
            Controller::Rws(_) => "",
            Controller::Marlin(m) => &m.config().machine_profile,
        }
    }

    /// How often the controller's state is refreshed.
    pub fn status_period(&self) -> Duration {
        match self {
            Controller::Grbl(g) => Duration::from_secs_f64(g.config().status_period_s),
            Controller::Rws(r) => r.poll_period(),
            Controller::Marlin(m) => Duration::from_secs_f64(m.config().status_period_s),
        }
    }

    /// Why `program` cannot run on this controller from `start_line`, as far as the program
    /// itself tells (dialect, machine profile, files, G-code text, start line): what
    /// [`Controller::execute`] would refuse before sending anything, link and busy state aside.
    ///
    /// # Errors
    /// One line naming the controller or the file and why.
    pub fn check_program(&self, program: &MachineProgram, start_line: u32) -> Result<(), String> {
        match self {
            Controller::Grbl(g) => g.prepare(program, start_line).map(|_| ()),
            Controller::Rws(r) => r.refuse_reason(program, start_line).map_or(Ok(()), Err),
            Controller::Marlin(m) => m.prepare(program, start_line).map(|_| ()),
        }
    }

    /// Runs a program to its end (see each kind).
    pub async fn execute(&self, program: &MachineProgram, start_line: u32) -> RunOutcome {
        match self {
            Controller::Grbl(g) => g.execute(program, start_line).await,
            Controller::Rws(r) => r.execute(program, start_line).await,
            Controller::Marlin(m) => m.execute(program, start_line).await,
        }
    }

    /// Acts on an operator command now.
    ///
    /// # Errors
    /// One line naming the controller and why.
    pub async fn command(&self, command: &MachineCommand) -> Result<String, String> {
        match self {
            Controller::Grbl(g) => g.command(command).await,
            Controller::Rws(r) => r.command(command).await,
            Controller::Marlin(m) => m.command(command).await,
        }
    }

    /// Brings the machine to a safe state within about `budget` before the process exits
    /// (SIGINT, SIGTERM): see [`GrblController::stop_for_shutdown`]; an ABB robot that runs or
    /// holds gets the abort (stop with heat off). One line for the log.
    pub async fn stop_for_shutdown(&self, budget: Duration) -> String {
        match self {
            Controller::Grbl(g) => g.stop_for_shutdown(budget).await,
            Controller::Marlin(m) => m.stop_for_shutdown(budget).await,
            Controller::Rws(r) => {
                let state = r.status().state;
                if !matches!(
                    state,
                    MachineStatus::STATE_RUNNING | MachineStatus::STATE_HOLD
                ) {
                    return format!("{}: not running", r.config().id);
                }
                let abort = MachineCommand {
                    machine_id: r.config().id.clone(),
                    command: MachineCommand::COMMAND_ABORT,
                    value: 0,
                };
                let _ = r.command(&abort).await;
                let deadline = tokio::time::Instant::now() + budget;
                while r.status().state == MachineStatus::STATE_RUNNING
                    && tokio::time::Instant::now() < deadline
                {
                    tokio::time::sleep(Duration::from_millis(20)).await;
                }
                format!("{}: abort sent; state {}", r.config().id, r.status().state)
            }
        }
    }

    /// The heaters' last reading (a Marlin printer's `M105`/`ok T:` reports; none for GRBL and
    /// ABB controllers). `MachineStatus` has no temperature fields, so the node sends these
    /// beside the status: to Rerun, and as `sensor_msgs/Temperature` and `/diagnostics` values.
    pub fn heaters(&self) -> Vec<HeaterStatus> {
        match self {
            Controller::Marlin(m) => m.heaters(),
            Controller::Grbl(_) | Controller::Rws(_) => Vec::new(),
        }
    }

    /// The state now (header left for the node to stamp).
    pub fn status(&self) -> MachineStatus {
        match self {
            Controller::Grbl(g) => g.status(),
            Controller::Rws(r) => r.status(),
            Controller::Marlin(m) => m.status(),
        }
    }

    /// The current (or last) job's acknowledged share, 0..100.
    pub fn percent_done(&self) -> f32 {
        match self {
            Controller::Grbl(g) => g.job().map_or(0.0, |j| j.percent_done()),
            Controller::Rws(r) => r.job().map_or(0.0, |j| j.percent_done()),
            Controller::Marlin(m) => m.job().map_or(0.0, |j| j.percent_done()),
        }
    }
}

/// Picks the controller for a goal: the one named by `machine_id`; else the one configured for
/// the program's machine profile; else the default.
///
/// # Errors
/// An unknown `machine_id`, or no controller at all.
pub fn choose<'a>(
    controllers: &'a [Controller],
    default: usize,
    machine_id: &str,
    program: &MachineProgram,
) -> Result<&'a Controller, String> {
    if !machine_id.is_empty() {
        return controllers
            .iter()
            .find(|c| c.id().eq_ignore_ascii_case(machine_id))
            .ok_or_else(|| {
                format!(
                    "no controller {machine_id:?} on this bridge (it has {})",
                    controllers
                        .iter()
                        .map(Controller::id)
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            });
    }
    if !program.machine_profile.is_empty() {
        if let Some(c) = controllers.iter().find(|c| {
            c.machine_profile()
                .eq_ignore_ascii_case(&program.machine_profile)
        }) {
            return Ok(c);
        }
    }
    controllers
        .get(default)
        .ok_or_else(|| "the bridge has no controller".to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_counts_sent_lines() {
        let mut j = JobInfo::new(&MachineProgram::default(), 120, 100);
        assert_eq!(j.percent_done(), 0.0);
        j.acked_lines = 25;
        assert_eq!(j.percent_done(), 25.0);
        j.finished = Some(ExecuteProgramResult::OUTCOME_FINISHED);
        assert_eq!(j.percent_done(), 100.0);
    }
}
