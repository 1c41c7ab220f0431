//! The standard-type views (issue 22, item 6) over real DDS: a sequencer node's toolpath as
//! `nav_msgs/Path` and `visualization_msgs/MarkerArray` in metres, its heat frames as
//! `sensor_msgs/Image` (`32FC1`), the machine bridge's `JointState`, `/tf`, `/tf_static` and
//! `/diagnostics` after a program on the GRBL simulator, and `standard_views: false`
//! publishing none of them. The subscribers use `cell_msgs`' Rust types of the stock
//! definitions (the drift test holds them to the vendored Jazzy `.msg` files).

mod common;

use std::collections::HashMap;
use std::time::Duration;

use cell_grbl::sim::Faults;
use cell_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus};
use cell_msgs::nav_msgs::Path;
use cell_msgs::sensor_msgs::{Image, JointState};
use cell_msgs::tf2_msgs::TFMessage;
use cell_msgs::visualization_msgs::{Marker, MarkerArray};
use cell_msgs::{HeatMap, MachineStatus, RosMessage, SequenceSheetGoal, Toolpath, ToolpathSegment};
use cell_runtime::{action::GoalStatusEnum, CellNode, QosPreset, Subscriber};
use cell_views::kind_style;
use common::machines::{execute, goal, grbl_program, grbl_sim, operator, status_until};
use common::{discover_action_server, follow_goal, fresh_domain, node, within, FollowedGoal};

