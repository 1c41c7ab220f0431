//! The wing path of a slicing job (seed 002, G-Wing; issue 8): a wing spec
//! ([`cell_wing::spec::WingSpec`]) → the design (lifting line, spars, sections, Algorithm 2) →
//! one printable section's layers (closed perimeter, spars, a solid rib on the first layer)
//! → a `Toolpath` with extrusion flow for the emitter's Marlin profile, the perimeters as a
//! `LayerStack`, and the section's mass and build-time estimates.
//!
//! One goal prints one section: the sections are separate prints (seed 002 eq. 1), each its
//! own program. `cell wing` writes them all; it shares [`SectionFigures`] with this module.

use std::path::Path;
use std::time::Instant;

use cell_geometry::{orientation, Orientation};
use cell_msgs::std_msgs::Header;
use cell_msgs::{LayerStack, Polygon2, SliceLayer, Toolpath};
use cell_wing::estimate::{build_time_s, deposited_volume_mm3, mass_g};
use cell_wing::layers::{moves, Layer, Role};
use cell_wing::marlin::FirmwareMotion;
use cell_wing::section::Side;
use cell_wing::spec::{Wing, WingSpec};
use serde::Serialize;

use crate::job::{check_stop, JobError, JobProgress, Phase};

/// Marlin 2's stock planner (acceleration, junction deviation, look-ahead, axis limits), for
/// the second build-time figure.
pub const MARLIN_ACCELERATION: FirmwareMotion = FirmwareMotion::MARLIN_2_DEFAULTS;

/// A section's side as reports spell it.
pub fn side_name(side: Side) -> &'static str {
    match side {
        Side::Centre => "centre",
        Side::Left => "left",
        Side::Right => "right",
    }
}

/// One section's figures (seed 002 §5 estimators): where it sits in the span, its layers,
/// deposited volume, mass and build time without and with acceleration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SectionFigures {
    /// Index into the design's section list.
    pub index: usize,
    /// `centre`, `left` or `right`.
    pub side: &'static str,
    /// Position along its semispan (0 = the centre section).
    pub position: usize,
    /// Spanwise y of the face on the bed, mm.
    pub y_bed_mm: f64,
    /// Spanwise y of the top face, mm.
    pub y_top_mm: f64,
    /// Layers printed.
    pub layers: usize,
    /// Σ w·h·L over every stroke, mm³.
    pub deposited_volume_mm3: f64,
    /// Deposited volume × the spec's density, g.
    pub mass_g: f64,
    /// Σ L/v over every move, s.
    pub build_time_s: f64,
    /// The time Marlin 2's planner takes with its stock settings (`cell_wing::marlin`), s.
    pub build_time_with_acceleration_s: f64,
}

impl SectionFigures {
    /// The figures of section `index` of `wing`, printed as `layers`.
    pub fn of(wing: &Wing, index: usize, layers: &[Layer]) -> Option<Self> {
        let section = wing.sections.get(index)?;
        let bp = wing.spec.build_params();
        let path = moves(layers, &bp);
        Some(SectionFigures {
            index,
            side: side_name(section.side),
            position: section.index,
            y_bed_mm: section.y_bed_mm,
            y_top_mm: section.y_top_mm,
            layers: layers.len(),
            deposited_volume_mm3: deposited_volume_mm3(layers, bp.extrusion_width_mm),
            mass_g: mass_g(layers, bp.extrusion_width_mm, wing.spec.build.density_kg_m3),
            build_time_s: build_time_s(&path, None),
            build_time_with_acceleration_s: build_time_s(&path, Some(MARLIN_ACCELERATION)),
        })
    }
}

/// The report of a wing goal (the action result's `report_json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WingReport {
    /// The spec file.
    pub spec: String,
    /// Its airfoil file.
    pub airfoil: String,
    /// Span b, mm.
    pub span_mm: f64,
    /// The design lift coefficient c_L of the lifting-line solution (condition 1).
    pub c_l: f64,
    /// The design case (seed 002 Table 1), its solved planform and each condition.
    pub design: cell_wing::design::DesignReport,
    /// Sections in the design.
    pub sections_in_design: usize,
    /// Layers of the whole section (`section.layers` counts those printed).
    pub layers_in_section: usize,
    /// The section printed.
    pub section: SectionFigures,
    /// Wall-clock time of the job, s.
    pub runtime_s: f64,
}

