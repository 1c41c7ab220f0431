//! The `planner` node: serves the `plan_hotwire` action (`cell_msgs/action/PlanHotwire`).
//!
//! Per goal: validate (chord > 0, airfoil resolvable; otherwise the goal is rejected), accept,
//! run [`crate::job::plan_observed`] on a blocking thread, send feedback every
//! `feedback_every` iterations, republish the latest exposure profile on `exposure` every
//! `exposure_period_s` (the baseline's while the swarm runs: the optimiser does not expose its
//! intermediate best), then publish the `Toolpath` on `toolpath`, the final profile on
//! `exposure` and the wire × panel matrix on `exposure_matrix`, log to Rerun and send the
//! result. A failed job ends its goal as aborted with the error; the node keeps serving.
//! Goals are planned one at a time, in arrival order.
//!
//! Today only the root section is planned (z = 0, no tip points); goal fields for the tip and
//! the machine profile are accepted and reported as ignored.

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

use crate::job::{self, AirfoilSource, HotwireJob, HotwirePlan, JobProgress};
use crate::pso::PsoConfig;

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct PlannerParams {
    /// Foam id used when a goal's `material` is empty.
    pub default_material: String,
    /// Wire id from the material library.
    pub wire: String,
    /// Nominal wire current [A] (sets the default offset; constant current as a fallback).
    pub current_a: f64,
    /// Supply current limit [A] for the current schedule.
    pub max_current_a: f64,
    /// Cutting feed [mm/s].
    pub feed_mm_s: f64,
    /// Straight lead-in / lead-out length behind the trailing edge [mm].
    pub lead_in_mm: f64,
    /// Surface panels N of the exposure model.
    pub panels: usize,
    /// PSO iterations when a goal asks for 0.
    pub iterations: usize,
    /// PSO particles.
    pub particles: usize,
    /// PSO restart period [iterations]; 0: never.
    pub restart_every: usize,
    /// Send feedback every this many iterations (and after the last).
    pub feedback_every: usize,
    /// Republish the latest exposure profile this often while planning [s]; 0: only at the
    /// start and the end.
    pub exposure_period_s: f64,
    /// How long to wait for a client to ask for a goal's result [s].
    pub result_timeout_s: f64,
}

impl Default for PlannerParams {
    fn default() -> Self {
        let job = HotwireJob::default();
        Self {
            default_material: job.material,
            wire: job.wire,
            current_a: job.current_a,
            max_current_a: job.supply.max_a,
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
/// # Errors
/// A chord that is not > 0, an airfoil that does not resolve or load, other invalid values.
pub fn goal_to_job(goal: &PlanHotwireGoal, p: &PlannerParams) -> Result<HotwireJob, String> {
    let defaults = HotwireJob::default();
    let job = HotwireJob {
        root_airfoil: AirfoilSource::parse(&goal.root_airfoil),
        chord_mm: goal.root_chord_mm,
        material: if goal.material.is_empty() {
            p.default_material.clone()
        } else {
            goal.material.clone()
        },
        wire: p.wire.clone(),
        current_a: p.current_a,
        supply: crate::kerf::CurrentLimits {
            min_a: 0.0,
            max_a: p.max_current_a,
        },
        cse: (goal.cse > 0.0).then_some(goal.cse),
        panels: p.panels,
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
    if goal.root_airfoil.is_empty() {
        return Err("root_airfoil is empty".into());
    }
    job::validate(&job).map_err(|e| e.to_string())?;
    job.pso.validate().map_err(|e| e.to_string())?;
    job.root_airfoil.load().map_err(|e| e.to_string())?;
    Ok(job)
}

/// Goal fields this version does not plan yet, for the result message.
fn ignored_fields(goal: &PlanHotwireGoal) -> Vec<&'static str> {
    let mut out = Vec::new();
    if !goal.tip_airfoil.is_empty() {
        out.push("tip_airfoil");
    }
    for (name, v) in [
        ("tip_chord_mm", goal.tip_chord_mm),
        ("tip_twist_deg", goal.tip_twist_deg),
        ("tip_sweep_mm", goal.tip_sweep_mm),
        ("span_mm", goal.span_mm),
    ] {
        if v != 0.0 {
            out.push(name);
        }
    }
    if !goal.machine_profile.is_empty() {
        out.push("machine_profile");
    }
    out
}

/// What the planning thread reports to the node.
enum Update {
    Baseline(HeatMap),
    Progress(JobProgress),
}

/// The result message of a finished plan.
fn summary(job_id: &str, job: &HotwireJob, plan: &HotwirePlan, ignored: &[&str]) -> String {
    let mut msg = format!(
        "planned {job_id}: {} at {} mm, loss {:.4e} -> {:.4e}, RMS {:.4} -> {:.4} \
         ({} iterations, {:.1} s, seed {})",
        plan.airfoil,
        job.chord_mm,
        plan.baseline_loss,
        plan.final_loss,
        plan.baseline_stats.rms,
        plan.optimised_stats.rms,
        plan.iterations,
        plan.seconds,
        plan.seed
    );
    for note in &plan.notes {
        msg.push_str("; ");
        msg.push_str(note);
    }
    if !ignored.is_empty() {
        msg.push_str(&format!(
            "; root section only, ignored: {}",
            ignored.join(", ")
        ));
    }
    msg
}

fn log_to_rerun(node: &CellNode, plan: &HotwirePlan, toolpath: &Toolpath, profile: &HeatMap) {
    let sink = node.rerun();
    sink.set_time(&toolpath.header.stamp, 0);
    if let Some(rec) = sink.stream() {
        let mut foil: Vec<[f32; 3]> = plan
            .foil
            .iter()
            .map(|p| [p.x as f32, p.y as f32, 0.0])
            .collect();
        foil.extend(foil.first().copied());
        if let Err(e) = rec.log("/hotwire/foil", &rerun::LineStrips3D::new([foil])) {
            tracing::warn!("rerun: {e}");
        }
        for &(it, loss) in &plan.loss_history {
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
            toolpath.job_id, plan.baseline_loss, plan.final_loss
        ),
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
        let task = {
            let (job, stop, tx) = (job.clone(), stop.clone(), tx);
            tokio::task::spawn_blocking(move || {
                job::plan_observed(
                    &job,
                    |h| {
                        let _ = tx.send(Update::Baseline(h));
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
        let mut latest: Option<HeatMap> = None;
        let period = Duration::from_secs_f64(if p.exposure_period_s > 0.0 {
            p.exposure_period_s
        } else {
            1e6
        });
        let mut ticker = tokio::time::interval(period);
        loop {
            tokio::select! {
                update = rx.recv() => match update {
                    Some(Update::Baseline(h)) => {
                        exposure.publish(h.clone()).await?;
                        latest = Some(h);
                    }
                    Some(Update::Progress(pr)) => {
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
                _ = ticker.tick() => {
                    if let Some(h) = &latest {
                        exposure.publish(h.clone()).await?;
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
                let message = summary(&job_id, &job, &plan, &ignored_fields(&goal));
                tracing::info!("plan_hotwire: {message}");
                (
                    GoalEndStatus::Succeeded,
                    PlanHotwireResult {
                        success: true,
                        message,
                        toolpath,
                        final_loss: plan.final_loss,
                        baseline_loss: plan.baseline_loss,
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
        if stop.load(Ordering::Relaxed) {
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
    }
}
