//! Vendored `sensor_msgs` types.

use serde::{Deserialize, Serialize};

use crate::std_msgs::Header;

/// An uncompressed image (`sensor_msgs/msg/Image`); (0, 0) is the top-left pixel.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct Image {
    /// Acquisition time and frame.
    pub header: Header,
    /// Number of rows.
    pub height: u32,
    /// Number of columns.
    pub width: u32,
    /// Pixel encoding, e.g. `32FC1` (one 32-bit float per pixel), from `image_encodings.hpp`.
    pub encoding: String,
    /// 1 if the pixel data is big-endian.
    pub is_bigendian: u8,
    /// Full row length in bytes.
    pub step: u32,
    /// `step * height` bytes of pixel data.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// A compressed image (`sensor_msgs/msg/CompressedImage`); here only as a field of
/// `visualization_msgs/msg/Marker`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct CompressedImage {
    /// Acquisition time and frame.
    pub header: Header,
    /// Compression format, e.g. `jpeg` or `png`.
    pub format: String,
    /// The compressed image.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// The state of a set of joints (`sensor_msgs/msg/JointState`): positions in rad or m,
/// velocities in rad/s or m/s, efforts in N·m or N; each array as long as `name`, or empty.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct JointState {
    /// Time the states were recorded.
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions (rad or m).
    pub position: Vec<f64>,
    /// Velocities (rad/s or m/s).
    pub velocity: Vec<f64>,
    /// Efforts (N·m or N).
    pub effort: Vec<f64>,
}

/// A single temperature reading (`sensor_msgs/msg/Temperature`), °C.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct Temperature {
    /// Time of the measurement; `frame_id` is where it was taken.
    pub header: Header,
    /// The temperature, °C.
    pub temperature: f64,
    /// Its variance, °C²; 0: unknown.
    pub variance: f64,
}
