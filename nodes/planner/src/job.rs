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

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::time::Instant;

use cell_msgs::{
    builtin_interfaces::Time, geometry_msgs::Point, std_msgs::Header, HeatMap, Toolpath,
    ToolpathSegment,
};
use cell_profiles::{EnvelopeViolation, HotwireGeometry, MachineProfile};
use nalgebra::{Point2, Vector2};

use crate::airfoil::{Airfoil, AirfoilError, SyncedPoints};
use crate::calibration::{predict_chords, ChordPrediction, Sweep};
use crate::exposure::{coefficient_of_variation, DistanceLaw, ExposureModel, Panels};
use crate::kerf::{self, CurrentLimits, MaterialLibrary};
use crate::pso::{self, Objective, Problem, PsoConfig, PsoError};
use crate::trajectory::{is_feasible, Baseline};
use crate::wing::{move_durations, synchronise_paths, Placement, Towers};

/// The UIUC sections shipped in `config/airfoils/`, compiled in: (name, `.dat` text).
pub const EMBEDDED_AIRFOILS: &[(&str, &str)] = &[
    ("ag24", include_str!("../../../config/airfoils/ag24.dat")),
    (
        "clarky",
        include_str!("../../../config/airfoils/clarky.dat"),
    ),
    ("e387", include_str!("../../../config/airfoils/e387.dat")),
    ("mh32", include_str!("../../../config/airfoils/mh32.dat")),
    (
        "naca0012",
        include_str!("../../../config/airfoils/naca0012.dat"),
    ),
    (
        "psu94097",
        include_str!("../../../config/airfoils/psu94097.dat"),
    ),
    ("rg15", include_str!("../../../config/airfoils/rg15.dat")),
    ("s1223", include_str!("../../../config/airfoils/s1223.dat")),
    (
        "sd7037",
        include_str!("../../../config/airfoils/sd7037.dat"),
    ),
];

/// Wire offset used when the material library cannot give one (mm).
pub const FALLBACK_OFFSET_MM: f64 = 0.5;

/// Where a section comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AirfoilSource {
    /// A name from [`EMBEDDED_AIRFOILS`] (case-insensitive, e.g. `s1223`).
    Named(String),
    /// A UIUC `.dat` file.
    File(PathBuf),
}

impl AirfoilSource {
    /// Interprets a user's string: a path if it contains a path separator or ends in `.dat`,
    /// or names no embedded section but an existing file; else an embedded name.
    pub fn parse(text: &str) -> Self {
        let looks_like_path = text.contains('/')
            || text.contains(std::path::MAIN_SEPARATOR)
            || text.to_ascii_lowercase().ends_with(".dat");
        if looks_like_path || (embedded(text).is_none() && std::path::Path::new(text).is_file()) {
            Self::File(PathBuf::from(text))
        } else {
            Self::Named(text.to_string())
        }
    }

    /// Reads the section (chord-normalised, as in the file).
    ///
    /// # Errors
    /// [`JobError::UnknownAirfoil`] for a name that is not embedded; [`JobError::Airfoil`]
    /// (naming the file and line) for an unreadable or malformed file.
    pub fn load(&self) -> Result<Airfoil, JobError> {
        match self {
            Self::Named(name) => {
                let (key, text) = embedded(name)
                    .ok_or_else(|| JobError::UnknownAirfoil { name: name.clone() })?;
                Ok(Airfoil::from_dat_str(
                    text,
                    &format!("config/airfoils/{key}.dat"),
                )?)
            }
            Self::File(path) => Ok(Airfoil::load(path)?),
        }
    }
}

impl std::fmt::Display for AirfoilSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Named(n) => f.write_str(n),
            Self::File(p) => write!(f, "{}", p.display()),
        }
    }
}

fn embedded(name: &str) -> Option<(&'static str, &'static str)> {
    EMBEDDED_AIRFOILS
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name))
        .copied()
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
    #[error("{name} = {value} is invalid: must be {requirement}")]
    InvalidParameter {
        /// Parameter name, e.g. `chord_mm`.
        name: &'static str,
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
    /// material library at `current_a` and `feed_mm_s`, else [`FALLBACK_OFFSET_MM`].
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
    /// RNG seed; the same seed gives the same plan.
    pub seed: u64,
    /// Cutting feed of the faster foam face (mm/s).
    pub feed_mm_s: f64,
    /// Length of the straight lead-in and lead-out behind the trailing edge (mm).
    pub lead_in_mm: f64,
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
            seed: 0,
            feed_mm_s: 15.0,
            lead_in_mm: 10.0,
        }
    }
}

/// Progress of a running job, reported after every iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JobProgress {
    /// Iterations done (1-based).
    pub iteration: usize,
    /// Iterations configured.
    pub total: usize,
    /// Best loss so far.
    pub best_loss: f64,
    /// Estimated time to completion (s), from the mean iteration time so far.
    pub eta_s: f64,
}

/// How uniform an exposure profile is around the target.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExposureStats {
    /// √(mean (E − CSE)²).
    pub rms: f64,
    /// max |E − CSE|.
    pub max_abs: f64,
    /// Coefficient of variation of E (std / mean).
    pub cv: f64,
}

impl ExposureStats {
    /// Statistics of `exposure` around `cse`.
    pub fn of(exposure: &[f64], cse: f64) -> Self {
        let n = exposure.len().max(1) as f64;
        Self {
            rms: (exposure.iter().map(|e| (e - cse).powi(2)).sum::<f64>() / n).sqrt(),
            max_abs: exposure.iter().map(|e| (e - cse).abs()).fold(0.0, f64::max),
            cv: coefficient_of_variation(exposure),
        }
    }
}

/// One row of [`HotwirePlan::chord_predictions`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CalibrationRow {
    /// The material CSE assumed.
    pub cse: f64,
    /// What a cut along the fixed-offset baseline would leave.
    pub baseline: ChordPrediction,
    /// What a cut along the optimised path would leave.
    pub optimised: ChordPrediction,
}

/// One section's plan, in the section's own frame (LE at the origin, chord along +x; mm).
#[derive(Debug, Clone, PartialEq)]
pub struct SectionPlan {
    /// Section name (from the `.dat` name line).
    pub airfoil: String,
    /// Chord (mm).
    pub chord_mm: f64,
    /// The scaled foil, Selig order.
    pub foil: Vec<Point2<f64>>,
    /// The resampled foil whose panels the exposure is evaluated on (N + 1 points).
    pub surface: Vec<Point2<f64>>,
    /// The fixed-offset baseline path (closed).
    pub baseline: Vec<Point2<f64>>,
    /// The path the wire follows on this face (closed): the optimised path, resampled point
    /// for point with the other face's on a tapered panel.
    pub optimised: Vec<Point2<f64>>,
    /// Wire-centre offset of the baseline (mm).
    pub offset_mm: f64,
    /// The exposure target CSE.
    pub cse: f64,
    /// Baseline exposure per panel.
    pub baseline_exposure: Vec<f64>,
    /// Exposure per panel along [`SectionPlan::optimised`].
    pub optimised_exposure: Vec<f64>,
    /// Baseline uniformity.
    pub baseline_stats: ExposureStats,
    /// Optimised uniformity.
    pub optimised_stats: ExposureStats,
    /// Loss of the baseline.
    pub baseline_loss: f64,
    /// Loss of the optimised path (as optimised, before any resampling).
    pub final_loss: f64,
    /// (iteration, best loss) at iteration 0 and at every improvement.
    pub loss_history: Vec<(usize, f64)>,
    /// Feed / nominal feed at each point of the optimised path as optimised (all 1 unless the
    /// feed is a variable, [`Objective::feed`]).
    pub feed_ratio: Vec<f64>,
}

