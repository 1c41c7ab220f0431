//! Who may run the machines (issue 23, item 1), with a real `machine_bridge` process
//! (`cell node machine_bridge`) on the GRBL simulator over loopback TCP, goals from this test's
//! node and real `cell machine …` processes:
//! - unarmed, the bridge refuses a goal and a resume with the reason (logged at WARN with the
//!   peer) and still takes an abort; `cell machine arm` (a local act over the bridge's Unix
//!   socket, 0600 in a 0700 directory) lets the same goal run; the arming ends after
//!   `arm_idle_timeout_s` without machine activity, and the goal is refused again;
//! - a peer missing from `allowed_peers` is refused, goal and command alike, even armed.

mod common;

use std::os::unix::fs::{FileTypeExt, MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};
use std::time::{Duration, Instant};

use cell_grbl::sim::Faults;
use cell_msgs::{ExecuteProgramFeedback, ExecuteProgramGoal, ExecuteProgramResult as R};
use cell_runtime::action::ActionClient;
use common::machines::{accepted, execute, goal, grbl_program, grbl_sim};
use common::{discover_action_server, fresh_domain, node, DELIVERY_TIMEOUT};
use tokio::process::{Child, Command};

const CELL: &str = env!("CARGO_BIN_EXE_cell");

/// Idle time of the unarmed bridge's arming: short, so the test sees it end.
const IDLE_S: f64 = 3.0;

/// A bridge process in `/cell` on `domain`, driving `controller`, with `params` (`-p` values);
/// its stderr goes to `log`.
fn start_bridge(domain: u16, controller: &str, params: &[String], log: &Path) -> Child {
    let mut command = Command::new(CELL);
    command
        .args(["node", "machine_bridge", "--ros-args", "-r", "__ns:=/cell"])
        .arg("-p")
        .arg(format!("controllers:=['{controller}']"));
    for p in params {
        command.arg("-p").arg(p);
    }
    command
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("CELL_DDS_NETWORK", "loopback")
        .env("RUST_LOG", "info")
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(log).unwrap())
        .kill_on_drop(true)
        .spawn()
        .expect("start the bridge")
}

/// `cell machine ARGS` for the bridge in `/cell` on `domain`.
async fn cell_machine(domain: u16, args: &[&str]) -> Output {
    let run = Command::new(CELL)
        .arg("machine")
        .args(args)
        .args(["--timeout", "30", "--ros-args", "-r", "__ns:=/cell"])
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("CELL_DDS_NETWORK", "loopback")
        .env_remove("RUST_LOG")
        .output();
    tokio::time::timeout(2 * DELIVERY_TIMEOUT, run)
        .await
        .expect("cell machine ends")
        .expect("run cell")
}

