//! `cell hotwire`: plan one hot-wire cut on the spot, without DDS, and write the trajectory and
//! a report.
//!
//! Writes `DIR/trajectory.csv` (`x_mm,y_mm,feed_mm_s,current_a`: lead-in, the closed cut,
//! lead-out, in machine order; the u,v tip columns come with root/tip synchronisation) and
//! `DIR/report.json` (baseline and optimised exposure statistics, loss, run data).

use std::{fmt::Write as _, ops::ControlFlow, path::PathBuf, process::ExitCode};

use cell_planner::{
    job::{self, AirfoilSource, ExposureStats, HotwireJob, HotwirePlan},
    pso::PsoConfig,
};
use clap::Args;
use serde::Serialize;

/// `cell hotwire` options.
#[derive(Args, Debug)]
pub struct HotwireArgs {
    /// Airfoil: an embedded name (e.g. s1223) or a UIUC .dat file.
    #[arg(long, value_name = "NAME|FILE")]
    pub airfoil: String,
    /// Chord [mm].
    #[arg(long, value_name = "MM")]
    pub chord: f64,
    /// Foam id from the material library (e.g. eps_h_grade, xps).
    #[arg(long, value_name = "NAME")]
    pub material: Option<String>,
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
    /// Chord [mm].
    pub chord_mm: f64,
    /// Foam id.
    pub material: String,
    /// Wire offset used [mm].
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
    /// Optimiser wall time [s].
    pub seconds: f64,
    /// RNG seed.
    pub seed: u64,
    /// Fallbacks and warnings.
    pub notes: Vec<String>,
}

fn usage(message: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(cell_runtime::EXIT_USAGE)
}

/// The job the options ask for.
pub fn job_from_args(a: &HotwireArgs) -> HotwireJob {
    let defaults = HotwireJob::default();
    HotwireJob {
        root_airfoil: AirfoilSource::parse(&a.airfoil),
        chord_mm: a.chord,
        material: a.material.clone().unwrap_or(defaults.material.clone()),
        panels: a.panels.unwrap_or(defaults.panels),
        pso: PsoConfig {
            iterations: a.iterations.unwrap_or(defaults.pso.iterations),
            particles: a.particles.unwrap_or(defaults.pso.particles),
            ..defaults.pso
        },
        seed: a.seed,
        ..defaults
    }
}

/// The trajectory CSV: lead-in, cut, lead-out. Where one part ends on the point the next begins
/// with, the point is written once (a repeated row is a zero-length move for a controller).
pub fn trajectory_csv(plan: &HotwirePlan) -> String {
    let mut out = String::from("x_mm,y_mm,feed_mm_s,current_a\n");
    let (f, a) = (plan.lead_feed_mm_s, plan.lead_current_a);
    let lead_in = plan.lead_in.iter().map(|p| (p, f, a));
    let cut = plan
        .optimised
        .iter()
        .zip(plan.feed_mm_s.iter().zip(&plan.current_a))
        .map(|(p, (&f, &a))| (p, f, a));
    let lead_out = plan.lead_out.iter().map(|p| (p, f, a));
    let mut previous = None;
    for (p, f, a) in lead_in.chain(cut).chain(lead_out) {
        if previous == Some(*p) {
            continue;
        }
        previous = Some(*p);
        let _ = writeln!(out, "{:.6},{:.6},{f:.4},{a:.4}", p.x, p.y);
    }
    out
}

/// Runs `cell hotwire`.
pub fn run(a: HotwireArgs) -> ExitCode {
    let job = job_from_args(&a);
    if let Err(e) = job::validate(&job) {
        let flag = match &e {
            job::JobError::InvalidParameter {
                name: "chord_mm", ..
            } => "--chord",
            job::JobError::InvalidParameter { name: "panels", .. } => "--panels",
            _ => "",
        };
        return usage(format!(
            "{flag}{}{e}",
            if flag.is_empty() { "" } else { ": " }
        ));
    }
    if let Err(e) = job.pso.validate() {
        return usage(format!("--particles: {e}"));
    }
    if let Err(e) = job.root_airfoil.load() {
        return usage(format!("--airfoil: {e}"));
    }
    if let Err(e) = std::fs::create_dir_all(&a.out) {
        return usage(format!("--out {}: {e}", a.out.display()));
    }
    let bar = indicatif::ProgressBar::new(job.pso.iterations as u64);
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
        Err(e) => return usage(format!("--airfoil {}: {e}", a.airfoil)),
    };
    let report = Report {
        airfoil: a.airfoil.clone(),
        airfoil_name: plan.airfoil.clone(),
        chord_mm: job.chord_mm,
        material: job.material.clone(),
        offset_mm: plan.offset_mm,
        cse: plan.cse,
        baseline: plan.baseline_stats,
        optimised: plan.optimised_stats,
        baseline_loss: plan.baseline_loss,
        final_loss: plan.final_loss,
        iterations: plan.iterations,
        seconds: plan.seconds,
        seed: plan.seed,
        notes: plan.notes.clone(),
    };
    let json = match serde_json::to_string_pretty(&report) {
        Ok(j) => j,
        Err(e) => return usage(format!("report: {e}")),
    };
    for (name, text) in [
        ("trajectory.csv", trajectory_csv(&plan)),
        ("report.json", json + "\n"),
    ] {
        let path = a.out.join(name);
        if let Err(e) = std::fs::write(&path, text) {
            return usage(format!("--out: cannot write {}: {e}", path.display()));
        }
    }
    for note in &plan.notes {
        eprintln!("note: {note}");
    }
    println!(
        "cell hotwire: {} at {} mm: RMS {:.4} -> {:.4}, CV {:.4} -> {:.4} ({} iterations, {:.1} s); wrote {}",
        plan.airfoil,
        job.chord_mm,
        plan.baseline_stats.rms,
        plan.optimised_stats.rms,
        plan.baseline_stats.cv,
        plan.optimised_stats.cv,
        plan.iterations,
        plan.seconds,
        a.out.display()
    );
    ExitCode::SUCCESS
}
