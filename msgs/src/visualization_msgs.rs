//! Vendored `visualization_msgs` types.

use serde::{Deserialize, Serialize};

use crate::builtin_interfaces::Duration;
use crate::geometry_msgs::{Point, Pose, Vector3};
use crate::sensor_msgs::CompressedImage;
use crate::std_msgs::{ColorRGBA, Header};

/// A shape for RViz's Marker display and Foxglove's 3D panel (`visualization_msgs/msg/Marker`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct Marker {
    /// Time and frame.
    pub header: Header,
    /// Namespace; with `id` it names the marker.
    pub ns: String,
    /// Id within the namespace.
    pub id: i32,
    /// Shape: one of the type constants ([`Self::LINE_LIST`], …).
    #[serde(rename = "type")]
    pub type_: i32,
    /// [`Self::ADD`] (add or modify), [`Self::DELETE`] or [`Self::DELETEALL`].
    pub action: i32,
    /// Pose of the marker in `header.frame_id`.
    pub pose: Pose,
    /// Scale; for line markers `scale.x` is the line width (m).
    pub scale: Vector3,
    /// Colour, components in `[0, 1]`.
    pub color: ColorRGBA,
    /// How long the marker lasts; 0: forever.
    pub lifetime: Duration,
    /// Whether the marker is re-transformed into its frame every time step.
    pub frame_locked: bool,
    /// Points of list and strip shapes (m, in the marker's pose).
    pub points: Vec<Point>,
    /// Per-point colours: empty or one per point.
    pub colors: Vec<ColorRGBA>,
    /// Texture URI (or `embedded://name`).
    pub texture_resource: String,
    /// Embedded texture.
    pub texture: CompressedImage,
    /// Texture coordinates per vertex.
    pub uv_coordinates: Vec<UVCoordinate>,
    /// Text of text markers.
    pub text: String,
    /// Mesh URI (or `embedded://name`).
    pub mesh_resource: String,
    /// Embedded mesh.
    pub mesh_file: MeshFile,
    /// Whether an embedded mesh's own materials are used.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// Shape: arrow.
    pub const ARROW: i32 = 0;
    /// Shape: cube.
    pub const CUBE: i32 = 1;
    /// Shape: sphere.
    pub const SPHERE: i32 = 2;
    /// Shape: cylinder.
    pub const CYLINDER: i32 = 3;
    /// Shape: a line through `points` in order.
    pub const LINE_STRIP: i32 = 4;
    /// Shape: a line between each pair of `points`.
    pub const LINE_LIST: i32 = 5;
    /// Shape: a cube per point.
    pub const CUBE_LIST: i32 = 6;
    /// Shape: a sphere per point.
    pub const SPHERE_LIST: i32 = 7;
    /// Shape: points.
    pub const POINTS: i32 = 8;
    /// Shape: text facing the viewer.
    pub const TEXT_VIEW_FACING: i32 = 9;
    /// Shape: a mesh.
    pub const MESH_RESOURCE: i32 = 10;
    /// Shape: triangles.
    pub const TRIANGLE_LIST: i32 = 11;
    /// Shape: arrows along `points`.
    pub const ARROW_STRIP: i32 = 12;
    /// Action: add or modify.
    pub const ADD: i32 = 0;
    /// Action: add or modify (same as [`Self::ADD`]).
    pub const MODIFY: i32 = 0;
    /// Action: delete the marker `ns`/`id`.
    pub const DELETE: i32 = 2;
    /// Action: delete every marker (of `ns` if given).
    pub const DELETEALL: i32 = 3;
}

/// Several markers in one message (`visualization_msgs/msg/MarkerArray`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct MarkerArray {
    /// The markers, applied in order.
    pub markers: Vec<Marker>,
}

/// A texture coordinate (`visualization_msgs/msg/UVCoordinate`), each in `[0, 1]`.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
pub struct UVCoordinate {
    /// Horizontal ratio.
    pub u: f32,
    /// Vertical ratio.
    pub v: f32,
}

/// A raw mesh file (`visualization_msgs/msg/MeshFile`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct MeshFile {
    /// File name (its extension picks the parser).
    pub filename: String,
    /// The file's bytes.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}
