//! One action-goal server for every node: a [`GoalHandler`] says what a goal means and does;
//! [`serve`] owns the ROS 2 action protocol around it.
//!
//! Per goal, [`serve`]:
//! 1. names it ([`GoalHandler::job_id`]) and checks its sender ([`GoalHandler::admit`]) and
//!    the goal ([`GoalHandler::validate`]); a goal that fails a check is **rejected before it
//!    is accepted**, its reason logged (ROS 2 rejections carry no text);
//! 2. accepts it, starts executing it and runs [`GoalHandler::run`] on its own task with a
//!    [`GoalContext`]: feedback sent through the context is published in order, and a cancel
//!    request for the goal is accepted and shows in [`GoalContext::is_canceled`] (and completes
//!    [`GoalContext::canceled`]);
//! 3. once the run ends, publishes its terminal status at once and keeps its result for
//!    [`ServeOptions::result_timeout`] (rcl's result timeout), as rclcpp and rclpy servers do:
//!    every result request for the goal is answered, those read while it ran when it ends, later
//!    ones at once (a client may ask twice, late, or before the goal ends). Then the result is
//!    dropped, with a warning if nobody got it ("nobody asked for the result of …"); a request
//!    for a dropped or unknown goal is answered with status Unknown and a default result.
//!
//! Goals run one at a time, in arrival order (a goal sent meanwhile waits for the running one
//! to end before it is read), unless [`ServeOptions::concurrent`] is set. Cancel requests are
//! answered at any time: accepted for running goals, refused for anything else (a goal not yet
//! run, or one that ended). On shutdown no new goal is read. One-at-a-time servers (computations)
//! cancel the running goal and give it [`SHUTDOWN_GRACE`] to end before [`serve`] returns
//! anyway, naming it, so a node never outlives its launcher's patience for one stuck goal;
//! concurrent servers (the machine bridge) let their goals end as their handler decides (it may
//! watch [`crate::Shutdown`]). Kept results go when [`serve`] returns.
//!
//! A handler whose work is a blocking computation runs it with [`GoalContext::run_blocking`];
//! one whose work is async I/O (a machine run) awaits it in [`GoalHandler::run`] directly.

use std::{
    collections::{BTreeMap, VecDeque},
    future::Future,
    sync::Arc,
    time::Duration,
};

use anyhow::anyhow;
use cell_msgs::RosMessage;
use futures::{stream::FuturesUnordered, FutureExt, StreamExt};
use tokio::{sync::mpsc, time::Instant};
use tokio_util::sync::CancellationToken;

use crate::action::{AsyncActionServer, ExecutingGoalHandle, GoalEndStatus, GoalId};
use crate::node::CellNode;

/// What a node's action does with a goal (module docs).
pub trait GoalHandler: Send + Sync + 'static {
    /// The action's goal message.
    type Goal: RosMessage + ros2_client::Message;
    /// The action's result message (its default is the answer for an unknown goal).
    type Result: RosMessage + ros2_client::Message + Default;
    /// The action's feedback message.
    type Feedback: RosMessage + ros2_client::Message;
    /// What a valid goal becomes: everything [`GoalHandler::run`] needs.
    type Job: Send + 'static;

    /// The id of a goal in log lines and in what it produces: the goal's own, or one made from
    /// `served`, the goal's arrival number (1 for the first goal the node read).
    fn job_id(&self, goal: &Self::Goal, served: u64) -> String;

    /// Checks a goal before it is accepted: the job to run, or why the goal is rejected (one
    /// line naming the field or file).
    ///
    /// # Errors
    /// Anything that makes the goal unrunnable as given.
    fn validate(&self, goal: &Self::Goal, job_id: &str) -> Result<Self::Job, String>;

    /// Whether the goal's sender may send it, checked before [`GoalHandler::validate`]: `from`
    /// is the goal request's writer GID, whose first 12 bytes name the client's participant
    /// ([`CellNode::peer`]). A refusal rejects the goal like a failed validation. Default:
    /// every sender.
    ///
    /// # Errors
    /// Why this sender may not (one line naming the peer).
    fn admit(&self, _goal: &Self::Goal, _job_id: &str, _from: &[u8; 16]) -> Result<(), String> {
        Ok(())
    }

    /// Runs an accepted goal to its end: its status (succeeded, aborted with the reason in the
    /// result, canceled) and result.
    ///
    /// # Errors
    /// Only what the node cannot go on after (a topic it cannot publish on): [`serve`] returns
    /// the error and the node stops. A goal that fails ends as aborted instead.
    fn run(
        &self,
        job: Self::Job,
        ctx: GoalContext<Self::Feedback>,
    ) -> impl Future<Output = anyhow::Result<GoalEnd<Self::Result>>> + Send;
}

