//! Issue 21's benchmark: how uniform the exposure gets on airfoils the suite did not ship
//! before (`benches/data`, UIUC sections drawn at random from AeroSandbox's copy), at chord
//! 200 mm and 200 surface panels with the default job: seed 000's swarm, then the local
//! refinement, the feed along the path a design variable, the straight 10 mm lead-in behind the
//! trailing edge. Baseline = the fixed-offset path **with the same lead-in**. Per foil: CV of E
//! and the 95th percentile of |E − CSE| before → after, the least clearance from the foil
//! (path and lead-in, measured here, not taken from the planner) and the wall time; then the
//! medians and the targets.
//!
//! Then, on three foils, the paper's swarm alone (constant feed, no refinement, the same
//! iterations) here and in the NumPy peer `benches/pso_peer.py` on the same problem file.
//!
//! `cargo bench -p cell_planner --bench uniformity`
//! Environment: `UNIFORMITY_FOILS=ag24,e553` picks foils (file stems); `UNIFORMITY_PANELS`
//! (200); `PEER_PYTHON` a Python with NumPy (`pip install -r benches/requirements.txt`;
//! without it the peer rows are skipped with a note); `PEER_FOILS` (the first three);
//! `PEER_ITERATIONS` (2000).

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use cell_planner::job::{
    lead_in_start, plan, surface_points, AirfoilSource, ExposureStats, HotwireJob,
};
use cell_planner::pso::{optimise, Objective, Problem, PsoConfig};
use cell_planner::trajectory::{clearance_mm, Baseline};

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/data")
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn env_list(name: &str) -> Option<Vec<String>> {
    std::env::var(name)
        .ok()
        .map(|v| v.split(',').map(|s| s.trim().to_string()).collect())
}

/// True if `path`'s file stem is one of `names`.
fn named(path: &Path, names: &[String]) -> bool {
    names
        .iter()
        .any(|n| path.file_stem().is_some_and(|s| s == n.as_str()))
}

/// The foils the environment variable `var` names (comma-separated stems), else the first
/// three.
fn three_or_named(foils: &[PathBuf], var: &str) -> Vec<PathBuf> {
    match env_list(var) {
        Some(names) => foils.iter().filter(|p| named(p, &names)).cloned().collect(),
        None => foils.iter().take(3).cloned().collect(),
    }
}

struct Row {
    name: String,
    cv: (f64, f64),
    p95: (f64, f64),
    clearance_mm: f64,
    seconds: f64,
    iterations: usize,
}

