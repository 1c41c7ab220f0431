//! Faults, safety and resume, end to end through the in-process simulator under a paused tokio
//! clock: every assertion is about the simulator's logs and simulated time, never wall-clock.

mod common;

use std::time::Duration;

use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::protocol::{MachineState, Realtime};
use cell_grbl::sim::{self, Faults, SimConfig, SimEvent};
use cell_grbl::stream::{ClientConfig, Fault, FaultAction, FlowControl, GrblClient};
use common::*;

fn with_bad_line(n: usize, at: usize, bad: &str) -> Program {
    let mut lines: Vec<String> = program_text(n).lines().map(str::to_string).collect();
    lines.insert(at, bad.to_string());
    Program::parse(&lines.join("\n"), CleanOptions::default()).unwrap()
}

/// The executed log, minus `skip`, is a prefix of the program minus `skip`.
fn assert_prefix(executed: &[String], program: &[String], skip: Option<&str>) {
    let prog: Vec<&String> = program
        .iter()
        .filter(|t| Some(t.as_str()) != skip)
        .collect();
    assert!(executed.len() <= prog.len());
    for (i, (e, p)) in executed.iter().zip(&prog).enumerate() {
        assert_eq!(e, *p, "executed line {i} differs from the program");
    }
}

#[tokio::test(start_paused = true)]
async fn bad_gcode_stops_streaming_with_its_original_line_and_heat_goes_off() {
    for flow in [FlowControl::CharacterCounting, FlowControl::SendResponse] {
        // Original line 40 (0-based 39) is `G1 X5 Q3`: Q is no GRBL word, error:20.
        let p = with_bad_line(200, 39, "G1 X5 Q3");
        let bad = p
            .lines()
            .iter()
            .find(|l| l.text == "G1 X5 Q3")
            .unwrap()
            .clone();
        assert_eq!(bad.number, 40);
        let (sim, client) = in_process(SimConfig::default(), flow).await;
        let err = client
            .stream(&p)
            .await
            .expect_err("the bad line stops the stream");
        match &err.fault {
            Fault::Rejected {
                line,
                code,
                message,
                ..
            } => {
                assert_eq!((*line, *code), (40, 20), "{err}");
                assert_eq!(*message, "Unsupported command");
            }
            other => panic!("expected a rejected line, got {other:?}"),
        }
        let last = err
            .last_acked_line
            .expect("lines before it were acknowledged");
        assert!(last < 40, "{err}");
        if flow == FlowControl::SendResponse {
            assert_eq!(last, 39, "send-response: the line before the bad one");
            assert!(err.unacked_lines.is_empty());
        }
        let stop = err.safe_stop.as_ref().expect("safe stop ran");
        assert_eq!(stop.sent, vec!["!", "0x18", "M5"], "{stop:?}");
        assert!(stop.stopped_before_reset && stop.reset_confirmed && stop.heat_off_acked);
        assert_eq!(
            stop.state_after,
            Some(MachineState::Idle),
            "hold before reset keeps position: no ALARM:3"
        );
        let texts = texts(&p);
        let executed = sim.executed_lines();
        assert!(!executed.contains(&bad.text));
        assert_prefix(&executed[..executed.len() - 1], &texts, Some(&bad.text));
        assert_eq!(
            executed.last().map(String::as_str),
            Some("M5"),
            "M5 is the last line executed"
        );
        // Nothing past the lines that were on the wire ran.
        let max_sent = err.unacked_lines.last().copied().unwrap_or(40);
        assert!(sim
            .executed()
            .iter()
            .all(|l| l.seq as usize <= max_sent || l.text == "M5"));
        assert!(!sim.snapshot().spindle_on, "heat off");
    }
}

#[tokio::test(start_paused = true)]
async fn g1_without_feed_is_error_22() {
    let p = Program::parse(
        "(no feed yet)\nG21 G90\nG1 X10 Y10\nG1 X20 F100\n",
        CleanOptions::default(),
    )
    .unwrap();
    let (sim, client) = in_process(SimConfig::default(), FlowControl::CharacterCounting).await;
    let err = client.stream(&p).await.unwrap_err();
    assert!(
        matches!(
            err.fault,
            Fault::Rejected {
                line: 3,
                code: 22,
                ..
            }
        ),
        "{err}"
    );
    assert_eq!(
        err.to_string().split(';').next().unwrap(),
        "line 3 (G1 X10 Y10): error:22 Undefined feed rate"
    );
    assert!(sim
        .events()
        .iter()
        .any(|e| matches!(e, SimEvent::Error { code: 22, .. })));
}

