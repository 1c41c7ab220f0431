//! The goal server over real DDS, two in-process nodes on loopback: a goal that fails its
//! check is rejected before it is accepted, a good one streams feedback and succeeds, a result
//! asked for after its goal ended still arrives, a cancel is honoured, and the server returns
//! once its node shuts down; an async handler serves goals side by side; every result request
//! is answered (twice, late, after the result was dropped) and the end status is published
//! without one.

use std::time::Duration;

use cell_msgs::{PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult};
use cell_runtime::action::{request_result, ActionClient, GoalStatusEnum};
use cell_runtime::goal_server::{self, GoalContext, GoalEnd, GoalHandler, ServeOptions};
use cell_runtime::{CellNode, FastPathMode, NodeSetup};
use futures::StreamExt;

/// Generous bound for discovery and delivery on a loaded 2-core machine.
const PATIENCE: Duration = Duration::from_secs(30);

/// A domain no concurrently running test binary of the workspace is likely to use: counted down
/// from the top of the root package's integration tests' range (`CELL_TEST_DOMAIN_BASE`, or one
/// picked by process id), which they use from the bottom.
fn domain(n: u16) -> u16 {
    let base = std::env::var("CELL_TEST_DOMAIN_BASE")
        .ok()
        .and_then(|b| b.parse::<u16>().ok())
        .filter(|b| *b <= 216)
        .unwrap_or(100 + (std::process::id() % 8) as u16 * 16);
    base + 15 - n
}

fn node(name: &str, domain: u16) -> (CellNode, cell_runtime::Shutdown) {
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = FastPathMode::Off;
    let shutdown = setup.shutdown.clone();
    (CellNode::new(setup).expect("node comes up"), shutdown)
}

/// Counts `iterations` steps of 20 ms on a blocking thread, one feedback per step, stopping
/// early on cancel. Rejects a goal whose chord is not > 0.
struct Counter;

impl GoalHandler for Counter {
    type Goal = PlanHotwireGoal;
    type Result = PlanHotwireResult;
    type Feedback = PlanHotwireFeedback;
    type Job = u32;

    fn job_id(&self, goal: &PlanHotwireGoal, served: u64) -> String {
        if goal.job_id.is_empty() {
            format!("count-{served}")
        } else {
            goal.job_id.clone()
        }
    }

    fn validate(&self, goal: &PlanHotwireGoal, _job_id: &str) -> Result<u32, String> {
        if goal.root_chord_mm > 0.0 {
            Ok(goal.iterations)
        } else {
            Err(format!("root_chord_mm {}: must be > 0", goal.root_chord_mm))
        }
    }

    async fn run(
        &self,
        iterations: u32,
        ctx: GoalContext<PlanHotwireFeedback>,
    ) -> anyhow::Result<GoalEnd<PlanHotwireResult>> {
        let done = ctx
            .run_blocking(move |ctx| {
                for i in 1..=iterations {
                    if ctx.is_canceled() {
                        return i - 1;
                    }
                    ctx.feedback(PlanHotwireFeedback {
                        iteration: i,
                        total_iterations: iterations,
                        ..Default::default()
                    });
                    std::thread::sleep(Duration::from_millis(20));
                }
                iterations
            })
            .await?;
        let result = PlanHotwireResult {
            success: done == iterations,
            message: format!("{}: {done} of {iterations}", ctx.job_id()),
            ..Default::default()
        };
        Ok(if ctx.is_canceled() {
            GoalEnd::canceled(result)
        } else {
            GoalEnd::succeeded(result)
        })
    }
}

type Client = ActionClient<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>;

fn goal(chord: f64, iterations: u32) -> PlanHotwireGoal {
    PlanHotwireGoal {
        root_chord_mm: chord,
        iterations,
        ..Default::default()
    }
}

/// A server of `handler` on `action` (node `server`) and a client that has discovered it, on
/// `domain`.
struct Served {
    serving: tokio::task::JoinHandle<anyhow::Result<()>>,
    shutdown: cell_runtime::Shutdown,
    client: Client,
    /// The client's node, kept for as long as the client.
    _client_node: CellNode,
}