/// A run of carriage moves in machine coordinates (mm, mm/s, A). Point k is reached by move
/// k − 1, which lasts max(‖ΔXY‖, ‖ΔUV‖) / `feed_mm_s[k]`; entry 0 repeats entry 1's values.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Motion {
    /// XY carriage positions (root tower).
    pub xy: Vec<Point2<f64>>,
    /// UV carriage positions (tip tower); equal to `xy` on a straight cut.
    pub uv: Vec<Point2<f64>>,
    /// Feed of the carriage that moves farther, per point (mm/s).
    pub feed_mm_s: Vec<f64>,
    /// Wire current per point (A).
    pub current_a: Vec<f64>,
}

impl Motion {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.xy.len()
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.xy.is_empty()
    }
}

/// A planned hot-wire cut (see the module docs): the root section's plan, the tip's on a
/// tapered panel, and the carriage moves.
#[derive(Debug, Clone, PartialEq)]
pub struct HotwirePlan {
    /// The root section (the only one on a straight cut).
    pub root: SectionPlan,
    /// Exposure model used (for [`HotwirePlan::exposure_matrix_heat_map`]).
    pub model: ExposureModel,
    /// The tip section on a tapered panel.
    pub tip: Option<SectionPlan>,
    /// Iterations run (both sections together on a tapered panel).
    pub iterations: usize,
    /// Wall time of the optimisation (s).
    pub seconds: f64,
    /// RNG seed used.
    pub seed: u64,
    /// The machine profile's name.
    pub machine: String,
    /// Tower geometry the carriage moves were projected with.
    pub towers: Towers,
    /// Where the root section's LE sits in XY machine coordinates (mm).
    pub part_origin: Vector2<f64>,
    /// How the tip section is placed relative to the root (ROOT on a straight cut).
    pub tip_placement: Placement,
    /// True if the machine has a UV carriage (the toolpath carries secondary points).
    pub four_axis: bool,
    /// Straight lead-in from behind the trailing edge to the first cut point.
    pub lead_in: Motion,
    /// The cut (closed: the last point repeats the first).
    pub cut: Motion,
    /// Straight lead-out from the last cut point back behind the trailing edge.
    pub lead_out: Motion,
    /// Notes for the operator (fallbacks taken, clamped currents, slowed moves).
    pub notes: Vec<String>,
}

/// The kerf-model side of a job: offset and current schedule inputs.
struct Process {
    offset_mm: f64,
    /// (Q_eff in J/m², R' in Ω/m) when the library has the material and wire.
    schedule: Option<(f64, f64)>,
    supply: CurrentLimits,
    notes: Vec<String>,
}

fn process(job: &HotwireJob, hw: &HotwireGeometry) -> Result<Process, JobError> {
    let lib = MaterialLibrary::builtin();
    let mut notes = Vec::new();
    let (foam, wire) = (lib.find_foam(&job.material), lib.find_wire(&hw.wire));
    let model = match (foam, wire) {
        (Some(foam), Some(wire)) => {
            let inputs = kerf::KerfInputs::for_cut(job.current_a, job.feed_mm_s * 1e-3, wire, foam);
            kerf::predict_kerf_m(&inputs)
                .and_then(|k| kerf::clamp_kerf_to_wire(k, wire.diameter_m))
                .ok()
                .map(|k| (k.kerf_m, foam, wire))
        }
        _ => None,
    };
    let offset_mm = match (job.offset_mm, &model) {
        (Some(o), _) => o,
        (None, Some((kerf_m, ..))) => kerf_m / 2.0 * 1e3,
        (None, None) => FALLBACK_OFFSET_MM,
    };
    if !(offset_mm.is_finite() && offset_mm > 0.0) {
        return Err(JobError::InvalidParameter {
            name: "offset_mm",
            value: offset_mm,
            requirement: "finite and > 0",
        });
    }
    let schedule = match &model {
        // The area energy that cuts a kerf of 2 × offset: Q_eff = λ · ρ_f · ^mass Q_eff (seed 001
        // eq. 4–6).
        Some((_, foam, wire)) => Some((
            2.0 * offset_mm * 1e-3 * foam.density_kg_m3 * foam.mass_energy_j_kg(),
            wire.resistance_ohm_per_m,
        )),
        None => {
            let what = match (foam, wire) {
                (None, _) => format!(
                    "material {:?} is not in the material library (known: {})",
                    job.material,
                    lib.foam_names().join(", ")
                ),
                (_, None) => format!("wire {:?} is not in the material library", hw.wire),
                _ => "the kerf model rejected the current/feed".to_string(),
            };
            notes.push(format!(
                "{what}: constant current {} A{}",
                job.current_a,
                if job.offset_mm.is_none() {
                    format!(", offset {FALLBACK_OFFSET_MM} mm")
                } else {
                    String::new()
                }
            ));
            None
        }
    };
    Ok(Process {
        offset_mm,
        schedule,
        supply: CurrentLimits {
            min_a: hw.supply_a[0],
            max_a: hw.supply_a[1],
        },
        notes,
    })
}

/// Checks a job's scalar parameters (cheap; [`plan`] does it too).
///
/// # Errors
/// The first invalid parameter, named.
pub fn validate(job: &HotwireJob) -> Result<(), JobError> {
    let positive = |name, value: f64| {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(JobError::InvalidParameter {
                name,
                value,
                requirement: "finite and > 0",
            })
        }
    };
    positive("chord_mm", job.chord_mm)?;
    positive("feed_mm_s", job.feed_mm_s)?;
    positive("current_a", job.current_a)?;
    positive("span_mm", job.span_mm)?;
    if !(job.lead_in_mm.is_finite() && job.lead_in_mm >= 0.0) {
        return Err(JobError::InvalidParameter {
            name: "lead_in_mm",
            value: job.lead_in_mm,
            requirement: "finite and >= 0",
        });
    }
    if job.panels < crate::airfoil::MIN_POINTS {
        return Err(JobError::InvalidParameter {
            name: "panels",
            value: job.panels as f64,
            requirement: "at least 5",
        });
    }
    if let Some(c) = job.cse {
        positive("cse", c)?;
    }
    if let Some(tip) = &job.tip {
        positive("tip_chord_mm", tip.chord_mm)?;
        for (name, v) in [
            ("tip_twist_deg", tip.placement.twist_deg),
            ("tip_sweep_mm", tip.placement.sweep_mm),
            (
                "twist_pivot_chord_fraction",
                tip.placement.pivot_chord_fraction,
            ),
        ] {
            if !v.is_finite() {
                return Err(JobError::InvalidParameter {
                    name,
                    value: v,
                    requirement: "finite",
                });
            }
        }
        if tip.placement.twist_deg.abs() > 45.0 {
            return Err(JobError::InvalidParameter {
                name: "tip_twist_deg",
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
            name: "span_mm",
            value: job.span_mm,
            requirement: "at most the distance from the root face to the UV tower",
        });
    }
    Ok(())
}

fn two_axis(machine: &MachineProfile) -> JobError {
    JobError::Machine {
        machine: machine.name.clone(),
        reason: "has no UV carriage: a tapered, swept or twisted panel needs a 4-axis machine"
            .into(),
    }
}

/// Plans `job` (module docs). `progress` is called after every iteration; returning
/// [`ControlFlow::Break`] stops the run with [`JobError::Cancelled`].
///
/// # Errors
/// Invalid parameters (named), an unknown or malformed airfoil (named, with file and line),
/// an infeasible baseline or other planning failure (with the airfoil), a path outside the
/// machine's travel, cancellation.
pub fn plan(
    job: &HotwireJob,
    progress: impl FnMut(&JobProgress) -> ControlFlow<()>,
) -> Result<HotwirePlan, JobError> {
    plan_observed(job, &LiveOptions::default(), |_| {}, progress)
}

