//! One WAAM slicing job end to end (seed 004 §4.2–4.8; issue 8): load the STL
//! ([`cell_mesh::Mesh::load_stl`]), slice it into closed contours ([`cell_mesh::slice()`]),
//! place the part on the build plate, plan every layer's beads ([`cell_waam::plan_layer`], each
//! layer starting where the previous one ended, as [`cell_waam::plan_stack`] does, but one layer
//! at a time so progress can be reported), and sum up deposited volume, times and the
//! post-toolpath cost (seed 004 eq. 20 with eq. 1–6). The `slicer` node and `cell slice` are
//! thin adapters around [`run`].
//!
//! Mesh diagnostics (holes, non-manifold or flipped edges, degenerate triangles, open chains
//! left by the slicer) do not stop the job: they go into [`SliceReport::warnings`]. A mesh that
//! cannot be read (missing, empty, truncated, NaN) or a bad parameter ends it with a
//! [`JobError`] naming the file.

use std::path::{Path, PathBuf};
use std::time::Instant;

use cell_mesh::{Mesh, MeshReport, StlFormat};
use cell_waam::cost::{
    post_toolpath_cost, solid_machining_cost, PartVolumes, PostToolpathCost, SolidMachiningCost,
};
use cell_waam::toolpath::toolpath_totals;
use cell_waam::{plan_layer, LayerPolygons, LayerToolpath, SegmentKind, WaamProcess};
use serde::Serialize;

/// The built-in process profile, `config/processes/waam.yaml`, as shipped.
pub const BUILTIN_PROCESS_YAML: &str = include_str!("../../../config/processes/waam.yaml");

/// How the built-in profile is named in reports and errors.
pub const BUILTIN_PROCESS_NAME: &str = "config/processes/waam.yaml (built in)";

/// Where the part comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum PartSource {
    /// An STL file (ASCII or binary, mm).
    Stl(PathBuf),
    /// A wing spec for `cell_wing` ([`crate::wing::run_wing`]), and the section to print.
    WingSpec {
        /// The spec (YAML).
        file: PathBuf,
        /// Index into the design's sections.
        section: usize,
    },
}

/// Where the part is put in the work-object (build plate) frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Placement {
    /// Coordinates as in the file.
    AsIs,
    /// The bounding box's XY centre moves to `centre_xy_mm` and its bottom to z = 0 (the
    /// plate's top).
    OnPlate {
        /// Target of the bounding box's XY centre, mm.
        centre_xy_mm: [f64; 2],
    },
}

/// Everything one job needs.
#[derive(Debug, Clone, PartialEq)]
pub struct SliceJob {
    /// The part.
    pub part: PartSource,
    /// The process profile (checked by [`run`]).
    pub process: WaamProcess,
    /// The profile's name for the report (a path, or [`BUILTIN_PROCESS_NAME`]).
    pub process_name: String,
    /// Layer height, mm; `None` = the profile's `layer_height_mm`.
    pub layer_height_mm: Option<f64>,
    /// Where the part goes.
    pub placement: Placement,
}

/// Why a job failed; every message names the file or the field.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// The STL cannot be read or holds no usable triangle (the message names the file).
    #[error(transparent)]
    Mesh(#[from] cell_mesh::MeshError),
    /// Slicing refused its parameters.
    #[error("{file}: {error}")]
    Slice {
        /// The STL.
        file: String,
        /// The cause.
        error: cell_mesh::SliceError,
    },
    /// The process profile cannot be read or is invalid (file, line, field).
    #[error(transparent)]
    Process(#[from] cell_waam::ProcessError),
    /// The mesh is lower than half a layer: there is nothing to deposit.
    #[error(
        "{file}: nothing to deposit: the part is {height_mm:.3} mm high, less than half a layer \
         ({layer_height_mm} mm); STL coordinates are taken as mm"
    )]
    NothingToDeposit {
        /// The STL.
        file: String,
        /// The part's height, mm.
        height_mm: f64,
        /// The layer height, mm.
        layer_height_mm: f64,
    },
    /// Material of the part that no bead covers (the message lists the layers and regions).
    #[error("{file}: the beads leave part of the mesh uncovered: {regions}")]
    Uncovered {
        /// The STL.
        file: String,
        /// `layer k (z mm): x0..x1 × y0..y1 mm, area mm²`, joined by `; `.
        regions: String,
    },
    /// A layer could not be planned.
    #[error("{file}: {error}")]
    Toolpath {
        /// The STL.
        file: String,
        /// The cause.
        error: cell_waam::ToolpathError,
    },
    /// A parameter is out of range.
    #[error("{field} = {value}: {requirement}")]
    Param {
        /// The parameter.
        field: &'static str,
        /// The value given.
        value: f64,
        /// What it must satisfy.
        requirement: &'static str,
    },
    /// A wing spec cannot be read, is invalid or its design fails (the message names the
    /// field).
    #[error("{file}: {error}")]
    Wing {
        /// The spec file.
        file: String,
        /// The cause.
        error: String,
    },
    /// A wing section index beyond the design's sections.
    #[error("{file}: wing_section {section}: the design has {sections} sections (0..{})", sections.saturating_sub(1))]
    WingSection {
        /// The spec file.
        file: String,
        /// The index asked for.
        section: usize,
        /// Sections in the design.
        sections: usize,
    },
    /// The part at this layer height needs more than [`MAX_DEPOSIT_LAYERS`] layers.
    #[error(
        "{file}: layer_height_mm = {layer_height_mm} mm makes {layers} layers of the part's \
         {height_mm} mm (with the machining allowance): the limit is {max} layers \
         (MAX_DEPOSIT_LAYERS)"
    )]
    TooManyLayers {
        /// The STL.
        file: String,
        /// The layer height, mm.
        layer_height_mm: f64,
        /// Layers it would take.
        layers: f64,
        /// The part's height, mm.
        height_mm: f64,
        /// [`MAX_DEPOSIT_LAYERS`].
        max: usize,
    },
    /// [`run`] slices meshes; wing specs go to [`crate::wing::run_wing`].
    #[error("{0}: a wing spec is not a mesh: run it with cell_slicer::wing::run_wing")]
    NotAMesh(String),
    /// The stop hook of [`run_until`] or [`crate::wing::run_wing_until`] ended the job.
    #[error("cancelled after {layers_done} of {layers_total} layers")]
    Cancelled {
        /// Layers planned when it stopped.
        layers_done: usize,
        /// Layers in the stack (0 if it stopped before slicing).
        layers_total: usize,
    },
}

