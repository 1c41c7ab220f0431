//! Shared helpers for the in-process integration tests: fresh domains, loopback nodes.
#![allow(dead_code)] // each test binary uses a different subset

use std::{
    sync::atomic::{AtomicU16, Ordering},
    time::Duration,
};

use cell_runtime::{CellNode, FastPathMode, NodeSetup};

pub mod machines;
pub mod node_process;

static NEXT: AtomicU16 = AtomicU16::new(0);

/// A DDS domain no other running test uses: test binaries run one at a time, tests inside one
/// binary get consecutive ids from a per-process base. `CELL_TEST_DOMAIN_BASE` (0–216) fixes the
/// base instead, for people running test binaries side by side on one host.
pub fn fresh_domain() -> u16 {
    let base = std::env::var("CELL_TEST_DOMAIN_BASE")
        .ok()
        .and_then(|b| b.parse::<u16>().ok())
        .filter(|b| *b <= 216)
        .unwrap_or(100 + (std::process::id() % 8) as u16 * 16);
    base + NEXT.fetch_add(1, Ordering::Relaxed) % 16
}

/// A node on `domain`, DDS on loopback only, with or without the shared-memory fast path.
pub fn node(name: &str, domain: u16, fast_path: bool) -> CellNode {
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = if fast_path {
        FastPathMode::Auto
    } else {
        FastPathMode::Off
    };
    CellNode::new(setup).expect("node comes up")
}

/// Generous bound for discovery and delivery on a loaded 2-core machine.
pub const DELIVERY_TIMEOUT: Duration = Duration::from_secs(30);

/// Awaits `f`, failing the test if it takes longer than [`DELIVERY_TIMEOUT`].
pub async fn within<F: std::future::Future>(f: F) -> F::Output {
    tokio::time::timeout(DELIVERY_TIMEOUT, f)
        .await
        .expect("in time")
}

/// Waits until `client` has discovered the action server `name`, failing the test if that takes
/// longer than [`DELIVERY_TIMEOUT`]. Send goals only after this (goals sent earlier are lost).
pub async fn discover_action_server(client: &CellNode, name: &str) {
    assert!(
        client.wait_for_action_server(name, DELIVERY_TIMEOUT).await,
        "action server {name} never discovered"
    );
}

/// What an action client saw of one accepted goal.
pub struct FollowedGoal<F, R> {
    /// The first feedback message.
    pub first_feedback: F,
    /// The goal's final status.
    pub status: cell_runtime::action::GoalStatusEnum,
    /// The goal's result.
    pub result: R,
}

/// Sends `goal`; if the server accepts it, waits for its first feedback and then its result.
/// `None` when the server rejects the goal.
pub async fn follow_goal<G, R, F>(
    client: &cell_runtime::action::ActionClient<G, R, F>,
    goal: G,
) -> Option<FollowedGoal<F, R>>
where
    G: ros2_client::Message + Clone + 'static,
    R: ros2_client::Message + Clone + 'static,
    F: ros2_client::Message + 'static,
{
    use futures::StreamExt;
    let (goal_id, response) = within(client.async_send_goal(goal)).await.expect("sent");
    if !response.accepted {
        return None;
    }
    let feedback = client.feedback_stream(goal_id);
    let mut feedback = std::pin::pin!(feedback);
    let first_feedback = within(feedback.next())
        .await
        .expect("stream")
        .expect("feedback");
    // Asked again after 3 × DELIVERY_TIMEOUT without an answer, in case the request was lost
    // (`request_result`); the server answers every request for the goal.
    let (status, result) = cell_runtime::action::request_result(
        client,
        goal_id,
        3 * DELIVERY_TIMEOUT,
        3 * DELIVERY_TIMEOUT,
    )
    .await
    .expect("result");
    Some(FollowedGoal {
        first_feedback,
        status,
        result,
    })
}