#[tokio::test(start_paused = true)]
async fn an_alarm_stops_streaming_and_reports_it() {
    let cfg = SimConfig {
        faults: Faults {
            alarm_at_line: Some((50, 1)),
            ..Faults::default()
        },
        ..SimConfig::default()
    };
    let p = program(300);
    let (sim, client) = in_process(cfg, FlowControl::CharacterCounting).await;
    let err = client.stream(&p).await.unwrap_err();
    assert!(
        matches!(
            err.fault,
            Fault::Alarm {
                code: 1,
                message: "Hard limit"
            }
        ),
        "{err}"
    );
    // Everything before the 50th line ran; the 50th never completed; nothing after it ran.
    assert_eq!(sim.executed_lines(), texts(&p)[..49].to_vec());
    let stop = err.safe_stop.unwrap();
    assert_eq!(
        stop.sent,
        vec!["!", "0x18"],
        "in alarm after the reset: no M5, no unlock"
    );
    assert_eq!(stop.state_after, Some(MachineState::Alarm));
    assert!(
        !sim.snapshot().spindle_on,
        "the alarm switched the heat off"
    );
    // The operator unlocks.
    let r = client.command("$X").await.unwrap();
    assert_eq!(r.lines, vec!["[MSG:Caution: Unlocked]".to_string()]);
}

#[tokio::test(start_paused = true)]
async fn feed_hold_is_acted_on_within_one_status_cycle() {
    let p = program(400);
    let (sim, client) = in_process(SimConfig::default(), FlowControl::CharacterCounting).await;
    let streamer = {
        let (client, p) = (client.clone(), p.clone());
        tokio::spawn(async move { client.stream(&p).await })
    };
    sim.wait_for(WAIT, |s| s.state == MachineState::Run && s.executed > 50)
        .await
        .expect("the machine runs the program");
    let queries = |sim: &sim::SimHandle| {
        sim.events()
            .iter()
            .filter(|e| {
                matches!(
                    e,
                    SimEvent::Realtime {
                        command: Realtime::StatusQuery,
                        ..
                    }
                )
            })
            .count()
    };
    let asked_at = sim.now_s();
    let queries_before = queries(&sim);
    client.hold().await.unwrap();
    let held = sim
        .wait_for(WAIT, |s| s.state == MachineState::Hold(0))
        .await
        .expect("the hold comes to a stop");
    let events = sim.events();
    let hold_at = events
        .iter()
        .find_map(|e| match e {
            SimEvent::Realtime {
                command: Realtime::FeedHold,
                at_s,
                ..
            } => Some(*at_s),
            _ => None,
        })
        .expect("the simulator saw the hold");
    let queries_until_hold = events
        .iter()
        .take_while(|e| {
            !matches!(
                e,
                SimEvent::Realtime {
                    command: Realtime::FeedHold,
                    ..
                }
            )
        })
        .filter(|e| {
            matches!(
                e,
                SimEvent::Realtime {
                    command: Realtime::StatusQuery,
                    ..
                }
            )
        })
        .count();
    let period = ClientConfig::default().status_period.as_secs_f64();
    assert!(
        hold_at - asked_at <= period,
        "hold reached the controller {:.4} s after the request",
        hold_at - asked_at
    );
    assert!(
        queries_until_hold - queries_before <= 1,
        "at most one status poll between request and hold"
    );
    let stopped_at = events
        .iter()
        .find_map(|e| match e {
            SimEvent::HoldComplete { at_s } => Some(*at_s),
            _ => None,
        })
        .unwrap();
    // 1200 mm/min = 20 mm/s, decelerating at 200 mm/s²: 0.1 s.
    assert!(
        stopped_at - hold_at <= 0.1 + 1e-9,
        "decelerated in {:.4} s",
        stopped_at - hold_at
    );
    // Motion has stopped: nothing moves or executes for a simulated second.
    tokio::time::sleep(Duration::from_secs(1)).await;
    let later = sim.snapshot();
    assert_eq!(later.position, held.position);
    assert_eq!(later.executed, held.executed);
    assert_eq!(later.state, MachineState::Hold(0));
    assert!(
        client.progress().borrow().status.as_ref().unwrap().state == Some(MachineState::Hold(0))
    );
    // Resume and finish: still every line exactly once.
    client.resume().await.unwrap();
    streamer.await.unwrap().expect("completes after resume");
    assert_eq!(sim.executed_lines(), texts(&p));
}

