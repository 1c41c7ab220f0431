//! The `planner` node: serves the `plan_hotwire` action (`cell_msgs/action/PlanHotwire`).
//!
//! Per goal: validate (chord > 0, airfoil and machine resolvable; otherwise the goal is
//! rejected), accept, run [`crate::job::plan_observed`] on a blocking thread, send feedback
//! every `feedback_every` iterations (and log the loss curve to Rerun), publish the exposure
//! profile on `exposure` and the wire × panel matrix on `exposure_matrix` for each baseline and
//! then for the current best at most every `exposure_period_s`, then publish the `Toolpath` on
//! `toolpath` and the final maps, log to Rerun and send the result. A failed job ends its goal as aborted with the error; the node keeps serving.
//! Goals are planned one at a time, in arrival order.
//!
//! A goal naming a tip (airfoil, chord, twist or sweep) plans a tapered panel on a 4-axis
//! machine; the toolpath is in the machine profile's carriage coordinates. A cancel request
//! for the executing goal stops the swarm within one iteration and ends the goal as canceled.

use std::{
    ops::ControlFlow,
    sync::{
        atomic::{AtomicBool, Ordering},
        Arc,
    },
    time::Duration,
};

use cell_msgs::{HeatMap, PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult, Toolpath};
use cell_runtime::{action::GoalEndStatus, CellNode, QosPreset};
use serde::{Deserialize, Serialize};

use cell_profiles::MachineProfile;

use crate::job::{
    self, AirfoilSource, HotwireJob, HotwirePlan, JobProgress, LiveMaps, LiveOptions, TipRequest,
    TipSection,
};
use crate::pso::PsoConfig;
use crate::wing::Placement;

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct PlannerParams {
    /// Foam id used when a goal's `material` is empty.
    pub default_material: String,
    /// Machine profile used when a goal's `machine_profile` is empty: a name under
    /// `config/machines` or a path to a profile YAML (it gives the wire, supply and travel).
    pub machine_profile: String,
    /// Panel span (mm) when a goal's `span_mm` is 0.
    pub span_mm: f64,
    /// Tip twist pivot as a fraction of the tip chord from its LE.
    pub twist_pivot_chord_fraction: f64,
    /// Nominal wire current (A) (sets the default offset; constant current as a fallback).
    pub current_a: f64,
    /// Make the feed along the path a design variable (0.5–1.5 × `feed_mm_s`, constant
    /// current).
    pub optimise_feed: bool,
    /// Cutting feed (mm/s).
    pub feed_mm_s: f64,
    /// Straight lead-in / lead-out length behind the trailing edge (mm).
    pub lead_in_mm: f64,
    /// Surface panels N of the exposure model.
    pub panels: usize,
    /// PSO iterations when a goal asks for 0.
    pub iterations: usize,
    /// PSO particles.
    pub particles: usize,
    /// PSO restart period (iterations); 0: never.
    pub restart_every: usize,
    /// Send feedback every this many iterations (and after the last).
    pub feedback_every: usize,
    /// Publish the current best's exposure profile and matrix at most this often while
    /// planning (s); 0: only the baselines and the end.
    pub exposure_period_s: f64,
    /// How long to wait for a client to ask for a goal's result (s).
    pub result_timeout_s: f64,
}

impl Default for PlannerParams {
    fn default() -> Self {
        let job = HotwireJob::default();
        Self {
            default_material: job.material,
            machine_profile: job.machine.name,
            span_mm: job.span_mm,
            twist_pivot_chord_fraction: Placement::ROOT.pivot_chord_fraction,
            current_a: job.current_a,
            optimise_feed: false,
            feed_mm_s: job.feed_mm_s,
            lead_in_mm: job.lead_in_mm,
            panels: job.panels,
            iterations: job.pso.iterations,
            particles: job.pso.particles,
            restart_every: job.pso.restart_every,
            feedback_every: 50,
            exposure_period_s: 1.0,
            result_timeout_s: 600.0,
        }
    }
}

