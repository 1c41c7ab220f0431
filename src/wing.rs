//! `cell wing`: design a G-Wing wing and write its print programs on the spot, without DDS
//! (seed 002; issue 8). Reads a wing spec (`cell_wing::spec`, e.g.
//! `config/wings/gwing-table2.yaml`), runs the design (lifting line, spars, sections), and for
//! every printable section writes into `--out`:
//!
//! - `<job>.gcode`: the section's layers (perimeter, spars, first-layer rib) as a
//!   `cell_msgs/Toolpath` through [`cell_emitter`] for `--profile` (Marlin by default: E from the
//!   volumetric flow, retract and Z-hop around travel);
//! - `<job>.scad`: the section's OpenSCAD model in the same build orientation, from the design
//!   and not the G-code ([`cell_wing::scad`]: outer mould line, spar walls);
//! - once, `<spec>.scad`: the whole wing's OpenSCAD model in the wing frame;
//! - once, the AVL geometry files ([`cell_wing::avl`], for a vortex-lattice check):
//!   `<spec>.avl` as built (the airfoil's camber line from `AFILE <airfoil>.dat`, written
//!   alongside: run AVL in `--out`, it opens AFILE where it runs; Ainc = LLT α + α_L0) and
//!   `<spec>-flat.avl` (flat camber lines, Ainc = LLT α from the zero-lift line: the lifting
//!   line's own terms, what `tests/vlm/compare.py` checks);
//! - once, `<spec>-planform.svg` ([`cell_wing::picture`], seed 002 Fig. 7): the planform
//!   from above with the leading and trailing edges, the hinge line, the main and other spars
//!   and the section breaks, and below it c, α and ℓ against y;
//! - and, once, `report.json`: the design (its case of seed 002 Table 1, the solved chord and
//!   twist, c_L, lift slope, each condition requested against achieved; sections) and per
//!   section its layers, deposited volume, mass and build time (with and without
//!   acceleration; `times`: Σ L/v, Marlin 2's planner with the profile's motion settings, and
//!   Pronterface's estimate, the paper's Table 4 method, of the moves and of the program as
//!   written). The design's lines are also printed.
//!
//! A progress bar counts sections. Exit status: 0 written; 64 a bad command line (a section
//! index out of range, a profile that writes no extrusion program); 65 a spec that cannot be
//! read or is invalid (the message names the file and field) or a section the emitter refuses;
//! 1 the output cannot be written.

use std::{path::PathBuf, process::ExitCode};

use cell_slicer::wing::{side_name, SectionFigures};
use cell_wing::spec::{Wing, WingSpec};
use clap::Args;

use crate::exit::{bad_data, failure, usage};
use serde::Serialize;

/// `cell wing` options.
#[derive(Args, Debug)]
pub struct WingArgs {
    /// The wing spec (YAML, `cell_wing::spec`); its airfoil path is relative to the file.
    #[arg(long, visible_alias = "spec", value_name = "FILE")]
    pub config: PathBuf,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Machine profile for the programs: a name under config/machines or a YAML file.
    #[arg(long, default_value = "marlin-extruder", value_name = "NAME|FILE")]
    pub profile: String,
    /// Sections to write, as indices into the design's section list (see report.json);
    /// default all.
    #[arg(long, value_delimiter = ',', value_name = "I,J,…")]
    pub sections: Vec<usize>,
    /// Write only the first N layers of each section (a quick look); 0 = all.
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub layers: usize,
}

/// One section in `report.json`: the slicer's figures and the program written.
#[derive(Debug, Serialize)]
struct SectionReport {
    #[serde(flatten)]
    figures: SectionFigures,
    program: String,
    program_lines: u32,
    /// The section's OpenSCAD model.
    scad: String,
    /// Build time by three estimators, s.
    times: SectionTimes,
}

/// A section's build time three ways (seed 002 Table 4; `cell_wing::marlin`), s; heating and
/// homing excluded.
#[derive(Debug, Serialize)]
struct SectionTimes {
    /// Σ L/v at the feeds asked.
    feeds_only_s: f64,
    /// Marlin 2's planner with the profile's `gcode.extrusion.motion` (stock Marlin if absent).
    marlin_s: f64,
    /// Pronterface's estimate (Printrun `gcoder`'s method, as the paper's 2:10 was made).
    pronterface_s: f64,
    /// Marlin 2's planner on the program as written (its arcs in 1 mm chords, G0 at the modal
    /// feed as Marlin runs it); absent if the program cannot be read for timing.
    program_marlin_s: Option<f64>,
    /// Pronterface's estimate of the program as written (it skips G2/G3).
    program_pronterface_s: Option<f64>,
}

