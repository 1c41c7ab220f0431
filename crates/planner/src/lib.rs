//! `cell_planner`: the hot-wire planner's pure geometry and process-model library.
//!
//! - [`airfoil`]: UIUC `.dat` input (Selig and Lednicer, auto-detected) and the section geometry
//!   the wire follows: normalise, scale, twist, close the trailing edge, resample, and
//!   synchronise a root and a tip section point for point.
//! - [`kerf`]: the seed 001 hot-wire kerf model (Aitchison et al.), its five inverse forms, the
//!   constant-kerf current schedule, the wire-centre path offset and the foam/wire libraries.
//! - [`exposure`]: seed 000's surface thermal exposure (eq. 1–5), integrated in closed form over
//!   each wire segment, with the causal mask.
//! - [`trajectory`]: the fixed-offset baseline path, its periodic cubic B-spline normal
//!   displacement and the T ∩ G = ∅ feasibility test.
//! - [`pso`]: seed 000 §IV.C particle swarm optimisation of the path for uniform exposure.
//! - [`calibration`]: seed 000 §IV.D CSE calibration: the chord a path leaves for each CSE of a
//!   sweep, and the CSE a measured test-cut chord implies.
//! - [`wing`]: beyond the paper's 2-D cut: tapered, swept, twisted panels on a 4-axis cutter
//!   (root/tip synchronisation, projection onto the carriage planes, move timing).
//! - [`job`]: one planning job end to end (foil → offset → baseline → swarm → plan), with its
//!   `Toolpath` and `HeatMap` views.
//!
//! Everything here is synchronous and free of ROS, DDS, tokio and Rerun (checked by
//! `tests/architecture.rs`); the `planner` node (`nodes/planner`) serves it as the
//! `plan_hotwire` action.

#![warn(missing_docs)]

pub mod airfoil;
pub mod calibration;
pub mod exposure;
pub mod job;
pub mod kerf;
pub mod pso;
pub mod trajectory;
pub mod wing;
