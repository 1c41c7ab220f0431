//! The `job_runner` node: runs the cell's jobs, as an operator would.
//!
//! 1. Sends a `plan_hotwire` goal to the planner and follows its feedback.
//! 2. Waits for the emitter's `MachineProgram` for that job on `program_topic`.
//! 3. Sends it to the machine_bridge as an `execute_program` goal and follows it.
//! 4. If `sheet_job_id` is set, does the same for a sheet: a `sequence_sheet` goal to the
//!    sequencer (the layout embedded from `config/sheets/` or read from a file), the program an
//!    emitter makes of its toolpath, and `execute_program`.
//! 5. If `waam_job_id` is set, a WAAM job: a `slice` goal to the slicer (the part embedded from
//!    `tests/data/stl/`, written to the temp directory for the slicer to read, or an STL path),
//!    the RAPID program an emitter makes of its toolpath, and `execute_program` on the robot
//!    controller `waam_machine_id`.
//! 6. If `wing_job_id` is set, a G-Wing job (seed 002): a wing `slice` goal (on `wing_action`)
//!    for one section of the wing spec (embedded from `config/wings/` with its airfoil, written
//!    to `part_dir`, or a spec path), the Marlin program an emitter makes of its toolpath, and
//!    `execute_program` on the printer `wing_machine_id` (the Marlin simulator in the demo).
//! 7. Prints a summary table (stdout) and exits 0 if every stage succeeded, else 1 naming the
//!    stage and why.
//!
//! `cell demo` runs it with a reduced iteration count and stops the other nodes once it exits.

use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context as _};
use cell_msgs::{
    ExecuteProgramFeedback, ExecuteProgramGoal, ExecuteProgramResult, MachineProgram,
    PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult, SequenceSheetFeedback,
    SequenceSheetGoal, SequenceSheetResult, SliceFeedback, SliceGoal, SliceResult,
};
use cell_runtime::action::{request_result, ActionClient, GoalStatusEnum};
use cell_runtime::{CellNode, QosPreset};
use futures::StreamExt;
use serde::{Deserialize, Serialize};

/// The Rerun entity each job's summary rows go to.
pub const RERUN_LOG: &str = "/jobs/log";

/// Sheet layouts shipped in `config/sheets/`, embedded so the demo runs from any directory:
/// (name, JSON text in the sequencer's layout format).
pub const EMBEDDED_SHEETS: &[(&str, &str)] = &[(
    "plate-nest",
    include_str!("../../../config/sheets/plate-nest.json"),
)];

/// WAAM parts shipped with the repository, embedded so the demo runs from any directory:
/// (name, binary STL).
pub const EMBEDDED_PARTS: &[(&str, &[u8])] = &[(
    "20mm-xyz-cube",
    include_bytes!("../../../tests/data/stl/20mm-xyz-cube.stl"),
)];