#[tokio::test(start_paused = true)]
async fn link_drop_then_resume_sends_no_line_twice_and_skips_none() {
    for flow in [FlowControl::CharacterCounting, FlowControl::SendResponse] {
        let cfg = SimConfig {
            faults: Faults {
                drop_at_lines: vec![120],
                ..Faults::default()
            },
            ..SimConfig::default()
        };
        let p = program(300);
        let (sim, client) = in_process(cfg, flow).await;
        let err = client.stream(&p).await.unwrap_err();
        assert!(matches!(err.fault, Fault::LinkLost(_)), "{err}");
        assert!(err.safe_stop.is_none(), "no safe stop over a dead link");
        let last = err.last_acked_line.expect("acknowledged lines");
        if flow == FlowControl::CharacterCounting {
            assert!(
                !err.unacked_lines.is_empty(),
                "character counting has lines in flight"
            );
        }
        // The link is back; the controller kept running what its planner held.
        let progress = client.reconnect().await.expect("reconnects");
        assert_eq!(progress.last_acked_line, Some(last));
        sim.wait_for(WAIT, |s| {
            s.state == MachineState::Idle && s.planner_used == 0
        })
        .await
        .expect("the planner drains");
        // Operator confirmation: the machine's log ends with the last acknowledged line.
        let executed = sim.executed();
        let last_text = &p.lines()[p.index_of_line(last).unwrap()].text;
        assert_eq!(&executed.last().unwrap().text, last_text);
        assert!(err
            .unacked_lines
            .iter()
            .all(|n| executed.iter().all(|e| e.seq as usize != *n)));
        let resume_at = p.lines()[p.index_of_line(last).unwrap() + 1].number;
        let report = client
            .stream_from(&p, resume_at)
            .await
            .expect("resumed stream completes");
        assert_eq!(report.first_line, resume_at);
        assert_eq!(
            sim.executed_lines(),
            texts(&p),
            "union of both connections == program ({flow:?})"
        );
        let conns: Vec<u64> = sim.executed().iter().map(|e| e.connection).collect();
        assert!(conns.contains(&1) && conns.contains(&2));
    }
}

#[tokio::test(start_paused = true)]
async fn character_counting_never_overflows_even_with_wide_lines_and_slow_acks() {
    let mut text = String::from("G21 G90 G94 F3000\n");
    for i in 0..400 {
        // 60-70 byte lines: only one or two fit the budget at a time.
        text += &format!(
            "G1 X{:.4} Y{:.4} Z{:.4} F3000 (padding comment kept out)      \n",
            (i % 10) as f64 * 0.01,
            (i % 7) as f64 * 0.01,
            0.0
        );
        text += &format!(
            "G1   X{:.4}   Y{:.4}   Z{:.4}   F3000.000000\n",
            (i % 10) as f64 * 0.011,
            0.0,
            0.001
        );
    }
    let p = Program::parse(&text, CleanOptions::default()).unwrap();
    let cfg = SimConfig {
        faults: Faults {
            ack_delay_s: 0.004,
            ..Faults::default()
        },
        ..SimConfig::default()
    };
    let (sim, client) = in_process(cfg, FlowControl::CharacterCounting).await;
    client.stream(&p).await.unwrap();
    assert_eq!(sim.executed_lines(), texts(&p));
    assert!(!sim.overflowed());
    assert!(
        sim.rx_high_water() > 40,
        "the buffer was actually used: {}",
        sim.rx_high_water()
    );
    assert!(sim.rx_high_water() <= 127);
}

#[tokio::test(start_paused = true)]
async fn an_over_eager_sender_does_overflow_so_the_flag_is_real() {
    let sim = sim::start(SimConfig::default());
    let config = ClientConfig {
        rx_buffer_bytes: 2048, // pretends GRBL has a 2 KiB buffer
        on_fault: FaultAction::HoldOnly,
        ..ClientConfig::default()
    };
    let client = GrblClient::connect(sim.connector(), config).await.unwrap();
    let p = program(400);
    let _ = tokio::time::timeout(Duration::from_secs(120), client.stream(&p)).await;
    assert!(sim.overflowed(), "bytes were lost");
    assert!(sim.overflow_bytes() > 0);
    assert!(sim
        .events()
        .iter()
        .any(|e| matches!(e, SimEvent::RxOverflow { .. })));
}

