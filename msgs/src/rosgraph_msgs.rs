//! Vendored `rosgraph_msgs` types.

use serde::{Deserialize, Serialize};

use crate::builtin_interfaces::Time;

/// `rosgraph_msgs/msg/Clock`: the current time of a ROS time source, published on `/clock`
/// (by `cell bag play --clock`, `ros2 bag play --clock` or a simulator) and followed by nodes
/// whose `use_sim_time` is true (<https://design.ros2.org/articles/clock_and_time.html>).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Clock {
    /// The time source's current time.
    pub clock: Time,
}
