//! The sheet sequencer end to end (seed 003; issue 7): the `sequencer` node serving
//! `sequence_sheet` in process (goal, feedback, result, the Toolpath and CutPlan topics, heat
//! map frames on `sheet_heat`, a bad layout answered with `success = false`), and the one-shot
//! `cell sheet` command (files written, the program accepted by LinuxCNC's interpreter, errors
//! naming the file and entity).

mod common;

use std::path::{Path, PathBuf};

use cell_msgs::{
    CutPlan, HeatMap, SequenceSheetFeedback, SequenceSheetGoal, SequenceSheetResult, Toolpath,
    ToolpathSegment,
};
use cell_runtime::{action::GoalStatusEnum, QosPreset, Via};
use cell_sequencer::{
    job::{load_problem, LayoutSource, SheetJob},
    problem::Problem,
};
use common::{
    cancel_when, discover_action_server, follow_goal, fresh_domain, node, within, FollowedGoal,
};
use sequencer::{run, SequencerParams};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/sheet")
        .join(name)
}

fn problem_of(file: &Path) -> Problem {
    load_problem(&SheetJob {
        layout: LayoutSource::File(file.to_path_buf()),
        ..Default::default()
    })
    .unwrap()
}

/// Every contour cut exactly once, in an order the precedence rules allow.
fn assert_valid_order(problem: &Problem, order: &[u32]) {
    let order: Vec<usize> = order.iter().map(|&c| c as usize).collect();
    problem.precedence.check_order(&order).unwrap();
    let mut sorted = order.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, (0..problem.contours.len()).collect::<Vec<_>>());
}

type SheetClient = cell_runtime::action::ActionClient<
    SequenceSheetGoal,
    SequenceSheetResult,
    SequenceSheetFeedback,
>;