/// What [`plan_section`] needs besides the foil.
struct SectionJob<'a> {
    job: &'a HotwireJob,
    name: &'a str,
    offset_mm: f64,
    /// Frame id of its heat maps.
    frame_id: &'static str,
    /// Iterations already run by earlier sections, and the total over all sections.
    iterations_before: usize,
    iterations_total: usize,
    started: Instant,
}

/// Plans one section (`foil`: normalised and scaled to `chord_mm`): baseline at `offset_mm`,
/// swarm, exposure before and after.
fn plan_section(
    s: &SectionJob<'_>,
    foil: &Airfoil,
    chord_mm: f64,
    live: &mut Live<'_, impl FnMut(LiveMaps)>,
    progress: &mut impl FnMut(&JobProgress) -> ControlFlow<()>,
) -> Result<(SectionPlan, usize), JobError> {
    let job = s.job;
    let wrap = |source: PsoError| JobError::Plan {
        airfoil: s.name.to_string(),
        source,
    };
    let path_points = if job.path_points == 0 {
        job.panels + job.panels / 2
    } else {
        job.path_points
    };
    let baseline =
        Baseline::fixed_offset(foil, s.offset_mm, path_points).map_err(|e| wrap(e.into()))?;
    let objective = Objective {
        cse: job.cse,
        // Only the root's feed is a variable: the wire has one timing for both faces.
        feed: if s.frame_id == SECTION_FRAME_ID {
            job.objective.feed
        } else {
            None
        },
        ..job.objective
    };
    // A sharp trailing edge repeats its point at both ends: one more point gives N panels.
    let surface_points = surface_points(foil, job.panels)?;
    let problem = Problem::new(foil, surface_points, baseline, objective).map_err(wrap)?;
    let k = problem.trajectory().control_points();
    let baseline_exposure = problem.exposure(&vec![0.0; k]).map_err(wrap)?;
    live.show(&problem, &vec![0.0; k], 0, s.frame_id);
    let config = PsoConfig {
        seed: job.seed,
        ..job.pso
    };
    let result = pso::optimise(&problem, &config, |p| {
        let done = s.iterations_before + p.iteration;
        if p.improved && live.due() {
            live.show(&problem, p.best_controls, done, s.frame_id);
        }
        let elapsed = s.started.elapsed().as_secs_f64();
        let eta_s = elapsed / done.max(1) as f64 * s.iterations_total.saturating_sub(done) as f64;
        progress(&JobProgress {
            iteration: done,
            total: s.iterations_total,
            best_loss: p.best_loss,
            eta_s,
        })
    })
    .map_err(wrap)?;
    if result.cancelled {
        return Err(JobError::Cancelled {
            iteration: s.iterations_before + result.iterations_run,
        });
    }
    let optimised = problem.path(&result.controls);
    let optimised_exposure = problem.exposure(&result.controls).map_err(wrap)?;
    let cse = problem.cse();
    // Point k is reached by segment k − 1; point 0 takes segment 0's ratio.
    let segment_ratios = problem.feed_ratios(&result.controls);
    let mut feed_ratio = Vec::with_capacity(optimised.len());
    feed_ratio.push(segment_ratios.first().copied().unwrap_or(1.0));
    feed_ratio.extend_from_slice(&segment_ratios);
    let plan = SectionPlan {
        feed_ratio,
        airfoil: foil.name().to_string(),
        chord_mm,
        foil: foil.points().to_vec(),
        surface: foil.resampled_cosine(surface_points)?.points().to_vec(),
        baseline: problem.path(&vec![0.0; k]),
        optimised,
        offset_mm: s.offset_mm,
        cse,
        baseline_stats: ExposureStats::of(&baseline_exposure, cse),
        optimised_stats: ExposureStats::of(&optimised_exposure, cse),
        baseline_exposure,
        optimised_exposure,
        baseline_loss: result.baseline_loss,
        final_loss: result.best_loss,
        loss_history: result.history,
    };
    Ok((plan, result.iterations_run))
}

/// Closed perimeter of a foil (mm).
fn perimeter_mm(foil: &Airfoil) -> f64 {
    let p = foil.points();
    (0..p.len())
        .map(|i| (p[(i + 1) % p.len()] - p[i]).norm())
        .sum()
}

