//! Sequencing bench (seed 003 §A5 metrics, issue 7 and issue 19 targets): per instance and
//! policy, idle length, cut length, overheats, maximum temperature, runtime, peak memory and,
//! thermal cost off, the gap of our idle length to LKH-3 (PyPI `elkai` via
//! `benches/lkh_peer.py`, when installed) on the same pierce points.
//!
//! Instances: the seeded generator ([`cell_sequencer::generator`], seed 7) at each size, strict
//! precedence, free pierce candidates; then the real part outlines of
//! `tests/data/sheet/plate_holes_nest.json`; then the dense perforated layouts
//! ([`cell_sequencer::generator::generate_perforated`], seed 1 or `DENSE_SEED`; issue 19:
//! 5000 contours on 4000 × 2000 mm).
//!
//! `cargo bench -p cell_sequencer --bench sequencing [-- SIZES...]` (sizes in contours, default
//! 50 500 1000 5000 plus the plate nest and `dense5000`; `plate` alone runs only the plate
//! nest, `denseN` a dense layout of N contours, `dense` = `dense5000`). Every row gives the
//! peak resident memory while it ran (`peak_mb`: Linux `VmHWM`, reset before each row through
//! `/proc/self/clear_refs`).
//!
//! Every instance is cut as `cell sheet` cuts it (issue 19): the default material of a profile
//! (`BENCH_PROFILE`, else per instance), kerf offset and leads; `BENCH_CUT=0`: the drawn
//! contours pierced on the contour.
//!
//! Environment: `BENCH_THERMAL=on|off` runs one side only; `BENCH_POLICIES=0` skips the
//! paper's policies other than nearest (quicker tuning runs); `BENCH_STARTS` (comma-separated
//! `nearest`, `path`, `greedy`) picks the improvement rows; `K_LOSS`, `T_MAX_C`, `CELL_MM` and
//! `K_C` override the thermal defaults; `PROXY_WEIGHT`, `PROXY_RADIUS`, `IDLE_BUDGET`,
//! `PROXY_HALF_LIFE`, `PROXY_LOOKBACK`, `TIME_BUDGET_MS`, `MAX_ITER` and `IMPROVE_SEED` the improvement's;
//! `LKH_PYTHON` the peer's interpreter, `LKH_MAX` the most points handed to it (default 2000),
//! `LKH_RUNS` its runs (default 10).
//!
//! Rows: `nearest` … `cost_greedy` are the constructions alone; `nearest+imp`, `path+imp` and
//! `greedy+imp` are that construction then the improvement with its default parameters (idle
//! budget 1.5× nearest), runtime including the construction, the improvement and the final
//! true simulation (`nearest+imp`: the start's raster run goes alongside the search,
//! [`cell_sequencer::improve::Start::Cuts`]). Thermal off (`cell sheet --thermal off`):
//! `nearest` and `nearest+imp`, with the gap to LKH-3 on the pierce points chosen (LKH-3
//! ignores precedence, so part of the gap is the rules' price); last, `scatter` rows: the pure
//! TSP (scattered points, one pierce point each, no precedence) against LKH-3.

use std::path::Path;
use std::time::Instant;

use cell_profiles::MachineProfile;
use cell_sequencer::cost::{CostParams, Evaluator};
use cell_sequencer::cut::{cut_problem, spec_for_profile};
use cell_sequencer::fixtures::scattered;
use cell_sequencer::generator::{generate, generate_perforated, GeneratorConfig, PerforatedConfig};
use cell_sequencer::improve::{improve, ImproveOptions, ImproveParams, Improved, Start};
use cell_sequencer::layout::{Layout, PierceOptions};
use cell_sequencer::plan::CutPlan;
use cell_sequencer::policy::{construct, construct_cuts, Policy};
use cell_sequencer::precedence::PrecedenceMode;
use cell_sequencer::problem::Problem;
use cell_sequencer::thermal::ThermalParams;

