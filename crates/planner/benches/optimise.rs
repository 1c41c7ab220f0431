//! The full default optimisation (seed 000 §IV.C: 20 particles, up to 8000 iterations with the
//! stall stop, restart every 200, then the refinement) of the default job (S1223, chord 200 mm, H-grade EPS, kerf-model offset) at N = 100,
//! 200 and 400 panels through `cell_planner::job::plan`: wall seconds, iterations/s, baseline
//! and final loss, baseline vs optimised RMS(E − CSE) and max |E − CSE|. First, per N, the
//! cost of one loss evaluation broken down by stage (single-threaded).
//!
//! `CARGO_TARGET_DIR=/tmp/target-speed cargo bench -p cell_planner --bench optimise`
//! Options (environment): `OPTIMISE_N=100,400` picks panel counts; `OPTIMISE_ITERATIONS=500`
//! shortens the runs; `OPTIMISE_BREAKDOWN=0` skips the breakdown, `OPTIMISE_RUN=0` the runs.

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use cell_planner::exposure::WireSegments;
use cell_planner::job::{plan, AirfoilSource, HotwireJob};
use cell_planner::pso::{Objective, Problem, PsoConfig, Scratch};
use cell_planner::trajectory::{is_feasible, Baseline, OutlineGrid};
use rand::{Rng, SeedableRng};

/// Mean µs per call over a batch of at least 200 ms (after one warm-up call).
fn time_us(mut f: impl FnMut()) -> f64 {
    f();
    let (mut calls, t) = (0u64, Instant::now());
    while t.elapsed() < Duration::from_millis(200) {
        f();
        calls += 1;
    }
    t.elapsed().as_secs_f64() * 1e6 / calls as f64
}

fn env_list(name: &str) -> Option<Vec<usize>> {
    std::env::var(name).ok().map(|v| {
        v.split(',')
            .map(|n| n.trim().parse().unwrap_or_else(|_| panic!("{name}: {v}")))
            .collect()
    })
}

/// One loss evaluation of the default job at `panels`, stage by stage, on candidates the swarm
/// would see (controls uniform in ±0.15 mm).
fn breakdown(panels: usize, offset_mm: f64) {
    let foil = AirfoilSource::Named("s1223".into())
        .load()
        .unwrap()
        .normalised()
        .scaled(200.0)
        .unwrap();
    let surface_points = cell_planner::job::surface_points(&foil, panels).unwrap();
    let baseline = Baseline::fixed_offset(&foil, offset_mm, panels + panels / 2).unwrap();
    let objective = Objective::default();
    let problem = Problem::new(&foil, surface_points, baseline, objective).unwrap();
    let k = problem.trajectory().control_points();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let candidates: Vec<Vec<f64>> = (0..64)
        .map(|_| (0..k).map(|_| rng.random_range(-0.15..0.15)).collect())
        .collect();
    let mut c = 0;
    let mut next = || {
        c = (c + 1) % candidates.len();
        &candidates[c]
    };
    let mut path = Vec::new();
    problem.trajectory().path_into(next(), &mut path);
    let t_path = time_us(|| problem.trajectory().path_into(next(), &mut path));
    let paths: Vec<_> = candidates.iter().map(|c| problem.path(c)).collect();
    let outline: &[_] = foil.points();
    let grid = OutlineGrid::new(outline);
    let mut p = 0;
    let mut next_path = || {
        p = (p + 1) % paths.len();
        &paths[p]
    };
    let feasible = paths
        .iter()
        .filter(|q| is_feasible(q, outline, objective.min_clearance_mm))
        .count();
    assert!(paths
        .iter()
        .all(|q| grid.is_feasible(q, objective.min_clearance_mm)
            == is_feasible(q, outline, objective.min_clearance_mm)));
    let t_plain = time_us(|| {
        std::hint::black_box(is_feasible(
            next_path(),
            outline,
            objective.min_clearance_mm,
        ));
    });
    let t_grid = time_us(|| {
        std::hint::black_box(grid.is_feasible(next_path(), objective.min_clearance_mm));
    });
    let mut wire = WireSegments::default();
    let t_wire = time_us(|| wire.set(next_path()).unwrap());
    let surface = problem.surface();
    let mut out = vec![0.0; surface.len()];
    let t_exp = time_us(|| {
        wire.set(next_path()).unwrap();
        objective
            .model
            .exposure_into(surface, &wire, &mut out)
            .unwrap();
    }) - t_wire;
    let t_ref = time_us(|| {
        wire.set(next_path()).unwrap();
        objective
            .model
            .exposure_reference_into(surface, &wire, &mut out)
            .unwrap();
    }) - t_wire;
    let mut scratch = Scratch::default();
    let t_loss = time_us(|| {
        std::hint::black_box(problem.loss(next(), &mut scratch));
    });
    println!(
        "N={} M={} outline {} points, {feasible}/{} sample candidates feasible; µs per loss \
         evaluation, one thread:",
        surface.len(),
        paths[0].len() - 1,
        outline.len(),
        paths.len()
    );
    println!("  path (B-spline displacement) {t_path:7.1}");
    println!("  feasibility, grid            {t_grid:7.1}   (plain O(path × outline) test: {t_plain:.1})");
    println!("  wire segments (f64 + f32)    {t_wire:7.1}");
    println!("  exposure, fast               {t_exp:7.1}   (reference: {t_ref:.1})");
    println!(
        "  whole loss                   {t_loss:7.1}   → 160k evaluations on 2 cores ≈ {:.1} s",
        t_loss * 160e3 / 2.0 / 1e6
    );
}