/// [`plan`], also handing `on_maps` the exposure profile and the wire × panel matrix of the
/// baseline before each section's swarm starts, and of the best path so far whenever it
/// improved and at least [`LiveOptions::period`] has passed, so a caller can show the
/// optimisation as it runs.
///
/// On a tapered panel both sections are optimised (root first, then tip, each with the full
/// iteration count). The faster face is cut at [`HotwireJob::feed_mm_s`] with the kerf-model
/// offset; the slower face moves slower by the ratio of the perimeters and, at the one wire
/// current, melts a kerf wider by the inverse ratio (seed 001 eq. 5: λ ∝ 1/v), so its baseline
/// offset is scaled up by that ratio.
///
/// # Errors
/// As [`plan`].
pub fn plan_observed(
    job: &HotwireJob,
    options: &LiveOptions,
    on_maps: impl FnMut(LiveMaps),
    mut progress: impl FnMut(&JobProgress) -> ControlFlow<()>,
) -> Result<HotwirePlan, JobError> {
    let mut live = Live {
        options,
        last: None,
        sink: on_maps,
    };
    validate(job)?;
    let hw = job
        .machine
        .hotwire
        .as_ref()
        .expect("validate checked the hotwire section");
    let four_axis = job.machine.is_four_axis_hotwire();
    let root_loaded = job.root_airfoil.load()?;
    let root_foil = root_loaded.normalised().scaled(job.chord_mm)?;
    // The tip, normalised and scaled, unless it is the root again (a straight cut).
    let tip = match &job.tip {
        Some(t) => {
            let loaded = t.airfoil.load()?;
            let straight = loaded.points() == root_loaded.points()
                && t.chord_mm == job.chord_mm
                && t.placement.sweep_mm == 0.0
                && t.placement.twist_deg == 0.0;
            if straight {
                None
            } else {
                Some((t, loaded.normalised().scaled(t.chord_mm)?))
            }
        }
        None => None,
    };
    if tip.is_some() && !four_axis {
        return Err(two_axis(&job.machine));
    }
    let proc = process(job, hw)?;
    let mut notes = proc.notes.clone();

    // Offsets: the longer section is the faster face (nominal offset), the other is wider.
    let (root_offset, tip_offset) = match &tip {
        Some((_, tip_foil)) => {
            let ratio = perimeter_mm(&root_foil) / perimeter_mm(tip_foil);
            if ratio >= 1.0 {
                (proc.offset_mm, proc.offset_mm * ratio)
            } else {
                (proc.offset_mm / ratio, proc.offset_mm)
            }
        }
        None => (proc.offset_mm, proc.offset_mm),
    };
    let sections = if tip.is_some() { 2 } else { 1 };
    let started = Instant::now();
    let root_name = job.root_airfoil.to_string();
    let section_job = |name, offset_mm, frame_id, before| SectionJob {
        job,
        name,
        offset_mm,
        frame_id,
        iterations_before: before,
        iterations_total: job.pso.iterations * sections,
        started,
    };
    let (mut root, mut iterations) = plan_section(
        &section_job(&root_name, root_offset, SECTION_FRAME_ID, 0),
        &root_foil,
        job.chord_mm,
        &mut live,
        &mut progress,
    )?;
    let tip_plan = match &tip {
        Some((t, tip_foil)) => {
            let name = t.airfoil.to_string();
            let (plan, n) = plan_section(
                &section_job(&name, tip_offset, TIP_FRAME_ID, iterations),
                tip_foil,
                t.chord_mm,
                &mut live,
                &mut progress,
            )?;
            iterations += n;
            Some(plan)
        }
        None => None,
    };
    let seconds = started.elapsed().as_secs_f64();

    // Point-for-point root and tip paths, in each section's frame.
    let (root_cut, tip_cut) = match &tip_plan {
        Some(t) => {
            let (r, tp) = synchronised(job, &root, t)?;
            Some((r, tp))
        }
        None => None,
    }
    .unwrap_or_else(|| (root.optimised.clone(), root.optimised.clone()));
    let mut tip_plan = tip_plan;
    // Feed ratios at the cut points: as optimised, or carried onto the resampled points by arc
    // length (the resampled points lie on the optimised path).
    let cut_ratios = if tip_plan.is_some() {
        along_arc(&root.optimised, &root.feed_ratio, &root_cut)
    } else {
        root.feed_ratio.clone()
    };
    if let Some(t) = tip_plan.as_mut() {
        refresh_exposure(job, &mut root, &root_cut, &cut_ratios)?;
        refresh_exposure(job, t, &tip_cut, &vec![1.0; tip_cut.len()])?;
    }

    // Leads: straight along each chord line, from behind the TE.
    let behind_te = |s: &SectionPlan| {
        let foil = &s.foil;
        let te = nalgebra::center(&foil[0], &foil[foil.len() - 1]);
        te + Vector2::new(job.lead_in_mm + s.offset_mm, 0.0)
    };
    let root_out = behind_te(&root);
    let (tip_section, tip_chord, placement) = match (&tip_plan, &tip) {
        (Some(t), Some((spec, _))) => (t, t.chord_mm, spec.placement),
        _ => (&root, job.chord_mm, Placement::ROOT),
    };
    let tip_out = behind_te(tip_section);
    let origin = Vector2::new(hw.part_origin_mm[0], hw.part_origin_mm[1]);
    let towers = Towers {
        separation_mm: hw.tower_separation_mm,
        root_plane_mm: hw.root_plane_mm,
        tip_plane_mm: hw.root_plane_mm + job.span_mm,
    };
    let place = |r: &[Point2<f64>], t: &[Point2<f64>]| -> (Vec<Point2<f64>>, Vec<Point2<f64>>) {
        r.iter()
            .zip(t)
            .map(|(r, t)| (r + origin, placement.apply(tip_chord, *t) + origin))
            .unzip()
    };
    let mover = Mover {
        towers,
        feed_mm_s: job.feed_mm_s,
        max_feed_mm_s: job.machine.max_feed_mm_s,
        // With the feed a variable the current stays constant (see `FeedVariable`).
        schedule: proc.schedule.filter(|_| job.objective.feed.is_none()),
        supply: proc.supply,
        current_a: job.current_a,
    };
    let (r, t) = place(&[root_out, root_cut[0]], &[tip_out, tip_cut[0]]);
    let lead_in = mover.motion(&r, &t, &[1.0; 2], &mut notes)?;
    let (r, t) = place(&root_cut, &tip_cut);
    let cut = mover.motion(&r, &t, &cut_ratios, &mut notes)?;
    let last = root_cut.len() - 1;
    let (r, t) = place(&[root_cut[last], root_out], &[tip_cut[last], tip_out]);
    let lead_out = mover.motion(&r, &t, &[1.0; 2], &mut notes)?;
    for (what, m) in [
        ("lead-in", &lead_in),
        ("cut", &cut),
        ("lead-out", &lead_out),
    ] {
        check_envelope(&job.machine, four_axis, what, m)?;
    }
    root.optimised = root_cut;
    if let Some(t) = tip_plan.as_mut() {
        t.optimised = tip_cut;
    }
    Ok(HotwirePlan {
        root,
        model: job.objective.model,
        tip: tip_plan,
        iterations,
        seconds,
        seed: job.seed,
        machine: job.machine.name.clone(),
        towers,
        part_origin: origin,
        tip_placement: placement,
        four_axis,
        lead_in,
        cut,
        lead_out,
        notes,
    })
}

/// Resamples the two optimised paths point for point ([`synchronise_paths`]) finely enough
/// that both keep the clearance (3×, then up to 12× the longer path's point count).
fn synchronised(
    job: &HotwireJob,
    root: &SectionPlan,
    tip: &SectionPlan,
) -> Result<SyncedPoints, JobError> {
    let base = root.optimised.len().max(tip.optimised.len());
    let clearance = job.objective.min_clearance_mm;
    let mut last_gap = 0.0;
    for factor in [3, 6, 12] {
        let (r, t) = synchronise_paths(&root.optimised, &tip.optimised, base * factor + 1)?;
        if is_feasible(&r, &root.foil, clearance) && is_feasible(&t, &tip.foil, clearance) {
            return Ok((r, t));
        }
        last_gap = crate::trajectory::clearance_mm(&r, &root.foil, f64::INFINITY).min(
            crate::trajectory::clearance_mm(&t, &tip.foil, f64::INFINITY),
        );
    }
    Err(JobError::Plan {
        airfoil: root.airfoil.clone(),
        source: PsoError::InfeasibleBaseline {
            clearance_mm: last_gap,
        },
    })
}

/// `values` (one per point of `path`) carried onto `onto` (points lying on `path`) by
/// normalised arc length, linearly interpolated.
fn along_arc(path: &[Point2<f64>], values: &[f64], onto: &[Point2<f64>]) -> Vec<f64> {
    let arc = |p: &[Point2<f64>]| {
        let mut s = vec![0.0];
        for w in p.windows(2) {
            s.push(s[s.len() - 1] + (w[1] - w[0]).norm());
        }
        let total = s[s.len() - 1].max(f64::MIN_POSITIVE);
        s.iter().map(|v| v / total).collect::<Vec<f64>>()
    };
    let (from, to) = (arc(path), arc(onto));
    to.iter()
        .map(|&u| {
            let j = from.partition_point(|&v| v < u).clamp(1, from.len() - 1);
            let (u0, u1) = (from[j - 1], from[j]);
            let t = if u1 > u0 { (u - u0) / (u1 - u0) } else { 0.0 };
            values[j - 1] + t * (values[j] - values[j - 1])
        })
        .collect()
}

/// Recomputes a section's optimised exposure and statistics along `path` (the resampled path
/// the wire really follows) with feed ratio `ratios` at its points.
fn refresh_exposure(
    job: &HotwireJob,
    section: &mut SectionPlan,
    path: &[Point2<f64>],
    ratios: &[f64],
) -> Result<(), JobError> {
    let wrap = |e: crate::exposure::ExposureError| JobError::Plan {
        airfoil: section.airfoil.clone(),
        source: e.into(),
    };
    let panels = Panels::from_points(&section.surface).map_err(wrap)?;
    let mut wire = crate::exposure::WireSegments::from_points(path).map_err(wrap)?;
    let weights: Vec<f64> = ratios[1..].iter().map(|r| 1.0 / r).collect();
    wire.set_weights(&weights).map_err(wrap)?;
    section.optimised_exposure = vec![0.0; panels.len()];
    job.objective
        .model
        .exposure_into(&panels, &wire, &mut section.optimised_exposure)
        .map_err(wrap)?;
    section.optimised_stats = ExposureStats::of(&section.optimised_exposure, section.cse);
    Ok(())
}