fn sheet(name: &str) -> String {
    format!("{}/tests/data/sheet/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Collects what `sub` receives, in a task, until 5 s pass without a message (or none comes
/// within the delivery timeout).
fn collect<T: RosMessage>(mut sub: Subscriber<T>) -> tokio::task::JoinHandle<Vec<T>> {
    tokio::spawn(async move {
        let mut seen = Vec::new();
        let mut patience = common::DELIVERY_TIMEOUT;
        while let Ok(Some(r)) = tokio::time::timeout(patience, sub.recv()).await {
            seen.push(r.message);
            patience = Duration::from_secs(5);
        }
        seen
    })
}

/// The next message on `sub` that satisfies `pred`.
async fn next_where<T: RosMessage>(sub: &mut Subscriber<T>, pred: impl Fn(&T) -> bool) -> T {
    within(async {
        loop {
            let m = sub.recv().await.expect("subscription open").message;
            if pred(&m) {
                return m;
            }
        }
    })
    .await
}

/// (parent, child) of every static transform heard on `/tf_static` within a few seconds.
async fn static_frames(sub: &mut Subscriber<TFMessage>) -> Vec<(String, String)> {
    let mut frames = Vec::new();
    while let Ok(Some(r)) = tokio::time::timeout(Duration::from_secs(3), sub.recv()).await {
        for t in r.message.transforms {
            frames.push((t.header.frame_id, t.child_frame_id));
        }
    }
    frames
}

async fn sequence(client_node: &CellNode, job_id: &str) {
    let client = client_node
        .action_client::<SequenceSheetGoal, cell_msgs::SequenceSheetResult, cell_msgs::SequenceSheetFeedback>(
            "/sequence_sheet",
        )
        .unwrap();
    discover_action_server(client_node, "/sequence_sheet").await;
    let FollowedGoal { status, result, .. } = follow_goal(
        &client,
        SequenceSheetGoal {
            job_id: job_id.into(),
            layout_file: sheet("plate_holes_nest.json"),
            ..Default::default()
        },
    )
    .await
    .expect("accepted");
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_sheet_toolpath_and_its_heat_are_published_as_path_markers_and_images() {
    let domain = fresh_domain();
    let params = sequencer::SequencerParams {
        max_iterations: 10,
        frame_every_steps: 50,
        max_frames: 20,
        data_dirs: vec![
            concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data").into(),
            "config".into(),
        ],
        ..Default::default()
    };
    let server = tokio::spawn(sequencer::run(node("sequencer", domain, false), params));
    let client_node = node("viewer", domain, false);
    let mut toolpaths = client_node
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let mut paths = client_node
        .subscriber::<Path>("/toolpath/path", QosPreset::Status)
        .unwrap();
    let mut markers = client_node
        .subscriber::<MarkerArray>("/toolpath/markers", QosPreset::Status)
        .unwrap();
    let mut tf_static = client_node
        .subscriber::<TFMessage>("/tf_static", QosPreset::Plan)
        .unwrap();
    let heat = collect(
        client_node
            .subscriber::<HeatMap>("/sheet_heat", QosPreset::Stream)
            .unwrap(),
    );
    let images = collect(
        client_node
            .subscriber::<Image>("/sheet_heat/image", QosPreset::Status)
            .unwrap(),
    );
    sequence(&client_node, "views-1").await;

    let toolpath = within(toolpaths.recv()).await.expect("toolpath").message;
    assert_eq!(toolpath.job_id, "views-1");
    assert_eq!(toolpath.header.frame_id, "sheet");

    // The path: every point of every segment, in order, in metres, in the toolpath's frame.
    let path = next_where(&mut paths, |p| p.header.stamp == toolpath.header.stamp).await;
    assert_eq!(path.header.frame_id, "sheet");
    let expected: Vec<(f64, f64, f64)> = toolpath
        .segments
        .iter()
        .flat_map(|s| &s.points)
        .map(|p| (p.x / 1000.0, p.y / 1000.0, p.z / 1000.0))
        .collect();
    let got: Vec<(f64, f64, f64)> = path
        .poses
        .iter()
        .map(|p| (p.pose.position.x, p.pose.position.y, p.pose.position.z))
        .collect();
    assert!(expected.len() > 10, "{} points", expected.len());
    assert_eq!(got, expected, "path = toolpath points / 1000");

    // The markers: a DELETEALL, then one line list per kind (one layer here), coloured by kind,
    // with a line pair for every consecutive pair of points of that kind.
    let array = next_where(&mut markers, |m| {
        m.markers.first().map(|m| m.header.stamp) == Some(toolpath.header.stamp)
    })
    .await;
    assert_eq!(array.markers[0].action, Marker::DELETEALL);
    let by_ns: HashMap<&str, &Marker> = array.markers[1..]
        .iter()
        .map(|m| (m.ns.as_str(), m))
        .collect();
    for (kind, ns, colour) in [
        (ToolpathSegment::KIND_CUT, "cut", kind_style::CUT),
        (ToolpathSegment::KIND_TRAVEL, "travel", kind_style::TRAVEL),
    ] {
        let m = by_ns.get(ns).unwrap_or_else(|| panic!("no {ns} marker"));
        assert_eq!((m.type_, m.id), (Marker::LINE_LIST, 0));
        assert_eq!(m.color, colour, "{ns} colour");
        assert_eq!(m.header.frame_id, "sheet");
        let pairs: usize = toolpath
            .segments
            .iter()
            .filter(|s| s.kind == kind)
            .map(|s| s.points.len().saturating_sub(1))
            .sum();
        assert!(pairs > 0);
        assert_eq!(m.points.len(), 2 * pairs, "{ns} line pairs");
    }
    let first_cut = toolpath
        .segments
        .iter()
        .find(|s| s.kind == ToolpathSegment::KIND_CUT)
        .expect("a cut");
    let cut = by_ns["cut"];
    assert_eq!(cut.points[0].x, first_cut.points[0].x / 1000.0);
    assert_eq!(cut.points[1].y, first_cut.points[1].y / 1000.0);

    // The frames the views are in hang from `cell`.
    let frames = static_frames(&mut tf_static).await;
    assert!(
        frames.contains(&("cell".into(), "sheet".into())),
        "{frames:?}"
    );

    // The heat frames as 32FC1 images: same size, the same floats, little-endian, row-major.
    let (heat, images) = (heat.await.unwrap(), images.await.unwrap());
    assert!(!images.is_empty(), "no heat images");
    let mut matched = 0;
    for image in &images {
        assert_eq!(image.encoding, "32FC1");
        assert_eq!(image.is_bigendian, 0);
        assert_eq!(image.step, 4 * image.width);
        assert_eq!(image.data.len(), (image.step * image.height) as usize);
        if let Some(hm) = heat.iter().find(|h| h.header.stamp == image.header.stamp) {
            assert_eq!((image.width, image.height), (hm.width, hm.height));
            let floats: Vec<f32> = image
                .data
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            assert_eq!(
                floats.iter().map(|f| f.to_bits()).collect::<Vec<_>>(),
                hm.data.iter().map(|f| f.to_bits()).collect::<Vec<_>>()
            );
            matched += 1;
        }
    }
    assert!(
        matched > 0,
        "no image matched a heat frame ({} images, {} frames)",
        images.len(),
        heat.len()
    );
    server.abort();
}

/// A tapered hot-wire panel: the UV carriage's points get their own markers, half transparent,
/// and the exposure profile and matrix come as images of the same floats.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_hotwire_plan_shows_both_carriages_and_its_exposure_images() {
    use cell_msgs::{PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult};
    let domain = fresh_domain();
    let params = planner::PlannerParams {
        panels: 40,
        particles: 8,
        exposure_period_s: 0.0,
        ..Default::default()
    };
    let server = tokio::spawn(planner::run(node("planner", domain, false), params));
    let client_node = node("viewer", domain, false);
    let mut toolpaths = client_node
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let mut markers = client_node
        .subscriber::<MarkerArray>("/toolpath/markers", QosPreset::Status)
        .unwrap();
    let profiles = collect(
        client_node
            .subscriber::<HeatMap>("/exposure", QosPreset::Stream)
            .unwrap(),
    );
    let images = collect(
        client_node
            .subscriber::<Image>("/exposure/image", QosPreset::Status)
            .unwrap(),
    );
    let matrix_images = collect(
        client_node
            .subscriber::<Image>("/exposure_matrix/image", QosPreset::Status)
            .unwrap(),
    );
    let client = client_node
        .action_client::<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>("/plan_hotwire")
        .unwrap();
    discover_action_server(&client_node, "/plan_hotwire").await;
    let FollowedGoal { status, result, .. } = follow_goal(
        &client,
        PlanHotwireGoal {
            job_id: "panel-views".into(),
            root_airfoil: "s1223".into(),
            root_chord_mm: 180.0,
            tip_chord_mm: 120.0,
            span_mm: 400.0,
            iterations: 10,
            seed: 3,
            ..Default::default()
        },
    )
    .await
    .expect("accepted");
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    let toolpath = within(toolpaths.recv()).await.expect("toolpath").message;
    let array = next_where(&mut markers, |m| {
        m.markers.first().map(|m| m.header.stamp) == Some(toolpath.header.stamp)
    })
    .await;
    let ns: Vec<&str> = array.markers[1..].iter().map(|m| m.ns.as_str()).collect();
    assert_eq!(ns, ["lead", "lead/secondary", "cut", "cut/secondary"]);
    let uv = &array.markers[4];
    let tip_cut = &toolpath.segments[1].secondary_points;
    assert_eq!(uv.color.a, kind_style::CUT.a / 2.0);
    assert_eq!(uv.points.len(), 2 * (tip_cut.len() - 1));
    assert_eq!(uv.points[1].z, tip_cut[1].z / 1000.0);
    assert!(uv.points[1].z > 0.0, "the UV carriage is the far tower");
    assert_eq!(uv.header.frame_id, toolpath.header.frame_id);

    let (profiles, images, matrix_images) = (
        profiles.await.unwrap(),
        images.await.unwrap(),
        matrix_images.await.unwrap(),
    );
    assert!(!matrix_images.is_empty(), "no exposure matrix images");
    let image = images
        .iter()
        .find(|i| i.header.stamp == toolpath.header.stamp)
        .expect("the final exposure profile as an image");
    let profile = profiles
        .iter()
        .find(|p| p.header.stamp == image.header.stamp)
        .expect("the final exposure profile");
    let floats: Vec<f32> = image
        .data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    assert_eq!((image.width, image.height), (profile.width, profile.height));
    assert_eq!(
        floats.iter().map(|f| f.to_bits()).collect::<Vec<_>>(),
        profile.data.iter().map(|f| f.to_bits()).collect::<Vec<_>>()
    );
    assert_eq!((image.encoding.as_str(), image.height), ("32FC1", 1));
    assert_eq!(image.step, 4 * image.width);
    server.abort();
}

/// A WAAM part from the slicer as in the demo (namespace `/cell`, `toolpath` remapped to
/// `waam_toolpath`): the views follow the remapped topic, and each layer's beads are their own
/// `deposit` marker.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_waam_part_has_one_deposit_marker_per_layer_under_the_remapped_topic() {
    use cell_msgs::{SliceFeedback, SliceGoal, SliceResult};
    let domain = fresh_domain();
    let mut setup = cell_runtime::NodeSetup::local("slicer", domain);
    setup.fast_path = cell_runtime::FastPathMode::Off;
    setup.args = cell_runtime::args::NodeArgs::parse(
        [
            "--ros-args",
            "-r",
            "__ns:=/cell",
            "-r",
            "toolpath:=waam_toolpath",
        ]
        .map(String::from),
    )
    .expect("arguments");
    let server = tokio::spawn(slicer::run(
        CellNode::new(setup).unwrap(),
        slicer::SlicerParams {
            data_dirs: vec![
                concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data").into(),
                "config".into(),
            ],
            ..slicer::SlicerParams::default()
        },
    ));
    let client_node = node("viewer", domain, false);
    let mut toolpaths = client_node
        .subscriber::<Toolpath>("/cell/waam_toolpath", QosPreset::Plan)
        .unwrap();
    let mut markers = client_node
        .subscriber::<MarkerArray>("/cell/waam_toolpath/markers", QosPreset::Status)
        .unwrap();
    let client = client_node
        .action_client::<SliceGoal, SliceResult, SliceFeedback>("/cell/slice")
        .unwrap();
    discover_action_server(&client_node, "/cell/slice").await;
    let FollowedGoal { status, result, .. } = follow_goal(
        &client,
        SliceGoal {
            job_id: "cube-views".into(),
            stl_file: format!(
                "{}/tests/data/stl/20mm-xyz-cube.stl",
                env!("CARGO_MANIFEST_DIR")
            ),
            ..Default::default()
        },
    )
    .await
    .expect("accepted");
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    let toolpath = within(toolpaths.recv()).await.expect("toolpath").message;
    let array = next_where(&mut markers, |m| {
        m.markers.first().map(|m| m.header.stamp) == Some(toolpath.header.stamp)
    })
    .await;
    let mut layers: Vec<u32> = toolpath
        .segments
        .iter()
        .filter(|s| s.kind == ToolpathSegment::KIND_DEPOSIT)
        .map(|s| s.layer)
        .collect();
    layers.dedup();
    assert!(layers.len() > 5, "{} layers", layers.len());
    let deposits: Vec<&Marker> = array.markers.iter().filter(|m| m.ns == "deposit").collect();
    assert_eq!(
        deposits.iter().map(|m| m.id as u32).collect::<Vec<_>>(),
        layers,
        "one deposit marker per layer, id = layer"
    );
    for (m, &layer) in deposits.iter().zip(&layers) {
        assert_eq!(m.color, kind_style::DEPOSIT);
        let expected: Vec<f64> = toolpath
            .segments
            .iter()
            .filter(|s| s.kind == ToolpathSegment::KIND_DEPOSIT && s.layer == layer)
            .flat_map(|s| {
                s.points
                    .windows(2)
                    .flat_map(|w| [w[0].z / 1000.0, w[1].z / 1000.0])
            })
            .collect();
        let z: Vec<f64> = m.points.iter().map(|p| p.z).collect();
        assert_eq!(z, expected, "layer {layer} heights in metres");
    }
    server.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_bridge_publishes_joint_states_tool_frames_and_diagnostics() {
    let dir = tempfile::tempdir().unwrap();
    let (_sim, file) = grbl_sim(dir.path(), "cutter", Faults::default(), 50.0, "").await;
    let domain = fresh_domain();
    let bridge = tokio::spawn(machine_bridge::run(
        node("machine_bridge", domain, false),
        machine_bridge::BridgeParams {
            controllers: vec![file],
            arm_at_start: true,
            ..Default::default()
        },
    ));
    let mut op = operator(domain).await;
    let mut joints = op
        .node
        .subscriber::<JointState>("/joint_states", QosPreset::Status)
        .unwrap();
    let mut tf = op
        .node
        .subscriber::<TFMessage>("/tf", QosPreset::Status)
        .unwrap();
    let mut diagnostics = op
        .node
        .subscriber::<DiagnosticArray>("/diagnostics", QosPreset::Status)
        .unwrap();
    let mut tf_static = op
        .node
        .subscriber::<TFMessage>("/tf_static", QosPreset::Plan)
        .unwrap();

    let program = grbl_program("views-run", 40);
    let (result, _) = execute(&op.client, goal(&program, ""), Duration::from_secs(300)).await;
    assert!(result.success, "{}", result.message);
    let done = status_until(&mut op.status, "cutter", |s| {
        s.state == MachineStatus::STATE_DONE || s.state == MachineStatus::STATE_IDLE
    })
    .await;
    assert_eq!(done.axis_names, ["X", "Y", "U", "V"]);
    assert!(
        done.axis_positions.iter().any(|&p| p != 0.0),
        "the machine moved: {:?}",
        done.axis_positions
    );

    // Joint states: one joint per axis, named after the machine, in metres.
    let metres: Vec<f64> = done.axis_positions.iter().map(|p| p / 1000.0).collect();
    let js = next_where(&mut joints, |j| j.position == metres).await;
    assert_eq!(js.name, ["cutter/X", "cutter/Y", "cutter/U", "cutter/V"]);
    assert_eq!(js.header.frame_id, "cutter");

    // The tool frame on /tf at X, Y (no Z axis: 0), in metres.
    let tool = next_where(&mut tf, |m| {
        m.transforms.iter().any(|t| {
            t.child_frame_id == "cutter/tool"
                && t.transform.translation.x == metres[0]
                && t.transform.translation.y == metres[1]
        })
    })
    .await;
    let t = &tool.transforms[0];
    assert_eq!(t.header.frame_id, "cutter");
    assert_eq!(t.transform.translation.z, 0.0);
    assert_eq!(t.transform.rotation.w, 1.0);
    let frames = static_frames(&mut tf_static).await;
    assert!(
        frames.contains(&("cell".into(), "cutter".into())),
        "{frames:?}"
    );

    // Health: one status per controller, OK and done (or idle) once the run is over (the
    // 1 Hz diagnostics may still say running first).
    let health = next_where(&mut diagnostics, |d| {
        d.status
            .iter()
            .any(|s| s.hardware_id == "cutter" && ["idle", "done"].contains(&s.message.as_str()))
    })
    .await;
    let s = &health.status[0];
    assert_eq!(s.name, "machine_bridge: cutter");
    assert_eq!(s.level, DiagnosticStatus::OK);
    let value = |key: &str| {
        s.values
            .iter()
            .find(|kv| kv.key == key)
            .map(|kv| kv.value.clone())
    };
    assert_eq!(value("axis/X"), Some(done.axis_positions[0].to_string()));
    bridge.abort();
}

/// `standard_views: false`: the nodes still publish their own topics, and no view endpoint
/// exists in the graph.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn standard_views_false_publishes_no_view() {
    let dir = tempfile::tempdir().unwrap();
    let (_sim, file) = grbl_sim(dir.path(), "quiet", Faults::default(), 50.0, "").await;
    let domain = fresh_domain();
    let bridge = tokio::spawn(machine_bridge::run(
        node("machine_bridge", domain, false),
        machine_bridge::BridgeParams {
            controllers: vec![file],
            standard_views: false,
            ..Default::default()
        },
    ));
    let server = tokio::spawn(sequencer::run(
        node("sequencer", domain, false),
        sequencer::SequencerParams {
            max_iterations: 5,
            standard_views: false,
            data_dirs: vec![
                concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data").into(),
                "config".into(),
            ],
            ..Default::default()
        },
    ));
    let mut op = operator(domain).await;
    let mut toolpaths = op
        .node
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let mut joints = op
        .node
        .subscriber::<JointState>("/joint_states", QosPreset::Status)
        .unwrap();
    sequence(&op.node, "quiet-1").await;
    within(toolpaths.recv()).await.expect("the toolpath itself");
    status_until(&mut op.status, "quiet", |_| true).await;
    // Discovery has long caught up: the same nodes' other writers are known.
    tokio::time::sleep(Duration::from_secs(2)).await;
    let topics: Vec<String> = op
        .node
        .published_topics()
        .into_iter()
        .map(|t| t.topic)
        .collect();
    assert!(
        topics.contains(&"/toolpath".to_owned()) && topics.contains(&"/machine_status".to_owned()),
        "{topics:?}"
    );
    for view in [
        "/toolpath/path",
        "/toolpath/markers",
        "/sheet_heat/image",
        "/joint_states",
        "/tf",
        "/tf_static",
        "/diagnostics",
    ] {
        assert!(!topics.iter().any(|t| t == view), "{view} in {topics:?}");
    }
    assert!(
        tokio::time::timeout(Duration::from_secs(1), joints.recv())
            .await
            .is_err(),
        "a joint state arrived"
    );
    bridge.abort();
    server.abort();
}