/// The job a goal asks for, or why it cannot be planned (one line).
///
/// Empty or zero goal fields take the parameters' or the root's values: `tip_airfoil` empty
/// and `tip_chord_mm` 0 mean the root's, `span_mm` 0 and `machine_profile` empty the
/// parameters'.
///
/// # Errors
/// A chord that is not > 0, an airfoil or machine profile that does not resolve or load,
/// other invalid values.
pub fn goal_to_job(goal: &PlanHotwireGoal, p: &PlannerParams) -> Result<HotwireJob, String> {
    let defaults = HotwireJob::default();
    if goal.root_airfoil.is_empty() {
        return Err("root_airfoil is empty".into());
    }
    let machine_name = if goal.machine_profile.is_empty() {
        &p.machine_profile
    } else {
        &goal.machine_profile
    };
    let machine = MachineProfile::resolve(machine_name).map_err(|e| e.to_string())?;
    let root_airfoil = AirfoilSource::parse(&goal.root_airfoil);
    // Empty strings and zeros are the goal's "not given".
    let given = |v: f64| (v != 0.0).then_some(v);
    let request = TipRequest {
        airfoil: (!goal.tip_airfoil.is_empty()).then_some(goal.tip_airfoil.as_str()),
        chord_mm: given(goal.tip_chord_mm),
        twist_deg: given(goal.tip_twist_deg),
        sweep_mm: given(goal.tip_sweep_mm),
    };
    let tip = TipSection::requested(
        &request,
        &root_airfoil,
        goal.root_chord_mm,
        p.twist_pivot_chord_fraction,
    );
    let job = HotwireJob {
        root_airfoil,
        chord_mm: goal.root_chord_mm,
        tip,
        span_mm: if goal.span_mm == 0.0 {
            p.span_mm
        } else {
            goal.span_mm
        },
        machine,
        material: if goal.material.is_empty() {
            p.default_material.clone()
        } else {
            goal.material.clone()
        },
        current_a: p.current_a,
        cse: (goal.cse > 0.0).then_some(goal.cse),
        panels: p.panels,
        objective: crate::pso::Objective {
            feed: p.optimise_feed.then(crate::pso::FeedVariable::default),
            ..defaults.objective
        },
        pso: PsoConfig {
            particles: p.particles,
            iterations: if goal.iterations == 0 {
                p.iterations
            } else {
                goal.iterations as usize
            },
            restart_every: p.restart_every,
            ..defaults.pso
        },
        seed: goal.seed,
        feed_mm_s: p.feed_mm_s,
        lead_in_mm: p.lead_in_mm,
        ..defaults
    };
    job::validate(&job).map_err(|e| e.to_string())?;
    job.pso.validate().map_err(|e| e.to_string())?;
    job.root_airfoil.load().map_err(|e| e.to_string())?;
    if let Some(t) = &job.tip {
        t.airfoil.load().map_err(|e| e.to_string())?;
    }
    Ok(job)
}

/// What the planning thread reports to the node.
enum Update {
    Maps(Box<LiveMaps>),
    Progress(JobProgress),
}

/// The result message of a finished plan.
fn summary(job_id: &str, job: &HotwireJob, plan: &HotwirePlan) -> String {
    let mut msg = format!(
        "planned {job_id}: {} at {} mm, loss {:.4e} -> {:.4e}, RMS {:.4} -> {:.4} \
         ({} iterations, {:.1} s, seed {})",
        plan.root.airfoil,
        job.chord_mm,
        plan.root.baseline_loss,
        plan.root.final_loss,
        plan.root.baseline_stats.rms,
        plan.root.optimised_stats.rms,
        plan.iterations,
        plan.seconds,
        plan.seed
    );
    if let Some(t) = &plan.tip {
        msg.push_str(&format!(
            "; tip {} at {} mm: RMS {:.4} -> {:.4}",
            t.airfoil, t.chord_mm, t.baseline_stats.rms, t.optimised_stats.rms
        ));
    }
    for note in &plan.notes {
        msg.push_str("; ");
        msg.push_str(note);
    }
    msg
}