/// Wing specs shipped in `config/wings/`, embedded with their airfoil so the demo runs from any
/// directory: (name, spec YAML, airfoil file name, airfoil `.dat`).
pub const EMBEDDED_WINGS: &[(&str, &str, &str, &str)] = &[(
    "gwing-table2",
    include_str!("../../../config/wings/gwing-table2.yaml"),
    "ag24.dat",
    include_str!("../../../config/airfoils/ag24.dat"),
)];

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RunnerParams {
    /// Job id, carried into the toolpath and the program.
    pub job_id: String,
    /// Root airfoil (a name under config/airfoils or a .dat path).
    pub root_airfoil: String,
    /// Root chord (mm).
    pub root_chord_mm: f64,
    /// Tip airfoil; empty: the root's.
    pub tip_airfoil: String,
    /// Tip chord (mm); 0: the root's.
    pub tip_chord_mm: f64,
    /// Tip sweep (mm).
    pub tip_sweep_mm: f64,
    /// Tip twist (deg).
    pub tip_twist_deg: f64,
    /// Panel span (mm); 0: the planner's.
    pub span_mm: f64,
    /// Foam.
    pub material: String,
    /// Machine profile to plan and emit for.
    pub machine_profile: String,
    /// PSO iterations; 0: the planner's.
    pub iterations: u32,
    /// RNG seed.
    pub seed: u64,
    /// Controller for `execute_program`; empty: the bridge's choice.
    pub machine_id: String,
    /// Where the emitter publishes programs.
    pub program_topic: String,
    /// Give up after this long (s).
    pub timeout_s: f64,
    /// Job id of the sheet job; empty: no sheet job.
    pub sheet_job_id: String,
    /// Sheet layout: a name in [`EMBEDDED_SHEETS`] or a `.json`/`.dxf` path.
    pub sheet_layout: String,
    /// Machine profile the sheet is sequenced and emitted for.
    pub sheet_machine_profile: String,
    /// Improvement time budget of the sheet job (s).
    pub sheet_time_budget_s: f64,
    /// Job id of the WAAM job; empty: no WAAM job.
    pub waam_job_id: String,
    /// WAAM part: a name in [`EMBEDDED_PARTS`] or an STL path (read by the slicer).
    pub waam_part: String,
    /// Layer height of the WAAM job (mm); 0: the process profile's.
    pub waam_layer_height_mm: f64,
    /// Robot controller for the WAAM program.
    pub waam_machine_id: String,
    /// Directory the embedded WAAM part is written to for the slicer (created if missing; it
    /// must be one of the slicer's `data_dirs`); empty: the system's temporary directory.
    pub part_dir: String,
    /// Job id of the G-Wing job; empty: no wing job.
    pub wing_job_id: String,
    /// Wing spec: a name in [`EMBEDDED_WINGS`] or a spec path (read by the slicer).
    pub wing_spec: String,
    /// The section to print (index into the design's sections; 0: the centre section).
    pub wing_section: u32,
    /// The slicer's action for the wing goal (the demo runs a second slicer on `wing_slice`).
    pub wing_action: String,
    /// The printer (config/controllers) the Marlin program runs on.
    pub wing_machine_id: String,
}

impl Default for RunnerParams {
    fn default() -> Self {
        RunnerParams {
            job_id: "demo-wing".into(),
            root_airfoil: "s1223".into(),
            root_chord_mm: 200.0,
            tip_airfoil: String::new(),
            tip_chord_mm: 150.0,
            tip_sweep_mm: 20.0,
            tip_twist_deg: 0.0,
            span_mm: 0.0,
            material: "EPS".into(),
            machine_profile: "grbl-xyuv".into(),
            iterations: 0,
            seed: 1,
            machine_id: String::new(),
            program_topic: "machine_program".into(),
            timeout_s: 900.0,
            sheet_job_id: String::new(),
            sheet_layout: "plate-nest".into(),
            sheet_machine_profile: "grbl-laser".into(),
            sheet_time_budget_s: 2.0,
            waam_job_id: String::new(),
            waam_part: "20mm-xyz-cube".into(),
            waam_layer_height_mm: 0.0,
            waam_machine_id: "abb-irb2600-waam-sim".into(),
            part_dir: String::new(),
            wing_job_id: String::new(),
            wing_spec: "gwing-table2".into(),
            wing_section: 0,
            wing_action: "slice".into(),
            wing_machine_id: "marlin-sim".into(),
        }
    }
}

/// What each stage gave, for the summary.
#[derive(Debug, Clone, Default)]
pub struct JobSummary {
    /// The plan's result.
    pub plan: PlanHotwireResult,
    /// Planning time.
    pub plan_time: Duration,
    /// Iterations the planner ran.
    pub iterations: u32,
    /// The program.
    pub program: MachineProgram,
    /// The run's result.
    pub run: ExecuteProgramResult,
    /// Running time.
    pub run_time: Duration,
    /// The sheet job, if one was run.
    pub sheet: Option<SheetSummary>,
    /// The WAAM job, if one was run.
    pub waam: Option<SliceJobSummary>,
    /// The G-Wing job, if one was run.
    pub wing: Option<SliceJobSummary>,
}

/// What a slice job's stages gave, for the summary: the WAAM part or the G-Wing section (whose
/// `report_json` is `cell_slicer::wing::WingReport`).
#[derive(Debug, Clone, Default)]
pub struct SliceJobSummary {
    /// The slicer's result.
    pub slice: SliceResult,
    /// Slicing time (for a wing, design and slicing).
    pub slice_time: Duration,
    /// The program.
    pub program: MachineProgram,
    /// The run's result.
    pub run: ExecuteProgramResult,
    /// Running time.
    pub run_time: Duration,
}

