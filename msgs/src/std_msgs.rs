//! Vendored `std_msgs` types. `std_msgs/msg/String` is [`StringMsg`] so it cannot shadow
//! Rust's `String`.

use serde::{Deserialize, Serialize};

use crate::builtin_interfaces::Time;

/// Standard metadata for higher-level stamped data types: a timestamp and the coordinate
/// frame the data is in.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct Header {
    /// Two-integer timestamp that is expressed as seconds and nanoseconds.
    pub stamp: Time,
    /// Transform frame with which this data is associated.
    pub frame_id: String,
}

/// `std_msgs/msg/String` (deprecated upstream as of Foxy; kept for simple text topics).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct StringMsg {
    /// The text.
    pub data: String,
}

/// A colour in RGBA (`std_msgs/msg/ColorRGBA`), each component in `[0, 1]`.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
pub struct ColorRGBA {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Alpha (opacity).
    pub a: f32,
}