fn env(k: &str) -> Option<f64> {
    std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut sizes: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let plate_only = args.iter().any(|a| a == "plate");
    let mut dense: Vec<usize> = args
        .iter()
        .filter_map(|a| match a.strip_prefix("dense")? {
            "" => Some(5000),
            n => n.parse().ok(),
        })
        .collect();
    let defaults = sizes.is_empty() && dense.is_empty() && !plate_only;
    if defaults {
        sizes = vec![50, 500, 1000, 5000];
        dense = vec![5000];
    }
    println!(
        "{:>9} {:>6} {:>7} {:>12} {:>9} {:>9} {:>8} {:>7} {:>9} {:>8} {:>7} {:>7}",
        "inst",
        "n",
        "thermal",
        "policy",
        "idle_mm",
        "cut_mm",
        "overheat",
        "max_c",
        "cost",
        "ms",
        "peak_mb",
        "lkh_%"
    );
    let mut instances: Vec<(String, Problem)> = sizes
        .iter()
        .map(|&n| {
            let layout = generate(&GeneratorConfig {
                seed: 7,
                contours: n,
                ..Default::default()
            });
            (
                format!("gen{n}"),
                problem_of(&layout, "linuxcnc-plasma-3015"),
            )
        })
        .collect();
    if plate_only || defaults || args.iter().any(|a| a == "+plate") {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/data/sheet/plate_holes_nest.json");
        let layout = Layout::from_json_file(&path).expect("plate nest");
        instances.push(("plate".into(), problem_of(&layout, "linuxcnc-plasma")));
    }
    for &n in &dense {
        let layout = generate_perforated(&PerforatedConfig {
            seed: env("DENSE_SEED").map_or(1, |v| v as u64),
            contours: n,
            ..Default::default()
        });
        instances.push((
            format!("dense{n}"),
            problem_of(&layout, "linuxcnc-plasma-4020"),
        ));
    }
    for (name, problem) in &instances {
        run_instance(name, problem);
    }
    // The pure TSP side: scattered points, one pierce point each, no precedence.
    println!();
    for n in sizes.iter().copied().filter(|&n| n <= 1000) {
        let problem = scattered(n, 42);
        let cost = CostParams {
            thermal: false,
            ..Default::default()
        };
        let eval = Evaluator::new(&problem, thermal_params(), cost).unwrap();
        reset_peak();
        let t0 = Instant::now();
        let nearest = construct(&eval, Policy::Nearest, 0).unwrap();
        let better = improve(&eval, Start::Plan(&nearest), improve_options())
            .unwrap()
            .best;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let gap = lkh_length(&problem, &better).map(|l| 100.0 * (better.idle_mm / l - 1.0));
        row("scatter", n, false, "nearest+imp", &better, ms, gap);
    }
}

/// The problem of `layout` as `cell sheet` cuts it on `profile` (`config/machines/`, or
/// `BENCH_PROFILE`): its default material's kerf offset and leads, the pierce candidates the
/// lead-ins' starts ([`cell_sequencer::cut`]). `BENCH_CUT=0`: the drawn contours, pierced on
/// the contour (the figures before issue 19).
fn problem_of(layout: &Layout, profile: &str) -> Problem {
    let pierce = PierceOptions::default();
    if env("BENCH_CUT") == Some(0.0) {
        return layout
            .to_problem(PrecedenceMode::Strict, &pierce)
            .expect("valid layout");
    }
    let name = std::env::var("BENCH_PROFILE").unwrap_or_else(|_| profile.to_string());
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../config/machines")
        .join(format!("{name}.yaml"));
    let profile = MachineProfile::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let (spec, material) = spec_for_profile(&profile, None, None)
        .and_then(|s| s.ok_or_else(|| format!("{name} has no cutting: section")))
        .unwrap_or_else(|e| panic!("{e}"));
    let (problem, _) = cut_problem(layout, PrecedenceMode::Strict, &pierce, &spec)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    println!(
        "# {} contours cut on {name}: {} {} mm, kerf {} mm, {:?} lead-in {} mm, lead-out {} mm",
        problem.contours.len(),
        material.material,
        material.thickness_mm,
        spec.kerf_mm,
        spec.lead_shape,
        spec.lead_in_mm,
        spec.lead_out_mm
    );
    problem
}

/// The improvement with [`improve_params`] and no hooks.
fn improve_options() -> ImproveOptions<'static> {
    ImproveOptions {
        params: improve_params(),
        ..Default::default()
    }
}