/// An action client for `/sequence_sheet`, once the server is discovered.
async fn sheet_client(client_node: &cell_runtime::CellNode) -> SheetClient {
    let client = client_node
        .action_client::<SequenceSheetGoal, SequenceSheetResult, SequenceSheetFeedback>(
            "/sequence_sheet",
        )
        .unwrap();
    discover_action_server(client_node, "/sequence_sheet").await;
    client
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sequencer_node_sequences_a_sheet_and_survives_a_broken_layout() {
    let domain = fresh_domain();
    // Both on the shared-memory fast path: heat frames must take it (issue 7: iceoryx2).
    let server_node = node("sequencer", domain, true);
    let client_node = node("operator", domain, true);
    let params = SequencerParams {
        max_iterations: 30,
        feedback_every: 1,
        frame_every_steps: 50,
        max_frames: 20,
        // The layouts are test data (files in goals are confined: `cell_runtime::data_files`).
        data_dirs: vec![
            concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data").into(),
            "config".into(),
        ],
        ..SequencerParams::default()
    };
    let sequencer = tokio::spawn(run(server_node, params));

    let mut toolpaths = client_node
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let mut plans = client_node
        .subscriber::<CutPlan>("/cut_plan", QosPreset::Plan)
        .unwrap();
    let mut heat = client_node
        .subscriber::<HeatMap>("/sheet_heat", QosPreset::Stream)
        .unwrap();
    let client = sheet_client(&client_node).await;

    // A broken DXF first: a result with success = false naming the file and the entities.
    let broken = data("broken_open_chain.dxf");
    let FollowedGoal { status, result, .. } = follow_goal(
        &client,
        SequenceSheetGoal {
            job_id: "broken".into(),
            layout_file: broken.display().to_string(),
            ..Default::default()
        },
    )
    .await
    .expect("accepted");
    assert_eq!(status, GoalStatusEnum::Aborted, "{}", result.message);
    assert!(!result.success);
    assert!(
        result.message.contains("broken_open_chain.dxf")
            && result.message.contains("open contour")
            && result.message.contains("LINE"),
        "{}",
        result.message
    );

    // Then a good goal: the real plate nest, with improvement.
    let file = data("plate_holes_nest.json");
    let FollowedGoal {
        first_feedback,
        status,
        result,
    } = follow_goal(
        &client,
        SequenceSheetGoal {
            job_id: "nest-1".into(),
            layout_file: file.display().to_string(),
            improve: true,
            time_budget_s: 4.0,
            seed: 4,
            ..Default::default()
        },
    )
    .await
    .expect("accepted");
    assert!(
        ["load", "construction", "improvement", "simulation"]
            .contains(&first_feedback.phase.as_str()),
        "{first_feedback:?}"
    );
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    assert!(result.success, "{}", result.message);
    let problem = problem_of(&file);
    let plan = &result.plan;
    assert_valid_order(&problem, &plan.order);
    assert_eq!(plan.job_id, "nest-1");
    assert!(plan.improved);
    assert_eq!(plan.policy, "nearest");
    assert!(plan.idle_length_mm > 0.0 && plan.cut_length_mm > 0.0);

    let tp = &result.toolpath;
    assert_eq!(tp.process, Toolpath::PROCESS_SHEET_CUT);
    let cuts: Vec<&ToolpathSegment> = tp
        .segments
        .iter()
        .filter(|s| s.kind == ToolpathSegment::KIND_CUT)
        .collect();
    assert_eq!(cuts.len(), problem.contours.len());
    // Each cut pierces at its plan's pierce point: the heat goes on where the travel to it
    // ends (the profile's kerf and leads: the lead-in's start, on the scrap side), and each
    // cut closes on itself.
    let pierced: Vec<_> = tp
        .segments
        .windows(2)
        .filter(|w| w[0].kind == ToolpathSegment::KIND_TRAVEL)
        .map(|w| w[1].points.first())
        .collect();
    assert_eq!(pierced.len(), plan.pierce_points.len());
    for (start, pierce) in pierced.iter().zip(&plan.pierce_points) {
        assert_eq!(*start, Some(pierce));
    }
    for seg in &cuts {
        assert_eq!(seg.points.first(), seg.points.last());
    }
    assert!(
        plan.kerf_mm > 0.0 && plan.lead_in_mm > 0.0,
        "linuxcnc-plasma's cutting:"
    );
    let travel = cell_sequencer::toolpath::travel_length_mm(tp);
    assert!((travel - plan.idle_length_mm).abs() < 1e-6);

    let published = within(toolpaths.recv()).await.expect("toolpath topic");
    assert_eq!(published.message.job_id, "nest-1");
    assert_eq!(published.message.segments, tp.segments);
    let published = within(plans.recv()).await.expect("cut_plan topic");
    assert_eq!(published.message.order, plan.order);
    let frame = within(heat.recv()).await.expect("sheet_heat topic");
    assert_eq!(
        frame.via,
        Via::SharedMemory,
        "heat frames go over iceoryx2 on one host"
    );
    assert_eq!(frame.message.quantity, "sheet_temperature");
    assert!(frame.message.width > 1 && frame.message.height > 1);
    assert_eq!(
        frame.message.data.len(),
        (frame.message.width * frame.message.height) as usize
    );

    // Still serving after the broken goal and the good one.
    let FollowedGoal { status, result, .. } = follow_goal(
        &client,
        SequenceSheetGoal {
            job_id: "small".into(),
            layout_file: data("small.dxf").display().to_string(),
            policy: "nearest".into(),
            ..Default::default()
        },
    )
    .await
    .expect("accepted");
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    assert_valid_order(&problem_of(&data("small.dxf")), &result.plan.order);
    assert!(!sequencer.is_finished(), "the sequencer node must stay up");
    sequencer.abort();
}

/// A long improvement is cancelled after its first feedback: the goal ends as canceled within
/// seconds (not the 600 s budget), carrying the best plan so far, and nothing goes to the
/// emitter's topic.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_cancelled_goal_stops_improving_and_returns_the_best_plan_so_far() {
    use futures::StreamExt;
    let domain = fresh_domain();
    let params = SequencerParams {
        max_iterations: cell_sequencer::improve::MAX_IMPROVE_ITERATIONS,
        feedback_every: 1,
        data_dirs: vec![
            concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data").into(),
            "config".into(),
        ],
        ..SequencerParams::default()
    };
    let sequencer = tokio::spawn(run(node("sequencer", domain, false), params));
    let client_node = node("operator", domain, false);
    let mut toolpaths = client_node
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let client = sheet_client(&client_node).await;
    let file = data("plate_holes_nest.json");
    // Timed from sending the goal (it was from its acceptance: a few ms stricter now).
    let started = std::time::Instant::now();
    let client = &client;
    let (status, result) = cancel_when(
        client,
        SequenceSheetGoal {
            job_id: "long".into(),
            layout_file: file.display().to_string(),
            improve: true,
            time_budget_s: 600.0,
            ..Default::default()
        },
        std::time::Duration::from_secs(600),
        |goal_id| async move {
            let feedback = client.feedback_stream(goal_id);
            let mut feedback = std::pin::pin!(feedback);
            while let Some(Ok(f)) = within(feedback.next()).await {
                if f.phase == "improvement" {
                    break;
                }
            }
        },
    )
    .await;
    assert_eq!(status, GoalStatusEnum::Canceled, "{}", result.message);
    assert!(
        started.elapsed() < std::time::Duration::from_secs(120),
        "cancel took {:?} (budget 600 s)",
        started.elapsed()
    );
    assert!(!result.success);
    assert!(result.message.starts_with("canceled"), "{}", result.message);
    assert_valid_order(&problem_of(&file), &result.plan.order);
    assert!(
        tokio::time::timeout(std::time::Duration::from_secs(2), toolpaths.recv())
            .await
            .is_err(),
        "a canceled plan must not reach the emitter"
    );
    assert!(!sequencer.is_finished());
    sequencer.abort();
}

