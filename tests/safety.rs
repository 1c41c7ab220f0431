//! The machine ends safe on every stop path of the `machine_bridge` process: each case runs the
//! bridge as its own process (`cell node machine_bridge`) against the in-repo GRBL simulator on
//! loopback TCP, stops it the way it would be stopped in a cell (SIGINT, SIGTERM in a hold,
//! SIGKILL and a restart, a cancelled goal) and then asks the controller itself: its own
//! status (state, spindle) and, over a fresh connection, `$G` and a status report.
//!
//! Waits are bounded generously; nothing here measures speed.

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use cell_grbl::protocol::MachineState;
use cell_grbl::sim::{Faults, SimHandle};
use cell_grbl::stream::{ClientConfig, GrblClient, HeatState};
use cell_grbl::transport::{Connect, Endpoint};
use cell_msgs::{
    ExecuteProgramGoal, MachineCommand, SendMachineCommandRequest, SendMachineCommandResponse,
};
use common::machines::{goal, grbl_program, grbl_sim, operator, Operator};
use common::{cancel_when, fresh_domain, within, DELIVERY_TIMEOUT};

/// A `machine_bridge` process and the lines it wrote to stderr so far.
struct BridgeProcess {
    child: Child,
    log: Arc<Mutex<Vec<String>>>,
}

impl BridgeProcess {
    /// `cell node machine_bridge` on `domain` driving `controller_file`.
    fn start(dir: &Path, domain: u16, controller_file: &str) -> BridgeProcess {
        let params = dir.join(format!("bridge-{}.yaml", rand_suffix()));
        std::fs::write(
            &params,
            format!(
                "/**:\n  ros__parameters:\n    controllers: ['{controller_file}']\n    status_rate_hz: 10.0\n    arm_at_start: true\n"
            ),
        )
        .unwrap();
        let mut child = Command::new(env!("CARGO_BIN_EXE_cell"))
            .args(["node", "machine_bridge", "--ros-args", "--params-file"])
            .arg(&params)
            .env("CELL_DDS_NETWORK", "loopback")
            .env("ROS_DOMAIN_ID", domain.to_string())
            .env("RUST_LOG", "info")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start the bridge");
        let log = Arc::new(Mutex::new(Vec::new()));
        let stderr = child.stderr.take().unwrap();
        let sink = log.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                eprintln!("[bridge] {line}");
                sink.lock().unwrap().push(line);
            }
        });
        BridgeProcess { child, log }
    }

    fn signal(&self, name: &str) {
        let ok = Command::new("kill")
            .args(["-s", name, &self.child.id().to_string()])
            .status()
            .unwrap()
            .success();
        assert!(ok, "kill -s {name}");
    }

    /// Waits for the process to exit; its exit code.
    async fn exited(&mut self) -> Option<i32> {
        within(async {
            loop {
                if let Some(status) = self.child.try_wait().unwrap() {
                    return status.code();
                }
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
        })
        .await
    }

    fn log(&self) -> String {
        self.log.lock().unwrap().join("\n")
    }
}

impl Drop for BridgeProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn rand_suffix() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static N: AtomicU64 = AtomicU64::new(0);
    N.fetch_add(1, Ordering::Relaxed)
}

/// What the controller says about itself over a fresh connection (the bridge is gone or
/// stopped): its heat as `$G` and a status report give it, and its state.
async fn controller_says(sim: &SimHandle, addr: &str) -> (HeatState, Option<MachineState>) {
    let _ = sim;
    let endpoint: Arc<dyn Connect> = Arc::new(Endpoint::Tcp(addr.to_string()));
    let client = GrblClient::connect(endpoint, ClientConfig::default())
        .await
        .expect("the controller answers");
    let heat = client.heat_state().await;
    let state = client
        .progress()
        .borrow()
        .status
        .as_ref()
        .and_then(|s| s.state);
    (heat, state)
}

