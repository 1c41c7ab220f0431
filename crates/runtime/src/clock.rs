//! A node's clock, as ROS 2 defines it
//! (<https://design.ros2.org/articles/clock_and_time.html>): the system clock, or, when the
//! node's `use_sim_time` parameter is true, the time source's, i.e. the last
//! `rosgraph_msgs/msg/Clock` heard on `/clock` (from `cell bag play --clock`,
//! `ros2 bag play --clock` or a simulator). Like rclcpp and rclpy, simulated time is zero until
//! the first `/clock` message arrives, and it follows the source when it jumps back (a looped
//! bag). `use_sim_time` may also be switched at run time (`ros2 param set`), as in rclcpp: the
//! node subscribes to `/clock` when it is first needed.
//!
//! ros2-client's own spinner subscribes to `/clock` too, but as `builtin_interfaces/msg/Time`
//! and reliable, which matches no stock time source (they publish `rosgraph_msgs/msg/Clock`,
//! best-effort): hence this subscription of our own.

use std::sync::{Arc, Mutex};

use cell_msgs::{builtin_interfaces::Time, rosgraph_msgs::Clock};

use crate::{node::CellNode, pubsub::Subscriber, qos::QosPreset};

/// The topic a ROS 2 time source publishes on.
pub const CLOCK_TOPIC: &str = "/clock";

/// The latest `/clock` time, kept up to date by a task that ends when this is dropped.
pub(crate) struct SimulatedTime {
    latest: Arc<Mutex<Time>>,
    task: tokio::task::AbortHandle,
}

impl Drop for SimulatedTime {
    fn drop(&mut self) {
        self.task.abort();
    }
}

impl SimulatedTime {
    /// The last `/clock` time (zero before the first).
    pub(crate) fn now(&self) -> Time {
        *self.latest.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// Subscribes `node` to `/clock` and follows it.
///
/// # Errors
/// No tokio runtime on this thread; the subscription cannot be created.
pub(crate) fn follow_clock(node: &CellNode) -> anyhow::Result<SimulatedTime> {
    // `now()` may be asked from a plain thread; subscribing needs the runtime.
    let runtime = tokio::runtime::Handle::try_current()
        .map_err(|_| anyhow::anyhow!("no tokio runtime on this thread"))?;
    let _entered = runtime.enter();
    let mut clock = Subscriber::<Clock>::new(node, CLOCK_TOPIC, QosPreset::Clock)?;
    let latest = Arc::new(Mutex::new(Time::default()));
    let writer = latest.clone();
    let task = tokio::spawn(async move {
        while let Some(received) = clock.recv().await {
            *writer.lock().unwrap_or_else(|p| p.into_inner()) = received.message.clock;
        }
    });
    Ok(SimulatedTime {
        latest,
        task: task.abort_handle(),
    })
}