/// `Err(Cancelled)` once `stop` says so, else `Ok`: the check [`run_until`] makes between
/// steps.
pub(crate) fn check_stop(
    stop: &dyn Fn() -> bool,
    layers_done: usize,
    layers_total: usize,
) -> Result<(), JobError> {
    if stop() {
        Err(JobError::Cancelled {
            layers_done,
            layers_total,
        })
    } else {
        Ok(())
    }
}

/// Most deposit layers one part may take (issue 23: a 1e-9 mm layer height). A 2 m part at
/// 1 mm WAAM layers is 2 000; the limit is 10× that. The slab step (a quarter layer) then
/// stays within 4× the limit of planes, and the layer loop within seconds.
pub const MAX_DEPOSIT_LAYERS: usize = 20_000;

/// Layers [`crate::slab::deposit_layers`] makes of a part `height_mm` high with `allowance_mm`
/// of machining allowance at layer height `h`: `⌈(height + allowance)/h⌉`.
fn deposit_layer_count(height_mm: f64, allowance_mm: f64, h: f64) -> f64 {
    ((height_mm + allowance_mm) / h).ceil()
}

/// Loads a process profile: `""` or `"waam"` is the built-in `config/processes/waam.yaml`,
/// anything else a YAML file. Returns the profile and its name for reports.
///
/// # Errors
/// [`JobError::Process`]: the file cannot be read, has an unknown or mistyped key (file, line,
/// field), or a value out of range.
pub fn load_process(source: &str) -> Result<(WaamProcess, String), JobError> {
    if source.is_empty() || source == "waam" {
        let p = WaamProcess::from_yaml_str(BUILTIN_PROCESS_YAML, BUILTIN_PROCESS_NAME)?;
        Ok((p, BUILTIN_PROCESS_NAME.into()))
    } else {
        let p = WaamProcess::from_path(Path::new(source))?;
        Ok((p, source.into()))
    }
}

/// Which stage a progress report is from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Reading and welding the mesh.
    Load,
    /// Cutting it into layer contours.
    Slice,
    /// Planning the beads, layer by layer.
    Plan,
    /// Finished.
    Done,
}

impl Phase {
    /// The phase's name, as the action feedback carries it.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Load => "load",
            Phase::Slice => "slice",
            Phase::Plan => "plan",
            Phase::Done => "done",
        }
    }
}

/// A progress report: layers planned out of the total (0 of 0 while loading).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct JobProgress {
    /// Current phase.
    pub phase: Phase,
    /// Layers planned so far.
    pub layers_done: usize,
    /// Layers in the stack (0 until sliced).
    pub layers_total: usize,
}

/// What the loader found out about the mesh (serde mirror of [`MeshReport`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshSummary {
    /// `ascii` or `binary`.
    pub format: &'static str,
    /// Triangles in the file.
    pub input_triangles: usize,
    /// Vertices after welding.
    pub vertices: usize,
    /// Weld tolerance used, mm.
    pub weld_tolerance_mm: f64,
    /// Triangles that collapsed when welding.
    pub collapsed_triangles: usize,
    /// Zero-area triangles.
    pub degenerate_triangles: usize,
    /// Edges with one triangle.
    pub boundary_edges: usize,
    /// Closed loops of boundary edges (holes).
    pub boundary_loops: usize,
    /// Edges with more than two triangles.
    pub non_manifold_edges: usize,
    /// Edges whose two triangles disagree on winding.
    pub inconsistent_edges: usize,
    /// Bytes after the last triangle of a binary STL.
    pub trailing_bytes: usize,
    /// Closed, manifold and consistently wound.
    pub closed_manifold: bool,
    /// |signed volume| of the mesh, mm³ (meaningful for a closed mesh).
    pub volume_mm3: f64,
    /// Bounding box minimum in the file's frame, mm.
    pub bbox_min_mm: [f64; 3],
    /// Bounding box maximum in the file's frame, mm.
    pub bbox_max_mm: [f64; 3],
}

impl MeshSummary {
    /// The summary of a loaded mesh.
    pub fn of(mesh: &Mesh) -> Self {
        let r: &MeshReport = mesh.report();
        let (lo, hi) = mesh.bbox();
        MeshSummary {
            format: match r.format {
                StlFormat::Ascii => "ascii",
                _ => "binary",
            },
            input_triangles: r.input_triangles,
            vertices: r.vertices,
            weld_tolerance_mm: r.weld_tolerance_mm,
            collapsed_triangles: r.collapsed_triangles.len(),
            degenerate_triangles: r.degenerate_triangles.len(),
            boundary_edges: r.boundary_edges,
            boundary_loops: r.boundary_loops,
            non_manifold_edges: r.non_manifold_edges,
            inconsistent_edges: r.inconsistent_edges,
            trailing_bytes: r.trailing_bytes,
            closed_manifold: r.is_closed_manifold(),
            volume_mm3: mesh.signed_volume_mm3().abs(),
            bbox_min_mm: lo,
            bbox_max_mm: hi,
        }
    }