/// How a goal ended: the status its client sees and the result it gets.
#[derive(Debug, Clone, PartialEq)]
pub struct GoalEnd<R> {
    /// Succeeded, aborted or canceled.
    pub status: GoalEndStatus,
    /// The result message.
    pub result: R,
}

impl<R> GoalEnd<R> {
    /// The goal did what it was asked.
    pub fn succeeded(result: R) -> Self {
        Self {
            status: GoalEndStatus::Succeeded,
            result,
        }
    }

    /// The goal failed; the result says why.
    pub fn aborted(result: R) -> Self {
        Self {
            status: GoalEndStatus::Aborted,
            result,
        }
    }

    /// The goal stopped because its client asked.
    pub fn canceled(result: R) -> Self {
        Self {
            status: GoalEndStatus::Canceled,
            result,
        }
    }
}

/// What a running goal's handler holds: its id, a feedback channel, its cancel state. Cheap to
/// clone; usable from a blocking thread.
#[derive(Debug)]
pub struct GoalContext<F> {
    job_id: Arc<str>,
    feedback: mpsc::UnboundedSender<F>,
    cancel: CancellationToken,
}

// Not derived: a derive would ask for `F: Clone`.
impl<F> Clone for GoalContext<F> {
    fn clone(&self) -> Self {
        Self {
            job_id: self.job_id.clone(),
            feedback: self.feedback.clone(),
            cancel: self.cancel.clone(),
        }
    }
}

impl<F: Send + 'static> GoalContext<F> {
    /// The goal's id ([`GoalHandler::job_id`]).
    pub fn job_id(&self) -> &str {
        &self.job_id
    }

    /// Queues a feedback message; [`serve`] publishes it, in order, while the goal executes.
    /// Never blocks. Feedback after an accepted cancel is dropped (ROS 2 sends feedback only
    /// for an executing goal).
    pub fn feedback(&self, feedback: F) {
        // The receiver lives until the run ends, so a send cannot fail while it matters.
        let _ = self.feedback.send(feedback);
    }

    /// Whether the goal's client asked to cancel it (and the cancel was accepted).
    pub fn is_canceled(&self) -> bool {
        self.cancel.is_cancelled()
    }

    /// Completes once the goal's client asks to cancel it.
    pub async fn canceled(&self) {
        self.cancel.cancelled().await
    }

    /// Runs `work` on a blocking thread (a computation that would stall the async runtime),
    /// handing it a clone of this context for feedback and cancel checks; its return value.
    ///
    /// # Errors
    /// `work` panicked.
    pub async fn run_blocking<T: Send + 'static>(
        &self,
        work: impl FnOnce(&GoalContext<F>) -> T + Send + 'static,
    ) -> anyhow::Result<T> {
        let ctx = self.clone();
        tokio::task::spawn_blocking(move || work(&ctx))
            .await
            .map_err(|e| anyhow!("{}: the goal's thread failed: {e}", self.job_id))
    }
}

/// How [`serve`] runs goals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServeOptions {
    /// How long a finished goal's result is kept for clients to ask for (rcl's result timeout).
    pub result_timeout: Duration,
    /// Run goals side by side, each on its own task, instead of one at a time.
    pub concurrent: bool,
    /// On shutdown, cancel the running goals and return after this long even if they have
    /// not ended; `None`: wait for them however long they take.
    pub cancel_on_shutdown: Option<Duration>,
}

/// How long a one-at-a-time server's goal has to end once shutdown cancels it: below the 5 s
/// a launcher waits after SIGINT before it kills.
pub const SHUTDOWN_GRACE: Duration = Duration::from_secs(3);