/// Turns placed root/tip face points into carriage moves with feeds and currents.
struct Mover {
    towers: Towers,
    feed_mm_s: f64,
    max_feed_mm_s: f64,
    schedule: Option<(f64, f64)>,
    supply: CurrentLimits,
    current_a: f64,
}

impl Mover {
    /// Moves through the placed face points `root`, `tip` (machine XY frame): each lasts long
    /// enough for the faster face to run at the feed times `feed_ratio` of the point it
    /// reaches ([`move_durations`]) and for the faster
    /// carriage to stay within the machine's feed limit; the wire current follows the faster
    /// face's speed (seed 001 constant-kerf schedule).
    fn motion(
        &self,
        root: &[Point2<f64>],
        tip: &[Point2<f64>],
        feed_ratio: &[f64],
        notes: &mut Vec<String>,
    ) -> Result<Motion, JobError> {
        let (xy, uv): (Vec<_>, Vec<_>) = root
            .iter()
            .zip(tip)
            .map(|(r, t)| self.towers.project(*r, *t))
            .unzip();
        let mut durations = move_durations(root, tip, self.feed_mm_s);
        // Move k reaches point k + 1 at that point's feed ratio.
        for (d, r) in durations.iter_mut().zip(&feed_ratio[1..]) {
            *d /= r;
        }
        let mut slowed = 0;
        let mut carriage_feed = Vec::with_capacity(durations.len());
        let mut face_speed = Vec::with_capacity(durations.len());
        for (k, d) in durations.iter_mut().enumerate() {
            let carriage = (xy[k + 1] - xy[k]).norm().max((uv[k + 1] - uv[k]).norm());
            if *d > 0.0 && carriage / *d > self.max_feed_mm_s {
                *d = carriage / self.max_feed_mm_s;
                slowed += 1;
            }
            let face = (root[k + 1] - root[k])
                .norm()
                .max((tip[k + 1] - tip[k]).norm());
            if *d > 0.0 {
                carriage_feed.push(carriage / *d);
                face_speed.push(face / *d);
            } else {
                carriage_feed.push(self.feed_mm_s);
                face_speed.push(self.feed_mm_s);
            }
        }
        if slowed > 0 {
            notes.push(format!(
                "{slowed} moves slowed to the machine's feed limit {} mm/s (the carriages move \
                 farther than the foam faces)",
                self.max_feed_mm_s
            ));
        }
        let currents: Vec<f64> = match self.schedule {
            Some((q_eff, r)) => {
                let schedule = kerf::current_schedule(&face_speed, q_eff, r, self.supply)?;
                let clamped = schedule.iter().filter(|s| s.clamped).count();
                if clamped > 0 {
                    notes.push(format!(
                        "{clamped} of {} current set-points clamped to the supply limits \
                         {}..{} A: the kerf deviates there",
                        schedule.len(),
                        self.supply.min_a,
                        self.supply.max_a
                    ));
                }
                schedule.iter().map(|s| s.current_a).collect()
            }
            None => vec![self.current_a; face_speed.len()],
        };
        // Point k is reached by move k − 1; point 0 takes move 0's values.
        let per_point = |v: &[f64]| {
            let mut out = Vec::with_capacity(v.len() + 1);
            out.push(v.first().copied().unwrap_or(self.feed_mm_s));
            out.extend_from_slice(v);
            out
        };
        Ok(Motion {
            xy,
            uv,
            feed_mm_s: per_point(&carriage_feed),
            current_a: per_point(&currents),
        })
    }
}

/// Checks every carriage position of `motion` against the machine's travel.
fn check_envelope(
    machine: &MachineProfile,
    four_axis: bool,
    what: &'static str,
    motion: &Motion,
) -> Result<(), JobError> {
    for (k, (xy, uv)) in motion.xy.iter().zip(&motion.uv).enumerate() {
        let mut position = vec![('X', xy.x), ('Y', xy.y)];
        if let (true, Some([u, v])) = (four_axis, machine.second_carriage_axes()) {
            position.extend([(u, uv.x), (v, uv.y)]);
        }
        machine
            .check_position(&position)
            .map_err(|violation| JobError::Envelope {
                what,
                point: k,
                violation,
            })?;
    }
    Ok(())
}

/// How many resampled points give `panels` distinct surface panels on `foil`.
fn surface_points(foil: &Airfoil, panels: usize) -> Result<usize, JobError> {
    let probe = foil.resampled_cosine(panels)?;
    let pts = probe.points();
    Ok(if pts.first() == pts.last() {
        panels + 1
    } else {
        panels
    })
}

/// Frame id of the planner's toolpaths: the hot-wire machine's coordinates (XY carriage plane
/// at z = 0, UV at z = tower separation).
pub const FRAME_ID: &str = "hotwire_machine";

/// Frame id of the planner's root-section exposure heat maps (LE at the origin).
pub const SECTION_FRAME_ID: &str = "hotwire_root";

/// Frame id of the tip-section exposure heat maps of a tapered panel.
pub const TIP_FRAME_ID: &str = "hotwire_tip";

/// How often [`plan_observed`] hands out the current best's heat maps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveOptions {
    /// Least time between two updates (default 1 s); `None`: only the baselines.
    pub period: Option<std::time::Duration>,
}

impl Default for LiveOptions {
    fn default() -> Self {
        Self {
            period: Some(std::time::Duration::from_secs(1)),
        }
    }
}

/// The current best path's exposure while planning ([`plan_observed`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LiveMaps {
    /// Iterations done when it was computed (0: the baseline).
    pub iteration: usize,
    /// 1 × N exposure profile (`exposure_profile`).
    pub profile: HeatMap,
    /// M × N wire × panel contributions (`wire_exposure`).
    pub matrix: HeatMap,
}

/// Rate-limited producer of [`LiveMaps`].
struct Live<'a, F> {
    options: &'a LiveOptions,
    last: Option<Instant>,
    sink: F,
}

impl<F: FnMut(LiveMaps)> Live<'_, F> {
    fn due(&self) -> bool {
        match (self.options.period, self.last) {
            (None, _) => false,
            (Some(_), None) => true,
            (Some(p), Some(t)) => t.elapsed() >= p,
        }
    }

    /// Computes and hands out the maps of `controls` (skipped if the path is degenerate).
    fn show(&mut self, problem: &Problem, controls: &[f64], iteration: usize, frame: &str) {
        let model = problem.objective().model;
        let (Ok(exposure), Ok((rows, cols, values))) = (
            problem.exposure(controls),
            problem.exposure_matrix(controls),
        ) else {
            return;
        };
        let mut profile = profile_map(model, problem.cse(), &exposure);
        let mut matrix = heat_map(model, problem.cse(), "wire_exposure", cols, rows, values);
        profile.header.frame_id = frame.into();
        matrix.header.frame_id = frame.into();
        self.last = Some(Instant::now());
        (self.sink)(LiveMaps {
            iteration,
            profile,
            matrix,
        });
    }
}

impl HotwirePlan {
    /// True if the root path (and the tip path, on a tapered panel) keeps `min_clearance_mm`
    /// from its foil (T ∩ G = ∅).
    pub fn is_feasible(&self, min_clearance_mm: f64) -> bool {
        is_feasible(&self.root.optimised, &self.root.foil, min_clearance_mm)
            && self
                .tip
                .as_ref()
                .is_none_or(|t| is_feasible(&t.optimised, &t.foil, min_clearance_mm))
    }

