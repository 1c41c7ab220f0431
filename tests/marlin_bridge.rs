//! machine_bridge with a Marlin printer, over real DDS: the Marlin simulator on loopback TCP
//! (a printer behind a network bridge: no reset when a host connects, so what the bridge
//! leaves behind stays visible), goals from an operator node. The heat rule: a cancelled goal
//! ends with the heaters off, read back from the printer's own `M105`; a bridge that died with
//! the printer heating switches it off when it comes back. The heaters' readings reach DDS as
//! `sensor_msgs/Temperature` and in `/diagnostics`.

mod common;

use std::time::Duration;

use cell_marlin::sim::{self, OnConnect, SimConfig, SimHandle};
use cell_msgs::diagnostic_msgs::DiagnosticArray;
use cell_msgs::sensor_msgs::Temperature;
use cell_msgs::{ExecuteProgramResult, MachineProgram, MachineStatus, ProgramFile};
use cell_runtime::action::GoalStatusEnum;
use cell_runtime::QosPreset;
use common::machines::{execute, goal, operator, status_until};
use common::{cancel_when, fresh_domain, node, within, DELIVERY_TIMEOUT};
use machine_bridge::{run, BridgeParams};

/// A print's start: the bed heats up (M190), then the hotend from cold (M109: about 45
/// simulated s), then moves.
fn heat_and_print(job: &str) -> MachineProgram {
    let mut text = String::from("; test print\nM140 S60\nG28\nM190 S60\nM109 S210\n");
    for i in 0..40 {
        text.push_str(&format!(
            "G1 X{} Y{} E{:.2} F1800\n",
            20 + i % 5 * 10,
            20 + i % 3 * 10,
            0.5 * f64::from(i)
        ));
    }
    text.push_str("M104 S0\nM140 S0\nM84\n");
    MachineProgram {
        job_id: job.into(),
        dialect: "marlin".into(),
        machine_profile: "marlin-extruder".into(),
        line_count: text.lines().count() as u32,
        files: vec![ProgramFile {
            name: format!("{job}.gcode"),
            text,
        }],
        ..Default::default()
    }
}

/// A Marlin simulator on loopback and a controller file for it.
async fn printer(dir: &std::path::Path, time_scale: f64) -> (SimHandle, String) {
    let sim = sim::start(SimConfig {
        time_scale,
        on_connect: OnConnect::Silent,
        ..SimConfig::default()
    });
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let file = dir.join("printer.yaml");
    std::fs::write(
        &file,
        format!(
            "id: printer\nprotocol: marlin\nmachine_profile: marlin-extruder\n\
             endpoint: {{tcp: '{addr}'}}\nstatus_period_s: 0.2\ncommand_timeout_s: 5\n"
        ),
    )
    .unwrap();
    (sim, file.display().to_string())
}

fn start_bridge(domain: u16, file: &str) -> tokio::task::JoinHandle<anyhow::Result<()>> {
    tokio::spawn(run(
        node("machine_bridge", domain, false),
        BridgeParams {
            controllers: vec![file.to_owned()],
            arm_at_start: true,
            ..BridgeParams::default()
        },
    ))
}

