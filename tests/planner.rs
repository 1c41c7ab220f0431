//! The hot-wire planner end to end: the `planner` node serving `plan_hotwire` in process (goal,
//! feedback, result, the Toolpath topic, rejected goals), and the one-shot `cell hotwire`
//! command (files written, errors naming the file and line).

mod common;

use cell_msgs::{
    HeatMap, PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult, Toolpath, ToolpathSegment,
};
use cell_runtime::{action::GoalStatusEnum, QosPreset};
use common::{
    discover_action_server, follow_goal, fresh_domain, node, within, FollowedGoal, DELIVERY_TIMEOUT,
};
use planner::{run, PlannerParams};

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
    let mut matrices = client_node
        .subscriber::<HeatMap>("/exposure_matrix", QosPreset::Stream)
        .unwrap();
    let client = client_node
        .action_client::<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>("/plan_hotwire")
        .unwrap();
    discover_action_server(&client_node, "/plan_hotwire").await;

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

    let matrix = within(matrices.recv())
        .await
        .expect("exposure matrix topic");
    assert_eq!(matrix.message.quantity, "wire_exposure");
    assert!(matrix.message.height > 1 && matrix.message.width == 40);

    let published = within(toolpaths.recv()).await.expect("toolpath topic");
    assert_eq!(published.message.job_id, "wing-1");
    assert_eq!(published.message.segments, tp.segments);

    // A tapered, swept, twisted panel: both carriage planes in the toolpath.
    let tapered = PlanHotwireGoal {
        tip_airfoil: "e387".into(),
        tip_chord_mm: 120.0,
        tip_sweep_mm: 30.0,
        tip_twist_deg: -2.0,
        span_mm: 400.0,
        iterations: 20,
        ..goal(180.0, "panel-1")
    };
    let FollowedGoal { status, result, .. } =
        follow_goal(&client, tapered).await.expect("accepted");
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    assert!(result.message.contains("tip E387"), "{}", result.message);
    let cut = &result.toolpath.segments[1];
    assert_eq!(result.toolpath.plane_separation_mm, 1000.0);
    assert_eq!(cut.secondary_points.len(), cut.points.len());
    assert!(cut
        .points
        .iter()
        .zip(&cut.secondary_points)
        .any(|(p, s)| (p.x - s.x).abs() > 1.0));

    // A long goal, cancelled after its first feedback: it ends as canceled, promptly.
    {
        use futures::StreamExt;
        let long = PlanHotwireGoal {
            iterations: 100_000, // the most a goal may ask (cell_planner MAX_ITERATIONS)
            ..goal(150.0, "long-1")
        };
        let (goal_id, response) = within(client.async_send_goal(long)).await.expect("sent");
        assert!(response.accepted);
        let feedback = client.feedback_stream(goal_id);
        let mut feedback = std::pin::pin!(feedback);
        within(feedback.next())
            .await
            .expect("feedback")
            .expect("a feedback message");
        let cancel =
            within(client.async_cancel_goal(goal_id, ros2_client::builtin_interfaces::Time::ZERO))
                .await
                .expect("cancel answered");
        assert_eq!(cancel.goals_canceling.len(), 1, "{cancel:?}");
        let (status, result) = cell_runtime::action::request_result(
            &client,
            goal_id,
            std::time::Duration::from_secs(3),
            DELIVERY_TIMEOUT,
        )
        .await
        .expect("result");
        assert_eq!(status, GoalStatusEnum::Canceled, "{}", result.message);
        assert!(!result.success && result.message.contains("cancelled after"));
    }

    // Still serving after the rejected, the planned and the cancelled goals.
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
    // The default machine is the 4-axis linuxcnc-xyuv: carriage columns x,y,u,v.
    assert_eq!(
        lines.next(),
        Some("x_mm,y_mm,u_mm,v_mm,feed_mm_s,current_a")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() > 40);
    assert!(rows
        .iter()
        .all(|r| r.len() == 6 && r.iter().all(|v| v.is_finite())));
    assert!(rows.iter().all(|r| r[4] > 0.0 && r[5] > 0.0));
    assert!(rows.iter().all(|r| r[..2] == r[2..4]), "a straight cut");
    assert!(
        rows.windows(2).all(|w| w[0][..4] != w[1][..4]),
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
    // The CSE calibration table: the chord grows with the CSE assumed for the material.
    let rows = report["calibration"].as_array().unwrap();
    assert_eq!(rows.len(), 11);
    let chords: Vec<f64> = rows
        .iter()
        .map(|r| r["baseline"]["chord_mm"].as_f64().unwrap())
        .collect();
    // Monotone up to the 0.05 mm trailing-edge search step.
    assert!(chords.windows(2).all(|w| w[1] >= w[0] - 0.1), "{chords:?}");
    assert!(chords[0] < chords[10] && chords[10] <= 151.0, "{chords:?}");

    // exposure.svg: well-formed (read by xml-rs, which shares no code with the writer), the
    // paths and one exposure point per panel (--panels 40) before and after, the CSE line.
    let svg = out.join("exposure.svg");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        stdout.contains(&format!("cell hotwire: picture {}", svg.display())),
        "{stdout}"
    );
    let elements = svg_elements(&svg);
    let points = |id: &str| {
        let (_, attributes) = elements
            .iter()
            .find(|(_, a)| a.get("id").map(String::as_str) == Some(id))
            .unwrap_or_else(|| panic!("exposure.svg has no {id}"));
        attributes
            .get("points")
            .map_or(0, |p| p.split_whitespace().count())
    };
    for id in ["root-exposure-baseline", "root-exposure-optimised"] {
        assert_eq!(points(id), 40, "{id}");
    }
    for id in ["root-foil", "root-baseline-path", "root-optimised-path"] {
        assert!(points(id) > 40, "{id}");
    }
    for id in [
        "root-lead-in",
        "root-lead-out",
        "root-cse",
        "root-clearance-margin",
    ] {
        points(id);
    }
    assert!(elements.iter().any(|(name, _)| name == "title"));
}

