//! `cell hotwire`: plan one hot-wire cut on the spot, without DDS, and write the trajectory and
//! a report.
//!
//! Writes `DIR/trajectory.csv` (`x_mm,y_mm[,u_mm,v_mm],feed_mm_s,current_a`: the carriage
//! positions in machine coordinates for lead-in, the closed cut and lead-out, in machine
//! order; u,v on a 4-axis machine), `DIR/report.json` (baseline and optimised exposure
//! statistics of the root and, on a tapered panel, the tip; loss; run data) and
//! `DIR/toolpath.json` (the plan's `Toolpath` message as JSON, what `cell emit --toolpath`
//! reads) and `DIR/exposure.svg` (the plan drawn: foil, baseline and optimised paths with the
//! leads, the wire's distance from the foil and the exposure per panel before and after
//! against the CSE; [`job::exposure_svg`]).
//!
//! With `--profile NAME`, also the machine program for that profile through
//! [`cell_emitter::emit_program`]: `DIR/program.ngc` for G-code, or the RAPID files under their
//! own names. The planning machine is `--machine`; without it, `--profile` (which must then
//! be a hot-wire machine), else `linuxcnc-xyuv`. So `--profile grbl-xy` plans and emits for
//! grbl-xy, and `--machine linuxcnc-xyuv --profile my-controller.yaml` plans on one profile's
//! geometry and writes G-code for another's controller (its travel is checked again).

use std::{fmt::Write as _, ops::ControlFlow, path::PathBuf, process::ExitCode};

use cell_planner::{
    calibration,
    job::{
        self, AirfoilSource, ExposureStats, HotwireJob, HotwirePlan, JobParameter, TipRequest,
        TipSection,
    },
    kerf::MaterialLibrary,
    pso::PsoConfig,
};
use cell_profiles::MachineProfile;
use clap::Args;

use crate::exit::{failure, usage};
use serde::Serialize;

/// The current band `--vary-current` allows, as fractions of the nominal current.
const VARIED_CURRENT_BAND: (f64, f64) = (0.7, 1.3);

