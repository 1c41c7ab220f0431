//! Vendored `geometry_msgs` types.

use serde::{Deserialize, Serialize};

use crate::std_msgs::Header;

/// The position of a point in free space.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
pub struct Point {
    /// X coordinate.
    pub x: f64,
    /// Y coordinate.
    pub y: f64,
    /// Z coordinate.
    pub z: f64,
}

/// A vector in free space, anchored at the origin: transforms apply only their rotation to it.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
pub struct Vector3 {
    /// X component.
    pub x: f64,
    /// Y component.
    pub y: f64,
    /// Z component.
    pub z: f64,
}

/// An orientation in free space in quaternion form. Defaults to the identity (`w = 1`), as the
/// `.msg` defaults say.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct Quaternion {
    /// X component (default 0).
    pub x: f64,
    /// Y component (default 0).
    pub y: f64,
    /// Z component (default 0).
    pub z: f64,
    /// W component (default 1).
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// A pose in free space: position and orientation.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// A pose with a reference frame and timestamp (`geometry_msgs/msg/PoseStamped`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct PoseStamped {
    /// Frame and time of the pose.
    pub header: Header,
    /// The pose in `header.frame_id`.
    pub pose: Pose,
}

/// The transform between two coordinate frames (`geometry_msgs/msg/Transform`).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
pub struct Transform {
    /// Translation of the child frame's origin in the parent frame.
    pub translation: Vector3,
    /// Rotation of the child frame relative to the parent frame.
    pub rotation: Quaternion,
}

/// A transform from `header.frame_id` to `child_frame_id` at `header.stamp`
/// (`geometry_msgs/msg/TransformStamped`), as tf2 carries it.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct TransformStamped {
    /// Parent frame and time.
    pub header: Header,
    /// The frame the transform points to.
    pub child_frame_id: String,
    /// Pose of `child_frame_id` in `header.frame_id`.
    pub transform: Transform,
}