fn log_to_rerun(node: &CellNode, plan: &HotwirePlan, toolpath: &Toolpath, profile: &HeatMap) {
    let sink = node.rerun();
    sink.set_time(&toolpath.header.stamp, 0);
    if let Some(rec) = sink.stream() {
        // Foils and face paths where they sit in the machine, beside the carriage paths.
        for (name, pts) in plan.placed_sections() {
            let strip: Vec<[f32; 3]> = pts
                .iter()
                .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
                .collect();
            if let Err(e) = rec.log(
                format!("/hotwire/{name}"),
                &rerun::LineStrips3D::new([strip]),
            ) {
                tracing::warn!("rerun: {e}");
            }
        }
        for &(it, loss) in &plan.root.loss_history {
            rec.set_time_sequence("iteration", it as i64);
            if let Err(e) = rec.log("/hotwire/loss", &rerun::Scalars::single(loss)) {
                tracing::warn!("rerun: {e}");
            }
        }
        rec.disable_timeline("iteration");
    }
    sink.log_toolpath("/hotwire/trajectory", toolpath);
    sink.log_heat_map("/hotwire/exposure", profile);
    sink.log_text(
        "/hotwire/log",
        &format!(
            "{} loss {:.4e} -> {:.4e}",
            toolpath.job_id, plan.root.baseline_loss, plan.root.final_loss
        ),
    );
}

/// Logs one point of the loss curve on the `iteration` timeline.
fn log_loss(node: &CellNode, iteration: usize, loss: f64) {
    if let Some(rec) = node.rerun().stream() {
        rec.set_time_sequence("iteration", iteration as i64);
        if let Err(e) = rec.log("/hotwire/loss", &rerun::Scalars::single(loss)) {
            tracing::warn!("rerun: {e}");
        }
        rec.disable_timeline("iteration");
    }
}

/// Logs the current best's exposure profile and matrix while planning.
fn log_live(node: &CellNode, maps: &LiveMaps) {
    let sink = node.rerun();
    sink.set_time(&maps.profile.header.stamp, 0);
    let section = if maps.profile.header.frame_id == job::TIP_FRAME_ID {
        "tip"
    } else {
        "root"
    };
    sink.log_heat_map(&format!("/hotwire/live/{section}/exposure"), &maps.profile);
    sink.log_heat_map(
        &format!("/hotwire/live/{section}/exposure_matrix"),
        &maps.matrix,
    );
}