/// Asserts exit status `code` and no panic; returns stdout and stderr.
fn expect_exit(out: &Output, code: i32) -> (String, String) {
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(
        out.status.code(),
        Some(code),
        "stdout: {stdout}\nstderr: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    (stdout, stderr)
}

/// Waits (up to [`DELIVERY_TIMEOUT`]) for a line of `log` containing every one of `parts`.
async fn logged(log: &Path, parts: &[&str]) -> String {
    let deadline = Instant::now() + DELIVERY_TIMEOUT;
    loop {
        let text = std::fs::read_to_string(log).unwrap_or_default();
        if let Some(line) = text.lines().find(|l| parts.iter().all(|p| l.contains(p))) {
            return line.to_owned();
        }
        assert!(
            Instant::now() < deadline,
            "no line with {parts:?} in the bridge's log:\n{text}"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

type Client = ActionClient<ExecuteProgramGoal, R, ExecuteProgramFeedback>;

async fn client_on(op: &cell_runtime::CellNode) -> Client {
    let client = op.action_client("/cell/execute_program").unwrap();
    discover_action_server(op, "/cell/execute_program").await;
    client
}

/// Waits for the bridge's arm socket to appear.
async fn socket_appears(path: &Path) {
    let deadline = Instant::now() + DELIVERY_TIMEOUT;
    while !path.exists() {
        assert!(
            Instant::now() < deadline,
            "no arm socket {}",
            path.display()
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_unarmed_bridge_refuses_motion_until_armed_at_the_machine_and_disarms_when_idle() {
    let dir = tempfile::tempdir().unwrap();
    let (_sim, controller) = grbl_sim(dir.path(), "cutter", Faults::default(), 20.0, "").await;
    let domain = fresh_domain();
    let log = dir.path().join("bridge.log");
    let _bridge = start_bridge(
        domain,
        &controller,
        &[format!("arm_idle_timeout_s:={IDLE_S}")],
        &log,
    );
    let op = node("operator", domain, false);
    let client = client_on(&op).await;

    // The arm service: a Unix socket where `cell machine arm` looks, this user's alone.
    let socket: PathBuf = cell_bridge::arming::default_socket_path(domain, "/cell/machine_bridge");
    socket_appears(&socket).await;
    let meta = std::fs::metadata(&socket).unwrap();
    assert!(meta.file_type().is_socket());
    assert_eq!(meta.permissions().mode() & 0o777, 0o600);
    let folder = std::fs::metadata(socket.parent().unwrap()).unwrap();
    assert_eq!(folder.permissions().mode() & 0o777, 0o700);
    let me = std::fs::metadata(dir.path()).unwrap().uid();
    assert_eq!((meta.uid(), folder.uid()), (me, me));

    // Unarmed: the goal is rejected, the reason logged at WARN with the peer.
    let program = grbl_program("access", 30);
    assert!(!accepted(&client, goal(&program, "cutter")).await);
    let line = logged(&log, &["rejecting goal access", "not armed"]).await;
    assert!(
        line.contains("WARN") && line.contains("participant") && line.contains("127.0.0.1"),
        "{line}"
    );
    // A resume is refused with the reason; an abort (a stop) goes through unarmed.
    let (_, stderr) = expect_exit(
        &cell_machine(domain, &["resume", "--machine", "cutter"]).await,
        1,
    );
    assert!(stderr.contains("not armed"), "{stderr}");
    logged(&log, &["WARN", "resume refused", "not armed"]).await;
    let (stdout, _) = expect_exit(
        &cell_machine(domain, &["abort", "--machine", "cutter"]).await,
        0,
    );
    assert!(stdout.contains("cutter"), "{stdout}");
    let (stdout, _) = expect_exit(&cell_machine(domain, &["armed"]).await, 0);
    assert_eq!(stdout.trim(), "disarmed");

    // Armed at the machine, the same goal runs to its end.
    let (stdout, _) = expect_exit(&cell_machine(domain, &["arm"]).await, 0);
    assert!(stdout.starts_with("armed"), "{stdout}");
    let (result, _) = execute(&client, goal(&program, "cutter"), DELIVERY_TIMEOUT).await;
    let ended = Instant::now();
    assert!(result.success, "{}", result.message);
    assert_eq!(result.outcome, R::OUTCOME_FINISHED);

    // No machine activity for IDLE_S: the arming ends by itself, logged.
    let (stdout, _) = expect_exit(&cell_machine(domain, &["armed"]).await, 0);
    assert!(
        stdout.starts_with("armed"),
        "armed just after the run: {stdout}"
    );
    loop {
        let (stdout, _) = expect_exit(&cell_machine(domain, &["armed"]).await, 0);
        if stdout.trim() == "disarmed" {
            break;
        }
        assert!(
            ended.elapsed() < Duration::from_secs_f64(IDLE_S + 5.0),
            "still armed {:.1} s after the run",
            ended.elapsed().as_secs_f64()
        );
        tokio::time::sleep(Duration::from_millis(300)).await;
    }
    assert!(
        ended.elapsed() >= Duration::from_secs_f64(IDLE_S - 0.5),
        "disarmed after {:.1} s, before the idle time",
        ended.elapsed().as_secs_f64()
    );
    logged(&log, &["disarmed: no machine activity"]).await;
    assert!(!accepted(&client, goal(&program, "cutter")).await);

    // Where no bridge listens, `cell machine arm` says so (exit 69).
    let nowhere = dir.path().join("none.sock");
    let nowhere = nowhere.to_str().unwrap();
    let other = expect_exit(
        &cell_machine(domain, &["arm", "--socket", nowhere]).await,
        69,
    );
    assert!(other.1.contains("arm socket"), "{}", other.1);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_peer_missing_from_allowed_peers_is_refused_even_armed() {
    let dir = tempfile::tempdir().unwrap();
    let (_sim, controller) = grbl_sim(dir.path(), "cutter", Faults::default(), 20.0, "").await;
    let domain = fresh_domain();
    let log = dir.path().join("bridge.log");
    let socket = dir.path().join("arm.sock");
    // Another host and another participant: not this test's node, nor `cell machine`.
    let _bridge = start_bridge(
        domain,
        &controller,
        &[
            "allowed_peers:=['10.255.255.1', '01.02.03.04.05.06.07.08.09.0a.0b.0c']".into(),
            "arm_at_start:=true".into(),
            format!("arm_socket:={}", socket.display()),
        ],
        &log,
    );
    let op = node("operator", domain, false);
    let client = client_on(&op).await;
    socket_appears(&socket).await;
    logged(&log, &["WARN", "armed", "arm_at_start"]).await;

    let program = grbl_program("outsider", 30);
    assert!(!accepted(&client, goal(&program, "cutter")).await);
    let line = logged(&log, &["rejecting goal outsider", "not in allowed_peers"]).await;
    assert!(
        line.contains("WARN") && line.contains("127.0.0.1 is not listed"),
        "{line}"
    );
    // A command from an unlisted peer is refused too, stops included.
    let (_, stderr) = expect_exit(
        &cell_machine(domain, &["hold", "--machine", "cutter"]).await,
        1,
    );
    assert!(stderr.contains("not in allowed_peers"), "{stderr}");
    logged(&log, &["WARN", "hold refused", "not in allowed_peers"]).await;
    // It was the list, not the arming: the bridge is still armed.
    let armed = Command::new(CELL)
        .args(["machine", "armed", "--socket"])
        .arg(&socket)
        .output()
        .await
        .unwrap();
    let (stdout, _) = expect_exit(&armed, 0);
    assert!(stdout.starts_with("armed"), "{stdout}");
}