/// `cell hotwire` options.
#[derive(Args, Debug)]
pub struct HotwireArgs {
    /// Airfoil: an embedded name (e.g. s1223) or a UIUC .dat file.
    #[arg(long, value_name = "NAME|FILE")]
    pub airfoil: String,
    /// Chord (mm).
    #[arg(long, value_name = "MM")]
    pub chord: f64,
    /// Tip airfoil of a tapered panel (default: the root's); needs a 4-axis machine.
    #[arg(long, value_name = "NAME|FILE")]
    pub tip: Option<String>,
    /// Tip chord (mm) (default: the root chord).
    #[arg(long, value_name = "MM")]
    pub tip_chord: Option<f64>,
    /// Tip twist (deg), positive nose up, about --twist-pivot.
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub tip_twist: Option<f64>,
    /// Tip leading-edge sweep (mm), positive swept back.
    #[arg(long, value_name = "MM", allow_hyphen_values = true)]
    pub tip_sweep: Option<f64>,
    /// Twist pivot as a fraction of the tip chord from its LE.
    #[arg(long, value_name = "F", default_value_t = 0.25)]
    pub twist_pivot: f64,
    /// Panel span between the root and tip faces (mm).
    #[arg(long, value_name = "MM")]
    pub span: Option<f64>,
    /// Machine profile to plan on (geometry, travel, feed limit, wire): a name under
    /// config/machines (linuxcnc-xyuv, grbl-xy, …) or a YAML file (default: --profile if
    /// given, else linuxcnc-xyuv).
    #[arg(long, value_name = "NAME|FILE")]
    pub machine: Option<String>,
    /// Also write the machine program for this profile: DIR/program.ngc for G-code, or the
    /// RAPID files under their own names. Without --machine it is the planning machine too,
    /// so it must then be a hot-wire machine.
    #[arg(long, value_name = "NAME|FILE")]
    pub profile: Option<String>,
    /// Foam name or alias from the material library (e.g. EPS, XPS, eps_s_grade).
    #[arg(long, value_name = "NAME")]
    pub material: Option<String>,
    /// Target exposure CSE (default: the baseline's mean exposure).
    #[arg(long, value_name = "E")]
    pub cse: Option<f64>,
    /// Cutting feed of the faster foam face (mm/s).
    #[arg(long, value_name = "MM_S")]
    pub feed: Option<f64>,
    /// Keep the feed constant along the path (the paper's experiments) instead of making it a
    /// design variable (the default: 0.5–1.5 × --feed within the machine's feed limit, at
    /// constant current; slower where the surface needs more heat).
    #[arg(long)]
    pub constant_feed: bool,
    /// Length of the straight lead-in behind the trailing edge (mm).
    #[arg(long, value_name = "MM")]
    pub lead_in: Option<f64>,
    /// Let the optimiser lengthen the lead-in up to this (mm): more heat on the first panels
    /// cut; the block needs that much foam behind the trailing edge.
    #[arg(long, value_name = "MM")]
    pub lead_in_max: Option<f64>,
    /// Let the wire current vary along the path too (0.7–1.3 × the nominal, within the
    /// supply), where the feed alone cannot give the heat the surface needs.
    #[arg(long, conflicts_with = "constant_feed")]
    pub vary_current: bool,
    /// Accepted for older scripts: the feed is a design variable by default now.
    #[arg(long, hide = true)]
    pub optimise_feed: bool,
    /// CSE values for the calibration table in report.json (seed 000 §IV.D; default: 0.5 to
    /// 1.5 times the plan's CSE in 11 steps).
    #[arg(long, value_name = "CSE,…", value_delimiter = ',')]
    pub calibrate: Vec<f64>,
    /// Chord (mm) measured on a test cut of the fixed-offset (baseline) path: reports the CSE
    /// it implies from the calibration table.
    #[arg(long, value_name = "MM")]
    pub test_cut_chord: Option<f64>,
    /// PSO iterations (default: the paper's 8000).
    #[arg(long, value_name = "N")]
    pub iterations: Option<usize>,
    /// Surface panels of the exposure model.
    #[arg(long, value_name = "N")]
    pub panels: Option<usize>,
    /// PSO particles.
    #[arg(long, value_name = "N")]
    pub particles: Option<usize>,
    /// RNG seed; the same seed gives the same trajectory.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// `report.json`.
#[derive(Debug, Serialize)]
pub struct Report {
    /// The airfoil as given.
    pub airfoil: String,
    /// The section's name from its file.
    pub airfoil_name: String,
    /// Chord (mm).
    pub chord_mm: f64,
    /// Foam id.
    pub material: String,
    /// Wire offset used (mm).
    pub offset_mm: f64,
    /// Exposure target.
    pub cse: f64,
    /// Baseline (fixed offset) exposure statistics.
    pub baseline: ExposureStats,
    /// Optimised exposure statistics.
    pub optimised: ExposureStats,
    /// Loss of the baseline.
    pub baseline_loss: f64,
    /// Loss of the optimised path.
    pub final_loss: f64,
    /// Iterations run.
    pub iterations: usize,
    /// Optimiser wall time (s).
    pub seconds: f64,
    /// RNG seed.
    pub seed: u64,
    /// Machine profile name.
    pub machine: String,
    /// Predicted root chord for each material CSE, for the baseline and the optimised path.
    pub calibration: Vec<job::CalibrationRow>,
    /// The CSE a measured test-cut chord (`--test-cut-chord`) implies, if within the table.
    pub estimated_cse: Option<f64>,
    /// The tip section of a tapered panel.
    pub tip: Option<TipReport>,
    /// Fallbacks and warnings.
    pub notes: Vec<String>,
}

/// The tip section's part of `report.json`.
#[derive(Debug, Serialize)]
pub struct TipReport {
    /// The section's name from its file.
    pub airfoil_name: String,
    /// Chord (mm).
    pub chord_mm: f64,
    /// Wire offset of its baseline (mm).
    pub offset_mm: f64,
    /// Exposure target.
    pub cse: f64,
    /// Baseline exposure statistics.
    pub baseline: ExposureStats,
    /// Optimised exposure statistics (along the synchronised path).
    pub optimised: ExposureStats,
}

/// The planning machine's profile name and the flag it came from: `--machine`, else
/// `--profile`, else the default machine.
pub fn planning_machine(a: &HotwireArgs) -> (&str, &'static str) {
    match (&a.machine, &a.profile) {
        (Some(m), _) => (m, "--machine"),
        (None, Some(p)) => (p, "--profile"),
        (None, None) => (job::DEFAULT_MACHINE, "--machine"),
    }
}

/// The option a job parameter comes from; `None` for one `cell hotwire` has no option for (it
/// keeps the job's default). Exhaustive, so a new parameter needs a decision here.
pub fn flag_for(parameter: JobParameter) -> Option<&'static str> {
    match parameter {
        JobParameter::ChordMm => Some("--chord"),
        JobParameter::Panels => Some("--panels"),
        JobParameter::SpanMm => Some("--span"),
        JobParameter::FeedMmS => Some("--feed"),
        JobParameter::Cse => Some("--cse"),
        JobParameter::TipChordMm => Some("--tip-chord"),
        JobParameter::TipTwistDeg => Some("--tip-twist"),
        JobParameter::TipSweepMm => Some("--tip-sweep"),
        JobParameter::TwistPivotChordFraction => Some("--twist-pivot"),
        JobParameter::LeadInMm => Some("--lead-in"),
        JobParameter::LeadInMaxMm => Some("--lead-in-max"),
        JobParameter::Particles => Some("--particles"),
        JobParameter::Iterations => Some("--iterations"),
        JobParameter::CurrentA
        | JobParameter::OffsetMm
        | JobParameter::PathPoints
        | JobParameter::ControlPoints
        | JobParameter::RefineIterations => None,
    }
}