    /// The foils and the wire paths on their faces in machine coordinates (x, y, z along the
    /// wire from the XY plane): `[(name, points)]` for the root foil and path at the root face
    /// and, on a tapered panel, the tip's at the tip face. Closed polylines.
    pub fn placed_sections(&self) -> Vec<(&'static str, Vec<[f64; 3]>)> {
        let place = |pts: &[Point2<f64>], chord: f64, placement: &Placement, z: f64| {
            let mut out: Vec<[f64; 3]> = pts
                .iter()
                .map(|p| {
                    let q = placement.apply(chord, *p) + self.part_origin;
                    [q.x, q.y, z]
                })
                .collect();
            if out.first() != out.last() {
                out.extend(out.first().copied());
            }
            out
        };
        let root_chord = self.root.chord_mm;
        let zr = self.towers.root_plane_mm;
        let mut out = vec![
            (
                "root_foil",
                place(&self.root.foil, root_chord, &Placement::ROOT, zr),
            ),
            (
                "root_path",
                place(&self.root.optimised, root_chord, &Placement::ROOT, zr),
            ),
        ];
        if let Some(t) = &self.tip {
            let zt = self.towers.tip_plane_mm;
            out.push((
                "tip_foil",
                place(&t.foil, t.chord_mm, &self.tip_placement, zt),
            ));
            out.push((
                "tip_path",
                place(&t.optimised, t.chord_mm, &self.tip_placement, zt),
            ));
        }
        out
    }

    /// Every carriage position of the plan (lead-in, cut, lead-out) as (XY, UV) pairs, in
    /// order, without the repeated points where the motions meet.
    pub fn carriage_positions(&self) -> Vec<(Point2<f64>, Point2<f64>)> {
        let mut out: Vec<(Point2<f64>, Point2<f64>)> = Vec::new();
        for m in [&self.lead_in, &self.cut, &self.lead_out] {
            for p in m.xy.iter().copied().zip(m.uv.iter().copied()) {
                if out.last() != Some(&p) {
                    out.push(p);
                }
            }
        }
        out
    }

    /// The plan as a hot-wire `Toolpath` in machine coordinates (frame [`FRAME_ID`], wire
    /// current in A): LEAD in, CUT (closed), LEAD out. `points` are the XY carriage at z = 0;
    /// on a 4-axis machine `secondary_points` are the UV carriage at z = tower separation and
    /// `plane_separation_mm` is that separation. Feeds follow [`Motion`]'s convention.
    pub fn to_toolpath(&self, job_id: &str) -> Toolpath {
        let w = self.towers.separation_mm;
        let at = |p: &Point2<f64>, z: f64| Point { x: p.x, y: p.y, z };
        let segment = |kind, m: &Motion| ToolpathSegment {
            kind,
            points: m.xy.iter().map(|p| at(p, 0.0)).collect(),
            secondary_points: if self.four_axis {
                m.uv.iter().map(|p| at(p, w)).collect()
            } else {
                Vec::new()
            },
            feed_mm_s: m.feed_mm_s.iter().map(|&f| f as f32).collect(),
            power: m.current_a.iter().map(|&a| a as f32).collect(),
            ..Default::default()
        };
        Toolpath {
            header: Header {
                stamp: Time::now(),
                frame_id: FRAME_ID.into(),
            },
            job_id: job_id.into(),
            process: Toolpath::PROCESS_HOTWIRE,
            power_unit: Toolpath::POWER_WIRE_CURRENT_A,
            plane_separation_mm: w,
            segments: vec![
                segment(ToolpathSegment::KIND_LEAD, &self.lead_in),
                segment(ToolpathSegment::KIND_CUT, &self.cut),
                segment(ToolpathSegment::KIND_LEAD, &self.lead_out),
            ],
        }
    }

    /// The root chord a cut along the baseline and along the optimised path would leave for each
    /// material CSE of `cse_values` ([`crate::calibration`], seed 000 §IV.D), with
    /// `wire_radius_mm` as the closest the surface can come to the wire centre.
    ///
    /// # Errors
    /// The exposure model's (not expected for a plan from [`plan`]).
    pub fn chord_predictions(
        &self,
        cse_values: &[f64],
        wire_radius_mm: f64,
    ) -> Result<Vec<CalibrationRow>, JobError> {
        let wrap = |e: crate::exposure::ExposureError| JobError::Plan {
            airfoil: self.root.airfoil.clone(),
            source: e.into(),
        };
        let sweep = Sweep {
            wire_radius_mm,
            ..Sweep::default()
        };
        let chord = self.root.chord_mm;
        let predict = |path: &[Point2<f64>]| {
            predict_chords(
                &self.model,
                &self.root.surface,
                path,
                self.root.offset_mm,
                chord,
                cse_values,
                &sweep,
            )
            .map_err(wrap)
        };
        let (baseline, optimised) = (
            predict(&self.root.baseline)?,
            predict(&self.root.optimised)?,
        );
        Ok(baseline
            .into_iter()
            .zip(optimised)
            .map(|(baseline, optimised)| CalibrationRow {
                cse: baseline.cse,
                baseline,
                optimised,
            })
            .collect())
    }

    /// The optimised exposure along the foil as a 1 × N raster (`exposure_profile`, one cell
    /// per panel from the TE, index space), threshold = CSE.
    pub fn exposure_heat_map(&self) -> HeatMap {
        profile_map(self.model, self.root.cse, &self.root.optimised_exposure)
    }

    /// The baseline exposure profile, as [`HotwirePlan::exposure_heat_map`].
    pub fn baseline_heat_map(&self) -> HeatMap {
        profile_map(self.model, self.root.cse, &self.root.baseline_exposure)
    }

    /// Every optimised wire segment's contribution to every panel: M × N (`wire_exposure`,
    /// rows = wire segments, columns = panels), threshold = CSE.
    ///
    /// # Errors
    /// The exposure model's (a degenerate path); not expected for a plan from [`plan`].
    pub fn exposure_matrix_heat_map(&self) -> Result<HeatMap, JobError> {
        let wrap = |e: crate::exposure::ExposureError| JobError::Plan {
            airfoil: self.root.airfoil.clone(),
            source: e.into(),
        };
        let panels = Panels::from_points(&self.root.surface).map_err(wrap)?;
        let (rows, cols, values) = self
            .model
            .exposure_matrix(&panels, &self.root.optimised)
            .map_err(wrap)?;
        Ok(heat_map(
            self.model,
            self.root.cse,
            "wire_exposure",
            cols,
            rows,
            values,
        ))
    }
}

fn heat_map(
    model: ExposureModel,
    cse: f64,
    quantity: &str,
    width: usize,
    height: usize,
    data: Vec<f32>,
) -> HeatMap {
    HeatMap {
        header: Header {
            stamp: Time::now(),
            frame_id: SECTION_FRAME_ID.into(),
        },
        quantity: quantity.into(),
        unit: match model.law {
            DistanceLaw::Paper => "1",
            DistanceLaw::AuthorCode => "1/mm",
        }
        .into(),
        width: width as u32,
        height: height as u32,
        cell_width_mm: 1.0,
        cell_height_mm: 1.0,
        origin: Point::default(),
        threshold: cse as f32,
        data,
    }
}

