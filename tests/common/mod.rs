//! Shared helpers for the in-process integration tests: fresh domains, loopback nodes.
#![allow(dead_code)] // each test binary uses a different subset

use std::{
    sync::atomic::{AtomicU16, Ordering},
    time::Duration,
};

use cell_runtime::{CellNode, FastPathMode, NodeSetup};

static NEXT: AtomicU16 = AtomicU16::new(0);

/// A DDS domain no other running test uses: test binaries run one at a time, tests inside one
/// binary get consecutive ids from a per-process base.
pub fn fresh_domain() -> u16 {
    let base = 100 + (std::process::id() % 8) as u16 * 16;
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
    let (status, result) = cell_runtime::action::request_result(
        client,
        goal_id,
        std::time::Duration::from_secs(3),
        DELIVERY_TIMEOUT,
    )
    .await
    .expect("result");
    Some(FollowedGoal {
        first_feedback,
        status,
        result,
    })
}
