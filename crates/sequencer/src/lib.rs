//! `cell_sequencer`: the order in which a laser or plasma cutter cuts the contours of a nested
//! sheet, so that idle travel stays short and the sheet does not overheat (seed 003,
//! Verkhoturov et al. 2022, "Simulating Thermal Sheet Cutting of Figured Parts"; the
//! implementer's notes are `docs/notes/seed-notes-sheet-waam.md` §A0–A6, "notes §A…" below).
//!
//! - [`problem`]: the sequencing problem every algorithm works on: contours as closed
//!   polylines, their candidate pierce points, the start point and the [`precedence`] rules.
//! - [`precedence`]: which contours may be cut next (seed 003 §2, notes §A2/§A4), in strict or
//!   relaxed mode, and the check of a whole order.
//! - [`layout`]: the nested-layout model and its JSON format; conversion to a [`problem`] with
//!   precedence from the containment tree and free pierce candidates (seed 003 §A1, §2).
//! - [`containment`]: ring checks and the containment tree (seed 003 §A1 `IN` sets).
//! - [`dxf`]: DXF input with arc flattening and chaining of loose entities (issue 7), and the
//!   rule that finds the sheet.
//! - [`placement`]: where the sheet sits on the machine (the program cuts where the drawing
//!   says), and the machine-travel check (issue 19).
//! - [`generator`]: seeded realistic nested layouts, 50–5000 contours (issue 7).
//! - [`thermal`]: the discrete thermal raster of the sheet (seed 003 §A3) and our overheat
//!   metric.
//! - [`plan`] and [`cost`]: the cut plan, its metrics and the cost the improvement minimises.
//! - [`policy`]: the paper's greedy construction with its four `SelectContour` policies
//!   (seed 003 §A4).
//! - [`improve`]: precedence-safe local search and large-neighbourhood search on top.
//! - [`kerf`], [`leads`] and [`cut`]: cutting for real (issue 19): the cut path offset by half
//!   the kerf, lead-ins from the scrap side and lead-outs, applied to a layout's problem.
//! - [`job`]: one job end to end (layout → plan → final simulation with raster frames), what
//!   the `sequencer` node and `cell sheet` run.
//! - [`toolpath`]: a plan as the `cell_msgs` `Toolpath` (travel and cut segments) and
//!   `CutPlan` messages (notes §A6 outputs).
//! - [`plan_svg`]: the picture of a plan (`plan.svg`): sheet, parts, cuts, lead-ins, pierces,
//!   cut order, rapids and overheats, in machine coordinates (issue 19).
//! - [`fixtures`]: hand-built grid instances and a plasma cut spec for tests and the bench.
//!
//! Everything here is synchronous and free of ROS, DDS, tokio and Rerun (checked by
//! `tests/architecture.rs`); the `sequencer` node (`nodes/sequencer`) is a thin adapter over
//! [`job`] serving the `sequence_sheet` action.

#![warn(missing_docs)]

pub mod containment;
pub mod cut;
pub mod dxf;
pub mod generator;
pub mod layout;
pub mod placement;
pub mod precedence;
pub mod problem;

pub mod cost;
pub mod improve;
pub mod job;
pub mod kerf;
pub mod leads;
pub mod plan;
pub mod plan_svg;
pub mod policy;
pub mod thermal;
pub mod toolpath;

pub mod fixtures;
