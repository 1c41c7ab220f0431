//! WAAM process model after seed 004 (a master's thesis at BAE Systems Hägglunds: Matlab
//! slicer, cost model, RAPID export and CATIA workpiece for wire-arc additive manufacturing).
//! "Notes B1–B10" in its comments are part B of the implementer's notes,
//! `docs/notes/seed-notes-sheet-waam.md`.
//!
//! Pure library: no ROS, no I/O beyond writers given by the caller.
//!
//! - [`bead`]: bead width from travel and wire feed speed and its inverse (eq. 14, Chart 2),
//!   bead height (eq. 28), deposition rate (eq. 24).
//! - [`toolpath`]: per-layer toolpaths from [`toolpath::LayerPolygons`]: perimeters, zig-zag
//!   infill, the width-driven mid-wall mode, start spreading, dwell.
//! - [`rows`]: the thesis's toolpath rows `[X Y Z E C N LW/2 h k]` (eq. 7, eq. 12–13), the
//!   segment chainer (§4.3) and a CSV writer.
//! - [`allowance`]: the machining allowance a planned layer leaves around the part's section.
//! - [`cost`]: cost before and after the toolpath (eq. 1–6, 15–24, Chart 3).
//! - [`stock`]: the deposited beads as boxes in a binary STL for CAM (§4.8).
//! - [`process`]: the process profile (YAML, `config/processes/waam.yaml`).
//! - [`to_msg`]: the planned layers as a `cell_msgs::Toolpath` (kept apart from the algorithms).
//!
//! ```
//! use cell_waam::{plan_stack, LayerPolygons, WaamProcess};
//! use cell_waam::cost::{post_toolpath_cost, PartVolumes};
//! use cell_waam::toolpath::toolpath_totals;
//!
//! let square = vec![[0.0, 0.0], [80.0, 0.0], [80.0, 80.0], [0.0, 80.0]];
//! let layers: Vec<LayerPolygons> = (0..3)
//!     .map(|i| LayerPolygons {
//!         index: i,
//!         z_mm: 1.6 * (i + 1) as f64,
//!         outers_and_holes: vec![square.clone()],
//!     })
//!     .collect();
//! let process = WaamProcess::default();
//! let layers = plan_stack(&layers, &process).unwrap();
//! let cost = post_toolpath_cost(&process.cost, &PartVolumes::default(), &toolpath_totals(&layers));
//! assert!(cost.wire_sek > 0.0 && cost.deposition_sek > cost.wire_sek);
//! let mut stl = Vec::new();
//! cell_waam::stock::write_stock_stl(&mut stl, &cell_waam::stock::bead_boxes(&layers)).unwrap();
//! ```

pub mod allowance;
pub mod bead;
pub mod cost;
pub mod process;
pub mod rows;
pub mod stock;
pub mod to_msg;
pub mod toolpath;
pub mod torch;

pub use process::{ProcessError, WaamProcess, WidthMode, MAX_PERIMETERS};
pub use toolpath::{
    plan_layer, plan_stack, LayerPolygons, LayerToolpath, PathPoint, Segment, SegmentKind,
    SegmentRole, ToolpathError,
};