/// The option a rejected job's error points at: the parameter's option, or the flag the
/// planning machine came from (`--machine` or `--profile`) when the machine cannot run the job.
fn flag_of(e: &job::JobError, a: &HotwireArgs) -> Option<&'static str> {
    match e {
        job::JobError::InvalidParameter { parameter, .. } => flag_for(*parameter),
        job::JobError::Machine { .. } => Some(planning_machine(a).1),
        _ => None,
    }
}

/// The job the options ask for.
///
/// # Errors
/// The machine profile does not resolve (the message names it and its flag).
pub fn job_from_args(a: &HotwireArgs) -> Result<HotwireJob, String> {
    let defaults = HotwireJob::default();
    let (machine, flag) = planning_machine(a);
    let machine = MachineProfile::resolve(machine).map_err(|e| format!("{flag}: {e}"))?;
    let root_airfoil = AirfoilSource::parse(&a.airfoil);
    let request = TipRequest {
        airfoil: a.tip.as_deref(),
        chord_mm: a.tip_chord,
        twist_deg: a.tip_twist,
        sweep_mm: a.tip_sweep,
    };
    let tip = TipSection::requested(&request, &root_airfoil, a.chord, a.twist_pivot);
    Ok(HotwireJob {
        root_airfoil,
        chord_mm: a.chord,
        tip,
        span_mm: a.span.unwrap_or(defaults.span_mm),
        machine,
        material: a.material.clone().unwrap_or(defaults.material.clone()),
        cse: a.cse,
        feed_mm_s: a.feed.unwrap_or(defaults.feed_mm_s),
        lead_in_mm: a.lead_in.unwrap_or(defaults.lead_in_mm),
        lead_in_max_mm: a.lead_in_max,
        panels: a.panels.unwrap_or(defaults.panels),
        objective: cell_planner::pso::Objective {
            feed: (!a.constant_feed).then(|| {
                let feed = cell_planner::pso::FeedVariable::default();
                if a.vary_current {
                    feed.with_current_band(VARIED_CURRENT_BAND)
                } else {
                    feed
                }
            }),
            ..defaults.objective
        },
        pso: PsoConfig {
            iterations: a.iterations.unwrap_or(defaults.pso.iterations),
            particles: a.particles.unwrap_or(defaults.pso.particles),
            ..defaults.pso
        },
        seed: a.seed,
        ..defaults
    })
}

