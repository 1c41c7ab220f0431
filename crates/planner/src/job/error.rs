//! Why a job is rejected or a plan fails.

use cell_profiles::EnvelopeViolation;

use crate::airfoil::AirfoilError;
use crate::kerf;
use crate::pso::PsoError;

use super::EMBEDDED_AIRFOILS;

/// A scalar parameter of a [`HotwireJob`](super::HotwireJob) that [`validate`](super::validate)
/// or [`plan`](super::plan) can reject. Written as the field's name (`chord_mm`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum JobParameter {
    /// `chord_mm`: the root chord.
    ChordMm,
    /// `feed_mm_s`: the cutting feed.
    FeedMmS,
    /// `current_a`: the wire current.
    CurrentA,
    /// `span_mm`: the panel span between the root and tip faces.
    SpanMm,
    /// `lead_in_mm`: the lead-in length.
    LeadInMm,
    /// `lead_in_max_mm`: the longest lead-in the optimiser may choose.
    LeadInMaxMm,
    /// `panels`: surface panels of the exposure model.
    Panels,
    /// `cse`: the target exposure.
    Cse,
    /// `tip_chord_mm`: the tip chord.
    TipChordMm,
    /// `tip_twist_deg`: the tip twist.
    TipTwistDeg,
    /// `tip_sweep_mm`: the tip's leading-edge sweep.
    TipSweepMm,
    /// `twist_pivot_chord_fraction`: the twist pivot along the tip chord.
    TwistPivotChordFraction,
    /// `offset_mm`: the wire offset (given, or from the kerf model).
    OffsetMm,
    /// `path_points`: the baseline path resolution.
    PathPoints,
    /// `particles`: PSO particles.
    Particles,
    /// `iterations`: PSO iterations.
    Iterations,
    /// `control_points`: spline control values of the path or the feed.
    ControlPoints,
    /// `refine_iterations`: Levenberg–Marquardt iterations after the swarm.
    RefineIterations,
}

impl JobParameter {
    /// The field's name, as the job and the planner's goal spell it.
    pub fn name(self) -> &'static str {
        match self {
            Self::ChordMm => "chord_mm",
            Self::FeedMmS => "feed_mm_s",
            Self::CurrentA => "current_a",
            Self::SpanMm => "span_mm",
            Self::LeadInMm => "lead_in_mm",
            Self::LeadInMaxMm => "lead_in_max_mm",
            Self::Panels => "panels",
            Self::Cse => "cse",
            Self::TipChordMm => "tip_chord_mm",
            Self::TipTwistDeg => "tip_twist_deg",
            Self::TipSweepMm => "tip_sweep_mm",
            Self::TwistPivotChordFraction => "twist_pivot_chord_fraction",
            Self::OffsetMm => "offset_mm",
            Self::PathPoints => "path_points",
            Self::Particles => "particles",
            Self::Iterations => "iterations",
            Self::ControlPoints => "control_points",
            Self::RefineIterations => "refine_iterations",
        }
    }
}

impl std::fmt::Display for JobParameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A rejected job or a failed plan. Messages are one line and name the airfoil or parameter.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// An airfoil name that is not embedded.
    #[error(
        "airfoil {name:?} is not a known name (known: {}) nor a .dat path",
        EMBEDDED_AIRFOILS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
    )]
    UnknownAirfoil {
        /// The name given.
        name: String,
    },
    /// Reading or building the section failed (names the file and line).
    #[error(transparent)]
    Airfoil(#[from] AirfoilError),
    /// A job parameter is out of its domain.
    #[error("{parameter} = {value} is invalid: must be {requirement}")]
    InvalidParameter {
        /// Which parameter (a command line or a goal maps it to its own name).
        parameter: JobParameter,
        /// The value given.
        value: f64,
        /// The accepted domain.
        requirement: &'static str,
    },
    /// Baseline, optimiser or exposure failure, with the airfoil it was planning.
    #[error("{airfoil}: {source}")]
    Plan {
        /// The airfoil source.
        airfoil: String,
        /// The underlying error.
        #[source]
        source: PsoError,
    },
    /// The machine profile cannot run this job.
    #[error("machine {machine:?} {reason}")]
    Machine {
        /// The profile name.
        machine: String,
        /// Why not.
        reason: String,
    },
    /// A carriage position outside the machine's travel.
    #[error("{what} point {point}: {violation}")]
    Envelope {
        /// `lead-in`, `cut` or `lead-out`.
        what: &'static str,
        /// Index of the point in that motion.
        point: usize,
        /// Which axis and by how much.
        #[source]
        violation: EnvelopeViolation,
    },
    /// The kerf model rejected a current schedule input.
    #[error(transparent)]
    Kerf(#[from] kerf::KerfError),
    /// The progress callback stopped the run.
    #[error("cancelled after {iteration} iterations")]
    Cancelled {
        /// Iterations done.
        iteration: usize,
    },
}
