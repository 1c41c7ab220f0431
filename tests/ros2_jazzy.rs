//! A stock ROS 2 Jazzy peer against the real cell nodes (issue 22): rclpy on Fast DDS
//! (`rmw_fastrtps_cpp`, PyPI `ros-jazzy-*` wheels) with `cell_msgs` built from `msgs/` by stock
//! rosidl (`tests/ros2/build_msgs.sh`, through `cell_testkit::jazzy_workspace`). The planner,
//! sequencer, slicer, emitter and machine_bridge (on the GRBL simulator) run here as
//! `launch_scripts/demo.launch.yaml` wires them; `tests/ros2/jazzy_peer.py` discovers them,
//! decodes every cell topic, drives every action (feedback, result, cancel), calls every
//! service, lists, gets and (refused) sets parameters, turns a published Toolpath into a
//! MachineProgram, and reads the type hash of every endpoint. It prints one JSON line a check;
//! this test asserts what they saw.

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use cell_grbl::sim::Faults;
use cell_runtime::{args::NodeArgs, CellNode, FastPathMode, NodeSetup, Shutdown};
use common::fresh_domain;
use serde_json::Value;
use tokio::io::{AsyncBufReadExt, BufReader};

/// Whether every cell endpoint must announce its RIHS01 type hash (REP-2011). While false, an
/// endpoint that announces none (`INVALID`) passes, but one that announces a hash other than
/// the built package's fails. Turn it on once the nodes put `typehash=` in USER_DATA.
const ASSERT_TYPE_HASHES: bool = false;

/// The whole peer run, discovery included, on a loaded 2-core machine.
const PEER_TIMEOUT: Duration = Duration::from_secs(240);

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The peer's JSON lines by check name.
type Checks = BTreeMap<String, Vec<Value>>;

/// Starts node `name` (package `P`'s parameters) in `/cell` on `domain`, from its shipped
/// params file and `ros_args` after it, DDS on loopback only; returns its shutdown signal.
fn start<P, F, Fut>(name: &str, domain: u16, ros_args: &[&str], run: F) -> Shutdown
where
    P: serde::Serialize + serde::de::DeserializeOwned,
    F: FnOnce(CellNode, P) -> Fut,
    Fut: std::future::Future<Output = anyhow::Result<()>> + Send + 'static,
{
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = FastPathMode::Off;
    let params_file = format!("{ROOT}/config/{name}.yaml");
    let argv = [
        "--ros-args",
        "-r",
        "__ns:=/cell",
        "--params-file",
        &params_file,
    ];
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
            &["-r", "toolpath:=waam_toolpath"],
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
            &["-p", &controllers, "-p", "feedback_period_s:=0.05"],
            machine_bridge::run,
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

/// Runs the peer; its JSON lines by check. Its progress goes to stderr.
async fn run_peer(
    jazzy: &cell_testkit::JazzyEnv,
    domain: u16,
    log_dir: &Path,
) -> BTreeMap<String, Vec<Value>> {
    let mut peer = tokio::process::Command::new(&jazzy.python)
        .arg(format!("{ROOT}/tests/ros2/jazzy_peer.py"))
        .args(["--ns", "/cell", "--repo", ROOT, "--timeout", "30"])
        .arg("--install")
        .arg(&jazzy.install)
        .args(only_checks())
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
    let t0 = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let domain = fresh_domain();
    let (_sim, controller) =
        common::machines::grbl_sim(dir.path(), "cutter", Faults::default(), 10.0, "").await;
    let stops = start_cell(domain, &controller);
    let checks = run_peer(&jazzy, domain, dir.path()).await;
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
    type_hashes(&checks);
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
                if built.iter().any(|b| b.is_string()) {
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
    eprintln!(
        "type hashes: {announced} of {} endpoints announce one",
        lines.len()
    );
}
