//! `cell_slicer`: the WAAM slicing path of issue 8 (seed 004) as one job, and the pieces the
//! `slicer` node (`nodes/slicer`) and `cell slice` need. Pure: no ROS, DDS, tokio or Rerun.
//!
//! - [`job`]: mesh → [`cell_mesh::slice()`] → placement on the build plate →
//!   [`cell_waam::plan_layer`] per layer (with a progress callback and a cancel hook) → totals,
//!   cost breakdown (seed 004 eq. 1–6, 15–24) and a serde [`job::SliceReport`]; no ROS.
//! - [`wing`]: the G-Wing path (seed 002): wing spec → design → one section's layers → an
//!   extrusion `Toolpath`, a `LayerStack` of perimeters and mass/build-time figures; no ROS.
//! - [`to_msg`]: the sliced layers as a `cell_msgs::LayerStack`.

#![warn(missing_docs)]

pub mod job;
pub mod to_msg;
pub mod wing;