/// What a wing goal produces.
#[derive(Debug, Clone)]
pub struct WingOutcome {
    /// The section's layers (strokes in print order).
    pub layers: Vec<Layer>,
    /// The layers as a toolpath with extrusion flow (`cell_wing::msg::toolpath`).
    pub toolpath: Toolpath,
    /// One closed perimeter per layer, in machine coordinates.
    pub stack: LayerStack,
    /// The figures.
    pub report: WingReport,
}

/// Designs the wing of `spec_file` and prints section `section` (an index into the design's
/// sections; 0 is the centre section, or the right root section without one). `progress`
/// gets `load` (design), `slice` (the section's layers cut), `plan` after each layer's
/// estimate and `done`.
///
/// # Errors
/// [`JobError::Wing`]: the spec cannot be read or is invalid, or the design fails (naming the
/// file and field); [`JobError::WingSection`]: `section` is out of range.
pub fn run_wing(
    spec_file: &Path,
    section: usize,
    job_id: &str,
    frame_id: &str,
    progress: impl FnMut(JobProgress),
) -> Result<WingOutcome, JobError> {
    run_wing_until(spec_file, section, job_id, frame_id, progress, &|| false)
}

/// As [`run_wing`], with a cancel hook: `stop` is asked after the design and after every
/// layer, and once it returns true the job ends with [`JobError::Cancelled`].
///
/// # Errors
/// As [`run_wing`]; [`JobError::Cancelled`].
pub fn run_wing_until(
    spec_file: &Path,
    section: usize,
    job_id: &str,
    frame_id: &str,
    progress: impl FnMut(JobProgress),
    stop: &dyn Fn() -> bool,
) -> Result<WingOutcome, JobError> {
    run_wing_layers(spec_file, section, 0, job_id, frame_id, progress, stop)
}

/// As [`run_wing_until`], printing only the section's first `max_layers` layers (0: all), as
/// `cell wing --layers` does: a short print of the section's base (the demo's wing job). The
/// figures are the printed layers'; [`WingReport::layers_in_section`] keeps the whole count.
///
/// # Errors
/// As [`run_wing_until`].
pub fn run_wing_layers(
    spec_file: &Path,
    section: usize,
    max_layers: usize,
    job_id: &str,
    frame_id: &str,
    mut progress: impl FnMut(JobProgress),
    stop: &dyn Fn() -> bool,
) -> Result<WingOutcome, JobError> {
    let t0 = Instant::now();
    let file = spec_file.display().to_string();
    let wing_error = |error: cell_wing::spec::SpecError| JobError::Wing {
        file: file.clone(),
        error: error.to_string(),
    };
    let at = |phase, layers_done, layers_total| JobProgress {
        phase,
        layers_done,
        layers_total,
    };
    progress(at(Phase::Load, 0, 0));
    let spec = WingSpec::load(spec_file).map_err(wing_error)?;
    let wing = Wing::design(spec).map_err(wing_error)?;
    let sections = wing.sections.len();
    check_stop(stop, 0, 0)?;
    progress(at(Phase::Slice, 0, 0));
    let mut layers = wing.layers(section).ok_or(JobError::WingSection {
        file: file.clone(),
        section,
        sections,
    })?;
    let layers_in_section = layers.len();
    if max_layers > 0 {
        layers.truncate(max_layers);
    }
    let total = layers.len();
    let bp = wing.spec.build_params();
    let mut stack_layers = Vec::with_capacity(total);
    for (done, l) in layers.iter().enumerate() {
        stack_layers.extend(
            l.strokes
                .iter()
                .find(|s| s.role == Role::Perimeter)
                .map(|s| perimeter_layer(l, &s.points)),
        );
        progress(at(Phase::Plan, done + 1, total));
        check_stop(stop, done + 1, total)?;
    }
    let figures = SectionFigures::of(&wing, section, &layers).ok_or(JobError::WingSection {
        file: file.clone(),
        section,
        sections,
    })?;
    let mut toolpath = cell_wing::msg::toolpath(&layers, &bp, job_id);
    toolpath.header.frame_id = frame_id.into();
    let stack = LayerStack {
        header: Header {
            stamp: Default::default(),
            frame_id: frame_id.into(),
        },
        job_id: job_id.into(),
        layer_height_mm: bp.layer_height_mm,
        first_z_mm: layers.first().map_or(0.0, |l| l.z_mm),
        layers: stack_layers,
    };
    let report = WingReport {
        spec: file,
        airfoil: wing.spec.airfoil.display().to_string(),
        span_mm: wing.spec.aero.span_mm,
        c_l: wing.aero.c_l,
        design: wing.design_report(),
        sections_in_design: sections,
        layers_in_section,
        section: figures,
        runtime_s: t0.elapsed().as_secs_f64(),
    };
    progress(at(Phase::Done, total, total));
    Ok(WingOutcome {
        layers,
        toolpath,
        stack,
        report,
    })
}