fn main() {
    let ns = env_list("OPTIMISE_N").unwrap_or_else(|| vec![100, 200, 400]);
    let iterations = env_list("OPTIMISE_ITERATIONS").map(|v| v[0]);
    let breakdown_on = std::env::var("OPTIMISE_BREAKDOWN").map_or(true, |v| v != "0");
    let run_on = std::env::var("OPTIMISE_RUN").map_or(true, |v| v != "0");
    let threads = rayon::current_num_threads();
    let mut rows = Vec::new();
    for &n in &ns {
        let job = HotwireJob {
            panels: n,
            pso: PsoConfig {
                iterations: iterations.unwrap_or(PsoConfig::default().iterations),
                ..PsoConfig::default()
            },
            ..HotwireJob::default()
        };
        if breakdown_on {
            // The job's offset comes from the kerf model: ask a one-iteration plan for it.
            let quick = HotwireJob {
                pso: PsoConfig {
                    iterations: 1,
                    particles: 1,
                    ..PsoConfig::default()
                },
                ..job.clone()
            };
            let offset = plan(&quick, |_| ControlFlow::Continue(()))
                .unwrap()
                .root
                .offset_mm;
            breakdown(n, offset);
        }
        if !run_on {
            continue;
        }
        let p = plan(&job, |_| ControlFlow::Continue(())).expect("plan");
        let its = p.iterations as f64 / p.seconds;
        println!(
            "N={n}: {} iterations × {} particles in {:.2} s ({its:.0} it/s, {threads} threads); \
             loss {:.4e} → {:.4e} ({:.1} %); RMS(E − CSE) {:.4} → {:.4}; max|E − CSE| {:.4} → {:.4}; \
             CV {:.4} → {:.4}",
            p.iterations,
            job.pso.particles,
            p.seconds,
            p.root.baseline_loss,
            p.root.final_loss,
            100.0 * (1.0 - p.root.final_loss / p.root.baseline_loss),
            p.root.baseline_stats.rms,
            p.root.optimised_stats.rms,
            p.root.baseline_stats.max_abs,
            p.root.optimised_stats.max_abs,
            p.root.baseline_stats.cv,
            p.root.optimised_stats.cv,
        );
        rows.push((n, p));
    }
    if !rows.is_empty() {
        println!("\n| N | path points | iterations | wall s | it/s | baseline loss | final loss | RMS(E−CSE) base → opt | max abs(E−CSE) base → opt |");
        println!("|---|---|---|---|---|---|---|---|---|");
        for (n, p) in rows {
            println!(
                "| {n} | {} | {} | {:.2} | {:.0} | {:.4e} | {:.4e} | {:.4} → {:.4} | {:.4} → {:.4} |",
                p.root.optimised.len(),
                p.iterations,
                p.seconds,
                p.iterations as f64 / p.seconds,
                p.root.baseline_loss,
                p.root.final_loss,
                p.root.baseline_stats.rms,
                p.root.optimised_stats.rms,
                p.root.baseline_stats.max_abs,
                p.root.optimised_stats.max_abs
            );
        }
    }
}