/// The simulator's TCP address, from the controller file the helper wrote.
fn address_in(controller_file: &str) -> String {
    let text = std::fs::read_to_string(controller_file).unwrap();
    let at = text.find("tcp: '").unwrap() + "tcp: '".len();
    text[at..at + text[at..].find('\'').unwrap()].to_string()
}

/// Sends a goal and returns at once (the test stops the bridge while it runs).
async fn start_goal(op: &Operator, goal: ExecuteProgramGoal) {
    let (_, response) = within(op.client.async_send_goal(goal)).await.expect("sent");
    assert!(response.accepted, "the bridge accepts the goal");
}

/// Waits until the simulator runs the program with the heat on.
async fn cutting(sim: &SimHandle) {
    sim.wait_for(DELIVERY_TIMEOUT, |s| {
        s.state == MachineState::Run && s.spindle_on && s.executed > 10
    })
    .await
    .expect("the machine cuts, heat on");
}

/// The controller's own view after a stop: not moving, not held, heat off; and its
/// answers over a fresh link say the same.
async fn assert_safe(sim: &SimHandle, addr: &str, what: &str) {
    let snap = sim
        .wait_for(DELIVERY_TIMEOUT, |s| {
            !s.spindle_on && matches!(s.state, MachineState::Idle | MachineState::Alarm)
        })
        .await
        .unwrap_or_else(|s| panic!("{what}: the machine is not safe: {s:?}"));
    assert!(!snap.spindle_on, "{what}");
    let (heat, state) = controller_says(sim, addr).await;
    assert!(heat.is_confirmed_off(), "{what}: {heat}");
    assert!(
        matches!(state, Some(MachineState::Idle | MachineState::Alarm)),
        "{what}: {state:?}"
    );
}

/// A simulated controller, a bridge process driving it and an operator node on a fresh domain.
struct Cell {
    dir: tempfile::TempDir,
    sim: SimHandle,
    file: String,
    addr: String,
    bridge: BridgeProcess,
    op: Operator,
}

impl Cell {
    async fn start(id: &str) -> Cell {
        let dir = tempfile::tempdir().unwrap();
        let (sim, file) = grbl_sim(dir.path(), id, Faults::default(), 2.0, "").await;
        let addr = address_in(&file);
        let domain = fresh_domain();
        let bridge = BridgeProcess::start(dir.path(), domain, &file);
        let op = operator(domain).await;
        Cell {
            dir,
            sim,
            file,
            addr,
            bridge,
            op,
        }
    }

    /// Sends a 400-point wing panel as job `job` and waits until it cuts, heat on.
    async fn cut(&self, job: &str) {
        start_goal(&self.op, goal(&grbl_program(job, 400), "")).await;
        cutting(&self.sim).await;
    }

