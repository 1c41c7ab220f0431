//! `cell sheet`: sequence the cut of a nested sheet on the spot, without DDS (seed 003; issue
//! 7): read a layout (`.dxf` or the JSON format of `cell_sequencer::layout`), construct the
//! order with a policy, improve it within a time budget, simulate the final plan on the
//! thermal raster, and write into `--out`:
//!
//! - `plan.json`: the `cell_msgs/CutPlan` (order, parts, pierce points, policy, lengths,
//!   overheats, max temperature, cost) as JSON;
//! - `program.ngc`: the machine program for `--profile` (through [`cell_emitter`]);
//! - `report.json`: idle and cut length, overheats, max temperature, runtime, policy and the
//!   figures of every phase (load, construction, improvement, simulation).
//!
//! A progress bar shows the phase and the best cost so far.
//!
//! Exit status: 0 written; 64 a bad command line (unknown policy, precedence or pierce mode,
//! negative seconds, a profile that takes no programs); 65 a layout that cannot be read or is
//! invalid (the message names the file and the entity or field) or a plan the emitter refuses;
//! 1 the output cannot be written.

use std::{path::PathBuf, process::ExitCode};

use cell_sequencer::{
    improve::ImproveParams,
    job::{self, LayoutSource, PierceMode, SheetJob, SheetOption, UnknownChoice},
    toolpath::{to_cut_plan_msg, to_toolpath, ToolpathOptions},
};
use clap::Args;

use crate::exit::{bad_data, failure, usage};
use serde::Serialize;

/// `cell sheet` options.
#[derive(Args, Debug)]
pub struct SheetArgs {
    /// The layout: a `.dxf` drawing or a `.json` layout (cell_sequencer's format).
    #[arg(long, value_name = "FILE")]
    pub layout: PathBuf,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Construction policy: nearest, min_overheat, random, path_overheat, cost_greedy.
    #[arg(long, default_value = "nearest")]
    pub policy: String,
    /// Precedence rules: strict (seed 003 §2) or relaxed (the paper's pseudo-code).
    #[arg(long, default_value = "strict")]
    pub precedence: String,
    /// Pierce points: fixed (one per contour) or free (candidates along each contour).
    #[arg(long, default_value = "free")]
    pub pierce: String,
    /// Skip the improvement phase.
    #[arg(long)]
    pub no_improve: bool,
    /// Time budget of the improvement phase, in seconds; 0 = iterations only (deterministic).
    #[arg(long, default_value_t = 0.0)]
    pub seconds: f64,
    /// Machine profile for the program: a name under config/machines or a YAML file.
    #[arg(long, default_value = "linuxcnc-plasma", value_name = "NAME|FILE")]
    pub profile: String,
    /// RNG seed (random policy, improvement).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// `report.json`.
#[derive(Debug, Serialize)]
struct Report<'a> {
    layout: String,
    contours: usize,
    policy: &'a str,
    precedence: &'a str,
    pierce: &'a str,
    improved: bool,
    seed: u64,
    profile: &'a str,
    idle_length_mm: f64,
    cut_length_mm: f64,
    overheats: u32,
    max_temperature_c: f64,
    cost: f64,
    simulated_time_s: f64,
    runtime_s: f64,
    phases: &'a [job::PhaseFigures],
}

/// The option of `cell sheet` a job option comes from (exhaustive: a new option needs one).
pub fn flag_for(option: SheetOption) -> &'static str {
    match option {
        SheetOption::Policy => "--policy",
        SheetOption::Precedence => "--precedence",
        SheetOption::Pierce => "--pierce",
    }
}

/// A word option that names none of its choices: `--policy "fastest": expected …`, exit 64.
fn unknown_choice(e: &UnknownChoice) -> ExitCode {
    usage(format!(
        "{} {:?}: expected {}",
        flag_for(e.option),
        e.given,
        e.choices
    ))
}