/// What the sheet job's stages gave, for the summary.
#[derive(Debug, Clone, Default)]
pub struct SheetSummary {
    /// The sequencer's result.
    pub sequence: SequenceSheetResult,
    /// Sequencing time.
    pub sequence_time: Duration,
    /// The program.
    pub program: MachineProgram,
    /// The run's result.
    pub run: ExecuteProgramResult,
    /// Running time.
    pub run_time: Duration,
}

fn outcome_name(run: &ExecuteProgramResult) -> &'static str {
    match run.outcome {
        ExecuteProgramResult::OUTCOME_FINISHED => "finished",
        ExecuteProgramResult::OUTCOME_ABORTED => "aborted",
        ExecuteProgramResult::OUTCOME_ALARM => "alarm",
        ExecuteProgramResult::OUTCOME_REJECTED_LINE => "line rejected",
        ExecuteProgramResult::OUTCOME_LINK_LOST => "link lost",
        _ => "refused",
    }
}

/// `name (dialect, lines, sha256 prefix…)` of a program.
fn program_cell(program: &MachineProgram) -> String {
    let sha = program.sha256.get(..12).unwrap_or(&program.sha256);
    format!(
        "{} ({}, {} lines, sha256 {sha}…)",
        program.files.first().map_or("-", |file| file.name.as_str()),
        program.dialect,
        program.line_count
    )
}

/// `outcome: line a of n acknowledged in t s, k link drops` of a run.
fn run_cell(run: &ExecuteProgramResult, program: &MachineProgram, time: Duration) -> String {
    format!(
        "{}: line {} of {} acknowledged in {:.1} s, {} link drops",
        outcome_name(run),
        run.last_acked_line,
        program.line_count,
        time.as_secs_f64(),
        run.reconnects
    )
}

impl std::fmt::Display for JobSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "| stage   | result |")?;
        writeln!(f, "|---------|--------|")?;
        writeln!(
            f,
            "| plan    | {} iterations in {:.1} s; exposure loss {:.4e} -> {:.4e} |",
            self.iterations,
            self.plan_time.as_secs_f64(),
            self.plan.baseline_loss,
            self.plan.final_loss
        )?;
        writeln!(f, "| program | {} |", program_cell(&self.program))?;
        write!(
            f,
            "| machine | {} |",
            run_cell(&self.run, &self.program, self.run_time)
        )?;
        if let Some(s) = &self.sheet {
            let plan = &s.sequence.plan;
            write!(
                f,
                "\n| sheet   | {} contours by {}{}: idle {:.0} mm, cut {:.0} mm, {} overheats, \
                 in {:.1} s |",
                plan.order.len(),
                plan.policy,
                if plan.improved { " + improvement" } else { "" },
                plan.idle_length_mm,
                plan.cut_length_mm,
                plan.overheats,
                s.sequence_time.as_secs_f64()
            )?;
            write!(f, "\n| sheet program | {} |", program_cell(&s.program))?;
            write!(
                f,
                "\n| sheet machine | {} |",
                run_cell(&s.run, &s.program, s.run_time)
            )?;
        }
        if let Some(w) = &self.waam {
            let stack = &w.slice.layer_stack;
            let report: serde_json::Value =
                serde_json::from_str(&w.slice.report_json).unwrap_or_default();
            let figure = |k: &str| report[k].as_f64().unwrap_or(f64::NAN);
            write!(
                f,
                "\n| waam    | {} layers, {} contours: {:.0} mm³ deposited, {:.0} s arc on, {:.0} \
                 SEK, in {:.2} s |",
                stack.layers.len(),
                stack.layers.iter().map(|l| l.contours.len()).sum::<usize>(),
                figure("deposited_volume_mm3"),
                figure("deposition_time_s"),
                report["cost"]["total_sek"].as_f64().unwrap_or(f64::NAN),
                w.slice_time.as_secs_f64()
            )?;
            write!(f, "\n| waam program | {} |", program_cell(&w.program))?;
            write!(
                f,
                "\n| waam machine | {}: RAPID ran to its end in {:.1} s |",
                outcome_name(&w.run),
                w.run_time.as_secs_f64()
            )?;
        }
        if let Some(g) = &self.wing {
            let report: serde_json::Value =
                serde_json::from_str(&g.slice.report_json).unwrap_or_default();
            let s = &report["section"];
            let figure = |k: &str| s[k].as_f64().unwrap_or(f64::NAN);
            let printed = s["layers"].as_u64().unwrap_or(0);
            let whole = report["layers_in_section"].as_u64().unwrap_or(printed);
            let layers = if printed < whole {
                format!("the first {printed} of {whole} layers (a short demo print)")
            } else {
                format!("{printed} layers")
            };
            write!(
                f,
                "\n| gwing   | section {} ({} {}): {layers}, {:.2} g, build time {:.1} min ({:.1} \
                 min with Marlin's planner), designed and sliced in {:.1} s |",
                s["index"].as_u64().unwrap_or(0),
                s["side"].as_str().unwrap_or("?"),
                s["position"].as_u64().unwrap_or(0),
                figure("mass_g"),
                figure("build_time_s") / 60.0,
                figure("build_time_with_acceleration_s") / 60.0,
                g.slice_time.as_secs_f64()
            )?;
            write!(f, "\n| gwing program | {} |", program_cell(&g.program))?;
            write!(
                f,
                "\n| gwing machine | {}; {} |",
                run_cell(&g.run, &g.program, g.run_time),
                g.run.message
            )?;
        }
        Ok(())
    }
}