#[tokio::test(start_paused = true)]
async fn reset_in_motion_raises_alarm_3_and_the_banner() {
    let p = program(200);
    let (sim, client) = in_process(SimConfig::default(), FlowControl::CharacterCounting).await;
    let mut events = client.events();
    let streamer = {
        let (client, p) = (client.clone(), p.clone());
        tokio::spawn(async move { client.stream(&p).await })
    };
    sim.wait_for(WAIT, |s| s.state == MachineState::Run && s.executed > 20)
        .await
        .expect("the machine runs the program");
    client.soft_reset().await.unwrap();
    let err = streamer.await.unwrap().unwrap_err();
    assert!(matches!(err.fault, Fault::Alarm { code: 3, .. }), "{err}");
    let mut seen = Vec::new();
    while let Ok(e) = events.try_recv() {
        seen.push(e);
    }
    use cell_grbl::stream::Event;
    assert!(seen.contains(&Event::Alarm(3)));
    assert!(seen.iter().any(|e| matches!(
        e,
        Event::Banner(b) if b.version == "1.1h" && b.firmware == cell_grbl::firmware::Firmware::Grbl
    )));
    assert!(seen.contains(&Event::Message("'$H'|'$X' to unlock".into())));
    assert_eq!(sim.snapshot().state, MachineState::Alarm);
}

#[tokio::test(start_paused = true)]
async fn jog_cancel_overrides_and_commands() {
    let (sim, client) = in_process(SimConfig::default(), FlowControl::CharacterCounting).await;
    let gc = client.command("$G").await.unwrap();
    assert_eq!(
        gc.lines,
        vec!["[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]".to_string()]
    );
    client.command("$J=G91 X50 F600").await.unwrap();
    sim.wait_for(WAIT, |s| {
        s.state == MachineState::Jog && s.position[0] > 1.0
    })
    .await
    .expect("the jog moves");
    client.jog_cancel().await.unwrap();
    let s = sim
        .wait_for(WAIT, |s| s.state == MachineState::Idle)
        .await
        .expect("the jog cancel stops the machine");
    assert!(
        s.position[0] > 1.0 && s.position[0] < 50.0,
        "{:?}",
        s.position
    );
    let err = client.command("G1 X1").await.unwrap_err();
    assert!(err.to_string().contains("error:22"), "{err}");
    client.feed_override(150).await.unwrap();
    client.spindle_override(50).await.unwrap();
    // Overrides appear in a status report within a few polls.
    let mut rx = client.progress();
    let got = tokio::time::timeout(
        Duration::from_secs(10),
        rx.wait_for(|p| {
            p.status
                .as_ref()
                .and_then(|s| s.overrides)
                .is_some_and(|o| o.feed_pct == 150 && o.spindle_pct == 50)
        }),
    )
    .await;
    assert!(matches!(got, Ok(Ok(_))));
}

#[tokio::test(start_paused = true)]
async fn abort_mid_program_holds_resets_and_switches_heat_off() {
    let p = program(300);
    let (sim, client) = in_process(SimConfig::default(), FlowControl::CharacterCounting).await;
    let streamer = {
        let (client, p) = (client.clone(), p.clone());
        tokio::spawn(async move { client.stream(&p).await })
    };
    sim.wait_for(WAIT, |s| {
        s.state == MachineState::Run && s.executed > 30 && s.spindle_on
    })
    .await
    .expect("the machine runs the program with the heat on");
    client.abort().await.unwrap();
    let err = streamer.await.unwrap().unwrap_err();
    assert_eq!(err.fault, Fault::Aborted);
    let stop = err.safe_stop.unwrap();
    assert_eq!(stop.sent, vec!["!", "0x18", "M5"]);
    assert!(stop.heat_off_acked);
    assert!(!sim.snapshot().spindle_on);
    assert_eq!(sim.snapshot().state, MachineState::Idle);
    let executed = sim.executed_lines();
    assert_prefix(&executed[..executed.len() - 1], &texts(&p), None);
}

