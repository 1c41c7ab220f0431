//! The hot-wire planner end to end: the `planner` node serving `plan_hotwire` in process (goal,
//! feedback, result, the Toolpath topic, rejected goals), and the one-shot `cell hotwire`
//! command (files written, errors naming the file and line).

mod common;

use cell_msgs::{
    PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult, Toolpath, ToolpathSegment,
};
use cell_planner::node::{run, PlannerParams};
use cell_runtime::{action::GoalStatusEnum, QosPreset};
use common::{follow_goal, fresh_domain, node, within, FollowedGoal, DELIVERY_TIMEOUT};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn planner_node_plans_a_goal_and_survives_a_bad_one() {
    let domain = fresh_domain();
    let server_node = node("planner", domain, false);
    let client_node = node("operator", domain, false);
    let params = PlannerParams {
        panels: 40,
        particles: 8,
        restart_every: 30,
        feedback_every: 10,
        exposure_period_s: 0.2,
        ..PlannerParams::default()
    };
    let planner = tokio::spawn(run(server_node, params));

    let mut toolpaths = client_node
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let client = client_node
        .action_client::<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>("/plan_hotwire")
        .unwrap();
    assert!(
        client_node
            .wait_for_action_server("/plan_hotwire", DELIVERY_TIMEOUT)
            .await,
        "planner never discovered"
    );

    let goal = |chord: f64, job: &str| PlanHotwireGoal {
        job_id: job.into(),
        root_airfoil: "s1223".into(),
        root_chord_mm: chord,
        iterations: 60,
        seed: 3,
        ..Default::default()
    };

    // A bad goal first: rejected, and the node keeps serving.
    assert!(
        follow_goal(&client, goal(0.0, "bad")).await.is_none(),
        "a goal with chord 0 must be rejected"
    );

    let FollowedGoal {
        first_feedback: first,
        status,
        result,
    } = follow_goal(&client, goal(150.0, "wing-1"))
        .await
        .expect("the goal is accepted");
    assert!(
        first.iteration >= 1 && first.total_iterations == 60,
        "{first:?}"
    );
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    assert!(result.success, "{}", result.message);
    assert!(result.final_loss <= result.baseline_loss, "{result:?}");
    let tp = &result.toolpath;
    assert_eq!(tp.job_id, "wing-1");
    assert_eq!(tp.process, Toolpath::PROCESS_HOTWIRE);
    assert_eq!(tp.power_unit, Toolpath::POWER_WIRE_CURRENT_A);
    let kinds: Vec<u8> = tp.segments.iter().map(|s| s.kind).collect();
    assert_eq!(
        kinds,
        [
            ToolpathSegment::KIND_LEAD,
            ToolpathSegment::KIND_CUT,
            ToolpathSegment::KIND_LEAD
        ]
    );
    let cut = &tp.segments[1];
    assert!(cut.points.len() > 40);
    assert_eq!(cut.points.first(), cut.points.last(), "CUT is closed");
    assert_eq!(cut.feed_mm_s.len(), cut.points.len());
    assert_eq!(cut.power.len(), cut.points.len());

    let published = within(toolpaths.recv()).await.expect("toolpath topic");
    assert_eq!(published.message.job_id, "wing-1");
    assert_eq!(published.message.segments, tp.segments);

    // Still serving after the rejected and the planned goal.
    assert!(follow_goal(&client, goal(-5.0, "bad-2")).await.is_none());
    assert!(!planner.is_finished(), "the planner node must stay up");
    planner.abort();
}

const CELL: &str = env!("CARGO_BIN_EXE_cell");

#[test]
fn cell_hotwire_writes_trajectory_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let run = std::process::Command::new(CELL)
        .args([
            "hotwire",
            "--airfoil",
            "s1223",
            "--chord",
            "150",
            "--panels",
            "40",
            "--iterations",
            "60",
            "--particles",
            "8",
            "--seed",
            "3",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");

    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("x_mm,y_mm,feed_mm_s,current_a"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() > 40);
    assert!(rows
        .iter()
        .all(|r| r.len() == 4 && r.iter().all(|v| v.is_finite())));
    assert!(rows.iter().all(|r| r[2] > 0.0 && r[3] > 0.0));
    assert!(
        rows.windows(2).all(|w| w[0][..2] != w[1][..2]),
        "no zero-length moves: consecutive rows repeat a point"
    );

    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let rms = |k: &str| report[k]["rms"].as_f64().unwrap();
    assert!(rms("optimised") <= rms("baseline"), "{report}");
    assert_eq!(report["iterations"], 60);
    assert_eq!(report["seed"], 3);
    assert_eq!(report["airfoil"], "s1223");
    assert_eq!(report["chord_mm"], 150.0);
    assert!(report["material"].is_string());
    assert!(report["baseline"]["cv"].is_number() && report["seconds"].is_number());
}

#[test]
fn cell_hotwire_names_a_malformed_dat_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let dat = dir.path().join("broken.dat");
    std::fs::write(
        &dat,
        "BROKEN\n1.0 0.0\n0.5 0.05\n0.0 zero\n0.5 -0.05\n1.0 0.0\n",
    )
    .unwrap();
    let run = std::process::Command::new(CELL)
        .args(["hotwire", "--airfoil"])
        .arg(&dat)
        .args(["--chord", "100", "--out"])
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(64));
    let stderr = String::from_utf8_lossy(&run.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(lines[0].starts_with("error:"), "{stderr}");
    assert!(
        lines[0].contains(&format!("{}:4", dat.display())),
        "names the file and line: {stderr}"
    );

    let run = std::process::Command::new(CELL)
        .args(["hotwire", "--airfoil", "s1223", "--chord", "0", "--out"])
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(64));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.starts_with("error: --chord"), "{stderr}");
}