type PlanClient = ActionClient<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>;
type RunClient = ActionClient<ExecuteProgramGoal, ExecuteProgramResult, ExecuteProgramFeedback>;
type SheetClient = ActionClient<SequenceSheetGoal, SequenceSheetResult, SequenceSheetFeedback>;
type SliceClient = ActionClient<SliceGoal, SliceResult, SliceFeedback>;

/// How often a result request is asked again while a goal runs: a reply the server sent before
/// it had matched our new reply reader is lost (ROS 2 services are volatile), and asking again
/// is safe (see [`request_result`]).
const RESULT_RETRY: Duration = Duration::from_secs(10);

/// How often a goal that is still running is reported, with its last feedback, so a stage that
/// hangs names itself in the log long before the stage's timeout.
const STILL_RUNNING_EVERY: Duration = Duration::from_secs(30);

/// Sends a goal and waits for its result, logging feedback through `describe` at most once a
/// second, and every [`STILL_RUNNING_EVERY`] that it still runs.
async fn follow<G, R, F>(
    client: &ActionClient<G, R, F>,
    goal: G,
    what: &str,
    timeout: Duration,
    describe: impl Fn(&F) -> String,
) -> anyhow::Result<(GoalStatusEnum, R)>
where
    G: ros2_client::Message + Clone + 'static,
    R: ros2_client::Message + Clone + 'static,
    F: ros2_client::Message + 'static,
{
    let (goal_id, response) = tokio::time::timeout(timeout, client.async_send_goal(goal))
        .await
        .map_err(|_| anyhow!("{what}: no answer to the goal within {timeout:?}"))?
        .map_err(|e| anyhow!("{what}: goal not sent: {e:?}"))?;
    if !response.accepted {
        bail!("{what}: the goal was rejected (ROS 2 rejections carry no reason: the serving node logs it)");
    }
    let accepted = Instant::now();
    let feedback = client.feedback_stream(goal_id);
    let mut feedback = std::pin::pin!(feedback);
    let result = request_result(client, goal_id, RESULT_RETRY, timeout);
    let mut result = std::pin::pin!(result);
    let mut last_log = Instant::now() - Duration::from_secs(10);
    let mut last_feedback: Option<String> = None;
    let mut still_running = tokio::time::interval_at(
        tokio::time::Instant::now() + STILL_RUNNING_EVERY,
        STILL_RUNNING_EVERY,
    );
    let mut open = true;
    loop {
        tokio::select! {
            r = &mut result => {
                return r.map_err(|e| match &last_feedback {
                    Some(f) => e.context(format!("{what} (last feedback: {f})")),
                    None => e.context(format!("{what} (accepted, no feedback)")),
                });
            }
            f = feedback.next(), if open => match f {
                Some(Ok(f)) => {
                    let text = describe(&f);
                    if last_log.elapsed() >= Duration::from_secs(1) {
                        last_log = Instant::now();
                        tracing::info!("{what}: {text}");
                    }
                    last_feedback = Some(text);
                }
                Some(_) => {}
                None => open = false,
            },
            _ = still_running.tick() => tracing::info!(
                "{what}: still running {:.0} s after it was accepted (last feedback: {})",
                accepted.elapsed().as_secs_f64(),
                last_feedback.as_deref().unwrap_or("none"),
            ),
        }
    }
}