impl SectionTimes {
    fn of(
        layers: &[cell_wing::layers::Layer],
        wing: &Wing,
        profile: &cell_profiles::MachineProfile,
        program: &str,
    ) -> Self {
        use cell_wing::marlin::{blocks_from_moves, marlin_time_s, pronterface_time_s};
        let moves = cell_wing::layers::moves(layers, &wing.spec.build_params());
        let blocks = blocks_from_moves(&moves);
        let motion = marlin_motion(profile);
        let written = cell_wing::marlin::read_gcode(program).ok();
        Self {
            feeds_only_s: cell_wing::estimate::build_time_s(&moves, None),
            marlin_s: marlin_time_s(&blocks, &motion),
            pronterface_s: pronterface_time_s(&blocks),
            program_marlin_s: written.as_ref().map(|r| marlin_time_s(&r.blocks, &motion)),
            program_pronterface_s: written.as_ref().map(|r| pronterface_time_s(&r.blocks)),
        }
    }
}

/// The profile's firmware motion settings for the planner model (stock Marlin 2 if absent).
fn marlin_motion(profile: &cell_profiles::MachineProfile) -> cell_profiles::FirmwareMotion {
    profile
        .gcode
        .as_ref()
        .and_then(|g| g.extrusion.as_ref()?.motion)
        .unwrap_or(cell_profiles::FirmwareMotion::MARLIN_2_DEFAULTS)
}

/// The AVL files in `report.json`.
#[derive(Debug, Serialize)]
struct AvlFiles {
    /// As built: airfoil camber (`AFILE`), Ainc = LLT α + α_L0.
    geometry: String,
    /// Flat camber lines, Ainc = LLT α from the zero-lift line.
    zero_lift_line: String,
    /// The airfoil coordinates `geometry` reads.
    airfoil: String,
}

/// Writes the AVL files of [`AvlFiles`] into `dir`.
fn write_avl(
    wing: &cell_wing::spec::Wing,
    dir: &std::path::Path,
    stem: &str,
) -> Result<AvlFiles, String> {
    use cell_wing::avl::{afile_dat, geometry, AvlOptions, AvlWing, Camber};
    let files = AvlFiles {
        geometry: format!("{stem}.avl"),
        zero_lift_line: format!("{stem}-flat.avl"),
        airfoil: format!(
            "{}.dat",
            cell_emitter::file_stem(
                &wing
                    .spec
                    .airfoil
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "airfoil".into())
            )
        ),
    };
    let avl = AvlWing::of(wing);
    for (file, camber) in [
        (
            &files.geometry,
            Camber::Airfoil {
                afile: files.airfoil.clone(),
            },
        ),
        (&files.zero_lift_line, Camber::ZeroLiftLine),
    ] {
        let options = AvlOptions {
            title: format!("{stem} (cell wing)"),
            camber,
            ..AvlOptions::default()
        };
        let text = geometry(&avl, &options).map_err(|e| e.to_string())?;
        cell_emitter::program::write_atomically(&dir.join(file), &text)
            .map_err(|e| e.to_string())?;
    }
    cell_emitter::program::write_atomically(&dir.join(&files.airfoil), &afile_dat(&wing.airfoil))
        .map_err(|e| e.to_string())?;
    Ok(files)
}

/// `report.json`.
#[derive(Debug, Serialize)]
struct Report {
    config: String,
    airfoil: String,
    profile: String,
    span_mm: f64,
    c_l: f64,
    /// The design case, its solved planform and each condition, requested against achieved.
    design: cell_wing::design::DesignReport,
    sections_in_design: usize,
    /// The whole wing's OpenSCAD model.
    scad: String,
    /// The AVL geometry files.
    avl: AvlFiles,
    /// The planform picture.
    planform_svg: String,
    layers_limit: usize,
    sections: Vec<SectionReport>,
    total_mass_g: f64,
    total_build_time_s: f64,
}

