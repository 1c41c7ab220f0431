//! A resumed program runs in the machine state of an uninterrupted one: the emitter's G93
//! hot-wire and M4 laser programs (and its pierce-height sequence on an XYZ table) are stopped
//! at each line with a safe stop (feed hold, reset, `M5`), then resumed there with the
//! preamble of `cell_grbl::resume`; the simulator's parser state (`$G` and position) after
//! every line from the resumed one on must equal the uninterrupted run's, and no line may be
//! lost or run twice. In-process simulator, paused tokio clock.

mod common;

use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::protocol::MachineState;
use cell_grbl::resume::preamble;
use cell_grbl::sim::{ExecutedLine, ParserState, SimConfig, SimHandle};
use cell_grbl::stream::{Fault, FlowControl};
use common::*;

/// A program the emitter wrote: its snapshot under `crates/emitter/tests/snapshots/`, without
/// the snapshot's header.
fn emitted(profile: &str) -> Program {
    let path = format!(
        "{}/../emitter/tests/snapshots/dialects__{profile}.snap",
        env!("CARGO_MANIFEST_DIR")
    );
    let snap = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let body = snap.splitn(3, "---\n").nth(2).expect("a snapshot header");
    Program::parse(body, CleanOptions::default()).expect("the emitter's program parses")
}

/// The emitter's pierce-height sequence (`dialects__linuxcnc-plasma.snap`) written for GRBL
/// (no `G64`, which GRBL lacks): travel at Z10, pierce at Z3.8, cut at Z1.5.
fn plasma() -> Program {
    let text = "G17 G21 G90 G94\nG0 Z10\nG0 X0 Y0\nG0 X70 Y50\nG0 Z3.8\nM3 S80\nG4 P0.5\n\
                G1 Z1.5 F1200\nG3 X69.833 Y48.178 I-10 J-0.002\nG3 X70 Y50 I-9.833 J1.82\nM5\n\
                G0 Z10\nG0 X20 Y25\nG0 Z3.8\nM3 S80\nG4 P0.5\nG1 Z1.5\nG1 X92 Y25 F600\n\
                G3 X100 Y33 I0 J8\nG1 X100 Y75\nM5\nG0 Z10\nM2\n";
    Program::parse(text, CleanOptions::default()).unwrap()
}

fn sim_config(axes: &str) -> SimConfig {
    SimConfig {
        axes: axes.chars().collect(),
        ..SimConfig::default()
    }
}

/// The executed log of the whole program, uninterrupted.
async fn uninterrupted(program: &Program, axes: &str) -> Vec<ExecutedLine> {
    let (sim, client) = in_process(sim_config(axes), FlowControl::CharacterCounting).await;
    client.stream(program).await.expect("the program runs");
    let log = sim.executed();
    assert_eq!(
        log.iter().map(|l| l.text.clone()).collect::<Vec<_>>(),
        texts(program)
    );
    log
}

/// How the run before the resume ends.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Stop {
    /// Abort while the resumed line's move runs: the machine stops part-way along it.
    InTheLine,
    /// Run the lines before it, then a safe stop with the machine idle.
    BeforeTheLine,
}