/// Runs the job through the cell.
///
/// # Errors
/// A stage that fails or times out, named with its reason.
pub async fn run_job(node: &CellNode, p: &RunnerParams) -> anyhow::Result<JobSummary> {
    let timeout = Duration::from_secs_f64(p.timeout_s.max(1.0));
    let plan_client: PlanClient = node.action_client("plan_hotwire")?;
    let run_client: RunClient = node.action_client("execute_program")?;
    // Every stage's client now, not when its stage comes: the servers then discover our reply
    // readers while the earlier stages run, instead of racing the first goal.
    let sheet_client: Option<SheetClient> = (!p.sheet_job_id.is_empty())
        .then(|| node.action_client("sequence_sheet"))
        .transpose()?;
    let waam_client: Option<SliceClient> = (!p.waam_job_id.is_empty())
        .then(|| node.action_client("slice"))
        .transpose()?;
    let wing_client: Option<SliceClient> = (!p.wing_job_id.is_empty())
        .then(|| node.action_client(&p.wing_action))
        .transpose()?;
    let mut programs = node.subscriber::<MachineProgram>(&p.program_topic, QosPreset::Plan)?;
    for action in ["plan_hotwire", "execute_program"] {
        require_action_server(node, action, timeout).await?;
    }

    let goal = PlanHotwireGoal {
        job_id: p.job_id.clone(),
        root_airfoil: p.root_airfoil.clone(),
        tip_airfoil: p.tip_airfoil.clone(),
        root_chord_mm: p.root_chord_mm,
        tip_chord_mm: p.tip_chord_mm,
        tip_twist_deg: p.tip_twist_deg,
        tip_sweep_mm: p.tip_sweep_mm,
        span_mm: p.span_mm,
        material: p.material.clone(),
        cse: 0.0,
        machine_profile: p.machine_profile.clone(),
        iterations: p.iterations,
        seed: p.seed,
    };
    tracing::info!(
        "planning {} ({} at {} mm)",
        p.job_id,
        p.root_airfoil,
        p.root_chord_mm
    );
    let t0 = Instant::now();
    let last_iteration = std::sync::atomic::AtomicU32::new(0);
    let (status, plan) = follow(&plan_client, goal, "plan_hotwire", timeout, |f| {
        last_iteration.store(f.total_iterations, std::sync::atomic::Ordering::Relaxed);
        format!(
            "iteration {}/{}, best loss {:.4e}, {:.0} s to go",
            f.iteration, f.total_iterations, f.best_loss, f.eta_s
        )
    })
    .await?;
    if status != GoalStatusEnum::Succeeded || !plan.success {
        bail!("plan_hotwire: {}", plan.message);
    }
    let plan_time = t0.elapsed();
    tracing::info!("{}", plan.message);

    let (program, run, run_time) = program_and_run(
        &mut programs,
        p,
        (&p.job_id, &p.machine_id),
        &run_client,
        timeout,
    )
    .await?;
    let sheet = match &sheet_client {
        Some(client) => {
            Some(run_sheet(node, p, client, &mut programs, &run_client, timeout).await?)
        }
        None => None,
    };
    let waam = match &waam_client {
        Some(client) => Some(run_waam(node, p, client, &mut programs, &run_client, timeout).await?),
        None => None,
    };
    let wing = match &wing_client {
        Some(client) => Some(run_wing(node, p, client, &mut programs, &run_client, timeout).await?),
        None => None,
    };
    Ok(JobSummary {
        iterations: last_iteration.load(std::sync::atomic::Ordering::Relaxed),
        plan,
        plan_time,
        program,
        run,
        run_time,
        sheet,
        waam,
        wing,
    })
}

