//! Vendored `tf2_msgs` types.

use serde::{Deserialize, Serialize};

use crate::geometry_msgs::TransformStamped;

/// The message on `/tf` and `/tf_static` (`tf2_msgs/msg/TFMessage`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct TFMessage {
    /// Transforms, each from its `header.frame_id` to its `child_frame_id`.
    pub transforms: Vec<TransformStamped>,
}
