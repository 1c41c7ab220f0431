//! The `sequencer` node: serves the `sequence_sheet` action (`cell_msgs/action/SequenceSheet`),
//! a thin adapter around [`cell_sequencer::job::run`] (seed 003; issue 7).
//!
//! Goals go through [`cell_runtime::goal_server`]. Per goal: build a [`SheetJob`] from the goal
//! and the parameters (empty or zero goal fields take the parameters' values; a goal that does
//! not make one, e.g. an unknown policy or no layout, is rejected), accept it, run it on a
//! blocking thread, and send feedback (phase, iteration, best cost so far) at every phase change
//! and every `feedback_every` improvement iterations. While the final plan is simulated, the temperature raster goes out
//! as `HeatMap` frames on `sheet_heat` (Stream QoS, so the iceoryx2 fast path on one host) every
//! `frame_every_steps` spread steps, at most `max_frames` per goal. Then the `Toolpath` is
//! published on `toolpath` (Plan QoS), the `CutPlan` on `cut_plan` (Plan QoS), everything is
//! logged to Rerun and the result carries both. A goal that fails (a layout file that cannot be
//! read or is broken) ends as aborted with `success = false` and a message naming the file,
//! entity or field; the node keeps serving. Goals run one at a time, in arrival order. A cancel
//! request for the running goal is accepted: the improvement phase stops at its next iteration
//! (its `stop` check), the best plan so far is simulated as usual and the goal ends as canceled,
//! its result carrying that plan (`success = false`); nothing is published for the emitter.
//! Cancel requests for other goals are refused.
//!
//! A goal's `layout_file` and a `machine_profile` that is a path must be regular files under
//! `data_dirs` within `max_file_mib` ([`cell_runtime::data_files`]); a refusal, or a layout
//! file that does not parse, never quotes the file.
//!
//! Rerun entities (the suite's `/sheet/…` tree): `/sheet/heat` (the raster over the `sim_step`
//! timeline),
//! `/sheet/toolpath` (the toolpath as line strips coloured by segment kind: cut vs travel),
//! `/sheet/overheats` (points at the pierce points of the cuts that overheated, radius by count),
//! `/sheet/best_cost` (the feedback's best cost over the `iteration` timeline) and `/sheet/log`.

use cell_runtime::data_files::{without_content, DataDirs};

use cell_msgs::{
    geometry_msgs::Point, std_msgs::Header, CutPlan as CutPlanMsg, HeatMap, SequenceSheetFeedback,
    SequenceSheetGoal, SequenceSheetResult, Toolpath,
};
use cell_profiles::MachineProfile;
use cell_runtime::goal_server::{self, GoalContext, GoalEnd, GoalHandler, ServeOptions};
use cell_runtime::views::{HeatMapView, ToolpathViews};
use cell_runtime::{CellNode, Publisher, QosPreset};
use serde::{Deserialize, Serialize};

