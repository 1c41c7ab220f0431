//! Standard-type views of the cell's messages, for RViz, Foxglove and any stock ROS 2 tool.
//!
//! The cell's own messages are in millimetres and custom types; these pure functions turn them
//! into the standard types those tools draw, in SI units (metres, radians) as REP-103 asks:
//!
//! - a `Toolpath` → `nav_msgs/Path` ([`toolpath_path()`]) and `visualization_msgs/MarkerArray`
//!   ([`toolpath_markers()`]: one line-list marker per segment kind and layer, coloured by kind);
//! - a `HeatMap` → `sensor_msgs/Image` in `32FC1` ([`heat_map_image()`]);
//! - `MachineStatus` → `sensor_msgs/JointState` ([`joint_state()`]), the tool frame as a tf2
//!   transform ([`tool_transform()`]) and `diagnostic_msgs/DiagnosticArray` ([`diagnostics()`]);
//! - a printer's heater readings → `sensor_msgs/Temperature` ([`temperature()`]), and their
//!   current and target temperatures among the diagnostics' values.
//!
//! Frames ([`frames`]): `cell` is the fixed frame; each message keeps its own frame id (e.g.
//! `sheet`, `hotwire_machine`), attached to `cell` by an identity transform
//! ([`frames::attach_to_cell`]); a machine's frame is its `machine_id` and its tool frame is
//! `<machine_id>/tool`. Topic names are in [`topics`].

pub mod diagnostics;
pub mod error;
pub mod frames;
pub mod heat_map_image;
pub mod joint_state;
pub mod kind_style;
pub mod temperature;
pub mod tool_transform;
pub mod toolpath_markers;
pub mod toolpath_path;
pub mod topics;
pub mod units;

pub use diagnostics::diagnostics;
pub use error::ViewError;
pub use heat_map_image::heat_map_image;
pub use joint_state::joint_state;
pub use temperature::{temperature, HeaterReading};
pub use tool_transform::tool_transform;
pub use toolpath_markers::toolpath_markers;
pub use toolpath_path::toolpath_path;