/// A layer's closed perimeter as a slice layer (the closing point dropped, made
/// counter-clockwise as `Polygon2` wants outer contours).
fn perimeter_layer(layer: &Layer, points: &[[f64; 3]]) -> SliceLayer {
    let mut ring: Vec<[f64; 2]> = points.iter().map(|p| [p[0], p[1]]).collect();
    if ring.len() > 1 && ring.first() == ring.last() {
        ring.pop();
    }
    if orientation(&ring) == Orientation::Clockwise {
        ring.reverse();
    }
    SliceLayer {
        index: layer.index,
        z_mm: layer.z_mm,
        contours: vec![Polygon2 {
            x_mm: ring.iter().map(|p| p[0]).collect(),
            y_mm: ring.iter().map(|p| p[1]).collect(),
            is_hole: false,
        }],
        open_chains: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/wings/gwing-table2.yaml")
    }

    #[test]
    fn the_table2_centre_section_becomes_layers_a_toolpath_and_figures() {
        let mut seen = Vec::new();
        let out = run_wing(&spec(), 0, "wing-c", "work", |p| seen.push(p)).unwrap();
        let n = out.layers.len();
        assert!(n > 10, "{n} layers");
        assert_eq!(out.stack.layers.len(), n, "one perimeter per layer");
        assert_eq!(out.report.section.layers, n);
        // Feedback: load, slice, one per layer, done; layers_done never decreases.
        assert_eq!(seen.len(), n + 3);
        assert!(seen
            .windows(2)
            .all(|w| w[0].layers_done <= w[1].layers_done));
        assert_eq!(seen.last().unwrap().phase, Phase::Done);
        // Every perimeter is a closed outer contour at its layer's height, counter-clockwise.
        for (l, s) in out.layers.iter().zip(&out.stack.layers) {
            assert_eq!(s.z_mm, l.z_mm);
            let c = &s.contours[0];
            let ring: Vec<[f64; 2]> = c.x_mm.iter().zip(&c.y_mm).map(|(&x, &y)| [x, y]).collect();
            let area = cell_geometry::signed_area(&ring);
            assert!(area > 0.0, "layer {}: area {area}", l.index);
        }
        // The toolpath carries extrusion flow on every deposit point.
        assert_eq!(out.toolpath.process, Toolpath::PROCESS_EXTRUSION);
        let deposits: Vec<_> = out
            .toolpath
            .segments
            .iter()
            .filter(|s| s.kind == cell_msgs::ToolpathSegment::KIND_DEPOSIT)
            .collect();
        assert!(!deposits.is_empty());
        assert!(deposits.iter().all(|s| s.power.iter().all(|&q| q > 0.0)));
        // Mass = volume × density (PLA 1240 kg/m³ in the spec).
        let f = &out.report.section;
        assert!((f.mass_g - f.deposited_volume_mm3 * 1.24e-3).abs() < 1e-9 * f.mass_g.max(1.0));
        assert!(f.build_time_with_acceleration_s > f.build_time_s);
    }

    #[test]
    fn the_stop_hook_ends_a_wing_section_between_layers() {
        let e = run_wing_until(&spec(), 0, "w", "work", |_| {}, &|| true).unwrap_err();
        assert!(
            matches!(
                e,
                JobError::Cancelled {
                    layers_done: 0,
                    layers_total: 0
                }
            ),
            "stops right after the design: {e}"
        );
        let done = std::cell::Cell::new(0);
        let e = run_wing_until(
            &spec(),
            0,
            "w",
            "work",
            |p| done.set(p.layers_done),
            &|| done.get() >= 2,
        )
        .unwrap_err();
        assert!(
            matches!(e, JobError::Cancelled { layers_done: 2, .. }),
            "stops after the second layer: {e}"
        );
    }

    #[test]
    fn a_section_out_of_range_and_a_broken_spec_are_named() {
        let e = run_wing(&spec(), 99, "w", "work", |_| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("gwing-table2.yaml") && e.contains("99"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let bad = dir.path().join("bad-wing.yaml");
        std::fs::write(&bad, "airfoil: x.dat\naero:\n  spann_mm: 3\n").unwrap();
        let e = run_wing(&bad, 0, "w", "work", |_| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad-wing.yaml"), "{e}");
    }
}