/// Waits for the emitter's program for `job_id`.
async fn wait_for_program(
    programs: &mut cell_runtime::Subscriber<MachineProgram>,
    p: &RunnerParams,
    job_id: &str,
    timeout: Duration,
) -> anyhow::Result<MachineProgram> {
    let program = tokio::time::timeout(timeout, async {
        loop {
            match programs.recv().await {
                Some(r) if r.message.job_id == job_id => return Ok(r.message),
                Some(_) => continue,
                None => return Err(anyhow!("{}: the subscription ended", p.program_topic)),
            }
        }
    })
    .await
    .map_err(|_| {
        anyhow!(
            "no program for {job_id} on {} within {timeout:?}",
            p.program_topic
        )
    })??;
    tracing::info!(
        "program {}: {} lines of {}",
        program.job_id,
        program.line_count,
        program.dialect
    );
    Ok(program)
}

/// Runs a program on the machine_bridge and follows it.
async fn execute(
    run_client: &RunClient,
    program: &MachineProgram,
    machine_id: &str,
    timeout: Duration,
) -> anyhow::Result<ExecuteProgramResult> {
    let goal = ExecuteProgramGoal {
        program: program.clone(),
        machine_id: machine_id.to_owned(),
        start_line: 0,
    };
    let (_, run) = follow(run_client, goal, "execute_program", timeout, |f| {
        format!(
            "line {}/{} ({:.0} %)",
            f.acked_line, f.total_lines, f.percent_done
        )
    })
    .await?;
    Ok(run)
}

/// Waits up to `timeout` for the `action` server; an error naming its resolved name if none
/// comes.
async fn require_action_server(
    node: &CellNode,
    action: &str,
    timeout: Duration,
) -> anyhow::Result<()> {
    if !node.wait_for_action_server(action, timeout).await {
        bail!(
            "no {} server within {timeout:?}",
            node.resolve_topic(action)
        );
    }
    Ok(())
}

/// The sheet job: sequence, wait for its program, run it (stage 4 of the module docs).
async fn run_sheet(
    node: &CellNode,
    p: &RunnerParams,
    client: &SheetClient,
    programs: &mut cell_runtime::Subscriber<MachineProgram>,
    run_client: &RunClient,
    timeout: Duration,
) -> anyhow::Result<SheetSummary> {
    require_action_server(node, "sequence_sheet", timeout).await?;
    let (layout_file, layout_json) = match EMBEDDED_SHEETS
        .iter()
        .find(|(name, _)| *name == p.sheet_layout)
    {
        Some((_, json)) => (String::new(), (*json).to_owned()),
        None => (p.sheet_layout.clone(), String::new()),
    };
    let goal = SequenceSheetGoal {
        job_id: p.sheet_job_id.clone(),
        layout_file,
        layout_json,
        improve: true,
        time_budget_s: p.sheet_time_budget_s,
        machine_profile: p.sheet_machine_profile.clone(),
        seed: p.seed,
        ..Default::default()
    };
    tracing::info!("sequencing {} ({})", p.sheet_job_id, p.sheet_layout);
    let t0 = Instant::now();
    let (status, sequence) = follow(client, goal, "sequence_sheet", timeout, |f| {
        format!(
            "{}: iteration {}, best cost {:.1}, idle {:.0} mm, {} overheats",
            f.phase, f.iteration, f.best_cost, f.best_idle_length_mm, f.best_overheats
        )
    })
    .await?;
    if status != GoalStatusEnum::Succeeded || !sequence.success {
        bail!("sequence_sheet: {}", sequence.message);
    }
    let sequence_time = t0.elapsed();
    tracing::info!("{}", sequence.message);
    let (program, run, run_time) =
        program_and_run(programs, p, (&p.sheet_job_id, ""), run_client, timeout).await?;
    Ok(SheetSummary {
        sequence,
        sequence_time,
        program,
        run,
        run_time,
    })
}