const CELL: &str = env!("CARGO_BIN_EXE_cell");

#[test]
fn cell_sheet_writes_plan_program_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let layout = data("small.dxf");
    let run = std::process::Command::new(CELL)
        .args(["sheet", "--seed", "2", "--layout"])
        .arg(&layout)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");

    let plan: CutPlan =
        serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap();
    assert_valid_order(&problem_of(&layout), &plan.order);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["idle_length_mm"].as_f64(), Some(plan.idle_length_mm));
    assert_eq!(report["cut_length_mm"].as_f64(), Some(plan.cut_length_mm));
    assert_eq!(
        report["overheats"].as_u64(),
        Some(u64::from(plan.overheats))
    );
    assert_eq!(
        report["max_temperature_c"].as_f64(),
        Some(plan.max_temperature_c)
    );
    assert_eq!(report["policy"], "nearest");
    assert_eq!(report["improved"], true);
    let phases: Vec<&str> = report["phases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["phase"].as_str().unwrap())
        .collect();
    assert_eq!(
        phases,
        ["load", "construction", "improvement", "simulation"]
    );

    // The program passes LinuxCNC's interpreter, one pierce (M3) per contour.
    let ngc = out.join("program.ngc");
    let text = std::fs::read_to_string(&ngc).unwrap();
    assert_eq!(
        text.lines().filter(|l| l.starts_with("M3")).count(),
        plan.order.len(),
        "{text}"
    );
    if !cell_testkit::linuxcnc_interpreter_here() {
        return;
    }
    let canon = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/interp/canon.py");
    let check = std::process::Command::new("python3")
        .arg(canon)
        .arg(&ngc)
        .arg("XYZ")
        .output()
        .expect("python3 runs");
    let code = check.status.code().unwrap_or(-1);
    assert_ne!(
        code,
        3,
        "LinuxCNC's interpreter is missing: run `bash tests/interp/install.sh` ({})",
        String::from_utf8_lossy(&check.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&check.stdout).unwrap();
    assert_eq!(code, 0, "{}", json["error"]);
}

/// `--thermal off`: the order minimises idle travel alone; the report says so and still gives
/// the final simulation's overheats. A word other than on/off is a usage error.
#[test]
fn cell_sheet_thermal_off_minimises_idle_alone() {
    let dir = tempfile::tempdir().unwrap();
    let layout = data("plate_holes_nest.json");
    let report = |thermal: &str| -> serde_json::Value {
        let out = dir.path().join(thermal);
        let run = std::process::Command::new(CELL)
            .args(["sheet", "--thermal", thermal, "--layout"])
            .arg(&layout)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap()
    };
    let (on, off) = (report("on"), report("off"));
    assert_eq!(
        (on["thermal"].as_str(), off["thermal"].as_str()),
        (Some("on"), Some("off"))
    );
    let idle = |r: &serde_json::Value| r["idle_length_mm"].as_f64().unwrap();
    assert!(idle(&off) <= idle(&on) + 1e-9, "{off} vs {on}");
    // The overheats and the maximum temperature are simulated all the same.
    assert!(off["overheats"].as_u64().is_some());
    assert!(off["max_temperature_c"].as_f64().unwrap() > 100.0, "{off}");

    let run = std::process::Command::new(CELL)
        .args(["sheet", "--thermal", "warm", "--layout"])
        .arg(&layout)
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(64), "{stderr}");
    assert!(
        stderr.contains("--thermal") && stderr.contains("warm"),
        "{stderr}"
    );
}