/// Runs `program` up to its line at index `k`, stops as `stop` says, resumes from that line
/// with (or, for the control, without) the preamble; returns the simulator, the index in its
/// log of the first line after the stop, and the preamble sent.
async fn stop_and_resume(
    program: &Program,
    axes: &str,
    k: usize,
    stop: Stop,
    with_preamble: bool,
) -> (SimHandle, usize, Vec<String>) {
    let n = program.lines()[k].number;
    let (sim, client) = in_process(sim_config(axes), FlowControl::CharacterCounting).await;
    match stop {
        Stop::InTheLine => {
            let streamer = {
                let (client, program) = (client.clone(), program.clone());
                tokio::spawn(async move { client.stream(&program).await })
            };
            sim.wait_for(WAIT, |s| s.executed == k && s.state == MachineState::Run)
                .await
                .unwrap_or_else(|s| panic!("line {n} never ran: {s:?}"));
            // The abort goes out once the client's own status reports show the line running.
            let mut progress = client.progress();
            progress
                .wait_for(|p| p.status.as_ref().and_then(|s| s.state) == Some(MachineState::Run))
                .await
                .unwrap();
            client.abort().await.unwrap();
            let err = streamer.await.unwrap().expect_err("aborted");
            assert_eq!(err.fault, Fault::Aborted);
            let stop = err.safe_stop.expect("safe stop");
            assert!(stop.heat_off_acked, "line {n}: {stop:?} {:?}", sim.events());
        }
        Stop::BeforeTheLine => {
            let before = Program::from_clean_lines(&texts(program)[..k]).unwrap();
            client.stream(&before).await.expect("the lines before run");
            assert!(client.safe_stop().await.heat_off_acked);
        }
    }
    let ran: Vec<String> = sim.executed_lines();
    assert_eq!(
        ran[..k],
        texts(program)[..k],
        "{stop:?} at line {n}: the lines before it ran, and not it"
    );
    assert_eq!(ran[k..], ["M5"], "{stop:?} at line {n}: the safe stop's M5");
    let reset = sim.parser_state();
    assert_eq!(
        (reset.spindle.as_str(), reset.feed_mode.as_str()),
        ("M5", "G94"),
        "the reset left GRBL's defaults"
    );
    let after_stop = ran.len();
    let pre = if with_preamble {
        preamble(program, n).unwrap_or_else(|e| panic!("{e}"))
    } else {
        Vec::new()
    };
    for line in &pre {
        client
            .command(line)
            .await
            .unwrap_or_else(|e| panic!("{line}: {e}"));
    }
    client
        .stream_from(program, n)
        .await
        .unwrap_or_else(|e| panic!("resumed at {n}: {e}"));
    (sim, after_stop, pre)
}

/// The parts of a parser state a resume must restore (the motion mode only where a line
/// moves in it).
fn restored(s: &ParserState, moves: bool) -> String {
    let pos: Vec<String> = s.work_position.iter().map(|p| format!("{p:.4}")).collect();
    format!(
        "{} {} {} {} {} {} {} {} {} {} {} at {}",
        if moves { s.motion.as_str() } else { "-" },
        s.coordinate_system,
        s.plane,
        s.units,
        s.distance,
        s.feed_mode,
        s.feed,
        s.spindle,
        s.spindle_speed,
        s.coolant,
        s.tool,
        pos.join(",")
    )
}

fn moves(text: &str) -> bool {
    text.chars().any(|c| "XYZUV".contains(c))
}

