//! machine_bridge end to end, over real DDS: goals and commands from an operator node, the
//! bridge node, and the in-repo GRBL 1.1 and RWS simulators reached over loopback TCP/HTTP
//! exactly as real controllers would be. The programs are the emitter's own output.
//!
//! No wall-clock assertions except the documented "within one status cycle" of a hold, which
//! uses a 0.5 s cycle so a loaded machine has room.

mod common;

use std::time::Duration;

use cell_grbl::protocol::{MachineState, Realtime};
use cell_grbl::sim::{Faults, SimEvent};
use cell_msgs::{
    ExecuteProgramGoal, ExecuteProgramResult as R, MachineCommand, MachineStatus,
    SendMachineCommandRequest, SendMachineCommandResponse,
};
use cell_profiles::MachineProfile;
use cell_runtime::{CellNode, QosPreset};
use common::machines::{
    accepted, emitted, execute, goal, grbl_program, grbl_sim, grbl_sim_with, operator, sent_lines,
    status_until, texts, wing_panel, Operator,
};
use common::{fresh_domain, node, within, DELIVERY_TIMEOUT};
use machine_bridge::{run, BridgeParams};

/// The bridge node on `domain` driving these controller files.
fn start_bridge(
    domain: u16,
    controllers: Vec<String>,
) -> tokio::task::JoinHandle<anyhow::Result<()>> {
    tokio::spawn(run(
        node("machine_bridge", domain, false),
        BridgeParams {
            controllers,
            arm_at_start: true,
            ..BridgeParams::default()
        },
    ))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_program_goes_through_the_bridge_and_the_simulator_executes_it_line_for_line() {
    cell_runtime::logging::init(Some("info"));
    let dir = tempfile::tempdir().unwrap();
    let (sim, file) = grbl_sim(dir.path(), "cutter", Faults::default(), 20.0, "").await;
    let domain = fresh_domain();
    let rrd = dir.path().join("bridge.rrd");
    let mut setup = cell_runtime::NodeSetup::local("machine_bridge", domain);
    setup.fast_path = cell_runtime::FastPathMode::Off;
    setup.rerun = format!("save:{}", rrd.display()).parse().unwrap();
    let shutdown = setup.shutdown.clone();
    let bridge = tokio::spawn(run(
        CellNode::new(setup).unwrap(),
        BridgeParams {
            controllers: vec![file],
            arm_at_start: true,
            ..BridgeParams::default()
        },
    ));
    let mut op = operator(domain).await;
    let program = grbl_program("wing-e2e", 400);
    let sent = sent_lines(&program);
    assert!(sent.len() > 400, "{} lines", sent.len());

    // Status flows before any goal, with the controller's axes.
    let idle = status_until(&mut op.status, "cutter", |s| {
        s.state == MachineStatus::STATE_IDLE
    })
    .await;
    assert_eq!(idle.axis_names, ["X", "Y", "U", "V"]);
    assert_eq!(idle.axis_positions.len(), 4);

    // Statuses are gathered while the goal runs.
    let status_sub = std::mem::replace(
        &mut op.status,
        op.node
            .subscriber::<MachineStatus>("/machine_status", QosPreset::Status)
            .unwrap(),
    );
    let watch = tokio::spawn(async move {
        let mut sub = status_sub;
        let mut seen = Vec::new();
        while let Ok(Some(r)) = tokio::time::timeout(Duration::from_secs(3), sub.recv()).await {
            let done = r.message.state == MachineStatus::STATE_DONE;
            seen.push(r.message);
            if done {
                break;
            }
        }
        seen
    });
    // An empty machine_id: the controller for the program's machine profile.
    let (result, feedback) =
        execute(&op.client, goal(&program, ""), Duration::from_secs(300)).await;
    assert!(result.success, "{}", result.message);
    assert_eq!(result.outcome, R::OUTCOME_FINISHED);
    let last = sent.lines().last().unwrap().number as u32;
    assert_eq!((result.line, result.last_acked_line), (last, last));
    assert_eq!(result.reconnects, 0);
    assert_eq!(
        sim.executed_lines(),
        texts(&sent),
        "the simulator executed the program, line for line"
    );
    assert!(
        !sim.overflowed(),
        "character counting never overflows the RX buffer"
    );
    assert!(!sim.snapshot().spindle_on, "heat off at the end (M5)");

    assert!(!feedback.is_empty(), "feedback while running");
    assert!(
        feedback
            .windows(2)
            .all(|w| w[0].acked_line <= w[1].acked_line),
        "acknowledged lines never go back"
    );
    assert!(feedback.iter().all(|f| f.total_lines == program.line_count));
    assert!(feedback
        .iter()
        .any(|f| f.state == MachineStatus::STATE_RUNNING));

    let statuses = watch.await.unwrap();
    assert!(statuses
        .iter()
        .any(|s| s.state == MachineStatus::STATE_RUNNING && s.job_id == "wing-e2e"));
    assert!(
        statuses.iter().any(|s| s.buffer_fill > 0.0),
        "buffer fill reported"
    );
    assert!(statuses.iter().any(|s| s.feed_mm_s > 0.0), "feed reported");
    assert_eq!(statuses.last().unwrap().state, MachineStatus::STATE_DONE);
    assert_eq!(statuses.last().unwrap().acked_line, last);
    // At least 5 Hz: the median spacing of the stamps (the bridge publishes at 10 Hz).
    let mut gaps: Vec<f64> = statuses
        .windows(2)
        .map(|w| {
            let t = |s: &MachineStatus| {
                s.header.stamp.sec as f64 + s.header.stamp.nanosec as f64 * 1e-9
            };
            t(&w[1]) - t(&w[0])
        })
        .collect();
    gaps.sort_by(f64::total_cmp);
    assert!(gaps.len() > 5, "{} statuses", statuses.len());
    assert!(
        gaps[gaps.len() / 2] <= 0.2,
        "median status spacing {} s",
        gaps[gaps.len() / 2]
    );

    // A program in another dialect, or for a controller the bridge does not have, is rejected
    // before it is accepted (the reason goes to the log); the bridge stays up.
    let linuxcnc = cell_emitter::emit_program(
        &wing_panel("wrong-dialect", 20),
        &MachineProfile::resolve("linuxcnc-xyuv").unwrap(),
        "wrong-dialect",
    )
    .unwrap();
    assert!(!accepted(&op.client, goal(&linuxcnc, "cutter")).await);
    assert!(!accepted(&op.client, goal(&program, "lathe")).await);
    assert_eq!(
        sim.executed_lines().len(),
        sent.len(),
        "nothing more was sent"
    );
    assert!(!bridge.is_finished(), "the bridge stays up");

    // The Rerun recording decodes with Rerun's own decoder and holds the machine's entities.
    shutdown.trigger();
    within(bridge).await.unwrap().unwrap();
    let dump = common::rrd_dump(&rrd);
    for entity in [
        "/machine/cutter/position",
        "/machine/cutter/trace/0",
        "/machine/cutter/buffer_fill",
        "/machine/cutter/acked_line",
        "/machine/log",
    ] {
        assert!(dump.contains(entity), "bridge.rrd has no {entity}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn twenty_link_drops_are_resumed_with_no_line_lost_or_repeated() {
    let program = grbl_program("wing-drops", 1500);
    let sent = sent_lines(&program);
    // 20 distinct drop points spread over the program, from a fixed-seed LCG.
    let mut seed = 0x5eed_u64;
    let mut drops: Vec<u64> = Vec::new();
    while drops.len() < 20 {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let line = 20 + (seed >> 33) % (sent.len() as u64 - 40);
        if !drops.contains(&line) {
            drops.push(line);
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let (sim, file) = grbl_sim(
        dir.path(),
        "flaky",
        Faults {
            drop_at_lines: drops.clone(),
            ..Faults::default()
        },
        50.0,
        "resume_after_link_drop: auto\n",
    )
    .await;
    let domain = fresh_domain();
    let bridge = start_bridge(domain, vec![file]);
    let op = operator(domain).await;
    let (result, _) = execute(
        &op.client,
        goal(&program, "flaky"),
        Duration::from_secs(600),
    )
    .await;
    assert!(result.success, "{}", result.message);
    assert_eq!(result.reconnects, 20, "{}", result.message);
    let injected = sim
        .events()
        .iter()
        .filter(|e| matches!(e, SimEvent::Disconnected { injected: true, .. }))
        .count();
    assert_eq!(injected, 20, "every drop hit");
    assert_eq!(
        sim.executed_lines(),
        texts(&sent),
        "no line lost, none repeated across 21 connections"
    );
    bridge.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn after_a_drop_the_operator_resumes_from_the_reported_line() {
    let program = grbl_program("wing-resume", 300);
    let sent = sent_lines(&program);
    let dir = tempfile::tempdir().unwrap();
    let (sim, file) = grbl_sim(
        dir.path(),
        "serial-like",
        Faults {
            drop_at_lines: vec![150],
            ..Faults::default()
        },
        50.0,
        "resume_after_link_drop: operator\n",
    )
    .await;
    let domain = fresh_domain();
    let bridge = start_bridge(domain, vec![file]);
    let mut op = operator(domain).await;
    let (lost, _) = execute(&op.client, goal(&program, ""), Duration::from_secs(300)).await;
    assert_eq!(lost.outcome, R::OUTCOME_LINK_LOST, "{}", lost.message);
    let acked = lost.last_acked_line as usize;
    assert!(acked > 0);
    // The first thing on the new link was the safe stop, and the controller reported the
    // heat off; the moves its reset discarded are not lost: `line` is where to resume.
    assert!(
        lost.message.contains("heat off confirmed"),
        "{}",
        lost.message
    );
    let next = lost.line as usize;
    assert!(next > 0 && next <= acked + 1, "{}", lost.message);
    assert!(
        lost.message.contains(&format!("start_line {next}")),
        "{}",
        lost.message
    );
    status_until(&mut op.status, "serial-like", |s| {
        s.state == MachineStatus::STATE_IDLE
    })
    .await;
    let stopped = sim
        .wait_for(Duration::from_secs(60), |s| {
            s.state == MachineState::Idle && s.planner_used == 0
        })
        .await
        .expect("the machine is stopped");
    assert!(!stopped.spindle_on, "the heat is off after the drop");
    let executed = sim.executed_lines();
    let next_index = sent.index_of_line(next).unwrap();
    let all = texts(&sent);
    assert_eq!(
        executed[..executed.len() - 1],
        all[..next_index],
        "the machine ran every line before the resume line, and no other"
    );
    assert_eq!(
        executed.last().map(String::as_str),
        Some("M5"),
        "then the safe stop's M5"
    );

    let (resumed, _) = execute(
        &op.client,
        ExecuteProgramGoal {
            start_line: next as u32,
            ..goal(&program, "")
        },
        Duration::from_secs(300),
    )
    .await;
    assert!(resumed.success, "{}", resumed.message);
    let executed = sim.executed_lines();
    assert_eq!(executed[..next_index], all[..next_index]);
    assert!(
        executed.ends_with(&all[next_index..]),
        "no line lost, none repeated: the resumed run ends with the rest of the program"
    );
    // Between the two runs: the safe stop's M5, then what the resume sent to restore the
    // program's state at the resume line (never a program line twice).
    let between = &executed[next_index..executed.len() - (all.len() - next_index)];
    assert_eq!(
        between.first().map(String::as_str),
        Some("M5"),
        "{between:?}"
    );
    // What the resume sent is the preamble for that line, and the resumed line ran in the
    // state the line before it ran in: G93, the wire heated with the program's S.
    let preamble = cell_grbl::resume::preamble(&sent, next).unwrap();
    assert_eq!(between[1..], preamble[..]);
    let log = sim.executed();
    let (before, resumed) = (
        &log[next_index - 1].parser,
        &log[log.len() - (all.len() - next_index)].parser,
    );
    let groups = |s: &cell_grbl::sim::ParserState| {
        let g = [&s.coordinate_system, &s.plane, &s.units, &s.distance];
        let h = [&s.feed_mode, &s.spindle, &s.spindle_speed];
        g.into_iter().chain(h).cloned().collect::<Vec<_>>()
    };
    assert_eq!(groups(resumed), groups(before), "{preamble:?}");
    assert_eq!(
        (resumed.feed_mode.as_str(), resumed.spindle.as_str()),
        ("G93", "M3")
    );
    bridge.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn alarms_and_bad_lines_stop_the_program_and_name_the_line() {
    let program = grbl_program("wing-faults", 300);
    let sent = sent_lines(&program);
    let dir = tempfile::tempdir().unwrap();
    let alarm_at = 120u64;
    let error_at = 80u64;
    let (alarm_sim, alarm_file) = grbl_sim(
        dir.path(),
        "alarming",
        Faults {
            alarm_at_line: Some((alarm_at, 2)),
            ..Faults::default()
        },
        20.0,
        "",
    )
    .await;
    let (error_sim, error_file) = grbl_sim(
        dir.path(),
        "picky",
        Faults {
            error_at_line: Some((error_at, 33)),
            ..Faults::default()
        },
        20.0,
        "",
    )
    .await;
    let domain = fresh_domain();
    let bridge = start_bridge(domain, vec![alarm_file, error_file]);
    let mut op = operator(domain).await;

    let (alarm, _) = execute(
        &op.client,
        goal(&program, "alarming"),
        Duration::from_secs(300),
    )
    .await;
    assert_eq!(alarm.outcome, R::OUTCOME_ALARM, "{}", alarm.message);
    assert!(alarm.message.contains("ALARM:2"), "{}", alarm.message);
    // In alarm `M5` is not accepted, but `$G` is: the reset's M5 is read back.
    assert!(
        alarm.message.contains("heat off confirmed ($G M5"),
        "{}",
        alarm.message
    );
    assert_eq!(alarm.final_state, MachineStatus::STATE_ALARM);
    let s = status_until(&mut op.status, "alarming", |s| {
        s.state == MachineStatus::STATE_ALARM
    })
    .await;
    assert!(s.alarm.contains("ALARM:2 Soft limit"), "{}", s.alarm);
    // Streaming stopped at once: only lines already on the wire when the alarm came arrived,
    // and the machine ran nothing past the alarmed line.
    let snap = alarm_sim.snapshot();
    let alarm_seq = alarm_at as usize;
    assert!(
        snap.received as usize <= alarm_seq + 127 / 4,
        "{} lines received after an alarm at line {alarm_seq}",
        snap.received
    );
    assert!(alarm_sim.executed_lines().len() < alarm_seq);
    assert!(!snap.spindle_on, "heat off after the alarm");

    let (rejected, _) = execute(
        &op.client,
        goal(&program, "picky"),
        Duration::from_secs(300),
    )
    .await;
    assert_eq!(
        rejected.outcome,
        R::OUTCOME_REJECTED_LINE,
        "{}",
        rejected.message
    );
    // The simulator counts G-code lines; the bridge reports the program's own line number.
    let bad = &sent.lines()[error_at as usize - 1];
    assert_eq!(rejected.line as usize, bad.number, "{}", rejected.message);
    assert!(
        rejected.message.contains("error:33"),
        "{}",
        rejected.message
    );
    assert!(
        rejected.message.contains(&format!("line {}", bad.number)),
        "{}",
        rejected.message
    );
    assert!(
        rejected.message.contains("heat off confirmed"),
        "{}",
        rejected.message
    );
    assert!(!error_sim.snapshot().spindle_on);
    assert!(!bridge.is_finished());
    bridge.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hold_resume_and_abort_from_topic_and_service_act_within_one_status_cycle() {
    let program = grbl_program("wing-hold", 300);
    let sent = sent_lines(&program);
    let dir = tempfile::tempdir().unwrap();
    // Real time, and a 0.5 s status cycle: the hold must reach the machine within it.
    let (sim, file) = grbl_sim(
        dir.path(),
        "held",
        Faults::default(),
        1.0,
        "status_period_s: 0.5\n",
    )
    .await;
    let domain = fresh_domain();
    let bridge = start_bridge(domain, vec![file]);
    let mut op = operator(domain).await;
    let commands = op
        .node
        .publisher::<MachineCommand>("/machine_command", QosPreset::Status)
        .unwrap();
    let service = op
        .node
        .service_client::<SendMachineCommandRequest, SendMachineCommandResponse>("/machine_command")
        .unwrap();
    assert!(commands.wait_for_subscribers(1, DELIVERY_TIMEOUT).await);
    assert!(
        op.node
            .wait_for_service("/machine_command", DELIVERY_TIMEOUT)
            .await
    );

    let call = |command: u8, machine_id: &str, value: u16| {
        service.call(
            SendMachineCommandRequest {
                command: MachineCommand {
                    machine_id: machine_id.into(),
                    command,
                    value,
                },
            },
            DELIVERY_TIMEOUT,
        )
    };
    let Operator { client, status, .. } = &mut op;

    // Goal 1: hold on the topic, resume in the service; every line runs once.
    let operate = async {
        status_until(status, "held", |s| {
            s.state == MachineStatus::STATE_RUNNING && s.acked_line > 20
        })
        .await;
        let asked_at = sim.now_s();
        commands
            .publish(MachineCommand {
                machine_id: "held".into(),
                command: MachineCommand::COMMAND_HOLD,
                value: 0,
            })
            .await
            .unwrap();
        let held = status_until(status, "held", |s| s.state == MachineStatus::STATE_HOLD).await;
        let hold_arrived = sim
            .events()
            .iter()
            .find_map(|e| match e {
                SimEvent::Realtime {
                    command: Realtime::FeedHold,
                    at_s,
                    ..
                } => Some(*at_s),
                _ => None,
            })
            .expect("the machine got the feed hold");
        assert!(
            hold_arrived - asked_at < 0.5,
            "hold reached the machine {:.3} s after it was asked for; the status cycle is 0.5 s",
            hold_arrived - asked_at
        );
        assert!(held.acked_line > 0);
        let executed_in_hold = sim.executed_lines().len();
        tokio::time::sleep(Duration::from_millis(800)).await;
        let snap = sim.snapshot();
        assert!(
            matches!(snap.state, MachineState::Hold(_)),
            "{:?}",
            snap.state
        );
        assert!(
            sim.executed_lines().len() <= executed_in_hold + 1,
            "nothing runs in a hold"
        );
        let answer = call(MachineCommand::COMMAND_RESUME, "held", 0)
            .await
            .unwrap();
        assert!(answer.success, "{}", answer.message);
    };
    let ((result, _), ()) = tokio::join!(
        execute(client, goal(&program, "held"), Duration::from_secs(600)),
        operate
    );
    assert!(result.success, "{}", result.message);
    assert_eq!(sim.executed_lines(), texts(&sent));

    // Overrides out of range are refused with the range.
    let answer = call(MachineCommand::COMMAND_FEED_OVERRIDE, "held", 500)
        .await
        .unwrap();
    assert!(
        !answer.success && answer.message.contains("10..200"),
        "{}",
        answer.message
    );

    // Goal 2: abort (e-stop, every machine) in the service: the goal ends aborted, heat off.
    let operate = async {
        status_until(status, "held", |s| {
            s.state == MachineStatus::STATE_RUNNING && s.acked_line > 20
        })
        .await;
        assert!(sim.snapshot().spindle_on, "cutting with the heat on");
        let answer = call(MachineCommand::COMMAND_ABORT, "", 0).await.unwrap();
        assert!(answer.success, "{}", answer.message);
    };
    let ((aborted, _), ()) = tokio::join!(
        execute(client, goal(&program, "held"), Duration::from_secs(600)),
        operate
    );
    assert_eq!(aborted.outcome, R::OUTCOME_ABORTED, "{}", aborted.message);
    assert!(
        aborted.message.contains("heat off confirmed"),
        "{}",
        aborted.message
    );
    assert!(!sim.snapshot().spindle_on, "heat off after the abort");
    assert!(!bridge.is_finished());
    bridge.abort();
}

/// A bridge on a fresh domain driving a simulator whose feed holds take `accel_mm_s2` to stop
/// (the wing panel cuts at 4 mm/s), the operator and the command service.
async fn slow_stopping_cell(
    dir: &std::path::Path,
    id: &str,
    accel_mm_s2: f64,
    extra: &str,
) -> (
    cell_grbl::sim::SimHandle,
    tokio::task::JoinHandle<anyhow::Result<()>>,
    Operator,
    cell_runtime::ServiceClient<SendMachineCommandRequest, SendMachineCommandResponse>,
) {
    let cfg = cell_grbl::sim::SimConfig {
        time_scale: 4.0,
        accel_mm_s2,
        ..cell_grbl::sim::SimConfig::default()
    };
    let (sim, file) = grbl_sim_with(dir, id, cfg, extra).await;
    let domain = fresh_domain();
    let bridge = start_bridge(domain, vec![file]);
    let op = operator(domain).await;
    let service = op
        .node
        .service_client::<SendMachineCommandRequest, SendMachineCommandResponse>("/machine_command")
        .unwrap();
    assert!(
        op.node
            .wait_for_service("/machine_command", DELIVERY_TIMEOUT)
            .await
    );
    (sim, bridge, op, service)
}

async fn send(
    service: &cell_runtime::ServiceClient<SendMachineCommandRequest, SendMachineCommandResponse>,
    machine_id: &str,
    command: u8,
) -> SendMachineCommandResponse {
    service
        .call(
            SendMachineCommandRequest {
                command: MachineCommand {
                    machine_id: machine_id.into(),
                    command,
                    value: 0,
                },
            },
            DELIVERY_TIMEOUT,
        )
        .await
        .unwrap()
}

/// The states the simulator was in when each `~` arrived.
fn cycle_starts(sim: &cell_grbl::sim::SimHandle) -> Vec<MachineState> {
    sim.events()
        .iter()
        .filter_map(|e| match e {
            SimEvent::Realtime {
                command: Realtime::CycleStart,
                state,
                ..
            } => Some(*state),
            _ => None,
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_resume_sent_while_the_hold_decelerates_runs_the_program_to_the_end() {
    // 4 mm/s at 1 mm/s²: four simulated seconds (one real second) to stop. GRBL drops a `~`
    // that comes before the stop; the resume right after the hold lands inside it.
    let dir = tempfile::tempdir().unwrap();
    let (sim, bridge, mut op, service) = slow_stopping_cell(dir.path(), "heavy", 1.0, "").await;
    let program = grbl_program("wing-quick-resume", 300);
    let sent = sent_lines(&program);
    let Operator { client, status, .. } = &mut op;
    let operate = async {
        status_until(status, "heavy", |s| {
            s.state == MachineStatus::STATE_RUNNING && s.acked_line > 20
        })
        .await;
        let held = send(&service, "heavy", MachineCommand::COMMAND_HOLD).await;
        assert!(held.success, "{}", held.message);
        let resumed = send(&service, "heavy", MachineCommand::COMMAND_RESUME).await;
        assert!(
            cycle_starts(&sim) != [MachineState::Hold(1)],
            "the resume went out during the deceleration, where GRBL drops it: {}",
            resumed.message
        );
        assert!(resumed.success, "{}", resumed.message);
        assert!(
            resumed.message.contains("taken") && resumed.message.contains("Hold:0"),
            "{}",
            resumed.message
        );
        resumed
    };
    let ((result, _), resumed) = tokio::join!(
        execute(client, goal(&program, "heavy"), Duration::from_secs(300)),
        operate
    );
    assert!(
        result.success,
        "{} (resume: {})",
        result.message, resumed.message
    );
    assert_eq!(result.outcome, R::OUTCOME_FINISHED);
    assert_eq!(
        sim.executed_lines(),
        texts(&sent),
        "every line acknowledged and run once"
    );
    assert_eq!(
        cycle_starts(&sim),
        [MachineState::Hold(0)],
        "one `~`, sent once the hold was complete"
    );
    status_until(status, "heavy", |s| s.state == MachineStatus::STATE_DONE).await;
    assert!(!sim.snapshot().spindle_on, "heat off at the end (M5)");
    bridge.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_resume_the_controller_cannot_take_in_time_answers_failure_and_sends_nothing() {
    // 4 mm/s at 0.25 mm/s²: sixteen simulated seconds (four real ones) to stop, against a
    // 0.5 s resume.
    let dir = tempfile::tempdir().unwrap();
    let (sim, bridge, mut op, service) =
        slow_stopping_cell(dir.path(), "glacial", 0.25, "resume_timeout_s: 0.5\n").await;
    let program = grbl_program("wing-slow-stop", 300);
    let sent = sent_lines(&program);
    let Operator { client, status, .. } = &mut op;
    let operate = async {
        status_until(status, "glacial", |s| {
            s.state == MachineStatus::STATE_RUNNING && s.acked_line > 20
        })
        .await;
        let held = send(&service, "glacial", MachineCommand::COMMAND_HOLD).await;
        assert!(held.success, "{}", held.message);
        let refused = send(&service, "glacial", MachineCommand::COMMAND_RESUME).await;
        assert!(!refused.success, "{}", refused.message);
        assert!(
            refused.message.contains("glacial")
                && refused.message.contains("Hold:1")
                && refused.message.contains("not sent"),
            "{}",
            refused.message
        );
        assert!(cycle_starts(&sim).is_empty(), "no `~` went out");
        assert_eq!(sim.snapshot().state, MachineState::Hold(1));
        // Once the machine has stopped, the resume is taken and the program goes on.
        sim.wait_for(Duration::from_secs(60), |s| {
            s.state == MachineState::Hold(0)
        })
        .await
        .expect("the hold completes");
        let resumed = send(&service, "glacial", MachineCommand::COMMAND_RESUME).await;
        assert!(resumed.success, "{}", resumed.message);
    };
    let ((result, _), ()) = tokio::join!(
        execute(client, goal(&program, "glacial"), Duration::from_secs(300)),
        operate
    );
    assert!(result.success, "{}", result.message);
    assert_eq!(sim.executed_lines(), texts(&sent));
    assert_eq!(cycle_starts(&sim), [MachineState::Hold(0)]);
    bridge.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rapid_programs_run_on_the_rws_simulator_and_a_wrong_password_is_refused() {
    use cell_rws::sim::{RwsSim, SimConfig as RwsSimConfig};
    use cell_rws::RwsVersion;
    let rws = RwsSim::start(RwsSimConfig::new(RwsVersion::Rw6, "Operator", "weld:on-42"))
        .await
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("good.cred"), "Operator:weld:on-42\n").unwrap();
    std::fs::write(dir.path().join("bad.cred"), "Operator:guess\n").unwrap();
    let controller = |id: &str, cred: &str| {
        let path = dir.path().join(format!("{id}.yaml"));
        std::fs::write(
            &path,
            format!(
                "id: {id}\nprotocol: rws\nrws: rw6\nport: {}\ncredentials: {{file: {cred}}}\n",
                rws.addr().port()
            ),
        )
        .unwrap();
        path.display().to_string()
    };
    let good = controller("irb2600", "good.cred");
    let bad = controller("intruder", "bad.cred");
    let domain = fresh_domain();
    let bridge = start_bridge(domain, vec![good, bad]);
    let mut op = operator(domain).await;
    let program = emitted("wall", "abb-irb2600-waam", "wall-9");

    let (result, _) = execute(
        &op.client,
        goal(&program, "irb2600"),
        Duration::from_secs(120),
    )
    .await;
    assert!(result.success, "{}", result.message);
    assert_eq!(result.outcome, R::OUTCOME_FINISHED);
    let modules = rws.modules();
    assert_eq!(modules.len(), program.files.len() - 1, "{modules:?}");
    for f in &program.files {
        assert_eq!(
            rws.file(&format!("cellsuite/{}", f.name)).as_deref(),
            Some(f.text.as_bytes()),
            "{} uploaded byte for byte",
            f.name
        );
    }
    status_until(&mut op.status, "irb2600", |s| {
        s.state == MachineStatus::STATE_DONE
    })
    .await;

    let (refused, _) = execute(
        &op.client,
        goal(&program, "intruder"),
        Duration::from_secs(120),
    )
    .await;
    assert_eq!(refused.outcome, R::OUTCOME_REFUSED, "{}", refused.message);
    assert!(refused.message.contains("intruder"), "{}", refused.message);
    assert!(
        refused.message.to_lowercase().contains("credentials") || refused.message.contains("401"),
        "{}",
        refused.message
    );
    let s = status_until(&mut op.status, "intruder", |s| {
        s.state == MachineStatus::STATE_DISCONNECTED
    })
    .await;
    assert!(!s.alarm.is_empty());
    // A G-code program is not for a robot: rejected before it is accepted.
    assert!(!accepted(&op.client, goal(&grbl_program("g", 10), "irb2600")).await);
    assert!(!bridge.is_finished());
    bridge.abort();
}

/// The shipped `abb-irb2600-waam-sim` controller: the bridge starts the RWS simulator itself
/// (loopback, a login made up for the run, no credentials in any file) and runs a WAAM program
/// on it through the same RWS client as a real IRC5.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_shipped_rws_simulator_controller_is_started_by_the_bridge_and_runs_rapid() {
    let domain = fresh_domain();
    let bridge = start_bridge(domain, vec!["abb-irb2600-waam-sim".into()]);
    let mut op = operator(domain).await;
    let program = emitted("wall", "abb-irb2600-waam", "wall-sim");
    let (result, _) = execute(
        &op.client,
        goal(&program, "abb-irb2600-waam-sim"),
        Duration::from_secs(120),
    )
    .await;
    assert!(result.success, "{}", result.message);
    assert_eq!(result.outcome, R::OUTCOME_FINISHED, "{}", result.message);
    status_until(&mut op.status, "abb-irb2600-waam-sim", |s| {
        s.state == MachineStatus::STATE_DONE
    })
    .await;
    assert!(!bridge.is_finished());
    bridge.abort();
}

const CELL: &str = env!("CARGO_BIN_EXE_cell");

fn cell(args: &[&str]) -> std::process::Output {
    std::process::Command::new(CELL)
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run cell")
}

#[test]
fn cell_stream_runs_a_program_file_on_the_simulator_and_names_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    };
    // The planner's own tapered wing (`cell hotwire … --profile grbl-xyuv`).
    let program = emitted("wing", "grbl-xyuv", "wing");
    let good = write("wing.ngc", &program.files[0].text);
    let out = cell(&["stream", "--controller", "grbl-sim", "--program", &good]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let sent = sent_lines(&program).len();
    assert!(
        stdout.contains(&format!("{sent} lines streamed to grbl-sim")),
        "{stdout}"
    );

    // G1 before any feed: GRBL answers error:22; the line is named by its number in the file.
    let bad = write(
        "bad.ngc",
        "(no feed yet)\nG21 G90 G94\nG1 X5 Y5\nG1 X6 Y6 F100\n",
    );
    let out = cell(&["stream", "--controller", "grbl-sim", "--program", &bad]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("line 3") && err.contains("error:22"), "{err}");
    assert!(!err.contains("panicked"), "{err}");

    let broken = write("broken.ngc", "G21\nG1 X1 (unclosed F100\n");
    let out = cell(&["stream", "--controller", "grbl-sim", "--program", &broken]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(65), "{err}");
    assert!(err.contains("line 2") && err.contains("comment"), "{err}");

    let out = cell(&["stream", "--controller", "haas-vf2", "--program", &good]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(64), "{err}");
    assert!(
        err.contains("haas-vf2") && err.contains("grbl-sim"),
        "{err}"
    );
}