/// A fixed-seed linear congruential generator (Knuth's MMIX constants): the same lines on every
/// run, with no dependency.
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: u64) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        // The high bits of an LCG are the well-mixed ones.
        (self.0 >> 33) % n
    }
}

/// `count` distinct G-code line counts in `lo..=hi`, sorted.
fn distinct_lines(seed: u64, count: usize, lo: u64, hi: u64) -> Vec<u64> {
    let mut rng = Lcg(seed);
    let mut out = std::collections::BTreeSet::new();
    while out.len() < count {
        out.insert(lo + rng.below(hi - lo + 1));
    }
    out.into_iter().collect()
}

/// After a link loss: reconnect, let the controller finish what its planner held, check that the
/// machine stopped exactly after the last acknowledged line, and return the line to resume at.
async fn reconnect_and_confirm(
    sim: &sim::SimHandle,
    client: &GrblClient,
    p: &Program,
    err: &cell_grbl::stream::StreamError,
) -> usize {
    assert!(matches!(err.fault, Fault::LinkLost(_)), "{err}");
    assert!(err.safe_stop.is_none(), "no safe stop over a dead link");
    let last = err.last_acked_line.expect("acknowledged lines");
    let progress = client.reconnect().await.expect("reconnects");
    assert_eq!(progress.last_acked_line, Some(last));
    sim.wait_for(WAIT, |s| {
        !s.frozen && s.state == MachineState::Idle && s.planner_used == 0
    })
    .await
    .expect("the planner drains after the reconnect");
    // Operator confirmation: the machine's log ends with the last acknowledged line, and
    // (stronger) is the program up to it, line for line.
    let idx = p.index_of_line(last).expect("a program line");
    let executed = sim.executed_lines();
    assert_eq!(
        executed.last(),
        Some(&p.lines()[idx].text),
        "the log ends with line {last}"
    );
    assert_eq!(
        executed,
        texts(p)[..=idx].to_vec(),
        "log == program up to line {last}"
    );
    p.lines()
        .get(idx + 1)
        .expect("the fault hit before the last line was acknowledged")
        .number
}

#[tokio::test(start_paused = true)]
async fn twenty_link_drops_then_resumes_lose_and_repeat_no_line() {
    const DROPS: usize = 20;
    for flow in [FlowControl::CharacterCounting, FlowControl::SendResponse] {
        let p = program(1990);
        assert!(p.len() > 1990, "about 2000 lines: {}", p.len());
        // Every drop line loses one received line, so the simulator counts p.len() + DROPS
        // lines in all; drops at or below p.len() are all reached.
        let drops = distinct_lines(0x5eed_0001, DROPS, 10, p.len() as u64);
        assert_eq!(drops.len(), DROPS);
        let cfg = SimConfig {
            faults: Faults {
                drop_at_lines: drops.clone(),
                ..Faults::default()
            },
            ..SimConfig::default()
        };
        let (sim, client) = in_process(cfg, flow).await;
        let mut from = p.lines()[0].number;
        let mut lost = 0;
        let report = loop {
            match client.stream_from(&p, from).await {
                Ok(report) => break report,
                Err(err) => {
                    lost += 1;
                    assert!(lost <= DROPS, "more link losses than drops: {err}");
                    from = reconnect_and_confirm(&sim, &client, &p, &err).await;
                }
            }
        };
        assert_eq!(lost, DROPS, "every drop hit ({flow:?}, drops at {drops:?})");
        assert_eq!(report.first_line, from);
        assert_eq!(
            report.last_line,
            p.lines().last().unwrap().number,
            "the last stream finished the program"
        );
        assert_eq!(
            sim.executed_lines(),
            texts(&p),
            "executed log == program, line for line, across {} connections ({flow:?})",
            DROPS + 1
        );
        let events = sim.events();
        let connected = events
            .iter()
            .filter(|e| matches!(e, SimEvent::Connected { .. }))
            .count();
        let injected = events
            .iter()
            .filter(|e| matches!(e, SimEvent::Disconnected { injected: true, .. }))
            .count();
        assert_eq!(connected, DROPS + 1);
        assert_eq!(injected, DROPS);
        assert_eq!(client.progress().borrow().connections, DROPS as u64 + 1);
        assert_eq!(sim.snapshot().received, (p.len() + DROPS) as u64);
        assert!(!sim.overflowed());
    }
}