/// The WAAM job: slice, wait for its program, run it on the robot (stage 5 of the module docs).
async fn run_waam(
    node: &CellNode,
    p: &RunnerParams,
    client: &SliceClient,
    programs: &mut cell_runtime::Subscriber<MachineProgram>,
    run_client: &RunClient,
    timeout: Duration,
) -> anyhow::Result<SliceJobSummary> {
    require_action_server(node, "slice", timeout).await?;
    // The slicer reads a path; the demo's nodes share this host. The embedded part's copy is
    // removed once the slicer has answered.
    let (stl_file, written) = match EMBEDDED_PARTS.iter().find(|(name, _)| *name == p.waam_part) {
        Some((name, bytes)) => {
            let dir = if p.part_dir.is_empty() {
                std::env::temp_dir()
            } else {
                std::path::PathBuf::from(&p.part_dir)
            };
            std::fs::create_dir_all(&dir).with_context(|| format!("part_dir {}", dir.display()))?;
            // An absolute path: the slicer's working directory may differ.
            let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
            let path = dir.join(format!(
                "cellsuite-{}-{}-{name}.stl",
                p.waam_job_id,
                std::process::id()
            ));
            std::fs::write(&path, bytes)
                .with_context(|| format!("writing the embedded part to {}", path.display()))?;
            (path.display().to_string(), Some(path))
        }
        None => (p.waam_part.clone(), None),
    };
    let goal = SliceGoal {
        job_id: p.waam_job_id.clone(),
        stl_file,
        layer_height_mm: p.waam_layer_height_mm,
        ..Default::default()
    };
    tracing::info!("slicing {} ({})", p.waam_job_id, p.waam_part);
    let t0 = Instant::now();
    let followed = follow(client, goal, "slice", timeout, |f| {
        format!("{}: layer {}/{}", f.phase, f.layers_done, f.layers_total)
    })
    .await;
    if let Some(path) = written {
        let _ = std::fs::remove_file(path);
    }
    let slice = slice_verdict(followed, "slice")?;
    let slice_time = t0.elapsed();
    let (program, run, run_time) = program_and_run(
        programs,
        p,
        (&p.waam_job_id, &p.waam_machine_id),
        run_client,
        timeout,
    )
    .await?;
    Ok(SliceJobSummary {
        slice,
        slice_time,
        program,
        run,
        run_time,
    })
}

/// The slicer's answer to a slice goal, or why the job stops there.
fn slice_verdict(
    followed: anyhow::Result<(GoalStatusEnum, SliceResult)>,
    action: &str,
) -> anyhow::Result<SliceResult> {
    let (status, slice) = followed?;
    if status != GoalStatusEnum::Succeeded || !slice.success {
        bail!("{action}: {}", slice.message);
    }
    tracing::info!("{}", slice.message);
    Ok(slice)
}

/// A stage's program, once the emitter has published it, run to its end on `machine_id`:
/// the program, the run's result and its running time.
async fn program_and_run(
    programs: &mut cell_runtime::Subscriber<MachineProgram>,
    p: &RunnerParams,
    (job_id, machine_id): (&str, &str),
    run_client: &RunClient,
    timeout: Duration,
) -> anyhow::Result<(MachineProgram, ExecuteProgramResult, Duration)> {
    let program = wait_for_program(programs, p, job_id, timeout).await?;
    let t0 = Instant::now();
    let run = execute(run_client, &program, machine_id, timeout).await?;
    Ok((program, run, t0.elapsed()))
}