/// Runs `cell wing`.
pub fn run(a: WingArgs) -> ExitCode {
    let profile = match crate::emit::program_profile("--profile", &a.profile) {
        Ok(p) if p.gcode.as_ref().is_some_and(|g| g.extrusion.is_some()) => p,
        Ok(p) => {
            return usage(format!(
                "--profile {}: not an extrusion profile (no gcode.extrusion section)",
                p.name
            ))
        }
        Err(e) => return usage(e),
    };
    let spec = match WingSpec::load(&a.config) {
        Ok(s) => s,
        Err(e) => return bad_data(e),
    };
    let wing = match Wing::design(spec) {
        Ok(w) => w,
        Err(e) => return bad_data(format!("{}: {e}", a.config.display())),
    };
    let chosen: Vec<usize> = if a.sections.is_empty() {
        (0..wing.sections.len()).collect()
    } else {
        a.sections.clone()
    };
    if let Some(bad) = chosen.iter().find(|&&i| i >= wing.sections.len()) {
        return usage(format!(
            "--sections {bad}: the design has {} sections (0..{})",
            wing.sections.len(),
            wing.sections.len().saturating_sub(1)
        ));
    }
    if let Err(e) = std::fs::create_dir_all(&a.out) {
        return failure(format!("--out {}: {e}", a.out.display()));
    }
    let stem = cell_emitter::file_stem(
        &a.config
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "wing".into()),
    );
    let bp = wing.spec.build_params();
    let bar = indicatif::ProgressBar::new(chosen.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} sections {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut sections = Vec::new();
    for &i in &chosen {
        let section = wing.sections[i];
        let Some(mut layers) = wing.layers(i) else {
            continue;
        };
        if a.layers > 0 {
            layers.truncate(a.layers);
        }
        let job_id = format!("{stem}-{}-{}", side_name(section.side), section.index);
        bar.set_message(format!("{job_id}: {} layers", layers.len()));
        let toolpath = cell_wing::msg::toolpath(&layers, &bp, &job_id);
        let program = match cell_emitter::emit_program(&toolpath, &profile, &job_id) {
            Ok(p) => p,
            Err(e) => {
                bar.abandon();
                return bad_data(format!("{}: {job_id}: {e}", a.config.display()));
            }
        };
        let Some(file) = program.files.first() else {
            return failure("the emitter wrote no file");
        };
        if let Err(e) = cell_emitter::program::write_atomically(&a.out.join(&file.name), &file.text)
        {
            bar.abandon();
            return failure(e);
        }
        let scad = format!("{job_id}.scad");
        if let Some(text) = cell_wing::scad::section_scad(&wing, i) {
            if let Err(e) = cell_emitter::program::write_atomically(&a.out.join(&scad), &text) {
                bar.abandon();
                return failure(e);
            }
        }
        let Some(figures) = SectionFigures::of(&wing, i, &layers) else {
            continue;
        };
        sections.push(SectionReport {
            figures,
            program: file.name.clone(),
            program_lines: program.line_count,
            scad,
            times: SectionTimes::of(&layers, &wing, &profile, &file.text),
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let scad = format!("{stem}.scad");
    let text = cell_wing::scad::wing_scad(&wing);
    if let Err(e) = cell_emitter::program::write_atomically(&a.out.join(&scad), &text) {
        return failure(e);
    }
    let avl = match write_avl(&wing, &a.out, &stem) {
        Ok(files) => files,
        Err(e) => return failure(e),
    };
    let planform_svg = format!("{stem}-planform.svg");
    let picture = cell_wing::picture::planform_svg(&wing, &stem);
    if let Err(e) = cell_emitter::program::write_atomically(&a.out.join(&planform_svg), &picture) {
        return failure(e);
    }
    let report = Report {
        config: a.config.display().to_string(),
        airfoil: wing.spec.airfoil.display().to_string(),
        profile: profile.name.clone(),
        span_mm: wing.spec.aero.span_mm,
        c_l: wing.aero.c_l,
        design: wing.design_report(),
        sections_in_design: wing.sections.len(),
        scad,
        avl,
        planform_svg,
        layers_limit: a.layers,
        total_mass_g: sections.iter().map(|s| s.figures.mass_g).sum(),
        total_build_time_s: sections.iter().map(|s| s.figures.build_time_s).sum(),
        sections,
    };
    let text = match serde_json::to_string_pretty(&report) {
        Ok(t) => t,
        Err(e) => return failure(format!("report.json: {e}")),
    };
    if let Err(e) = cell_emitter::program::write_atomically(&a.out.join("report.json"), &text) {
        return failure(e);
    }
    for line in report.design.lines() {
        println!("{line}");
    }
    println!(
        "cell wing: {} of {} sections, {:.1} g, {:.0} min printing (no acceleration); wrote {} \
         programs, their OpenSCAD models, {}, {}, {} and report.json to {}",
        report.sections.len(),
        report.sections_in_design,
        report.total_mass_g,
        report.total_build_time_s / 60.0,
        report.sections.len(),
        report.scad,
        report.avl.geometry,
        report.planform_svg,
        a.out.display()
    );
    ExitCode::SUCCESS
}