use cell_sequencer::cost::CostParams;
use cell_sequencer::cut::spec_for_profile;
use cell_sequencer::dxf::DxfOptions;
use cell_sequencer::improve::ImproveParams;
use cell_sequencer::job::{
    self, JobProgress, LayoutSource, Phase, PierceMode, SheetJob, SheetOutcome,
};
use cell_sequencer::layout::PierceOptions;
use cell_sequencer::placement::Travel;
use cell_sequencer::thermal::{Frame, ThermalParams};
use cell_sequencer::toolpath::{to_cut_plan_msg, to_toolpath, with_cut, ToolpathOptions, FRAME_ID};

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`; nested keys as
/// `thermal.t_max_c`). Physical units in the names; defaults in `config/sequencer.yaml`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SequencerParams {
    /// Precedence rules when a goal's is empty: `strict` (seed 003 §2) or `relaxed`.
    pub precedence: String,
    /// Pierce mode when a goal's is empty: `fixed` or `free` ([`cell_sequencer::job`] docs).
    pub pierce: String,
    /// Construction policy when a goal's is empty (seed 003 §A4).
    pub policy: String,
    /// Improvement time budget when a goal asks for 0, s; 0 = iterations only.
    pub time_budget_s: f64,
    /// Improvement LNS iterations.
    pub max_iterations: usize,
    /// Machine profile when a goal's is empty: a name under `config/machines` or a YAML path;
    /// its feed limit caps the toolpath feeds and a part outside its X/Y travel fails the goal.
    pub machine_profile: String,
    /// `[x, y]`, mm: place the sheet's lower-left corner there on the machine (machine =
    /// sheet-relative + x, y); empty: the drawing's own coordinates
    /// ([`cell_sequencer::placement`]).
    pub sheet_origin: Vec<f64>,
    /// The sheet's material as the profile's `cutting:` kerf table names it; empty: the
    /// section's `default_material` ([`cell_sequencer::cut::spec_for_profile`]).
    pub material: String,
    /// The sheet's thickness, mm; 0: the section's `default_material`.
    pub thickness_mm: f64,
    /// Cutting power in the toolpath, %.
    pub power_percent: f64,
    /// Send improvement feedback every this many iterations (phase changes always).
    pub feedback_every: usize,
    /// Publish a raster frame every this many spread steps of the final simulation.
    pub frame_every_steps: u64,
    /// At most this many raster frames per goal.
    pub max_frames: usize,
    /// DXF arc flattening tolerance, mm.
    pub dxf_chord_tol_mm: f64,
    /// DXF endpoint join tolerance, mm.
    pub dxf_join_tol_mm: f64,
    /// Free pierce candidates (`max_candidates`, `spacing_mm`, `corner_angle_deg`,
    /// `corner_margin_mm`).
    pub pierce_options: PierceOptions,
    /// Thermal raster constants (seed 003 §A3; `cell_sequencer::thermal`).
    pub thermal: ThermalParams,
    /// Cost weights (`cell_sequencer::cost`); `cost.thermal: false` is the thermal-off mode
    /// (idle length alone, the final plan still simulated: `cell_sequencer::job` docs).
    pub cost: CostParams,
    /// How long a finished goal's result waits for the client to ask for it, s.
    pub result_timeout_s: f64,
    /// Also publish the standard-type views for RViz and Foxglove (default true): the
    /// toolpath on `toolpath/path` (`nav_msgs/Path`) and `toolpath/markers`
    /// (`visualization_msgs/MarkerArray`), the heat frames on `sheet_heat/image`
    /// (`sensor_msgs/Image`, `32FC1`); see `cell_runtime::views`.
    pub standard_views: bool,
    /// Directories a goal's layout file or machine profile path must lie in (relative: to the
    /// working directory); see `cell_runtime::data_files`.
    pub data_dirs: Vec<String>,
    /// Largest file a goal may name, MiB.
    pub max_file_mib: u64,
}

impl Default for SequencerParams {
    fn default() -> Self {
        let dxf = DxfOptions::default();
        SequencerParams {
            precedence: "strict".into(),
            pierce: "free".into(),
            policy: "nearest".into(),
            time_budget_s: 5.0,
            max_iterations: ImproveParams::default().max_iterations,
            machine_profile: "linuxcnc-plasma".into(),
            sheet_origin: Vec::new(),
            material: String::new(),
            thickness_mm: 0.0,
            power_percent: 100.0,
            feedback_every: 10,
            frame_every_steps: 200,
            max_frames: 200,
            dxf_chord_tol_mm: dxf.chord_tol_mm,
            dxf_join_tol_mm: dxf.join_tol_mm,
            pierce_options: PierceOptions::default(),
            thermal: ThermalParams::default(),
            cost: CostParams::default(),
            result_timeout_s: 600.0,
            standard_views: true,
            data_dirs: cell_runtime::data_files::default_data_dirs(),
            max_file_mib: cell_runtime::data_files::DEFAULT_MAX_FILE_MIB,
        }
    }
}

/// The job a goal asks for and the toolpath options, or why it cannot run (one line naming
/// the field).
///
/// # Errors
/// An unknown precedence, pierce mode or policy, a negative time budget, a machine profile
/// that does not resolve, or no layout at all.
pub fn goal_to_job(
    goal: &SequenceSheetGoal,
    p: &SequencerParams,
) -> Result<(SheetJob, ToolpathOptions), String> {
    let or = |g: &str, d: &str| {
        if g.is_empty() {
            d.to_string()
        } else {
            g.to_string()
        }
    };
    let precedence = job::parse_precedence(&or(&goal.precedence, &p.precedence))?;
    let pierce = PierceMode::parse(&or(&goal.pierce, &p.pierce))?;
    let policy = job::parse_policy(&or(&goal.policy, &p.policy))?;
    let budget_s = if goal.time_budget_s == 0.0 {
        p.time_budget_s
    } else {
        goal.time_budget_s
    };
    if !(budget_s.is_finite() && budget_s >= 0.0) {
        return Err(format!("time_budget_s {budget_s}: must be finite and ≥ 0"));
    }
    let data_dirs = DataDirs::from_params(&p.data_dirs, p.max_file_mib);
    let layout = match (goal.layout_file.is_empty(), goal.layout_json.is_empty()) {
        (false, _) => LayoutSource::File(
            data_dirs
                .check(&goal.layout_file)
                .map_err(|e| format!("layout_file: {e}"))?,
        ),
        (true, false) => LayoutSource::Json(goal.layout_json.clone()),
        (true, true) => return Err("layout_file and layout_json are both empty".into()),
    };
    let machine = if goal.machine_profile.is_empty() {
        MachineProfile::resolve(&p.machine_profile).map_err(|e| format!("machine_profile: {e}"))?
    } else {
        data_dirs.machine_profile("machine_profile", &goal.machine_profile)?
    };
    let sheet_origin = match p.sheet_origin[..] {
        [] => None,
        [x, y] if x.is_finite() && y.is_finite() => Some([x, y]),
        _ => {
            return Err(format!(
                "sheet_origin {:?}: expected [x, y] in mm (finite) or empty",
                p.sheet_origin
            ))
        }
    };
    let material = (!p.material.is_empty()).then_some(p.material.as_str());
    let thickness = (p.thickness_mm != 0.0).then_some(p.thickness_mm);
    let cut = spec_for_profile(&machine, material, thickness)
        .map_err(|e| format!("material/thickness_mm: {e}"))?
        .map(|(spec, _)| spec);
    let job = SheetJob {
        cut,
        layout,
        dxf: DxfOptions {
            chord_tol_mm: p.dxf_chord_tol_mm,
            join_tol_mm: p.dxf_join_tol_mm,
            ..DxfOptions::default()
        },
        precedence,
        pierce,
        pierce_options: p.pierce_options,
        policy,
        improve: goal.improve,
        improve_params: ImproveParams {
            max_iterations: p.max_iterations,
            time_budget_ms: (budget_s * 1000.0).round() as u64,
            ..ImproveParams::default()
        },
        thermal: p.thermal.clone(),
        cost: p.cost.clone(),
        seed: goal.seed,
        sheet_origin,
        travel: Some(Travel::of(&machine)),
    };
    // Sizes over their limits (issue 23) reject the goal up front, naming the parameter.
    if job.improve {
        job.improve_params.validate().map_err(|e| e.to_string())?;
    }
    job.pierce_options.validate().map_err(|e| e.to_string())?;
    let opt = ToolpathOptions {
        cut_mm_s: p.thermal.cut_speed_mm_s.min(machine.max_feed_mm_s),
        rapid_mm_s: p.thermal.rapid_speed_mm_s.min(machine.max_feed_mm_s),
        power_percent: p.power_percent,
    };
    Ok((job, opt))
}

/// A raster frame as a `HeatMap` (seed 003 §A3): absolute temperature in °C, threshold
/// `t_max_c`, cell (0, 0) centred half a cell in from the sheet origin.
pub fn frame_to_heat_map(frame: &Frame, t_max_c: f32) -> HeatMap {
    let half = frame.cell_mm / 2.0;
    HeatMap {
        header: Header {
            stamp: cell_msgs::builtin_interfaces::Time::now(),
            frame_id: FRAME_ID.into(),
        },
        quantity: "sheet_temperature".into(),
        unit: "degC".into(),
        width: frame.width as u32,
        height: frame.height as u32,
        cell_width_mm: frame.cell_mm,
        cell_height_mm: frame.cell_mm,
        origin: Point {
            x: half,
            y: half,
            z: 0.0,
        },
        threshold: t_max_c,
        data: frame
            .excess_c
            .iter()
            .map(|&e| e + frame.ambient_c)
            .collect(),
    }
}

/// What the job thread reports to the node.
enum Update {
    Progress(JobProgress),
    Frame(u64, Box<HeatMap>),
}

fn log_result(
    node: &CellNode,
    out: &SheetOutcome,
    toolpath: &Toolpath,
    plan: &CutPlanMsg,
    message: &str,
) {
    let sink = node.rerun();
    sink.set_time(&toolpath.header.stamp, 0);
    sink.log_toolpath("/sheet/toolpath", toolpath);
    if let Some(rec) = sink.stream() {
        let (points, radii): (Vec<[f32; 3]>, Vec<f32>) = out
            .plan
            .cuts
            .iter()
            .zip(&out.per_cut)
            .filter(|(_, t)| t.pierce_overheats + t.segment_overheats > 0)
            .map(|(c, t)| {
                let p = out.problem.to_machine(c.point(&out.problem));
                let n = (t.pierce_overheats + t.segment_overheats) as f32;
                ([p[0] as f32, p[1] as f32, 0.0], 2.0 + n)
            })
            .unzip();
        if let Err(e) = rec.log(
            "/sheet/overheats",
            &rerun::Points3D::new(points)
                .with_radii(radii)
                .with_colors([rerun::Color::from_rgb(255, 40, 40)]),
        ) {
            tracing::warn!("rerun: {e}");
        }
    }
    sink.log_text(
        "/sheet/log",
        &format!(
            "{message} (max {:.0} °C above ambient)",
            plan.max_temperature_c
        ),
    );
}

/// The `sequence_sheet` goals: [`goal_to_job`] checks them, [`job::run_until`] runs them.
struct Sequencer {
    node: CellNode,
    p: SequencerParams,
    toolpaths: Publisher<Toolpath>,
    plans: Publisher<CutPlanMsg>,
    heat: Publisher<HeatMap>,
    toolpath_views: ToolpathViews,
    heat_image: HeatMapView,
}

impl GoalHandler for Sequencer {
    type Goal = SequenceSheetGoal;
    type Result = SequenceSheetResult;
    type Feedback = SequenceSheetFeedback;
    type Job = (SheetJob, ToolpathOptions);

    fn job_id(&self, goal: &SequenceSheetGoal, served: u64) -> String {
        if goal.job_id.is_empty() {
            format!("sheet-{served}")
        } else {
            goal.job_id.clone()
        }
    }

    fn validate(
        &self,
        goal: &SequenceSheetGoal,
        _job_id: &str,
    ) -> Result<(SheetJob, ToolpathOptions), String> {
        goal_to_job(goal, &self.p)
    }

    async fn run(
        &self,
        (sheet_job, opt): (SheetJob, ToolpathOptions),
        ctx: GoalContext<SequenceSheetFeedback>,
    ) -> anyhow::Result<GoalEnd<SequenceSheetResult>> {
        let job_id = ctx.job_id().to_owned();
        tracing::info!(
            "sequence_sheet: sequencing {job_id} (seed {})",
            sheet_job.seed
        );
        // A layout file's errors may quote it; the caller gets them blanked.
        let from_file = matches!(sheet_job.layout, LayoutSource::File(_));
        let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel();
        let (every, frame_every, max_frames, t_max) = (
            self.p.feedback_every.max(1),
            self.p.frame_every_steps.max(1),
            self.p.max_frames,
            self.p.thermal.t_max_c,
        );
        let sequencing = {
            let sheet_job = sheet_job.clone();
            ctx.run_blocking(move |ctx| {
                let mut frames = 0usize;
                let ftx = tx.clone();
                let mut on_frame = |f: &Frame| {
                    if frames < max_frames {
                        frames += 1;
                        let hm = frame_to_heat_map(f, t_max);
                        let _ = ftx.send(Update::Frame(f.step, Box::new(hm)));
                    }
                };
                let mut last = None;
                job::run_until(
                    &sheet_job,
                    |pr| {
                        let changed = last != Some(pr.phase);
                        last = Some(pr.phase);
                        if changed || pr.phase != Phase::Improvement || pr.iteration % every == 0 {
                            let _ = tx.send(Update::Progress(pr));
                        }
                    },
                    frame_every,
                    &mut on_frame,
                    // A cancel ends the improvement; the best plan so far is still simulated.
                    &|| ctx.is_canceled(),
                )
            })
        };
        let forwarding = async {
            while let Some(update) = rx.recv().await {
                match update {
                    Update::Progress(pr) => {
                        log_best_cost(&self.node, &pr);
                        ctx.feedback(SequenceSheetFeedback {
                            phase: pr.phase.name().into(),
                            iteration: pr.iteration as u32,
                            best_cost: pr.best_cost,
                            best_idle_length_mm: pr.best_idle_mm,
                            best_overheats: pr.best_overheats as u32,
                        });
                    }
                    Update::Frame(step, mut hm) => {
                        hm.header.stamp = self.node.now();
                        if let Some(rec) = self.node.rerun().stream() {
                            rec.set_time_sequence("sim_step", step as i64);
                            self.node.rerun().log_heat_map("/sheet/heat", &hm);
                            rec.disable_timeline("sim_step");
                        }
                        self.heat_image.publish(&hm).await;
                        // A lost frame is not worth the goal (or the node).
                        if let Err(e) = self.heat.publish(*hm).await {
                            tracing::warn!("sequence_sheet: heat frame {step}: {e:#}");
                        }
                    }
                }
            }
        };
        let (outcome, ()) = tokio::join!(sequencing, forwarding);
        let out = match outcome? {
            Ok(out) => out,
            Err(e) if from_file => return Ok(failed(&job_id, without_content(&e.to_string()))),
            Err(e) => return Ok(failed(&job_id, e.to_string())),
        };
        let mut toolpath = to_toolpath(&out.problem, &out.plan, &job_id, &opt);
        toolpath.header.stamp = self.node.now();
        let mut plan = with_cut(
            to_cut_plan_msg(
                &out.problem,
                &out.plan,
                &job_id,
                job::policy_name(sheet_job.policy),
                out.improved,
                sheet_job.thermal.ambient_c,
            ),
            out.cut.as_ref(),
        );
        plan.header.stamp = toolpath.header.stamp;
        let canceled = ctx.is_canceled();
        if !canceled {
            self.toolpaths.publish(toolpath.clone()).await?;
            self.toolpath_views.publish(&toolpath).await;
            self.plans.publish(plan.clone()).await?;
        }
        let message = format!(
            "sequenced {job_id}: {} contours, {}{}, idle {:.1} mm, cut {:.1} mm, \
             {} overheats, cost {:.1} ({:.1} s); {}",
            out.problem.contours.len(),
            plan.policy,
            if out.improved { " + improvement" } else { "" },
            plan.idle_length_mm,
            plan.cut_length_mm,
            plan.overheats,
            plan.cost,
            out.seconds,
            out.sheet
        );
        // The kerf and leads it was cut with, and what it could not cut as drawn.
        let message = match &out.cut {
            Some(c) => {
                for w in &c.warnings {
                    tracing::warn!("sequence_sheet: {job_id}: {w}");
                }
                format!(
                    "{message}; kerf {} mm ({:?}), lead-in {} mm, lead-out {} mm, {} warnings \
                     (holes left out, features narrower than the kerf)",
                    c.kerf_mm,
                    c.compensation,
                    c.lead_in_mm,
                    c.lead_out_mm,
                    c.warnings.len()
                )
            }
            None => message,
        };
        log_result(&self.node, &out, &toolpath, &plan, &message);
        let message = if canceled {
            format!("canceled; best plan so far: {message}")
        } else {
            message
        };
        tracing::info!("sequence_sheet: {message}");
        let result = SequenceSheetResult {
            success: !canceled,
            message,
            plan,
            toolpath,
        };
        Ok(if canceled {
            GoalEnd::canceled(result)
        } else {
            GoalEnd::succeeded(result)
        })
    }
}

/// Logs the improvement's best cost on the `iteration` timeline.
fn log_best_cost(node: &CellNode, pr: &JobProgress) {
    if let Some(rec) = node.rerun().stream() {
        if pr.phase == Phase::Improvement {
            rec.set_time_sequence("iteration", pr.iteration as i64);
            if let Err(e) = rec.log("/sheet/best_cost", &rerun::Scalars::single(pr.best_cost)) {
                tracing::warn!("rerun: {e}");
            }
            rec.disable_timeline("iteration");
        }
    }
}

/// Serves `sequence_sheet` until shutdown.
pub async fn run(node: CellNode, p: SequencerParams) -> anyhow::Result<()> {
    let toolpaths = node.publisher::<Toolpath>("toolpath", QosPreset::Plan)?;
    let heat = node.publisher::<HeatMap>("sheet_heat", QosPreset::Stream)?;
    let sequencer = Sequencer {
        toolpath_views: ToolpathViews::new(&node, &toolpaths, p.standard_views)?,
        heat_image: HeatMapView::new(&node, &heat, p.standard_views)?,
        toolpaths,
        plans: node.publisher::<CutPlanMsg>("cut_plan", QosPreset::Plan)?,
        heat,
        node: node.clone(),
        p: p.clone(),
    };
    tracing::info!(
        "serving {} (policy {}, {} precedence, {} pierce, {} s improvement by default)",
        node.resolve_topic("sequence_sheet"),
        p.policy,
        p.precedence,
        p.pierce,
        p.time_budget_s
    );
    let options = ServeOptions::one_at_a_time(p.result_timeout_s);
    goal_server::serve(node, "sequence_sheet", sequencer, options).await
}

fn failed(job_id: &str, e: String) -> GoalEnd<SequenceSheetResult> {
    let message = format!("{job_id}: {e}");
    tracing::warn!("sequence_sheet: failed: {message}");
    GoalEnd::aborted(SequenceSheetResult {
        success: false,
        message,
        ..Default::default()
    })
}

/// The `sequencer` binary (also `cell node sequencer`).
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("sequencer", argv, run)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_params_file_parses_and_matches_the_defaults() {
        let mut sources = cell_runtime::params::ParamSources::default();
        let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/sequencer.yaml");
        sources
            .merge_file(std::path::Path::new(file), "/", "sequencer")
            .unwrap();
        let p: SequencerParams = sources.parse().unwrap();
        assert_eq!(p, SequencerParams::default());
    }

    #[test]
    fn parameters_over_their_limits_reject_the_goal() {
        let goal = SequenceSheetGoal {
            layout_json: "{}".into(),
            improve: true,
            ..Default::default()
        };
        let at = SequencerParams {
            max_iterations: cell_sequencer::improve::MAX_IMPROVE_ITERATIONS,
            ..SequencerParams::default()
        };
        assert!(goal_to_job(&goal, &at).is_ok());
        let over = SequencerParams {
            max_iterations: at.max_iterations + 1,
            ..at.clone()
        };
        let e = goal_to_job(&goal, &over).unwrap_err();
        assert_eq!(
            e,
            "parameter `max_iterations` = 100001: must be in [0, 100000] (MAX_IMPROVE_ITERATIONS)"
        );
        let mut pierce = SequencerParams::default();
        pierce.pierce_options.max_candidates = 1000;
        let e = goal_to_job(&goal, &pierce).unwrap_err();
        assert!(e.ends_with("(MAX_PIERCE_CANDIDATES)"), "{e}");
    }

    #[test]
    fn goals_map_to_jobs_and_bad_ones_are_named() {
        let p = SequencerParams::default();
        let goal = SequenceSheetGoal {
            layout_json: "{}".into(),
            ..Default::default()
        };
        let (job, opt) = goal_to_job(&goal, &p).unwrap();
        assert_eq!(job.policy, cell_sequencer::policy::Policy::Nearest);
        assert!(!job.improve);
        assert_eq!(job.improve_params.time_budget_ms, 5000);
        assert_eq!(opt.cut_mm_s, p.thermal.cut_speed_mm_s);
        // linuxcnc-plasma's feed limit (150 mm/s) caps the rapid.
        assert_eq!(opt.rapid_mm_s, 150.0);
        let bad = |g: SequenceSheetGoal, word: &str| {
            let e = goal_to_job(&g, &p).unwrap_err();
            assert!(e.contains(word), "{e}");
        };
        bad(
            SequenceSheetGoal {
                policy: "fastest".into(),
                ..goal.clone()
            },
            "fastest",
        );
        bad(
            SequenceSheetGoal {
                precedence: "loose".into(),
                ..goal.clone()
            },
            "loose",
        );
        bad(
            SequenceSheetGoal {
                machine_profile: "mill_9000".into(),
                ..goal.clone()
            },
            "mill_9000",
        );
        bad(SequenceSheetGoal::default(), "layout_file");
    }

    #[test]
    fn sheet_origin_and_the_profiles_travel_reach_the_job() {
        let goal = SequenceSheetGoal {
            layout_json: "{}".into(),
            ..Default::default()
        };
        let (job, _) = goal_to_job(&goal, &SequencerParams::default()).unwrap();
        assert_eq!(job.sheet_origin, None, "empty: the drawing's own placement");
        let travel = job.travel.expect("the profile's travel is checked");
        assert_eq!(
            (travel.x_mm, travel.y_mm),
            (Some([0.0, 1250.0]), Some([0.0, 1250.0]))
        );
        let p = SequencerParams {
            sheet_origin: vec![100.0, -50.0],
            ..Default::default()
        };
        assert_eq!(
            goal_to_job(&goal, &p).unwrap().0.sheet_origin,
            Some([100.0, -50.0])
        );
        for bad in [vec![1.0], vec![1.0, 2.0, 3.0], vec![f64::NAN, 0.0]] {
            let p = SequencerParams {
                sheet_origin: bad,
                ..Default::default()
            };
            let e = goal_to_job(&goal, &p).unwrap_err();
            assert!(e.starts_with("sheet_origin ["), "{e}");
        }
    }

    /// `-p cost.thermal:=false` (the thermal-off mode) reaches the job.
    #[test]
    fn thermal_off_reaches_the_job() {
        let args = cell_runtime::args::NodeArgs::parse(["--ros-args", "-p", "cost.thermal:=false"])
            .unwrap();
        let p: SequencerParams =
            cell_runtime::params::ParamSources::collect(&args.ros, "/", "sequencer")
                .unwrap()
                .parse()
                .unwrap();
        let goal = SequenceSheetGoal {
            layout_json: "{}".into(),
            ..Default::default()
        };
        let (job, _) = goal_to_job(&goal, &p).unwrap();
        assert!(!job.cost.thermal);
        let (default_job, _) = goal_to_job(&goal, &SequencerParams::default()).unwrap();
        assert!(default_job.cost.thermal);
    }

    #[test]
    fn frames_become_heat_maps_in_absolute_degrees() {
        let data = [0.0f32, 10.0, 280.0, 0.0, 0.0, 0.0];
        let f = Frame {
            step: 3,
            time_s: 0.3,
            width: 3,
            height: 2,
            cell_mm: 4.0,
            ambient_c: 20.0,
            excess_c: &data,
        };
        let hm = frame_to_heat_map(&f, 300.0);
        assert_eq!((hm.width, hm.height), (3, 2));
        assert_eq!(hm.data[2], 300.0);
        assert_eq!(hm.origin.x, 2.0);
        assert_eq!(hm.threshold, 300.0);
    }

    /// The profile's `cutting:` section reaches the job: its default material, or the
    /// `material` / `thickness_mm` parameters; a material its kerf table lacks is named.
    #[test]
    fn material_and_thickness_pick_the_kerf() {
        let goal = SequenceSheetGoal {
            layout_json: "{}".into(),
            ..Default::default()
        };
        let (job, _) = goal_to_job(&goal, &SequencerParams::default()).unwrap();
        let cut = job.cut.expect("linuxcnc-plasma has a cutting: section");
        assert_eq!(cut.kerf_mm, 1.5, "its default: mild steel, 6 mm");
        let p = SequencerParams {
            material: "mild_steel".into(),
            thickness_mm: 3.0,
            ..Default::default()
        };
        let (job, _) = goal_to_job(&goal, &p).unwrap();
        assert!(job.cut.unwrap().kerf_mm < 1.5);
        let p = SequencerParams {
            material: "unobtainium".into(),
            ..Default::default()
        };
        let e = goal_to_job(&goal, &p).unwrap_err();
        assert!(
            e.starts_with("material/thickness_mm:") && e.contains("unobtainium"),
            "{e}"
        );
    }
}
