//! Vendored `nav_msgs` types.

use serde::{Deserialize, Serialize};

use crate::geometry_msgs::PoseStamped;
use crate::std_msgs::Header;

/// An array of poses that represents a path for a robot to follow (`nav_msgs/msg/Path`); RViz's
/// Path display and Foxglove's 3D panel draw it as a line.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct Path {
    /// Frame of the path.
    pub header: Header,
    /// The poses, in order.
    pub poses: Vec<PoseStamped>,
}
