//! `cell machine` end to end, all real processes: a `grbl_sim` process on loopback TCP, a
//! `machine_bridge` process (`cell node machine_bridge`) in the `/cell` namespace on a domain of
//! its own, a program goal sent from this test, and `cell machine …` processes that watch,
//! hold, resume and abort it. The simulator's executed-line log (written when it is stopped
//! with SIGINT) shows what the machine really did.

mod common;

use std::path::Path;
use std::process::{Output, Stdio};
use std::time::Duration;

use cell_msgs::{
    ExecuteProgramFeedback, ExecuteProgramGoal, ExecuteProgramResult as R, MachineProgram,
    MachineStatus, ProgramFile,
};
use cell_runtime::action::GoalStatusEnum;
use cell_runtime::QosPreset;
use common::machines::{sent_lines, status_until, texts};
use common::{discover_action_server, fresh_domain, node, within, DELIVERY_TIMEOUT};
use tokio::io::{AsyncBufReadExt, BufReader, Lines};
use tokio::process::{Child, ChildStdout, Command};

const CELL: &str = env!("CARGO_BIN_EXE_cell");
const GRBL_SIM: &str = env!("CARGO_BIN_EXE_grbl_sim");

/// `--timeout` for `cell machine` calls that must reach the bridge: generous, for discovery on
/// a loaded 2-core machine.
const REACH: &str = "30";

/// A 4-axis hot-wire program of `moves` short cuts at 120 mm/min (about a third of a second
/// each, real time), heat on; every line is distinct, so the simulator's log shows each line
/// run once or not.
fn long_program(moves: usize) -> MachineProgram {
    let mut text = String::from("(cell machine test)\nG21 G90 G94\nG0 X0 Y0 U0 V0\nM3 S1000\n");
    for i in 1..=moves {
        let (x, y) = (i as f64 * 0.5, (i % 2) as f64 * 0.5);
        text.push_str(&format!("G1 X{x:.1} Y{y:.1} U{x:.1} V{y:.1} F120\n"));
    }
    text.push_str("M5\n");
    MachineProgram {
        job_id: "long-cut".into(),
        dialect: "grbl".into(),
        machine_profile: "grbl-xyuv".into(),
        line_count: text.lines().count() as u32,
        files: vec![ProgramFile {
            name: "long-cut.ngc".into(),
            text,
        }],
        ..MachineProgram::default()
    }
}

/// A `grbl_sim` process on an ephemeral loopback port, its executed lines logged to `log` on
/// SIGINT; its address and the rest of its stdout (kept open: it prints a summary at exit).
async fn start_grbl_sim(log: &Path) -> (Child, String, Lines<BufReader<ChildStdout>>) {
    let mut sim = Command::new(GRBL_SIM)
        .args(["--tcp", "127.0.0.1:0", "--axes", "XYUV", "--log"])
        .arg(log)
        .stdout(Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .expect("start grbl_sim");
    let mut stdout = BufReader::new(sim.stdout.take().unwrap()).lines();
    let banner = within(stdout.next_line())
        .await
        .unwrap()
        .expect("grbl_sim prints where it listens");
    let addr = banner
        .split_whitespace()
        .last()
        .filter(|_| banner.contains("tcp"))
        .unwrap_or_else(|| panic!("no address in {banner:?}"))
        .to_string();
    (sim, addr, stdout)
}

/// The bridge process on `domain`, namespace `/cell`, driving the controller file; its log
/// goes to `log`.
fn start_bridge(domain: u16, controller: &Path, log: &Path) -> Child {
    Command::new(CELL)
        .args([
            "node",
            "machine_bridge",
            "--ros-args",
            "-r",
            "__ns:=/cell",
            "-p",
            "arm_at_start:=true",
            "-p",
        ])
        .arg(format!("controllers:=['{}']", controller.display()))
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("CELL_DDS_NETWORK", "loopback")
        .env_remove("RUST_LOG")
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(log).unwrap())
        .kill_on_drop(true)
        .spawn()
        .expect("start the bridge")
}

