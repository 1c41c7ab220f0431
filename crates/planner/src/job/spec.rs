//! The job spec: what to cut (root and tip sections, span), on which machine, in which foam and
//! with which optimiser settings, and the checks a job passes before it is planned.

use cell_profiles::MachineProfile;

use crate::pso::{Objective, PsoConfig};
use crate::refine::RefineConfig;
use crate::wing::Placement;

use super::{AirfoilSource, JobError, JobParameter};

/// The tip section of a tapered panel (4-axis machines).
#[derive(Debug, Clone, PartialEq)]
pub struct TipSection {
    /// The tip airfoil (may differ from the root).
    pub airfoil: AirfoilSource,
    /// Tip chord (mm), > 0.
    pub chord_mm: f64,
    /// Sweep and twist relative to the root ([`Placement::apply`]).
    pub placement: Placement,
}

/// What a request (a goal, command-line options) says about the tip; `None` fields were not
/// given.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TipRequest<'a> {
    /// Tip airfoil (name or `.dat` path); default: the root's.
    pub airfoil: Option<&'a str>,
    /// Tip chord (mm); default: the root's.
    pub chord_mm: Option<f64>,
    /// Tip twist (degrees, nose up); default 0.
    pub twist_deg: Option<f64>,
    /// Tip leading-edge sweep (mm); default 0.
    pub sweep_mm: Option<f64>,
}

impl TipSection {
    /// The tip `request` asks for, completed from the root's airfoil and chord, or `None` if it
    /// names no tip field at all (a straight cut).
    pub fn requested(
        request: &TipRequest<'_>,
        root_airfoil: &AirfoilSource,
        root_chord_mm: f64,
        pivot_chord_fraction: f64,
    ) -> Option<Self> {
        if *request == TipRequest::default() {
            return None;
        }
        Some(Self {
            airfoil: request
                .airfoil
                .map_or_else(|| root_airfoil.clone(), AirfoilSource::parse),
            chord_mm: request.chord_mm.unwrap_or(root_chord_mm),
            placement: Placement {
                sweep_mm: request.sweep_mm.unwrap_or(0.0),
                twist_deg: request.twist_deg.unwrap_or(0.0),
                pivot_chord_fraction,
            },
        })
    }
}

/// One hot-wire cut to plan: a straight extrusion of the root section, or with a
/// [`HotwireJob::tip`] a tapered, swept, twisted panel on a 4-axis machine ([`crate::wing`]).
#[derive(Debug, Clone, PartialEq)]
pub struct HotwireJob {
    /// The root section to cut.
    pub root_airfoil: AirfoilSource,
    /// Root chord (mm), > 0.
    pub chord_mm: f64,
    /// The tip section; `None` (or one equal to the root): a straight cut.
    pub tip: Option<TipSection>,
    /// Panel span between the root and tip faces (mm), > 0, at most the room between the root
    /// face and the UV tower.
    pub span_mm: f64,
    /// The machine: tower geometry, travel, feed limit, wire and supply (`config/machines`).
    pub machine: MachineProfile,
    /// Foam name or alias in the material library (case-insensitive, e.g. `EPS`, `xps`).
    pub material: String,
    /// Nominal wire current (A): sets the default offset (kerf / 2 at this current and feed)
    /// and is the constant current when the material library cannot give a schedule.
    pub current_a: f64,
    /// Target exposure CSE; `None`: the baseline's mean exposure.
    pub cse: Option<f64>,
    /// Wire-centre offset from the faster face's surface (mm); `None`: kerf / 2 from the
    /// material library at `current_a` and `feed_mm_s`, else
    /// [`FALLBACK_OFFSET_MM`](super::FALLBACK_OFFSET_MM).
    pub offset_mm: Option<f64>,
    /// Surface panels N for the exposure (default 100): the profile has N values.
    pub panels: usize,
    /// Baseline path resolution (foil resampling before the offset); 0: 1.5 × `panels`.
    pub path_points: usize,
    /// Objective settings (exposure model, smoothing, clearance, control points); its `cse`
    /// is overridden by [`HotwireJob::cse`].
    pub objective: Objective,
    /// Swarm settings; its `seed` is overridden by [`HotwireJob::seed`].
    pub pso: PsoConfig,
    /// Local refinement after the swarm ([`crate::refine`]; `iterations: 0` switches it off).
    pub refine: RefineConfig,
    /// RNG seed; the same seed gives the same plan.
    pub seed: u64,
    /// Cutting feed of the faster foam face (mm/s).
    pub feed_mm_s: f64,
    /// Length of the straight lead-in and lead-out behind the trailing edge (mm).
    pub lead_in_mm: f64,
    /// The longest lead-in (mm) if its length is a design variable between
    /// [`HotwireJob::lead_in_mm`] and this (`None`, default: fixed at `lead_in_mm`). A longer
    /// lead-in heats the first panels cut; the block needs that much foam behind the trailing
    /// edge.
    pub lead_in_max_mm: Option<f64>,
}

