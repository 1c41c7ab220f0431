//! The `slicer` node: serves the `slice` action (`cell_msgs/action/Slice`), a thin adapter
//! around [`cell_slicer::job::run`] (seed 004; issue 8).
//!
//! Goals go through [`cell_runtime::goal_server`]. Per goal: build a [`SliceJob`] from the goal
//! and the parameters (empty or zero goal fields take the parameters' values; a goal that does
//! not make one, e.g. neither or both part files, an unknown machine, a process profile that
//! cannot be read or a bad layer height, is rejected), accept it, run it on a blocking thread,
//! and send feedback (phase, layers done, layers total) at every phase change and after every
//! planned layer. Then the `Toolpath` is published on `toolpath` and the `LayerStack` on
//! `layer_stack` (Plan QoS), every layer is logged to Rerun and the result carries both plus the
//! report as JSON. A goal that fails (an unreadable, empty, truncated or NaN mesh, a wing spec
//! that cannot be read, a section beyond the design's or one that does not fit the wing
//! machine) ends as aborted with `success = false` and a message naming the file or field; the
//! node keeps serving. Mesh defects (holes, non-manifold edges, open chains) are warnings:
//! logged, put into the report, and the job goes on. Goals run one at a time, in arrival order.
//! A cancel request for the running goal is accepted: the job stops after its current layer,
//! the goal ends as canceled and nothing is published.
//!
//! A goal's `stl_file`, `wing_spec_file`, `process_file` and a `machine_profile` that is a
//! path must be regular files under `data_dirs` within `max_file_mib`
//! ([`cell_runtime::data_files`]); a refusal, or a file that does not parse, never quotes the
//! file (a failed goal's message has its quoted values blanked).
//!
//! Rerun entities (the suite's `/waam/…` tree), over the `layer` timeline (one step per layer):
//! `/waam/layers/contours` (the layer's closed contours as line strips: outer contours blue, holes
//! red), `/waam/layers/beads` (the deposit pieces as line strips, radius half the bead width, coloured
//! by bead width from blue (narrowest) to red (widest)), `/waam/layers/travel` (travel moves, grey);
//! without the timeline `/waam/toolpath` (the whole toolpath, deposit vs travel, as every node
//! logs toolpaths), `/waam/stock` (the stock model, seed 004 §4.8, as a mesh) and `/waam/log`.
//!
//! **Wing goals** (`wing_spec_file`, seed 002): the wing is designed and section `wing_section`
//! printed by [`cell_slicer::wing::run_wing`] (feedback per layer); the toolpath carries extrusion flow
//! for the emitter's Marlin profile, the stack one perimeter per layer. Every point must lie in
//! the travel of the goal's machine (default `wing_machine_profile`). Rerun: `/wing/layers/
//! perimeter`, `/wing/layers/spars`, `/wing/layers/rib` on the `layer` timeline, `/wing/toolpath`
//! and `/wing/log`.

use cell_msgs::{LayerStack, SliceFeedback, SliceGoal, SliceResult, Toolpath};
use cell_profiles::MachineProfile;
use cell_runtime::data_files::{self, without_content, DataDirs};
use cell_runtime::goal_server::{self, GoalContext, GoalEnd, GoalHandler, ServeOptions};
use cell_runtime::views::ToolpathViews;
use cell_runtime::{CellNode, Publisher, QosPreset};
use cell_waam::{LayerToolpath, SegmentKind, WaamProcess};
use serde::{Deserialize, Serialize};

use cell_slicer::job::{self, JobProgress, PartSource, Placement, SliceJob, SliceOutcome};
use cell_slicer::to_msg::layer_stack_msg;

