//! A stock ROS 2 Jazzy peer against the real cell nodes (issue 22): rclpy on Fast DDS
//! (`rmw_fastrtps_cpp`, PyPI `ros-jazzy-*` wheels) with `cell_msgs` built from `msgs/` by stock
//! rosidl (`tests/ros2/build_msgs.sh`, through `cell_testkit::jazzy_workspace`). The planner,
//! sequencer, slicer, emitter and machine_bridge (on the GRBL simulator) run here as
//! `launch_scripts/demo.launch.yaml` wires them; `tests/ros2/jazzy_peer.py` discovers them,
//! decodes every cell topic, drives every action (feedback, result, cancel), calls every
//! service, lists, gets and (refused) sets parameters, turns a published Toolpath into a
//! MachineProgram, decodes the standard-type views (nav_msgs/Path, visualization_msgs/MarkerArray,
//! sensor_msgs/Image and JointState, tf2_msgs/TFMessage, diagnostic_msgs/DiagnosticArray) beside
//! the cell messages they show, is the `/clock` of an emitter on simulated time and follows the
//! `/clock` of a replayed bag, reads every node's `/rosout`, and reads the type hash of every
//! endpoint. It prints one JSON line a check; this test asserts what they saw.

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use cell_bag::{BagWriter, QosProfile};
use cell_grbl::sim::Faults;
use cell_msgs::std_msgs::{Header, StringMsg};
use cell_msgs::visualization_msgs::Marker;
use cell_msgs::RosMessage;
use cell_runtime::{args::NodeArgs, CellNode, FastPathMode, NodeSetup, Shutdown};
use cell_views::{diagnostics, frames, kind_style};
use common::fresh_domain;
use serde_json::Value;
use tokio::io::{AsyncBufReadExt, BufReader};

/// Whether every cell endpoint must announce its RIHS01 type hash (REP-2011), equal to the one
/// stock rosidl computed for the peer's packages (the wheels', cell_msgs and the tf2_msgs
/// stand-in). While false, an endpoint that announces none (`INVALID`) or whose type the peer
/// has no description of passes, but one that announces a hash other than rosidl's fails.
const ASSERT_TYPE_HASHES: bool = true;

/// The whole peer run, discovery included, on a loaded 2-core machine.
const PEER_TIMEOUT: Duration = Duration::from_secs(240);

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The peer's JSON lines by check name.
type Checks = BTreeMap<String, Vec<Value>>;

/// The namespace of the cell nodes on simulated time (the emitter the peer is the clock of,
/// and the replayer whose clock the peer follows).
const SIM_NS: &str = "/sim";

/// The peer's `/clock` starts here (2001-09-09), far from the wall clock.
const PEER_CLOCK_S: u64 = 1_000_000_000;

/// The replayed bag's first log time (2017-07-14).
const BAG_T0_NS: u64 = 1_500_000_000_000_000_000;

/// Starts node `name` (package `P`'s parameters) in `/cell` on `domain`, from its shipped
/// params file and `ros_args` after it, DDS on loopback only; returns its shutdown signal.
fn start<P, F, Fut>(name: &str, domain: u16, ros_args: &[&str], run: F) -> Shutdown
where
    P: serde::Serialize + serde::de::DeserializeOwned,
    F: FnOnce(CellNode, P) -> Fut,
    Fut: std::future::Future<Output = anyhow::Result<()>> + Send + 'static,
{
    start_in("/cell", name, domain, ros_args, run)
}

/// [`start`] in `namespace`.
fn start_in<P, F, Fut>(
    namespace: &str,
    name: &str,
    domain: u16,
    ros_args: &[&str],
    run: F,
) -> Shutdown
where
    P: serde::Serialize + serde::de::DeserializeOwned,
    F: FnOnce(CellNode, P) -> Fut,
    Fut: std::future::Future<Output = anyhow::Result<()>> + Send + 'static,
{
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = FastPathMode::Off;
    let params_file = format!("{ROOT}/config/{name}.yaml");
    let ns = format!("__ns:={namespace}");
    let argv = ["--ros-args", "-r", &ns, "--params-file", &params_file];
    setup.args = NodeArgs::parse(argv.iter().chain(ros_args).copied()).expect("node arguments");
    let shutdown = setup.shutdown.clone();
    let (node, params) =
        CellNode::with_params::<P>(setup).unwrap_or_else(|e| panic!("{name} comes up: {e:#}"));
    let name = name.to_string();
    let running = run(node, params);
    tokio::spawn(async move {
        if let Err(e) = running.await {
            panic!("{name} stopped: {e:#}");
        }
    });
    shutdown
}

