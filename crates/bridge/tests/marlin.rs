//! The Marlin controller against the Marlin simulator over real loopback TCP: a program
//! streamed to its end, and the heat off, confirmed by the printer's own `M105`, after every
//! kind of stop: finish, abort in the middle of `M109`, link loss, a kill, shutdown, and a
//! printer found heating when the bridge connects.

use std::time::Duration;

use cell_bridge::config::ControllerSpec;
use cell_bridge::controller::{Controller, RunOutcome};
use cell_bridge::marlin::MarlinController;
use cell_marlin::sim::{self, OnConnect, SimConfig, SimEvent, SimHandle, SimSnapshot};
use cell_msgs::{ExecuteProgramResult as R, MachineCommand, MachineProgram, ProgramFile};

const PROGRAM: &str = "\
; a small Marlin job
M117 test
M140 S60
M104 S210
G28
M190 S60
M109 S210
G1 Z0.2 F600
G1 X20 Y20 E1.0 F1800
G1 X60 Y20 E2.5
G1 X60 Y60 E4.0
G1 X20 Y60 E5.5
G1 X20 Y20 E7.0
M104 S0
M140 S0
G28 X Y
M84
";

fn program() -> MachineProgram {
    MachineProgram {
        job_id: "marlin-test".into(),
        dialect: "marlin".into(),
        machine_profile: "marlin-extruder".into(),
        files: vec![ProgramFile {
            name: "marlin-test.gcode".into(),
            text: PROGRAM.into(),
        }],
        line_count: PROGRAM.lines().count() as u32,
        ..Default::default()
    }
}

fn program_lines() -> Vec<String> {
    PROGRAM
        .lines()
        .map(|l| l.split(';').next().unwrap().trim().to_owned())
        .filter(|l| !l.is_empty())
        .collect()
}

async fn sim_controller(time_scale: f64) -> (Controller, std::sync::Arc<MarlinController>) {
    let yaml = format!(
        "id: marlin-test\nprotocol: marlin\nmachine_profile: marlin-extruder\n\
         endpoint: {{simulator: {{time_scale: {time_scale}}}}}\n\
         status_period_s: 0.2\ncommand_timeout_s: 3\nreconnect: {{attempts: 5, delay_s: 0.1}}\n"
    );
    let spec = ControllerSpec::from_yaml_str(&yaml, "marlin-test.yaml", None).unwrap();
    let c = Controller::start(spec).await.unwrap();
    let Controller::Marlin(m) = &c else { panic!() };
    let m = m.clone();
    assert!(m.wait_connected(Duration::from_secs(5)).await);
    (c, m)
}

/// Starts [`program`] on `c` in the background and waits up to `within` for the printer to
/// reach `state`; returns the run to await.
async fn run_until(
    c: &Controller,
    sim: &SimHandle,
    within: Duration,
    state: impl Fn(&SimSnapshot) -> bool,
) -> tokio::task::JoinHandle<RunOutcome> {
    let run = {
        let c = c.clone();
        tokio::spawn(async move { c.execute(&program(), 0).await })
    };
    let (s, ok) = sim.wait_for(within, state).await;
    assert!(ok, "the printer never got there: {s:?}");
    run
}

