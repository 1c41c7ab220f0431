//! Sequencing bench (seed 003 §A5 metrics, issue 7 targets): per policy and instance size,
//! idle length, cut length, overheats, max temperature and runtime, before and after the
//! improvement phase. Hand-built grid instances (`fixtures::grid`) until the generator lands.
//! Then, thermal cost off on scattered points without precedence, the idle length next to
//! LKH-3's (PyPI `elkai` via `benches/lkh_peer.py`, when installed).
//!
//! `cargo bench -p cell_sequencer --bench sequencing [-- SIZES...]` (sizes in contours, default
//! 50 500 1000). `K_LOSS`, `T_MAX_C`, `CELL_MM` and `K_C` override the thermal defaults,
//! `PROXY_WEIGHT` and `PROXY_RADIUS` the improvement's heat proxy.

use std::time::Instant;

use cell_sequencer::cost::{CostParams, Evaluator};
use cell_sequencer::fixtures::{grid, scattered};
use cell_sequencer::improve::{improve, ImproveParams};
use cell_sequencer::policy::{construct, Policy};
use cell_sequencer::precedence::PrecedenceMode;
use cell_sequencer::thermal::ThermalParams;

fn main() {
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let sizes = if sizes.is_empty() {
        vec![50, 500, 1000]
    } else {
        sizes
    };
    println!(
        "{:>6} {:>8} {:>13} {:>10} {:>10} {:>9} {:>8} {:>9} {:>8}",
        "n", "thermal", "policy", "idle_mm", "cut_mm", "overheat", "max_c", "cost", "ms"
    );
    for &target in &sizes {
        // Each part: round hole + big hole + nested part + outer = 4 contours.
        let parts = (target / 4).max(1);
        let nx = (parts as f64).sqrt().ceil() as usize;
        let ny = parts.div_ceil(nx);
        let problem = grid(nx, ny, 56.0, true, true, PrecedenceMode::Strict);
        let n = problem.contours.len();
        for thermal in [true, false] {
            let cost = CostParams {
                thermal,
                ..Default::default()
            };
            let eval = Evaluator::new(&problem, thermal_params(), cost).unwrap();
            let mut nearest = None;
            for policy in Policy::ALL {
                if !thermal && policy.is_thermal() {
                    continue;
                }
                let t0 = Instant::now();
                let plan = construct(&eval, policy, 1).unwrap();
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                row(n, thermal, &format!("{policy:?}"), &plan, ms);
                if policy == Policy::Nearest {
                    nearest = Some(plan.clone());
                }
                if matches!(policy, Policy::PathOverheat | Policy::CostGreedy)
                    || (!thermal && policy == Policy::Nearest)
                {
                    let t0 = Instant::now();
                    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
                    let d = ImproveParams::default();
                    let params = ImproveParams {
                        time_budget_ms: 1500,
                        proxy_weight: env("PROXY_WEIGHT").unwrap_or(d.proxy_weight),
                        proxy_radius_mm: env("PROXY_RADIUS").unwrap_or(d.proxy_radius_mm),
                        ..d
                    };
                    let better = improve(&eval, &plan, &params, |_| {}).unwrap();
                    let ms2 = ms + t0.elapsed().as_secs_f64() * 1e3;
                    row(n, thermal, &format!("{policy:?}+imp"), &better, ms2);
                    if let Some(nn) = nearest.as_ref().filter(|_| thermal) {
                        println!(
                            "{:>6}   vs nearest: overheats {:+.0} %, idle ×{:.2}",
                            "",
                            100.0 * (better.overheats as f64 / nn.overheats.max(1) as f64 - 1.0),
                            better.idle_mm / nn.idle_mm
                        );
                    }
                }
            }
        }
    }
    tsp_gap(&sizes);
}

/// Defaults, with `K_LOSS`, `T_MAX_C`, `CELL_MM`, `K_C` from the environment for tuning runs.
fn thermal_params() -> ThermalParams {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
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

/// Thermal cost off, one pierce point per contour, no precedence: our idle length against
/// LKH-3 (PyPI `elkai` through `benches/lkh_peer.py`) on the same points.
fn tsp_gap(sizes: &[usize]) {
    println!(
        "\n{:>6} {:>12} {:>12} {:>12} {:>8} {:>8}",
        "n", "nearest_mm", "ours_mm", "lkh3_mm", "gap_%", "ours_ms"
    );
    for &n in sizes {
        let problem = scattered(n, 42);
        let cost = CostParams {
            thermal: false,
            ..Default::default()
        };
        let eval = Evaluator::new(&problem, thermal_params(), cost).unwrap();
        let t0 = Instant::now();
        let nn = construct(&eval, Policy::Nearest, 0).unwrap();
        let ours = improve(
            &eval,
            &nn,
            &ImproveParams {
                time_budget_ms: 1500,
                ..Default::default()
            },
            |_| {},
        )
        .unwrap();
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let lkh = lkh_length(&problem);
        let (lkh_s, gap) = match lkh {
            Some(l) => (
                format!("{l:.0}"),
                format!("{:+.2}", 100.0 * (ours.idle_mm / l - 1.0)),
            ),
            None => ("n/a".into(), "n/a".into()),
        };
        println!(
            "{:>6} {:>12.0} {:>12.0} {:>12} {:>8} {:>8.1}",
            n, nn.idle_mm, ours.idle_mm, lkh_s, gap, ms
        );
    }
}

/// LKH-3's closed-tour length over the start and every pierce point, if `python3` with
/// `elkai` is available (`pip install -r nodes/sequencer/benches/requirements.txt`).
fn lkh_length(problem: &cell_sequencer::problem::Problem) -> Option<f64> {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/lkh_peer.py");
    let mut child = Command::new("python3")
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    {
        let mut stdin = child.stdin.take()?;
        let mut text = format!("{} {}\n", problem.start[0], problem.start[1]);
        for c in &problem.contours {
            let p = c.pierce_candidates[0];
            text.push_str(&format!("{} {}\n", p[0], p[1]));
        }
        stdin.write_all(text.as_bytes()).ok()?;
    }
    let out = child.wait_with_output().ok()?;
    String::from_utf8(out.stdout).ok()?.trim().parse().ok()
}

fn row(n: usize, thermal: bool, name: &str, p: &cell_sequencer::plan::CutPlan, ms: f64) {
    println!(
        "{:>6} {:>8} {:>13} {:>10.0} {:>10.0} {:>9} {:>8.0} {:>9.0} {:>8.1}",
        n, thermal, name, p.idle_mm, p.cut_mm, p.overheats, p.max_temp_c, p.cost, ms
    );
}