/// Runs `cell sheet`.
pub fn run(a: SheetArgs) -> ExitCode {
    let policy = match job::parse_policy(&a.policy) {
        Ok(p) => p,
        Err(e) => return unknown_choice(&e),
    };
    let precedence = match job::parse_precedence(&a.precedence) {
        Ok(p) => p,
        Err(e) => return unknown_choice(&e),
    };
    let pierce = match PierceMode::parse(&a.pierce) {
        Ok(p) => p,
        Err(e) => return unknown_choice(&e),
    };
    if !(a.seconds.is_finite() && a.seconds >= 0.0) {
        return usage(format!("--seconds {}: must be finite and ≥ 0", a.seconds));
    }
    let profile = match crate::emit::program_profile("--profile", &a.profile) {
        Ok(p) => p,
        Err(e) => return usage(e),
    };
    let sheet_job = SheetJob {
        layout: LayoutSource::File(a.layout.clone()),
        precedence,
        pierce,
        policy,
        improve: !a.no_improve,
        improve_params: ImproveParams {
            time_budget_ms: (a.seconds * 1000.0).round() as u64,
            ..Default::default()
        },
        seed: a.seed,
        ..Default::default()
    };
    if let Err(e) = std::fs::create_dir_all(&a.out) {
        return failure(format!("--out {}: {e}", a.out.display()));
    }
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    let outcome = job::run(
        &sheet_job,
        |p| {
            bar.set_message(format!(
                "{} (iteration {}), best cost {:.1}",
                p.phase.name(),
                p.iteration,
                p.best_cost
            ));
            bar.tick();
        },
        u64::MAX,
        &mut |_| {},
    );
    bar.finish_and_clear();
    let out = match outcome {
        Ok(o) => o,
        Err(e) => return bad_data(e),
    };
    let job_id = cell_emitter::file_stem(
        &a.layout
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "sheet".into()),
    );
    let t = &sheet_job.thermal;
    let opt = ToolpathOptions {
        cut_mm_s: t.cut_speed_mm_s.min(profile.max_feed_mm_s),
        rapid_mm_s: t.rapid_speed_mm_s.min(profile.max_feed_mm_s),
        power_percent: 100.0,
    };
    let toolpath = to_toolpath(&out.problem, &out.plan, &job_id, &opt);
    let plan_msg = to_cut_plan_msg(
        &out.problem,
        &out.plan,
        &job_id,
        job::policy_name(policy),
        out.improved,
        t.ambient_c,
    );
    let program = match cell_emitter::emit_program(&toolpath, &profile, &job_id) {
        Ok(p) => p,
        Err(e) => return bad_data(format!("{}: {e}", a.layout.display())),
    };
    let Some(ngc) = program.files.first() else {
        return failure("the emitter wrote no file");
    };
    let report = Report {
        layout: a.layout.display().to_string(),
        contours: out.problem.contours.len(),
        policy: job::policy_name(policy),
        precedence: &a.precedence,
        pierce: &a.pierce,
        improved: out.improved,
        seed: a.seed,
        profile: &profile.name,
        idle_length_mm: plan_msg.idle_length_mm,
        cut_length_mm: plan_msg.cut_length_mm,
        overheats: plan_msg.overheats,
        max_temperature_c: plan_msg.max_temperature_c,
        cost: plan_msg.cost,
        simulated_time_s: out.plan.time_s,
        runtime_s: out.seconds,
        phases: &out.phases,
    };
    let files = [
        ("plan.json", serde_json::to_string_pretty(&plan_msg)),
        ("report.json", serde_json::to_string_pretty(&report)),
    ];
    for (name, text) in files {
        let text = match text {
            Ok(t) => t,
            Err(e) => return failure(format!("{name}: {e}")),
        };
        if let Err(e) = cell_emitter::program::write_atomically(&a.out.join(name), &text) {
            return failure(e);
        }
    }
    if let Err(e) = cell_emitter::program::write_atomically(&a.out.join("program.ngc"), &ngc.text) {
        return failure(e);
    }
    println!(
        "cell sheet: {} contours, {} ({}), idle {:.1} mm, cut {:.1} mm, {} overheats, max {:.0} °C \
         above ambient, {:.1} s; wrote {}/{{plan.json,program.ngc,report.json}}",
        report.contours,
        report.policy,
        if out.improved { "improved" } else { "not improved" },
        report.idle_length_mm,
        report.cut_length_mm,
        report.overheats,
        report.max_temperature_c,
        report.runtime_s,
        a.out.display()
    );
    ExitCode::SUCCESS
}
