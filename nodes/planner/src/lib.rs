//! `cell_planner`: the hot-wire planner's pure geometry and process-model library.
//!
//! - [`airfoil`]: UIUC `.dat` input (Selig and Lednicer, auto-detected) and the section geometry
//!   the wire follows: normalise, scale, twist, close the trailing edge, resample, and
//!   synchronise a root and a tip section point for point.
//! - [`kerf`]: the seed 001 hot-wire kerf model (Aitchison et al.), its five inverse forms, the
//!   constant-kerf current schedule, the wire-centre path offset and the foam/wire libraries.
//!
//! Everything here is synchronous and free of ROS/DDS. The surface exposure model (seed 000),
//! the PSO path optimiser and the planner node itself come next and build on these modules.

#![warn(missing_docs)]

pub mod airfoil;
pub mod kerf;
