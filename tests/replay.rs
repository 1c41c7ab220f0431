//! The replayer over real DDS: a cell run recorded by the `recorder` node and replayed on a
//! fresh domain makes a fresh emitter and bridge produce the same program and the same
//! executed-line log; rate, topic selection, remap, start offset, pause/resume over the
//! service, transient-local plans for a late joiner, loop, and bad input.
//!
//! Timing bounds are generous (a loaded 2-core machine): the schedule itself is unit-tested in
//! `nodes/replayer/src/schedule.rs`.

mod common;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use cell_bag::{BagWriter, QosProfile};
use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::sim::{self, SimConfig, SimHandle};
use cell_msgs::std_msgs::StringMsg;
use cell_msgs::std_srvs::{SetBoolRequest, SetBoolResponse};
use cell_msgs::{
    MachineProgram, PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult, RosMessage, Toolpath,
};
use cell_runtime::{action::GoalStatusEnum, CellNode, NodeSetup, QosPreset, Shutdown};
use common::{discover_action_server, follow_goal, fresh_domain, node, within, DELIVERY_TIMEOUT};
use emitter::EmitterParams;
use machine_bridge::BridgeParams;
use planner::PlannerParams;
use recorder::RecorderParams;
use replayer::{Replay, ReplaySummary, ReplayerParams};

/// A bag's first log time (any fixed epoch time).
const T0_NS: u64 = 1_763_800_000_000_000_000;

/// A node in `namespace` on `domain` (DDS on loopback, no fast path) and its shutdown signal.
fn ns_node(name: &str, namespace: &str, domain: u16) -> (CellNode, Shutdown) {
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = cell_runtime::FastPathMode::Off;
    setup.args.ros.namespace = Some(namespace.into());
    let shutdown = setup.shutdown.clone();
    (CellNode::new(setup).expect("node comes up"), shutdown)
}

/// A GRBL 1.1 simulator for the 4-axis cutter on loopback TCP (the shipped `grbl-sim` settings:
/// ×20 time, 115 200 baud) and a controller file for it.
async fn grbl_sim(dir: &Path, id: &str) -> (SimHandle, String) {
    let sim = sim::start(SimConfig {
        time_scale: 20.0,
        axes: vec!['X', 'Y', 'U', 'V'],
        ..SimConfig::default()
    });
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let path = dir.join(format!("{id}.yaml"));
    std::fs::write(
        &path,
        format!(
            "id: {id}\nprotocol: grbl\nmachine_profile: grbl-xyuv\naxes: XYUV\n\
             endpoint: {{tcp: '{addr}'}}\n"
        ),
    )
    .unwrap();
    (sim, path.display().to_string())
}

/// What the controller is sent of a program: its G-code lines, comments and blanks dropped.
fn sent_lines(program: &MachineProgram) -> Vec<String> {
    Program::parse(&program.files[0].text, CleanOptions::default())
        .unwrap()
        .lines()
        .iter()
        .map(|l| l.text.clone())
        .collect()
}

