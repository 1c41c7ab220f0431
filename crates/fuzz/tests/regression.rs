//! The fuzz targets on stable Rust, in CI: every saved finding (`crates/fuzz/corpus/<target>/`)
//! runs through its target without a panic and in bounded time, and every target survives a
//! small fixed-seed run of mutated inputs (the seeds first).

use std::time::{Duration, Instant};

use cell_fuzz::run::{self, Options};

/// Inputs per target in the small run; the two GRBL targets that run a tokio runtime, a link
/// task or a simulator per input get fewer (each input costs milliseconds unoptimised).
fn budget(name: &str) -> u64 {
    match name {
        "grbl_link" | "grbl_sim" | "marlin_link" | "marlin_sim" => 150,
        "layout_dxf" | "bag_reader" | "bag_repair" | "stl" => 600,
        _ => 2_000,
    }
}

#[test]
fn every_saved_finding_runs_clean() {
    let mut replayed = 0;
    let mut failures = Vec::new();
    for target in cell_fuzz::targets() {
        for (name, input) in run::saved_findings(target.name) {
            let started = Instant::now();
            if let Err(panic) = run::run_one(&target, &input) {
                failures.push(format!("{}/{name}: {panic}", target.name));
            }
            let took = started.elapsed();
            if took > Duration::from_secs(10) {
                failures.push(format!("{}/{name}: took {took:?}", target.name));
            }
            replayed += 1;
        }
    }
    cell_fuzz::remove_scratch();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    eprintln!("{replayed} saved findings replayed");
}

#[test]
fn every_target_survives_a_small_run() {
    let mut problems = Vec::new();
    for target in cell_fuzz::targets() {
        let seeds = (target.seeds)();
        assert!(!seeds.is_empty(), "{} has no seed inputs", target.name);
        let options = Options {
            inputs: budget(target.name),
            seed: 2026,
            timeout: Duration::from_secs(20),
            save: false,
        };
        let report = run::run(&target, &options);
        assert_eq!(
            report.inputs, options.inputs,
            "{}: not every input ran",
            target.name
        );
        for f in &report.findings {
            problems.push(format!(
                "{}: {:?} ×{}: {} (input {:?})",
                target.name,
                f.kind,
                f.hits,
                f.message,
                String::from_utf8_lossy(&f.input[..f.input.len().min(200)])
            ));
        }
        eprintln!(
            "{:<22} {:>6} inputs {:>8.0}/s",
            target.name,
            report.inputs,
            report.per_second()
        );
    }
    cell_fuzz::remove_scratch();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn a_panicking_target_is_a_finding_with_its_input() {
    fn panics_on_x(data: &[u8]) {
        assert!(!data.contains(&b'X'), "found an X");
    }
    let target = cell_fuzz::Target {
        name: "selftest",
        about: "panics on X",
        run: panics_on_x,
        seeds: || vec![b"abc".to_vec(), b"aXc".to_vec()],
        tokens: &["X"],
        max_len: 16,
    };
    let report = run::run(
        &target,
        &Options {
            inputs: 200,
            seed: 3,
            timeout: Duration::from_secs(5),
            save: false,
        },
    );
    assert_eq!(report.findings.len(), 1, "{:?}", report.findings);
    let f = &report.findings[0];
    assert!(f.input.contains(&b'X'));
    assert!(f.message.contains("found an X"), "{}", f.message);
    assert!(f.hits >= 1);
}

#[test]
fn a_hanging_target_is_a_finding() {
    fn hangs_on_h(data: &[u8]) {
        if data.first() == Some(&b'H') {
            std::thread::sleep(Duration::from_secs(3));
        }
    }
    let target = cell_fuzz::Target {
        name: "selftest_hang",
        about: "sleeps on H",
        run: hangs_on_h,
        seeds: || vec![b"ok".to_vec(), b"Hang".to_vec()],
        tokens: &[],
        max_len: 16,
    };
    let report = run::run(
        &target,
        &Options {
            inputs: 10,
            seed: 1,
            timeout: Duration::from_millis(300),
            save: false,
        },
    );
    assert!(report.hung(), "{:?}", report.findings);
    assert_eq!(report.findings.last().unwrap().input, b"Hang");
}