/// Serves `plan_hotwire` until shutdown.
pub async fn run(node: CellNode, p: PlannerParams) -> anyhow::Result<()> {
    let server = Arc::new(
        node.action_server::<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>(
            "plan_hotwire",
        )?,
    );
    let toolpaths = node.publisher::<Toolpath>("toolpath", QosPreset::Plan)?;
    let exposure = node.publisher::<HeatMap>("exposure", QosPreset::Stream)?;
    let matrix = node.publisher::<HeatMap>("exposure_matrix", QosPreset::Stream)?;
    tracing::info!(
        "serving {} ({} panels, {} particles, {} iterations by default)",
        node.resolve_topic("plan_hotwire"),
        p.panels,
        p.particles,
        p.iterations
    );
    let mut served = 0u64;
    loop {
        let handle = tokio::select! {
            h = server.receive_new_goal() => match h {
                Ok(h) => h,
                Err(e) => {
                    tracing::warn!("plan_hotwire: cannot read a goal: {e:?}");
                    continue;
                }
            },
            c = server.receive_cancel_request() => {
                // Nothing is executing: whatever it names is not cancellable.
                if let Ok(c) = c {
                    if let Err(e) = server.respond_to_cancel_requests(&c, std::iter::empty()).await {
                        tracing::warn!("plan_hotwire: cancel response: {e:?}");
                    }
                }
                continue;
            }
            _ = node.shutdown().requested() => return Ok(()),
        };
        let Some(goal) = server.get_new_goal(handle.clone()) else {
            tracing::warn!("plan_hotwire: goal without a body");
            continue;
        };
        served += 1;
        let job_id = if goal.job_id.is_empty() {
            format!("hotwire-{served}")
        } else {
            goal.job_id.clone()
        };
        let job = match goal_to_job(&goal, &p) {
            Ok(job) => job,
            Err(e) => {
                tracing::warn!("plan_hotwire: rejecting goal {job_id}: {e}");
                if let Err(e) = server.reject_goal(handle).await {
                    tracing::warn!("plan_hotwire: reject {job_id}: {e:?}");
                }
                continue;
            }
        };
        let accepted = match server.accept_goal(handle).await {
            Ok(a) => a,
            Err(e) => {
                tracing::warn!("plan_hotwire: accept {job_id}: {e:?}");
                continue;
            }
        };
        let executing = match server.start_executing_goal(accepted).await {
            Ok(x) => x,
            Err(e) => {
                tracing::warn!("plan_hotwire: execute {job_id}: {e:?}");
                continue;
            }
        };
        tracing::info!(
            "plan_hotwire: planning {job_id} ({} at {} mm, {} iterations, seed {})",
            job.root_airfoil,
            job.chord_mm,
            job.pso.iterations,
            job.seed
        );

        let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel();
        let stop = Arc::new(AtomicBool::new(false));
        let every = p.feedback_every.max(1);
        let live = LiveOptions {
            period: (p.exposure_period_s > 0.0)
                .then(|| Duration::from_secs_f64(p.exposure_period_s)),
        };
        let task = {
            let (job, stop, tx) = (job.clone(), stop.clone(), tx);
            tokio::task::spawn_blocking(move || {
                job::plan_observed(
                    &job,
                    &live,
                    |maps| {
                        let _ = tx.send(Update::Maps(Box::new(maps)));
                    },
                    |pr| {
                        if pr.iteration % every == 0 || pr.iteration == pr.total {
                            let _ = tx.send(Update::Progress(*pr));
                        }
                        if stop.load(Ordering::Relaxed) {
                            ControlFlow::Break(())
                        } else {
                            ControlFlow::Continue(())
                        }
                    },
                )
            })
        };
        let mut cancelled = false;
        loop {
            tokio::select! {
                update = rx.recv() => match update {
                    Some(Update::Maps(maps)) => {
                        log_live(&node, &maps);
                        exposure.publish(maps.profile).await?;
                        matrix.publish(maps.matrix).await?;
                    }
                    Some(Update::Progress(pr)) => {
                        log_loss(&node, pr.iteration, pr.best_loss);
                        let feedback = PlanHotwireFeedback {
                            iteration: pr.iteration as u32,
                            total_iterations: pr.total as u32,
                            best_loss: pr.best_loss,
                            eta_s: pr.eta_s,
                        };
                        if let Err(e) = server.publish_feedback(executing.clone(), feedback).await {
                            tracing::warn!("plan_hotwire: feedback {job_id}: {e:?}");
                        }
                    }
                    None => break,
                },
                c = server.receive_cancel_request() => {
                    let Ok(c) = c else { continue };
                    let goal_id = executing.goal_id();
                    let ours = c.contains_goal(&goal_id);
                    if ours {
                        tracing::info!("plan_hotwire: cancelling {job_id}");
                        cancelled = true;
                        stop.store(true, Ordering::Relaxed);
                    }
                    let accepted = ours.then_some(goal_id).into_iter();
                    if let Err(e) = server.respond_to_cancel_requests(&c, accepted).await {
                        tracing::warn!("plan_hotwire: cancel response {job_id}: {e:?}");
                    }
                }
                _ = node.shutdown().requested(), if !stop.load(Ordering::Relaxed) => {
                    stop.store(true, Ordering::Relaxed);
                }
            }
        }
        let outcome = task
            .await
            .map_err(|e| anyhow::anyhow!("planning thread: {e}"))?;
        let (status, result) = match outcome {
            Ok(plan) => {
                let toolpath = plan.to_toolpath(&job_id);
                let profile = plan.exposure_heat_map();
                toolpaths.publish(toolpath.clone()).await?;
                exposure.publish(profile.clone()).await?;
                match plan.exposure_matrix_heat_map() {
                    Ok(m) => matrix.publish(m).await?,
                    Err(e) => tracing::warn!("plan_hotwire: {job_id}: exposure matrix: {e}"),
                }
                log_to_rerun(&node, &plan, &toolpath, &profile);
                let message = summary(&job_id, &job, &plan);
                tracing::info!("plan_hotwire: {message}");
                (
                    GoalEndStatus::Succeeded,
                    PlanHotwireResult {
                        success: true,
                        message,
                        toolpath,
                        final_loss: plan.root.final_loss,
                        baseline_loss: plan.root.baseline_loss,
                    },
                )
            }
            Err(e @ job::JobError::Cancelled { .. }) if cancelled => {
                let message = format!("{job_id}: {e} at the client's request");
                tracing::info!("plan_hotwire: {message}");
                (
                    GoalEndStatus::Canceled,
                    PlanHotwireResult {
                        success: false,
                        message,
                        ..Default::default()
                    },
                )
            }
            Err(e) => {
                let message = format!("{job_id}: {e}");
                tracing::warn!("plan_hotwire: failed: {message}");
                (
                    GoalEndStatus::Aborted,
                    PlanHotwireResult {
                        success: false,
                        message,
                        ..Default::default()
                    },
                )
            }
        };
        // The result goes out once the client asks for it; do not hold up the next goal.
        let (server, wait) = (
            server.clone(),
            Duration::from_secs_f64(p.result_timeout_s.max(0.0)),
        );
        tokio::spawn(async move {
            match tokio::time::timeout(wait, server.send_result_response(executing, status, result))
                .await
            {
                Ok(Ok(())) => {}
                Ok(Err(e)) => tracing::warn!("plan_hotwire: result {job_id}: {e:?}"),
                Err(_) => tracing::warn!("plan_hotwire: nobody asked for the result of {job_id}"),
            }
        });
        if stop.load(Ordering::Relaxed) && !cancelled {
            return Ok(());
        }
    }
}

