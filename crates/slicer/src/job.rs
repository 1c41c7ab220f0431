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

use cell_mesh::{Mesh, MeshReport, SliceParams, StlFormat};
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
    let mut stack =
        cell_mesh::slice(&mesh, &SliceParams::new(h)).map_err(|error| JobError::Slice {
            file: name.clone(),
            error,
        })?;
    let (lo, hi) = mesh.bbox();
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
    if total == 0 {
        warnings.push(format!(
            "{name}: no layer: the part is {:.3} mm high, less than half a layer ({h} mm); STL \
             coordinates are taken as mm",
            hi[2] - lo[2]
        ));
    }
    progress(JobProgress {
        phase: Phase::Plan,
        layers_done: 0,
        layers_total: total,
    });

    let mut layers: Vec<LayerToolpath> = Vec::with_capacity(total);
    let mut from: Option<[f64; 3]> = None;
    for (done, l) in stack.layers.iter().enumerate() {
        let polygons = LayerPolygons {
            index: l.index,
            z_mm: l.z_mm,
            outers_and_holes: l.contours.iter().map(|c| c.points.clone()).collect(),
        };
        let tp = plan_layer(&polygons, &job.process, from).map_err(|error| JobError::Toolpath {
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
        let done = std::cell::Cell::new(0);
        let e = run_until(&cube, |p| done.set(p.layers_done), &|| done.get() >= 3).unwrap_err();
        assert!(
            matches!(
                e,
                JobError::Cancelled {
                    layers_done: 3,
                    layers_total: 12
                }
            ),
            "stops after the third layer: {e}"
        );
        assert_eq!(e.to_string(), "cancelled after 3 of 12 layers");
    }

    #[test]
    fn a_cube_slices_into_layers_with_monotone_progress_and_consistent_totals() {
        let mut seen = Vec::new();
        let out = run(&job("20mm-xyz-cube.stl"), |p| seen.push(p)).unwrap();
        // 20 mm / 1.6 mm mid-layer planes: z_min + 0.8 + 1.6 k < z_max → k = 0..=11.
        assert_eq!(out.report.layers, 12, "20 mm cube at 1.6 mm layers");
        assert_eq!(out.layers.len(), 12);
        assert!(seen
            .windows(2)
            .all(|w| w[0].layers_done <= w[1].layers_done));
        assert_eq!(seen.last().unwrap().phase, Phase::Done);
        assert_eq!(
            seen.iter().filter(|p| p.phase == Phase::Plan).count(),
            13,
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