    /// One line per problem the mesh has (empty for a clean, closed mesh).
    pub fn warnings(&self, file: &str) -> Vec<String> {
        let mut w = Vec::new();
        let mut add = |n: usize, what: &str| {
            if n > 0 {
                w.push(format!("{file}: {n} {what}"));
            }
        };
        add(
            self.boundary_edges,
            "boundary edges (the mesh is not closed)",
        );
        add(self.boundary_loops, "holes (boundary loops)");
        add(self.non_manifold_edges, "non-manifold edges");
        add(self.inconsistent_edges, "edges with flipped winding");
        add(self.degenerate_triangles, "degenerate triangles");
        add(self.collapsed_triangles, "triangles collapsed by welding");
        add(
            self.trailing_bytes,
            "trailing bytes after the last triangle",
        );
        w
    }
}

/// Figures of one layer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LayerFigures {
    /// Layer index.
    pub index: usize,
    /// Height in the plate frame, mm.
    pub z_mm: f64,
    /// Closed contours (outer and holes).
    pub contours: usize,
    /// Holes among them.
    pub holes: usize,
    /// Chains left open by the slicer (not planned).
    pub open_chains: usize,
    /// Net area (outer minus holes), mm².
    pub area_mm2: f64,
    /// Deposited volume Σ w·h·L, mm³ (seed 004 eq. 25).
    pub deposited_volume_mm3: f64,
    /// Arc-on time, s (eq. 18).
    pub deposition_time_s: f64,
    /// Travel time plus arc start/stop time, s.
    pub travel_time_s: f64,
    /// Interlayer dwell, s.
    pub dwell_time_s: f64,
    /// Arc starts (deposit segments).
    pub arc_starts: usize,
}

/// `report.json`: what the job did and what the part costs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SliceReport {
    /// The STL.
    pub source: String,
    /// The process profile's name.
    pub process: String,
    /// Layer height used, mm.
    pub layer_height_mm: f64,
    /// Height of the first plane in the plate frame, mm.
    pub first_z_mm: f64,
    /// Translation from the file's frame to the plate frame, mm.
    pub offset_mm: [f64; 3],
    /// Layers.
    pub layers: usize,
    /// Closed contours over all layers.
    pub contours: usize,
    /// Holes among them.
    pub holes: usize,
    /// Open chains over all layers (not planned).
    pub open_chains: usize,
    /// Toolpath segments (deposit and travel).
    pub segments: usize,
    /// Arc starts (deposit segments).
    pub arc_starts: usize,
    /// Narrowest and widest bead, mm (0 when nothing is deposited).
    pub bead_width_range_mm: [f64; 2],
    /// V_d, deposited volume Σ w·h·L, mm³ (seed 004 eq. 16–17, 25).
    pub deposited_volume_mm3: f64,
    /// Deposited mass V_d·ρ, kg.
    pub deposited_mass_kg: f64,
    /// V_f, the part's (mesh's) volume, mm³.
    pub part_volume_mm3: f64,
    /// The process's machining allowance per side, mm.
    pub machining_allowance_mm: f64,
    /// The least allowance measured over the part's surface, mm: per layer, the signed distance
    /// from the part region's boundary to the deposit's (beads as their width swept along the
    /// path), and the top (last bead's top minus the part's top); the part's bottom sits on the
    /// plate. Negative: part left uncovered.
    pub min_allowance_mm: f64,
    /// Where the least allowance occurs (plate frame, mm; x and y NaN for the top).
    pub min_allowance_at_mm: [f64; 3],
    /// Material machined away afterwards, V_d − V_f, mm³ (eq. 6 with no substrate).
    pub machining_volume_mm3: f64,
    /// t_D, arc-on time, s (eq. 18).
    pub deposition_time_s: f64,
    /// Travel moves plus arc starts/stops, s.
    pub travel_time_s: f64,
    /// Interlayer dwell, s.
    pub dwell_time_s: f64,
    /// Sum of the three, s.
    pub total_time_s: f64,
    /// Part volumes the cost model used (m³): V_f = the mesh's volume, no substrate, and for
    /// machining from solid V_i = the bounding box, V_r = V_i − V_f.
    pub volumes: PartVolumes,
    /// Post-toolpath WAAM cost, every term named (seed 004 eq. 1–6, 20), SEK.
    pub cost: PostToolpathCost,
    /// Machining the same part from a solid block (eq. 21–23), SEK, for comparison.
    pub solid_machining: SolidMachiningCost,
    /// The mesh diagnostics.
    pub mesh: MeshSummary,
    /// Problems found (mesh defects, open chains); the job went on.
    pub warnings: Vec<String>,
    /// Wall-clock time of the job, s.
    pub runtime_s: f64,
    /// Per-layer figures.
    pub per_layer: Vec<LayerFigures>,
}

/// What a job produced.
#[derive(Debug, Clone)]
pub struct SliceOutcome {
    /// The sliced layers, in the plate frame.
    pub stack: cell_mesh::LayerStack,
    /// The planned layers, in the plate frame.
    pub layers: Vec<LayerToolpath>,
    /// The report.
    pub report: SliceReport,
}

impl SliceOutcome {
    /// The stock model (every deposited piece as a box, seed 004 §4.8) as binary STL bytes.
    pub fn stock_stl(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let boxes = cell_waam::stock::bead_boxes(&self.layers);
        // Writing into a Vec cannot fail.
        let _ = cell_waam::stock::write_stock_stl(&mut out, &boxes);
        out
    }