/// A 1 × N `exposure_profile` raster of `exposure`, threshold = `cse`.
fn profile_map(model: ExposureModel, cse: f64, exposure: &[f64]) -> HeatMap {
    heat_map(
        model,
        cse,
        "exposure_profile",
        exposure.len(),
        1,
        exposure.iter().map(|&e| e as f32).collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small(seed: u64) -> HotwireJob {
        HotwireJob {
            panels: 40,
            pso: PsoConfig {
                particles: 8,
                iterations: 60,
                restart_every: 30,
                ..PsoConfig::default()
            },
            seed,
            ..HotwireJob::default()
        }
    }

    #[test]
    fn every_embedded_airfoil_loads() {
        for (name, _) in EMBEDDED_AIRFOILS {
            AirfoilSource::parse(name).load().unwrap();
        }
        assert_eq!(
            AirfoilSource::parse("S1223"),
            AirfoilSource::Named("S1223".into())
        );
        assert!(matches!(
            AirfoilSource::parse("x/y.dat"),
            AirfoilSource::File(_)
        ));
    }

    #[test]
    fn short_job_beats_baseline_is_feasible_and_reproducible() {
        let mut calls = 0;
        let a = plan(&small(3), |p| {
            calls += 1;
            assert!(p.eta_s >= 0.0 && p.total == 60);
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(calls, 60);
        assert_eq!(a.iterations, 60);
        assert!(a.root.final_loss <= a.root.baseline_loss, "{a:?}");
        assert!(a.root.optimised_stats.rms <= a.root.baseline_stats.rms + 1e-12);
        assert!(a.is_feasible(Objective::default().min_clearance_mm));
        assert_eq!(a.root.optimised_exposure.len(), 40);
        assert_eq!(a.cut.len(), a.root.optimised.len());
        assert_eq!(a.cut.feed_mm_s.len(), a.cut.len());
        assert_eq!(a.cut.current_a.len(), a.cut.len());
        assert!(a.notes.is_empty(), "{:?}", a.notes);
        // The default offset is the kerf model's λ/2, so the schedule gives the nominal current
        // wherever the face runs at the nominal feed (a straight cut: everywhere).
        assert!(
            a.cut.current_a.iter().all(|c| (c - 3.0).abs() < 1e-9),
            "{:?}",
            &a.cut.current_a[..3]
        );
        assert!(a.cut.feed_mm_s.iter().all(|f| (f - 15.0).abs() < 1e-9));
        // A straight cut: both carriages on the section, placed at the part origin.
        assert_eq!(a.cut.xy, a.cut.uv);
        let origin = Vector2::new(60.0, 60.0);
        assert!(a
            .cut
            .xy
            .iter()
            .zip(&a.root.optimised)
            .all(|(m, p)| (m - (p + origin)).norm() < 1e-9));

        let b = plan(&small(3), |_| ControlFlow::Continue(())).unwrap();
        assert_eq!(
            (&a.root.optimised, a.root.final_loss, &a.cut),
            (&b.root.optimised, b.root.final_loss, &b.cut)
        );

        let tp = a.to_toolpath("t");
        assert_eq!(tp.segments.len(), 3);
        assert_eq!(tp.plane_separation_mm, 1000.0);
        let cut = &tp.segments[1];
        assert_eq!(cut.points.first(), cut.points.last());
        assert_eq!(cut.secondary_points.len(), cut.points.len());
        assert!(cut.secondary_points.iter().all(|p| p.z == 1000.0));
        assert_eq!(tp.segments[0].points.last(), cut.points.first());
        assert_eq!(tp.segments[2].points.first(), cut.points.last());
        let h = a.exposure_heat_map();
        assert_eq!((h.width, h.height, h.data.len()), (40, 1, 40));
        let m = a.exposure_matrix_heat_map().unwrap();
        assert_eq!(m.width, 40);
        assert_eq!(m.data.len(), (m.width * m.height) as usize);
        assert_eq!(m.height as usize, a.root.optimised.len() - 1);
    }

    fn tapered(seed: u64) -> HotwireJob {
        HotwireJob {
            tip: Some(TipSection {
                airfoil: AirfoilSource::parse("e387"),
                chord_mm: 120.0,
                placement: Placement {
                    sweep_mm: 40.0,
                    twist_deg: -3.0,
                    pivot_chord_fraction: 0.25,
                },
            }),
            span_mm: 400.0,
            ..small(seed)
        }
    }

    #[test]
    fn tapered_panel_is_synchronised_projected_and_timed() {
        let job = tapered(5);
        let mut last = 0;
        let p = plan(&job, |pr| {
            assert_eq!(pr.total, 120);
            last = pr.iteration;
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!((last, p.iterations), (120, 120));
        let tip = p.tip.as_ref().expect("a tip plan");
        assert_eq!(tip.chord_mm, 120.0);
        assert!(p.is_feasible(Objective::default().min_clearance_mm));
        // The slower (tip) face gets the wider kerf: offset × perimeter ratio.
        assert!(
            tip.offset_mm > p.root.offset_mm * 1.5,
            "{} {}",
            tip.offset_mm,
            p.root.offset_mm
        );
        assert!(tip.optimised_stats.rms.is_finite());
        assert_eq!(tip.optimised.len(), p.root.optimised.len());

        // Rebuild each wire line from the carriages and check it passes the placed root and
        // tip points on the two faces.
        let (zr, zt, w) = (200.0, 600.0, 1000.0);
        let origin = Vector2::new(60.0, 60.0);
        for k in (0..p.cut.len()).step_by(7) {
            let (xy, uv) = (p.cut.xy[k], p.cut.uv[k]);
            let at = |z: f64| xy + (uv - xy) * (z / w);
            assert!((at(zr) - (p.root.optimised[k] + origin)).norm() < 1e-9);
            let t = job
                .tip
                .as_ref()
                .unwrap()
                .placement
                .apply(120.0, tip.optimised[k])
                + origin;
            assert!((at(zt) - t).norm() < 1e-9, "{k}");
        }
        // Every move: the faster face at the feed (or slower when a carriage hits the limit),
        // the carriage feed within the machine limit, the current from the face speed.
        for k in 1..p.cut.len() {
            let dr = (p.root.optimised[k] - p.root.optimised[k - 1]).norm();
            let dt = (tip.optimised[k] - tip.optimised[k - 1]).norm();
            let dxy = (p.cut.xy[k] - p.cut.xy[k - 1]).norm();
            let duv = (p.cut.uv[k] - p.cut.uv[k - 1]).norm();
            let f = p.cut.feed_mm_s[k];
            assert!(f <= 25.0 + 1e-9, "{k}: {f}");
            if dxy.max(duv) > 0.0 {
                let duration = dxy.max(duv) / f;
                let face = dr.max(dt) / duration;
                assert!(face <= 15.0 + 1e-6, "{k}: face speed {face}");
            }
        }
        let placed = p.placed_sections();
        let names: Vec<&str> = placed.iter().map(|(n, _)| *n).collect();
        assert_eq!(names, ["root_foil", "root_path", "tip_foil", "tip_path"]);
        assert!(placed[1].1.iter().all(|q| q[2] == zr));
        assert!(placed[3].1.iter().all(|q| q[2] == zt));
        // The placed tip path is where the wire crosses the tip face.
        let (xy, uv) = (p.cut.xy[5], p.cut.uv[5]);
        let at_tip = xy + (uv - xy) * (zt / w);
        assert!((at_tip.x - placed[3].1[5][0]).abs() < 1e-9);
        let tp = p.to_toolpath("panel");
        assert_ne!(tp.segments[1].points, tp.segments[1].secondary_points);
        assert_eq!(tp.segments[0].secondary_points.len(), 2);
    }

    #[test]
    fn out_of_travel_and_two_axis_machines_are_refused_by_name() {
        let mut far = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
        far.hotwire.as_mut().unwrap().part_origin_mm = [450.0, 60.0];
        let e = plan(
            &HotwireJob {
                machine: far,
                ..small(1)
            },
            |_| ControlFlow::Continue(()),
        )
        .unwrap_err();
        assert!(matches!(e, JobError::Envelope { .. }), "{e}");
        assert!(e.to_string().contains("X = "), "{e}");
        let e = plan(
            &HotwireJob {
                machine: MachineProfile::resolve("grbl-xy").unwrap(),
                ..tapered(1)
            },
            |_| ControlFlow::Continue(()),
        )
        .unwrap_err();
        assert!(e.to_string().contains("grbl-xy"), "{e}");
        let e = validate(&HotwireJob {
            span_mm: 900.0,
            ..small(1)
        })
        .unwrap_err();
        assert!(e.to_string().starts_with("span_mm"), "{e}");
        // The same section as tip is a straight cut.
        let straight = HotwireJob {
            tip: Some(TipSection {
                airfoil: AirfoilSource::parse("s1223"),
                chord_mm: 200.0,
                placement: Placement::ROOT,
            }),
            pso: PsoConfig {
                particles: 2,
                iterations: 2,
                ..PsoConfig::default()
            },
            ..small(1)
        };
        let p = plan(&straight, |_| ControlFlow::Continue(())).unwrap();
        assert!(p.tip.is_none());
        assert_eq!(p.cut.xy, p.cut.uv);
    }

    #[test]
    fn live_maps_show_the_baseline_then_each_better_path() {
        let mut seen: Vec<LiveMaps> = Vec::new();
        let options = LiveOptions {
            period: Some(std::time::Duration::ZERO),
        };
        let p = plan_observed(
            &small(3),
            &options,
            |m| seen.push(m),
            |_| ControlFlow::Continue(()),
        )
        .unwrap();
        assert!(seen.len() >= 2, "{}", seen.len());
        assert_eq!(seen[0].iteration, 0);
        assert_eq!(seen[0].profile.data, p.baseline_heat_map().data);
        assert!(seen.windows(2).all(|w| w[1].iteration > w[0].iteration));
        let last = seen.last().unwrap();
        assert_eq!(last.profile.width, 40);
        assert_eq!(
            last.matrix.data.len(),
            (last.matrix.width * last.matrix.height) as usize
        );
        // The last improvement is the optimised path.
        let final_map = p.exposure_heat_map();
        assert!(last
            .profile
            .data
            .iter()
            .zip(&final_map.data)
            .all(|(a, b)| (a - b).abs() <= 1e-5 * b.abs().max(1.0)));
        let none = plan_observed(
            &small(3),
            &LiveOptions { period: None },
            |m| assert_eq!(m.iteration, 0, "only the baseline"),
            |_| ControlFlow::Continue(()),
        );
        assert!(none.is_ok());
    }

    #[test]
    fn an_optimised_feed_varies_within_its_band_at_constant_current() {
        let job = HotwireJob {
            objective: Objective {
                feed: Some(crate::pso::FeedVariable::default()),
                ..Objective::default()
            },
            ..small(4)
        };
        let p = plan(&job, |_| ControlFlow::Continue(())).unwrap();
        let feeds = &p.cut.feed_mm_s;
        assert!(feeds
            .iter()
            .all(|&f| (7.5 - 1e-9..=22.5 + 1e-9).contains(&f)));
        assert!(
            feeds.iter().any(|&f| (f - 15.0).abs() > 0.01),
            "the feed moved"
        );
        assert!(
            p.cut.current_a.iter().all(|&a| a == 3.0),
            "constant current"
        );
        assert!(p.root.final_loss < p.root.baseline_loss);
        // The reported exposure is the feed-weighted one the loss saw.
        let fit = p
            .root
            .optimised_exposure
            .iter()
            .map(|e| (e - p.root.cse).powi(2))
            .sum::<f64>()
            / p.root.optimised_exposure.len() as f64;
        assert!(
            fit <= p.root.final_loss + 1e-12,
            "{fit} vs {}",
            p.root.final_loss
        );
    }

    /// The quality bar, with the paper's default law (1/‖R‖): on three real sections the
    /// optimised path is clearly more uniform than the fixed offset, never touches the foil and
    /// stays within the machine's travel.
    #[test]
    fn optimised_paths_beat_the_fixed_offset_on_three_airfoils() {
        for name in ["s1223", "clarky", "e387"] {
            let job = HotwireJob {
                root_airfoil: AirfoilSource::parse(name),
                panels: 60,
                pso: PsoConfig {
                    particles: 10,
                    iterations: 400,
                    restart_every: 100,
                    // A short run explores faster with larger restart velocities.
                    initial_velocity_mm: 0.5,
                    ..PsoConfig::default()
                },
                seed: 11,
                ..HotwireJob::default()
            };
            let p = plan(&job, |_| ControlFlow::Continue(())).unwrap();
            let (b, o) = (p.root.baseline_stats, p.root.optimised_stats);
            eprintln!(
                "{name}: RMS {:.4} -> {:.4} ({:.0} %), max {:.4} -> {:.4}, CV {:.4} -> {:.4}",
                b.rms,
                o.rms,
                100.0 * (1.0 - o.rms / b.rms),
                b.max_abs,
                o.max_abs,
                b.cv,
                o.cv
            );
            // Measured: 15–19 % lower RMS in this short run (400 iterations, 10 particles).
            assert!(o.rms <= 0.9 * b.rms, "{name}: RMS {} -> {}", b.rms, o.rms);
            assert!(
                p.is_feasible(Objective::default().min_clearance_mm),
                "{name}"
            );
            for (xy, uv) in p.carriage_positions() {
                let at = [('X', xy.x), ('Y', xy.y), ('U', uv.x), ('V', uv.y)];
                assert!(job.machine.check_position(&at).is_ok(), "{name}: {xy} {uv}");
            }
        }
    }

    #[test]
    fn material_aliases_resolve() {
        let lib = MaterialLibrary::builtin();
        assert_eq!(
            lib.find_foam("EPS").map(|f| f.density_kg_m3),
            Some(26.0),
            "EPS is the paper's H grade"
        );
        assert_eq!(lib.find_foam("xps").map(|f| f.density_kg_m3), Some(30.0));
        assert!(lib.find_foam("EPP").is_none());
    }

    #[test]
    fn unknown_material_falls_back_to_constant_current() {
        let job = HotwireJob {
            material: "EPP".into(),
            pso: PsoConfig {
                particles: 2,
                iterations: 2,
                ..PsoConfig::default()
            },
            panels: 40,
            ..HotwireJob::default()
        };
        let p = plan(&job, |_| ControlFlow::Continue(())).unwrap();
        assert_eq!(p.root.offset_mm, FALLBACK_OFFSET_MM);
        assert!(p.cut.current_a.iter().all(|&a| a == 3.0));
        assert!(p.notes[0].contains("EPP"), "{:?}", p.notes);
    }

    #[test]
    fn errors_name_the_parameter_or_airfoil() {
        let e = plan(
            &HotwireJob {
                chord_mm: 0.0,
                ..small(1)
            },
            |_| ControlFlow::Continue(()),
        )
        .unwrap_err();
        assert!(e.to_string().starts_with("chord_mm"), "{e}");
        let e = plan(
            &HotwireJob {
                root_airfoil: AirfoilSource::parse("nope"),
                ..small(1)
            },
            |_| ControlFlow::Continue(()),
        )
        .unwrap_err();
        assert!(e.to_string().contains("\"nope\""), "{e}");
        let e = AirfoilSource::parse("/nonexistent/x.dat")
            .load()
            .unwrap_err();
        assert!(e.to_string().contains("/nonexistent/x.dat"), "{e}");
        let e = plan(&small(1), |p| {
            if p.iteration == 2 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .unwrap_err();
        assert!(matches!(e, JobError::Cancelled { iteration: 2 }), "{e}");
    }
}
