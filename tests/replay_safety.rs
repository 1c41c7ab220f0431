//! Replay is safe by default (issue 23): a bag holding a machine program and a machine command,
//! played with `cell bag play` onto a domain where a real `machine_bridge` drives the GRBL
//! simulator, leaves both out and says so; naming the program topic without
//! `--allow-machine-topics` is refused, naming what was found; nothing is published on the
//! program topic, the simulator executes nothing and the bridge stays idle. With the flag the
//! program is published, so it is the replayer, not the bridge (whose arming is its own
//! business), that held it back.

mod common;

use std::path::Path;
use std::time::Duration;

use cell_bag::{BagWriter, QosProfile};
use cell_grbl::sim::{self, SimConfig, SimHandle};
use cell_msgs::std_msgs::StringMsg;
use cell_msgs::{MachineCommand, MachineProgram, MachineStatus, ProgramFile};
use cell_runtime::{CellNode, NodeSetup, QosPreset, Shutdown, Subscriber};
use common::{fresh_domain, within, DELIVERY_TIMEOUT};
use machine_bridge::BridgeParams;

const CELL: &str = env!("CARGO_BIN_EXE_cell");
const T0_NS: u64 = 1_763_800_000_000_000_000;

/// A node in `/cell` on `domain` (DDS on loopback, no fast path) and its shutdown signal.
fn cell_node(name: &str, domain: u16) -> (CellNode, Shutdown) {
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = cell_runtime::FastPathMode::Off;
    setup.args.ros.namespace = Some("/cell".into());
    let shutdown = setup.shutdown.clone();
    (CellNode::new(setup).expect("node comes up"), shutdown)
}

/// A short 4-axis program, heat off.
fn program() -> MachineProgram {
    let text = "G21 G90 G94\nG0 X1 Y1 U1 V1\nG1 X2 Y2 U2 V2 F600\n".to_owned();
    MachineProgram {
        job_id: "replayed".into(),
        dialect: "grbl".into(),
        machine_profile: "grbl-xyuv".into(),
        line_count: text.lines().count() as u32,
        files: vec![ProgramFile {
            name: "replayed.ngc".into(),
            text,
        }],
        ..MachineProgram::default()
    }
}

/// A bag as the recorder writes a cell run: the program (transient-local, as the emitter
/// publishes it), an abort command and one ordinary message.
fn machine_bag(dir: &Path) -> String {
    let path = dir.join("machine");
    let mut w = BagWriter::create(&path, Default::default()).unwrap();
    let plan = [QosProfile::reliable_transient_local(1)];
    let status = [QosProfile::reliable_volatile(10)];
    w.add_topic(
        "/cell/machine_program",
        "cell_msgs/msg/MachineProgram",
        &plan,
    )
    .unwrap();
    w.add_topic(
        "/cell/machine_command",
        "cell_msgs/msg/MachineCommand",
        &status,
    )
    .unwrap();
    w.add_topic("/cell/note", "std_msgs/msg/String", &status)
        .unwrap();
    w.write("/cell/machine_program", &program(), T0_NS).unwrap();
    let abort = MachineCommand {
        command: MachineCommand::COMMAND_ABORT,
        ..Default::default()
    };
    w.write("/cell/machine_command", &abort, T0_NS + 100_000_000)
        .unwrap();
    let note = StringMsg {
        data: "hello".into(),
    };
    w.write("/cell/note", &note, T0_NS + 200_000_000).unwrap();
    w.finish().unwrap();
    path.display().to_string()
}

/// A GRBL 1.1 simulator for the 4-axis cutter on loopback TCP and a controller file for it.
async fn grbl_sim(dir: &Path) -> (SimHandle, String) {
    let sim = sim::start(SimConfig {
        time_scale: 20.0,
        axes: vec!['X', 'Y', 'U', 'V'],
        ..SimConfig::default()
    });
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let path = dir.join("cutter.yaml");
    std::fs::write(
        &path,
        format!(
            "id: cutter\nprotocol: grbl\nmachine_profile: grbl-xyuv\naxes: XYUV\n\
             endpoint: {{tcp: '{addr}'}}\n"
        ),
    )
    .unwrap();
    (sim, path.display().to_string())
}

