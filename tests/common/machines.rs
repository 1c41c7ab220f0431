//! Machines for the cross-process tests: emitted programs, a GRBL simulator on loopback TCP
//! with its controller file, and an operator node that sends `execute_program` goals and reads
//! `machine_status`.
#![allow(dead_code)] // each test binary uses a different subset

use std::path::Path;
use std::time::Duration;

use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::sim::{self, Faults, SimConfig, SimHandle};
use cell_msgs::geometry_msgs::Point;
use cell_msgs::{
    ExecuteProgramFeedback, ExecuteProgramGoal, ExecuteProgramResult as R, MachineProgram,
    MachineStatus, Toolpath, ToolpathSegment,
};
use cell_profiles::MachineProfile;
use cell_runtime::action::ActionClient;
use cell_runtime::{CellNode, QosPreset, Subscriber};
use futures::StreamExt;

use super::{discover_action_server, node, within};

/// The bridge's action client.
pub type Client = ActionClient<ExecuteProgramGoal, R, ExecuteProgramFeedback>;

/// A 4-axis hot-wire wing panel with `n` cut points: lead-in, an airfoil-like loop (root on
/// X/Y, a smaller tip on U/V), lead-out.
pub fn wing_panel(job_id: &str, n: usize) -> Toolpath {
    let p = |x: f64, y: f64| Point { x, y, z: 0.0 };
    let lead = |from: (f64, f64), to: (f64, f64)| ToolpathSegment {
        kind: ToolpathSegment::KIND_LEAD,
        points: vec![p(from.0, from.1), p(to.0, to.1)],
        secondary_points: vec![p(from.0, from.1), p(to.0, to.1)],
        feed_mm_s: vec![6.0, 6.0],
        power: vec![1.5, 1.5],
        ..ToolpathSegment::default()
    };
    let (mut root, mut tip) = (Vec::new(), Vec::new());
    for i in 0..=n {
        let t = std::f64::consts::TAU * i as f64 / n as f64;
        let (c, s) = (t.cos(), t.sin());
        root.push(p(90.0 + 60.0 * c, 60.0 + 8.0 * s * (1.0 + 0.3 * c)));
        tip.push(p(95.0 + 45.0 * c, 60.0 + 6.0 * s * (1.0 + 0.3 * c)));
    }
    let cut = ToolpathSegment {
        kind: ToolpathSegment::KIND_CUT,
        feed_mm_s: vec![4.0; root.len()],
        power: vec![1.5; root.len()],
        points: root,
        secondary_points: tip,
        ..ToolpathSegment::default()
    };
    Toolpath {
        job_id: job_id.into(),
        process: Toolpath::PROCESS_HOTWIRE,
        power_unit: Toolpath::POWER_WIRE_CURRENT_A,
        plane_separation_mm: 1000.0,
        segments: vec![
            lead((160.0, 60.0), (150.0, 60.0)),
            cut,
            lead((150.0, 60.0), (160.0, 60.0)),
        ],
        ..Toolpath::default()
    }
}

/// The emitter's GRBL program for the panel.
pub fn grbl_program(job_id: &str, n: usize) -> MachineProgram {
    let profile = MachineProfile::resolve("grbl-xyuv").unwrap();
    cell_emitter::emit_program(&wing_panel(job_id, n), &profile, job_id).expect("emits")
}