fn improve_params() -> ImproveParams {
    let d = ImproveParams::default();
    ImproveParams {
        proxy_weight: env("PROXY_WEIGHT").unwrap_or(d.proxy_weight),
        proxy_radius_mm: env("PROXY_RADIUS").unwrap_or(d.proxy_radius_mm),
        idle_budget: env("IDLE_BUDGET").unwrap_or(d.idle_budget),
        proxy_half_life_mm: env("PROXY_HALF_LIFE").unwrap_or(d.proxy_half_life_mm),
        proxy_lookback: env("PROXY_LOOKBACK").map_or(d.proxy_lookback, |v| v as usize),
        time_budget_ms: env("TIME_BUDGET_MS").map_or(d.time_budget_ms, |v| v as u64),
        max_iterations: env("MAX_ITER").map_or(d.max_iterations, |v| v as usize),
        seed: env("IMPROVE_SEED").map_or(d.seed, |v| v as u64),
        ..d
    }
}

fn run_instance(name: &str, problem: &Problem) {
    let n = problem.contours.len();
    let all = env("BENCH_POLICIES").is_none_or(|v| v != 0.0);
    let modes: &[bool] = match std::env::var("BENCH_THERMAL").as_deref() {
        Ok("on") => &[true],
        Ok("off") => &[false],
        _ => &[true, false],
    };
    for &thermal in modes {
        let cost = CostParams {
            thermal,
            ..Default::default()
        };
        let eval = Evaluator::new(problem, thermal_params(), cost).unwrap();
        reset_peak();
        let t0 = Instant::now();
        let nearest = construct(&eval, Policy::Nearest, 1).unwrap();
        let nn_ms = t0.elapsed().as_secs_f64() * 1e3;
        row(name, n, thermal, "nearest", &nearest, nn_ms, None);
        if thermal && all {
            for policy in [
                Policy::MinOverheat,
                Policy::Random,
                Policy::PathOverheat,
                Policy::CostGreedy,
            ] {
                reset_peak();
                let t0 = Instant::now();
                let plan = construct(&eval, policy, 1).unwrap();
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                row(name, n, thermal, &policy_name(policy), &plan, ms, None);
            }
        }
        // Improvement from nearest pierce and (thermal cost on) from the paper's method, the
        // node's default construction.
        let starts: Vec<Policy> = if thermal {
            vec![Policy::Nearest, Policy::PathOverheat, Policy::CostGreedy]
        } else {
            vec![Policy::Nearest]
        };
        let only = std::env::var("BENCH_STARTS").unwrap_or_default();
        for policy in starts
            .into_iter()
            .filter(|&p| only.is_empty() || only.split(',').any(|s| s == start_name(p)))
        {
            reset_peak();
            let t0 = Instant::now();
            let better = if policy == Policy::Nearest {
                // The order alone; its raster run goes alongside the search.
                let cuts = construct_cuts(&eval, policy, 1).unwrap();
                let Improved {
                    start,
                    best: better,
                } = improve(&eval, Start::Cuts(&cuts), improve_options()).unwrap();
                assert_eq!(start, nearest);
                better
            } else {
                let start = construct(&eval, policy, 1).unwrap();
                improve(&eval, Start::Plan(&start), improve_options())
                    .unwrap()
                    .best
            };
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            let gap = if thermal {
                None
            } else {
                lkh_length(problem, &better).map(|l| 100.0 * (better.idle_mm / l - 1.0))
            };
            let label = format!("{}+imp", start_name(policy));
            let label = label.as_str();
            row(name, n, thermal, label, &better, ms, gap);
            if !thermal {
                no_rules_row(name, problem);
            }
            if thermal {
                println!(
                    "{:>9}   {label} vs nearest: overheats {:+.1} %, idle ×{:.2}",
                    "",
                    100.0 * (better.overheats as f64 / nearest.overheats.max(1) as f64 - 1.0),
                    better.idle_mm / nearest.idle_mm
                );
            }
        }
    }
}

/// Thermal cost off, the same cuts without the precedence rules: nearest + improvement against
/// LKH-3 on a problem both see alike, our search's own gap (the `nearest+imp` row's gap less
/// this one is about the rules' price).
fn no_rules_row(name: &str, problem: &Problem) {
    let mut free = problem.clone();
    let n = free.contours.len();
    free.precedence.predecessors = vec![Vec::new(); n];
    free.precedence.groups.clear();
    let cost = CostParams {
        thermal: false,
        ..Default::default()
    };
    let eval = Evaluator::new(&free, thermal_params(), cost).unwrap();
    reset_peak();
    let t0 = Instant::now();
    let cuts = construct_cuts(&eval, Policy::Nearest, 1).unwrap();
    let better = improve(&eval, Start::Cuts(&cuts), improve_options())
        .unwrap()
        .best;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let gap = lkh_length(&free, &better).map(|l| 100.0 * (better.idle_mm / l - 1.0));
    row(name, n, false, "no rules+imp", &better, ms, gap);
}