fn assert_heat_off(m: &MarlinController) {
    let s = m.simulator().unwrap().snapshot();
    assert_eq!((s.hotend.target, s.bed.target), (0.0, 0.0), "{s:?}");
    let t = m.last_heat_off().expect("an M105 confirmed the heat off");
    assert!(t.targets_off(), "{t}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_program_runs_to_its_end_and_the_heat_off_is_read_back() {
    let (c, m) = sim_controller(50.0).await;
    let run = c.execute(&program(), 0).await;
    assert!(run.success, "{}", run.message);
    assert_eq!(run.outcome, R::OUTCOME_FINISHED);
    assert!(run.message.contains("confirmed by M105"), "{}", run.message);
    // The bridge saw the heat-up the program asked for (M190 S60, M109 S210 waited).
    let peak: f64 = run
        .message
        .split("heated to T:")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{}", run.message));
    assert!(peak >= 209.0, "{}", run.message);
    let sim = m.simulator().unwrap();
    // Every program line ran, in order, between the bridge's own polls and stop lines.
    let executed: Vec<String> = sim
        .executed()
        .into_iter()
        .filter(|c| !matches!(c.as_str(), "M105" | "M114" | "M110 N0" | "M400" | "M107"))
        .filter(|c| !(c == "M104 S0" || c == "M140 S0") || PROGRAM.contains(c.as_str()))
        .collect();
    let expected = program_lines();
    assert_eq!(&executed[..expected.len()], &expected[..]);
    let s = sim.snapshot();
    assert_eq!(s.planned_blocks, 0);
    assert!(s.moves_done >= 6, "{s:?}");
    // It heated for real: the bed and the hotend waits took simulated time.
    assert!(s.now_s > 60.0, "{s:?}");
    assert_heat_off(&m);
    assert_eq!(c.status().state, cell_msgs::MachineStatus::STATE_DONE);
    assert_eq!(c.percent_done(), 100.0);
    // The heaters the node logs to Rerun: the printer's last report, both targets off, the
    // hotend still warm and matching the simulator's own state.
    let heaters = c.heaters();
    let names: Vec<_> = heaters.iter().map(|h| h.name).collect();
    assert_eq!(names, ["hotend", "bed"]);
    assert!(heaters.iter().all(|h| h.target_c == 0.0), "{heaters:?}");
    let hotend = heaters[0].current_c;
    assert!(
        hotend > 100.0 && (hotend - s.hotend.current).abs() < 15.0,
        "{heaters:?} vs {s:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn abort_in_the_middle_of_m109_switches_the_heat_off() {
    // The hotend heats from cold in the M109: about 45 simulated s, 2 real s at 20×.
    let (c, m) = sim_controller(20.0).await;
    let mut heat_then_move = program();
    heat_then_move.files[0].text = "M140 S60\nM109 S210\nG1 X10 F600\nM104 S0\n".into();
    let run = {
        let c = c.clone();
        tokio::spawn(async move { c.execute(&heat_then_move, 0).await })
    };
    let sim = m.simulator().unwrap().clone();
    let deadline = tokio::time::Instant::now() + Duration::from_secs(10);
    while !sim.executed().iter().any(|c| c == "M109 S210") {
        assert!(tokio::time::Instant::now() < deadline, "no M109");
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let s = sim.snapshot();
    assert!(
        s.hotend.target == 210.0 && s.busy && s.hotend.current < 200.0,
        "mid-wait: {s:?}"
    );
    let abort = MachineCommand {
        machine_id: "marlin-test".into(),
        command: MachineCommand::COMMAND_ABORT,
        value: 0,
    };
    c.command(&abort).await.unwrap();
    let run = run.await.unwrap();
    assert_eq!(run.outcome, R::OUTCOME_ABORTED, "{}", run.message);
    assert!(
        run.message.contains("heaters off, confirmed by M105"),
        "{}",
        run.message
    );
    assert_heat_off(&m);
    let after = sim.snapshot();
    assert!(
        after.halted.is_none(),
        "M108 ended the wait; no kill was needed"
    );
    assert!(
        !sim.executed().iter().any(|c| c.starts_with("G1")),
        "nothing after the M109 ran"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn link_loss_ends_with_the_heat_off_after_reconnecting() {
    let (c, m) = sim_controller(50.0).await;
    // A link drop while the first moves go out (the poll lines count too: drop late enough).
    let sim = m.simulator().unwrap().clone();
    let run = run_until(&c, &sim, Duration::from_secs(20), |s| s.moves_done >= 2).await;
    sim.drop_link();
    let run = run.await.unwrap();
    assert_eq!(run.outcome, R::OUTCOME_LINK_LOST, "{}", run.message);
    assert!(
        run.message
            .contains("reconnected; heaters off, confirmed by M105"),
        "{}",
        run.message
    );
    assert_heat_off(&m);
    assert!(
        sim.events()
            .iter()
            .filter(|e| **e == SimEvent::Reset)
            .count()
            >= 2
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_kill_mid_program_is_an_alarm_and_the_reset_confirms_the_heat_off() {
    let (c, m) = sim_controller(50.0).await;
    let sim = m.simulator().unwrap().clone();
    let run = run_until(&c, &sim, Duration::from_secs(20), |s| s.moves_done >= 1).await;
    // Someone presses the printer's kill button (KILL_PIN): kill(), heaters off, halted.
    sim.press_kill();
    let run = run.await.unwrap();
    assert_eq!(run.outcome, R::OUTCOME_ALARM, "{}", run.message);
    assert!(run.message.contains("printer halted"), "{}", run.message);
    assert!(
        run.message
            .contains("reconnected; heaters off, confirmed by M105"),
        "{}",
        run.message
    );
    assert_heat_off(&m);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn shutdown_while_running_leaves_the_heat_off() {
    let (c, m) = sim_controller(50.0).await;
    let sim = m.simulator().unwrap().clone();
    let run = run_until(&c, &sim, Duration::from_secs(10), |s| s.bed.target == 60.0).await;
    let line = c.stop_for_shutdown(Duration::from_secs(5)).await;
    assert!(line.contains("confirmed by M105"), "{line}");
    let run = run.await.unwrap();
    assert_eq!(run.outcome, R::OUTCOME_ABORTED);
    assert_heat_off(&m);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_printer_found_heating_is_switched_off_on_connect() {
    // A printer on a network bridge (no reset on connect), left heating by a host that died.
    let sim = sim::start(SimConfig {
        time_scale: 50.0,
        on_connect: OnConnect::Silent,
        ..SimConfig::default()
    });
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    {
        use tokio::io::AsyncWriteExt;
        let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
        s.write_all(b"M104 S200\nM140 S60\n").await.unwrap();
        let (_, ok) = sim
            .wait_for(Duration::from_secs(5), |s| s.bed.target == 60.0)
            .await;
        assert!(ok);
    }
    let yaml = format!(
        "id: bench\nprotocol: marlin\nendpoint: {{tcp: '{addr}'}}\nstatus_period_s: 0.2\ncommand_timeout_s: 3\n"
    );
    let spec = ControllerSpec::from_yaml_str(&yaml, "bench.yaml", None).unwrap();
    let c = Controller::start(spec).await.unwrap();
    let Controller::Marlin(m) = &c else { panic!() };
    let (s, ok) = sim
        .wait_for(Duration::from_secs(5), |s| {
            s.hotend.target == 0.0 && s.bed.target == 0.0
        })
        .await;
    assert!(ok, "{s:?}");
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert!(m.last_heat_off().is_some_and(|t| t.targets_off()));
    assert!(
        m.last_fault().is_some_and(|f| f.contains("found heating")),
        "{:?}",
        m.last_fault()
    );
}

#[test]
fn the_shipped_marlin_sim_file_loads_and_refuses_other_dialects() {
    let spec = ControllerSpec::resolve("marlin-sim").unwrap();
    let ControllerSpec::Marlin(cfg) = spec else {
        panic!()
    };
    assert_eq!(cfg.machine_profile, "marlin-extruder");
    let e = ControllerSpec::from_yaml_str(
        "id: a\nprotocol: marlin\nmachine_profile: grbl-xy\nendpoint: {tcp: 'h:1'}\n",
        "a.yaml",
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("not a Marlin profile"), "{e}");
}