#[tokio::test(start_paused = true)]
async fn a_silent_controller_is_a_link_loss_and_the_stream_resumes() {
    for flow in [FlowControl::CharacterCounting, FlowControl::SendResponse] {
        let cfg = SimConfig {
            faults: Faults {
                freeze_at_line: Some(150),
                ..Faults::default()
            },
            ..SimConfig::default()
        };
        let p = program(300);
        let (sim, client) = in_process(cfg, flow).await;
        let config = client.config().clone();
        let err = tokio::time::timeout(WAIT, client.stream(&p))
            .await
            .expect("the status watchdog ends a stream to a silent controller")
            .expect_err("the controller froze mid-program");
        assert_eq!(
            err.fault,
            Fault::LinkLost("no answer from the controller for 2.0 s".into()),
            "{err}"
        );
        // Simulated time runs with tokio's clock (time_scale 1): the loss came one timeout
        // after the freeze, give or take the poll that first went unanswered.
        let frozen_at = sim
            .events()
            .iter()
            .find_map(|e| match e {
                SimEvent::Frozen { at_s, .. } => Some(*at_s),
                _ => None,
            })
            .expect("the simulator froze");
        let waited = sim.now_s() - frozen_at;
        let timeout = config.status_timeout.as_secs_f64();
        let period = config.status_period.as_secs_f64();
        assert!(
            waited >= timeout - 0.01 && waited <= timeout + period + 0.05,
            "link dropped {waited:.3} s after the freeze"
        );
        // The controller never closed the link itself; the client did.
        assert!(sim.snapshot().frozen);
        assert!(!sim
            .events()
            .iter()
            .any(|e| matches!(e, SimEvent::Disconnected { injected: true, .. })));
        assert!(!client.progress().borrow().connected);
        let resume_at = reconnect_and_confirm(&sim, &client, &p, &err).await;
        client
            .stream_from(&p, resume_at)
            .await
            .expect("resumed stream completes");
        assert_eq!(sim.executed_lines(), texts(&p), "({flow:?})");
        assert_eq!(client.progress().borrow().connections, 2);
    }
}

#[tokio::test(start_paused = true)]
async fn a_long_slow_move_without_ok_is_not_a_link_loss() {
    // 5 mm at 60 mm/min: 5 s a move. With the 15-block planner full, each further line's `ok`
    // waits for a move to finish, well past the status timeout; status reports keep coming.
    let mut text = String::from("G21 G90 G94\n");
    for i in 1..=24 {
        text += &format!("G1 X{} F60\n", if i % 2 == 1 { 5 } else { 0 });
    }
    let p = Program::parse(&text, CleanOptions::default()).unwrap();
    let (sim, client) = in_process(SimConfig::default(), FlowControl::CharacterCounting).await;
    let timeout = client.config().status_timeout;
    let mut progress = client.progress();
    let gaps = tokio::spawn(async move {
        // The longest time between two acknowledgements while streaming.
        let (mut acked, mut at, mut longest) = (0, tokio::time::Instant::now(), Duration::ZERO);
        while progress.changed().await.is_ok() {
            let p = progress.borrow_and_update().clone();
            if p.lines_acked != acked {
                longest = longest.max(at.elapsed());
                acked = p.lines_acked;
                at = tokio::time::Instant::now();
            }
            if p.lines_acked == 25 {
                break;
            }
        }
        longest
    });
    let report = tokio::time::timeout(WAIT * 2, client.stream(&p))
        .await
        .expect("finishes")
        .expect("no fault: a withheld ok is not a dead controller");
    assert_eq!(report.lines, 25);
    assert_eq!(sim.executed_lines(), texts(&p));
    let longest = gaps.await.unwrap();
    assert!(
        longest > timeout * 2,
        "an ok was withheld for {longest:?}, longer than the {timeout:?} status timeout"
    );
    assert_eq!(client.progress().borrow().connections, 1);
}

#[tokio::test(start_paused = true)]
async fn wait_for_gives_up_with_the_last_snapshot() {
    let sim = sim::start(SimConfig::default());
    let last = sim
        .wait_for(Duration::from_secs(5), |s| s.state == MachineState::Run)
        .await
        .expect_err("nothing ever runs");
    assert_eq!(last.state, MachineState::Idle);
    assert!(!last.connected);
    let now = sim
        .wait_for(Duration::from_secs(5), |s| s.state == MachineState::Idle)
        .await
        .expect("already idle");
    assert_eq!(now.executed, 0);
}
