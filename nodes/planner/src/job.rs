//! One hot-wire planning job, end to end: load and scale the foil, pick the wire offset from the
//! kerf model, build the fixed-offset baseline, run the swarm ([`crate::pso::optimise`]) and
//! package the result as a [`HotwirePlan`] with its per-point feed and wire current, lead-in and
//! lead-out, exposure statistics and the `cell_msgs` views ([`HotwirePlan::to_toolpath`],
//! [`HotwirePlan::exposure_heat_map`], [`HotwirePlan::exposure_matrix_heat_map`]).
//!
//! Synchronous and free of ROS/DDS: the planner node runs [`plan`] on a blocking thread, the
//! `cell hotwire` command runs it directly.
//!
//! Today the job plans one section (the root); the wire path lies in the root plane (z = 0) and
//! the toolpath carries no secondary (tip) points. Root/tip synchronisation for 4-axis cutters
//! ([`crate::airfoil::synchronise`]) is a later step.

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::time::Instant;

use cell_msgs::{
    builtin_interfaces::Time, geometry_msgs::Point, std_msgs::Header, HeatMap, Toolpath,
    ToolpathSegment,
};
use nalgebra::Point2;

use crate::airfoil::{Airfoil, AirfoilError};
use crate::exposure::{coefficient_of_variation, DistanceLaw, ExposureModel, Panels};
use crate::kerf::{self, CurrentLimits, MaterialLibrary};
use crate::pso::{self, Objective, Problem, PsoConfig, PsoError};
use crate::trajectory::{is_feasible, Baseline};

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
    /// The progress callback stopped the run.
    #[error("cancelled after {iteration} iterations")]
    Cancelled {
        /// Iterations done.
        iteration: usize,
    },
}

/// One hot-wire cut to plan.
#[derive(Debug, Clone, PartialEq)]
pub struct HotwireJob {
    /// The section to cut.
    pub root_airfoil: AirfoilSource,
    /// Chord (mm), > 0.
    pub chord_mm: f64,
    /// Foam id in the material library (case-insensitive, e.g. `eps_h_grade`, `xps`).
    pub material: String,
    /// Wire id in the material library.
    pub wire: String,
    /// Nominal wire current (A): sets the default offset (kerf / 2 at this current and feed)
    /// and is the constant current when the material library cannot give a schedule.
    pub current_a: f64,
    /// Supply limits for the current schedule.
    pub supply: CurrentLimits,
    /// Target exposure CSE; `None`: the baseline's mean exposure.
    pub cse: Option<f64>,
    /// Wire-centre offset from the surface (mm); `None`: kerf / 2 from the material library at
    /// `current_a` and `feed_mm_s`, else [`FALLBACK_OFFSET_MM`].
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
    /// Cutting feed (mm/s).
    pub feed_mm_s: f64,
    /// Length of the straight lead-in and lead-out behind the trailing edge (mm).
    pub lead_in_mm: f64,
}