#[test]
fn cell_sheet_names_a_broken_layout_and_bad_options() {
    let dir = tempfile::tempdir().unwrap();
    let run = std::process::Command::new(CELL)
        .args(["sheet", "--layout"])
        .arg(data("broken_open_chain.dxf"))
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(65), "{stderr}");
    assert!(
        stderr.contains("broken_open_chain.dxf") && stderr.contains("LINE"),
        "{stderr}"
    );
    assert!(!dir.path().join("plan.json").exists());

    let run = std::process::Command::new(CELL)
        .args(["sheet", "--policy", "fastest", "--layout"])
        .arg(data("small.dxf"))
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(64), "{stderr}");
    assert!(stderr.contains("fastest"), "{stderr}");
}

/// `--material`/`--thickness` pick the kerf from the profile's `cutting:` table: the report
/// and the plan state it, every pierce lies on the scrap side off the drawn contours; a
/// material the table lacks is a usage error, a hole too small for the kerf names the hole.
#[test]
fn cell_sheet_cuts_with_the_profiles_kerf_and_leads() {
    let dir = tempfile::tempdir().unwrap();
    let layout = data("plate_holes_nest.json");
    let sheet = |args: &[&str], layout: &Path, out: &Path| {
        std::process::Command::new(CELL)
            .args(["sheet", "--no-improve"])
            .args(args)
            .arg("--layout")
            .arg(layout)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap()
    };
    let out = dir.path().join("3mm");
    let run = sheet(
        &["--material", "mild_steel", "--thickness", "3"],
        &layout,
        &out,
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let cut = &report["cut"];
    assert_eq!(cut["material"], "mild_steel");
    assert_eq!(cut["thickness_mm"].as_f64(), Some(3.0));
    let kerf = cut["kerf_mm"].as_f64().unwrap();
    assert!(kerf > 0.5 && kerf < 1.5, "{cut}");
    assert_eq!(cut["compensation"], "geometric");
    let plan: CutPlan =
        serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap();
    assert_eq!(plan.kerf_mm, kerf);
    assert_eq!(plan.path_offset_mm, kerf / 2.0);
    assert_eq!(plan.lead_in_mm, cut["lead_in_mm"].as_f64().unwrap());
    // Every pierce on the scrap side of its contour, clear of the drawn line.
    let problem = problem_of(&layout);
    for (&c, p) in plan.order.iter().zip(&plan.pierce_points) {
        let contour = &problem.contours[c as usize];
        let q = [p.x, p.y];
        let ring = &contour.points;
        let n = ring.len();
        let (mut inside, mut d) = (false, f64::INFINITY);
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            if (a[1] > q[1]) != (b[1] > q[1])
                && q[0] < a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
            {
                inside = !inside;
            }
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let t =
                (((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            d = d.min((q[0] - a[0] - t * dx).hypot(q[1] - a[1] - t * dy));
        }
        let hole = contour.role == cell_sequencer::problem::ContourRole::Hole;
        assert_eq!(inside, hole, "contour {c}: pierce {q:?} on the part's side");
        assert!(
            d > kerf / 2.0 + 0.1,
            "contour {c}: pierce {d} mm off its line"
        );
    }
    let text = std::fs::read_to_string(out.join("program.ngc")).unwrap();
    assert_eq!(
        text.lines().filter(|l| l.starts_with("M3")).count(),
        plan.order.len()
    );

    let run = sheet(
        &["--material", "unobtainium"],
        &layout,
        &dir.path().join("x"),
    );
    assert_eq!(run.status.code(), Some(64));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("--material") && stderr.contains("unobtainium"),
        "{stderr}"
    );

    let tiny = dir.path().join("tiny_hole.json");
    std::fs::write(
        &tiny,
        r#"{"sheet": [100, 100], "parts": [{"name": "plate",
            "outer": {"points": [[10,10],[90,10],[90,90],[10,90]]},
            "holes": [{"points": [[50,50],[51,50],[51,51],[50,51]]}]}]}"#,
    )
    .unwrap();
    let run = sheet(&[], &tiny, &dir.path().join("tiny"));
    assert_eq!(run.status.code(), Some(65));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("tiny_hole.json") && stderr.contains("parts[0] (plate).holes[0]"),
        "{stderr}"
    );
}
