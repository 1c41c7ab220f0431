//! The ABB robot ends safe on every stop path: the bridge's RWS controller against the RWS
//! simulator over loopback HTTP, running the emitter's RAPID for the IRB 1600 cell, whose weld
//! power is the digital output `doWeld` (`SetDO doWeld, 1` around each weld run). Each case
//! asserts RAPID's state and the weld output from the simulator's own state, and what the
//! result or the command's answer says about the heat.
//!
//! Faults come from the simulator: [`RwsSim::stall`] leaves requests unanswered, as a cut cable
//! or a hung controller would, and drops them when lifted.

use std::sync::Arc;
use std::time::Duration;

use cell_bridge::config::ControllerSpec;
use cell_bridge::controller::{Controller, RunOutcome};
use cell_msgs::{ExecuteProgramResult as R, MachineCommand, MachineProgram, MachineStatus};
use cell_rws::sim::{RwsSim, SimConfig};
use cell_rws::RwsVersion;

const WELD: &str = "Local/DRV_1/doWeld";

fn program(job: &str) -> MachineProgram {
    let text = std::fs::read_to_string(format!(
        "{}/../../tests/data/toolpaths/wall.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut tp: cell_msgs::Toolpath = cell_msgs::json::from_str(&text).unwrap();
    // The wall moved into the IRB 1600's reach (X 500..900, Y -300..300, Z 100..500 mm).
    for p in tp.segments.iter_mut().flat_map(|s| s.points.iter_mut()) {
        p.x += 500.0;
        p.y -= 100.0;
        p.z += 150.0;
    }
    let profile = cell_profiles::MachineProfile::resolve("abb-irb1600-rw7-do").unwrap();
    let program = cell_emitter::emit_program(&tp, &profile, job).unwrap();
    assert!(
        program
            .files
            .iter()
            .any(|f| f.text.contains("SetDO doWeld, 1;")),
        "the program switches the weld output itself"
    );
    program
}

/// An OmniCore simulator whose program "runs" for a minute, and a controller file for it with
/// the weld output as heat-off output and `extra` lines.
async fn robot(extra: &str) -> (RwsSim, Controller, tempfile::TempDir) {
    let mut cfg = SimConfig::new(RwsVersion::Rw7, "Operator", "weld:on-42");
    cfg.run_time = Duration::from_secs(60);
    let sim = RwsSim::start(cfg).await.unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("op.cred"), "Operator:weld:on-42\n").unwrap();
    let c = controller(&sim, &dir, extra).await;
    (sim, c, dir)
}

async fn controller(sim: &RwsSim, dir: &tempfile::TempDir, extra: &str) -> Controller {
    let path = dir.path().join("irb1600.yaml");
    std::fs::write(
        &path,
        format!(
            "id: irb1600\nprotocol: rws\nrws: rw7\nport: {}\ncredentials: {{file: op.cred}}\nheat_off_outputs:\n  - {{signal: {WELD}, value: \"0\"}}\n{extra}",
            sim.addr().port()
        ),
    )
    .unwrap();
    Controller::start(ControllerSpec::load(&path).unwrap())
        .await
        .unwrap()
}

/// Waits (generously) until `done` holds; panics naming `what`.
async fn until(what: &str, mut done: impl FnMut() -> bool) {
    let deadline = tokio::time::Instant::now() + Duration::from_secs(60);
    while !done() {
        assert!(
            tokio::time::Instant::now() < deadline,
            "timed out waiting for {what}"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

fn command(c: &Controller, command: u8) -> MachineCommand {
    MachineCommand {
        machine_id: c.id().into(),
        command,
        value: 0,
    }
}

/// Starts `program` on `c` and waits until RAPID runs with the weld output on.
async fn welding(sim: &RwsSim, c: &Controller, job: &str) -> tokio::task::JoinHandle<RunOutcome> {
    let (c2, p) = (c.clone(), program(job));
    let mut run = tokio::spawn(async move { c2.execute(&p, 0).await });
    until("RAPID welding", || {
        sim.rapid_running() && sim.signal(WELD).as_deref() == Some("1") || run.is_finished()
    })
    .await;
    if run.is_finished() {
        let out = (&mut run).await.unwrap();
        panic!("the run ended before RAPID welded: {}", out.message);
    }
    run
}

async fn outcome(run: tokio::task::JoinHandle<RunOutcome>) -> RunOutcome {
    tokio::time::timeout(Duration::from_secs(120), run)
        .await
        .expect("the run ends")
        .unwrap()
}

/// Hold stops RAPID and switches the weld output off (RAPID alone would leave it on); resume
/// starts RAPID again and the program switches the output on itself; abort ends the run safe.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hold_switches_the_weld_output_off_and_abort_ends_the_run_safe() {
    let (sim, c, _dir) = robot("").await;
    let run = welding(&sim, &c, "hold").await;

    let answer = c.command(&command(&c, MachineCommand::COMMAND_HOLD)).await;
    let answer = answer.expect("hold is confirmed");
    assert!(answer.contains("heat off confirmed"), "{answer}");
    assert!(!sim.rapid_running(), "RAPID stopped");
    assert_eq!(sim.signal(WELD).as_deref(), Some("0"), "weld output off");
    assert_eq!(c.status().state, MachineStatus::STATE_HOLD);

    let answer = c
        .command(&command(&c, MachineCommand::COMMAND_RESUME))
        .await
        .unwrap();
    assert!(answer.contains("program pointer"), "{answer}");
    until("RAPID welding again", || {
        sim.rapid_running() && sim.signal(WELD).as_deref() == Some("1")
    })
    .await;

    c.command(&command(&c, MachineCommand::COMMAND_ABORT))
        .await
        .unwrap();
    let out = outcome(run).await;
    assert_eq!(out.outcome, R::OUTCOME_ABORTED, "{}", out.message);
    assert!(
        out.message.contains("heat off confirmed"),
        "{}",
        out.message
    );
    assert!(!sim.rapid_running(), "RAPID stopped");
    assert_eq!(sim.signal(WELD).as_deref(), Some("0"), "weld output off");
    assert_eq!(sim.starts(), 2, "started, resumed, nothing more");
}

/// A node shutting down (SIGINT, SIGTERM) aborts and then drops its tasks, the run's included:
/// the abort's answer already has RAPID stopped and the heat confirmed off.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_abort_leaves_the_robot_safe_even_if_the_run_is_dropped_right_after() {
    let (sim, c, _dir) = robot("").await;
    let run = welding(&sim, &c, "shutdown").await;
    let answer = c
        .command(&command(&c, MachineCommand::COMMAND_ABORT))
        .await
        .expect("confirmed");
    run.abort(); // the runtime goes away with the process
    let _ = run.await;
    assert!(answer.contains("heat off confirmed"), "{answer}");
    assert!(!sim.rapid_running(), "RAPID stopped");
    assert_eq!(sim.signal(WELD).as_deref(), Some("0"), "weld output off");
}

/// An abort (a cancel sends the same) while the program is being uploaded ends the run before
/// RAPID is started, and still switches off a weld output found on.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_abort_during_the_upload_ends_the_run_before_rapid_starts() {
    let (sim, c, _dir) = robot("").await;
    assert!(sim.set_signal(WELD, "1"), "left on by someone else");
    sim.stall("PUT /fileservice");
    let (c2, p) = (c.clone(), program("early"));
    let run = tokio::spawn(async move { c2.execute(&p, 0).await });
    until("the upload under way", || sim.stalled() > 0).await;
    assert_eq!(
        c.status().state,
        MachineStatus::STATE_RUNNING,
        "a job of ours"
    );
    assert!(
        c.command(&command(&c, MachineCommand::COMMAND_HOLD))
            .await
            .is_err(),
        "nothing to hold yet"
    );

    let answer = c
        .command(&command(&c, MachineCommand::COMMAND_ABORT))
        .await
        .unwrap();
    assert!(answer.contains("abort"), "{answer}");
    let out = outcome(run).await;
    sim.answer_all();
    assert_eq!(out.outcome, R::OUTCOME_ABORTED, "{}", out.message);
    assert!(
        out.message.contains("before RAPID was started")
            && out.message.contains("heat off confirmed"),
        "{}",
        out.message
    );
    assert_eq!(sim.starts(), 0, "RAPID was never started");
    assert!(!sim.requests().iter().any(|r| r.contains("/start")));
    assert!(!sim.rapid_running());
    assert!(!sim.mastership_held(), "mastership given back");
    assert_eq!(sim.signal(WELD).as_deref(), Some("0"), "weld output off");
}

/// An abort mid-run takes effect while the execution-state poll hangs (its timeout here is a
/// minute): RAPID is stopped at once, and the heat is confirmed off once the controller's state
/// can be read back.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_abort_mid_run_does_not_wait_for_a_hung_poll() {
    let (sim, c, _dir) =
        robot("timeouts: {control_s: 60}\nreconnect: {attempts: 100, delay_s: 0.1}\n").await;
    let run = welding(&sim, &c, "mid").await;
    sim.stall("GET /rw/rapid/execution");
    until("a poll hanging", || sim.stalled() > 0).await;

    let (c2, abort) = (c.clone(), command(&c, MachineCommand::COMMAND_ABORT));
    let answer = tokio::spawn(async move { c2.command(&abort).await });
    until("RAPID stopped and the weld output off", || {
        !sim.rapid_running() && sim.signal(WELD).as_deref() == Some("0")
    })
    .await;
    // The read-back of RAPID's state hangs too: lifting the stall lets it be confirmed.
    sim.answer_all();
    let answer = answer.await.unwrap();
    let text = answer.as_ref().unwrap_or_else(|e| e);
    assert!(text.starts_with("irb1600: abort: "), "{text}");
    let out = outcome(run).await;
    assert_eq!(out.outcome, R::OUTCOME_ABORTED, "{}", out.message);
    assert!(
        out.message.contains("heat off confirmed"),
        "{}",
        out.message
    );
    assert!(!sim.rapid_running());
    assert_eq!(sim.signal(WELD).as_deref(), Some("0"));
}