impl Default for HotwireJob {
    /// s1223 at 200 mm in H-grade EPS with 0.36 mm Nichrome at 3 A and 15 mm/s (the seed 001
    /// worked-example conditions), 100 panels, the paper's swarm.
    fn default() -> Self {
        Self {
            root_airfoil: AirfoilSource::Named("s1223".into()),
            chord_mm: 200.0,
            material: "eps_h_grade".into(),
            wire: "nichrome_0_36mm".into(),
            current_a: 3.0,
            supply: CurrentLimits {
                min_a: 0.0,
                max_a: 10.0,
            },
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

/// A planned hot-wire cut (mm, mm/s, A), see the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct HotwirePlan {
    /// Section name (from the `.dat` name line).
    pub airfoil: String,
    /// The scaled foil (LE at the origin, TE at (chord, 0)), Selig order.
    pub foil: Vec<Point2<f64>>,
    /// The resampled foil whose panels the exposure is evaluated on (N + 1 points).
    pub surface: Vec<Point2<f64>>,
    /// The fixed-offset baseline path (closed).
    pub baseline: Vec<Point2<f64>>,
    /// The optimised path (closed, same points as the baseline moved along its normals).
    pub optimised: Vec<Point2<f64>>,
    /// Straight lead-in from behind the TE to the first path point.
    pub lead_in: Vec<Point2<f64>>,
    /// Straight lead-out from the last path point back behind the TE.
    pub lead_out: Vec<Point2<f64>>,
    /// Exposure model used (for [`HotwirePlan::exposure_matrix_heat_map`]).
    pub model: ExposureModel,
    /// The exposure target CSE.
    pub cse: f64,
    /// Baseline exposure per panel.
    pub baseline_exposure: Vec<f64>,
    /// Optimised exposure per panel.
    pub optimised_exposure: Vec<f64>,
    /// Baseline uniformity.
    pub baseline_stats: ExposureStats,
    /// Optimised uniformity.
    pub optimised_stats: ExposureStats,
    /// Loss of the baseline.
    pub baseline_loss: f64,
    /// Loss of the optimised path.
    pub final_loss: f64,
    /// (iteration, best loss) at iteration 0 and at every improvement.
    pub loss_history: Vec<(usize, f64)>,
    /// Iterations run.
    pub iterations: usize,
    /// Wall time of the optimisation (s).
    pub seconds: f64,
    /// RNG seed used.
    pub seed: u64,
    /// Wire-centre offset used (mm).
    pub offset_mm: f64,
    /// Feed at each optimised path point (mm/s).
    pub feed_mm_s: Vec<f64>,
    /// Wire current at each optimised path point (A).
    pub current_a: Vec<f64>,
    /// Feed and current on the leads (mm/s, A).
    pub lead_feed_mm_s: f64,
    /// Wire current on the leads (A).
    pub lead_current_a: f64,
    /// Notes for the operator (fallbacks taken, clamped currents).
    pub notes: Vec<String>,
}

/// The kerf-model side of a job: offset and current schedule inputs.
struct Process {
    offset_mm: f64,
    /// (Q_eff in J/m², R' in Ω/m) when the library has the material and wire.
    schedule: Option<(f64, f64)>,
    notes: Vec<String>,
}

fn find<'a, T>(map: &'a std::collections::BTreeMap<String, T>, id: &str) -> Option<&'a T> {
    map.iter()
        .find(|(k, _)| k.eq_ignore_ascii_case(id))
        .map(|(_, v)| v)
}

