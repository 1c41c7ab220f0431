//! `cell slice`: slice a part for wire-arc additive manufacturing on the spot, without DDS
//! (seed 004; issue 8): read an STL, slice it into layer contours, plan the beads of every
//! layer with a WAAM process profile, and write into `--out`:
//!
//! - `layers.json`: the `cell_msgs/LayerStack` (per layer: z and the closed contours) as JSON;
//! - the RAPID program for `--profile` (through [`cell_emitter`]): the main module
//!   `WAAM_<job>.mod`, part modules when the program is split, and `WAAM_<job>.pgf`, each under
//!   its own name (the controller wants a module's file named like the module, and the `.pgf`
//!   lists them by name); a G-code profile writes `program.ngc` instead;
//! - `report.json`: layers, contours, deposited volume and mass, arc-on, travel and dwell
//!   times, the cost breakdown (seed 004 eq. 1–6, 20–23), the mesh diagnostics and warnings,
//!   the program's files and per-layer figures ([`cell_slicer::job::SliceReport`] plus
//!   `program`);
//! - `stock.stl`: the stock model, every deposited piece as a box (seed 004 §4.8);
//! - with `--rows`, `rows.csv`: the thesis's toolpath rows `[X Y Z E C N LW/2 h k]`.
//! - `slice.svg`: layer `--picture-layer` (default the middle one) in plan and a side section
//!   through the part's centre, with the part, the beads and the machining allowance
//!   ([`cell_slicer::picture`]).
//!
//! The part is put on the plate (bounding-box bottom at z = 0, centred on the machine's X/Y
//! travel) unless `--as-is`. A progress bar counts the planned layers.
//!
//! Exit status: 0 written; 64 a bad command line (a layer height ≤ 0, an unknown profile or
//! one that takes no programs); 65 a mesh or process file that cannot be read or is invalid
//! (the message names the file) or a toolpath the emitter refuses; 1 the output cannot be
//! written.

use std::{path::PathBuf, process::ExitCode};

use cell_slicer::job::{self, PartSource, SliceJob};
use cell_slicer::to_msg::layer_stack_msg;
use clap::Args;
use slicer::{cap_speeds, placement_for, FRAME_ID};

use crate::exit::{bad_data, failure, usage};
use serde::Serialize;

/// `cell slice` options.
#[derive(Args, Debug)]
pub struct SliceArgs {
    /// The part: an STL file (ASCII or binary, mm).
    #[arg(long, value_name = "FILE")]
    pub stl: PathBuf,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// WAAM process profile: `waam` (the built-in config/processes/waam.yaml) or a YAML file.
    #[arg(long, default_value = "waam", value_name = "waam|FILE.yaml")]
    pub process: String,
    /// Layer height in mm; default: the process profile's.
    #[arg(long, value_name = "MM")]
    pub layer_height: Option<f64>,
    /// Machine profile for the program: a name under config/machines or a YAML file.
    #[arg(long, default_value = "abb-irb2600-waam", value_name = "NAME|FILE")]
    pub profile: String,
    /// Job id for the program's names (default: the STL's file stem).
    #[arg(long, value_name = "ID")]
    pub job_id: Option<String>,
    /// Keep the STL's coordinates instead of putting the part on the plate.
    #[arg(long)]
    pub as_is: bool,
    /// Also write rows.csv, the thesis's toolpath rows.
    #[arg(long)]
    pub rows: bool,
    /// Layer drawn in slice.svg (with a side section through the part's centre); default:
    /// the middle layer.
    #[arg(long, value_name = "N")]
    pub picture_layer: Option<usize>,
}

/// `report.json`: the job's report and the program written.
#[derive(Debug, Serialize)]
struct Report<'a> {
    #[serde(flatten)]
    report: &'a job::SliceReport,
    profile: &'a str,
    job_id: &'a str,
    program: ProgramSummary,
}

/// The program's files and size.
#[derive(Debug, Serialize)]
struct ProgramSummary {
    dialect: String,
    files: Vec<String>,
    lines: u32,
    sha256: String,
}

