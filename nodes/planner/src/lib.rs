//! The `planner` node: serves the `plan_hotwire` action (`cell_msgs/action/PlanHotwire`).
//!
//! Goals go through [`cell_runtime::goal_server`]. Per goal: validate (chord > 0, airfoil and
//! machine resolvable; otherwise the goal is rejected), accept, run
//! [`cell_planner::job::plan_observed`] on a blocking thread, send feedback every
//! `feedback_every` iterations (and log the loss curve to Rerun), publish the exposure profile on
//! `exposure` and the wire × panel matrix on `exposure_matrix` for each baseline and then for the
//! current best at most every `exposure_period_s`, then publish the `Toolpath` on `toolpath` and
//! the final maps, log to Rerun and send the result. A failed job ends its goal as aborted with
//! the error; the node keeps serving. Goals are planned one at a time, in arrival order.
//!
//! A goal's `machine_profile`, `root_airfoil` or `tip_airfoil` that is a path must be a
//! regular file under `data_dirs` within `max_file_mib` ([`cell_runtime::data_files`]); a
//! refusal or a file that does not parse never quotes the file.
//!
//! A goal naming a tip (airfoil, chord, twist or sweep) plans a tapered panel on a 4-axis
//! machine; the toolpath is in the machine profile's carriage coordinates. A cancel request
//! for the executing goal stops the swarm within one iteration and ends the goal as canceled.

use std::{ops::ControlFlow, time::Duration};

use cell_msgs::{HeatMap, PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult, Toolpath};
use cell_runtime::data_files::{self, DataDirs};
use cell_runtime::goal_server::{self, GoalContext, GoalEnd, GoalHandler, ServeOptions};
use cell_runtime::views::{HeatMapView, ToolpathViews};
use cell_runtime::{CellNode, Publisher, QosPreset};
use serde::{Deserialize, Serialize};

use cell_profiles::MachineProfile;

use cell_planner::job::{
    self, AirfoilSource, HotwireJob, HotwirePlan, JobProgress, LiveMaps, LiveOptions, TipRequest,
    TipSection,
};
use cell_planner::pso::PsoConfig;
use cell_planner::wing::Placement;

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
    /// Make the feed along the path a design variable (0.5–1.5 × `feed_mm_s` within the
    /// machine's limit, constant current; default true).
    pub optimise_feed: bool,
    /// With `optimise_feed`, let the wire current vary too, within
    /// `min_current_ratio`…`max_current_ratio` × `current_a` and the supply (default false).
    pub vary_current: bool,
    /// Lowest current as a fraction of `current_a` when `vary_current` (default 0.7).
    pub min_current_ratio: f64,
    /// Highest current as a fraction of `current_a` when `vary_current` (default 1.3).
    pub max_current_ratio: f64,
    /// Cutting feed (mm/s).
    pub feed_mm_s: f64,
    /// Straight lead-in / lead-out length behind the trailing edge (mm).
    pub lead_in_mm: f64,
    /// The longest lead-in (mm) when its length is a design variable from `lead_in_mm` to
    /// this; 0 (default): fixed at `lead_in_mm`.
    pub lead_in_max_mm: f64,
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
    /// Also publish the standard-type views for RViz and Foxglove (default true): the
    /// toolpath on `toolpath/path` (`nav_msgs/Path`) and `toolpath/markers`
    /// (`visualization_msgs/MarkerArray`), the heat maps on `exposure/image` and
    /// `exposure_matrix/image` (`sensor_msgs/Image`, `32FC1`); see `cell_runtime::views`.
    pub standard_views: bool,
    /// Directories a goal's airfoil or machine profile path must lie in (relative: to the
    /// working directory); see `cell_runtime::data_files`.
    pub data_dirs: Vec<String>,
    /// Largest file a goal may name, MiB.
    pub max_file_mib: u64,
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
            optimise_feed: true,
            vary_current: false,
            min_current_ratio: 0.7,
            max_current_ratio: 1.3,
            feed_mm_s: job.feed_mm_s,
            lead_in_mm: job.lead_in_mm,
            lead_in_max_mm: 0.0,
            panels: job.panels,
            iterations: job.pso.iterations,
            particles: job.pso.particles,
            restart_every: job.pso.restart_every,
            feedback_every: 50,
            exposure_period_s: 1.0,
            result_timeout_s: 600.0,
            standard_views: true,
            data_dirs: data_files::default_data_dirs(),
            max_file_mib: data_files::DEFAULT_MAX_FILE_MIB,
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
    let data_dirs = DataDirs::from_params(&p.data_dirs, p.max_file_mib);
    let machine = if goal.machine_profile.is_empty() {
        MachineProfile::resolve(&p.machine_profile).map_err(|e| e.to_string())?
    } else {
        data_dirs.machine_profile("machine_profile", &goal.machine_profile)?
    };
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
    let mut job = HotwireJob {
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
        objective: cell_planner::pso::Objective {
            feed: p.optimise_feed.then(|| {
                let feed = cell_planner::pso::FeedVariable::default();
                if p.vary_current {
                    feed.with_current_band((p.min_current_ratio, p.max_current_ratio))
                } else {
                    feed
                }
            }),
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
        lead_in_max_mm: (p.lead_in_max_mm > 0.0).then_some(p.lead_in_max_mm),
        ..defaults
    };
    job::validate(&job).map_err(|e| e.to_string())?;
    job.pso.validate().map_err(|e| e.to_string())?;
    confine_airfoil(&data_dirs, "root_airfoil", &mut job.root_airfoil)?;
    if let Some(t) = &mut job.tip {
        confine_airfoil(&data_dirs, "tip_airfoil", &mut t.airfoil)?;
    }
    Ok(job)
}

