//! Every action node serves its goals through the one goal server (`cell_runtime::goal_server`),
//! so every action behaves the same way. For the planner, the sequencer, the slicer and the
//! machine bridge, each node in process over real DDS:
//! - a malformed goal is rejected before it is accepted: the client sees `accepted = false`,
//!   not an accepted goal that then aborts;
//! - a cancel sent while the goal runs is honoured: the goal ends as canceled, and nothing it
//!   would have produced is published.

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use cell_msgs::{
    ExecuteProgramFeedback, ExecuteProgramGoal, ExecuteProgramResult, MachineProgram,
    MachineStatus, PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult, SequenceSheetFeedback,
    SequenceSheetGoal, SequenceSheetResult, SliceFeedback, SliceGoal, SliceResult, Toolpath,
};
use cell_runtime::action::{ActionClient, GoalStatusEnum};
use cell_runtime::{CellNode, QosPreset, Subscriber};
use common::{cancel_when, discover_action_server, fresh_domain, node, within, DELIVERY_TIMEOUT};
use futures::StreamExt;

/// A client of `action` on `client_node`, once the server is discovered.
async fn client<G, R, F>(client_node: &CellNode, action: &str) -> ActionClient<G, R, F>
where
    G: cell_msgs::RosMessage + ros2_client::Message,
    R: cell_msgs::RosMessage + ros2_client::Message,
    F: cell_msgs::RosMessage + ros2_client::Message,
{
    let client = client_node.action_client(action).unwrap();
    discover_action_server(client_node, action).await;
    client
}

/// Whether the server accepts `goal` (it answers either way).
async fn accepted<G, R, F>(client: &ActionClient<G, R, F>, goal: G) -> bool
where
    G: ros2_client::Message + Clone + 'static,
    R: ros2_client::Message + Clone + 'static,
    F: ros2_client::Message + 'static,
{
    let (_, response) = within(client.async_send_goal(goal)).await.expect("sent");
    response.accepted
}

/// Sends `goal`, cancels it at the first feedback `started` says the run is under way, and
/// returns how it ended. The result is asked for once, at the start, and held open.
async fn cancel_while_running<G, R, F>(
    client: &ActionClient<G, R, F>,
    goal: G,
    started: impl Fn(&F) -> bool,
) -> (GoalStatusEnum, R)
where
    G: ros2_client::Message + Clone + 'static,
    R: ros2_client::Message + Clone + 'static,
    F: ros2_client::Message + 'static,
{
    cancel_when(client, goal, 10 * DELIVERY_TIMEOUT, |goal_id| async move {
        let feedback = client.feedback_stream(goal_id);
        let mut feedback = std::pin::pin!(feedback);
        loop {
            match within(feedback.next()).await {
                Some(Ok(f)) if started(&f) => break,
                Some(_) => {}
                None => panic!("feedback ended before the run was under way"),
            }
        }
    })
    .await
}

/// Asserts nothing arrives on `toolpaths` for two seconds.
async fn nothing_published(toolpaths: &mut Subscriber<Toolpath>, what: &str) {
    assert!(
        tokio::time::timeout(Duration::from_secs(2), toolpaths.recv())
            .await
            .is_err(),
        "a canceled {what} must not publish a toolpath"
    );
}

