//! Feed rates far beyond the machine's (fuzzer findings `minimal-g1-f-2pow64` and
//! `minimal-f-i64-max-arc-after-m3` in crates/fuzz/corpus/grbl_sim): GRBL 1.1 clamps a feed
//! move to the axes' max rate (`$110`-`$112`, `plan_compute_profile_nominal_speed`), so
//! `F18446744073709551616` runs at the max rate and the move ends where it should. The
//! simulator used to take such a move at the commanded rate, a duration below the resolution
//! of its clock, and loop for ever.

use std::sync::mpsc;
use std::time::Duration;

use cell_grbl::protocol::MachineState;
use cell_grbl::sim::{self, ExecutedLine, SimConfig, SimFirmware, SimSnapshot};
use tokio::io::AsyncWriteExt;

/// Wall time a case may take: a hang fails the test instead of stalling it.
const WALL: Duration = Duration::from_secs(1);

/// Sends `lines` to a fresh simulator on a paused clock and waits (simulated time) until every
/// line has run and the machine is idle; the final snapshot and the executed-line log. Runs on
/// its own thread, so a simulator that never returns fails the test after [`WALL`].
fn run(firmware: SimFirmware, lines: &'static [&'static str]) -> (SimSnapshot, Vec<ExecutedLine>) {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .start_paused(true)
            .build()
            .expect("a current-thread runtime");
        let got = rt.block_on(async {
            let sim = sim::start(SimConfig::for_firmware(firmware));
            let (host, controller) = tokio::io::duplex(1 << 16);
            sim.attach(controller);
            let (mut rd, mut wr) = tokio::io::split(host);
            tokio::spawn(async move { tokio::io::copy(&mut rd, &mut tokio::io::sink()).await });
            for line in lines {
                wr.write_all(format!("{line}\n").as_bytes())
                    .await
                    .expect("write");
            }
            let end = sim
                .wait_for(Duration::from_secs(60), |s| {
                    s.executed == lines.len() && s.state == MachineState::Idle
                })
                .await
                .unwrap_or_else(|s| panic!("{firmware:?}: lines did not all run: {s:?}"));
            (end, sim.executed())
        });
        let _ = tx.send(got);
    });
    rx.recv_timeout(WALL)
        .unwrap_or_else(|e| panic!("{firmware:?} {lines:?}: no result within {WALL:?} ({e})"))
}

/// When the executed line `text` took effect (simulated s).
fn at(log: &[ExecutedLine], text: &str) -> f64 {
    log.iter()
        .find(|l| l.text == text)
        .unwrap_or_else(|| panic!("{text} not executed: {log:?}"))
        .at_s
}

const FIRMWARES: [SimFirmware; 3] = [
    SimFirmware::Grbl11h,
    SimFirmware::GrblHal,
    SimFirmware::FluidNc,
];

#[test]
fn a_line_at_2_pow_64_mm_per_min_runs_at_the_max_rate_to_x5() {
    let max_mm_s = SimConfig::default().rapid_mm_min / 60.0;
    for fw in FIRMWARES {
        let (end, log) = run(fw, &["G1 X5 F18446744073709551616"]);
        assert_eq!(end.position, [5.0, 0.0, 0.0], "{fw:?}");
        // The move starts once its 28 bytes have arrived (a few ms at 115200 baud) and takes
        // 5 mm at the max rate.
        let took = at(&log, "G1 X5 F18446744073709551616");
        let min = 5.0 / max_mm_s;
        assert!(
            (min..min + 0.01).contains(&took),
            "{fw:?}: ended at {took} s"
        );
    }
}

#[test]
fn an_arc_after_a_line_at_i64_max_mm_per_min_runs_at_the_max_rate_to_x20() {
    let max_mm_s = SimConfig::default().rapid_mm_min / 60.0;
    let lines = &[
        "G21",
        "M3 S1000",
        "G1 X10 F9223372036854775807",
        "G2 X20 I5 J0",
    ];
    for fw in FIRMWARES {
        let (end, log) = run(fw, lines);
        assert_eq!(end.position.len(), 3);
        assert!((end.position[0] - 20.0).abs() < 1e-9, "{fw:?}: {end:?}");
        assert!(end.position[1].abs() < 1e-9, "{fw:?}: {end:?}");
        // The line: 10 mm at the max rate after its bytes arrive; the arc, queued meanwhile,
        // starts as it ends: a half circle of radius 5 at the max rate.
        let line = at(&log, "G1 X10 F9223372036854775807") - at(&log, "M3 S1000");
        let min = 10.0 / max_mm_s;
        assert!(
            (min..min + 0.01).contains(&line),
            "{fw:?}: line took {line} s"
        );
        let arc = at(&log, "G2 X20 I5 J0") - at(&log, "G1 X10 F9223372036854775807");
        let want = 5.0 * std::f64::consts::PI / max_mm_s;
        assert!(
            (arc - want).abs() < 1e-9,
            "{fw:?}: arc took {arc} s, not {want}"
        );
    }
}