/// An airfoil file must pass `data_dirs` (then it is read by its canonical path); it is loaded
/// once here so a bad one rejects the goal, with the error's quoted values blanked.
fn confine_airfoil(
    data_dirs: &DataDirs,
    field: &str,
    airfoil: &mut AirfoilSource,
) -> Result<(), String> {
    let AirfoilSource::File(path) = airfoil else {
        return airfoil.load().map(drop).map_err(|e| e.to_string());
    };
    *path = data_dirs
        .check(&path.to_string_lossy())
        .map_err(|e| format!("{field}: {e}"))?;
    airfoil
        .load()
        .map(drop)
        .map_err(|e| format!("{field}: {}", data_files::without_content(&e.to_string())))
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

/// Logs the picture `cell hotwire` draws in `exposure.svg` ([`job::exposure_svg`]), per section
/// (`root`, and `tip` on a tapered panel):
///
/// - `/hotwire/picture/{section}/{foil,baseline,optimised,lead_in,lead_out}`: 2-D line strips
///   in the section's own frame (LE at the origin, mm), y negated because Rerun's 2-D views
///   point y down. Not magnified: the viewer zooms. (`/hotwire/{root,tip}_foil` and `_path`
///   are the machine-placed 3-D foil and optimised path; the baseline and leads are only here.)
/// - `/hotwire/exposure_profile/{section}/{baseline,optimised,cse}` and
///   `/hotwire/clearance_profile/{section}/{baseline,optimised,margin}` (mm): one scalar per
///   panel on the `panel` timeline (panels in Selig order from the trailing edge), so a
///   time-series view with the `panel` timeline overlays before, after and the target. Chosen
///   over bar charts, which show one series per view and cannot draw the CSE across them.
fn log_picture(node: &CellNode, plan: &HotwirePlan, clearance_mm: f64) {
    let Some(rec) = node.rerun().stream() else {
        return;
    };
    let report = |r: Result<(), rerun::RecordingStreamError>| {
        if let Err(e) = r {
            tracing::warn!("rerun: {e}");
        }
    };
    let grey = rerun::Color::from_rgb(140, 140, 140);
    let blue = rerun::Color::from_rgb(31, 111, 209);
    let orange = rerun::Color::from_rgb(224, 123, 0);
    let red = rerun::Color::from_rgb(198, 40, 40);
    let mut sections = vec![("root", &plan.root)];
    sections.extend(plan.tip.as_ref().map(|t| ("tip", t)));
    for (role, s) in sections {
        for (name, pts, close, colour) in [
            ("foil", &s.foil, true, rerun::Color::from_rgb(85, 85, 85)),
            ("baseline", &s.baseline, true, grey),
            ("optimised", &s.optimised, true, blue),
            ("lead_in", &s.lead_in, false, orange),
            ("lead_out", &s.lead_out, false, orange),
        ] {
            let strip = y_down_strip(pts.iter().map(|p| (p.x, p.y)), close);
            report(rec.log(
                format!("/hotwire/picture/{role}/{name}"),
                &rerun::LineStrips2D::new([strip]).with_colors([colour]),
            ));
        }
        let profiles = job::PanelProfiles::of(s);
        let exposure = format!("/hotwire/exposure_profile/{role}");
        let clearance = format!("/hotwire/clearance_profile/{role}");
        for (entity, colour, label) in [
            (format!("{exposure}/baseline"), grey, "baseline"),
            (format!("{exposure}/optimised"), blue, "optimised"),
            (format!("{exposure}/cse"), red, "CSE"),
            (format!("{clearance}/baseline"), grey, "baseline (mm)"),
            (format!("{clearance}/optimised"), blue, "optimised (mm)"),
            (format!("{clearance}/margin"), red, "clearance margin (mm)"),
        ] {
            let style = rerun::SeriesLines::new()
                .with_colors([colour])
                .with_names([label]);
            report(rec.log_static(entity, &style));
        }
        // One point per panel ([`job::PanelProfiles`] counts the panels with both exposures).
        for i in 0..profiles.position.len() {
            rec.set_time_sequence("panel", i as i64);
            for (entity, value) in [
                (format!("{exposure}/baseline"), s.baseline_exposure[i]),
                (format!("{exposure}/optimised"), s.optimised_exposure[i]),
                (format!("{exposure}/cse"), s.cse),
                (
                    format!("{clearance}/baseline"),
                    profiles.baseline_clearance_mm[i],
                ),
                (
                    format!("{clearance}/optimised"),
                    profiles.optimised_clearance_mm[i],
                ),
                (format!("{clearance}/margin"), clearance_mm),
            ] {
                report(rec.log(entity, &rerun::Scalars::single(value)));
            }
        }
        rec.disable_timeline("panel");
    }
}

/// A 2-D line strip with y negated (Rerun's 2-D views point y down), closed if `close`.
fn y_down_strip(points: impl Iterator<Item = (f64, f64)>, close: bool) -> Vec<[f32; 2]> {
    let mut out: Vec<[f32; 2]> = points.map(|(x, y)| [x as f32, -y as f32]).collect();
    if close && out.first() != out.last() {
        out.extend(out.first().copied());
    }
    out
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

/// The `plan_hotwire` goals: [`goal_to_job`] checks them, the PSO plans them.
struct Planner {
    node: CellNode,
    p: PlannerParams,
    toolpaths: Publisher<Toolpath>,
    exposure: Publisher<HeatMap>,
    matrix: Publisher<HeatMap>,
    toolpath_views: ToolpathViews,
    exposure_image: HeatMapView,
    matrix_image: HeatMapView,
}

impl GoalHandler for Planner {
    type Goal = PlanHotwireGoal;
    type Result = PlanHotwireResult;
    type Feedback = PlanHotwireFeedback;
    type Job = HotwireJob;

    fn job_id(&self, goal: &PlanHotwireGoal, served: u64) -> String {
        if goal.job_id.is_empty() {
            format!("hotwire-{served}")
        } else {
            goal.job_id.clone()
        }
    }

    fn validate(&self, goal: &PlanHotwireGoal, _job_id: &str) -> Result<HotwireJob, String> {
        goal_to_job(goal, &self.p)
    }

    async fn run(
        &self,
        job: HotwireJob,
        ctx: GoalContext<PlanHotwireFeedback>,
    ) -> anyhow::Result<GoalEnd<PlanHotwireResult>> {
        let job_id = ctx.job_id().to_owned();
        tracing::info!(
            "plan_hotwire: planning {job_id} ({} at {} mm, {} iterations, seed {})",
            job.root_airfoil,
            job.chord_mm,
            job.pso.iterations,
            job.seed
        );
        let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel();
        let every = self.p.feedback_every.max(1);
        let live = LiveOptions {
            period: (self.p.exposure_period_s > 0.0)
                .then(|| Duration::from_secs_f64(self.p.exposure_period_s)),
        };
        let planning = {
            let (job, shutdown) = (job.clone(), self.node.shutdown().clone());
            ctx.run_blocking(move |ctx| {
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
                        // A cancel, or the node stopping, ends the swarm within one iteration.
                        if ctx.is_canceled() || shutdown.is_triggered() {
                            ControlFlow::Break(())
                        } else {
                            ControlFlow::Continue(())
                        }
                    },
                )
            })
        };
        let forwarding = async {
            while let Some(update) = rx.recv().await {
                match update {
                    Update::Maps(mut maps) => {
                        let now = self.node.now();
                        maps.profile.header.stamp = now;
                        maps.matrix.header.stamp = now;
                        log_live(&self.node, &maps);
                        self.exposure_image.publish(&maps.profile).await;
                        self.matrix_image.publish(&maps.matrix).await;
                        self.exposure.publish(maps.profile).await?;
                        self.matrix.publish(maps.matrix).await?;
                    }
                    Update::Progress(pr) => {
                        log_loss(&self.node, pr.iteration, pr.best_loss);
                        ctx.feedback(PlanHotwireFeedback {
                            iteration: pr.iteration as u32,
                            total_iterations: pr.total as u32,
                            best_loss: pr.best_loss,
                            eta_s: pr.eta_s,
                        });
                    }
                }
            }
            anyhow::Ok(())
        };
        let (outcome, forwarded) = tokio::join!(planning, forwarding);
        forwarded?;
        Ok(match outcome? {
            Ok(plan) => {
                let now = self.node.now();
                let mut toolpath = plan.to_toolpath(&job_id);
                toolpath.header.stamp = now;
                let mut profile = plan.exposure_heat_map();
                profile.header.stamp = now;
                self.toolpaths.publish(toolpath.clone()).await?;
                self.toolpath_views.publish(&toolpath).await;
                self.exposure.publish(profile.clone()).await?;
                self.exposure_image.publish(&profile).await;
                match plan.exposure_matrix_heat_map() {
                    Ok(mut m) => {
                        m.header.stamp = now;
                        self.matrix_image.publish(&m).await;
                        self.matrix.publish(m).await?
                    }
                    Err(e) => tracing::warn!("plan_hotwire: {job_id}: exposure matrix: {e}"),
                }
                log_to_rerun(&self.node, &plan, &toolpath, &profile);
                log_picture(&self.node, &plan, job.objective.min_clearance_mm);
                let message = summary(&job_id, &job, &plan);
                tracing::info!("plan_hotwire: {message}");
                GoalEnd::succeeded(PlanHotwireResult {
                    success: true,
                    message,
                    toolpath,
                    final_loss: plan.root.final_loss,
                    baseline_loss: plan.root.baseline_loss,
                })
            }
            Err(e @ job::JobError::Cancelled { .. }) if ctx.is_canceled() => {
                let message = format!("{job_id}: {e} at the client's request");
                tracing::info!("plan_hotwire: {message}");
                GoalEnd::canceled(PlanHotwireResult {
                    success: false,
                    message,
                    ..Default::default()
                })
            }
            Err(e) => {
                let message = format!("{job_id}: {e}");
                tracing::warn!("plan_hotwire: failed: {message}");
                GoalEnd::aborted(PlanHotwireResult {
                    success: false,
                    message,
                    ..Default::default()
                })
            }
        })
    }
}

/// Serves `plan_hotwire` until shutdown.
pub async fn run(node: CellNode, p: PlannerParams) -> anyhow::Result<()> {
    let toolpaths = node.publisher::<Toolpath>("toolpath", QosPreset::Plan)?;
    let exposure = node.publisher::<HeatMap>("exposure", QosPreset::Stream)?;
    let matrix = node.publisher::<HeatMap>("exposure_matrix", QosPreset::Stream)?;
    let planner = Planner {
        toolpath_views: ToolpathViews::new(&node, &toolpaths, p.standard_views)?,
        exposure_image: HeatMapView::new(&node, &exposure, p.standard_views)?,
        matrix_image: HeatMapView::new(&node, &matrix, p.standard_views)?,
        toolpaths,
        exposure,
        matrix,
        node: node.clone(),
        p: p.clone(),
    };
    tracing::info!(
        "serving {} ({} panels, {} particles, {} iterations by default)",
        node.resolve_topic("plan_hotwire"),
        p.panels,
        p.particles,
        p.iterations
    );
    let options = ServeOptions::one_at_a_time(p.result_timeout_s);
    goal_server::serve(node, "plan_hotwire", planner, options).await
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