fn main() {
    let panels: usize = std::env::var("UNIFORMITY_PANELS")
        .ok()
        .map_or(200, |v| v.parse().expect("UNIFORMITY_PANELS"));
    let mut foils: Vec<PathBuf> = std::fs::read_dir(data_dir())
        .expect("benches/data")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "dat"))
        .collect();
    foils.sort();
    if let Some(names) = env_list("UNIFORMITY_FOILS") {
        foils.retain(|p| named(p, &names));
    }
    let clearance_required = Objective::default().min_clearance_mm;
    println!(
        "{} foils, chord 200 mm, {panels} panels, default job ({} threads)\n",
        foils.len(),
        rayon::current_num_threads()
    );
    println!("| foil | CV base → opt | CV cut | p95 abs(E−CSE) base → opt | p95 cut | clearance mm | iterations | wall s |");
    println!("|---|---|---|---|---|---|---|---|");
    let mut rows = Vec::new();
    for path in &foils {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let job = HotwireJob {
            root_airfoil: AirfoilSource::File(path.clone()),
            panels,
            ..HotwireJob::default()
        };
        let started = Instant::now();
        let p = match plan(&job, |_| ControlFlow::Continue(())) {
            Ok(p) => p,
            Err(e) => {
                println!("| {name} | failed: {e} |");
                continue;
            }
        };
        let seconds = started.elapsed().as_secs_f64();
        let r = &p.root;
        let mut wire = r.lead_in.clone();
        wire.extend_from_slice(&r.optimised);
        let row = Row {
            name,
            cv: (r.baseline_stats.cv, r.optimised_stats.cv),
            p95: (r.baseline_stats.p95_abs, r.optimised_stats.p95_abs),
            clearance_mm: clearance_mm(&wire, &r.foil, f64::INFINITY),
            seconds,
            iterations: p.iterations,
        };
        println!(
            "| {} | {:.3} → {:.3} | {:.0} % | {:.3} → {:.3} | {:.0} % | {:.3} | {} | {:.1} |",
            row.name,
            row.cv.0,
            row.cv.1,
            100.0 * (1.0 - row.cv.1 / row.cv.0),
            row.p95.0,
            row.p95.1,
            100.0 * (1.0 - row.p95.1 / row.p95.0),
            row.clearance_mm,
            row.iterations,
            row.seconds
        );
        rows.push(row);
    }
    if rows.is_empty() {
        return;
    }
    let cuts: Vec<f64> = rows.iter().map(|r| 1.0 - r.cv.1 / r.cv.0).collect();
    let p95_cuts: Vec<f64> = rows.iter().map(|r| 1.0 - r.p95.1 / r.p95.0).collect();
    let worst = cuts.iter().copied().fold(f64::INFINITY, f64::min);
    let least_clearance = rows
        .iter()
        .map(|r| r.clearance_mm)
        .fold(f64::INFINITY, f64::min);
    let slowest = rows.iter().map(|r| r.seconds).fold(0.0, f64::max);
    println!(
        "\nmedian CV cut {:.0} % (target ≥ 65 %), worst {:.0} % (target ≥ 40 %); median p95 cut \
         {:.0} % (target ≥ 50 %); least clearance {least_clearance:.3} mm (required \
         {clearance_required} mm); median wall {:.1} s, slowest {slowest:.1} s (target ≤ 10 s)",
        100.0 * median(cuts),
        100.0 * worst,
        100.0 * median(p95_cuts),
        median(rows.iter().map(|r| r.seconds).collect()),
    );
    peer_rows(&foils, panels);
    if std::env::var("UNIFORMITY_LADDER").is_ok_and(|v| v != "0") {
        ladder(&foils, panels);
    }
    if std::env::var("UNIFORMITY_ENTRY").is_ok_and(|v| v != "0") {
        entries(&foils, panels);
    }
}

/// Where the wire enters the loop (issue 21, item 2): the refinement alone (200 iterations,
/// from the baseline, the default objective) entering at the trailing edge (lead-in along the
/// chord behind it), the middle of the upper surface (lead-in along the outward normal), the
/// leading edge (lead-in along the chord ahead of it) and the middle of the lower surface, on
/// the foils `ENTRY_FOILS` names (default the first three). CV of E before → after each.
fn entries(foils: &[PathBuf], panels: usize) {
    use cell_planner::exposure::coefficient_of_variation;
    use cell_planner::refine::{refine, RefineConfig};
    use nalgebra::Vector2;
    println!("\nEntry point (refinement alone from the baseline; CV before → after):\n");
    println!("| foil | trailing edge | upper middle | leading edge | lower middle |\n|---|---|---|---|---|");
    for path in three_or_named(foils, "ENTRY_FOILS") {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let Section {
            job,
            foil,
            offset,
            baseline,
            surface_points,
        } = section(&path, panels);
        let m = baseline.points().len() - 1;
        let le = (0..m)
            .min_by(|&a, &b| baseline.points()[a].x.total_cmp(&baseline.points()[b].x))
            .unwrap();
        let mut cells = Vec::new();
        for vertex in [0, le / 2, le, (le + m) / 2] {
            let problem = Problem::new(
                &foil,
                surface_points,
                baseline.clone(),
                Objective::default(),
            )
            .and_then(|p| p.entering_at(vertex))
            .unwrap();
            let b = problem.trajectory().baseline();
            let (first, normal) = (b.points()[0], b.normals()[0]);
            let start = match vertex {
                0 => lead_in_start(foil.points(), job.lead_in_mm, offset),
                v if v == le => first - Vector2::new(job.lead_in_mm, 0.0),
                _ => first + normal * job.lead_in_mm,
            };
            let cell = match problem.with_lead_in(start) {
                Ok(p) => {
                    let zero = vec![0.0; p.dimension()];
                    let config = RefineConfig {
                        iterations: 200,
                        ..RefineConfig::default()
                    };
                    let r = refine(&p, &zero, &config, |_| ControlFlow::Continue(()));
                    format!(
                        "{:.3} → {:.3}",
                        coefficient_of_variation(&p.exposure(&zero).unwrap()),
                        coefficient_of_variation(&p.exposure(&r.controls).unwrap())
                    )
                }
                Err(e) => format!("lead-in refused: {e}"),
            };
            cells.push(cell);
        }
        println!("| {name} | {} |", cells.join(" | "));
    }
}