/// The machine profile [`HotwireJob::default`] uses.
pub const DEFAULT_MACHINE: &str = "linuxcnc-xyuv";

impl Default for HotwireJob {
    /// s1223 at 200 mm, straight, 300 mm span on [`DEFAULT_MACHINE`], in H-grade EPS at 3 A and
    /// 15 mm/s (the seed 001 worked-example conditions), 100 panels, the paper's swarm.
    fn default() -> Self {
        Self {
            root_airfoil: AirfoilSource::Named("s1223".into()),
            chord_mm: 200.0,
            tip: None,
            span_mm: 300.0,
            // Embedded and tested (`cell_profiles`), so it always resolves.
            machine: MachineProfile::resolve(DEFAULT_MACHINE)
                .expect("embedded default machine profile"),
            material: "eps_h_grade".into(),
            current_a: 3.0,
            cse: None,
            offset_mm: None,
            panels: 100,
            path_points: 0,
            objective: Objective::default(),
            pso: PsoConfig::default(),
            refine: RefineConfig::default(),
            seed: 0,
            feed_mm_s: 15.0,
            lead_in_mm: 10.0,
            lead_in_max_mm: None,
        }
    }
}

/// Most surface panels N (issue 23: every size has a limit). The default is 100 and the paper's
/// plots use ~100–200; the limit is 10× the largest.
pub const MAX_PANELS: usize = 2_000;

/// Most baseline path points (default 1.5 × panels): 1.5 × [`MAX_PANELS`].
pub const MAX_PATH_POINTS: usize = 3_000;

/// Most PSO particles: the paper's swarm has 20; 50× that.
pub const MAX_PARTICLES: usize = 1_000;

/// Most PSO iterations: the paper runs 8 000; ~12× that.
pub const MAX_ITERATIONS: usize = 100_000;

/// Most spline control values of the path or the feed: defaults 32 and 16; ~30× that (a
/// value per few panels at [`MAX_PANELS`]).
pub const MAX_CONTROL_POINTS: usize = 1_000;

/// Most Levenberg–Marquardt iterations: the default is 60; it stops on its tolerance long
/// before.
pub const MAX_REFINE_ITERATIONS: usize = 1_000;

/// Most exposure kernel evaluations the swarm may make, particles × iterations × panels × path
/// points (issue 23: each cap alone still multiplies to days). The defaults make 2.4·10⁹
/// (20 × 8 000 × 100 × 150, under a minute); the limit is ~10× that.
pub const MAX_EXPOSURE_WORK: f64 = 2.5e10;