/// The `planner` binary (also `cell node planner`).
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("planner", argv, run)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_params_file_parses_and_matches_the_defaults() {
        let mut sources = cell_runtime::params::ParamSources::default();
        let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/planner.yaml");
        sources
            .merge_file(std::path::Path::new(file), "/", "planner")
            .unwrap();
        let p: PlannerParams = sources.parse().unwrap();
        assert_eq!(p, PlannerParams::default());
    }

    #[test]
    fn goals_map_to_jobs_and_bad_ones_are_named() {
        let p = PlannerParams::default();
        let goal = PlanHotwireGoal {
            root_airfoil: "s1223".into(),
            root_chord_mm: 150.0,
            ..Default::default()
        };
        let job = goal_to_job(&goal, &p).unwrap();
        assert_eq!(job.pso.iterations, p.iterations);
        assert_eq!(job.material, p.default_material);
        let job = goal_to_job(
            &PlanHotwireGoal {
                iterations: 7,
                ..goal.clone()
            },
            &p,
        )
        .unwrap();
        assert_eq!(job.pso.iterations, 7);
        let e = goal_to_job(
            &PlanHotwireGoal {
                root_chord_mm: 0.0,
                ..goal.clone()
            },
            &p,
        )
        .unwrap_err();
        assert!(e.starts_with("chord_mm"), "{e}");
        let e = goal_to_job(
            &PlanHotwireGoal {
                root_airfoil: "nope".into(),
                ..goal
            },
            &p,
        )
        .unwrap_err();
        assert!(e.contains("nope"), "{e}");
        let tapered = PlanHotwireGoal {
            root_airfoil: "s1223".into(),
            root_chord_mm: 150.0,
            tip_chord_mm: 100.0,
            ..Default::default()
        };
        let job = goal_to_job(&tapered, &p).unwrap();
        let tip = job.tip.as_ref().unwrap();
        assert_eq!((tip.chord_mm, &tip.airfoil), (100.0, &job.root_airfoil));
        assert_eq!(job.span_mm, p.span_mm);
        let e = goal_to_job(
            &PlanHotwireGoal {
                machine_profile: "grbl-xy".into(),
                ..tapered.clone()
            },
            &p,
        )
        .unwrap_err();
        assert!(e.contains("4-axis"), "{e}");
        let e = goal_to_job(
            &PlanHotwireGoal {
                machine_profile: "mill_9000".into(),
                ..tapered
            },
            &p,
        )
        .unwrap_err();
        assert!(e.contains("mill_9000"), "{e}");
    }
}