/// The crate docs' evidence ("Why the swarm stalled"): each change on top of the previous
/// one, on three foils (`LADDER_FOILS`, default the first three), as the planner reports it
/// (rows without a lead-in measure the loop alone, as the planner did then).
fn ladder(foils: &[PathBuf], panels: usize) {
    use cell_planner::refine::RefineConfig;
    use cell_planner::spline::SplineEnds;
    use cell_planner::trajectory::ControlSpacing;
    let picks = three_or_named(foils, "LADDER_FOILS");
    let paper = |job: HotwireJob| HotwireJob {
        objective: Objective {
            feed: None,
            ends: SplineEnds::Periodic,
            spacing: ControlSpacing::ArcLength,
            ..Objective::default()
        },
        pso: PsoConfig {
            initial_velocity_mm: 0.05,
            restart_velocity_mm: 0.05,
            stall_iterations: 0,
            ..PsoConfig::default()
        },
        refine: RefineConfig {
            iterations: 0,
            ..RefineConfig::default()
        },
        lead_in_mm: 0.0,
        ..job
    };
    type Step = fn(HotwireJob) -> HotwireJob;
    let steps: [(&str, Step); 11] = [
        (
            "the swarm as it was (±0.05 mm start velocity, no lead-in in the model)",
            |j| j,
        ),
        ("+ the 10 mm lead-in's heat in the model", |j| HotwireJob {
            lead_in_mm: 10.0,
            ..j
        }),
        ("+ start/restart velocity ±0.3/±0.1 mm", |j| HotwireJob {
            pso: PsoConfig {
                initial_velocity_mm: 0.3,
                restart_velocity_mm: 0.1,
                ..j.pso
            },
            ..j
        }),
        ("+ Levenberg–Marquardt refinement", |j| HotwireJob {
            refine: RefineConfig::default(),
            ..j
        }),
        ("+ feed as a variable", |j| HotwireJob {
            objective: Objective {
                feed: Objective::default().feed,
                ..j.objective
            },
            ..j
        }),
        ("+ open spline ends", |j| HotwireJob {
            objective: Objective {
                ends: SplineEnds::Open,
                ..j.objective
            },
            ..j
        }),
        ("+ controls clustered like the panels", |j| HotwireJob {
            objective: Objective {
                spacing: ControlSpacing::PathPoints,
                ..j.objective
            },
            ..j
        }),
        ("+ stop the swarm when it stalls (the default job)", |j| {
            HotwireJob {
                pso: PsoConfig {
                    stall_iterations: PsoConfig::default().stall_iterations,
                    ..j.pso
                },
                ..j
            }
        }),
        ("(option) + lead-in up to 40 mm", |j| HotwireJob {
            lead_in_max_mm: Some(40.0),
            ..j
        }),
        ("(option) + current 0.7–1.3 × nominal", |j| HotwireJob {
            objective: Objective {
                feed: j.objective.feed.map(|f| f.with_current_band((0.7, 1.3))),
                ..j.objective
            },
            ..j
        }),
        (
            "(for comparison) the default job's refinement alone, no swarm",
            |j| HotwireJob {
                lead_in_max_mm: None,
                objective: Objective::default(),
                pso: PsoConfig {
                    iterations: 0,
                    ..j.pso
                },
                ..j
            },
        ),
    ];
    println!("\nLadder (each row adds one change; CV base → opt, p95 abs(E−CSE) base → opt, s):\n");
    let names: Vec<String> = picks
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
        .collect();
    println!("| change | {} |", names.join(" | "));
    println!("|---|{}", "---|".repeat(names.len()));
    let mut jobs: Vec<HotwireJob> = picks
        .iter()
        .map(|p| {
            paper(HotwireJob {
                root_airfoil: AirfoilSource::File(p.clone()),
                panels,
                ..HotwireJob::default()
            })
        })
        .collect();
    for (label, step) in steps {
        let mut cells = Vec::new();
        for job in &mut jobs {
            *job = step(job.clone());
            let t = Instant::now();
            let cell = match plan(job, |_| ControlFlow::Continue(())) {
                Ok(p) => format!(
                    "{:.3} → {:.3}, {:.2} → {:.2}, {:.1}",
                    p.root.baseline_stats.cv,
                    p.root.optimised_stats.cv,
                    p.root.baseline_stats.p95_abs,
                    p.root.optimised_stats.p95_abs,
                    t.elapsed().as_secs_f64()
                ),
                Err(e) => format!("failed: {e}"),
            };
            cells.push(cell);
        }
        println!("| {label} | {} |", cells.join(" | "));
    }
}

