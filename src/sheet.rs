//! `cell sheet`: sequence the cut of a nested sheet on the spot, without DDS (seed 003; issue
//! 7): read a layout (`.dxf` or the JSON format of `cell_sequencer::layout`), construct the
//! order with a policy, improve it within a time budget, simulate the final plan on the
//! thermal raster, and write into `--out`:
//!
//! - `plan.json`: the `cell_msgs/CutPlan` (order, parts, pierce points, policy, lengths,
//!   overheats, max temperature, cost) as JSON;
//! - `program.ngc`: the machine program for `--profile` (through [`cell_emitter`]);
//! - `tool.tbl`: with a profile's `cutting.compensation: controller`, LinuxCNC's tool table
//!   giving tool 1 the kerf as its diameter (the program's `G41`/`G42` read it);
//! - `plan.svg`: the plan to check before cutting, in machine coordinates
//!   ([`cell_sequencer::plan_svg`]): sheet, parts, cuts, lead-ins, pierces with the cut order,
//!   rapids and the overheats, the figures in its title;
//! - `report.json`: idle and cut length, overheats, max temperature, runtime, policy, the
//!   figures of every phase (load, construction, improvement, simulation) and the sheet
//!   (`{"rule": "limits", "size_mm": [3000, 1500], "origin_mm": [0, 0], "origin_from":
//!   "drawing"}`: which rule found it and where its corner is on the machine), and with a
//!   profile's `cutting:` section the `cut`: material, thickness, kerf, compensation, lead
//!   lengths, how many pierces had to come closer than the lead-in length, small holes
//!   pierced at their centre, and the holes left out (`too_small_holes: skip`).
//!
//! Kerf and leads (`cell_sequencer::cut`): with a `cutting:` section in the profile, every
//! contour is cut half the kerf (for `--material` at `--thickness`, from the profile's table)
//! off its drawn line on the scrap side and entered along a lead-in from a pierce on the scrap
//! side; a hole too small for the kerf, or parts nested closer than the kerf, are errors
//! naming them (exit 65).
//!
//! The program cuts where the drawing says (`cell_sequencer::placement`): a DXF's coordinates
//! are kept, unless `--sheet-origin X,Y` places the sheet's lower-left corner at X,Y on the
//! machine. A part outside the profile's X/Y travel is an error naming it; nothing is written.
//!
//! A progress bar shows the phase and the best cost so far.
//!
//! Exit status: 0 written; 64 a bad command line (unknown policy, precedence or pierce mode,
//! negative seconds, a profile that takes no programs); 65 a layout that cannot be read or is
//! invalid (the message names the file and the entity or field) or a plan the emitter refuses;
//! 1 the output cannot be written.

use std::{path::PathBuf, process::ExitCode};

use cell_sequencer::{
    cut::{spec_for_profile, CutSummary},
    improve::ImproveParams,
    job::{self, LayoutSource, PierceMode, SheetJob, SheetOption, UnknownChoice},
    placement::{SheetPlacement, Travel},
    plan_svg::plan_svg,
    toolpath::{to_cut_plan_msg, to_toolpath, with_cut, ToolpathOptions},
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
    /// Heat in the cost: on (the thermal raster, seed 003) or off (idle length alone under the
    /// precedence rules; the final plan is still simulated, so report.json gives its overheats).
    #[arg(long, default_value = "on", value_name = "on|off")]
    pub thermal: String,
    /// Time budget of the improvement phase, in seconds; 0 = iterations only (deterministic).
    #[arg(long, default_value_t = 0.0)]
    pub seconds: f64,
    /// Machine profile for the program: a name under config/machines or a YAML file.
    #[arg(long, default_value = "linuxcnc-plasma", value_name = "NAME|FILE")]
    pub profile: String,
    /// RNG seed (random policy, improvement).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Place the sheet's lower-left corner at X,Y mm on the machine (machine = sheet-relative +
    /// X,Y). Default: the drawing's own coordinates (the sheet is the SHEET-layer contour, else
    /// $LIMMIN/$LIMMAX or $EXTMIN/$EXTMAX when they contain the parts, else the parts' extent;
    /// a JSON layout's `origin`). report.json says which rule applied.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true, value_parser = parse_origin)]
    pub sheet_origin: Option<[f64; 2]>,
    /// The sheet's material, as the profile's kerf table names it (e.g. mild_steel). Default:
    /// the profile's `cutting.default_material`. With a `cutting:` section the contours are
    /// offset by half the kerf and entered along lead-ins from the scrap side.
    #[arg(long, value_name = "NAME")]
    pub material: Option<String>,
    /// The sheet's thickness, mm (picks the kerf from the profile's table, interpolated between
    /// rows). Default: the profile's `cutting.default_material`.
    #[arg(long, value_name = "MM")]
    pub thickness: Option<f64>,
}