    /// The thesis's toolpath rows `[X Y Z E C N LW/2 h k]` (seed 004 eq. 7, 12–13) as CSV,
    /// paths numbered across layers.
    pub fn rows_csv(&self) -> Vec<u8> {
        let mut rows = Vec::new();
        for l in &self.layers {
            // Every path ends with its break row, which carries the path's k.
            let next_k = rows
                .last()
                .map_or(0, |r: &cell_waam::rows::ThesisRow| r.k + 1);
            rows.extend(cell_waam::rows::rows_from_layer(
                l,
                next_k,
                cell_waam::rows::VectorConvention::Unit,
            ));
        }
        let mut out = Vec::new();
        let _ = cell_waam::rows::write_csv(&mut out, &rows);
        out
    }
}

/// The translation [`Placement`] asks for, given the mesh's bounding box.
pub fn placement_offset(placement: Placement, lo: [f64; 3], hi: [f64; 3]) -> [f64; 3] {
    match placement {
        Placement::AsIs => [0.0; 3],
        Placement::OnPlate { centre_xy_mm } => [
            centre_xy_mm[0] - 0.5 * (lo[0] + hi[0]),
            centre_xy_mm[1] - 0.5 * (lo[1] + hi[1]),
            -lo[2],
        ],
    }
}

/// Runs the job (module docs). `progress` gets a report when loading starts, when slicing
/// starts, after every planned layer and at the end; `layers_done` never decreases.
///
/// # Errors
/// [`JobError`]: an unreadable or empty mesh (naming the file), a bad layer height or process
/// profile (naming the field), a wing spec ([`JobError::NotAMesh`]).
pub fn run(job: &SliceJob, progress: impl FnMut(JobProgress)) -> Result<SliceOutcome, JobError> {
    run_until(job, progress, &|| false)
}

/// As [`run`], with a cancel hook: `stop` is asked after loading, after slicing and after every
/// planned layer, and once it returns true the job ends with [`JobError::Cancelled`] (nothing
/// half-planned is returned).
///
/// # Errors
/// As [`run`]; [`JobError::Cancelled`].
pub fn run_until(
    job: &SliceJob,
    mut progress: impl FnMut(JobProgress),
    stop: &dyn Fn() -> bool,
) -> Result<SliceOutcome, JobError> {
    let t0 = Instant::now();
    let file = match &job.part {
        PartSource::Stl(p) => p.clone(),
        PartSource::WingSpec { file, .. } => {
            return Err(JobError::NotAMesh(file.display().to_string()))
        }
    };
    let name = file.display().to_string();
    job.process.check(&job.process_name)?;
    let h = job.layer_height_mm.unwrap_or(job.process.layer_height_mm);
    if !(h.is_finite() && h > 0.0) {
        return Err(JobError::Param {
            field: "layer_height_mm",
            value: h,
            requirement: "must be finite and > 0",
        });
    }
    progress(JobProgress {
        phase: Phase::Load,
        layers_done: 0,
        layers_total: 0,
    });
    let mesh = Mesh::load_stl(&file)?;
    check_stop(stop, 0, 0)?;
    let summary = MeshSummary::of(&mesh);
    let mut warnings = summary.warnings(&name);

    progress(JobProgress {
        phase: Phase::Slice,
        layers_done: 0,
        layers_total: 0,
    });
    let (lo, hi) = mesh.bbox();
    if hi[2] - lo[2] < 0.5 * h {
        return Err(JobError::NothingToDeposit {
            file: name.clone(),
            height_mm: hi[2] - lo[2],
            layer_height_mm: h,
        });
    }
    let layers = deposit_layer_count(hi[2] - lo[2], job.process.machining_allowance_mm, h);
    if layers > MAX_DEPOSIT_LAYERS as f64 {
        return Err(JobError::TooManyLayers {
            file: name.clone(),
            layer_height_mm: h,
            layers,
            height_mm: hi[2] - lo[2],
            max: MAX_DEPOSIT_LAYERS,
        });
    }
    // The deposit regions, layer by layer, with progress and the stop hook (thin layers make
    // this phase long).
    let mut sliced = (0, 0);
    let stack = crate::slab::deposit_layers(
        &mesh,
        h,
        job.process.machining_allowance_mm,
        &mut |done, total| {
            sliced = (done, total);
            progress(JobProgress {
                phase: Phase::Slice,
                layers_done: done,
                layers_total: total,
            });
            !stop()
        },
    )
    .map_err(|error| JobError::Slice {
        file: name.clone(),
        error,
    })?;
    let Some(mut stack) = stack else {
        return Err(JobError::Cancelled {
            layers_done: 0,
            layers_total: sliced.1,
        });
    };
    let offset = placement_offset(job.placement, lo, hi);
    for l in &mut stack.layers {
        l.z_mm += offset[2];
        for c in &mut l.contours {
            for p in &mut c.points {
                p[0] += offset[0];
                p[1] += offset[1];
            }
        }
        for c in &mut l.open_chains {
            for p in &mut c.points {
                p[0] += offset[0];
                p[1] += offset[1];
            }
        }
    }
    stack.first_z_mm += offset[2];
    let open = stack.open_chain_count();
    if open > 0 {
        let layers = stack
            .layers
            .iter()
            .filter(|l| !l.open_chains.is_empty())
            .count();
        warnings.push(format!(
            "{name}: {open} open chains in {layers} layers were left out (the mesh is not closed there)"
        ));
    }
    let total = stack.layers.len();
    check_stop(stop, 0, total)?;
    progress(JobProgress {
        phase: Phase::Plan,
        layers_done: 0,
        layers_total: total,
    });

    // The planner sizes thin-feature beads to be at least one layer high.
    let mut process = job.process.clone();
    process.layer_height_mm = h;
    let mut layers: Vec<LayerToolpath> = Vec::with_capacity(total);
    let mut from: Option<[f64; 3]> = None;
    for (done, l) in stack.layers.iter().enumerate() {
        let polygons = LayerPolygons {
            index: l.index,
            z_mm: l.z_mm,
            outers_and_holes: l.contours.iter().map(|c| c.points.clone()).collect(),
        };
        let tp = plan_layer(&polygons, &process, from).map_err(|error| JobError::Toolpath {
            file: name.clone(),
            error,
        })?;
        if let Some(p) = tp.segments.last().and_then(|s| s.points.last()) {
            from = Some([p.x_mm, p.y_mm, p.z_mm]);
        }
        layers.push(tp);
        progress(JobProgress {
            phase: Phase::Plan,
            layers_done: done + 1,
            layers_total: total,
        });
        check_stop(stop, done + 1, total)?;
    }

    check_covered(&name, &layers)?;
    let report = build_report(
        job, &name, h, offset, &stack, &layers, summary, warnings, t0,
    );
    progress(JobProgress {
        phase: Phase::Done,
        layers_done: total,
        layers_total: total,
    });
    Ok(SliceOutcome {
        stack,
        layers,
        report,
    })
}