/// Waits until the printer runs its `M109` with the hotend still below the target.
async fn heating(sim: &SimHandle) {
    within(async {
        loop {
            let s = sim.snapshot();
            if sim.executed().iter().any(|c| c == "M109 S210")
                && s.hotend.target == 210.0
                && s.hotend.current < 200.0
            {
                return;
            }
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_cancel_in_the_middle_of_m109_ends_canceled_with_the_heaters_read_back_off() {
    let dir = tempfile::tempdir().unwrap();
    // 5 simulated s per real s: the M109 lasts several real seconds.
    let (sim, file) = printer(dir.path(), 5.0).await;
    let domain = fresh_domain();
    let bridge = start_bridge(domain, &file);
    let mut op = operator(domain).await;
    status_until(&mut op.status, "printer", |s| {
        s.state == MachineStatus::STATE_IDLE
    })
    .await;
    let client = &op.client;
    let (status, result) = cancel_when(
        client,
        goal(&heat_and_print("c"), ""),
        DELIVERY_TIMEOUT * 4,
        |_| heating(&sim),
    )
    .await;
    assert_eq!(status, GoalStatusEnum::Canceled, "{}", result.message);
    assert!(
        result.message.contains("heaters off, confirmed by M105"),
        "{}",
        result.message
    );
    let s = sim.snapshot();
    assert_eq!((s.hotend.target, s.bed.target), (0.0, 0.0), "{s:?}");
    assert!(s.hotend.current < 209.0, "the wait was cut short: {s:?}");
    assert!(
        !sim.executed().iter().any(|c| c.starts_with("G1 X")),
        "no move after the cancel"
    );
    assert!(!bridge.is_finished());
    bridge.abort();
}

/// `cell node machine_bridge` as its own process, so it can be killed or stopped by a signal.
struct BridgeProcess(std::process::Child);

impl BridgeProcess {
    fn start(dir: &std::path::Path, domain: u16, controller_file: &str, n: u32) -> Self {
        let params = dir.join(format!("bridge-{n}.yaml"));
        std::fs::write(
            &params,
            format!(
                "/**:\n  ros__parameters:\n    controllers: ['{controller_file}']\n    arm_at_start: true\n"
            ),
        )
        .unwrap();
        let child = std::process::Command::new(env!("CARGO_BIN_EXE_cell"))
            .args(["node", "machine_bridge", "--ros-args", "--params-file"])
            .arg(&params)
            .env("CELL_DDS_NETWORK", "loopback")
            .env("ROS_DOMAIN_ID", domain.to_string())
            .stdout(std::process::Stdio::null())
            .spawn()
            .expect("start the bridge");
        BridgeProcess(child)
    }

    fn signal(&self, name: &str) {
        let ok = std::process::Command::new("kill")
            .args(["-s", name, &self.0.id().to_string()])
            .status()
            .unwrap()
            .success();
        assert!(ok, "kill -s {name}");
    }

    async fn exited(&mut self) {
        within(async {
            while self.0.try_wait().unwrap().is_none() {
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
        })
        .await;
    }
}

impl Drop for BridgeProcess {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bridge_that_died_with_the_printer_heating_switches_it_off_when_it_comes_back() {
    let dir = tempfile::tempdir().unwrap();
    let (sim, file) = printer(dir.path(), 5.0).await;
    let domain = fresh_domain();
    let mut bridge = BridgeProcess::start(dir.path(), domain, &file, 1);
    let op = operator(domain).await;
    let (_, response) = within(
        op.client
            .async_send_goal(goal(&heat_and_print("crash"), "")),
    )
    .await
    .expect("sent");
    assert!(response.accepted);
    heating(&sim).await;
    // The bridge dies (SIGKILL: no stop of any kind runs); the printer goes on heating.
    bridge.signal("KILL");
    bridge.exited().await;
    drop(op);
    let s = sim.snapshot();
    assert_eq!(s.hotend.target, 210.0, "left heating: {s:?}");
    // A new bridge connects, finds it heating with no program of its own, and switches it off.
    let _again = BridgeProcess::start(dir.path(), domain, &file, 2);
    let (s, off) = sim
        .wait_for(DELIVERY_TIMEOUT, |s| {
            s.hotend.target == 0.0 && s.bed.target == 0.0
        })
        .await;
    assert!(off, "{s:?}");
    let mut op = operator(domain).await;
    let status = status_until(&mut op.status, "printer", |s| {
        s.alarm.contains("found heating")
    })
    .await;
    assert!(
        status.alarm.contains("heaters off, confirmed by M105"),
        "{}",
        status.alarm
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bridge_stopped_by_sigterm_mid_print_leaves_the_heaters_off() {
    let dir = tempfile::tempdir().unwrap();
    let (sim, file) = printer(dir.path(), 5.0).await;
    let domain = fresh_domain();
    let mut bridge = BridgeProcess::start(dir.path(), domain, &file, 1);
    let op = operator(domain).await;
    let (_, response) = within(op.client.async_send_goal(goal(&heat_and_print("term"), "")))
        .await
        .expect("sent");
    assert!(response.accepted);
    heating(&sim).await;
    bridge.signal("TERM");
    bridge.exited().await;
    let s = sim.snapshot();
    assert_eq!((s.hotend.target, s.bed.target), (0.0, 0.0), "{s:?}");
    assert!(
        s.halted.is_none(),
        "M108 and M104/M140 S0, no kill needed: {s:?}"
    );
    assert!(
        !sim.executed().iter().any(|c| c.starts_with("G1 X")),
        "stopped in the M109"
    );
}

/// The bridge's diagnostic value `key` for the machine `printer`, if `array` has it.
fn printer_value(array: &DiagnosticArray, key: &str) -> Option<f64> {
    let status = array
        .status
        .iter()
        .find(|s| s.name == "machine_bridge: printer")?;
    let kv = status.values.iter().find(|kv| kv.key == key)?;
    Some(kv.value.parse().expect("a number"))
}

/// The printer's heaters on DDS, for stock tools (`MachineStatus` has no temperatures): each
/// heater's measured temperature as `sensor_msgs/Temperature` on
/// `<machine>/temperature/<heater>`, and current and target among the `/diagnostics` values.
/// While the print's `M109` waits, the hotend's readings climb from ambient towards 210 °C;
/// after the program's `M104 S0`/`M140 S0` the targets read 0 and the hotend cools.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn heater_temperatures_reach_dds_as_sensor_msgs_temperature_and_diagnostics() {
    let dir = tempfile::tempdir().unwrap();
    // 10 simulated s per real s: the bed's and hotend's waits take a few real seconds.
    let (sim, file) = printer(dir.path(), 10.0).await;
    let domain = fresh_domain();
    let bridge = start_bridge(domain, &file);
    let mut op = operator(domain).await;
    let subscribe = |topic: &str| {
        op.node
            .subscriber::<Temperature>(topic, QosPreset::Status)
            .unwrap()
    };
    let (mut hotend, mut bed) = (
        subscribe("/printer/temperature/hotend"),
        subscribe("/printer/temperature/bed"),
    );
    let mut diagnostics = op
        .node
        .subscriber::<DiagnosticArray>("/diagnostics", QosPreset::Status)
        .unwrap();
    status_until(&mut op.status, "printer", |s| {
        s.state == MachineStatus::STATE_IDLE
    })
    .await;
    // Cold before the print: the first reading heard is the printer's ambient.
    let cold = within(hotend.recv())
        .await
        .expect("a hotend reading")
        .message;
    assert_eq!(cold.header.frame_id, "printer/hotend");
    assert_eq!(cold.variance, 0.0, "unknown");
    assert!(cold.header.stamp.sec > 0, "stamped: {:?}", cold.header);
    let ambient = sim.snapshot().hotend.current;
    assert!(
        (cold.temperature - ambient).abs() < 1.0,
        "{cold:?} vs {ambient}"
    );

    let run = execute(
        &op.client,
        goal(&heat_and_print("temps"), ""),
        DELIVERY_TIMEOUT * 4,
    );
    tokio::pin!(run);
    let (mut hotend_c, mut bed_c, mut diagnosed) = (Vec::new(), Vec::new(), Vec::new());
    let (result, _) = loop {
        tokio::select! {
            r = &mut run => break r,
            t = hotend.recv() => {
                let t = t.expect("hotend stream").message;
                assert_eq!(t.header.frame_id, "printer/hotend");
                hotend_c.push(t.temperature);
            }
            t = bed.recv() => bed_c.push(t.expect("bed stream").message.temperature),
            d = diagnostics.recv() => {
                let d = d.expect("diagnostics stream").message;
                let value = |key| printer_value(&d, key);
                if let (Some(current), Some(target)) =
                    (value("heater/hotend/current_c"), value("heater/hotend/target_c"))
                {
                    diagnosed.push((current, target));
                }
            }
        }
    };
    assert_eq!(
        result.outcome,
        ExecuteProgramResult::OUTCOME_FINISHED,
        "{}",
        result.message
    );
    // M109 S210 waits until within TEMP_WINDOW (1 K) of the target: the readings climbed to
    // it through values in between (a rise, not a jump) without passing it.
    let peak = hotend_c.iter().copied().fold(f64::MIN, f64::max);
    assert!(
        (208.0..=211.0).contains(&peak),
        "hotend peak {peak}: {hotend_c:?}"
    );
    let first_hot = hotend_c.iter().position(|c| *c >= 200.0).expect("hot");
    let climb = &hotend_c[..first_hot];
    let between = climb
        .iter()
        .filter(|c| (ambient + 10.0..200.0).contains(*c));
    assert!(between.count() >= 5, "on the way up: {climb:?}");
    assert!(
        climb.windows(2).all(|w| w[1] >= w[0] - 0.5),
        "the hotend climbs: {climb:?}"
    );
    let bed_peak = bed_c.iter().copied().fold(f64::MIN, f64::max);
    assert!(bed_peak >= 58.0, "M190 S60: bed peak {bed_peak}: {bed_c:?}");
    assert!(
        diagnosed
            .iter()
            .any(|&(c, t)| t == 210.0 && c > ambient + 10.0 && c <= peak + 0.5),
        "/diagnostics showed the hotend heating to 210: {diagnosed:?}"
    );

    // After the stop: the targets read 0 in /diagnostics, as the printer reports them, and the
    // hotend's topic shows it cooling.
    let s = sim.snapshot();
    assert_eq!((s.hotend.target, s.bed.target), (0.0, 0.0), "{s:?}");
    let off = within(async {
        loop {
            let d = diagnostics.recv().await.expect("diagnostics").message;
            if printer_value(&d, "heater/hotend/target_c") == Some(0.0)
                && printer_value(&d, "heater/bed/target_c") == Some(0.0)
            {
                return d;
            }
        }
    })
    .await;
    let current = printer_value(&off, "heater/hotend/current_c").expect("current");
    assert!(current > ambient + 10.0 && current <= peak, "{current}");
    let cooled = within(async {
        loop {
            let t = hotend.recv().await.expect("hotend").message.temperature;
            if t < peak - 5.0 {
                return t;
            }
        }
    })
    .await;
    assert!(cooled > ambient, "{cooled}");
    bridge.abort();
}