/// Checks a job's scalar parameters (cheap; [`plan`](super::plan) does it too).
///
/// # Errors
/// The first invalid parameter, named.
pub fn validate(job: &HotwireJob) -> Result<(), JobError> {
    let positive = |parameter, value: f64| {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(JobError::InvalidParameter {
                parameter,
                value,
                requirement: "finite and > 0",
            })
        }
    };
    positive(JobParameter::ChordMm, job.chord_mm)?;
    positive(JobParameter::FeedMmS, job.feed_mm_s)?;
    positive(JobParameter::CurrentA, job.current_a)?;
    positive(JobParameter::SpanMm, job.span_mm)?;
    if !(job.lead_in_mm.is_finite() && job.lead_in_mm >= 0.0) {
        return Err(JobError::InvalidParameter {
            parameter: JobParameter::LeadInMm,
            value: job.lead_in_mm,
            requirement: "finite and >= 0",
        });
    }
    if let Some(max) = job.lead_in_max_mm {
        if !(max.is_finite() && max >= job.lead_in_mm && job.lead_in_mm > 0.0) {
            return Err(JobError::InvalidParameter {
                parameter: JobParameter::LeadInMaxMm,
                value: max,
                requirement: "finite and >= lead_in_mm (which must be > 0)",
            });
        }
    }
    if job.panels < crate::airfoil::MIN_POINTS {
        return Err(JobError::InvalidParameter {
            parameter: JobParameter::Panels,
            value: job.panels as f64,
            requirement: "at least 5",
        });
    }
    let at_most = |parameter, value: usize, max: usize, requirement: &'static str| {
        if value <= max {
            Ok(())
        } else {
            Err(JobError::InvalidParameter {
                parameter,
                value: value as f64,
                requirement,
            })
        }
    };
    at_most(
        JobParameter::Panels,
        job.panels,
        MAX_PANELS,
        "at most 2000 (MAX_PANELS)",
    )?;
    at_most(
        JobParameter::PathPoints,
        job.path_points,
        MAX_PATH_POINTS,
        "at most 3000 (MAX_PATH_POINTS)",
    )?;
    at_most(
        JobParameter::Particles,
        job.pso.particles,
        MAX_PARTICLES,
        "at most 1000 (MAX_PARTICLES)",
    )?;
    at_most(
        JobParameter::Iterations,
        job.pso.iterations,
        MAX_ITERATIONS,
        "at most 100000 (MAX_ITERATIONS)",
    )?;
    let feed_controls = job.objective.feed.as_ref().map_or(0, |f| f.control_points);
    at_most(
        JobParameter::ControlPoints,
        job.objective.control_points.max(feed_controls),
        MAX_CONTROL_POINTS,
        "at most 1000 (MAX_CONTROL_POINTS)",
    )?;
    at_most(
        JobParameter::RefineIterations,
        job.refine.iterations,
        MAX_REFINE_ITERATIONS,
        "at most 1000 (MAX_REFINE_ITERATIONS)",
    )?;
    let path_points = if job.path_points == 0 {
        job.panels + job.panels / 2
    } else {
        job.path_points
    };
    let work =
        job.pso.particles as f64 * job.pso.iterations as f64 * (job.panels * path_points) as f64;
    if work > MAX_EXPOSURE_WORK {
        return Err(JobError::InvalidParameter {
            parameter: JobParameter::Iterations,
            value: job.pso.iterations as f64,
            requirement: "such that particles × iterations × panels × path points ≤ 2.5e10 \
                          (MAX_EXPOSURE_WORK)",
        });
    }
    if let Some(c) = job.cse {
        positive(JobParameter::Cse, c)?;
    }
    if let Some(tip) = &job.tip {
        positive(JobParameter::TipChordMm, tip.chord_mm)?;
        for (parameter, v) in [
            (JobParameter::TipTwistDeg, tip.placement.twist_deg),
            (JobParameter::TipSweepMm, tip.placement.sweep_mm),
            (
                JobParameter::TwistPivotChordFraction,
                tip.placement.pivot_chord_fraction,
            ),
        ] {
            if !v.is_finite() {
                return Err(JobError::InvalidParameter {
                    parameter,
                    value: v,
                    requirement: "finite",
                });
            }
        }
        if tip.placement.twist_deg.abs() > 45.0 {
            return Err(JobError::InvalidParameter {
                parameter: JobParameter::TipTwistDeg,
                value: tip.placement.twist_deg,
                requirement: "within ±45°",
            });
        }
    }
    let hw = job
        .machine
        .hotwire
        .as_ref()
        .ok_or_else(|| JobError::Machine {
            machine: job.machine.name.clone(),
            reason: "is not a hot-wire machine (no hotwire section)".into(),
        })?;
    if let Some(tip) = &job.tip {
        let tapered = tip.airfoil != job.root_airfoil
            || tip.chord_mm != job.chord_mm
            || tip.placement.sweep_mm != 0.0
            || tip.placement.twist_deg != 0.0;
        if tapered && !job.machine.is_four_axis_hotwire() {
            return Err(two_axis(&job.machine));
        }
    }
    let room = hw.tower_separation_mm - hw.root_plane_mm;
    if job.span_mm > room {
        return Err(JobError::InvalidParameter {
            parameter: JobParameter::SpanMm,
            value: job.span_mm,
            requirement: "at most the distance from the root face to the UV tower",
        });
    }
    Ok(())
}

pub(super) fn two_axis(machine: &MachineProfile) -> JobError {
    JobError::Machine {
        machine: machine.name.clone(),
        reason: "has no UV carriage: a tapered, swept or twisted panel needs a 4-axis machine"
            .into(),
    }
}