/// Runs `cell machine ARGS` against the bridge on `domain` (loopback DDS).
async fn cell_machine(domain: u16, args: &[&str]) -> Output {
    let run = Command::new(CELL)
        .arg("machine")
        .args(args)
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("CELL_DDS_NETWORK", "loopback")
        .env_remove("RUST_LOG")
        .output();
    tokio::time::timeout(3 * DELIVERY_TIMEOUT, run)
        .await
        .expect("cell machine ends")
        .expect("run cell")
}

/// `cell machine ARGS --timeout 30 --ros-args -r __ns:=/cell`.
async fn at_cell(domain: u16, args: &[&str]) -> Output {
    let mut all = args.to_vec();
    all.extend(["--timeout", REACH, "--ros-args", "-r", "__ns:=/cell"]);
    cell_machine(domain, &all).await
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Asserts exit status `code` and no panic; returns stdout and stderr.
fn expect_exit(out: &Output, code: i32) -> (String, String) {
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(
        out.status.code(),
        Some(code),
        "stdout: {stdout}\nstderr: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    (stdout, stderr)
}

/// Sends SIGINT to a process this test started and waits for it to exit.
async fn interrupt(child: &mut Child) -> std::process::ExitStatus {
    let pid = child.id().expect("still running").to_string();
    let sent = Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .await
        .unwrap();
    assert!(sent.success(), "kill -INT {pid}");
    within(child.wait()).await.unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cell_machine_watches_holds_resumes_and_aborts_a_running_bridge() {
    let dir = tempfile::tempdir().unwrap();
    let executed_log = dir.path().join("executed.nc");
    let (mut sim, addr, mut sim_stdout) = start_grbl_sim(&executed_log).await;
    let controller = dir.path().join("cutter.yaml");
    std::fs::write(
        &controller,
        format!(
            "id: cutter\nprotocol: grbl\nmachine_profile: grbl-xyuv\naxes: XYUV\n\
             endpoint: {{tcp: '{addr}'}}\nreconnect: {{attempts: 20, delay_s: 0.1}}\n"
        ),
    )
    .unwrap();
    let domain = fresh_domain();
    let bridge_log = dir.path().join("bridge.log");
    let mut bridge = start_bridge(domain, &controller, &bridge_log);
    let bridge_said = || std::fs::read_to_string(&bridge_log).unwrap_or_default();

    // The operator's view before any job: the controller by name, connected and idle.
    let op = node("operator", domain, false);
    let mut status = op
        .subscriber::<MachineStatus>("/cell/machine_status", QosPreset::Status)
        .unwrap();
    status_until(&mut status, "cutter", |s| {
        s.state == MachineStatus::STATE_IDLE
    })
    .await;
    let (stdout, _) = expect_exit(&at_cell(domain, &["status"]).await, 0);
    let line = stdout.trim();
    assert!(
        line.starts_with("cutter  IDLE") && line.contains("X=0.000 Y=0.000 U=0.000 V=0.000"),
        "{stdout}"
    );
    assert_eq!(stdout.lines().count(), 1, "one controller, one line");

    // A watcher that follows the whole job (`status --follow`), read as it prints.
    let mut follow = Command::new(CELL)
        .args(["machine", "status", "--follow", "--timeout", REACH])
        .args(["--ros-args", "-r", "__ns:=/cell"])
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("CELL_DDS_NETWORK", "loopback")
        .env_remove("RUST_LOG")
        .stdout(Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .unwrap();
    let mut follow_lines = BufReader::new(follow.stdout.take().unwrap()).lines();
    let first = within(follow_lines.next_line()).await.unwrap();
    assert!(
        first
            .as_deref()
            .is_some_and(|l| l.starts_with("cutter  IDLE")),
        "{first:?}"
    );
    let followed = tokio::spawn(async move {
        let mut lines = Vec::new();
        while let Ok(Some(line)) = follow_lines.next_line().await {
            lines.push(line);
        }
        lines
    });

    let client = op
        .action_client::<ExecuteProgramGoal, R, ExecuteProgramFeedback>("/cell/execute_program")
        .unwrap();
    discover_action_server(&op, "/cell/execute_program").await;
    let program = long_program(400);
    let sent = texts(&sent_lines(&program));
    let goal = ExecuteProgramGoal {
        program: program.clone(),
        machine_id: "cutter".into(),
        start_line: 0,
    };
    let (goal_id, response) = within(client.async_send_goal(goal)).await.unwrap();
    assert!(response.accepted, "{}", bridge_said());
    let result = cell_runtime::action::request_result(
        &client,
        goal_id,
        Duration::from_secs(600),
        Duration::from_secs(600),
    );

    let operate = async {
        status_until(&mut status, "cutter", |s| {
            s.state == MachineStatus::STATE_RUNNING && s.acked_line > 10
        })
        .await;

        // Hold: the bridge says it sent the feed hold, the machine stops where it is.
        let (stdout, _) = expect_exit(&at_cell(domain, &["hold", "--machine", "cutter"]).await, 0);
        assert!(
            stdout.contains("cutter") && stdout.contains("hold"),
            "{stdout}"
        );
        let held = status_until(&mut status, "cutter", |s| {
            s.state == MachineStatus::STATE_HOLD
        })
        .await;
        tokio::time::sleep(Duration::from_millis(800)).await;
        let still = status_until(&mut status, "cutter", |_| true).await;
        assert_eq!(still.state, MachineStatus::STATE_HOLD);
        let (stdout, _) = expect_exit(
            &at_cell(domain, &["status", "--machine", "CUTTER"]).await,
            0,
        );
        assert!(
            stdout.starts_with("cutter  HOLD  job long-cut  line "),
            "{stdout}"
        );
        let now = status_until(&mut status, "cutter", |_| true).await;
        assert_eq!(
            now.axis_positions, still.axis_positions,
            "nothing moves in a hold (held at line {})",
            held.acked_line
        );

        // Resume must name its machine (only stops address every one); then it moves on.
        let (_, stderr) = expect_exit(&at_cell(domain, &["resume"]).await, 1);
        assert!(stderr.contains("machine_id is empty"), "{stderr}");
        let (stdout, _) = expect_exit(
            &at_cell(domain, &["resume", "--machine", "cutter"]).await,
            0,
        );
        assert!(stdout.contains("cutter"), "{stdout}");
        status_until(&mut status, "cutter", |s| {
            s.state == MachineStatus::STATE_RUNNING && s.axis_positions != now.axis_positions
        })
        .await;

        // A refused command: the bridge's own reason, exit 1.
        let (_, stderr) = expect_exit(
            &at_cell(
                domain,
                &["override", "--feed", "500", "--machine", "cutter"],
            )
            .await,
            1,
        );
        assert!(stderr.contains("10..200"), "{stderr}");

        // Abort: the bridge answers at once; the goal ends aborted.
        let (stdout, _) = expect_exit(&at_cell(domain, &["abort", "--machine", "cutter"]).await, 0);
        assert!(
            stdout.contains("cutter") && stdout.contains("abort"),
            "{stdout}"
        );
    };
    let (result, ()) = tokio::join!(result, operate);
    let (goal_status, result) = result.expect("the goal's result");
    assert_eq!(result.outcome, R::OUTCOME_ABORTED, "{}", result.message);
    assert_eq!(goal_status, GoalStatusEnum::Canceled, "{}", result.message);

    // After the abort: idle, no alarm, as `cell machine status` shows it.
    status_until(&mut status, "cutter", |s| {
        s.state == MachineStatus::STATE_IDLE || s.state == MachineStatus::STATE_ALARM
    })
    .await;
    let (stdout, _) = expect_exit(
        &at_cell(domain, &["status", "--machine", "cutter"]).await,
        0,
    );
    assert!(stdout.starts_with("cutter  IDLE"), "{stdout}");
    assert!(!stdout.contains("alarm"), "{stdout}");

    // An unknown controller: the bridge's error, exit 1, for commands and status alike.
    let (_, stderr) = expect_exit(&at_cell(domain, &["hold", "--machine", "nope"]).await, 1);
    assert!(
        stderr.starts_with("error:") && stderr.contains("\"nope\""),
        "{stderr}"
    );
    let (_, stderr) = expect_exit(&at_cell(domain, &["status", "--machine", "nope"]).await, 1);
    assert!(
        stderr.contains("\"nope\"") && stderr.contains("cutter"),
        "{stderr}"
    );

    // The watcher saw the job run, hold, run again and end; Ctrl-C ends it cleanly.
    assert!(interrupt(&mut follow).await.success());
    let states: Vec<String> = within(followed)
        .await
        .unwrap()
        .iter()
        .map(|l| l.split("  ").nth(1).unwrap_or_default().to_string())
        .collect();
    let mut changes = states.clone();
    changes.dedup();
    let seen = changes.join(" ");
    assert!(
        seen.contains("RUNNING HOLD RUNNING") && seen.ends_with("IDLE"),
        "{seen}"
    );

    // The bridge stops cleanly; the simulator's log shows every program line it ran ran once,
    // in order, and the heat was switched off last.
    assert!(interrupt(&mut bridge).await.success(), "{}", bridge_said());
    assert!(interrupt(&mut sim).await.success());
    while let Ok(Some(_)) = sim_stdout.next_line().await {}
    let executed: Vec<String> = std::fs::read_to_string(&executed_log)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    // The program's own last line, M5, never ran: the M5 in the log is the safe stop's.
    let body = &sent[..sent.len() - 1];
    let ran: Vec<&String> = executed.iter().filter(|l| body.contains(l)).collect();
    assert!(
        ran.len() > 4 && ran.len() < body.len(),
        "{} of {} lines ran",
        ran.len(),
        body.len()
    );
    assert_eq!(
        ran,
        body.iter().take(ran.len()).collect::<Vec<_>>(),
        "in order, once each"
    );
    let last_heat = executed
        .iter()
        .rev()
        .find(|l| l.starts_with("M3") || l.starts_with("M4") || l.starts_with("M5"));
    assert_eq!(last_heat.map(String::as_str), Some("M5"), "{executed:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_a_bridge_cell_machine_says_where_it_looked() {
    let domain = fresh_domain();
    let out = cell_machine(
        domain,
        &["abort", "--timeout", "2", "--ros-args", "-r", "__ns:=/cell"],
    )
    .await;
    let (_, stderr) = expect_exit(&out, 69);
    assert!(
        stderr.starts_with("error:")
            && stderr.contains("/cell/machine_command")
            && stderr.contains(&format!("ROS_DOMAIN_ID={domain}")),
        "{stderr}"
    );
    let out = cell_machine(domain, &["status", "--follow", "--timeout", "2"]).await;
    let (_, stderr) = expect_exit(&out, 69);
    assert!(
        stderr.contains("/machine_status") && stderr.contains(&format!("ROS_DOMAIN_ID={domain}")),
        "{stderr}"
    );
    // Bad command lines: exit 64, one line naming the fault.
    let (_, stderr) = expect_exit(&cell_machine(domain, &["hold", "--timeout", "0"]).await, 64);
    assert!(stderr.contains("--timeout"), "{stderr}");
    let (_, stderr) = expect_exit(&cell_machine(domain, &["hold", "stray"]).await, 64);
    assert!(
        stderr.contains("stray") && stderr.contains("--ros-args"),
        "{stderr}"
    );
    let (_, stderr) = expect_exit(&cell_machine(domain, &["override"]).await, 64);
    assert!(
        stderr.contains("--feed") && stderr.contains("--spindle"),
        "{stderr}"
    );
}