/// [`JobError::Uncovered`] naming every layer and region no bead covers; also when nothing at
/// all is deposited.
fn check_covered(name: &str, layers: &[LayerToolpath]) -> Result<(), JobError> {
    let mut regions: Vec<String> = Vec::new();
    for l in layers {
        for r in &l.uncovered {
            regions.push(format!(
                "layer {} (z {:.2} mm): x {:.1}..{:.1} × y {:.1}..{:.1} mm, {:.1} mm²",
                l.index,
                l.z_mm,
                r.bbox_min_mm[0],
                r.bbox_max_mm[0],
                r.bbox_min_mm[1],
                r.bbox_max_mm[1],
                r.area_mm2
            ));
        }
    }
    if layers.iter().all(|l| l.arc_starts == 0) {
        regions.push(format!("no bead in any of the {} layers", layers.len()));
    }
    if regions.is_empty() {
        Ok(())
    } else {
        Err(JobError::Uncovered {
            file: name.into(),
            regions: regions.join("; "),
        })
    }
}

/// Boundary sample spacing of the allowance measure (mm).
const ALLOWANCE_STEP_MM: f64 = 0.5;

/// The least allowance over the layers (seed-free; issue 20): the side allowance of every
/// layer ([`cell_waam::allowance::layer_allowance`] against the layer's region) and the top
/// one (the last layer's top above the part's top). Returns (value, where, layer index or
/// `None` for the top).
fn min_allowance(
    stack: &cell_mesh::LayerStack,
    layers: &[LayerToolpath],
    part_height_mm: f64,
    tol_mm: f64,
) -> (f64, [f64; 3]) {
    let h = stack.layer_height_mm;
    let top = layers.len() as f64 * h - part_height_mm;
    let mut best = (
        top,
        [
            f64::NAN,
            f64::NAN,
            stack.first_z_mm - 0.5 * h + part_height_mm,
        ],
    );
    for (s, t) in stack.layers.iter().zip(layers) {
        let rings: Vec<Vec<[f64; 2]>> = s.contours.iter().map(|c| c.points.clone()).collect();
        if let Some(a) = cell_waam::allowance::layer_allowance(&rings, t, ALLOWANCE_STEP_MM, tol_mm)
        {
            if a.min_mm < best.0 {
                best = (a.min_mm, [a.at_mm[0], a.at_mm[1], s.z_mm]);
            }
        }
    }
    best
}