/// The trajectory CSV: carriage positions of lead-in, cut and lead-out, with u,v on a 4-axis
/// machine. Where one part ends on the point the next begins with, the point is written once
/// (a repeated row is a zero-length move for a controller).
pub fn trajectory_csv(plan: &HotwirePlan) -> String {
    let mut out = String::from(if plan.four_axis {
        "x_mm,y_mm,u_mm,v_mm,feed_mm_s,current_a\n"
    } else {
        "x_mm,y_mm,feed_mm_s,current_a\n"
    });
    let mut previous = None;
    for m in [&plan.lead_in, &plan.cut, &plan.lead_out] {
        for k in 0..m.len() {
            let (xy, uv) = (m.xy[k], m.uv[k]);
            if previous == Some((xy, uv)) {
                continue;
            }
            previous = Some((xy, uv));
            let (f, a) = (m.feed_mm_s[k], m.current_a[k]);
            let _ = if plan.four_axis {
                writeln!(
                    out,
                    "{:.6},{:.6},{:.6},{:.6},{f:.4},{a:.4}",
                    xy.x, xy.y, uv.x, uv.y
                )
            } else {
                writeln!(out, "{:.6},{:.6},{f:.4},{a:.4}", xy.x, xy.y)
            };
        }
    }
    out
}