async fn serve_with_client<H: GoalHandler>(
    domain: u16,
    server: &str,
    action: &'static str,
    handler: H,
    options: ServeOptions,
) -> Served {
    let (server_node, shutdown) = node(server, domain);
    let (client_node, _) = node("operator", domain);
    let serving = tokio::spawn(goal_server::serve(server_node, action, handler, options));
    let client: Client = client_node.action_client(action).unwrap();
    assert!(
        client_node.wait_for_action_server(action, PATIENCE).await,
        "action server {action} never discovered"
    );
    Served {
        serving,
        shutdown,
        client,
        _client_node: client_node,
    }
}

/// Sends a goal to sleep `ms` milliseconds (in `iterations`) as job `job`; it must be accepted.
async fn send_sleep(client: &Client, job: &str, ms: u32) -> cell_runtime::action::GoalId {
    let g = PlanHotwireGoal {
        job_id: job.into(),
        iterations: ms,
        ..Default::default()
    };
    let (id, response) = tokio::time::timeout(PATIENCE, client.async_send_goal(g))
        .await
        .expect("goal answered in time")
        .expect("goal sent");
    assert!(response.accepted);
    id
}

async fn result_of(
    client: &Client,
    goal_id: cell_runtime::action::GoalId,
) -> (GoalStatusEnum, PlanHotwireResult) {
    request_result(client, goal_id, 3 * PATIENCE, 3 * PATIENCE)
        .await
        .expect("result")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn goals_are_checked_run_canceled_and_answered_late() {
    let served = serve_with_client(
        domain(0),
        "counter",
        "/count",
        Counter,
        ServeOptions::one_at_a_time(60.0),
    )
    .await;
    let (client, shutdown) = (&served.client, &served.shutdown);
    let send = |g: PlanHotwireGoal| async {
        tokio::time::timeout(PATIENCE, client.async_send_goal(g))
            .await
            .expect("goal answered in time")
            .expect("goal sent")
    };

    // A goal that fails the check: not accepted (rather than accepted and then aborted).
    let (_, response) = send(goal(0.0, 3)).await;
    assert!(!response.accepted, "a goal with chord 0 must be rejected");

    // A good goal: feedback in order, then the result.
    let (goal_id, response) = send(goal(100.0, 5)).await;
    assert!(response.accepted);
    let feedback = client.feedback_stream(goal_id);
    let mut feedback = std::pin::pin!(feedback);
    let first = tokio::time::timeout(PATIENCE, feedback.next())
        .await
        .expect("feedback in time")
        .expect("stream")
        .expect("feedback");
    assert_eq!(first.total_iterations, 5, "{first:?}");
    let (status, result) = result_of(client, goal_id).await;
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    assert_eq!(
        result.message, "count-2: 5 of 5",
        "the id counts every goal read"
    );

    // A result asked for only after its goal ended still arrives.
    let (goal_id, response) = send(goal(100.0, 1)).await;
    assert!(response.accepted);
    tokio::time::sleep(Duration::from_secs(2)).await;
    let (status, result) = result_of(client, goal_id).await;
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    assert_eq!(result.message, "count-3: 1 of 1");

    // A cancel during the run: the goal stops early and ends as canceled.
    let (goal_id, response) = send(goal(100.0, 100_000)).await;
    assert!(response.accepted);
    let feedback = client.feedback_stream(goal_id);
    let mut feedback = std::pin::pin!(feedback);
    tokio::time::timeout(PATIENCE, feedback.next())
        .await
        .expect("feedback in time");
    client.cancel_goal(goal_id).expect("cancel sent");
    let (status, result) = result_of(client, goal_id).await;
    assert_eq!(status, GoalStatusEnum::Canceled, "{}", result.message);
    assert!(!result.success, "{}", result.message);

    // The node shutting down ends the server.
    shutdown.trigger();
    tokio::time::timeout(PATIENCE, served.serving)
        .await
        .expect("the server returns on shutdown")
        .expect("task")
        .expect("served without error");
}

/// Waits the goal's `iterations` milliseconds: [`Sleeper::Awaits`] awaiting rather than
/// blocking (as a machine run does), or until it is canceled; [`Sleeper::Stuck`] on a blocking
/// thread that never looks at its cancel (a computation stuck where it cannot be asked to stop).
#[derive(Clone, Copy)]
enum Sleeper {
    Awaits,
    Stuck,
}

impl GoalHandler for Sleeper {
    type Goal = PlanHotwireGoal;
    type Result = PlanHotwireResult;
    type Feedback = PlanHotwireFeedback;
    type Job = u64;

    fn job_id(&self, goal: &PlanHotwireGoal, _served: u64) -> String {
        goal.job_id.clone()
    }

    fn validate(&self, goal: &PlanHotwireGoal, _job_id: &str) -> Result<u64, String> {
        Ok(u64::from(goal.iterations))
    }

    async fn run(
        &self,
        ms: u64,
        ctx: GoalContext<PlanHotwireFeedback>,
    ) -> anyhow::Result<GoalEnd<PlanHotwireResult>> {
        ctx.feedback(PlanHotwireFeedback::default());
        let result = |message: &str| PlanHotwireResult {
            message: format!("{}: {message}", ctx.job_id()),
            ..Default::default()
        };
        if matches!(self, Sleeper::Stuck) {
            ctx.run_blocking(move |_| std::thread::sleep(Duration::from_millis(ms)))
                .await?;
            return Ok(GoalEnd::succeeded(result("slept through")));
        }
        Ok(tokio::select! {
            _ = tokio::time::sleep(Duration::from_millis(ms)) => GoalEnd::succeeded(result("slept")),
            _ = ctx.canceled() => GoalEnd::canceled(result("woken")),
        })
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn concurrent_goals_run_side_by_side_and_cancel_alone() {
    let served = serve_with_client(
        domain(1),
        "sleeper",
        "/sleep",
        Sleeper::Awaits,
        ServeOptions::concurrent(60.0),
    )
    .await;
    let (serving, client) = (&served.serving, &served.client);
    let long = send_sleep(client, "long", 600_000).await;
    // Accepted and run while the long one still runs.
    let short = send_sleep(client, "short", 100).await;
    let (status, result) = result_of(client, short).await;
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    assert_eq!(result.message, "short: slept");
    client.cancel_goal(long).expect("cancel sent");
    let (status, result) = result_of(client, long).await;
    assert_eq!(status, GoalStatusEnum::Canceled, "{}", result.message);
    assert_eq!(result.message, "long: woken");
    assert!(!serving.is_finished());
    serving.abort();
}

/// Every answer to `requests` (result requests of `client`), in request order, or a panic after
/// `timeout`. Reads the replies itself: waiting for one request at a time would drop the reply
/// to another that arrived first.
async fn answers(
    client: &Client,
    requests: &[ros2_client::RmwRequestId],
    timeout: Duration,
) -> Vec<(GoalStatusEnum, PlanHotwireResult)> {
    let deadline = tokio::time::Instant::now() + timeout;
    let mut got = vec![None; requests.len()];
    while got.iter().any(Option::is_none) {
        assert!(
            tokio::time::Instant::now() < deadline,
            "answered within {timeout:?}: {:?} of {requests:?}",
            got.iter().map(Option::is_some).collect::<Vec<_>>()
        );
        match client
            .result_client()
            .receive_response()
            .expect("a reply decodes")
        {
            Some((id, answer)) => {
                let i = requests
                    .iter()
                    .position(|r| *r == id)
                    .expect("a reply we asked for");
                got[i] = Some((answer.status, answer.result));
            }
            None => tokio::time::sleep(Duration::from_millis(20)).await,
        }
    }
    got.into_iter().flatten().collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_result_request_is_answered_and_the_end_status_is_published_without_one() {
    let result_timeout = Duration::from_secs(4);
    let served = serve_with_client(
        domain(2),
        "sleeper",
        "/sleep",
        Sleeper::Awaits,
        ServeOptions::one_at_a_time(result_timeout.as_secs_f64()),
    )
    .await;
    let (serving, client) = (&served.serving, &served.client);
    let ask = |goal| client.request_result(goal).expect("result requested");

    // Asked twice while the goal runs (a client retrying), and once after it ended: every
    // request is answered.
    let twice = send_sleep(client, "twice", 1500).await;
    let early = [ask(twice), ask(twice)];
    for (status, result) in answers(client, &early, PATIENCE).await {
        assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
        assert_eq!(result.message, "twice: slept");
    }
    let late = ask(twice);
    let t0 = std::time::Instant::now();
    let (status, result) = answers(client, &[late], PATIENCE).await.remove(0);
    assert_eq!(status, GoalStatusEnum::Succeeded);
    assert_eq!(result.message, "twice: slept");
    eprintln!("late request answered in {:?}", t0.elapsed());

    // Nobody asks: the end status is still published when the goal ends.
    let quiet = send_sleep(client, "quiet", 200).await;
    let statuses = client.status_stream(quiet);
    let mut statuses = std::pin::pin!(statuses);
    let ended = tokio::time::timeout(PATIENCE, async {
        loop {
            let status = statuses.next().await.expect("stream").expect("status");
            if status.status != GoalStatusEnum::Accepted
                && status.status != GoalStatusEnum::Executing
            {
                return status.status;
            }
        }
    })
    .await
    .expect("the end status is published without a result request");
    let ended_at = std::time::Instant::now();
    assert_eq!(ended, GoalStatusEnum::Succeeded);
    let (status, result) = answers(client, &[ask(quiet)], PATIENCE).await.remove(0);
    assert_eq!(status, GoalStatusEnum::Succeeded);
    assert_eq!(result.message, "quiet: slept");

    // After the result timeout the result is gone: asked again, the goal is unknown (rclcpp's
    // answer), and so is a goal the server never had.
    tokio::time::sleep(
        (result_timeout + Duration::from_secs(2)).saturating_sub(ended_at.elapsed()),
    )
    .await;
    let never = cell_runtime::action::GoalId::new_random();
    let gone = answers(client, &[ask(quiet), ask(never)], PATIENCE).await;
    for (status, result) in gone {
        assert_eq!(status, GoalStatusEnum::Unknown);
        assert_eq!(result, PlanHotwireResult::default());
    }
    assert!(!serving.is_finished());
    serving.abort();
}

/// Shuts a server of `handler` down while a goal of `iterations` runs; how long `serve` took to
/// return.
async fn shutdown_while_running<H: GoalHandler>(
    domain: u16,
    handler: H,
    iterations: u32,
) -> Duration {
    let served = serve_with_client(
        domain,
        "computer",
        "/compute",
        handler,
        ServeOptions::one_at_a_time(60.0),
    )
    .await;
    let (client, shutdown) = (&served.client, &served.shutdown);
    let (goal_id, response) =
        tokio::time::timeout(PATIENCE, client.async_send_goal(goal(100.0, iterations)))
            .await
            .expect("goal answered in time")
            .expect("goal sent");
    assert!(response.accepted);
    let feedback = client.feedback_stream(goal_id);
    let mut feedback = std::pin::pin!(feedback);
    tokio::time::timeout(PATIENCE, feedback.next())
        .await
        .expect("the goal runs");
    let t0 = std::time::Instant::now();
    shutdown.trigger();
    tokio::time::timeout(PATIENCE, served.serving)
        .await
        .expect("the server returns on shutdown")
        .expect("task")
        .expect("served without error");
    t0.elapsed()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn shutdown_cancels_a_running_computation_and_leaves_one_that_ignores_it() {
    // A computation that checks its cancel ends through it, well inside the grace.
    let cooperative = shutdown_while_running(domain(3), Counter, 100_000).await;
    assert!(
        cooperative < goal_server::SHUTDOWN_GRACE,
        "a cancelled computation ended in {cooperative:?}"
    );
    // One that never checks (a 12 s sleep) is left after the grace instead of holding the node.
    let stubborn = shutdown_while_running(domain(4), Sleeper::Stuck, 12_000).await;
    assert!(
        stubborn >= goal_server::SHUTDOWN_GRACE && stubborn < Duration::from_secs(8),
        "a stuck computation held shutdown for {stubborn:?}"
    );
}