/// `cell bag play ARGS` on `domain` over loopback DDS: (exit code, stdout, stderr).
async fn play(domain: u16, args: &[&str]) -> (Option<i32>, String, String) {
    let run = tokio::process::Command::new(CELL)
        .args(["bag", "play"])
        .args(args)
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("CELL_DDS_NETWORK", "loopback")
        .env_remove("RUST_LOG")
        .output();
    let out = tokio::time::timeout(3 * DELIVERY_TIMEOUT, run)
        .await
        .expect("cell bag play ends")
        .expect("run cell");
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code(), text(&out.stdout), text(&out.stderr))
}

/// The statuses received over the next second (the bridge sends 10 a second); fails if the
/// bridge reports anything but idle. Returns how many there were.
async fn assert_idle(statuses: &mut Subscriber<MachineStatus>) -> usize {
    let mut n = 0;
    let window = tokio::time::sleep(Duration::from_secs(1));
    tokio::pin!(window);
    loop {
        tokio::select! {
            _ = &mut window => return n,
            s = statuses.recv() => {
                let s = s.expect("statuses").message;
                assert_eq!(s.state, MachineStatus::STATE_IDLE, "the bridge left idle: {s:?}");
                n += 1;
            }
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn machine_topics_are_left_out_and_refused_while_a_bridge_runs() {
    cell_runtime::logging::init(Some("info"));
    let dir = tempfile::tempdir().unwrap();
    let bag = machine_bag(dir.path());
    let domain = fresh_domain();
    let (sim, controller) = grbl_sim(dir.path()).await;
    let (bridge, bridge_stop) = cell_node("machine_bridge", domain);
    tokio::spawn(machine_bridge::run(
        bridge,
        BridgeParams {
            controllers: vec![controller],
            program_topic: "machine_program".into(),
            // Ready to run whatever arrives: only the replayer stands in the way.
            arm_at_start: true,
            ..BridgeParams::default()
        },
    ));
    let (watcher, _) = cell_node("watcher", domain);
    let mut statuses = watcher
        .subscriber::<MachineStatus>("machine_status", QosPreset::Status)
        .unwrap();
    let mut programs = watcher
        .subscriber::<MachineProgram>("machine_program", QosPreset::Plan)
        .unwrap();
    within(async {
        loop {
            let s = statuses.recv().await.expect("statuses").message;
            if s.state == MachineStatus::STATE_IDLE {
                break;
            }
        }
    })
    .await;

    // By default the program and the command are left out, and the replay says so.
    let (code, stdout, stderr) = play(domain, &[&bag, "--wait-for-subscribers", "0"]).await;
    assert_eq!(code, Some(0), "{stderr}");
    for topic in ["/cell/machine_program", "/cell/machine_command"] {
        assert!(
            stderr.contains("left out machine topics") && stderr.contains(topic),
            "{stderr}"
        );
        assert!(stdout.contains(&format!("{topic} (1 message)")), "{stdout}");
    }
    assert!(
        stdout.contains("replayed 1 messages on 1 topic"),
        "{stdout}"
    );

    // Named, but a bridge runs here: refused before anything is published.
    let (code, _, stderr) = play(
        domain,
        &[&bag, "--topics", "/cell/machine_program", "/cell/note"],
    )
    .await;
    assert_eq!(code, Some(64), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "refusing to play machine topics /cell/machine_program onto ROS domain {domain}"
        )),
        "{stderr}"
    );
    assert!(
        stderr.contains("cell_msgs/srv/SendMachineCommand_Request")
            && stderr.contains("--allow-machine-topics"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");

    // Neither replay published a program or drove the machine: nothing reached the
    // simulator, the bridge stayed idle.
    tokio::time::sleep(Duration::from_secs(2)).await;
    assert!(assert_idle(&mut statuses).await > 0, "statuses keep coming");
    assert_eq!(sim.executed_lines(), Vec::<String>::new());
    assert!(
        tokio::time::timeout(Duration::from_millis(500), programs.recv())
            .await
            .is_err(),
        "no program was published"
    );

    // With the flag the program is published (whether the bridge then runs it is its arming's
    // business): the refusal above is what held it back.
    let (code, _, stderr) = play(
        domain,
        &[
            &bag,
            "--topics",
            "/cell/machine_program",
            "--allow-machine-topics",
            "--wait-for-subscribers",
            "20",
        ],
    )
    .await;
    assert_eq!(code, Some(0), "{stderr}");
    let program = within(programs.recv()).await.expect("a program").message;
    assert_eq!(program.job_id, "replayed");
    bridge_stop.trigger();
}