impl ServeOptions {
    /// One goal at a time, in arrival order; results kept `result_timeout_s` seconds (a
    /// negative or NaN value is 0, an infinite one forever); on shutdown the running goal is
    /// canceled and given [`SHUTDOWN_GRACE`].
    pub fn one_at_a_time(result_timeout_s: f64) -> Self {
        Self {
            result_timeout: Duration::try_from_secs_f64(result_timeout_s.max(0.0))
                .unwrap_or(Duration::MAX),
            concurrent: false,
            cancel_on_shutdown: Some(SHUTDOWN_GRACE),
        }
    }

    /// Every goal as soon as it arrives, side by side (the handler refuses what cannot run
    /// alongside); results kept as [`ServeOptions::one_at_a_time`] says.
    pub fn concurrent(result_timeout_s: f64) -> Self {
        Self {
            concurrent: true,
            cancel_on_shutdown: None,
            ..Self::one_at_a_time(result_timeout_s)
        }
    }
}

type Server<H> = AsyncActionServer<
    <H as GoalHandler>::Goal,
    <H as GoalHandler>::Result,
    <H as GoalHandler>::Feedback,
>;

/// A goal [`serve`] runs: what it needs to cancel it and to answer for it.
struct Running<G> {
    job_id: String,
    cancel: CancellationToken,
    executing: ExecutingGoalHandle<G>,
}