/// `X,Y` in mm, both finite.
fn parse_origin(s: &str) -> Result<[f64; 2], String> {
    let bad = || format!("{s:?}: expected X,Y in mm, e.g. 100,50");
    let (x, y) = s.split_once(',').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if x.is_finite() && y.is_finite() {
        Ok([x, y])
    } else {
        Err(bad())
    }
}

/// `report.json`.
#[derive(Debug, Serialize)]
struct Report<'a> {
    layout: String,
    contours: usize,
    policy: &'a str,
    precedence: &'a str,
    pierce: &'a str,
    /// `on` or `off` (`--thermal`): whether the order weighed the heat; the overheats below
    /// are the final simulation's either way.
    thermal: &'a str,
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
    sheet: SheetPlacement,
    /// The material, kerf and leads (absent for a profile without a `cutting:` section).
    #[serde(skip_serializing_if = "Option::is_none")]
    cut: Option<CutReport>,
}

/// `report.json`'s `cut`: the material and what its kerf and leads did.
#[derive(Debug, Serialize)]
struct CutReport {
    material: String,
    thickness_mm: f64,
    #[serde(flatten)]
    summary: CutSummary,
}

/// The option of `cell sheet` a job option comes from (exhaustive: a new option needs one).
pub fn flag_for(option: SheetOption) -> &'static str {
    match option {
        SheetOption::Policy => "--policy",
        SheetOption::Precedence => "--precedence",
        SheetOption::Pierce => "--pierce",
        SheetOption::Thermal => "--thermal",
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
    let thermal = match job::parse_thermal(&a.thermal) {
        Ok(t) => t,
        Err(e) => return unknown_choice(&e),
    };
    if !(a.seconds.is_finite() && a.seconds >= 0.0) {
        return usage(format!("--seconds {}: must be finite and ≥ 0", a.seconds));
    }
    let profile = match crate::emit::program_profile("--profile", &a.profile) {
        Ok(p) => p,
        Err(e) => return usage(e),
    };
    let cut = match spec_for_profile(&profile, a.material.as_deref(), a.thickness) {
        Ok(c) => c,
        Err(e) => return usage(format!("--material/--thickness: {e}")),
    };
    let sheet_job = SheetJob {
        cut: cut.as_ref().map(|(spec, _)| spec.clone()),
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
        cost: cell_sequencer::cost::CostParams {
            thermal,
            ..Default::default()
        },
        sheet_origin: a.sheet_origin,
        travel: Some(Travel::of(&profile)),
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
    // What is not cut as drawn (holes left out, features narrower than the kerf).
    for w in out.cut.iter().flat_map(|c| &c.warnings) {
        eprintln!("cell sheet: warning: {}: {w}", a.layout.display());
    }
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
    let plan_msg = with_cut(
        to_cut_plan_msg(
            &out.problem,
            &out.plan,
            &job_id,
            job::policy_name(policy),
            out.improved,
            t.ambient_c,
        ),
        out.cut.as_ref(),
    );
    // The job's material: controller compensation's tool table gets its kerf.
    let emit_options = cell_emitter::EmitOptions {
        material: cut.as_ref().map(|(_, m)| m.clone()),
    };
    let program = match cell_emitter::emit_program_with(&toolpath, &profile, &job_id, &emit_options)
    {
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
        thermal: &a.thermal,
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
        sheet: out.sheet,
        cut: cut.zip(out.cut.clone()).map(|((_, m), summary)| CutReport {
            material: m.material,
            thickness_mm: m.thickness_mm,
            summary,
        }),
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
    // Files the program needs beside it (controller compensation's tool.tbl).
    for file in &program.files[1..] {
        if let Err(e) = cell_emitter::program::write_atomically(&a.out.join(&file.name), &file.text)
        {
            return failure(e);
        }
    }
    let picture = plan_svg(&out.problem, &toolpath, &plan_msg, &out.overheat_points);
    if let Err(e) = cell_emitter::program::write_atomically(&a.out.join("plan.svg"), &picture) {
        return failure(e);
    }
    println!(
        "cell sheet: {} contours, {}, {} ({}), idle {:.1} mm, cut {:.1} mm, {} overheats, max \
         {:.0} °C above ambient, {:.1} s; wrote \
         {}/{{plan.json,plan.svg,program.ngc,report.json}}",
        report.contours,
        report.sheet,
        report.policy,
        if out.improved {
            "improved"
        } else {
            "not improved"
        },
        report.idle_length_mm,
        report.cut_length_mm,
        report.overheats,
        report.max_temperature_c,
        report.runtime_s,
        a.out.display()
    );
    ExitCode::SUCCESS
}