/// Every resume point of `program`, also stopped part-way along the line where it is a feed
/// move long enough (a second) for the client to see it run.
async fn every_line_resumes_as_if_uninterrupted(program: Program, axes: &str) {
    let reference = uninterrupted(&program, axes).await;
    let lines = program.lines();
    let mut stopped_in_a_line = 0;
    for k in 1..lines.len() {
        let long_feed_move = moves(&lines[k].text)
            && !lines[k].text.starts_with("G0")
            && reference[k].at_s - reference[k - 1].at_s > 1.0;
        let stops: &[Stop] = if long_feed_move {
            &[Stop::InTheLine, Stop::BeforeTheLine]
        } else {
            &[Stop::BeforeTheLine]
        };
        for &stop in stops {
            stopped_in_a_line += usize::from(stop == Stop::InTheLine);
            let (sim, after_stop, pre) = stop_and_resume(&program, axes, k, stop, true).await;
            let log = sim.executed();
            let what = format!("{stop:?}, resumed at line {}", lines[k].number);
            let sent: Vec<&str> = log[after_stop..].iter().map(|l| l.text.as_str()).collect();
            let expected: Vec<&str> = pre
                .iter()
                .map(String::as_str)
                .chain(lines[k..].iter().map(|l| l.text.as_str()))
                .collect();
            assert_eq!(sent, expected, "{what}: the preamble, then every line once");
            for l in &log[after_stop..after_stop + pre.len()] {
                if l.text.starts_with("G0") && moves(&l.text) {
                    assert_eq!(
                        l.parser.spindle, "M5",
                        "{what}: {} with the heat on",
                        l.text
                    );
                }
            }
            // The heat goes on only where the program had it on, at the resumed line's start
            // and at the height the program switched it on at (the pierce height).
            let heat_on = |l: &&ExecutedLine| l.text.starts_with("M3") || l.text.starts_with("M4");
            let on = log[after_stop..after_stop + pre.len()].iter().find(heat_on);
            assert_eq!(
                on.is_some(),
                reference[k - 1].parser.spindle != "M5",
                "{what}: {pre:?}"
            );
            if let Some(on) = on {
                let program_on = reference[..k].iter().rev().find(heat_on).unwrap();
                let expected: Vec<String> = axes
                    .chars()
                    .enumerate()
                    .map(|(i, a)| {
                        let from = if a == 'Z' {
                            program_on
                        } else {
                            &reference[k - 1]
                        };
                        format!("{:.4}", from.parser.work_position[i])
                    })
                    .collect();
                let got: Vec<String> = on
                    .parser
                    .work_position
                    .iter()
                    .map(|p| format!("{p:.4}"))
                    .collect();
                assert_eq!(got, expected, "{what}: where the heat went on");
            }
            let resumed = &log[after_stop + pre.len()..];
            for (r, u) in resumed.iter().zip(&reference[k..]) {
                let m = moves(&u.text);
                assert_eq!(
                    restored(&r.parser, m),
                    restored(&u.parser, m),
                    "{what}: the state after `{}`",
                    u.text
                );
            }
        }
    }
    assert!(
        stopped_in_a_line >= 2,
        "only {stopped_in_a_line} stops inside a cut"
    );
}

#[tokio::test(start_paused = true)]
async fn a_g93_hot_wire_program_resumes_in_its_own_state_at_every_line() {
    every_line_resumes_as_if_uninterrupted(emitted("grbl-xyuv"), "XYUV").await;
}

#[tokio::test(start_paused = true)]
async fn an_m4_laser_program_resumes_in_its_own_state_at_every_line() {
    every_line_resumes_as_if_uninterrupted(emitted("grbl-laser"), "XY").await;
}

#[tokio::test(start_paused = true)]
async fn a_pierce_height_program_resumes_with_a_fresh_pierce_at_every_line() {
    every_line_resumes_as_if_uninterrupted(plasma(), "XYZ").await;
}

/// The control: without the preamble the G93 cut goes on in G94 with the wire cold, which the
/// comparison above sees.
#[tokio::test(start_paused = true)]
async fn without_the_preamble_the_hot_wire_cut_goes_on_cold_in_g94() {
    let program = emitted("grbl-xyuv");
    let reference = uninterrupted(&program, "XYUV").await;
    let k = program
        .lines()
        .iter()
        .position(|l| l.text.starts_with("G1") && l.text.contains("F4.9752"))
        .unwrap();
    let (sim, after_stop, pre) = stop_and_resume(&program, "XYUV", k, Stop::InTheLine, false).await;
    assert!(pre.is_empty());
    let resumed = &sim.executed()[after_stop];
    assert_eq!(resumed.text, reference[k].text);
    assert_eq!(
        (
            reference[k].parser.feed_mode.as_str(),
            reference[k].parser.spindle.as_str()
        ),
        ("G93", "M3")
    );
    assert_eq!(
        (
            resumed.parser.feed_mode.as_str(),
            resumed.parser.spindle.as_str()
        ),
        ("G94", "M5")
    );
    assert_ne!(
        restored(&resumed.parser, true),
        restored(&reference[k].parser, true)
    );
}