/// The cell on `domain`: the three planning nodes (the sequencer's and slicer's toolpaths
/// remapped as in the demo, so the emitter only gets the hot-wire's), the emitter for the
/// 4-axis cutter and the bridge on `controller`, running only `execute_program` goals.
fn start_cell(domain: u16, controller: &str) -> Vec<Shutdown> {
    let controllers = format!("controllers:=[{controller}]");
    vec![
        start(
            "planner",
            domain,
            &[
                "-p",
                "machine_profile:=grbl-xyuv",
                "-p",
                "panels:=40",
                "-p",
                "particles:=8",
                "-p",
                "feedback_every:=5",
                "-p",
                "exposure_period_s:=0.2",
            ],
            planner::run,
        ),
        start(
            "sequencer",
            domain,
            &[
                "-r",
                "toolpath:=sheet_toolpath",
                "-p",
                "frame_every_steps:=50",
            ],
            sequencer::run,
        ),
        start(
            "slicer",
            domain,
            // The peer's parts are test data (files in goals: `cell_runtime::data_files`).
            &[
                "-r",
                "toolpath:=waam_toolpath",
                "-p",
                "data_dirs:=[config, tests/data]",
            ],
            slicer::run,
        ),
        start(
            "emitter",
            domain,
            &["-p", "machine_profile:=grbl-xyuv"],
            emitter::run,
        ),
        start(
            "machine_bridge",
            domain,
            &[
                "-p",
                &controllers,
                "-p",
                "feedback_period_s:=0.05",
                "-p",
                "arm_at_start:=true",
            ],
            machine_bridge::run,
        ),
    ]
}

/// The cell nodes on simulated time, in [`SIM_NS`]: an emitter started with
/// `use_sim_time:=true` (named `sim_emitter`), whose clock the peer is, and a replayer of a
/// 2 s bag with `/clock` at 20 Hz, which waits for the peer to subscribe to the bag's
/// `bag_chatter` ("start", "middle", "end" at 0, 1 and 2 s) before it plays.
fn start_sim(domain: u16, dir: &Path) -> Vec<Shutdown> {
    let bag = dir.join("clock-bag");
    let mut w = BagWriter::create(&bag, Default::default()).expect("bag");
    let topic = format!("{SIM_NS}/bag_chatter");
    w.add_topic(
        &topic,
        StringMsg::ROS_NAME,
        &[QosProfile::reliable_volatile(32)],
    )
    .unwrap();
    for (i, text) in ["start", "middle", "end"].into_iter().enumerate() {
        let data = text.to_string();
        w.write(
            &topic,
            &StringMsg { data },
            BAG_T0_NS + i as u64 * 1_000_000_000,
        )
        .unwrap();
    }
    w.finish().unwrap();
    let bag_param = format!("bag:={}", bag.display());
    vec![
        start_in(
            SIM_NS,
            "emitter",
            domain,
            &[
                "-r",
                "__node:=sim_emitter",
                "-p",
                "use_sim_time:=true",
                "-p",
                "machine_profile:=grbl-xyuv",
            ],
            emitter::run,
        ),
        start_in(
            SIM_NS,
            "replayer",
            domain,
            &[
                "-r",
                "__node:=bag_play",
                "-p",
                &bag_param,
                "-p",
                "clock_hz:=20.0",
                "-p",
                "wait_for_subscribers_s:=200.0",
                "-p",
                "linger_s:=0.5",
            ],
            replayer::run,
        ),
    ]
}

/// `CELL_JAZZY_CHECKS="emit execute"` runs only those checks of the peer (while working on
/// them; the test then fails on the checks left out).
fn only_checks() -> Vec<String> {
    match std::env::var("CELL_JAZZY_CHECKS") {
        Ok(only) if !only.trim().is_empty() => std::iter::once("--only".to_string())
            .chain(only.split_whitespace().map(str::to_string))
            .collect(),
        _ => Vec::new(),
    }
}