/// Waits until the simulator has executed `n` lines.
async fn executed(sim: &SimHandle, n: usize) -> Vec<String> {
    within(async {
        loop {
            let lines = sim.executed_lines();
            if lines.len() >= n {
                return lines;
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    })
    .await
}

/// An emitter (grbl-xyuv) and a bridge running what it publishes, in `/cell` on `domain`, as
/// `launch_scripts/hotwire.launch.yaml` wires them.
fn emitter_and_bridge(domain: u16, controller: String) -> Vec<Shutdown> {
    let (emitter, emitter_stop) = ns_node("emitter", "/cell", domain);
    tokio::spawn(emitter::run(
        emitter,
        EmitterParams {
            machine_profile: "grbl-xyuv".into(),
            ..EmitterParams::default()
        },
    ));
    let (bridge, bridge_stop) = ns_node("machine_bridge", "/cell", domain);
    tokio::spawn(machine_bridge::run(
        bridge,
        BridgeParams {
            controllers: vec![controller],
            program_topic: "machine_program".into(),
            arm_at_start: true,
            ..BridgeParams::default()
        },
    ));
    vec![emitter_stop, bridge_stop]
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recorded_cell_run_replays_to_the_same_program_and_the_same_executed_lines() {
    cell_runtime::logging::init(Some("info"));
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("run");

    // (a) A real run on one domain: planner, emitter, bridge + simulator, recorder.
    let domain = fresh_domain();
    let (sim_a, controller_a) = grbl_sim(dir.path(), "cutter").await;
    let (recorder, recorder_stop) = ns_node("recorder", "/cell", domain);
    let recording = tokio::spawn(recorder::run(
        recorder,
        RecorderParams {
            output: bag.display().to_string(),
            topics: vec!["/cell/.*".into()],
            discover_every_s: 0.2,
            ..RecorderParams::default()
        },
    ));
    let (planner, planner_stop) = ns_node("planner", "/cell", domain);
    tokio::spawn(planner::run(
        planner,
        PlannerParams {
            machine_profile: "grbl-xyuv".into(),
            panels: 40,
            particles: 8,
            restart_every: 30,
            feedback_every: 10,
            exposure_period_s: 0.2,
            ..PlannerParams::default()
        },
    ));
    let mut stops = emitter_and_bridge(domain, controller_a);
    stops.push(planner_stop);
    let (operator, _) = ns_node("operator", "/cell", domain);
    let mut programs = operator
        .subscriber::<MachineProgram>("machine_program", QosPreset::Plan)
        .unwrap();
    let client = operator
        .action_client::<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>("plan_hotwire")
        .unwrap();
    discover_action_server(&operator, "plan_hotwire").await;
    let goal = PlanHotwireGoal {
        job_id: "replay-wing".into(),
        root_airfoil: "s1223".into(),
        root_chord_mm: 150.0,
        machine_profile: "grbl-xyuv".into(),
        iterations: 40,
        seed: 7,
        ..Default::default()
    };
    let planned = follow_goal(&client, goal).await.expect("goal accepted");
    assert_eq!(
        planned.status,
        GoalStatusEnum::Succeeded,
        "{}",
        planned.result.message
    );
    let program_a = within(programs.recv()).await.expect("a program").message;
    let lines = sent_lines(&program_a);
    assert!(lines.len() > 40, "{} lines", lines.len());
    let executed_a = executed(&sim_a, lines.len()).await;
    assert_eq!(executed_a, lines, "run (a) executed its program");
    // Let the recorder write what is still in flight, then finish the bag.
    tokio::time::sleep(Duration::from_millis(500)).await;
    recorder_stop.trigger();
    within(recording).await.unwrap().unwrap();
    for stop in stops {
        stop.trigger();
    }
    let info = cell_bag::BagInfo::open(&bag).unwrap();
    let toolpath_topic = info
        .topics
        .iter()
        .find(|t| t.name == "/cell/toolpath")
        .expect("the toolpath was recorded");
    assert_eq!(toolpath_topic.message_count, 1);

    // (b) A fresh domain, a fresh emitter and bridge + simulator, and the replayer playing
    // only the toolpath from the bag.
    let domain = fresh_domain();
    let (sim_b, controller_b) = grbl_sim(dir.path(), "cutter-b").await;
    let stops = emitter_and_bridge(domain, controller_b);
    let (watcher, _) = ns_node("watcher", "/cell", domain);
    let mut programs = watcher
        .subscriber::<MachineProgram>("machine_program", QosPreset::Plan)
        .unwrap();
    let (replayer, _) = ns_node("replayer", "/cell", domain);
    let replaying = tokio::spawn(replayer::run(
        replayer,
        ReplayerParams {
            bag: bag.display().to_string(),
            topics: vec!["/cell/toolpath".into()],
            wait_for_subscribers_s: 20.0,
            linger_s: 2.0,
            ..ReplayerParams::default()
        },
    ));
    let program_b = within(programs.recv()).await.expect("a program").message;
    assert_eq!(program_b.files.len(), 1);
    assert_eq!(
        program_b.files[0].text, program_a.files[0].text,
        "the replayed toolpath gives the same program text"
    );
    assert_eq!(program_b.sha256, program_a.sha256);
    let executed_b = executed(&sim_b, lines.len()).await;
    assert_eq!(
        executed_b, executed_a,
        "the simulator executed the same lines as in the recorded run"
    );
    within(replaying).await.unwrap().unwrap();
    // Only the toolpath was played: a second program would mean another topic got through.
    assert!(
        tokio::time::timeout(Duration::from_millis(500), programs.recv())
            .await
            .is_err(),
        "one program only"
    );
    assert_eq!(sim_b.executed_lines().len(), lines.len());
    for stop in stops {
        stop.trigger();
    }
}

/// Writes a bag of `std_msgs/String` messages: (topic, seconds after the start, text).
fn string_bag(dir: &Path, name: &str, messages: &[(&str, f64, &str)]) -> PathBuf {
    let path = dir.join(name);
    let mut w = BagWriter::create(&path, Default::default()).unwrap();
    for (topic, _, _) in messages {
        // Registering a topic twice with its type is allowed; the first QoS stays.
        w.add_topic(
            topic,
            StringMsg::ROS_NAME,
            &[QosProfile::reliable_volatile(32)],
        )
        .unwrap();
    }
    for (topic, t, text) in messages {
        let msg = StringMsg {
            data: (*text).into(),
        };
        w.write(topic, &msg, T0_NS + (t * 1e9) as u64).unwrap();
    }
    w.finish().unwrap();
    path
}

/// Messages received on one topic, with their arrival times.
type Inbox<T> = Arc<Mutex<Vec<(Instant, T)>>>;

fn inbox<T: RosMessage>(node: &CellNode, topic: &str, qos: QosPreset) -> Inbox<T> {
    let mut sub = node.subscriber::<T>(topic, qos).unwrap();
    let got: Inbox<T> = Arc::default();
    let sink = got.clone();
    tokio::spawn(async move {
        while let Some(r) = sub.recv().await {
            sink.lock().unwrap().push((Instant::now(), r.message));
        }
    });
    got
}

fn texts(inbox: &Inbox<StringMsg>) -> Vec<String> {
    inbox
        .lock()
        .unwrap()
        .iter()
        .map(|(_, m)| m.data.clone())
        .collect()
}

async fn wait_for_count<T>(inbox: &Inbox<T>, n: usize) {
    within(async {
        while inbox.lock().unwrap().len() < n {
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    })
    .await
}

/// Starts a replay of `params` on a node `name` in `/` on `domain`.
fn start_replay(
    name: &str,
    domain: u16,
    params: ReplayerParams,
) -> (
    tokio::task::JoinHandle<anyhow::Result<ReplaySummary>>,
    Shutdown,
) {
    let (node, shutdown) = ns_node(name, "/", domain);
    let task = tokio::spawn(async move {
        let replay = Replay::open(&params)?;
        replay.run(&node, |_| {}).await
    });
    (task, shutdown)
}

fn params(bag: &Path) -> ReplayerParams {
    ReplayerParams {
        bag: bag.display().to_string(),
        wait_for_subscribers_s: 20.0,
        linger_s: 0.5,
        ..ReplayerParams::default()
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_rate_scales_the_recorded_gaps() {
    let dir = tempfile::tempdir().unwrap();
    let bag = string_bag(
        dir.path(),
        "gap",
        &[("/chatter", 0.0, "one"), ("/chatter", 1.0, "two")],
    );
    let domain = fresh_domain();
    let listener = node("listener", domain, false);
    let got = inbox::<StringMsg>(&listener, "/chatter", QosPreset::Status);
    let (task, _) = start_replay(
        "replayer",
        domain,
        ReplayerParams {
            rate: 4.0,
            ..params(&bag)
        },
    );
    wait_for_count(&got, 2).await;
    let summary = within(task).await.unwrap().unwrap();
    assert_eq!(summary.published, 2);
    assert_eq!(texts(&got), ["one", "two"]);
    let arrivals: Vec<Instant> = got.lock().unwrap().iter().map(|(t, _)| *t).collect();
    let gap = arrivals[1] - arrivals[0];
    // 1 s recorded at ×4 is 0.25 s; ×1 would be 1 s.
    assert!(
        gap > Duration::from_millis(50) && gap < Duration::from_millis(750),
        "gap {gap:?}, expected about 0.25 s"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn topics_exclude_and_remap_pick_and_rename_and_unknown_types_are_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mixed");
    let mut w = BagWriter::create(&path, Default::default()).unwrap();
    for topic in ["/a", "/b", "/c"] {
        w.add_topic(
            topic,
            StringMsg::ROS_NAME,
            &[QosProfile::reliable_volatile(32)],
        )
        .unwrap();
    }
    // A type from a package this suite does not have.
    w.add_topic_with_definition("/x", "other_msgs/msg/Thing", "int32 value", &[])
        .unwrap();
    for i in 0..3u64 {
        for topic in ["/a", "/b", "/c"] {
            let msg = StringMsg {
                data: format!("{topic}{i}"),
            };
            w.write(topic, &msg, T0_NS + i * 100_000_000).unwrap();
        }
        w.write_raw(
            "/x",
            "other_msgs/msg/Thing",
            &[0, 1, 0, 0, 7, 0, 0, 0],
            T0_NS + i * 100_000_000,
        )
        .unwrap();
    }
    w.finish().unwrap();

    let domain = fresh_domain();
    let listener = node("listener", domain, false);
    let renamed = inbox::<StringMsg>(&listener, "/renamed", QosPreset::Status);
    let others: Vec<Inbox<StringMsg>> = ["/a", "/b", "/c"]
        .iter()
        .map(|t| inbox::<StringMsg>(&listener, t, QosPreset::Status))
        .collect();
    let (task, _) = start_replay(
        "replayer",
        domain,
        ReplayerParams {
            topics: vec!["/a".into(), "/b".into(), "/x".into()],
            exclude: vec!["/b".into()],
            remap: vec!["/a:=/renamed".into()],
            ..params(&path)
        },
    );
    wait_for_count(&renamed, 3).await;
    let summary = within(task).await.unwrap().unwrap();
    assert_eq!(texts(&renamed), ["/a0", "/a1", "/a2"]);
    assert_eq!(summary.published, 3);
    assert_eq!(summary.topics, 1);
    assert_eq!(summary.unknown_type, 3, "{summary}");
    tokio::time::sleep(Duration::from_millis(500)).await;
    for (topic, got) in ["/a", "/b", "/c"].iter().zip(&others) {
        assert!(texts(got).is_empty(), "{topic} got {:?}", texts(got));
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_start_offset_skips_the_beginning_of_the_bag() {
    let dir = tempfile::tempdir().unwrap();
    let bag = string_bag(
        dir.path(),
        "offset",
        &[
            ("/chatter", 0.0, "m0"),
            ("/chatter", 0.2, "m1"),
            ("/chatter", 0.4, "m2"),
            ("/chatter", 0.6, "m3"),
        ],
    );
    let domain = fresh_domain();
    let listener = node("listener", domain, false);
    let got = inbox::<StringMsg>(&listener, "/chatter", QosPreset::Status);
    let (task, _) = start_replay(
        "replayer",
        domain,
        ReplayerParams {
            start_offset_s: 0.3,
            ..params(&bag)
        },
    );
    let summary = within(task).await.unwrap().unwrap();
    wait_for_count(&got, 2).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert_eq!(texts(&got), ["m2", "m3"]);
    assert_eq!((summary.published, summary.before_offset), (2, 2));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pause_and_resume_over_the_service_hold_the_replay_without_a_burst() {
    let dir = tempfile::tempdir().unwrap();
    let schedule: Vec<(&str, f64, String)> = (0..8)
        .map(|i| ("/chatter", 0.25 * f64::from(i), format!("m{i}")))
        .collect();
    let entries: Vec<(&str, f64, &str)> = schedule
        .iter()
        .map(|(t, s, m)| (*t, *s, m.as_str()))
        .collect();
    let bag = string_bag(dir.path(), "pause", &entries);
    let all: Vec<String> = (0..8).map(|i| format!("m{i}")).collect();
    let domain = fresh_domain();
    let listener = node("listener", domain, false);
    let got = inbox::<StringMsg>(&listener, "/chatter", QosPreset::Status);
    let client = listener
        .service_client::<SetBoolRequest, SetBoolResponse>("/replayer/set_paused")
        .unwrap();
    let (task, _) = start_replay("replayer", domain, params(&bag));
    assert!(
        listener
            .wait_for_service("/replayer/set_paused", DELIVERY_TIMEOUT)
            .await,
        "the pause service is up while the replay runs"
    );
    wait_for_count(&got, 2).await;
    let paused = client
        .call(SetBoolRequest { data: true }, DELIVERY_TIMEOUT)
        .await
        .unwrap();
    assert!(paused.success, "{}", paused.message);
    assert!(
        paused.message.starts_with("paused at t="),
        "{}",
        paused.message
    );
    // What was published before the pause may still be on its way.
    tokio::time::sleep(Duration::from_millis(300)).await;
    let held = got.lock().unwrap().len();
    tokio::time::sleep(Duration::from_millis(1500)).await;
    assert_eq!(got.lock().unwrap().len(), held, "nothing while paused");
    assert!(held < 8, "paused before the end ({held} of 8)");
    let resumed_at = Instant::now();
    let resumed = client
        .call(SetBoolRequest { data: false }, DELIVERY_TIMEOUT)
        .await
        .unwrap();
    assert!(
        resumed.message.starts_with("resumed at t="),
        "{}",
        resumed.message
    );
    let summary = within(task).await.unwrap().unwrap();
    assert_eq!(summary.published, 8);
    wait_for_count(&got, 8).await;
    assert_eq!(texts(&got), all, "each once, in order");
    // No burst: what was left keeps its 0.25 s gaps after the resume.
    let after: Vec<Instant> = got
        .lock()
        .unwrap()
        .iter()
        .map(|(t, _)| *t)
        .filter(|t| *t > resumed_at)
        .collect();
    if after.len() >= 3 {
        let span = *after.last().unwrap() - after[0];
        assert!(
            span > Duration::from_millis(100),
            "{} messages within {span:?} of each other after the resume",
            after.len()
        );
    }

    // Started paused: nothing until the resume, then everything. (A fresh participant:
    // rustdds would hand a second reader in the first one the samples it already holds.)
    let listener = node("listener2", domain, false);
    let got = inbox::<StringMsg>(&listener, "/chatter", QosPreset::Status);
    let client = listener
        .service_client::<SetBoolRequest, SetBoolResponse>("/held/set_paused")
        .unwrap();
    let (task, _) = start_replay(
        "held",
        domain,
        ReplayerParams {
            start_paused: true,
            ..params(&bag)
        },
    );
    assert!(
        listener
            .wait_for_service("/held/set_paused", DELIVERY_TIMEOUT)
            .await
    );
    tokio::time::sleep(Duration::from_millis(1500)).await;
    assert!(texts(&got).is_empty(), "started paused: {:?}", texts(&got));
    let resumed = client
        .call(SetBoolRequest { data: false }, DELIVERY_TIMEOUT)
        .await
        .unwrap();
    assert!(resumed.success, "{}", resumed.message);
    within(task).await.unwrap().unwrap();
    wait_for_count(&got, 8).await;
    assert_eq!(texts(&got), all);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn plans_keep_their_transient_local_qos_for_a_late_joiner_and_loops_repeat() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plan");
    let toolpath = Toolpath {
        job_id: "late".into(),
        process: Toolpath::PROCESS_HOTWIRE,
        ..Toolpath::default()
    };
    let mut w = BagWriter::create(&path, Default::default()).unwrap();
    w.add_topic(
        "/cell/toolpath",
        Toolpath::ROS_NAME,
        &[QosProfile::reliable_transient_local(16)],
    )
    .unwrap();
    w.write("/cell/toolpath", &toolpath, T0_NS).unwrap();
    w.finish().unwrap();

    // Nobody listens while it plays; a subscriber that comes afterwards still gets the plan.
    let domain = fresh_domain();
    let (played_tx, played_rx) = tokio::sync::oneshot::channel();
    let (node_r, stop) = ns_node("replayer", "/", domain);
    let p = ReplayerParams {
        wait_for_subscribers_s: 0.0,
        linger_s: 60.0,
        ..params(&path)
    };
    let task = tokio::spawn(async move {
        let mut played = Some(played_tx);
        Replay::open(&p)?
            .run(&node_r, |pr| {
                if pr.published == 1 {
                    if let Some(tx) = played.take() {
                        let _ = tx.send(());
                    }
                }
            })
            .await
    });
    within(played_rx).await.unwrap();
    let late = node("late", domain, false);
    let mut sub = late
        .subscriber::<Toolpath>("/cell/toolpath", QosPreset::Plan)
        .unwrap();
    let got = within(sub.recv()).await.expect("the plan").message;
    assert_eq!(got.job_id, "late");
    stop.trigger();
    let summary = within(task).await.unwrap().unwrap();
    assert_eq!(summary.published, 1);
    assert!(
        !summary.stopped,
        "it had finished; shutdown ended the linger"
    );

    // Looping: the two messages again and again until shutdown.
    let bag = string_bag(
        dir.path(),
        "loop",
        &[("/chatter", 0.0, "a"), ("/chatter", 0.1, "b")],
    );
    let listener = node("listener", domain, false);
    let got = inbox::<StringMsg>(&listener, "/chatter", QosPreset::Status);
    let (task, stop) = start_replay(
        "looper",
        domain,
        ReplayerParams {
            r#loop: true,
            rate: 2.0,
            ..params(&bag)
        },
    );
    wait_for_count(&got, 6).await;
    stop.trigger();
    let summary = within(task).await.unwrap().unwrap();
    assert!(summary.stopped);
    assert!(summary.passes >= 3, "{summary}");
    let seen = texts(&got);
    assert_eq!(seen[..6], ["a", "b", "a", "b", "a", "b"]);
}

#[test]
fn bad_input_is_refused_naming_the_parameter_or_file() {
    let dir = tempfile::tempdir().unwrap();
    let bag = string_bag(dir.path(), "ok", &[("/chatter", 0.0, "x")]);
    let cell = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_cell"))
            .args(args)
            .env("ROS_DOMAIN_ID", fresh_domain().to_string())
            .output()
            .unwrap()
    };
    let check = |out: std::process::Output, code: i32, needle: &str| {
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{stderr}");
        assert!(stderr.contains(needle), "{needle:?} not in {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    };
    let missing = dir.path().join("no-such-bag");
    let missing = missing.display().to_string();
    check(cell(&["bag", "play", &missing]), 64, &missing);
    check(
        cell(&[
            "node",
            "replayer",
            "--ros-args",
            "-p",
            &format!("bag:={missing}"),
        ]),
        64,
        &missing,
    );
    let ok = bag.display().to_string();
    check(cell(&["bag", "play", &ok, "--rate", "0"]), 64, "rate: 0");
    check(
        cell(&["bag", "play", &ok, "--topics", "("]),
        64,
        "topics[0]",
    );
    check(
        cell(&["bag", "play", &ok, "--remap", "/chatter=/x"]),
        64,
        "remap[0]",
    );
    check(
        cell(&[
            "node",
            "replayer",
            "--ros-args",
            "-p",
            &format!("bag:={ok}"),
            "-p",
            "rate:=-1",
        ]),
        64,
        "rate",
    );
    check(
        cell(&["bag", "play", &ok, "--clock", "5000"]),
        64,
        "clock_hz: 5000",
    );
    check(
        cell(&[
            "node",
            "replayer",
            "--ros-args",
            "-p",
            &format!("bag:={ok}"),
            "-p",
            "clock_hz:=-1",
        ]),
        64,
        "clock_hz",
    );

    // An unfinished bag (its writer killed): exit 65 naming the file and saying what to do.
    let mcap = bag.join("ok_0.mcap");
    let bytes = std::fs::read(&mcap).unwrap();
    std::fs::write(&mcap, &bytes[..bytes.len() - 30]).unwrap();
    let name = mcap.display().to_string();
    check(cell(&["bag", "play", &ok]), 65, &name);
    check(
        cell(&[
            "node",
            "replayer",
            "--ros-args",
            "-p",
            &format!("bag:={ok}"),
        ]),
        65,
        "repair",
    );
}

/// `--clock`: the replay publishes the bag's time on `/clock`, and a node started with
/// `use_sim_time:=true` stamps what it publishes with that time, not the wall clock.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_clock_carries_the_bag_time_and_sim_time_nodes_stamp_with_it() {
    cell_runtime::logging::init(Some("info"));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("clock");
    let mut w = BagWriter::create(&path, Default::default()).unwrap();
    w.add_topic(
        "/cell/toolpath",
        Toolpath::ROS_NAME,
        &[QosProfile::reliable_transient_local(16)],
    )
    .unwrap();
    w.add_topic(
        "/chatter",
        StringMsg::ROS_NAME,
        &[QosProfile::reliable_volatile(32)],
    )
    .unwrap();
    // A 100 × 70 mm rectangle inside grbl-xy's travel.
    let p = |x: f64, y: f64| cell_msgs::geometry_msgs::Point { x, y, z: 0.0 };
    let cut = vec![
        p(50.0, 50.0),
        p(150.0, 50.0),
        p(150.0, 120.0),
        p(50.0, 120.0),
        p(50.0, 50.0),
    ];
    let toolpath = Toolpath {
        job_id: "timed".into(),
        process: Toolpath::PROCESS_HOTWIRE,
        power_unit: Toolpath::POWER_WIRE_CURRENT_A,
        segments: vec![cell_msgs::ToolpathSegment {
            kind: cell_msgs::ToolpathSegment::KIND_CUT,
            feed_mm_s: vec![8.0; cut.len()],
            power: vec![2.5; cut.len()],
            points: cut,
            ..Default::default()
        }],
        ..Toolpath::default()
    };
    w.write(
        "/chatter",
        &StringMsg {
            data: "start".into(),
        },
        T0_NS,
    )
    .unwrap();
    // The toolpath 1 s into the bag, then 1 s more of bag.
    w.write("/cell/toolpath", &toolpath, T0_NS + 1_000_000_000)
        .unwrap();
    w.write(
        "/chatter",
        &StringMsg { data: "end".into() },
        T0_NS + 2_000_000_000,
    )
    .unwrap();
    w.finish().unwrap();

    let domain = fresh_domain();
    // An emitter on simulated time, as a bringup with use_sim_time:=true starts it.
    let mut setup = NodeSetup::local("emitter", domain);
    setup.fast_path = cell_runtime::FastPathMode::Off;
    setup.args = cell_runtime::args::NodeArgs::parse([
        "--ros-args",
        "-r",
        "__ns:=/cell",
        "-p",
        "use_sim_time:=true",
    ])
    .unwrap();
    let emitter = CellNode::new(setup).unwrap();
    assert!(emitter.standard_params().use_sim_time);
    assert_eq!(emitter.now(), Default::default(), "zero before any /clock");
    tokio::spawn(emitter::run(
        emitter,
        EmitterParams {
            machine_profile: "grbl-xy".into(),
            ..EmitterParams::default()
        },
    ));
    let listener = node("listener", domain, false);
    let clocks = inbox::<cell_msgs::rosgraph_msgs::Clock>(&listener, "/clock", QosPreset::Clock);
    let programs = inbox::<MachineProgram>(&listener, "/cell/machine_program", QosPreset::Plan);
    let chatter = inbox::<StringMsg>(&listener, "/chatter", QosPreset::Status);

    let (task, _stop) = start_replay(
        "bag_play",
        domain,
        ReplayerParams {
            clock_hz: 50.0,
            ..params(&path)
        },
    );
    wait_for_count(&programs, 1).await;
    let summary = within(task).await.unwrap().unwrap();
    assert_eq!(summary.published, 3, "{summary}");
    assert_eq!(texts(&chatter), ["start", "end"]);

    let ns = |t: &cell_msgs::builtin_interfaces::Time| {
        t.sec as u64 * 1_000_000_000 + u64::from(t.nanosec)
    };
    let end_ns = T0_NS + 2_000_000_000;
    let ticks: Vec<u64> = clocks
        .lock()
        .unwrap()
        .iter()
        .map(|(_, c)| ns(&c.clock))
        .collect();
    // About 2 s at 50 Hz; a loaded machine may deliver fewer.
    assert!(ticks.len() >= 10, "{} /clock messages", ticks.len());
    assert!(
        ticks
            .iter()
            .all(|&t| (T0_NS..=end_ns + 100_000_000).contains(&t)),
        "every /clock within the bag's time: {ticks:?}"
    );
    assert!(
        ticks.windows(2).all(|w| w[0] <= w[1]),
        "monotonic: {ticks:?}"
    );
    // The program was emitted when the bag's clock stood at about 1 s in: that is its stamp,
    // decades away from the wall clock.
    let stamp = ns(&programs.lock().unwrap()[0].1.header.stamp);
    assert!(
        (T0_NS + 700_000_000..=T0_NS + 1_600_000_000).contains(&stamp),
        "program stamped {stamp}, the bag's toolpath was at {}",
        T0_NS + 1_000_000_000
    );
}