/// Writes an embedded wing spec and its airfoil into `dir` (the airfoil next to the spec, as
/// the spec names it); returns the spec's path, or `None` for a name that is not embedded.
fn write_embedded_wing(
    p: &RunnerParams,
    dir: &std::path::Path,
) -> anyhow::Result<Option<std::path::PathBuf>> {
    let Some((name, spec, airfoil_name, airfoil)) =
        EMBEDDED_WINGS.iter().find(|(n, ..)| *n == p.wing_spec)
    else {
        return Ok(None);
    };
    std::fs::create_dir_all(dir).with_context(|| format!("part_dir {}", dir.display()))?;
    let dir = std::fs::canonicalize(dir).unwrap_or(dir.to_path_buf());
    let prefix = format!("cellsuite-{}-{}", p.wing_job_id, std::process::id());
    let airfoil_file = format!("{prefix}-{airfoil_name}");
    // The spec's airfoil path is relative to the spec file: point it at the copy beside it.
    let text: String = spec
        .lines()
        .map(|l| {
            if l.starts_with("airfoil:") {
                format!("airfoil: {airfoil_file}\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    std::fs::write(dir.join(&airfoil_file), airfoil)
        .with_context(|| format!("writing {airfoil_file} to {}", dir.display()))?;
    let path = dir.join(format!("{prefix}-{name}.yaml"));
    std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    Ok(Some(path))
}

/// The G-Wing job: design and slice one section, wait for its Marlin program, print it (stage
/// 6 of the module docs).
async fn run_wing(
    node: &CellNode,
    p: &RunnerParams,
    client: &SliceClient,
    programs: &mut cell_runtime::Subscriber<MachineProgram>,
    run_client: &RunClient,
    timeout: Duration,
) -> anyhow::Result<SliceJobSummary> {
    require_action_server(node, &p.wing_action, timeout).await?;
    let dir = if p.part_dir.is_empty() {
        std::env::temp_dir()
    } else {
        std::path::PathBuf::from(&p.part_dir)
    };
    let written = write_embedded_wing(p, &dir)?;
    let spec_file = written
        .as_ref()
        .map_or(p.wing_spec.clone(), |w| w.display().to_string());
    let goal = SliceGoal {
        job_id: p.wing_job_id.clone(),
        wing_spec_file: spec_file,
        wing_section: p.wing_section,
        ..Default::default()
    };
    tracing::info!(
        "designing and slicing {} ({}, section {})",
        p.wing_job_id,
        p.wing_spec,
        p.wing_section
    );
    let t0 = Instant::now();
    let followed = follow(client, goal, &p.wing_action, timeout, |f| {
        format!("{}: layer {}/{}", f.phase, f.layers_done, f.layers_total)
    })
    .await;
    if let Some(spec) = written {
        let airfoils: Vec<_> = EMBEDDED_WINGS
            .iter()
            .map(|(.., a, _)| {
                spec.with_file_name(format!(
                    "cellsuite-{}-{}-{a}",
                    p.wing_job_id,
                    std::process::id()
                ))
            })
            .collect();
        let _ = std::fs::remove_file(&spec);
        for a in airfoils {
            let _ = std::fs::remove_file(a);
        }
    }
    let slice = slice_verdict(followed, &p.wing_action)?;
    let slice_time = t0.elapsed();
    let (program, run, run_time) = program_and_run(
        programs,
        p,
        (&p.wing_job_id, &p.wing_machine_id),
        run_client,
        timeout,
    )
    .await?;
    Ok(SliceJobSummary {
        slice,
        slice_time,
        program,
        run,
        run_time,
    })
}

/// Runs the job, prints the summary, and returns an error unless the program ran to its end.
///
/// # Errors
/// As [`run_job`]; a program that did not finish.
pub async fn run(node: CellNode, p: RunnerParams) -> anyhow::Result<()> {
    let sink = node.rerun();
    sink.set_time(&cell_msgs::builtin_interfaces::Time::now(), 0);
    let summary = match run_job(&node, &p).await {
        Ok(s) => s,
        Err(e) => {
            sink.log_text(RERUN_LOG, &format!("{}: {e:#}", p.job_id));
            return Err(e);
        }
    };
    sink.set_time(&cell_msgs::builtin_interfaces::Time::now(), 1);
    for line in summary.to_string().lines().skip(2) {
        sink.log_text(RERUN_LOG, &format!("{}: {line}", p.job_id));
    }
    println!("{summary}");
    if !summary.run.success {
        bail!("execute_program: {}", summary.run.message);
    }
    if let Some(sheet) = summary.sheet.as_ref().filter(|s| !s.run.success) {
        bail!(
            "execute_program ({}): {}",
            p.sheet_job_id,
            sheet.run.message
        );
    }
    if let Some(waam) = summary.waam.as_ref().filter(|w| !w.run.success) {
        bail!("execute_program ({}): {}", p.waam_job_id, waam.run.message);
    }
    if let Some(wing) = summary.wing.as_ref().filter(|w| !w.run.success) {
        bail!("execute_program ({}): {}", p.wing_job_id, wing.run.message);
    }
    Ok(())
}

/// The `job_runner` binary (also `cell node job_runner`).
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("job_runner", argv, run)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_params_file_parses_and_matches_the_defaults() {
        let mut sources = cell_runtime::params::ParamSources::default();
        let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/job_runner.yaml");
        sources
            .merge_file(std::path::Path::new(file), "/", "job_runner")
            .unwrap();
        let p: RunnerParams = sources.parse().unwrap();
        assert_eq!(p, RunnerParams::default());
    }
}