/// Runs the peer (`only` those checks, else every default one or [`only_checks`]); its JSON
/// lines by check. Its progress goes to stderr.
async fn run_peer(
    jazzy: &cell_testkit::JazzyEnv,
    domain: u16,
    log_dir: &Path,
    only: &[&str],
) -> BTreeMap<String, Vec<Value>> {
    let only: Vec<String> = if only.is_empty() {
        only_checks()
    } else {
        std::iter::once("--only")
            .chain(only.iter().copied())
            .map(str::to_string)
            .collect()
    };
    let mut peer = tokio::process::Command::new(&jazzy.python)
        .arg(format!("{ROOT}/tests/ros2/jazzy_peer.py"))
        .args(["--ns", "/cell", "--repo", ROOT, "--timeout", "30"])
        .args([
            "--sim-ns",
            SIM_NS,
            "--sim-time-s",
            &PEER_CLOCK_S.to_string(),
        ])
        .arg("--install")
        .arg(&jazzy.install)
        .args(only)
        .envs(jazzy.vars.iter().map(|(k, v)| (k, v)))
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        .env("ROS_LOG_DIR", log_dir)
        .stdout(Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .expect("start the rclpy peer");
    let mut lines = BufReader::new(peer.stdout.take().unwrap()).lines();
    let mut checks = Checks::new();
    let read = async {
        while let Some(line) = lines.next_line().await.unwrap() {
            let value: Value = serde_json::from_str(&line)
                .unwrap_or_else(|e| panic!("the peer prints JSON lines: {e}: {line}"));
            let check = value["check"].as_str().expect("a check name").to_string();
            checks.entry(check).or_default().push(value);
        }
        peer.wait().await.unwrap()
    };
    let status = tokio::time::timeout(PEER_TIMEOUT, read)
        .await
        .unwrap_or_else(|_| panic!("the peer did not finish in {PEER_TIMEOUT:?}"));
    assert!(status.success(), "rclpy peer: {status}");
    checks
}

/// The line of `check` whose `case` is `case` (any line when `case` is empty), failing with the
/// peer's error when the check raised.
fn line<'a>(checks: &'a Checks, check: &str, case: &str) -> &'a Value {
    let lines = checks
        .get(check)
        .unwrap_or_else(|| panic!("the peer printed nothing for {check}"));
    if let Some(error) = lines.iter().find_map(|l| l.get("error")) {
        panic!("{check}: {error}");
    }
    lines
        .iter()
        .find(|l| case.is_empty() || l["case"] == case)
        .unwrap_or_else(|| panic!("{check}: no {case:?} line in {lines:?}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stock_jazzy_rclpy_peer_drives_every_cell_interface() {
    let Some(jazzy) = cell_testkit::jazzy_workspace(Path::new(env!("CARGO_TARGET_TMPDIR"))) else {
        return;
    };
    // The nodes' log lines also go to /rosout (cell_runtime::rosout), which the peer reads.
    cell_runtime::logging::init(Some("info"));
    let t0 = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let domain = fresh_domain();
    let (_sim, controller) =
        common::machines::grbl_sim(dir.path(), "cutter", Faults::default(), 10.0, "").await;
    let mut stops = start_cell(domain, &controller);
    stops.extend(start_sim(domain, dir.path()));
    let checks = run_peer(&jazzy, domain, dir.path(), &[]).await;
    for stop in stops {
        stop.trigger();
    }
    eprintln!("the peer ran in {:.1} s", t0.elapsed().as_secs_f64());
    // Shown when the test fails (or with --nocapture).
    for line in checks.values().flatten() {
        eprintln!("{line}");
    }

    discovery(&checks);
    parameters(&checks);
    emitter(&checks);
    plan_hotwire(&checks);
    sequence_sheet(&checks);
    slice(&checks);
    execute_program(&checks);
    topics(&checks);
    views(&checks);
    machine_views(&checks);
    sim_time(&checks);
    bag_clock(&checks);
    rosout(&checks);
    type_hashes(&checks);
}

/// A printer's heaters reach a stock rclpy node: the bridge driving the Marlin simulator
/// (`marlin-sim`, idle and cold) publishes its hotend as `sensor_msgs/Temperature` on
/// `marlin_sim/temperature/hotend` with stock rosidl's type hash, and its heaters' current and
/// target temperatures among its `/diagnostics` values.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stock_jazzy_rclpy_peer_reads_the_printer_heaters() {
    let Some(jazzy) = cell_testkit::jazzy_workspace(Path::new(env!("CARGO_TARGET_TMPDIR"))) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let domain = fresh_domain();
    let bridge = start(
        "machine_bridge",
        domain,
        &["-p", "controllers:=[marlin-sim]"],
        machine_bridge::run,
    );
    let checks = run_peer(&jazzy, domain, dir.path(), &["heaters", "type_hash"]).await;
    bridge.trigger();
    for line in checks.values().flatten() {
        eprintln!("{line}");
    }
    let t = lines_where(&checks, "heaters", "view", "temperature")[0];
    assert_eq!(t["frame_id"], frames::heater("marlin-sim", "hotend"), "{t}");
    assert_eq!(t["variance"], 0.0, "unknown: {t}");
    assert!(t["stamp_ns"].as_u64().unwrap() > 0, "{t}");
    let hotend_c = t["temperature"].as_f64().unwrap();
    assert!((15.0..40.0).contains(&hotend_c), "cold, at ambient: {t}");

    let d = lines_where(&checks, "heaters", "view", "diagnostics")[0];
    assert_eq!(d["name"], "machine_bridge: marlin-sim", "{d}");
    let value = |key: &str| -> f64 {
        let text = d["values"][key].as_str();
        text.unwrap_or_else(|| panic!("no {key}: {d}"))
            .parse()
            .unwrap()
    };
    assert_eq!(value("heater/hotend/target_c"), 0.0, "{d}");
    assert_eq!(value("heater/bed/target_c"), 0.0, "{d}");
    assert!(
        (value("heater/hotend/current_c") - hotend_c).abs() < 1.0,
        "{d}"
    );

    let endpoints: Vec<&Value> = checks["type_hash"]
        .iter()
        .filter(|l| l["type"] == "sensor_msgs/msg/Temperature")
        .collect();
    assert!(!endpoints.is_empty(), "{:?}", checks["type_hash"]);
    for l in endpoints {
        assert!(l["built"].is_string(), "the venv describes it: {l}");
        assert_eq!(l["announced"], l["built"], "stock rosidl's hash: {l}");
        let topic = l["topic"].as_str().unwrap();
        assert!(
            topic.ends_with("cell/marlin_sim/temperature/hotend")
                || topic.ends_with("cell/marlin_sim/temperature/bed"),
            "{l}"
        );
    }
}