/// Serves the action `action` (resolved against namespace and remappings) with `handler` until
/// the node shuts down (module docs). Log lines start with `action` as given.
///
/// # Errors
/// The action server cannot be created; a handler's run returned an error or panicked.
pub async fn serve<H: GoalHandler>(
    node: CellNode,
    action: &str,
    handler: H,
    options: ServeOptions,
) -> anyhow::Result<()> {
    let server: Arc<Server<H>> = Arc::new(node.action_server(action)?);
    let handler = Arc::new(handler);
    let mut running: BTreeMap<GoalId, Running<H::Goal>> = BTreeMap::new();
    let mut runs = FuturesUnordered::new();
    // Ended goals by when their results are dropped (one timeout for all, so in order).
    let mut kept: VecDeque<(Instant, GoalId, String)> = VecDeque::new();
    let mut served = 0u64;
    let mut stopping = false;
    // When a shutdown stops waiting for canceled goals.
    let mut give_up_at: Option<Instant> = None;
    loop {
        let idle = running.is_empty();
        if stopping && idle {
            return Ok(());
        }
        let next_drop = kept.front().map(|(at, ..)| *at);
        tokio::select! {
            handle = server.receive_new_goal(), if !stopping && (idle || options.concurrent) => {
                let handle = match handle {
                    Ok(h) => h,
                    Err(e) => {
                        tracing::warn!("{action}: cannot read a goal: {e:?}");
                        continue;
                    }
                };
                let Some(goal) = server.get_new_goal(handle.clone()) else {
                    tracing::warn!("{action}: goal without a body");
                    continue;
                };
                served += 1;
                let job_id = handler.job_id(&goal, served);
                let from = handle.request_id().writer_gid.to_bytes16();
                let checked = handler
                    .admit(&goal, &job_id, &from)
                    .and_then(|()| handler.validate(&goal, &job_id));
                let job = match checked {
                    Ok(job) => job,
                    Err(why) => {
                        tracing::warn!("{action}: rejecting goal {job_id}: {why}");
                        if let Err(e) = server.reject_goal(handle).await {
                            tracing::warn!("{action}: reject {job_id}: {e:?}");
                        }
                        continue;
                    }
                };
                let accepted = match server.accept_goal(handle).await {
                    Ok(a) => a,
                    Err(e) => {
                        tracing::warn!("{action}: accept {job_id}: {e:?}");
                        continue;
                    }
                };
                let executing = match server.start_executing_goal(accepted).await {
                    Ok(x) => x,
                    Err(e) => {
                        tracing::warn!("{action}: execute {job_id}: {e:?}");
                        continue;
                    }
                };
                let goal_id = executing.goal_id();
                let cancel = CancellationToken::new();
                let run = tokio::spawn(run_goal(
                    handler.clone(),
                    server.clone(),
                    executing.clone(),
                    job,
                    job_id.as_str().into(),
                    cancel.clone(),
                    action.to_owned(),
                ));
                runs.push(run.map(move |ended| (goal_id, ended)));
                running.insert(goal_id, Running { job_id, cancel, executing });
            }
            cancel = server.receive_cancel_request() => {
                let Ok(cancel) = cancel else { continue };
                let ours: Vec<GoalId> = running
                    .keys()
                    .copied()
                    .filter(|g| cancel.contains_goal(g))
                    .collect();
                for g in &ours {
                    let goal = &running[g];
                    tracing::info!("{action}: cancelling {}", goal.job_id);
                    goal.cancel.cancel();
                }
                if let Err(e) = server.respond_to_cancel_requests(&cancel, ours.into_iter()).await {
                    tracing::warn!("{action}: cancel response: {e:?}");
                }
            }
            Some((goal_id, ended)) = runs.next(), if !idle => {
                let Running { job_id, executing, .. } =
                    running.remove(&goal_id).expect("every run is registered");
                let end = ended
                    .map_err(|e| anyhow!("{action}: goal {job_id}: {e}"))
                    .and_then(|end| end)?;
                // Publishes the terminal status and answers the requests read so far; no wait.
                if let Err(e) = server.send_result_response(executing, end.status, end.result).await {
                    tracing::warn!("{action}: result {job_id}: {e:?}");
                }
                // An infinite timeout overflows: kept for good.
                if let Some(at) = Instant::now().checked_add(options.result_timeout) {
                    kept.push_back((at, goal_id, job_id));
                }
            }
            // One reader of result requests for all goals: answered at once or when their goal ends.
            asked = server.receive_result_request() => {
                if let Err(e) = asked {
                    tracing::warn!("{action}: result request: {e:?}");
                }
            }
            _ = tokio::time::sleep_until(next_drop.unwrap_or_else(Instant::now)), if next_drop.is_some() => {
                let (_, goal_id, job_id) = kept.pop_front().expect("a result is kept");
                if !server.forget_result(goal_id) {
                    tracing::warn!("{action}: nobody asked for the result of {job_id}");
                }
            }
            _ = node.shutdown().requested(), if !stopping => {
                stopping = true;
                if let Some(grace) = options.cancel_on_shutdown {
                    for goal in running.values() {
                        tracing::info!("{action}: shutting down: cancelling {}", goal.job_id);
                        goal.cancel.cancel();
                    }
                    give_up_at = Some(Instant::now() + grace);
                }
            }
            _ = tokio::time::sleep_until(give_up_at.unwrap_or_else(Instant::now)), if give_up_at.is_some() => {
                let left: Vec<&str> = running.values().map(|g| g.job_id.as_str()).collect();
                tracing::warn!(
                    "{action}: shutting down: {} still running {:?} after it was cancelled; leaving it",
                    left.join(", "),
                    options.cancel_on_shutdown.unwrap_or_default(),
                );
                return Ok(());
            }
        }
    }
}

/// One goal's task: the handler's run, and its feedback published while it runs.
async fn run_goal<H: GoalHandler>(
    handler: Arc<H>,
    server: Arc<Server<H>>,
    executing: ExecutingGoalHandle<H::Goal>,
    job: H::Job,
    job_id: Arc<str>,
    cancel: CancellationToken,
    action: String,
) -> anyhow::Result<GoalEnd<H::Result>> {
    let (feedback, mut feedback_rx) = mpsc::unbounded_channel();
    let ctx = GoalContext {
        job_id: job_id.clone(),
        feedback,
        cancel: cancel.clone(),
    };
    let run = handler.run(job, ctx);
    // Ends once the run and every clone of its context are gone, after the last feedback.
    let publish = async {
        while let Some(feedback) = feedback_rx.recv().await {
            if cancel.is_cancelled() {
                continue;
            }
            if let Err(e) = server.publish_feedback(executing.clone(), feedback).await {
                tracing::warn!("{action}: feedback {job_id}: {e:?}");
            }
        }
    };
    let (end, ()) = tokio::join!(run, publish);
    end
}