/// Runs `cell hotwire`.
pub fn run(a: HotwireArgs) -> ExitCode {
    let job = match job_from_args(&a) {
        Ok(job) => job,
        Err(e) => return usage(e),
    };
    if let Err(e) = job::validate(&job) {
        return match flag_of(&e, &a) {
            Some(flag) => usage(format!("{flag}: {e}")),
            None => usage(e),
        };
    }
    if let Err(e) = job.pso.validate() {
        return usage(format!("--particles: {e}"));
    }
    if let Err(e) = job.root_airfoil.load() {
        return usage(format!("--airfoil: {e}"));
    }
    if let Some(t) = &job.tip {
        if let Err(e) = t.airfoil.load() {
            return usage(format!("--tip: {e}"));
        }
    }
    let program_profile = match a
        .profile
        .as_deref()
        .map(|p| crate::emit::program_profile("--profile", p))
        .transpose()
    {
        Ok(p) => p,
        Err(e) => return usage(e),
    };
    if let Err(e) = std::fs::create_dir_all(&a.out) {
        return usage(format!("--out {}: {e}", a.out.display()));
    }
    let sections = if job.tip.is_some() { 2 } else { 1 };
    let bar = indicatif::ProgressBar::new((job.pso.iterations * sections) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} iterations, loss {msg}, ETA {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let planned = job::plan(&job, |p| {
        bar.set_position(p.iteration as u64);
        bar.set_message(format!("{:.4e}", p.best_loss));
        ControlFlow::Continue(())
    });
    bar.finish_and_clear();
    let plan = match planned {
        Ok(plan) => plan,
        Err(e) => return failure(e),
    };
    let cse_values = if a.calibrate.is_empty() {
        (0..=10)
            .map(|k| plan.root.cse * (0.5 + 0.1 * k as f64))
            .collect()
    } else {
        a.calibrate.clone()
    };
    let wire_radius_mm = job
        .machine
        .hotwire
        .as_ref()
        .and_then(|h| MaterialLibrary::builtin().find_wire(&h.wire).cloned())
        .map_or(0.18, |w| w.diameter_m / 2.0 * 1e3);
    let calibration = match plan.chord_predictions(&cse_values, wire_radius_mm) {
        Ok(rows) => rows,
        Err(e) => return failure(format!("calibration: {e}")),
    };
    let baseline_rows: Vec<_> = calibration.iter().map(|r| r.baseline).collect();
    let estimated_cse = a
        .test_cut_chord
        .and_then(|c| calibration::cse_for_chord(&baseline_rows, c));
    if let (Some(c), None) = (a.test_cut_chord, estimated_cse) {
        eprintln!(
            "note: --test-cut-chord {c} mm lies outside the predicted chords of the CSE sweep; \
             widen it with --calibrate"
        );
    }
    let report = Report {
        airfoil: a.airfoil.clone(),
        airfoil_name: plan.root.airfoil.clone(),
        chord_mm: job.chord_mm,
        material: job.material.clone(),
        offset_mm: plan.root.offset_mm,
        cse: plan.root.cse,
        baseline: plan.root.baseline_stats,
        optimised: plan.root.optimised_stats,
        baseline_loss: plan.root.baseline_loss,
        final_loss: plan.root.final_loss,
        iterations: plan.iterations,
        seconds: plan.seconds,
        seed: plan.seed,
        machine: plan.machine.clone(),
        calibration,
        estimated_cse,
        tip: plan.tip.as_ref().map(|t| TipReport {
            airfoil_name: t.airfoil.clone(),
            chord_mm: t.chord_mm,
            offset_mm: t.offset_mm,
            cse: t.cse,
            baseline: t.baseline_stats,
            optimised: t.optimised_stats,
        }),
        notes: plan.notes.clone(),
    };
    let json = match serde_json::to_string_pretty(&report) {
        Ok(j) => j,
        Err(e) => return failure(format!("report: {e}")),
    };
    let job_id = job_id(&a.airfoil);
    let toolpath = plan.to_toolpath(&job_id);
    let toolpath_json = match serde_json::to_string_pretty(&toolpath) {
        Ok(j) => j,
        Err(e) => return failure(format!("toolpath: {e}")),
    };
    for (name, text) in [
        ("trajectory.csv", trajectory_csv(&plan)),
        ("report.json", json + "\n"),
        ("toolpath.json", toolpath_json + "\n"),
        (
            "exposure.svg",
            job::exposure_svg(&plan, Some(job.objective.min_clearance_mm)),
        ),
    ] {
        let path = a.out.join(name);
        if let Err(e) = std::fs::write(&path, text) {
            return failure(format!("--out: cannot write {}: {e}", path.display()));
        }
    }
    for note in &plan.notes {
        eprintln!("note: {note}");
    }
    let program = match &program_profile {
        Some(profile) => match write_program(&toolpath, profile, &job_id, &a.out) {
            Ok(line) => Some(line),
            Err(e) => return failure(e),
        },
        None => None,
    };
    if let (Some(chord), Some(cse)) = (a.test_cut_chord, report.estimated_cse) {
        println!("a {chord} mm test cut of the baseline path implies CSE ≈ {cse:.4}");
    }
    let tip = plan.tip.as_ref().map_or(String::new(), |t| {
        format!(
            "; tip {} at {} mm: RMS {:.4} -> {:.4}",
            t.airfoil, t.chord_mm, t.baseline_stats.rms, t.optimised_stats.rms
        )
    });
    println!(
        "cell hotwire: {} at {} mm: RMS {:.4} -> {:.4}, CV {:.4} -> {:.4}{tip} ({} iterations, \
         {:.1} s, machine {}); wrote {}",
        plan.root.airfoil,
        job.chord_mm,
        plan.root.baseline_stats.rms,
        plan.root.optimised_stats.rms,
        plan.root.baseline_stats.cv,
        plan.root.optimised_stats.cv,
        plan.iterations,
        plan.seconds,
        plan.machine,
        a.out.display()
    );
    println!(
        "cell hotwire: picture {}",
        a.out.join("exposure.svg").display()
    );
    if let Some(line) = program {
        println!("cell hotwire: program {line}");
    }
    ExitCode::SUCCESS
}

/// The job id of a `cell hotwire` run: `hotwire-` and the airfoil's name (a file's stem).
fn job_id(airfoil: &str) -> String {
    let name = std::path::Path::new(airfoil)
        .file_stem()
        .map_or(airfoil.into(), |s| s.to_string_lossy());
    format!("hotwire-{name}")
}

/// Emits the program for `profile` into `dir`: a single-file program (G-code) as
/// `program.<ext>`, a multi-file one (RAPID) under the files' own names. Returns the summary
/// and the files written, or one error line naming `--profile`.
fn write_program(
    toolpath: &cell_msgs::Toolpath,
    profile: &MachineProfile,
    job_id: &str,
    dir: &std::path::Path,
) -> Result<String, String> {
    let flag = format!("--profile {}", profile.name);
    let program = cell_emitter::emit_program(toolpath, profile, job_id)
        .map_err(|e| format!("{flag}: no program written: {e}"))?;
    let main = match program.files.as_slice() {
        [only] => {
            let ext = std::path::Path::new(&only.name)
                .extension()
                .map_or("ngc".into(), |e| e.to_string_lossy());
            Some(dir.join(format!("program.{ext}")))
        }
        _ => None,
    };
    let written = cell_emitter::program::write_files(&program, dir, main.as_deref())
        .map_err(|e| format!("{flag}: {e}"))?;
    let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    Ok(format!(
        "{}; wrote {}",
        cell_emitter::program::summary(&program),
        names.join(", ")
    ))
}