fn discovery(checks: &Checks) {
    let graph = line(checks, "graph", "");
    let nodes = &graph["nodes"];
    for node in [
        "planner",
        "sequencer",
        "slicer",
        "emitter",
        "machine_bridge",
    ] {
        assert!(
            nodes
                .as_array()
                .unwrap()
                .iter()
                .any(|n| n == &format!("/cell/{node}")),
            "/cell/{node} not discovered: {nodes}"
        );
    }
    let services = &graph["services"];
    assert_eq!(
        services["/cell/emit_program"][0],
        "cell_msgs/srv/EmitProgram"
    );
    assert_eq!(
        services["/cell/machine_command"][0],
        "cell_msgs/srv/SendMachineCommand"
    );
    assert_eq!(
        services["/cell/plan_hotwire/_action/send_goal"][0],
        "cell_msgs/action/PlanHotwire_SendGoal"
    );
}

fn parameters(checks: &Checks) {
    let lines = &checks["params"];
    assert_eq!(lines.len(), 5, "one line per node: {lines:?}");
    for l in lines {
        let node = l["node"].as_str().unwrap();
        let listed: Vec<&str> = l["listed"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(Value::as_str)
            .collect();
        assert!(listed.contains(&"use_sim_time"), "{node}: {listed:?}");
        assert_eq!(l["values"]["use_sim_time"], false, "{node}: {l}");
        let set = l["set_name"].as_str().unwrap();
        assert!(
            listed.contains(&set) && set != "use_sim_time",
            "{node}: {l}"
        );
        // Read once at start-up: the set is refused with a reason, the value stays.
        assert_eq!(
            l["set_successful"],
            serde_json::json!([false]),
            "{node}: {l}"
        );
        assert!(
            !l["set_reason"][0].as_str().unwrap().is_empty(),
            "{node}: {l}"
        );
        assert_eq!(l["value_after_set"], l["values"][set], "{node}: {l}");
    }
    let planner = lines.iter().find(|l| l["node"] == "/cell/planner").unwrap();
    // From the params file, then -p on the command line (start_cell).
    assert_eq!(planner["values"]["machine_profile"], "grbl-xyuv");
    let sequencer = lines
        .iter()
        .find(|l| l["node"] == "/cell/sequencer")
        .unwrap();
    assert_eq!(sequencer["values"]["machine_profile"], "linuxcnc-plasma");
}

/// A program's summary names the job and the grbl-xyuv profile and has G-code motion lines.
fn assert_program(program: &Value, job_id: &str) {
    assert_eq!(program["job_id"], job_id, "{program}");
    assert_eq!(program["dialect"], "grbl", "{program}");
    assert_eq!(program["machine_profile"], "grbl-xyuv", "{program}");
    assert_eq!(program["files"][0], format!("{job_id}.ngc"), "{program}");
    assert!(program["motion_lines"].as_u64().unwrap() >= 24, "{program}");
    assert!(
        program["line_count"].as_u64().unwrap() > program["motion_lines"].as_u64().unwrap() - 1
    );
    assert_eq!(program["sha256"].as_str().unwrap().len(), 64, "{program}");
}

fn emitter(checks: &Checks) {
    let good = line(checks, "emit", "good");
    assert_eq!(good["success"], true, "{good}");
    assert_program(&good["program"], "jazzy-emit");
    let bad = line(checks, "emit", "bad");
    assert_eq!(bad["success"], false, "{bad}");
    assert!(bad["message"].as_str().unwrap().contains("feed"), "{bad}");
    assert_eq!(bad["files"], 0);
    // The peer's Toolpath on /cell/toolpath came back as a program on /cell/machine_program.
    assert_program(&line(checks, "topic_emit", "")["program"], "jazzy-topic");
}

/// An accepted goal that ended `status`, with feedback.
fn assert_goal(l: &Value, status: &str) {
    assert_eq!(l["accepted"], true, "{l}");
    assert_eq!(l["status"], status, "{l}");
    assert!(l["feedback_count"].as_u64().unwrap() >= 1, "{l}");
}

/// A goal canceled at its first feedback: the server took the cancel and ended it CANCELED.
fn assert_canceled(l: &Value) {
    assert_goal(l, "CANCELED");
    assert_eq!(l["cancel_return_code"], 0, "ERROR_NONE: {l}");
    assert_eq!(l["goals_canceling"], 1, "{l}");
    assert_eq!(l["success"], false, "{l}");
}

fn plan_hotwire(checks: &Checks) {
    assert_eq!(
        line(checks, "plan", "rejected")["accepted"],
        false,
        "a negative chord"
    );
    let goal = line(checks, "plan", "goal");
    assert_goal(goal, "SUCCEEDED");
    assert_eq!(goal["success"], true, "{goal}");
    let feedback = &goal["last_feedback"];
    assert_eq!(feedback["iteration"], 60, "{goal}");
    assert_eq!(feedback["total_iterations"], 60, "{goal}");
    let toolpath = &goal["toolpath"];
    assert_eq!(toolpath["job_id"], "jazzy-wing");
    assert_eq!(toolpath["process"], 0, "PROCESS_HOTWIRE");
    assert!(toolpath["segments"].as_u64().unwrap() >= 1, "{toolpath}");
    assert!(toolpath["points"].as_u64().unwrap() > 40, "{toolpath}");
    let (final_loss, baseline) = (
        goal["final_loss"].as_f64().unwrap(),
        goal["baseline_loss"].as_f64().unwrap(),
    );
    assert!(
        final_loss > 0.0 && final_loss < baseline,
        "the swarm beats the baseline: {goal}"
    );
    let cancel = line(checks, "plan", "cancel");
    assert_canceled(cancel);
    assert!(
        cancel["last_feedback"]["iteration"].as_u64().unwrap() < 200_000,
        "stopped early: {cancel}"
    );
}

fn sequence_sheet(checks: &Checks) {
    let goal = line(checks, "sheet", "goal");
    assert_goal(goal, "SUCCEEDED");
    assert_eq!(goal["success"], true, "{goal}");
    let mut order: Vec<u64> = goal["order"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    order.sort_unstable();
    assert!(!order.is_empty(), "{goal}");
    assert_eq!(
        order,
        (0..order.len() as u64).collect::<Vec<_>>(),
        "every contour cut once: {goal}"
    );
    assert!(goal["cut_length_mm"].as_f64().unwrap() > 0.0, "{goal}");
    assert_eq!(goal["toolpath"]["process"], 1, "PROCESS_SHEET_CUT");
    assert!(
        goal["toolpath"]["segments"].as_u64().unwrap() >= order.len() as u64,
        "{goal}"
    );
    assert_canceled(line(checks, "sheet", "cancel"));
}

fn slice(checks: &Checks) {
    let goal = line(checks, "slice", "goal");
    assert_goal(goal, "SUCCEEDED");
    assert_eq!(goal["success"], true, "{goal}");
    let layers = goal["layers"].as_u64().unwrap();
    assert!(layers >= 2, "a 20 mm cube in layers: {goal}");
    assert_eq!(goal["last_feedback"]["layers_done"], layers, "{goal}");
    assert!(goal["contours"].as_u64().unwrap() >= layers, "{goal}");
    assert_eq!(goal["toolpath"]["process"], 2, "PROCESS_WAAM");
    assert!(
        goal["toolpath"]["kinds"]
            .as_array()
            .unwrap()
            .contains(&Value::from(2)),
        "deposit segments: {goal}"
    );
    assert!(
        goal["report_keys"]
            .as_array()
            .unwrap()
            .contains(&Value::from("deposited_volume_mm3")),
        "{goal}"
    );
    assert_canceled(line(checks, "slice", "cancel"));
}

fn execute_program(checks: &Checks) {
    let hold = line(checks, "execute", "hold");
    assert_eq!(hold["hold"]["success"], true, "{hold}");
    assert_eq!(hold["resume"]["success"], true, "{hold}");
    let goal = line(checks, "execute", "goal");
    assert_goal(goal, "SUCCEEDED");
    assert_eq!(goal["success"], true, "{goal}");
    assert_eq!(goal["saw_hold"], true, "{goal}");
    assert_eq!(goal["outcome"], 0, "OUTCOME_FINISHED: {goal}");
    assert_eq!(goal["final_state"], 6, "STATE_DONE: {goal}");
    assert_eq!(goal["last_acked_line"], goal["program_lines"], "{goal}");
    assert_eq!(
        goal["last_feedback"]["total_lines"], goal["program_lines"],
        "{goal}"
    );
    let cancel = line(checks, "execute", "cancel");
    assert_canceled(cancel);
    assert_eq!(cancel["outcome"], 1, "OUTCOME_ABORTED: {cancel}");
}

fn topics(checks: &Checks) {
    let lines = &checks["topics"];
    let topic = |name: &str| {
        let l = lines
            .iter()
            .find(|l| l["topic"] == format!("/cell/{name}"))
            .unwrap_or_else(|| panic!("no line for /cell/{name}"));
        assert!(l.get("error").is_none(), "{l}");
        assert!(l["count"].as_u64().unwrap() >= 1, "{l}");
        &l["sample"]
    };
    for (name, process) in [("toolpath", 0), ("sheet_toolpath", 1), ("waam_toolpath", 2)] {
        let sample = topic(name);
        assert_eq!(sample["process"], process, "{name}: {sample}");
        assert!(sample["points"].as_u64().unwrap() > 0, "{name}: {sample}");
    }
    assert!(!topic("cut_plan")["order"].as_array().unwrap().is_empty());
    assert!(topic("layer_stack")["layers"].as_u64().unwrap() >= 2);
    assert_eq!(topic("machine_program")["dialect"], "grbl");
    for (name, quantity) in [
        ("exposure", "exposure_profile"),
        ("exposure_matrix", "wire_exposure"),
        ("sheet_heat", "sheet_temperature"),
    ] {
        let sample = topic(name);
        assert_eq!(sample["quantity"], quantity, "{name}: {sample}");
        let cells = sample["width"].as_u64().unwrap() * sample["height"].as_u64().unwrap();
        assert!(cells > 0 && sample["cells"] == cells, "{name}: {sample}");
    }
    let status = topic("machine_status");
    assert_eq!(status["machine_id"], "cutter");
    assert_eq!(
        status["axis_names"],
        serde_json::json!(["X", "Y", "U", "V"])
    );
}

/// The lines of `check` whose `field` is `value`, failing with the peer's error when it raised.
fn lines_where<'a>(checks: &'a Checks, check: &str, field: &str, value: &str) -> Vec<&'a Value> {
    line(checks, check, "");
    checks[check].iter().filter(|l| l[field] == value).collect()
}

