//! `cell wing`: design a G-Wing wing and write its print programs on the spot, without DDS
//! (seed 002; issue 8). Reads a wing spec (`cell_wing::spec`, e.g.
//! `config/wings/gwing-table2.yaml`), runs the design (lifting line, spars, sections), and for
//! every printable section writes into `--out`:
//!
//! - `<job>.gcode`: the section's layers (perimeter, spars, first-layer rib) as a
//!   `cell_msgs/Toolpath` through [`cell_emitter`] for `--profile` (Marlin by default: E from the
//!   volumetric flow, retract and Z-hop around travel);
//! - and, once, `report.json`: the design (c_L, sections) and per section its layers, deposited
//!   volume, mass and build time (with and without acceleration).
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
    #[arg(long, value_name = "FILE")]
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
}

/// `report.json`.
#[derive(Debug, Serialize)]
struct Report {
    config: String,
    airfoil: String,
    profile: String,
    span_mm: f64,
    c_l: f64,
    sections_in_design: usize,
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
        let Some(figures) = SectionFigures::of(&wing, i, &layers) else {
            continue;
        };
        sections.push(SectionReport {
            figures,
            program: file.name.clone(),
            program_lines: program.line_count,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let report = Report {
        config: a.config.display().to_string(),
        airfoil: wing.spec.airfoil.display().to_string(),
        profile: profile.name.clone(),
        span_mm: wing.spec.aero.span_mm,
        c_l: wing.aero.c_l,
        sections_in_design: wing.sections.len(),
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
    println!(
        "cell wing: {} of {} sections, {:.1} g, {:.0} min printing (no acceleration); wrote {} \
         programs and report.json to {}",
        report.sections.len(),
        report.sections_in_design,
        report.total_mass_g,
        report.total_build_time_s / 60.0,
        report.sections.len(),
        a.out.display()
    );
    ExitCode::SUCCESS
}
