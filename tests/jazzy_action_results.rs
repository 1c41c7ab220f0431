//! A stock ROS 2 Jazzy `rclpy.action.ActionClient` (Fast DDS, PyPI `ros-jazzy-*` wheels, through
//! `cell_testkit::jazzy_workspace`) against the goal server every cell action node uses
//! (`cell_runtime::goal_server`): the goal's terminal status is published on
//! `<action>/_action/status` when it ends, without any result request, and a result asked for
//! after the end, twice, is answered both times at once (rclcpp's and rclpy's servers keep
//! it for their result timeout). `tests/ros2/action_results_peer.py` is the client.

mod common;

use std::path::Path;
use std::process::Stdio;
use std::time::Duration;

use cell_msgs::{PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult};
use cell_runtime::goal_server::{self, GoalContext, GoalEnd, GoalHandler, ServeOptions};
use serde_json::Value;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// How long the goal runs: long enough for the peer to see it executing.
const GOAL_MS: u32 = 1500;

/// Sleeps the goal's `iterations` milliseconds and succeeds.
struct Sleeper;

impl GoalHandler for Sleeper {
    type Goal = PlanHotwireGoal;
    type Result = PlanHotwireResult;
    type Feedback = PlanHotwireFeedback;
    type Job = (String, u64);

    fn job_id(&self, goal: &PlanHotwireGoal, _served: u64) -> String {
        goal.job_id.clone()
    }

    fn validate(&self, goal: &PlanHotwireGoal, job_id: &str) -> Result<(String, u64), String> {
        Ok((job_id.to_owned(), u64::from(goal.iterations)))
    }

    async fn run(
        &self,
        (job_id, ms): (String, u64),
        _ctx: GoalContext<PlanHotwireFeedback>,
    ) -> anyhow::Result<GoalEnd<PlanHotwireResult>> {
        tokio::time::sleep(Duration::from_millis(ms)).await;
        Ok(GoalEnd::succeeded(PlanHotwireResult {
            success: true,
            message: format!("{job_id}: slept"),
            ..Default::default()
        }))
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stock_rclpy_client_sees_the_end_status_and_gets_a_late_result_twice() {
    let Some(jazzy) = cell_testkit::jazzy_workspace(Path::new(env!("CARGO_TARGET_TMPDIR"))) else {
        return;
    };
    let domain = common::fresh_domain();
    let serving = tokio::spawn(goal_server::serve(
        common::node("sleeper", domain, false),
        "/late_results",
        Sleeper,
        ServeOptions::one_at_a_time(60.0),
    ));
    let dir = tempfile::tempdir().unwrap();
    let peer = tokio::process::Command::new(&jazzy.python)
        .arg(format!("{ROOT}/tests/ros2/action_results_peer.py"))
        .args(["--action", "/late_results", "--timeout", "30"])
        .args(["--ms", &GOAL_MS.to_string()])
        .envs(jazzy.vars.iter().map(|(k, v)| (k, v)))
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        .env("ROS_LOG_DIR", dir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .kill_on_drop(true)
        .output();
    let out = tokio::time::timeout(Duration::from_secs(180), peer)
        .await
        .expect("the peer finishes")
        .expect("the peer runs");
    assert!(out.status.success(), "rclpy peer: {}", out.status);
    let line = String::from_utf8_lossy(&out.stdout);
    eprintln!("{line}");
    let seen: Value = serde_json::from_str(line.trim()).expect("one JSON line");
    assert!(seen.get("error").is_none(), "{seen}");
    assert_eq!(seen["accepted"], true, "{seen}");

    // The end status arrives by itself, after the goal was seen running.
    let statuses: Vec<&str> = seen["statuses"]
        .as_array()
        .expect("statuses")
        .iter()
        .map(|s| s.as_str().expect("a name"))
        .collect();
    assert_eq!(statuses.last(), Some(&"SUCCEEDED"), "{seen}");
    assert!(statuses.contains(&"EXECUTING"), "{seen}");
    let terminal_after = seen["terminal_after_s"].as_f64().expect("seconds");
    assert!(
        terminal_after >= f64::from(GOAL_MS) / 1000.0 * 0.9,
        "not before the goal ended: {seen}"
    );

    // Asked late, twice: both answered with the result, each at once.
    let answers = seen["answers"].as_array().expect("answers");
    assert_eq!(answers.len(), 2, "{seen}");
    for answer in answers {
        assert_eq!(answer["status"], "SUCCEEDED", "{seen}");
        assert_eq!(answer["message"], "jazzy-late: slept", "{seen}");
        let s = answer["seconds"].as_f64().expect("seconds");
        assert!(s < 5.0, "answered at once, not after {s} s: {seen}");
    }
    assert_eq!(seen["handle_status"], "SUCCEEDED", "{seen}");
    assert!(!serving.is_finished(), "the server still serves");
    serving.abort();
}