/// Sends `goal`, which must be accepted, cancels it once `ready(goal_id)` completes, and
/// returns the goal's end status and result (asked for while `ready` runs, again after each
/// `result_wait` without an answer, [`cell_runtime::action::request_result`]).
pub async fn cancel_when<G, R, F, Ready>(
    client: &cell_runtime::action::ActionClient<G, R, F>,
    goal: G,
    result_wait: Duration,
    ready: impl FnOnce(cell_runtime::action::GoalId) -> Ready,
) -> (cell_runtime::action::GoalStatusEnum, R)
where
    G: ros2_client::Message + Clone + 'static,
    R: ros2_client::Message + Clone + 'static,
    F: ros2_client::Message + 'static,
    Ready: std::future::Future<Output = ()>,
{
    let (goal_id, response) = within(client.async_send_goal(goal)).await.expect("sent");
    assert!(response.accepted, "the goal is accepted");
    let result = cell_runtime::action::request_result(client, goal_id, result_wait, result_wait);
    let cancel = async {
        ready(goal_id).await;
        client.cancel_goal(goal_id).expect("cancel sent");
    };
    let (result, ()) = tokio::join!(result, cancel);
    result.expect("result")
}

/// A Python with `requirements` (a path from the workspace root) installed, in the venv
/// `CARGO_TARGET_TMPDIR/<name>`: [`cell_testkit::venv_python`].
pub fn venv_python(name: &str, requirements: &str, import: &str) -> Option<std::path::PathBuf> {
    cell_testkit::venv_python(
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")),
        name,
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(requirements),
        import,
    )
}

/// Every message of an `.rrd` file, decoded by Rerun's own decoder, as one debug string to
/// search for entity paths; fails the test if the file is not a valid recording.
pub fn rrd_dump(path: &std::path::Path) -> String {
    let reader = std::io::BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    );
    let messages: Vec<_> = re_log_encoding::DecoderApp::decode_eager(reader)
        .unwrap_or_else(|e| panic!("{} is not a valid .rrd: {e}", path.display()))
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    format!("{messages:?}")
}

/// Checks an `.rrd` file with Rerun's own tool, `rerun rrd verify` from the PyPI rerun-sdk of
/// the crate's version (a venv made on first use); panics with its complaint. Skips the check
/// (see [`venv_python`]) when the venv cannot be made.
pub fn rrd_verify(path: &std::path::Path) {
    let Some(python) = venv_python("rerun-venv", "tests/rerun/requirements.txt", "rerun") else {
        return;
    };
    let verify = std::process::Command::new(&python)
        .args(["-m", "rerun", "rrd", "verify"])
        .arg(path)
        .env("RERUN_ANALYTICS", "false")
        .output()
        .expect("run rerun");
    assert!(
        verify.status.success(),
        "rerun rrd verify {}: {}",
        path.display(),
        String::from_utf8_lossy(&verify.stderr)
    );
}

/// A closed 100 × 70 mm rectangle cut (one segment, 8 mm/s, 2.5 A) inside grbl-xy's travel.
pub fn rectangle_cut(job_id: &str) -> cell_msgs::Toolpath {
    use cell_msgs::{geometry_msgs::Point, Toolpath, ToolpathSegment};
    let p = |x: f64, y: f64| Point { x, y, z: 0.0 };
    let points = vec![
        p(50.0, 50.0),
        p(150.0, 50.0),
        p(150.0, 120.0),
        p(50.0, 120.0),
        p(50.0, 50.0),
    ];
    Toolpath {
        job_id: job_id.into(),
        process: Toolpath::PROCESS_HOTWIRE,
        power_unit: Toolpath::POWER_WIRE_CURRENT_A,
        segments: vec![ToolpathSegment {
            kind: ToolpathSegment::KIND_CUT,
            feed_mm_s: vec![8.0; points.len()],
            power: vec![2.5; points.len()],
            points,
            ..Default::default()
        }],
        ..Default::default()
    }
}