/// The emitter's program for a sample toolpath under `tests/data/toolpaths/`.
pub fn emitted(sample: &str, profile: &str, job_id: &str) -> MachineProgram {
    let path = format!(
        "{}/tests/data/toolpaths/{sample}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let toolpath: Toolpath =
        cell_msgs::json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let profile = MachineProfile::resolve(profile).unwrap();
    cell_emitter::emit_program(&toolpath, &profile, job_id).expect("emits")
}

/// What the controller is sent: the program's G-code lines, comments and blanks dropped.
pub fn sent_lines(program: &MachineProgram) -> Program {
    Program::parse(&program.files[0].text, CleanOptions::default()).unwrap()
}

pub fn texts(p: &Program) -> Vec<String> {
    p.lines().iter().map(|l| l.text.clone()).collect()
}

/// A GRBL simulator on loopback TCP and a controller file for it.
pub async fn grbl_sim(
    dir: &Path,
    id: &str,
    faults: Faults,
    time_scale: f64,
    extra: &str,
) -> (SimHandle, String) {
    let cfg = SimConfig {
        time_scale,
        faults,
        ..SimConfig::default()
    };
    grbl_sim_with(dir, id, cfg, extra).await
}

/// [`grbl_sim`] with the simulator's settings given whole (axes become `XYUV`).
pub async fn grbl_sim_with(
    dir: &Path,
    id: &str,
    cfg: SimConfig,
    extra: &str,
) -> (SimHandle, String) {
    let sim = sim::start(SimConfig {
        axes: vec!['X', 'Y', 'U', 'V'],
        ..cfg
    });
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let path = dir.join(format!("{id}.yaml"));
    std::fs::write(
        &path,
        format!(
            "id: {id}\nprotocol: grbl\nmachine_profile: grbl-xyuv\naxes: XYUV\n\
             endpoint: {{tcp: '{addr}'}}\nreconnect: {{attempts: 20, delay_s: 0.05}}\n{extra}"
        ),
    )
    .unwrap();
    (sim, path.display().to_string())
}

/// A node that sends goals to the bridge and reads its status.
pub struct Operator {
    /// The node.
    pub node: CellNode,
    /// `execute_program` client.
    pub client: Client,
    /// `machine_status`.
    pub status: Subscriber<MachineStatus>,
}

pub async fn operator(domain: u16) -> Operator {
    let node = node("operator", domain, false);
    let client = node
        .action_client::<ExecuteProgramGoal, R, ExecuteProgramFeedback>("/execute_program")
        .unwrap();
    let status = node
        .subscriber::<MachineStatus>("/machine_status", QosPreset::Status)
        .unwrap();
    discover_action_server(&node, "/execute_program").await;
    Operator {
        node,
        client,
        status,
    }
}

/// Sends a goal and waits for its result, collecting feedback on the way.
pub async fn execute(
    client: &Client,
    goal: ExecuteProgramGoal,
    patience: Duration,
) -> (R, Vec<ExecuteProgramFeedback>) {
    let (goal_id, response) = within(client.async_send_goal(goal)).await.expect("sent");
    assert!(response.accepted, "the bridge accepts a goal it can run");
    let feedback = client.feedback_stream(goal_id);
    let mut feedback = std::pin::pin!(feedback);
    let result =
        // One request, held open for the whole run: the bridge answers it when the program
        // ends (see `request_result`).
        cell_runtime::action::request_result(client, goal_id, patience, patience);
    let mut result = std::pin::pin!(result);
    let mut seen = Vec::new();
    let mut open = true;
    let (_, result) = loop {
        tokio::select! {
            r = &mut result => break r.expect("result"),
            f = feedback.next(), if open => match f {
                Some(Ok(f)) => seen.push(f),
                Some(Err(_)) => {}
                None => open = false,
            },
        }
    };
    (result, seen)
}

/// Waits for a `MachineStatus` of `machine` stamped from now on that satisfies `pred` (older
/// ones still queued in the subscription are skipped).
pub async fn status_until(
    sub: &mut Subscriber<MachineStatus>,
    machine: &str,
    pred: impl Fn(&MachineStatus) -> bool,
) -> MachineStatus {
    let secs = |t: &cell_msgs::builtin_interfaces::Time| t.sec as f64 + t.nanosec as f64 * 1e-9;
    let from = secs(&cell_msgs::builtin_interfaces::Time::now());
    within(async {
        loop {
            let s = sub.recv().await.expect("status stream").message;
            if s.machine_id == machine && secs(&s.header.stamp) >= from && pred(&s) {
                return s;
            }
        }
    })
    .await
}

/// Whether the bridge accepts `goal`: one it cannot run (an unknown controller, a program that
/// controller cannot take) is rejected before it is accepted, its reason logged.
pub async fn accepted(client: &Client, goal: ExecuteProgramGoal) -> bool {
    let (_, response) = within(client.async_send_goal(goal)).await.expect("sent");
    response.accepted
}

pub fn goal(program: &MachineProgram, machine_id: &str) -> ExecuteProgramGoal {
    ExecuteProgramGoal {
        program: program.clone(),
        machine_id: machine_id.into(),
        start_line: 0,
    }
}
