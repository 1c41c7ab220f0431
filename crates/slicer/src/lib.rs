//! `cell_slicer`: the WAAM slicing path of issue 8 (seed 004) as one job, and the pieces the
//! `slicer` node (`nodes/slicer`) and `cell slice` need. Pure: no ROS, DDS, tokio or Rerun.
//!
//! - [`job`]: mesh → [`cell_mesh::slice()`] → placement on the build plate →
//!   [`cell_waam::plan_layer`] per layer (with a progress callback and a cancel hook) → totals,
//!   cost breakdown (seed 004 eq. 1–6, 15–24) and a serde [`job::SliceReport`]; no ROS.
//! - [`slab`]: the deposit layers: per layer slab, the union of the part's sections over the slab
//!   widened by the machining allowance, and enough layers to cover the top.
//! - [`wing`]: the G-Wing path (seed 002): wing spec → design → one section's layers → an
//!   extrusion `Toolpath`, a `LayerStack` of perimeters and mass/build-time figures; no ROS.
//! - [`to_msg`]: the sliced layers as a `cell_msgs::LayerStack`.
//! - [`picture`]: `slice.svg`, one layer and a side section with the part, the beads and the
//!   machining allowance.

#![warn(missing_docs)]

pub mod job;
pub mod picture;
pub mod slab;
pub mod to_msg;
pub mod wing;