/// Writes `bytes` to `path` through a temporary file and a rename (no half-written file).
fn write_bytes(path: &std::path::Path, bytes: &[u8]) -> Result<(), String> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Runs `cell slice`.
pub fn run(a: SliceArgs) -> ExitCode {
    if let Some(h) = a.layer_height {
        if !(h.is_finite() && h > 0.0) {
            return usage(format!("--layer-height {h}: must be finite and > 0"));
        }
    }
    let profile = match crate::emit::program_profile("--profile", &a.profile) {
        Ok(p) => p,
        Err(e) => return usage(e),
    };
    let (process, process_name) = match job::load_process(&a.process) {
        Ok(p) => p,
        Err(e) => return bad_data(format!("--process: {e}")),
    };
    let slice_job = SliceJob {
        part: PartSource::Stl(a.stl.clone()),
        process,
        process_name,
        layer_height_mm: a.layer_height,
        placement: placement_for(&profile, !a.as_is),
    };
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {elapsed} [{bar:30}] {pos}/{len} layers {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let outcome = job::run(&slice_job, |p| {
        bar.set_length(p.layers_total as u64);
        bar.set_position(p.layers_done as u64);
        bar.set_message(p.phase.name());
    });
    bar.finish_and_clear();
    let mut out = match outcome {
        Ok(o) => o,
        Err(e) => return bad_data(e),
    };
    let capped = cap_speeds(&mut out.layers, profile.max_feed_mm_s);
    if capped > 0 {
        out.report.warnings.push(format!(
            "{capped} points slowed to the machine's {} mm/s",
            profile.max_feed_mm_s
        ));
    }
    for w in &out.report.warnings {
        eprintln!("warning: {w}");
    }
    let job_id = cell_emitter::file_stem(&a.job_id.clone().unwrap_or_else(|| {
        a.stl
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "part".into())
    }));
    // The torch pose and tool point height of the process (issue 20 item 5).
    let toolpath = cell_waam::to_msg::toolpath_msg_for(
        &out.layers,
        &slice_job.process.torch,
        out.report.layer_height_mm,
        &job_id,
        FRAME_ID,
    );
    let program = match cell_emitter::emit_program(&toolpath, &profile, &job_id) {
        Ok(p) => p,
        Err(e) => return bad_data(format!("{}: {e}", a.stl.display())),
    };
    let stack = layer_stack_msg(&out.stack, &job_id, FRAME_ID);
    if let Err(e) = std::fs::create_dir_all(&a.out) {
        return failure(format!("--out {}: {e}", a.out.display()));
    }
    let mut files: Vec<(String, String)> = Vec::new();
    if profile.rapid.is_some() {
        files.extend(
            program
                .files
                .iter()
                .map(|f| (f.name.clone(), f.text.clone())),
        );
    } else if let Some(f) = program.files.first() {
        files.push(("program.ngc".into(), f.text.clone()));
    }
    let report = Report {
        report: &out.report,
        profile: &profile.name,
        job_id: &job_id,
        program: ProgramSummary {
            dialect: program.dialect.clone(),
            files: files.iter().map(|(n, _)| n.clone()).collect(),
            lines: program.line_count,
            sha256: program.sha256.clone(),
        },
    };
    for (name, text) in [
        ("layers.json", serde_json::to_string_pretty(&stack)),
        ("report.json", serde_json::to_string_pretty(&report)),
    ] {
        match text {
            Ok(t) => files.push((name.into(), t)),
            Err(e) => return failure(format!("{name}: {e}")),
        }
    }
    // slice.svg: one layer and a side section with the part, beads and allowance (issue 20).
    match cell_slicer::picture::slice_svg(
        &out.stack,
        &out.layers,
        out.report.machining_allowance_mm,
        a.picture_layer,
    ) {
        Ok(svg) => files.push(("slice.svg".into(), svg)),
        Err(e @ cell_slicer::picture::PictureError::NoSuchLayer { .. }) => {
            return usage(e.to_string())
        }
        Err(e) => eprintln!("warning: slice.svg not written: {e}"),
    }
    if a.rows {
        match String::from_utf8(out.rows_csv()) {
            Ok(t) => files.push(("rows.csv".into(), t)),
            Err(e) => return failure(format!("rows.csv: {e}")),
        }
    }
    for (name, text) in &files {
        if let Err(e) = cell_emitter::program::write_atomically(&a.out.join(name), text) {
            return failure(e);
        }
    }
    if let Err(e) = write_bytes(&a.out.join("stock.stl"), &out.stock_stl()) {
        return failure(e);
    }
    let r = &out.report;
    println!(
        "cell slice: {} layers of {} mm, {} contours, {:.0} mm³ ({:.3} kg) deposited, {:.0} s arc \
         on + {:.0} s travel, {:.0} SEK, {} warnings; wrote {}/{{{},stock.stl}}",
        r.layers,
        r.layer_height_mm,
        r.contours,
        r.deposited_volume_mm3,
        r.deposited_mass_kg,
        r.deposition_time_s,
        r.travel_time_s,
        r.cost.total_sek,
        r.warnings.len(),
        a.out.display(),
        files
            .iter()
            .map(|(n, _)| n.as_str())
            .collect::<Vec<_>>()
            .join(",")
    );
    ExitCode::SUCCESS
}