/// The frame id a view shows a message of frame `frame_id` in ([`frames::of_header`]).
fn view_frame(frame_id: &Value) -> String {
    frames::of_header(&Header {
        frame_id: frame_id.as_str().unwrap().into(),
        ..Default::default()
    })
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("an array: {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// The views of the three jobs' toolpaths and of the heat maps, beside their sources.
fn views(checks: &Checks) {
    let jobs = [
        ("toolpath", "jazzy-wing"),
        ("sheet_toolpath", "jazzy-sheet"),
        ("waam_toolpath", "jazzy-waam"),
    ];
    let paths = lines_where(checks, "views", "view", "path");
    assert_eq!(paths.len(), 3, "{paths:?}");
    for (topic, job) in jobs {
        let l = paths
            .iter()
            .find(|l| l["topic"] == format!("/cell/{topic}/path"))
            .unwrap_or_else(|| panic!("no path of {topic}: {paths:?}"));
        assert_eq!(l["job_id"], job, "{l}");
        // Every point of the toolpath, in order, in metres (mm / 1000, exactly).
        assert!(l["points"].as_u64().unwrap() > 10, "{l}");
        assert_eq!(l["poses"], l["points"], "{l}");
        assert_eq!(l["equal_poses"], l["poses"], "{l}");
        assert_eq!(l["max_abs_diff_m"], 0.0, "{l}");
        let frame = view_frame(&l["toolpath_frame_id"]);
        assert_eq!(l["frame_id"], frame.as_str(), "{l}");
        assert_eq!(l["pose_frame_ids"], serde_json::json!([frame]), "{l}");
    }

    let arrays = lines_where(checks, "views", "view", "markers");
    assert_eq!(arrays.len(), 3, "{arrays:?}");
    for (topic, job) in jobs {
        let l = arrays
            .iter()
            .find(|l| l["topic"] == format!("/cell/{topic}/markers"))
            .unwrap_or_else(|| panic!("no markers of {topic}: {arrays:?}"));
        assert_eq!(l["job_id"], job, "{l}");
        assert_eq!(l["first_action"], Marker::DELETEALL, "{l}");
        let frame = view_frame(&l["toolpath_frame_id"]);
        let markers = l["markers"].as_array().unwrap();
        let groups = l["groups"].as_array().unwrap();
        assert!(!groups.is_empty(), "{l}");
        assert_eq!(
            markers.len(),
            groups.len(),
            "one marker per kind and layer: {l}"
        );
        for g in groups {
            let style = kind_style::kind_style(g["kind"].as_u64().unwrap() as u8);
            let secondary = g["secondary"] == true;
            let (ns, alpha) = if secondary {
                (
                    format!("{}/secondary", style.namespace),
                    style.color.a / 2.0,
                )
            } else {
                (style.namespace.clone(), style.color.a)
            };
            let m = markers
                .iter()
                .find(|m| m["ns"] == ns.as_str() && m["id"] == g["layer"])
                .unwrap_or_else(|| panic!("{topic}: no marker {ns} {}: {l}", g["layer"]));
            assert_eq!(
                (&m["type"], &m["action"]),
                (&Marker::LINE_LIST.into(), &Marker::ADD.into()),
                "{m}"
            );
            assert_eq!(m["frame_id"], frame.as_str(), "{m}");
            assert_eq!(
                m["points"],
                2 * g["pairs"].as_u64().unwrap(),
                "{topic}: {m} {g}"
            );
            let color: Vec<f32> = f64s(&m["color"]).iter().map(|&c| c as f32).collect();
            let c = style.color;
            assert_eq!(color, [c.r, c.g, c.b, alpha], "{topic} {ns} colour");
            assert_eq!(m["scale_x"], style.width_m, "{m}");
            let first_m = f64s(&m["first_m"]);
            for (got, mm) in first_m.iter().zip(f64s(&g["first_mm"])) {
                assert!((got - mm / 1000.0).abs() < 1e-12, "{topic}: {m} {g}");
            }
        }
    }

    let images = lines_where(checks, "views", "view", "image");
    assert_eq!(images.len(), 3, "{images:?}");
    for topic in ["exposure", "exposure_matrix", "sheet_heat"] {
        let l = images
            .iter()
            .find(|l| l["topic"] == format!("/cell/{topic}/image"))
            .unwrap_or_else(|| panic!("no image of {topic}: {images:?}"));
        let count = l["count"].as_u64().unwrap();
        assert!(count >= 1, "{l}");
        assert_eq!(l["encodings"], serde_json::json!(["32FC1"]), "{l}");
        assert_eq!(l["is_bigendian"], serde_json::json!([0]), "{l}");
        assert_eq!(
            l["steps_ok"], count,
            "step = 4 × width, data = step × height: {l}"
        );
        // Images of the same stamp as a HeatMap: same size, the same float32 bits.
        assert!(l["matched"].as_u64().unwrap() >= 1, "{l}");
        assert_eq!(l["equal"], l["matched"], "{l}");
        assert_eq!(
            (&l["width"], &l["height"]),
            (&l["heat_width"], &l["heat_height"]),
            "{l}"
        );
        assert_eq!(l["step"], 4 * l["width"].as_u64().unwrap(), "{l}");
        assert_eq!(
            l["frame_id"],
            view_frame(&l["heat_frame_id"]).as_str(),
            "{l}"
        );
    }
}

/// The bridge's views after the programs ran on the simulator: joint states and the tool
/// frame beside the MachineStatus of the same stamp, the static frames, the diagnostics.
fn machine_views(checks: &Checks) {
    let js = lines_where(checks, "machine_views", "view", "joint_states")[0];
    let machine = js["machine_id"].as_str().unwrap();
    assert_eq!(machine, "cutter", "{js}");
    let names: Vec<String> = js["axis_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| format!("{machine}/{}", a.as_str().unwrap()))
        .collect();
    assert_eq!(js["name"], serde_json::json!(names), "{js}");
    assert_eq!(js["frame_id"], machine, "{js}");
    assert_eq!(f64s(&js["position"]).len(), names.len(), "{js}");
    assert_eq!(js["max_abs_diff_m"], 0.0, "positions = axes / 1000: {js}");
    assert_eq!(
        (&js["velocity"], &js["effort"]),
        (&0.into(), &0.into()),
        "{js}"
    );

    let tf = lines_where(checks, "machine_views", "view", "tf")[0];
    assert_eq!(tf["parent"], machine, "{tf}");
    assert_eq!(tf["child"], frames::tool(machine), "{tf}");
    assert_eq!(
        tf["max_abs_diff_m"], 0.0,
        "the tool at X, Y, Z / 1000: {tf}"
    );
    assert_eq!(f64s(&tf["rotation"]), [0.0, 0.0, 0.0, 1.0], "{tf}");
    assert_eq!(f64s(&tf["translation"])[2], 0.0, "no Z axis: {tf}");

    let statics = lines_where(checks, "machine_views", "view", "tf_static")[0];
    let frames_seen: Vec<(String, String)> = statics["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p[0].as_str().unwrap().into(), p[1].as_str().unwrap().into()))
        .collect();
    let mut wanted = vec![machine.to_string()];
    for l in lines_where(checks, "views", "view", "path") {
        wanted.push(view_frame(&l["toolpath_frame_id"]));
    }
    for child in wanted {
        if child != frames::CELL {
            assert!(
                frames_seen.contains(&(frames::CELL.into(), child.clone())),
                "{child} attached to {}: {frames_seen:?}",
                frames::CELL
            );
        }
    }

    let diag = lines_where(checks, "machine_views", "view", "diagnostics")[0];
    let last = &diag["last_status"];
    assert!(last.is_object(), "a status before the diagnostics: {diag}");
    let status = diag["status"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["hardware_id"] == machine)
        .unwrap_or_else(|| panic!("no status of {machine}: {diag}"));
    assert_eq!(
        status["name"],
        format!("machine_bridge: {machine}"),
        "{status}"
    );
    let state = last["state"].as_u64().unwrap() as u8;
    assert_eq!(status["level"], diagnostics::level(state), "{diag}");
    assert_eq!(
        status["values"]["state"],
        diagnostics::state_name(state),
        "{diag}"
    );
    assert!(
        status["message"]
            .as_str()
            .unwrap()
            .starts_with(diagnostics::state_name(state)),
        "{diag}"
    );
    for (axis, position) in last["axis_names"]
        .as_array()
        .unwrap()
        .iter()
        .zip(f64s(&last["axis_positions"]))
    {
        let key = format!("axis/{}", axis.as_str().unwrap());
        let value: f64 = status["values"][&key]
            .as_str()
            .unwrap_or_else(|| panic!("no {key}: {diag}"))
            .parse()
            .unwrap();
        assert!((value - position).abs() < 1e-9, "{key}: {diag}");
    }
}

/// The emitter on simulated time stamped the peer's program with the peer's `/clock`.
fn sim_time(checks: &Checks) {
    let l = line(checks, "sim_time", "");
    let stamp = l["stamp_ns"].as_u64().unwrap();
    let (first, last) = (
        l["first_tick_ns"].as_u64().unwrap(),
        l["last_tick_ns"].as_u64().unwrap(),
    );
    assert_eq!(first, PEER_CLOCK_S * 1_000_000_000, "{l}");
    assert_ne!(stamp, 0, "a program stamped with a /clock time: {l}");
    assert_eq!(l["stamp_is_a_tick"], true, "the last /clock received: {l}");
    assert!((first..=last).contains(&stamp), "{l}");
    // Years away from the wall clock: not the system time.
    let wall = l["wall_ns"].as_u64().unwrap();
    assert!(wall - stamp > 10 * 365 * 86_400 * 1_000_000_000, "{l}");
}

/// The replayer's `/clock` carried the bag's time while it played.
fn bag_clock(checks: &Checks) {
    let l = line(checks, "bag_clock", "");
    assert_eq!(
        l["chatter"],
        serde_json::json!(["start", "middle", "end"]),
        "{l}"
    );
    assert!(l["ticks"].as_u64().unwrap() >= 5, "2 s at 20 Hz: {l}");
    assert_eq!(l["monotonic"], true, "{l}");
    let (first, last) = (
        l["first_ns"].as_u64().unwrap(),
        l["last_ns"].as_u64().unwrap(),
    );
    let end = BAG_T0_NS + 2_000_000_000;
    // From the bag's start; at most the lingering half second past its end.
    assert!(first >= BAG_T0_NS && first < end, "{l}");
    assert!(
        last >= BAG_T0_NS + 1_000_000_000 && last <= end + 600_000_000,
        "{l}"
    );
    // When "end" (2 s in) arrived, the clock stood in the bag's last second (or, if the message
    // was slow to arrive, the lingering half second after it).
    let at_end = l["clock_at_chatter_ns"][2]
        .as_u64()
        .unwrap_or_else(|| panic!("no /clock before the bag's end: {l}"));
    assert!(
        (BAG_T0_NS + 1_000_000_000..=end + 600_000_000).contains(&at_end),
        "{l}"
    );
}

/// Every cell node's log lines reached `/rosout`, named after it, at a known level and stamped
/// with the wall clock of this run.
fn rosout(checks: &Checks) {
    let l = line(checks, "rosout", "");
    let (started, now) = (
        l["peer_started_ns"].as_u64().unwrap(),
        l["now_ns"].as_u64().unwrap(),
    );
    // rcl's logger names: namespace and name joined by dots.
    for node in [
        "cell.planner",
        "cell.sequencer",
        "cell.slicer",
        "cell.emitter",
        "cell.machine_bridge",
        "sim.sim_emitter",
        "sim.bag_play",
    ] {
        let n = &l["by_name"][node];
        assert!(
            n["count"].as_u64().unwrap_or(0) >= 1,
            "no /rosout line of {node}: {l}"
        );
        for level in n["levels"].as_array().unwrap() {
            assert!(
                [10, 20, 30, 40, 50].contains(&level.as_u64().unwrap()),
                "{node}: {n}"
            );
        }
        let (min, max) = (
            n["min_stamp_ns"].as_u64().unwrap(),
            n["max_stamp_ns"].as_u64().unwrap(),
        );
        // Lines from before the peer came are kept for late joiners (transient local, 10 s).
        assert!(
            min + 60_000_000_000 >= started && max <= now + 1_000_000_000,
            "{node}: {n}"
        );
    }
    let emitted = &l["emitter_topic_lines"];
    assert!(
        emitted
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["level"] == 20 && e["msg"].as_str().unwrap().contains("machine_program")),
        "the emitter's INFO line for the program of jazzy-topic: {l}"
    );
}

fn type_hashes(checks: &Checks) {
    let lines = &checks["type_hash"];
    let mut cell_endpoints = 0;
    let mut announced = 0;
    for l in lines {
        let ty = l["type"].as_str().unwrap();
        let built = [&l["built"], &l["built_service"]];
        if ty.starts_with("cell_msgs/") {
            cell_endpoints += 1;
            assert!(l["built"].is_string(), "the built package has {ty}: {l}");
        }
        match l["announced"].as_str().unwrap() {
            "INVALID" => {
                if ASSERT_TYPE_HASHES {
                    panic!("no type hash announced: {l}");
                }
            }
            hash => {
                announced += 1;
                // Types the peer has no description of (packages not in the venv) are left out.
                if ASSERT_TYPE_HASHES || built.iter().any(|b| b.is_string()) {
                    assert!(
                        built.iter().any(|b| *b == hash),
                        "a hash other than stock rosidl's: {l}"
                    );
                }
            }
        }
    }
    assert!(
        cell_endpoints >= 20,
        "{cell_endpoints} cell endpoints: {lines:?}"
    );
    // The views', the time source's and the log's endpoints are among them.
    for ty in [
        "nav_msgs/msg/Path",
        "visualization_msgs/msg/MarkerArray",
        "sensor_msgs/msg/Image",
        "sensor_msgs/msg/JointState",
        "tf2_msgs/msg/TFMessage",
        "diagnostic_msgs/msg/DiagnosticArray",
        "rosgraph_msgs/msg/Clock",
        "rcl_interfaces/msg/Log",
    ] {
        assert!(
            lines.iter().any(|l| l["type"] == ty),
            "no endpoint of {ty}: {lines:?}"
        );
    }
    eprintln!(
        "type hashes: {announced} of {} endpoints announce one",
        lines.len()
    );
    for l in lines.iter().filter(|l| l["announced"] == "INVALID") {
        eprintln!(
            "  no type hash: {} {} {} ({})",
            l["node"], l["kind"], l["topic"], l["type"]
        );
    }
}