fn data(dir: &str, name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(dir)
        .join(name)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_planner_rejects_a_malformed_goal_and_honours_cancel() {
    let domain = fresh_domain();
    let params = planner::PlannerParams {
        panels: 40,
        particles: 8,
        feedback_every: 1,
        exposure_period_s: 0.0,
        ..planner::PlannerParams::default()
    };
    let planner = tokio::spawn(planner::run(node("planner", domain, false), params));
    let client_node = node("operator", domain, false);
    let mut toolpaths = client_node
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let client: ActionClient<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback> =
        client(&client_node, "/plan_hotwire").await;
    let goal = |chord: f64, iterations: u32| PlanHotwireGoal {
        job_id: "wing".into(),
        root_airfoil: "s1223".into(),
        root_chord_mm: chord,
        iterations,
        ..Default::default()
    };

    assert!(!accepted(&client, goal(0.0, 10)).await, "chord 0");
    assert!(
        !accepted(
            &client,
            PlanHotwireGoal {
                root_airfoil: "nope".into(),
                ..goal(150.0, 10)
            }
        )
        .await,
        "an airfoil that does not resolve"
    );

    let (status, result) =
        cancel_while_running(&client, goal(150.0, 100_000), |f| f.iteration >= 1).await;
    assert_eq!(status, GoalStatusEnum::Canceled, "{}", result.message);
    assert!(!result.success);
    assert!(
        result.message.contains("at the client's request"),
        "{}",
        result.message
    );
    nothing_published(&mut toolpaths, "plan").await;
    assert!(!planner.is_finished(), "the planner keeps serving");
    planner.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_sequencer_rejects_a_malformed_goal_and_honours_cancel() {
    let domain = fresh_domain();
    let params = sequencer::SequencerParams {
        max_iterations: cell_sequencer::improve::MAX_IMPROVE_ITERATIONS,
        feedback_every: 1,
        // The layout is test data (files in goals are confined: `cell_runtime::data_files`).
        data_dirs: vec![
            concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data").into(),
            "config".into(),
        ],
        ..sequencer::SequencerParams::default()
    };
    let sequencer = tokio::spawn(sequencer::run(node("sequencer", domain, false), params));
    let client_node = node("operator", domain, false);
    let mut toolpaths = client_node
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let client: ActionClient<SequenceSheetGoal, SequenceSheetResult, SequenceSheetFeedback> =
        client(&client_node, "/sequence_sheet").await;
    let nest = data("sheet", "plate_holes_nest.json").display().to_string();

    assert!(
        !accepted(
            &client,
            SequenceSheetGoal {
                layout_file: nest.clone(),
                policy: "fastest".into(),
                ..Default::default()
            }
        )
        .await,
        "an unknown policy"
    );
    assert!(
        !accepted(&client, SequenceSheetGoal::default()).await,
        "no layout"
    );

    let goal = SequenceSheetGoal {
        job_id: "long".into(),
        layout_file: nest,
        improve: true,
        time_budget_s: 600.0,
        ..Default::default()
    };
    let (status, result) = cancel_while_running(&client, goal, |f| f.phase == "improvement").await;
    assert_eq!(status, GoalStatusEnum::Canceled, "{}", result.message);
    assert!(!result.success);
    assert!(result.message.starts_with("canceled"), "{}", result.message);
    nothing_published(&mut toolpaths, "sheet plan").await;
    assert!(!sequencer.is_finished(), "the sequencer keeps serving");
    sequencer.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_slicer_rejects_a_malformed_goal_and_honours_cancel() {
    let domain = fresh_domain();
    let slicer = tokio::spawn(slicer::run(
        node("slicer", domain, false),
        slicer::SlicerParams {
            log_stock_mesh: false,
            data_dirs: vec![
                concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data").into(),
                "config".into(),
            ],
            ..slicer::SlicerParams::default()
        },
    ));
    let client_node = node("operator", domain, false);
    let mut toolpaths = client_node
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let client: ActionClient<SliceGoal, SliceResult, SliceFeedback> =
        client(&client_node, "/slice").await;
    let plate = data("stl", "plate_holes.STL").display().to_string();

    assert!(
        !accepted(&client, SliceGoal::default()).await,
        "neither an STL nor a wing spec"
    );
    assert!(
        !accepted(
            &client,
            SliceGoal {
                stl_file: plate.clone(),
                layer_height_mm: -1.0,
                ..Default::default()
            }
        )
        .await,
        "a negative layer height"
    );

    // 685 layers of 0.02 mm (12.7 mm and the 1 mm allowance): long slicing and planning,
    // cancelled once the first layer's region is done.
    let goal = SliceGoal {
        job_id: "thin".into(),
        stl_file: plate,
        layer_height_mm: 0.02,
        ..Default::default()
    };
    let (status, result) = cancel_while_running(&client, goal, |f| {
        (f.phase == "slice" || f.phase == "plan") && f.layers_done >= 1
    })
    .await;
    assert_eq!(status, GoalStatusEnum::Canceled, "{}", result.message);
    assert!(!result.success);
    assert!(
        result.message.contains("cancelled after") && result.message.contains(" layers"),
        "{}",
        result.message
    );
    nothing_published(&mut toolpaths, "slice").await;
    assert!(!slicer.is_finished(), "the slicer keeps serving");
    slicer.abort();
}

/// The emitter's program for the sample wing toolpath on the 4-axis GRBL cutter (about 30 s of
/// cutting in real time).
fn wing_program() -> MachineProgram {
    let toolpath: Toolpath = cell_msgs::json::from_str(
        &std::fs::read_to_string(data("toolpaths", "wing.json")).unwrap(),
    )
    .unwrap();
    let profile = cell_profiles::MachineProfile::resolve("grbl-xyuv").unwrap();
    cell_emitter::emit_program(&toolpath, &profile, "wing").expect("emits")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_machine_bridge_rejects_a_malformed_goal_and_honours_cancel() {
    use cell_grbl::sim::{self, SimConfig};
    let dir = tempfile::tempdir().unwrap();
    // A GRBL simulator in real time, so the program is still running when the cancel comes.
    let sim = sim::start(SimConfig {
        time_scale: 1.0,
        axes: vec!['X', 'Y', 'U', 'V'],
        ..SimConfig::default()
    });
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let controller = dir.path().join("cutter.yaml");
    std::fs::write(
        &controller,
        format!(
            "id: cutter\nprotocol: grbl\nmachine_profile: grbl-xyuv\naxes: XYUV\n\
             endpoint: {{tcp: '{addr}'}}\n"
        ),
    )
    .unwrap();
    let domain = fresh_domain();
    let bridge = tokio::spawn(machine_bridge::run(
        node("machine_bridge", domain, false),
        machine_bridge::BridgeParams {
            controllers: vec![controller.display().to_string()],
            arm_at_start: true,
            ..machine_bridge::BridgeParams::default()
        },
    ));
    let client_node = node("operator", domain, false);
    let client: ActionClient<ExecuteProgramGoal, ExecuteProgramResult, ExecuteProgramFeedback> =
        client(&client_node, "/execute_program").await;
    let program = wing_program();
    let goal = |program: &MachineProgram, machine_id: &str| ExecuteProgramGoal {
        program: program.clone(),
        machine_id: machine_id.into(),
        start_line: 0,
    };

    assert!(
        !accepted(&client, goal(&program, "lathe")).await,
        "a controller the bridge does not have"
    );
    let linuxcnc = cell_emitter::emit_program(
        &cell_msgs::json::from_str(
            &std::fs::read_to_string(data("toolpaths", "wing.json")).unwrap(),
        )
        .unwrap(),
        &cell_profiles::MachineProfile::resolve("linuxcnc-xyuv").unwrap(),
        "wrong-dialect",
    )
    .unwrap();
    assert!(
        !accepted(&client, goal(&linuxcnc, "cutter")).await,
        "a program in another dialect"
    );
    assert!(
        sim.executed_lines().is_empty(),
        "nothing reached the machine"
    );

    let (status, result) = cancel_while_running(&client, goal(&program, "cutter"), |f| {
        f.state == MachineStatus::STATE_RUNNING && f.acked_line > 0
    })
    .await;
    assert_eq!(status, GoalStatusEnum::Canceled, "{}", result.message);
    assert_eq!(
        result.outcome,
        ExecuteProgramResult::OUTCOME_ABORTED,
        "{}",
        result.message
    );
    assert!(!result.success);
    assert!(
        result.message.contains("heat off confirmed"),
        "{}",
        result.message
    );
    assert!(!sim.snapshot().spindle_on, "heat off after the cancel");
    assert!(!bridge.is_finished(), "the bridge keeps serving");
    bridge.abort();
}