/// The short name of an improvement start in the rows and `BENCH_STARTS`.
fn start_name(p: Policy) -> &'static str {
    match p {
        Policy::Nearest => "nearest",
        Policy::PathOverheat => "path",
        Policy::CostGreedy => "greedy",
        Policy::MinOverheat => "min",
        Policy::Random => "random",
    }
}

fn policy_name(p: Policy) -> String {
    match p {
        Policy::Nearest => "nearest",
        Policy::MinOverheat => "min_overheat",
        Policy::Random => "random",
        Policy::PathOverheat => "path_overheat",
        Policy::CostGreedy => "cost_greedy",
    }
    .into()
}

/// Defaults, with `K_LOSS`, `T_MAX_C`, `CELL_MM`, `K_C` from the environment for tuning runs.
fn thermal_params() -> ThermalParams {
    let mut p = ThermalParams::default();
    if let Some(v) = env("K_LOSS") {
        p.k_loss = v as f32;
    }
    if let Some(v) = env("T_MAX_C") {
        p.t_max_c = v as f32;
    }
    if let Some(v) = env("CELL_MM") {
        p.cell_mm = v;
    }
    if let Some(v) = env("K_C") {
        p.k_conductivity = v as f32;
    }
    p
}

/// LKH-3's closed-tour length over the start and the cuts `plan` chose, each entered at its
/// pierce point and left at its exit (the end of its lead-out; an asymmetric TSP then; no
/// precedence: a lower bound on what any precedence-respecting order of them can reach), if
/// `python3` with `elkai` is available (`pip install -r crates/sequencer/benches/requirements.txt`;
/// `LKH_PYTHON` names another interpreter, e.g. a venv's).
fn lkh_length(problem: &Problem, plan: &CutPlan) -> Option<f64> {
    use std::io::Write;
    // LKH-3's ten runs take minutes from a few thousand points on: skipped above LKH_MAX
    // points (default 2000).
    if plan.cuts.len() as f64 > env("LKH_MAX").unwrap_or(2000.0) {
        return None;
    }
    use std::process::{Command, Stdio};
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/lkh_peer.py");
    let python = std::env::var("LKH_PYTHON").unwrap_or_else(|_| "python3".into());
    let runs = env("LKH_RUNS").map_or(10, |v| v as usize);
    let mut child = Command::new(python)
        .arg(script)
        .arg(runs.to_string())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    {
        let mut stdin = child.stdin.take()?;
        let mut text = format!("{} {}\n", problem.start[0], problem.start[1]);
        for c in &plan.cuts {
            let (p, e) = (c.point(problem), c.exit(problem));
            text.push_str(&format!("{} {} {} {}\n", p[0], p[1], e[0], e[1]));
        }
        stdin.write_all(text.as_bytes()).ok()?;
    }
    let out = child.wait_with_output().ok()?;
    String::from_utf8(out.stdout).ok()?.trim().parse().ok()
}

/// Resets the process's peak resident set size (Linux: `5` into `/proc/self/clear_refs`), so
/// the next [`peak_mb`] is the peak of what ran in between.
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Peak resident set size since the last [`reset_peak`], MB (`VmHWM` of `/proc/self/status`).
fn peak_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: f64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb / 1024.0)
}

fn row(inst: &str, n: usize, thermal: bool, name: &str, p: &CutPlan, ms: f64, gap: Option<f64>) {
    let gap = gap.map_or_else(|| "".to_string(), |g| format!("{g:+.2}"));
    let peak = peak_mb().map_or_else(|| "".to_string(), |m| format!("{m:.0}"));
    println!(
        "{:>9} {:>6} {:>7} {:>12} {:>9.0} {:>9.0} {:>8} {:>7.0} {:>9.0} {:>8.1} {:>7} {:>7}",
        inst,
        n,
        if thermal { "on" } else { "off" },
        name,
        p.idle_mm,
        p.cut_mm,
        p.overheats,
        p.max_temp_c,
        p.cost,
        ms,
        peak,
        gap
    );
}