/// One foil's default job at `panels` panels and what the optimiser starts from.
struct Section {
    job: HotwireJob,
    /// Normalised, scaled to 200 mm.
    foil: cell_planner::airfoil::Airfoil,
    /// The job's kerf-model offset (mm).
    offset: f64,
    /// The fixed-offset baseline at the job's resolution.
    baseline: Baseline,
    /// Resampled points for `panels` surface panels.
    surface_points: usize,
}

fn section(path: &Path, panels: usize) -> Section {
    let job = HotwireJob {
        root_airfoil: AirfoilSource::File(path.to_path_buf()),
        panels,
        ..HotwireJob::default()
    };
    // The job's offset, from a plan with no swarm iterations.
    let quick = HotwireJob {
        pso: PsoConfig {
            iterations: 0,
            ..PsoConfig::default()
        },
        ..job.clone()
    };
    let offset = plan(&quick, |_| ControlFlow::Continue(()))
        .expect("plan")
        .root
        .offset_mm;
    let foil = job
        .root_airfoil
        .load()
        .unwrap()
        .normalised()
        .scaled(200.0)
        .unwrap();
    let baseline = Baseline::fixed_offset(&foil, offset, panels + panels / 2).unwrap();
    let surface_points = surface_points(&foil, panels).unwrap();
    Section {
        job,
        foil,
        offset,
        baseline,
        surface_points,
    }
}