fn process(job: &HotwireJob) -> Result<Process, JobError> {
    let lib = MaterialLibrary::builtin();
    let mut notes = Vec::new();
    let (foam, wire) = (find(&lib.foams, &job.material), find(&lib.wires, &job.wire));
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
        // The area energy that cuts a kerf of 2 × offset: Q_eff = λ · ρ_f · ^mass Q_eff (eq. 4–6).
        Some((_, foam, wire)) => Some((
            2.0 * offset_mm * 1e-3 * foam.density_kg_m3 * foam.mass_energy_j_kg(),
            wire.resistance_ohm_per_m,
        )),
        None => {
            let what = match (foam, wire) {
                (None, _) => format!("material {:?} is not in the material library", job.material),
                (_, None) => format!("wire {:?} is not in the material library", job.wire),
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
    Ok(())
}

/// Plans `job` (module docs). `progress` is called after every iteration; returning
/// [`ControlFlow::Break`] stops the run with [`JobError::Cancelled`].
///
/// # Errors
/// Invalid parameters (named), an unknown or malformed airfoil (named, with file and line),
/// an infeasible baseline or other planning failure (with the airfoil), cancellation.
pub fn plan(
    job: &HotwireJob,
    progress: impl FnMut(&JobProgress) -> ControlFlow<()>,
) -> Result<HotwirePlan, JobError> {
    plan_observed(job, |_| {}, progress)
}

/// [`plan`], also handing `on_baseline` the baseline's exposure profile (as
/// [`HotwirePlan::baseline_heat_map`] would give it) before the swarm starts, so a caller can
/// show it while the optimiser runs.
///
/// # Errors
/// As [`plan`].
pub fn plan_observed(
    job: &HotwireJob,
    on_baseline: impl FnOnce(HeatMap),
    mut progress: impl FnMut(&JobProgress) -> ControlFlow<()>,
) -> Result<HotwirePlan, JobError> {
    validate(job)?;
    let loaded = job.root_airfoil.load()?;
    let foil = loaded.normalised().scaled(job.chord_mm)?;
    let proc = process(job)?;
    let wrap = |source: PsoError| JobError::Plan {
        airfoil: job.root_airfoil.to_string(),
        source,
    };
    let path_points = if job.path_points == 0 {
        job.panels + job.panels / 2
    } else {
        job.path_points
    };
    let baseline =
        Baseline::fixed_offset(&foil, proc.offset_mm, path_points).map_err(|e| wrap(e.into()))?;
    let objective = Objective {
        cse: job.cse,
        ..job.objective
    };
    // A sharp trailing edge repeats its point at both ends: one more point gives N panels.
    let surface_points = surface_points(&foil, job.panels)?;
    let problem = Problem::new(&foil, surface_points, baseline, objective).map_err(wrap)?;
    let k = problem.trajectory().control_points();
    let baseline_exposure = problem.exposure(&vec![0.0; k]).map_err(wrap)?;
    on_baseline(profile_map(
        objective.model,
        problem.cse(),
        &baseline_exposure,
    ));
    let config = PsoConfig {
        seed: job.seed,
        ..job.pso
    };
    let started = Instant::now();
    let result = pso::optimise(&problem, &config, |p| {
        let elapsed = started.elapsed().as_secs_f64();
        let eta_s = elapsed / p.iteration.max(1) as f64 * (p.iterations - p.iteration) as f64;
        progress(&JobProgress {
            iteration: p.iteration,
            total: p.iterations,
            best_loss: p.best_loss,
            eta_s,
        })
    })
    .map_err(wrap)?;
    let seconds = started.elapsed().as_secs_f64();
    if result.cancelled {
        return Err(JobError::Cancelled {
            iteration: result.iterations_run,
        });
    }
    let baseline_path = problem.path(&vec![0.0; k]);
    let optimised = problem.path(&result.controls);
    let optimised_exposure = problem.exposure(&result.controls).map_err(wrap)?;
    let cse = problem.cse();

    let mut notes = proc.notes;
    let feed_mm_s = vec![job.feed_mm_s; optimised.len()];
    let current_a = match proc.schedule {
        Some((q_eff, r)) => {
            let schedule = kerf::current_schedule(&feed_mm_s, q_eff, r, job.supply)
                .map_err(|e| wrap(PsoError::Trajectory(e.into())))?;
            let clamped = schedule.iter().filter(|s| s.clamped).count();
            if clamped > 0 {
                notes.push(format!(
                    "{clamped} of {} current set-points clamped to the supply limits {}..{} A: \
                     the kerf deviates there",
                    schedule.len(),
                    job.supply.min_a,
                    job.supply.max_a
                ));
            }
            schedule.iter().map(|s| s.current_a).collect()
        }
        None => vec![job.current_a; optimised.len()],
    };
    let lead_current_a = current_a.first().copied().unwrap_or(job.current_a);

    // Leads: straight, along the chord line behind the TE.
    let (le, te) = (foil.leading_edge(), foil.trailing_edge());
    let outside = te + (te - le).normalize() * (job.lead_in_mm + proc.offset_mm);
    let (first, last) = (optimised[0], optimised[optimised.len() - 1]);
    Ok(HotwirePlan {
        airfoil: loaded.name().to_string(),
        foil: foil.points().to_vec(),
        surface: foil.resampled_cosine(surface_points)?.points().to_vec(),
        baseline: baseline_path,
        optimised,
        lead_in: vec![outside, first],
        lead_out: vec![last, outside],
        model: objective.model,
        cse,
        baseline_stats: ExposureStats::of(&baseline_exposure, cse),
        optimised_stats: ExposureStats::of(&optimised_exposure, cse),
        baseline_exposure,
        optimised_exposure,
        baseline_loss: result.baseline_loss,
        final_loss: result.best_loss,
        loss_history: result.history,
        iterations: result.iterations_run,
        seconds,
        seed: job.seed,
        offset_mm: proc.offset_mm,
        feed_mm_s,
        current_a,
        lead_feed_mm_s: job.feed_mm_s,
        lead_current_a,
        notes,
    })
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

fn point(p: &Point2<f64>) -> Point {
    Point {
        x: p.x,
        y: p.y,
        z: 0.0,
    }
}

/// Frame id of the planner's messages: the hot-wire cutter's root plane.
pub const FRAME_ID: &str = "hotwire_root";

impl HotwirePlan {
    /// True if the optimised path keeps `min_clearance_mm` from the foil (T ∩ G = ∅).
    pub fn is_feasible(&self, min_clearance_mm: f64) -> bool {
        is_feasible(&self.optimised, &self.foil, min_clearance_mm)
    }

    /// The plan as a hot-wire `Toolpath` (wire current in A): LEAD in, CUT (the closed
    /// optimised path), LEAD out; z = 0, no secondary (tip) points yet.
    pub fn to_toolpath(&self, job_id: &str) -> Toolpath {
        let lead = |pts: &[Point2<f64>]| ToolpathSegment {
            kind: ToolpathSegment::KIND_LEAD,
            points: pts.iter().map(point).collect(),
            feed_mm_s: vec![self.lead_feed_mm_s as f32; pts.len()],
            power: vec![self.lead_current_a as f32; pts.len()],
            ..Default::default()
        };
        let cut = ToolpathSegment {
            kind: ToolpathSegment::KIND_CUT,
            points: self.optimised.iter().map(point).collect(),
            feed_mm_s: self.feed_mm_s.iter().map(|&f| f as f32).collect(),
            power: self.current_a.iter().map(|&a| a as f32).collect(),
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
            plane_separation_mm: 0.0,
            segments: vec![lead(&self.lead_in), cut, lead(&self.lead_out)],
        }
    }

    /// The optimised exposure along the foil as a 1 × N raster (`exposure_profile`, one cell
    /// per panel from the TE, index space), threshold = CSE.
    pub fn exposure_heat_map(&self) -> HeatMap {
        profile_map(self.model, self.cse, &self.optimised_exposure)
    }

    /// The baseline exposure profile, as [`HotwirePlan::exposure_heat_map`].
    pub fn baseline_heat_map(&self) -> HeatMap {
        profile_map(self.model, self.cse, &self.baseline_exposure)
    }

    /// Every optimised wire segment's contribution to every panel: M × N (`wire_exposure`,
    /// rows = wire segments, columns = panels), threshold = CSE.
    ///
    /// # Errors
    /// The exposure model's (a degenerate path); not expected for a plan from [`plan`].
    pub fn exposure_matrix_heat_map(&self) -> Result<HeatMap, JobError> {
        let wrap = |e: crate::exposure::ExposureError| JobError::Plan {
            airfoil: self.airfoil.clone(),
            source: e.into(),
        };
        let panels = Panels::from_points(&self.surface).map_err(wrap)?;
        let (rows, cols, values) = self
            .model
            .exposure_matrix(&panels, &self.optimised)
            .map_err(wrap)?;
        Ok(heat_map(
            self.model,
            self.cse,
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
            frame_id: FRAME_ID.into(),
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
        assert!(a.final_loss <= a.baseline_loss, "{a:?}");
        assert!(a.optimised_stats.rms <= a.baseline_stats.rms + 1e-12);
        assert!(a.is_feasible(Objective::default().min_clearance_mm));
        assert_eq!(a.optimised_exposure.len(), 40);
        assert_eq!(a.feed_mm_s.len(), a.optimised.len());
        assert_eq!(a.current_a.len(), a.optimised.len());
        assert!(a.notes.is_empty(), "{:?}", a.notes);
        // The default offset is the kerf model's λ/2, so the schedule gives the nominal current.
        assert!((a.current_a[0] - 3.0).abs() < 1e-9, "{}", a.current_a[0]);

        let b = plan(&small(3), |_| ControlFlow::Continue(())).unwrap();
        assert_eq!(
            (&a.optimised, a.final_loss, &a.current_a),
            (&b.optimised, b.final_loss, &b.current_a)
        );

        let tp = a.to_toolpath("t");
        assert_eq!(tp.segments.len(), 3);
        let cut = &tp.segments[1];
        assert_eq!(cut.points.first(), cut.points.last());
        assert_eq!(tp.segments[0].points.last(), cut.points.first());
        assert_eq!(tp.segments[2].points.first(), cut.points.last());
        let h = a.exposure_heat_map();
        assert_eq!((h.width, h.height, h.data.len()), (40, 1, 40));
        let m = a.exposure_matrix_heat_map().unwrap();
        assert_eq!(m.width, 40);
        assert_eq!(m.data.len(), (m.width * m.height) as usize);
        assert_eq!(m.height as usize, a.optimised.len() - 1);
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
        assert_eq!(p.offset_mm, FALLBACK_OFFSET_MM);
        assert!(p.current_a.iter().all(|&a| a == 3.0));
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
