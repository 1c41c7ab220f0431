//! One hot-wire planning job, end to end: load and scale the foil, pick the wire offset from the
//! kerf model, build the fixed-offset baseline, run the swarm ([`crate::pso::optimise`]) and
//! package the result as a [`HotwirePlan`] with its per-point feed and wire current, lead-in and
//! lead-out, exposure statistics and the `cell_msgs` views ([`HotwirePlan::to_toolpath`],
//! [`HotwirePlan::exposure_heat_map`], [`HotwirePlan::exposure_matrix_heat_map`]).
//!
//! Synchronous and free of ROS/DDS: the planner node runs [`plan`] on a blocking thread, the
//! `cell hotwire` command runs it directly.
//!
//! A straight cut plans the root section only. A tapered panel ([`HotwireJob::tip`]) plans the
//! tip section too, synchronises both paths point for point and projects them onto the
//! machine's carriage planes ([`crate::wing`]); every carriage position is checked against the
//! machine profile's travel ([`cell_profiles::MachineProfile`]).
//!
//! One file per concept:
//! - `spec`: the job ([`HotwireJob`], [`TipSection`]) and its checks ([`validate`]);
//!   `source`: where a section comes from ([`AirfoilSource`]); `error`: [`JobError`].
//! - `process`: the kerf-model side (offset and current schedule inputs, seed 001).
//! - `run`: orchestration ([`plan`], [`plan_observed`]).
//! - `motion`: motion timing (carriage moves, feeds, currents, travel check; [`Motion`]).
//! - `live`: live preview of the best path while the swarm runs ([`LiveMaps`]).
//! - `output`: what a job produces ([`HotwirePlan`], [`SectionPlan`], [`JobProgress`]).
//! - `views`: the `Toolpath` and `HeatMap` message views of a plan and their frame ids.
//! - `picture`: `exposure.svg`, the plan drawn for the operator ([`exposure_svg`]).

mod error;
mod live;
mod motion;
mod output;
mod picture;
mod process;
mod run;
mod source;
mod spec;
mod views;

pub use error::{JobError, JobParameter};
pub use live::{LiveMaps, LiveOptions};
pub use motion::Motion;
pub use output::{CalibrationRow, ExposureStats, HotwirePlan, JobProgress, SectionPlan};
pub use picture::{exposure_svg, PanelProfiles};
pub use process::FALLBACK_OFFSET_MM;
pub use run::{lead_in_start, plan, plan_observed, surface_points};
pub use source::{AirfoilSource, EMBEDDED_AIRFOILS};
pub use spec::{
    validate, HotwireJob, TipRequest, TipSection, DEFAULT_MACHINE, MAX_CONTROL_POINTS,
    MAX_EXPOSURE_WORK, MAX_ITERATIONS, MAX_PANELS, MAX_PARTICLES, MAX_PATH_POINTS,
    MAX_REFINE_ITERATIONS,
};
pub use views::{FRAME_ID, SECTION_FRAME_ID, TIP_FRAME_ID};

#[cfg(test)]
mod tests;