    /// The bridge exited 0 after `signal` and logged the heat read back off.
    async fn stop_bridge_with(&mut self, signal: &str) {
        self.bridge.signal(signal);
        let code = self.bridge.exited().await;
        assert_eq!(code, Some(0), "{}", self.bridge.log());
        assert!(
            self.bridge.log().contains("heat off confirmed"),
            "the bridge read the heat back before exiting:\n{}",
            self.bridge.log()
        );
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigint_mid_program_stops_the_machine_with_the_heat_off_before_the_bridge_exits() {
    let mut cell = Cell::start("hotwire").await;
    cell.cut("sigint").await;
    cell.stop_bridge_with("INT").await;
    // The process is gone: whatever the machine does now, it was left that way.
    assert_safe(&cell.sim, &cell.addr, "after SIGINT").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_while_held_counts_as_running_and_switches_the_heat_off() {
    let mut cell = Cell::start("held").await;
    cell.cut("sigterm-hold").await;
    let op = &cell.op;
    let service = op
        .node
        .service_client::<SendMachineCommandRequest, SendMachineCommandResponse>("/machine_command")
        .unwrap();
    assert!(
        op.node
            .wait_for_service("/machine_command", DELIVERY_TIMEOUT)
            .await
    );
    let held = service
        .call(
            SendMachineCommandRequest {
                command: MachineCommand {
                    machine_id: String::new(),
                    command: MachineCommand::COMMAND_HOLD,
                    value: 0,
                },
            },
            DELIVERY_TIMEOUT,
        )
        .await
        .expect("the bridge answers");
    assert!(held.success, "{}", held.message);
    cell.sim
        .wait_for(DELIVERY_TIMEOUT, |s| s.state == MachineState::Hold(0))
        .await
        .expect("held");
    // A hold keeps the heat on (GRBL switches the spindle off in a hold only with a door or
    // laser mode): the stop must not trust it.
    assert!(cell.sim.snapshot().spindle_on, "held with the heat on");
    cell.stop_bridge_with("TERM").await;
    assert_safe(&cell.sim, &cell.addr, "after SIGTERM in a hold").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bridge_killed_mid_program_is_followed_by_one_that_finds_the_heat_on_and_stops_it() {
    let mut cell = Cell::start("orphan").await;
    cell.cut("killed").await;
    // SIGKILL: no chance to stop anything. The controller runs on what its planner holds.
    cell.bridge.child.kill().unwrap();
    let _ = cell.bridge.exited().await;
    assert!(cell.sim.snapshot().spindle_on, "the heat is still on");
    let restarted = BridgeProcess::start(cell.dir.path(), fresh_domain(), &cell.file);
    cell.sim
        .wait_for(DELIVERY_TIMEOUT, |s| !s.spindle_on)
        .await
        .unwrap_or_else(|s| {
            panic!(
                "the new bridge left the heat on: {s:?}\n{}",
                restarted.log()
            )
        });
    // Give its log a moment to arrive through the pipe.
    within(async {
        while !restarted.log().contains("heat off confirmed") {
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    })
    .await;
    assert!(
        restarted.log().contains("found the machine"),
        "{}",
        restarted.log()
    );
    drop(restarted);
    assert_safe(&cell.sim, &cell.addr, "after a killed bridge").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_cancelled_goal_ends_canceled_with_the_heat_read_back_off() {
    let cell = Cell::start("cancel").await;
    let client = &cell.op.client;
    let result = cancel_when(
        client,
        goal(&grbl_program("cancel", 400), ""),
        DELIVERY_TIMEOUT * 4,
        |_| cutting(&cell.sim),
    )
    .await;
    let (status, result) = result;
    assert_eq!(
        status,
        cell_runtime::action::GoalStatusEnum::Canceled,
        "{}",
        result.message
    );
    assert!(
        result.message.contains("heat off confirmed"),
        "{}",
        result.message
    );
    let Cell {
        sim, addr, bridge, ..
    } = cell;
    drop(bridge);
    assert_safe(&sim, &addr, "after a cancel").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cell_stream_stopped_by_sigterm_leaves_the_heat_read_back_off() {
    let dir = tempfile::tempdir().unwrap();
    let (sim, file) = grbl_sim(dir.path(), "stream", Faults::default(), 2.0, "").await;
    let addr = address_in(&file);
    let program = grbl_program("stream-term", 400);
    let ngc = dir.path().join("stream-term.ngc");
    std::fs::write(&ngc, &program.files[0].text).unwrap();
    let mut stream = Command::new(env!("CARGO_BIN_EXE_cell"))
        .args(["stream", "--controller", &file, "--program"])
        .arg(&ngc)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start cell stream");
    cutting(&sim).await;
    let ok = Command::new("kill")
        .args(["-s", "TERM", &stream.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok);
    let out = within(async move {
        tokio::task::spawn_blocking(move || {
            let status = stream.wait().unwrap();
            let mut err = String::new();
            std::io::Read::read_to_string(&mut stream.stderr.take().unwrap(), &mut err).unwrap();
            (status, err)
        })
        .await
        .unwrap()
    })
    .await;
    let (status, stderr) = out;
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("SIGTERM: aborting"), "{stderr}");
    assert!(stderr.contains("heat off confirmed"), "{stderr}");
    assert_safe(&sim, &addr, "after SIGTERM to cell stream").await;
}