/// The elements of an SVG file: (name, attributes); any XML error fails the test.
fn svg_elements(
    path: &std::path::Path,
) -> Vec<(String, std::collections::HashMap<String, String>)> {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    xml::reader::EventReader::new(std::io::BufReader::new(file))
        .into_iter()
        .filter_map(|event| {
            match event.unwrap_or_else(|e| panic!("{}: not well-formed: {e}", path.display())) {
                xml::reader::XmlEvent::StartElement {
                    name, attributes, ..
                } => Some((
                    name.local_name,
                    attributes
                        .into_iter()
                        .map(|a| (a.name.local_name, a.value))
                        .collect(),
                )),
                _ => None,
            }
        })
        .collect()
}

#[test]
fn cell_hotwire_plans_a_tapered_panel_and_refuses_it_on_a_two_axis_machine() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let args = [
        "hotwire",
        "--airfoil",
        "s1223",
        "--chord",
        "200",
        "--tip",
        "e387",
        "--tip-chord",
        "120",
        "--tip-sweep",
        "40",
        "--tip-twist",
        "-3",
        "--span",
        "400",
        "--material",
        "EPS",
        "--panels",
        "40",
        "--iterations",
        "20",
        "--particles",
        "6",
        "--out",
    ];
    let run = std::process::Command::new(CELL)
        .args(args)
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["machine"], "linuxcnc-xyuv");
    assert_eq!(report["tip"]["chord_mm"], 120.0);
    assert_eq!(report["iterations"], 40, "root and tip sections");
    assert!(report["tip"]["offset_mm"].as_f64() > report["offset_mm"].as_f64());
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // Swept back and smaller: the UV carriage runs a different, shorter path.
    assert!(rows.iter().any(|r| (r[0] - r[2]).abs() > 5.0));
    let (x_span, u_span) = rows
        .iter()
        .fold((0.0f64, 0.0f64), |(x, u), r| (x.max(r[0]), u.max(r[2])));
    assert!(x_span > 0.0 && u_span > 0.0);
    assert!(
        rows.iter().all(|r| r[4] <= 25.0 + 1e-3),
        "machine feed limit"
    );
    // The picture draws both sections.
    let ids: Vec<String> = svg_elements(&out.join("exposure.svg"))
        .into_iter()
        .filter_map(|(_, mut a)| a.remove("id"))
        .collect();
    for id in [
        "root-exposure-optimised",
        "tip-exposure-optimised",
        "tip-cse",
    ] {
        assert!(ids.iter().any(|i| i == id), "exposure.svg has no {id}");
    }

    let run = std::process::Command::new(CELL)
        .args(args)
        .arg(&out)
        .args(["--machine", "grbl-xy"])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(64));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.starts_with("error: --machine"), "{stderr}");
    assert!(stderr.contains("4-axis"), "{stderr}");
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
