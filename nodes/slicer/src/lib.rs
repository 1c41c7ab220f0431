//! `cell_slicer`: the WAAM slicing path of issue 8 (seed 004) as one job, a ROS 2 node and the
//! pieces `cell slice` needs.
//!
//! - [`job`]: mesh → [`cell_mesh::slice()`] → placement on the build plate →
//!   [`cell_waam::plan_layer`] per layer (with a progress callback) → totals, cost breakdown
//!   (seed 004 eq. 1–6, 15–24) and a serde [`job::SliceReport`]; no ROS.
//! - [`wing`]: the G-Wing path (seed 002): wing spec → design → one section's layers → an
//!   extrusion `Toolpath`, a `LayerStack` of perimeters and mass/build-time figures; no ROS.
//! - [`to_msg`]: the sliced layers as a `cell_msgs::LayerStack`.
//! - [`node`]: the `slicer` node serving the `slice` action (`cell_msgs/action/Slice`),
//!   publishing `toolpath` and `layer_stack` and logging every layer to Rerun.

#![warn(missing_docs)]

pub mod job;
pub mod node;
pub mod to_msg;
pub mod wing;