/// Frame of the toolpath and the layer stack: the build plate's work object.
pub const FRAME_ID: &str = "work";

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`). Defaults in
/// `config/slicer.yaml`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SlicerParams {
    /// Machine profile when a goal's is empty: a name under `config/machines` or a YAML path.
    /// Its X/Y travel centres the part on the plate; its feed limit caps the speeds.
    pub machine_profile: String,
    /// Process profile when a goal's is empty: a YAML path, or empty / `waam` for the built-in
    /// `config/processes/waam.yaml`.
    pub process_file: String,
    /// Put the part on the plate (bounding-box bottom at z = 0, XY centre at the centre of the
    /// machine's X/Y travel); false keeps the file's coordinates.
    pub place_on_plate: bool,
    /// Log the stock model (every bead piece as a box) to Rerun as a mesh.
    pub log_stock_mesh: bool,
    /// How long a finished goal's result waits for the client to ask for it, s.
    pub result_timeout_s: f64,
    /// Machine profile of wing goals (seed 002) whose `machine_profile` is empty: every point
    /// of the section must lie within its travel.
    pub wing_machine_profile: String,
    /// Print only the first N layers of a wing goal's section (0: all): a short print of the
    /// section's base, as `cell wing --layers` (the demo's wing job).
    pub wing_max_layers: u32,
    /// Also publish the standard-type views for RViz and Foxglove (default true): the
    /// toolpath on `toolpath/path` (`nav_msgs/Path`) and `toolpath/markers`
    /// (`visualization_msgs/MarkerArray`, one marker per layer); see `cell_runtime::views`.
    pub standard_views: bool,
    /// Directories a goal's STL, wing spec, process or machine profile path must lie in
    /// (relative: to the working directory); see `cell_runtime::data_files`.
    pub data_dirs: Vec<String>,
    /// Largest file a goal may name, MiB.
    pub max_file_mib: u64,
}

impl Default for SlicerParams {
    fn default() -> Self {
        SlicerParams {
            machine_profile: "abb-irb2600-waam".into(),
            process_file: String::new(),
            place_on_plate: true,
            log_stock_mesh: true,
            result_timeout_s: 600.0,
            wing_machine_profile: "marlin-extruder".into(),
            wing_max_layers: 0,
            standard_views: true,
            data_dirs: data_files::default_data_dirs(),
            max_file_mib: data_files::DEFAULT_MAX_FILE_MIB,
        }
    }
}

/// The placement for a machine: the centre of its X/Y travel, or the file's coordinates when
/// `on_plate` is false or the profile has no X/Y axes.
pub fn placement_for(machine: &MachineProfile, on_plate: bool) -> Placement {
    match (on_plate, machine.axes.get(&'X'), machine.axes.get(&'Y')) {
        (true, Some(x), Some(y)) => Placement::OnPlate {
            centre_xy_mm: [0.5 * (x[0] + x[1]), 0.5 * (y[0] + y[1])],
        },
        _ => Placement::AsIs,
    }
}

/// Caps every point's speed at the machine's feed limit (travel moves at 50 mm/s, deposits at
/// a few mm/s: only a slow machine changes anything). Returns how many points were capped.
pub fn cap_speeds(layers: &mut [LayerToolpath], max_mm_s: f64) -> usize {
    let mut n = 0;
    for p in layers
        .iter_mut()
        .flat_map(|l| &mut l.segments)
        .flat_map(|s| &mut s.points)
    {
        if p.speed_mm_s > max_mm_s {
            p.speed_mm_s = max_mm_s;
            n += 1;
        }
    }
    n
}

/// The job a goal asks for and its machine, or why it cannot run (one line naming the field
/// or file).
///
/// # Errors
/// Neither or both of `stl_file` and `wing_spec_file`, a machine profile that does not
/// resolve, a process profile that cannot be read, a negative or non-finite layer height.
pub fn goal_to_job(
    goal: &SliceGoal,
    p: &SlicerParams,
) -> Result<(SliceJob, MachineProfile), String> {
    let data_dirs = DataDirs::from_params(&p.data_dirs, p.max_file_mib);
    let checked =
        |field: &str, name: &str| data_dirs.check(name).map_err(|e| format!("{field}: {e}"));
    let part = match (goal.stl_file.is_empty(), goal.wing_spec_file.is_empty()) {
        (false, true) => PartSource::Stl(checked("stl_file", &goal.stl_file)?),
        (true, false) => PartSource::WingSpec {
            file: checked("wing_spec_file", &goal.wing_spec_file)?,
            section: goal.wing_section as usize,
        },
        (true, true) => return Err("stl_file and wing_spec_file are both empty".into()),
        (false, false) => return Err("give stl_file or wing_spec_file, not both".into()),
    };
    let machine = match (goal.machine_profile.is_empty(), &part) {
        (false, _) => data_dirs.machine_profile("machine_profile", &goal.machine_profile)?,
        (true, PartSource::WingSpec { .. }) => MachineProfile::resolve(&p.wing_machine_profile)
            .map_err(|e| format!("machine_profile: {e}"))?,
        (true, PartSource::Stl(_)) => MachineProfile::resolve(&p.machine_profile)
            .map_err(|e| format!("machine_profile: {e}"))?,
    };
    let (process, process_name) = match goal.process_file.as_str() {
        "" => job::load_process(&p.process_file).map_err(|e| e.to_string())?,
        "waam" => job::load_process("waam").map_err(|e| e.to_string())?,
        named => {
            let field = |e: &dyn std::fmt::Display| format!("process_file: {e}");
            let file = data_dirs.read(named).map_err(|e| field(&e))?;
            let text = file.text().map_err(|e| field(&e))?;
            let process = WaamProcess::from_yaml_str(text, named)
                .map_err(|e| field(&without_content(&e.to_string())))?;
            (process, named.to_owned())
        }
    };
    let h = goal.layer_height_mm;
    if !(h.is_finite() && h >= 0.0) {
        return Err(format!(
            "layer_height_mm {h}: must be finite and ≥ 0 (0 = the profile's)"
        ));
    }
    let job = SliceJob {
        part,
        process,
        process_name,
        layer_height_mm: (h > 0.0).then_some(h),
        placement: placement_for(&machine, p.place_on_plate),
    };
    Ok((job, machine))
}

/// A colour from blue (t = 0) through green to red (t = 1).
fn ramp(t: f64) -> rerun::Color {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (r, g, b) = if t < 0.5 {
        let u = t * 2.0;
        (0.0, u, 1.0 - u)
    } else {
        let u = (t - 0.5) * 2.0;
        (u, 1.0 - u, 0.0)
    };
    rerun::Color::from_rgb((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8)
}

/// Logs one layer: contours, bead pieces coloured by width, travel moves (module docs).
fn log_layer(
    rec: &rerun::RecordingStream,
    layer: &cell_mesh::Layer,
    tp: &LayerToolpath,
    width_range_mm: [f64; 2],
) -> Result<(), rerun::RecordingStreamError> {
    rec.set_time_sequence("layer", layer.index as i64);
    let z = layer.z_mm as f32;
    let (strips, colors): (Vec<Vec<[f32; 3]>>, Vec<rerun::Color>) = layer
        .contours
        .iter()
        .map(|c| {
            let mut s: Vec<[f32; 3]> = c
                .points
                .iter()
                .map(|p| [p[0] as f32, p[1] as f32, z])
                .collect();
            s.push(s[0]);
            let color = if c.is_hole {
                rerun::Color::from_rgb(220, 60, 60)
            } else {
                rerun::Color::from_rgb(60, 120, 230)
            };
            (s, color)
        })
        .unzip();
    rec.log(
        "/waam/layers/contours",
        &rerun::LineStrips3D::new(strips).with_colors(colors),
    )?;
    let [lo, hi] = width_range_mm;
    let span = if hi > lo { hi - lo } else { 1.0 };
    let mut beads = Vec::new();
    let mut bead_colors = Vec::new();
    let mut radii = Vec::new();
    let mut travel = Vec::new();
    for s in &tp.segments {
        let pts = |a: &cell_waam::PathPoint| [a.x_mm as f32, a.y_mm as f32, a.z_mm as f32];
        match s.kind {
            SegmentKind::Deposit => {
                for w in s.points.windows(2) {
                    beads.push(vec![pts(&w[0]), pts(&w[1])]);
                    bead_colors.push(ramp((w[0].bead_width_mm - lo) / span));
                    radii.push((w[0].bead_width_mm / 2.0) as f32);
                }
            }
            SegmentKind::Travel => travel.push(s.points.iter().map(pts).collect::<Vec<_>>()),
        }
    }
    rec.log(
        "/waam/layers/beads",
        &rerun::LineStrips3D::new(beads)
            .with_colors(bead_colors)
            .with_radii(radii),
    )?;
    rec.log(
        "/waam/layers/travel",
        &rerun::LineStrips3D::new(travel).with_colors([rerun::Color::from_rgb(150, 150, 150)]),
    )?;
    rec.disable_timeline("layer");
    Ok(())
}

/// Logs the whole outcome: every layer, the stock mesh (if asked) and a summary line.
fn log_outcome(
    node: &CellNode,
    out: &SliceOutcome,
    toolpath: &Toolpath,
    log_stock: bool,
    message: &str,
) {
    let sink = node.rerun();
    sink.set_time(&toolpath.header.stamp, 0);
    sink.log_toolpath("/waam/toolpath", toolpath);
    if let Some(rec) = sink.stream() {
        let range = out.report.bead_width_range_mm;
        let mut result = Ok(());
        for (layer, tp) in out.stack.layers.iter().zip(&out.layers) {
            result = result.and(log_layer(rec, layer, tp, range));
        }
        if log_stock {
            let tris =
                cell_waam::stock::stock_triangles(&cell_waam::stock::bead_boxes(&out.layers));
            let positions: Vec<[f32; 3]> = tris
                .iter()
                .flat_map(|t| t.vertices.iter().map(|v| [v[0], v[1], v[2]]))
                .collect();
            let normals: Vec<[f32; 3]> = tris
                .iter()
                .flat_map(|t| std::iter::repeat_n([t.normal[0], t.normal[1], t.normal[2]], 3))
                .collect();
            result = result.and(
                rec.log(
                    "/waam/stock",
                    &rerun::Mesh3D::new(positions)
                        .with_vertex_normals(normals)
                        .with_albedo_factor(rerun::datatypes::Rgba32::from_rgb(180, 180, 190)),
                ),
            );
        }
        if let Err(e) = result {
            tracing::warn!("rerun: {e}");
        }
    }
    for w in &out.report.warnings {
        sink.log_text("/waam/log", &format!("warning: {w}"));
    }
    sink.log_text("/waam/log", message);
}

fn feedback(pr: JobProgress) -> SliceFeedback {
    SliceFeedback {
        phase: pr.phase.name().into(),
        layers_done: pr.layers_done as u32,
        layers_total: pr.layers_total as u32,
    }
}

/// The `slice` goals: [`goal_to_job`] checks them, [`job::run_until`] or
/// [`cell_slicer::wing::run_wing_until`] runs them.
struct Slicer {
    node: CellNode,
    p: SlicerParams,
    toolpaths: Publisher<Toolpath>,
    stacks: Publisher<LayerStack>,
    toolpath_views: ToolpathViews,
}

/// A finished goal: what to publish and answer, or why there is nothing.
type Served = Result<(Toolpath, LayerStack, SliceResult), Unserved>;

/// Why a goal ended without a product.
enum Unserved {
    /// Its client canceled it; where it stopped.
    Canceled(String),
    /// It failed; why (one line naming the file or field).
    Failed(String),
}

impl From<job::JobError> for Unserved {
    fn from(e: job::JobError) -> Self {
        match e {
            // Only the goal's cancel stops a job.
            job::JobError::Cancelled { .. } => Unserved::Canceled(e.to_string()),
            e => Unserved::Failed(e.to_string()),
        }
    }
}

impl GoalHandler for Slicer {
    type Goal = SliceGoal;
    type Result = SliceResult;
    type Feedback = SliceFeedback;
    type Job = (SliceJob, MachineProfile);

    fn job_id(&self, goal: &SliceGoal, served: u64) -> String {
        if goal.job_id.is_empty() {
            format!("slice-{served}")
        } else {
            goal.job_id.clone()
        }
    }

    fn validate(
        &self,
        goal: &SliceGoal,
        _job_id: &str,
    ) -> Result<(SliceJob, MachineProfile), String> {
        goal_to_job(goal, &self.p)
    }

    async fn run(
        &self,
        (slice_job, machine): (SliceJob, MachineProfile),
        ctx: GoalContext<SliceFeedback>,
    ) -> anyhow::Result<GoalEnd<SliceResult>> {
        let job_id = ctx.job_id().to_owned();
        tracing::info!("slice: {job_id} ({:?})", slice_job.part);
        let done = match slice_job.part.clone() {
            PartSource::WingSpec { file, section } => {
                let max_layers = self.p.wing_max_layers as usize;
                serve_wing(&self.node, &ctx, (file, section, max_layers), &machine).await?
            }
            PartSource::Stl(_) => {
                serve_mesh(&self.node, &ctx, slice_job, &machine, self.p.log_stock_mesh).await?
            }
        };
        Ok(match done {
            Ok((toolpath, stack, result)) => {
                self.toolpath_views.publish(&toolpath).await;
                self.toolpaths.publish(toolpath).await?;
                self.stacks.publish(stack).await?;
                GoalEnd::succeeded(result)
            }
            Err(Unserved::Canceled(e)) => {
                let message = format!("{job_id}: {e} at the client's request");
                tracing::info!("slice: {message}");
                GoalEnd::canceled(SliceResult {
                    success: false,
                    message,
                    ..Default::default()
                })
            }
            // The part's reader may quote the file: blanked for the caller.
            Err(Unserved::Failed(e)) => failed(&job_id, without_content(&e)),
        })
    }
}

/// Serves `slice` until shutdown.
pub async fn run(node: CellNode, p: SlicerParams) -> anyhow::Result<()> {
    let toolpaths = node.publisher::<Toolpath>("toolpath", QosPreset::Plan)?;
    let slicer = Slicer {
        toolpath_views: ToolpathViews::new(&node, &toolpaths, p.standard_views)?,
        toolpaths,
        stacks: node.publisher::<LayerStack>("layer_stack", QosPreset::Plan)?,
        node: node.clone(),
        p: p.clone(),
    };
    tracing::info!(
        "serving {} (machine {}, process {})",
        node.resolve_topic("slice"),
        p.machine_profile,
        if p.process_file.is_empty() {
            job::BUILTIN_PROCESS_NAME
        } else {
            &p.process_file
        }
    );
    let options = ServeOptions::one_at_a_time(p.result_timeout_s);
    goal_server::serve(node, "slice", slicer, options).await
}

/// The WAAM path: slice the mesh, plan the beads (seed 004).
async fn serve_mesh(
    node: &CellNode,
    ctx: &GoalContext<SliceFeedback>,
    slice_job: SliceJob,
    machine: &MachineProfile,
    log_stock: bool,
) -> anyhow::Result<Served> {
    let job_id = ctx.job_id();
    let torch = slice_job.process.torch;
    let outcome = ctx
        .run_blocking(move |ctx| {
            job::run_until(&slice_job, |pr| ctx.feedback(feedback(pr)), &|| {
                ctx.is_canceled()
            })
        })
        .await?;
    let mut out = match outcome {
        Ok(out) => out,
        Err(e) => return Ok(Err(e.into())),
    };
    let capped = cap_speeds(&mut out.layers, machine.max_feed_mm_s);
    if capped > 0 {
        out.report.warnings.push(format!(
            "{capped} points slowed to the machine's {} mm/s",
            machine.max_feed_mm_s
        ));
    }
    let mut toolpath = cell_waam::to_msg::toolpath_msg_for(
        &out.layers,
        &torch,
        out.report.layer_height_mm,
        job_id,
        FRAME_ID,
    );
    toolpath.header.stamp = node.now();
    let stack = layer_stack_msg(&out.stack, job_id, FRAME_ID);
    for w in &out.report.warnings {
        tracing::warn!("slice: {job_id}: {w}");
    }
    let r = &out.report;
    let message = format!(
        "sliced {job_id}: {} layers, {} contours, {:.0} mm³ deposited, \
         {:.0} s arc on + {:.0} s travel, {:.0} SEK{}",
        r.layers,
        r.contours,
        r.deposited_volume_mm3,
        r.deposition_time_s,
        r.travel_time_s,
        r.cost.total_sek,
        if r.warnings.is_empty() {
            String::new()
        } else {
            format!(" ({} warnings)", r.warnings.len())
        }
    );
    log_outcome(node, &out, &toolpath, log_stock, &message);
    Ok(Ok(succeeded(message, stack, toolpath, &out.report)))
}

/// The wing path: design the wing, print one section (seed 002).
async fn serve_wing(
    node: &CellNode,
    ctx: &GoalContext<SliceFeedback>,
    (file, section, max_layers): (std::path::PathBuf, usize, usize),
    machine: &MachineProfile,
) -> anyhow::Result<Served> {
    let job_id = ctx.job_id().to_string();
    let id = job_id.clone();
    let outcome = ctx
        .run_blocking(move |ctx| {
            cell_slicer::wing::run_wing_layers(
                &file,
                section,
                max_layers,
                &id,
                FRAME_ID,
                |pr| ctx.feedback(feedback(pr)),
                &|| ctx.is_canceled(),
            )
        })
        .await?;
    let out = match outcome {
        Ok(out) => out,
        Err(e) => return Ok(Err(e.into())),
    };
    // The section must fit the printer (the emitter would refuse the program otherwise).
    for (si, seg) in out.toolpath.segments.iter().enumerate() {
        for q in &seg.points {
            if let Err(v) = machine.check_position(&[('X', q.x), ('Y', q.y), ('Z', q.z)]) {
                return Ok(Err(Unserved::Failed(format!(
                    "wing section {section} does not fit {}: segment {si}: {v}",
                    machine.name
                ))));
            }
        }
    }
    let mut toolpath = out.toolpath.clone();
    let now = node.now();
    toolpath.header.stamp = now;
    let mut stack = out.stack.clone();
    stack.header.stamp = now;
    let f = &out.report.section;
    let layers = if f.layers < out.report.layers_in_section {
        format!(
            "the first {} of {} layers",
            f.layers, out.report.layers_in_section
        )
    } else {
        format!("{} layers", f.layers)
    };
    let message = format!(
        "printed {job_id}: wing section {section} ({} {}), {layers}, {:.1} g, {:.0} min \
         (c_L {:.3})",
        f.side,
        f.position,
        f.mass_g,
        f.build_time_s / 60.0,
        out.report.c_l
    );
    log_wing(node, &out, &toolpath, &message);
    Ok(Ok(succeeded(message, stack, toolpath, &out.report)))
}

/// A finished goal: the summary logged, the result carrying the stack, the toolpath and the
/// report as JSON.
fn succeeded(
    message: String,
    stack: LayerStack,
    toolpath: Toolpath,
    report: &impl Serialize,
) -> (Toolpath, LayerStack, SliceResult) {
    tracing::info!("slice: {message}");
    let report_json =
        serde_json::to_string(report).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
    let result = SliceResult {
        success: true,
        message,
        layer_stack: stack.clone(),
        toolpath: toolpath.clone(),
        report_json,
    };
    (toolpath, stack, result)
}

/// Logs a wing section: per layer (on the `layer` timeline) the perimeter, the spars and the
/// rib in their own colours; the whole toolpath; a summary line.
fn log_wing(
    node: &CellNode,
    out: &cell_slicer::wing::WingOutcome,
    toolpath: &Toolpath,
    message: &str,
) {
    use cell_wing::layers::Role;
    let sink = node.rerun();
    sink.set_time(&toolpath.header.stamp, 0);
    sink.log_toolpath("/wing/toolpath", toolpath);
    if let Some(rec) = sink.stream() {
        let mut result = Ok(());
        for layer in &out.layers {
            rec.set_time_sequence("layer", i64::from(layer.index));
            for (role, path, color) in [
                (Role::Perimeter, "/wing/layers/perimeter", (60, 120, 230)),
                (Role::Spar, "/wing/layers/spars", (230, 140, 40)),
                (Role::Rib, "/wing/layers/rib", (90, 180, 90)),
            ] {
                let strips: Vec<Vec<[f32; 3]>> = layer
                    .strokes
                    .iter()
                    .filter(|s| s.role == role)
                    .map(|s| {
                        s.points
                            .iter()
                            .map(|q| [q[0] as f32, q[1] as f32, q[2] as f32])
                            .collect()
                    })
                    .collect();
                result = result.and(
                    rec.log(
                        path,
                        &rerun::LineStrips3D::new(strips)
                            .with_colors([rerun::Color::from_rgb(color.0, color.1, color.2)]),
                    ),
                );
            }
        }
        rec.disable_timeline("layer");
        if let Err(e) = result {
            tracing::warn!("rerun: {e}");
        }
    }
    sink.log_text("/wing/log", message);
}

fn failed(job_id: &str, e: String) -> GoalEnd<SliceResult> {
    let message = format!("{job_id}: {e}");
    tracing::warn!("slice: failed: {message}");
    GoalEnd::aborted(SliceResult {
        success: false,
        message,
        ..Default::default()
    })
}

/// The `slicer` binary (also `cell node slicer`).
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("slicer", argv, run)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_params_file_parses_and_matches_the_defaults() {
        let mut sources = cell_runtime::params::ParamSources::default();
        let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/slicer.yaml");
        sources
            .merge_file(std::path::Path::new(file), "/", "slicer")
            .unwrap();
        let p: SlicerParams = sources.parse().unwrap();
        assert_eq!(p, SlicerParams::default());
    }

    #[test]
    fn goals_map_to_jobs_and_bad_ones_are_named() {
        let p = SlicerParams {
            data_dirs: vec![concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data").into()],
            ..SlicerParams::default()
        };
        let goal = SliceGoal {
            stl_file: "stl/20mm-xyz-cube.stl".into(),
            ..Default::default()
        };
        let (job, machine) = goal_to_job(&goal, &p).unwrap();
        assert_eq!(machine.name, "abb-irb2600-waam");
        assert_eq!(job.layer_height_mm, None);
        // abb-irb2600-waam's build volume is 600 × 400 mm.
        assert_eq!(
            job.placement,
            Placement::OnPlate {
                centre_xy_mm: [300.0, 200.0]
            }
        );
        let bad = |g: SliceGoal, word: &str| {
            let e = goal_to_job(&g, &p).unwrap_err();
            assert!(e.contains(word), "{e}");
        };
        bad(SliceGoal::default(), "stl_file");
        bad(
            SliceGoal {
                machine_profile: "mill_9000".into(),
                ..goal.clone()
            },
            "mill_9000",
        );
        bad(
            SliceGoal {
                process_file: "/nonexistent/waam.yaml".into(),
                ..goal.clone()
            },
            "/nonexistent/waam.yaml",
        );
        bad(
            SliceGoal {
                stl_file: "/etc/passwd".into(),
                ..goal.clone()
            },
            "stl_file: /etc/passwd: outside",
        );
        bad(
            SliceGoal {
                layer_height_mm: -1.0,
                ..goal.clone()
            },
            "layer_height_mm",
        );
    }

    #[test]
    fn the_width_ramp_runs_blue_to_red() {
        assert_eq!(ramp(0.0), rerun::Color::from_rgb(0, 0, 255));
        assert_eq!(ramp(1.0), rerun::Color::from_rgb(255, 0, 0));
        assert_eq!(ramp(f64::NAN), ramp(0.0));
    }
}