/// The link drops mid-run and comes back while the bridge retries: RAPID is stopped and the
/// weld output switched off as soon as the controller answers, and the result says so.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lost_link_ends_with_the_heat_confirmed_off_once_the_robot_answers() {
    let (sim, c, _dir) =
        robot("timeouts: {control_s: 0.3}\nreconnect: {attempts: 1000, delay_s: 0.1}\n").await;
    let run = welding(&sim, &c, "lost").await;
    sim.stall("");
    until("the bridge reporting the lost link", || {
        let s = c.status();
        s.state == MachineStatus::STATE_DISCONNECTED && s.alarm.contains("link lost")
    })
    .await;
    assert!(sim.rapid_running(), "nothing reached the robot");
    sim.answer_all();
    let out = outcome(run).await;
    assert_eq!(out.outcome, R::OUTCOME_LINK_LOST, "{}", out.message);
    assert!(
        out.message.contains("heat off confirmed"),
        "{}",
        out.message
    );
    assert!(!sim.rapid_running(), "RAPID stopped");
    assert_eq!(sim.signal(WELD).as_deref(), Some("0"), "weld output off");
}

/// The link stays down longer than the retries: the result says the heat state is unknown and
/// why; when the robot answers again the bridge stops it and switches the heat off by itself.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_link_lost_for_good_says_the_heat_is_unknown_and_is_made_safe_when_it_returns() {
    let (sim, c, _dir) =
        robot("timeouts: {control_s: 0.3}\nreconnect: {attempts: 2, delay_s: 0.1}\n").await;
    let run = welding(&sim, &c, "gone").await;
    sim.stall("");
    let out = outcome(run).await;
    assert_eq!(out.outcome, R::OUTCOME_LINK_LOST, "{}", out.message);
    assert!(
        out.message.contains("heat state unknown after 2 attempts")
            && out.message.contains("no answer within")
            && out.message.contains("check the robot"),
        "{}",
        out.message
    );
    assert!(sim.rapid_running(), "the robot went on: nothing reached it");
    assert_eq!(sim.signal(WELD).as_deref(), Some("1"));

    sim.answer_all();
    until("RAPID stopped and the weld output off", || {
        !sim.rapid_running() && sim.signal(WELD).as_deref() == Some("0")
    })
    .await;
    until("the robot shown again", || {
        c.status().state != MachineStatus::STATE_DISCONNECTED
    })
    .await;
}

/// A bridge killed mid-run leaves RAPID welding; the bridge started next finds the weld output
/// on with no run of its own and stops RAPID and switches the heat off before anything else.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_restarted_bridge_finding_the_heat_on_makes_the_robot_safe_first() {
    let (sim, killed, dir) = robot("").await;
    let run = welding(&sim, &killed, "killed").await;
    run.abort(); // the process dies: no safe stop
    let _ = run.await;
    drop(killed);
    assert!(sim.rapid_running() && sim.signal(WELD).as_deref() == Some("1"));

    let restarted: Arc<Controller> = Arc::new(controller(&sim, &dir, "").await);
    until("RAPID stopped and the weld output off", || {
        !sim.rapid_running() && sim.signal(WELD).as_deref() == Some("0")
    })
    .await;
    until("the robot idle", || {
        restarted.status().state == MachineStatus::STATE_IDLE
    })
    .await;
}
