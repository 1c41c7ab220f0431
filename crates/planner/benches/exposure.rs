//! One exposure evaluation (seed 000 eq. 1–5, closed form, causal cut point) on S1223, chord
//! 200 mm, 0.5 mm fixed offset, at N = 100, 200, 400 surface panels and the job's wire
//! resolution (1.5·N path points before the offset, so M ≈ 1.5·N + 20 segments): µs per
//! evaluation, single-threaded, for the fast path and the f64 reference, both distance laws,
//! next to a NumPy peer (`benches/exposure_peer.py`, N × M arrays) run on the same geometry,
//! whose values are cross-checked against the Rust ones.
//!
//! `CARGO_TARGET_DIR=/tmp/target-speed cargo bench -p cell_planner --bench exposure`
//! Options (environment): `EXPOSURE_N=100,400` picks panel counts; `EXPOSURE_PEER=0` skips the
//! NumPy peer (it needs `python3` with numpy: `pip install numpy`); `EXPOSURE_PROFILE=3` only
//! runs the fast path (paper law) for 3 s per N, for a profiler.

use std::fmt::Write as _;
use std::process::Command;
use std::time::{Duration, Instant};

use cell_planner::airfoil::Airfoil;
use cell_planner::exposure::{
    Causal, DistanceLaw, ExposureModel, Panels, WireSegments, CAUSAL_WINDOW,
};
use cell_planner::trajectory::Baseline;
use nalgebra::Point2;

/// Best of 5 batches of µs per call, each batch at least 60 ms.
fn time_us(mut f: impl FnMut()) -> f64 {
    let mut batch = 1usize;
    loop {
        let t = Instant::now();
        for _ in 0..batch {
            f();
        }
        if t.elapsed() > Duration::from_millis(60) {
            break;
        }
        batch *= 2;
    }
    (0..5)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..batch {
                f();
            }
            t.elapsed().as_secs_f64() * 1e6 / batch as f64
        })
        .fold(f64::INFINITY, f64::min)
}

/// max |a − b| / max(|b|, mean |b|) (the fast path's test tolerance measure).
fn worst_error(a: &[f64], b: &[f64]) -> f64 {
    let mean = b.iter().map(|v| v.abs()).sum::<f64>() / b.len() as f64;
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / y.abs().max(mean))
        .fold(0.0, f64::max)
}

fn law_name(law: DistanceLaw) -> &'static str {
    match law {
        DistanceLaw::Paper => "paper",
        DistanceLaw::AuthorCode => "author_code",
    }
}

fn json_points(points: &[Point2<f64>]) -> String {
    let mut s = String::from("[");
    for (k, p) in points.iter().enumerate() {
        if k > 0 {
            s.push(',');
        }
        // Shortest round-trip representation: the peer sees exactly these doubles.
        write!(s, "[{:?},{:?}]", p.x, p.y).unwrap();
    }
    s.push(']');
    s
}

/// Runs the NumPy peer on the geometry; `None` (with a message) if it cannot run.
fn run_peer(
    surface: &[Point2<f64>],
    wire: &[Point2<f64>],
    model: &ExposureModel,
) -> Option<serde_json::Value> {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/exposure_peer.py");
    let file = std::env::temp_dir().join(format!("exposure_peer_{}.json", std::process::id()));
    let spec = format!(
        r#"{{"surface":{},"wire":{},"min_distance_mm":{:?},"window":{:?},"settings":[["paper","cut_point"],["author_code","cut_point"]],"min_seconds":1.0}}"#,
        json_points(surface),
        json_points(wire),
        model.min_distance_mm,
        CAUSAL_WINDOW
    );
    std::fs::write(&file, spec).expect("write the peer's input");
    // glibc's malloc thresholds raised, as the notes' best NumPy figures need (N × M
    // temporaries otherwise go through mmap/munmap on every operation); one thread.
    let out = Command::new("python3")
        .arg(script)
        .arg(&file)
        .env("MALLOC_MMAP_THRESHOLD_", "1073741824")
        .env("MALLOC_TRIM_THRESHOLD_", "1073741824")
        .env("MALLOC_TOP_PAD_", "268435456")
        .env("OMP_NUM_THREADS", "1")
        .env("OPENBLAS_NUM_THREADS", "1")
        .output();
    let _ = std::fs::remove_file(&file);
    match out {
        Err(e) => {
            println!("  NumPy peer skipped: cannot run python3 ({e}); install Python 3 and `pip install numpy`");
            None
        }
        Ok(o) if !o.status.success() => {
            let err = String::from_utf8_lossy(&o.stderr);
            if err.contains("No module named 'numpy'") {
                println!("  NumPy peer skipped: numpy is not installed (`pip install numpy`)");
            } else {
                println!("  NumPy peer failed: {}", err.trim());
            }
            None
        }
        Ok(o) => Some(serde_json::from_slice(&o.stdout).expect("peer JSON")),
    }
}