/// The paper's swarm (constant feed, no refinement) here and in NumPy on the same problems.
fn peer_rows(foils: &[PathBuf], panels: usize) {
    let iterations: usize = std::env::var("PEER_ITERATIONS")
        .ok()
        .map_or(2000, |v| v.parse().expect("PEER_ITERATIONS"));
    let picks = three_or_named(foils, "PEER_FOILS");
    let python = std::env::var("PEER_PYTHON").ok();
    println!(
        "\nThe paper's swarm alone, {iterations} iterations, constant feed, no refinement:\n\n\
         | foil | here: CV base → opt | here s | NumPy: CV base → opt | NumPy s |\n|---|---|---|---|---|"
    );
    for path in picks {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let Section {
            job,
            foil,
            offset,
            baseline,
            surface_points,
        } = section(&path, panels);
        let objective = Objective {
            feed: None,
            ..Objective::default()
        };
        let start = lead_in_start(foil.points(), job.lead_in_mm, offset);
        let problem = Problem::new(&foil, surface_points, baseline.clone(), objective)
            .unwrap()
            .with_lead_in(start)
            .unwrap();
        let config = PsoConfig {
            iterations,
            stall_iterations: 0,
            ..PsoConfig::default()
        };
        let t = Instant::now();
        let r = optimise(&problem, &config, |_| ControlFlow::Continue(())).unwrap();
        let here_s = t.elapsed().as_secs_f64();
        let cse = problem.cse();
        let base = ExposureStats::of(&problem.exposure(&vec![0.0; 32]).unwrap(), cse);
        let opt = ExposureStats::of(&problem.exposure(&r.controls).unwrap(), cse);
        let peer = python.as_deref().map(|py| {
            run_peer(
                py,
                &foil,
                surface_points,
                &baseline,
                start,
                &objective,
                &config,
            )
        });
        let peer_text = match peer {
            Some(Ok((b, o, s))) => format!("{b:.3} → {o:.3} | {s:.1}"),
            Some(Err(e)) => format!("failed: {e} |"),
            None => "(set PEER_PYTHON) |".into(),
        };
        println!(
            "| {name} | {:.3} → {:.3} | {here_s:.1} | {peer_text} |",
            base.cv, opt.cv
        );
    }
}

/// Writes the problem file `benches/pso_peer.py` reads and runs it: (CV before, after, s).
fn run_peer(
    python: &str,
    foil: &cell_planner::airfoil::Airfoil,
    surface_points: usize,
    baseline: &Baseline,
    lead_start: nalgebra::Point2<f64>,
    objective: &Objective,
    config: &PsoConfig,
) -> Result<(f64, f64, f64), String> {
    let xy =
        |p: &[nalgebra::Point2<f64>]| -> Vec<[f64; 2]> { p.iter().map(|q| [q.x, q.y]).collect() };
    let mut surface = foil
        .resampled_cosine(surface_points)
        .unwrap()
        .points()
        .to_vec();
    surface.dedup();
    if surface.len() > 1 && surface.first() == surface.last() {
        surface.pop();
    }
    let loop_points = baseline.points();
    let problem = serde_json::json!({
        "surface": xy(&surface),
        "loop": xy(loop_points),
        "normals": baseline.normals().iter().map(|n| [n.x, n.y]).collect::<Vec<_>>(),
        "arc_u": baseline.arc_positions(),
        "lead_in": xy(&[lead_start, loop_points[0]]),
        "outline": xy(foil.points()),
        "min_clearance_mm": objective.min_clearance_mm,
        "min_distance_mm": objective.model.min_distance_mm,
        "window": cell_planner::exposure::CAUSAL_WINDOW,
        "law": "paper",
        "cse": null,
        "control_points": objective.control_points,
        "smoothing": objective.smoothing,
        "pso": {
            "particles": config.particles, "iterations": config.iterations,
            "restart_every": config.restart_every, "inertia": config.inertia,
            "cognitive": config.cognitive, "social": config.social,
            "initial_velocity_mm": config.initial_velocity_mm,
            "restart_velocity_mm": config.restart_velocity_mm, "seed": config.seed
        }
    });
    let file = std::env::temp_dir().join(format!("pso_peer_{}.json", std::process::id()));
    std::fs::write(&file, problem.to_string()).map_err(|e| e.to_string())?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/pso_peer.py");
    let out = std::process::Command::new(python)
        .arg(&script)
        .arg(&file)
        .output()
        .map_err(|e| format!("{python}: {e}"))?;
    let _ = std::fs::remove_file(&file);
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr)
            .lines()
            .last()
            .unwrap_or("")
            .to_string());
    }
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).map_err(|e| format!("peer output: {e}"))?;
    let f = |k: &str| v[k]["cv"].as_f64().unwrap_or(f64::NAN);
    Ok((
        f("baseline"),
        f("optimised"),
        v["seconds"].as_f64().unwrap_or(f64::NAN),
    ))
}