#[allow(clippy::too_many_arguments)]
fn build_report(
    job: &SliceJob,
    name: &str,
    h: f64,
    offset: [f64; 3],
    stack: &cell_mesh::LayerStack,
    layers: &[LayerToolpath],
    mesh: MeshSummary,
    warnings: Vec<String>,
    t0: Instant,
) -> SliceReport {
    let per_layer: Vec<LayerFigures> = stack
        .layers
        .iter()
        .zip(layers)
        .map(|(s, t)| LayerFigures {
            index: s.index,
            z_mm: s.z_mm,
            contours: s.contours.len(),
            holes: s.contours.iter().filter(|c| c.is_hole).count(),
            open_chains: s.open_chains.len(),
            area_mm2: s.net_area_mm2(),
            deposited_volume_mm3: t.deposited_volume_mm3,
            deposition_time_s: t.deposition_time_s,
            travel_time_s: t.travel_time_s,
            dwell_time_s: t.dwell_time_s,
            arc_starts: t.arc_starts,
        })
        .collect();
    let totals = toolpath_totals(layers);
    let rates = &job.process.cost;
    let finished_m3 = mesh.volume_mm3 * 1e-9;
    let bbox_m3 = (0..3)
        .map(|k| mesh.bbox_max_mm[k] - mesh.bbox_min_mm[k])
        .product::<f64>()
        * 1e-9;
    let volumes = PartVolumes {
        finished_m3,
        substrate_m3: 0.0,
        initial_m3: bbox_m3,
        removed_m3: (bbox_m3 - finished_m3).max(0.0),
    };
    let cost = post_toolpath_cost(rates, &volumes, &totals);
    let mut warnings = warnings;
    if totals.deposited_m3 < finished_m3 {
        // Eq. 6 then removes a negative mass: the machining terms come out negative.
        warnings.push(format!(
            "{name}: deposited volume {:.0} mm³ is below the part's {:.0} mm³: the beads do \
             not cover the part (machining cost {:.2} SEK is not meaningful)",
            totals.deposited_m3 * 1e9,
            mesh.volume_mm3,
            cost.machining_sek
        ));
    }
    let solid_machining = solid_machining_cost(rates, &volumes);
    let widths = layers
        .iter()
        .flat_map(|l| &l.segments)
        .filter(|s| s.kind == SegmentKind::Deposit)
        .flat_map(|s| &s.points)
        .map(|p| p.bead_width_mm)
        .filter(|w| *w > 0.0);
    let (wmin, wmax) = widths.fold((f64::INFINITY, 0.0f64), |(a, b), w| (a.min(w), b.max(w)));
    let deposition_time_s = totals.deposition_s + 0.0;
    let travel_time_s = totals.travel.seconds() + 0.0;
    let dwell_time_s = totals.wait_s + 0.0;
    // `+ 0.0`: an empty f64 sum is −0.0, which reports would print as "-0".
    let deposited_volume_mm3: f64 =
        layers.iter().map(|l| l.deposited_volume_mm3).sum::<f64>() + 0.0;
    let part_height = mesh.bbox_max_mm[2] - mesh.bbox_min_mm[2];
    let (min_allowance_mm, min_allowance_at_mm) =
        min_allowance(stack, layers, part_height, job.process.arc_tolerance_mm);
    let low_beads = layers
        .iter()
        .flat_map(|l| &l.segments)
        .flat_map(|s| &s.points)
        .filter(|p| p.arc_on && p.bead_height_mm < h - 1e-9)
        .count();
    if low_beads > 0 {
        warnings.push(format!(
            "{name}: {low_beads} bead points are lower than the {h} mm layer (eq. 28): the \
             layers will not stack to the planned height"
        ));
    }
    SliceReport {
        source: name.into(),
        process: job.process_name.clone(),
        layer_height_mm: h,
        first_z_mm: stack.first_z_mm,
        offset_mm: offset,
        layers: stack.layers.len(),
        contours: per_layer.iter().map(|l| l.contours).sum(),
        holes: per_layer.iter().map(|l| l.holes).sum(),
        open_chains: per_layer.iter().map(|l| l.open_chains).sum(),
        segments: layers.iter().map(|l| l.segments.len()).sum(),
        arc_starts: layers.iter().map(|l| l.arc_starts).sum(),
        bead_width_range_mm: if wmax > 0.0 { [wmin, wmax] } else { [0.0, 0.0] },
        deposited_volume_mm3,
        deposited_mass_kg: deposited_volume_mm3 * 1e-9 * rates.density_kg_m3,
        part_volume_mm3: mesh.volume_mm3,
        machining_allowance_mm: job.process.machining_allowance_mm,
        min_allowance_mm,
        min_allowance_at_mm,
        machining_volume_mm3: deposited_volume_mm3 - mesh.volume_mm3,
        deposition_time_s,
        travel_time_s,
        dwell_time_s,
        total_time_s: deposition_time_s + travel_time_s + dwell_time_s,
        volumes,
        cost,
        solid_machining,
        mesh,
        warnings,
        runtime_s: t0.elapsed().as_secs_f64(),
        per_layer,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(name: &str) -> PathBuf {
        PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data/stl")).join(name)
    }

    fn job(file: &str) -> SliceJob {
        let (process, process_name) = load_process("waam").unwrap();
        SliceJob {
            part: PartSource::Stl(data(file)),
            process,
            process_name,
            layer_height_mm: None,
            placement: Placement::OnPlate {
                centre_xy_mm: [300.0, 200.0],
            },
        }
    }

    #[test]
    fn the_builtin_profile_is_the_crate_default() {
        let (p, name) = load_process("").unwrap();
        assert_eq!(p, WaamProcess::default());
        assert_eq!(name, BUILTIN_PROCESS_NAME);
    }

    #[test]
    fn the_stop_hook_ends_the_job_between_steps() {
        let cube = job("20mm-xyz-cube.stl");
        let e = run_until(&cube, |_| {}, &|| true).unwrap_err();
        assert!(
            matches!(
                e,
                JobError::Cancelled {
                    layers_done: 0,
                    layers_total: 0
                }
            ),
            "stops right after loading: {e}"
        );
        // Stopped while the layers' regions are computed (thin layers make that phase long).
        let sliced = std::cell::Cell::new(0);
        let e = run_until(
            &cube,
            |p| {
                if p.phase == Phase::Slice {
                    sliced.set(p.layers_done)
                }
            },
            &|| sliced.get() >= 2,
        )
        .unwrap_err();
        assert_eq!(e.to_string(), "cancelled after 0 of 14 layers");
        let done = std::cell::Cell::new(0);
        let e = run_until(
            &cube,
            |p| {
                if p.phase == Phase::Plan {
                    done.set(p.layers_done)
                }
            },
            &|| done.get() >= 3,
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                JobError::Cancelled {
                    layers_done: 3,
                    layers_total: 14
                }
            ),
            "stops after the third layer: {e}"
        );
        assert_eq!(e.to_string(), "cancelled after 3 of 14 layers");
    }

    #[test]
    fn a_cube_slices_into_layers_with_monotone_progress_and_consistent_totals() {
        let mut seen = Vec::new();
        let out = run(&job("20mm-xyz-cube.stl"), |p| seen.push(p)).unwrap();
        // Issue 20: the last bead's top is the allowance above the part's: ⌈(20 + 1)/1.6⌉ = 14
        // layers (12 reached only 19.2 mm).
        assert_eq!(out.report.layers, 14, "20 mm cube at 1.6 mm layers");
        assert_eq!(out.layers.len(), 14);
        // Monotone within each phase: slicing counts the layers' regions, planning their beads.
        assert!(seen
            .windows(2)
            .all(|w| w[0].phase != w[1].phase || w[0].layers_done <= w[1].layers_done));
        assert_eq!(
            seen.iter().filter(|p| p.phase == Phase::Slice).count(),
            15,
            "one report before slicing and one per layer"
        );
        assert_eq!(seen.last().unwrap().phase, Phase::Done);
        assert_eq!(
            seen.iter().filter(|p| p.phase == Phase::Plan).count(),
            15,
            "one report before planning and one per layer"
        );
        let r = &out.report;
        // On the plate: bottom at z = 0, first plane mid-layer, centred at (300, 200).
        assert!((r.first_z_mm - 0.8).abs() < 1e-9, "{}", r.first_z_mm);
        let totals = toolpath_totals(&out.layers);
        assert!((r.deposited_volume_mm3 * 1e-9 - totals.deposited_m3).abs() < 1e-15);
        assert!(r.deposited_volume_mm3 > 0.0);
        let rel = (r.mesh.volume_mm3 - 8000.0).abs() / 8000.0;
        assert!(
            rel < 0.05,
            "cube volume {} mm³ (20³ minus engraving)",
            r.mesh.volume_mm3
        );
        assert!(r.cost.total_sek > 0.0 && r.cost.wire_sek > 0.0);
        assert!((r.cost.deposition_h * 3600.0 - r.deposition_time_s).abs() < 1e-6);
        for l in &out.layers {
            for s in &l.segments {
                for p in &s.points {
                    assert!((290.0..=310.0).contains(&p.x_mm), "{}", p.x_mm);
                    assert!((190.0..=210.0).contains(&p.y_mm), "{}", p.y_mm);
                }
            }
        }
        // A clean mesh: the only warning possible is the coverage one, there exactly when the
        // beads hold less metal than the part.
        let covers = r.deposited_volume_mm3 >= r.mesh.volume_mm3;
        assert_eq!(r.warnings.len(), usize::from(!covers), "{:?}", r.warnings);
        assert!(r.warnings.iter().all(|w| w.contains("do not cover")));
        assert!(!out.stock_stl().is_empty());
        let csv = String::from_utf8(out.rows_csv()).unwrap();
        assert!(csv.lines().count() > 12);
    }

    #[test]
    fn broken_meshes_and_wing_specs_fail_naming_the_file() {
        let e = run(&job("empty.stl"), |_| {}).unwrap_err().to_string();
        assert!(e.contains("empty.stl"), "{e}");
        let mut j = job("20mm-xyz-cube.stl");
        j.part = PartSource::WingSpec {
            file: "wing.yaml".into(),
            section: 0,
        };
        let e = run(&j, |_| {}).unwrap_err().to_string();
        assert!(e.contains("wing.yaml") && e.contains("run_wing"), "{e}");
        let mut j = job("20mm-xyz-cube.stl");
        j.layer_height_mm = Some(-1.0);
        let e = run(&j, |_| {}).unwrap_err().to_string();
        assert!(e.contains("layer_height_mm"), "{e}");
    }

    #[test]
    fn deposit_layers_are_capped() {
        // 20 000 layers of 2⁻¹⁰ mm, exactly.
        let (height, allowance, h) = (18.53125, 1.0, 1.0 / 1024.0);
        assert_eq!(deposit_layer_count(height, allowance, h), 20_000.0);
        assert_eq!(
            deposit_layer_count(height, allowance, h * (1.0 - 1e-9)),
            20_001.0
        );
        let mut j = job("20mm-xyz-cube.stl");
        j.layer_height_mm = Some(1e-9);
        let t0 = std::time::Instant::now();
        let e = run(&j, |_| {}).unwrap_err();
        assert!(t0.elapsed().as_secs_f64() < 5.0, "{:?}", t0.elapsed());
        assert!(
            matches!(e, JobError::TooManyLayers { max: 20_000, .. }),
            "{e}"
        );
        let e = e.to_string();
        assert!(
            e.contains("20mm-xyz-cube.stl: layer_height_mm = 0.000000001 mm makes")
                && e.ends_with("the limit is 20000 layers (MAX_DEPOSIT_LAYERS)"),
            "{e}"
        );
    }

    /// A binary STL of `tris` (mm) at `path`.
    fn write_stl(path: &Path, tris: &[[[f64; 3]; 3]]) {
        let mut b = vec![0u8; 80];
        b.extend((tris.len() as u32).to_le_bytes());
        for t in tris {
            b.extend([0u8; 12]);
            for v in t {
                for c in v {
                    b.extend((*c as f32).to_le_bytes());
                }
            }
            b.extend([0u8; 2]);
        }
        std::fs::write(path, b).unwrap();
    }

    /// The prism between the CCW rings `outer` and `inner` (same count; `inner` may be a single
    /// repeated point for a solid), from z = 0 to `h`, outward normals.
    fn prism(outer: &[[f64; 2]], inner: &[[f64; 2]], h: f64) -> Vec<[[f64; 3]; 3]> {
        let v = |p: [f64; 2], z: f64| [p[0], p[1], z];
        let mut t = Vec::new();
        let n = outer.len();
        for i in 0..n {
            let (p, q) = (outer[i], outer[(i + 1) % n]);
            let (r, s) = (inner[i], inner[(i + 1) % n]);
            t.push([v(p, 0.0), v(q, 0.0), v(q, h)]);
            t.push([v(p, 0.0), v(q, h), v(p, h)]);
            if r != s {
                t.push([v(s, 0.0), v(r, 0.0), v(r, h)]);
                t.push([v(s, 0.0), v(r, h), v(s, h)]);
            }
            // Top and bottom: the band between the rings.
            t.push([v(p, h), v(q, h), v(s, h)]);
            t.push([v(p, h), v(s, h), v(r, h)]);
            t.push([v(q, 0.0), v(p, 0.0), v(r, 0.0)]);
            t.push([v(q, 0.0), v(r, 0.0), v(s, 0.0)]);
        }
        t.retain(|[a, b, c]| a != b && b != c && c != a);
        t
    }

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 2]> {
        vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    }

    /// Runs `file` (a path) with the built-in profile and checks issue 20's coverage: more metal
    /// than the part, the least allowance at least the profile's minus 0.2 mm, a positive
    /// machining term and no coverage warning.
    fn covered(file: PathBuf) -> SliceReport {
        let mut j = job("20mm-xyz-cube.stl");
        j.part = PartSource::Stl(file.clone());
        let r = run(&j, |_| {}).unwrap().report;
        let a = r.machining_allowance_mm;
        assert_eq!(a, 1.0, "the built-in allowance");
        assert!(
            r.deposited_volume_mm3 > r.part_volume_mm3,
            "{file:?}: {} mm³ deposited for {} mm³",
            r.deposited_volume_mm3,
            r.part_volume_mm3
        );
        assert!(
            r.min_allowance_mm >= a - 0.2,
            "{file:?}: least allowance {} mm at {:?}",
            r.min_allowance_mm,
            r.min_allowance_at_mm
        );
        assert!(r.cost.machining_sek > 0.0 && r.machining_volume_mm3 > 0.0);
        assert!(
            r.warnings.iter().all(|w| !w.contains("do not cover")),
            "{:?}",
            r.warnings
        );
        r
    }

    #[test]
    fn shipped_parts_are_covered_with_the_allowance() {
        let cube = covered(data("20mm-xyz-cube.stl"));
        // The top too: 14 layers of 1.6 mm reach 22.4 mm over a 20 mm part.
        assert!(cube.layers as f64 * 1.6 >= 20.0 + 1.0);
        let plate = covered(data("plate_holes.STL"));
        assert_eq!(plate.holes % plate.layers, 0, "every layer keeps its holes");
        assert!(plate.holes > 0);
        // idler_riser.STL is drawn in inches (2.58 × 2.95 × 0.625): in mm it is lower than half
        // a layer (an error, below); scaled by 25.4 it is a 65 × 75 × 15.9 mm riser.
        let dir = tempfile::tempdir().unwrap();
        let mesh = Mesh::load_stl(data("idler_riser.STL")).unwrap();
        let v = mesh.vertices();
        let tris: Vec<[[f64; 3]; 3]> = mesh
            .triangles()
            .iter()
            .map(|t| t.map(|i| v[i as usize].map(|c| 25.4 * c)))
            .collect();
        let riser = dir.path().join("idler_riser_mm.stl");
        write_stl(&riser, &tris);
        covered(riser);
        let e = run(&job("idler_riser.STL"), |_| {})
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("idler_riser.STL") && e.contains("nothing to deposit"),
            "{e}"
        );
    }

    #[test]
    fn a_thin_walled_box_and_a_pin_are_deposited_and_covered() {
        let dir = tempfile::tempdir().unwrap();
        // A 40 × 30 mm box with 3 mm walls, 25 mm high: every layer one 3 mm ring.
        let tube = dir.path().join("tube.stl");
        write_stl(
            &tube,
            &prism(
                &rect(0.0, 0.0, 40.0, 30.0),
                &rect(3.0, 3.0, 37.0, 27.0),
                25.0,
            ),
        );
        let r = covered(tube);
        assert_eq!(r.layers, 17, "⌈(25 + 1)/1.6⌉");
        assert_eq!(r.arc_starts, r.layers, "one closed mid-wall bead per layer");
        // A 5 mm pin (32-gon), 20 mm high: a column of one small circle per layer.
        let pin = dir.path().join("pin.stl");
        let ring: Vec<[f64; 2]> = (0..32)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / 32.0;
                [2.5 * t.cos(), 2.5 * t.sin()]
            })
            .collect();
        write_stl(&pin, &prism(&ring, &vec![[0.0, 0.0]; 32], 20.0));
        let mut j = job("20mm-xyz-cube.stl");
        j.part = PartSource::Stl(pin.clone());
        let out = run(&j, |_| {}).unwrap();
        let r = covered(pin);
        assert_eq!(r.arc_starts, r.layers, "one circle per layer");
        for p in out
            .layers
            .iter()
            .flat_map(|l| &l.segments)
            .flat_map(|s| &s.points)
        {
            assert!(!p.arc_on || p.bead_height_mm >= 1.6, "beads stack: {p:?}");
            assert!(
                !p.arc_on || p.bead_width_mm < 9.11,
                "the narrowest bead that stacks"
            );
        }
    }

    #[test]
    fn a_part_lower_than_half_a_layer_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let flat = dir.path().join("flat.stl");
        write_stl(
            &flat,
            &prism(&rect(0.0, 0.0, 10.0, 10.0), &[[5.0, 5.0]; 4], 0.5),
        );
        let mut j = job("20mm-xyz-cube.stl");
        j.part = PartSource::Stl(flat);
        let e = run(&j, |_| {}).unwrap_err();
        assert!(matches!(e, JobError::NothingToDeposit { .. }), "{e}");
        let e = e.to_string();
        assert!(
            e.contains("flat.stl") && e.contains("nothing to deposit"),
            "{e}"
        );
    }

    #[test]
    fn an_open_mesh_is_sliced_with_warnings() {
        let out = run(&job("teapot.stl"), |_| {}).unwrap();
        assert!(out.report.mesh.boundary_edges > 0);
        assert!(
            out.report.warnings.iter().any(|w| w.contains("teapot.stl")),
            "{:?}",
            out.report.warnings
        );
        assert!(out.report.layers > 0);
    }
}