fn main() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../config/airfoils/s1223.dat"
    );
    let foil = Airfoil::load(path)
        .and_then(|f| f.scaled(200.0))
        .expect("s1223");
    let ns: Vec<usize> = std::env::var("EXPOSURE_N")
        .ok()
        .map(|v| {
            v.split(',')
                .map(|n| n.trim().parse().expect("EXPOSURE_N"))
                .collect()
        })
        .unwrap_or_else(|| vec![100, 200, 400]);
    let peer_on = std::env::var("EXPOSURE_PEER").map_or(true, |v| v != "0");
    println!(
        "S1223 chord 200 mm, 0.5 mm fixed offset, causal cut point; µs per evaluation, one thread"
    );
    let mut table = Vec::new();
    for n in ns {
        // As the job does: a sharp trailing edge repeats its point, so one more gives N panels.
        let probe = foil.resampled_cosine(n).expect("resample");
        let closed = probe.points().first() == probe.points().last();
        let surface_pts = foil
            .resampled_cosine(if closed { n + 1 } else { n })
            .expect("resample")
            .points()
            .to_vec();
        let surface = Panels::from_points(&surface_pts).expect("panels");
        let wire_pts = Baseline::fixed_offset(&foil, 0.5, n + n / 2)
            .expect("baseline")
            .points()
            .to_vec();
        let wire = WireSegments::from_points(&wire_pts).expect("wire");
        let (nn, m) = (surface.len(), wire.len());
        println!("N={nn} M={m}");
        let model = |law| ExposureModel {
            law,
            causal: Causal::CutPoint,
            ..ExposureModel::default()
        };
        let peer = if peer_on {
            // The peer gets the distinct surface points, as `Panels` uses them.
            let mut ring = surface_pts.clone();
            ring.dedup();
            if ring.len() > 1 && ring.first() == ring.last() {
                ring.pop();
            }
            run_peer(&ring, &wire_pts, &model(DistanceLaw::Paper))
        } else {
            println!("  NumPy peer skipped (EXPOSURE_PEER=0)");
            None
        };
        if let Ok(secs) = std::env::var("EXPOSURE_PROFILE") {
            // Only the fast path, for a profiler: `EXPOSURE_PROFILE=3 perf record …`.
            let m_ = model(DistanceLaw::Paper);
            let mut out = vec![0.0; nn];
            let t = Instant::now();
            while t.elapsed().as_secs_f64() < secs.parse::<f64>().unwrap_or(3.0) {
                m_.exposure_into(&surface, &wire, &mut out).unwrap();
            }
            continue;
        }
        for law in [DistanceLaw::Paper, DistanceLaw::AuthorCode] {
            let m_ = model(law);
            let mut fast = vec![0.0; nn];
            let mut reference = vec![0.0; nn];
            m_.exposure_into(&surface, &wire, &mut fast).unwrap();
            m_.exposure_reference_into(&surface, &wire, &mut reference)
                .unwrap();
            let t_fast = time_us(|| {
                m_.exposure_into(&surface, &wire, &mut fast).unwrap();
                std::hint::black_box(&fast);
            });
            let t_ref = time_us(|| {
                m_.exposure_reference_into(&surface, &wire, &mut reference)
                    .unwrap();
                std::hint::black_box(&reference);
            });
            let off = ExposureModel {
                causal: Causal::Off,
                ..m_
            };
            let t_off = time_us(|| {
                off.exposure_into(&surface, &wire, &mut fast).unwrap();
                std::hint::black_box(&fast);
            });
            m_.exposure_into(&surface, &wire, &mut fast).unwrap();
            let err = worst_error(&fast, &reference);
            let mut line = format!(
                "  {:<11} fast {t_fast:7.1} µs (causal off {t_off:7.1})  reference {t_ref:8.1} µs  \
                 ×{:5.1}  fast vs reference {err:.1e}",
                law_name(law),
                t_ref / t_fast
            );
            let mut numpy = None;
            if let Some(peer) = &peer {
                let r = peer["results"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .find(|r| r["law"] == law_name(law))
                    .expect("peer result");
                let us = r["us_per_eval"].as_f64().unwrap();
                let values: Vec<f64> = r["values"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().unwrap())
                    .collect();
                assert_eq!(values.len(), nn, "peer panel count");
                let peer_ref = worst_error(&values, &reference);
                let peer_fast = worst_error(&fast, &values);
                write!(
                    line,
                    "\n  {:<11} NumPy {us:8.1} µs  fast is ×{:.1} faster; NumPy vs reference \
                     {peer_ref:.1e}, fast vs NumPy {peer_fast:.1e}",
                    "",
                    us / t_fast
                )
                .unwrap();
                numpy = Some(us);
            }
            println!("{line}");
            table.push((nn, m, law, t_fast, t_ref, numpy));
        }
    }
    println!("\n| N | M | law | fast µs | reference µs | NumPy µs | NumPy / fast |");
    println!("|---|---|---|---|---|---|---|");
    for (n, m, law, f, r, np) in table {
        let (np_s, ratio) = match np {
            Some(v) => (format!("{v:.0}"), format!("{:.0}×", v / f)),
            None => ("–".into(), "–".into()),
        };
        println!(
            "| {n} | {m} | {} | {f:.1} | {r:.0} | {np_s} | {ratio} |",
            law_name(law)
        );
    }
}
