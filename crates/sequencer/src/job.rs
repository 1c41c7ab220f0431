//! One sequencing job end to end (seed 003 §A4 `Main`, notes §A6 inputs → outputs): read the
//! layout, build the [`Problem`], construct a plan with a [`Policy`], optionally
//! improve it ([`crate::improve::improve`]), and simulate the final plan on the thermal raster
//! (seed 003 §A3), reporting raster frames. When the improvement finds a better order, its
//! own raster run of that order ([`crate::improve::ImproveOptions::run_best`]) is that
//! simulation and streams the frames; a
//! separate run is made only when the start order stays. The `sequencer` node and `cell sheet`
//! are thin adapters around [`run`].
//!
//! **Pierce modes.** [`PierceMode::Fixed`]: one pierce point per contour (seed 003 §A1 `P_ij`):
//! the layout's where it gives one, else the single best free candidate
//! ([`PierceOptions`] with `max_candidates = 1`). [`PierceMode::Free`]: the layout's pierce
//! point where it gives one, else up to `max_candidates` free candidates (the GTSP variant).
//! With a cut spec ([`SheetJob::cut`], [`crate::cut`]) each candidate is a lead-in's start on
//! the scrap side, and the contours are their cut paths, offset by half the kerf.
//!
//! **Thermal off** (`cost.thermal = false`, [`parse_thermal`]; issue 19): the construction and
//! the improvement minimise the idle length (plus corner penalties) under the precedence rules
//! alone, without the raster. The final plan is still simulated on the raster once, so its
//! overheats, maximum temperature and time are what that order does to the sheet; its cost
//! stays what was minimised. The construction's figures are not simulated (0 overheats).

use std::path::PathBuf;
use std::time::Instant;

use cell_geometry::{ring_perimeter, Norm};
use serde::Serialize;

use crate::cost::{CostParams, EvalError, Evaluator};
use crate::cut::{cut_problem, CutError, CutSpec, CutSummary};
use crate::dxf::{read_layout_with_rule, DxfError, DxfOptions};
use crate::improve::{improve, ImproveOptions, ImproveParams, Improved, Progress, Start};
use crate::layout::{Layout, LayoutError, PierceOptions};
use crate::placement::{check_travel, OriginFrom, OutOfTravel, SheetPlacement, SheetRule, Travel};
use crate::plan::{Cut, CutPlan};
use crate::policy::{construct, construct_cuts, Policy};
use crate::precedence::{PrecedenceMode, Violation};
use crate::problem::{Point, Problem};
use crate::thermal::{CutThermal, Frame, SequencerParamError, ThermalOutcome, ThermalParams};

/// Where the layout comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum LayoutSource {
    /// A `.dxf` or `.json` file ([`crate::dxf::read_layout`]).
    File(PathBuf),
    /// The JSON format inline ([`Layout::from_json_str`]), named `<layout_json>` in errors.
    Json(String),
}

/// A sheet-job option given as a word: the goal's and the job's field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SheetOption {
    /// `policy`: the construction policy.
    Policy,
    /// `precedence`: strict or relaxed precedence rules.
    Precedence,
    /// `pierce`: fixed or free pierce points.
    Pierce,
    /// `thermal`: the heat in the cost (`on`) or idle length alone (`off`).
    Thermal,
}

impl SheetOption {
    /// The field's name, as the goal and the job spell it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Policy => "policy",
            Self::Precedence => "precedence",
            Self::Pierce => "pierce",
            Self::Thermal => "thermal",
        }
    }
}

impl std::fmt::Display for SheetOption {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A word that names none of an option's choices: `policy "fastest": expected nearest, …`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{option} {given:?}: expected {choices}")]
pub struct UnknownChoice {
    /// Which option.
    pub option: SheetOption,
    /// The word given.
    pub given: String,
    /// The words accepted, for people (`fixed or free`).
    pub choices: &'static str,
}

impl From<UnknownChoice> for String {
    fn from(e: UnknownChoice) -> Self {
        e.to_string()
    }
}

/// How pierce candidates are chosen (module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum PierceMode {
    /// One pierce point per contour.
    Fixed,
    /// Several candidates per contour where the layout fixes none.
    #[default]
    Free,
}

impl PierceMode {
    /// Parses `fixed` / `free`.
    ///
    /// # Errors
    /// Any other word, named.
    pub fn parse(s: &str) -> Result<Self, UnknownChoice> {
        match s {
            "fixed" => Ok(PierceMode::Fixed),
            "free" => Ok(PierceMode::Free),
            _ => Err(UnknownChoice {
                option: SheetOption::Pierce,
                given: s.into(),
                choices: "fixed or free",
            }),
        }
    }
}

/// Parses the thermal mode (module docs): `on` (the raster in the cost) gives true, `off`
/// (idle length alone) false; the job's `cost.thermal`.
///
/// # Errors
/// Any other word, named.
pub fn parse_thermal(s: &str) -> Result<bool, UnknownChoice> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(UnknownChoice {
            option: SheetOption::Thermal,
            given: s.into(),
            choices: "on or off",
        }),
    }
}

/// Parses a precedence mode, `strict` or `relaxed` (seed 003 §2 / notes §A2).
///
/// # Errors
/// Any other word, named.
pub fn parse_precedence(s: &str) -> Result<PrecedenceMode, UnknownChoice> {
    match s {
        "strict" => Ok(PrecedenceMode::Strict),
        "relaxed" => Ok(PrecedenceMode::Relaxed),
        _ => Err(UnknownChoice {
            option: SheetOption::Precedence,
            given: s.into(),
            choices: "strict or relaxed",
        }),
    }
}

/// Parses a policy name (`nearest`, `min_overheat`, `random`, `path_overheat`, `cost_greedy`).
///
/// # Errors
/// Any other word, named with the choices.
pub fn parse_policy(s: &str) -> Result<Policy, UnknownChoice> {
    Policy::ALL
        .into_iter()
        .find(|p| policy_name(*p) == s)
        .ok_or_else(|| UnknownChoice {
            option: SheetOption::Policy,
            given: s.into(),
            choices: "nearest, min_overheat, random, path_overheat or cost_greedy",
        })
}

/// The snake-case name of a policy (as the action and the CLI spell it).
pub fn policy_name(p: Policy) -> &'static str {
    match p {
        Policy::Nearest => "nearest",
        Policy::MinOverheat => "min_overheat",
        Policy::Random => "random",
        Policy::PathOverheat => "path_overheat",
        Policy::CostGreedy => "cost_greedy",
    }
}

/// Everything one job needs.
#[derive(Debug, Clone, PartialEq)]
pub struct SheetJob {
    /// The layout.
    pub layout: LayoutSource,
    /// DXF reading options.
    pub dxf: DxfOptions,
    /// Precedence rules (seed 003 §2).
    pub precedence: PrecedenceMode,
    /// Pierce mode (module docs).
    pub pierce: PierceMode,
    /// Free pierce candidates.
    pub pierce_options: PierceOptions,
    /// Construction policy (seed 003 §A4).
    pub policy: Policy,
    /// Run the improvement phase.
    pub improve: bool,
    /// Improvement knobs (its `seed` is overridden by [`SheetJob::seed`]).
    pub improve_params: ImproveParams,
    /// Thermal raster constants (seed 003 §A3).
    pub thermal: ThermalParams,
    /// Cost weights.
    pub cost: CostParams,
    /// RNG seed of the random policy and the improvement.
    pub seed: u64,
    /// Kerf compensation and leads ([`crate::cut`]); `None`: the drawn contours, pierced on
    /// the contour.
    pub cut: Option<CutSpec>,
    /// The operator's placement of the sheet's lower-left corner on the machine, mm; `None`
    /// keeps the drawing's ([`crate::placement`]).
    pub sheet_origin: Option<Point>,
    /// The machine's travel: a part outside it once placed is [`JobError::OutOfTravel`]
    /// before anything is sequenced; `None` = unchecked.
    pub travel: Option<Travel>,
}

impl Default for SheetJob {
    fn default() -> Self {
        SheetJob {
            layout: LayoutSource::Json(String::new()),
            dxf: DxfOptions::default(),
            precedence: PrecedenceMode::Strict,
            pierce: PierceMode::Free,
            pierce_options: PierceOptions::default(),
            policy: Policy::Nearest,
            improve: true,
            improve_params: ImproveParams::default(),
            thermal: ThermalParams::default(),
            cost: CostParams::default(),
            seed: 0,
            cut: None,
            sheet_origin: None,
            travel: None,
        }
    }
}

/// Why a job failed; every message names the file, entity or field.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// The layout file cannot be read or is invalid (names file and entity or field).
    #[error(transparent)]
    Dxf(#[from] DxfError),
    /// The inline layout JSON does not parse (the message names `<layout_json>` and the field).
    #[error(transparent)]
    Json(LayoutError),
    /// The layout is invalid (`source_name` names the file or `<layout_json>`).
    #[error("{source_name}: {error}")]
    Layout {
        /// The file or `<layout_json>`.
        source_name: String,
        /// The cause.
        error: LayoutError,
    },
    /// A parameter or the problem is invalid.
    #[error(transparent)]
    Eval(#[from] EvalError),
    /// An improvement parameter is invalid.
    #[error(transparent)]
    Param(#[from] SequencerParamError),
    /// The precedence rules cannot be met.
    #[error("precedence: {0}")]
    Precedence(#[from] Violation),
    /// The kerf or the leads do not fit the layout (names the contours).
    #[error("{source_name}: {error}")]
    Cut {
        /// The file or `<layout_json>`.
        source_name: String,
        /// The contours and why.
        error: Box<CutError>,
    },
    /// The layout's sheet at the raster's `cell_mm` is over
    /// [`crate::thermal::MAX_RASTER_CELLS`], or its contours' cutting over
    /// [`crate::thermal::MAX_CUT_STEPS`] raster steps.
    #[error("{source_name}: {error}")]
    Raster {
        /// The file or `<layout_json>`.
        source_name: String,
        /// The sheet, the cell size and the limit.
        error: SequencerParamError,
    },
    /// A part lies outside the machine's travel once the sheet is placed.
    #[error("{source_name}: {error}")]
    OutOfTravel {
        /// The file or `<layout_json>`.
        source_name: String,
        /// The part, its extent and the travel.
        error: Box<OutOfTravel>,
    },
}

/// Which stage a progress report is from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Reading the layout and building the problem.
    Load,
    /// The greedy construction.
    Construction,
    /// The improvement phase.
    Improvement,
    /// The final thermal simulation.
    Simulation,
}

impl Phase {
    /// The phase's name, as the action feedback carries it.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Load => "load",
            Phase::Construction => "construction",
            Phase::Improvement => "improvement",
            Phase::Simulation => "simulation",
        }
    }
}

/// Figures of one phase (for reports).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhaseFigures {
    /// Which phase.
    pub phase: Phase,
    /// Wall-clock time, s.
    pub seconds: f64,
    /// Cost of the plan after it (0 for the load phase).
    pub cost: f64,
    /// Idle length after it, mm.
    pub idle_mm: f64,
    /// Overheats after it.
    pub overheats: usize,
}

/// A progress report: the phase, the iteration in it and the best cost so far.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JobProgress {
    /// Current phase.
    pub phase: Phase,
    /// Iteration within the phase (LNS iterations in the improvement).
    pub iteration: usize,
    /// Best cost so far (the improvement reports its surrogate cost).
    pub best_cost: f64,
    /// Idle length of the best plan known, mm (the construction's during the improvement).
    pub best_idle_mm: f64,
    /// Overheats of the best plan known (the construction's during the improvement; 0 until
    /// known when a policy that does not read the raster is improved: then the construction's
    /// raster run goes alongside the search, [`crate::improve::Start::Cuts`]).
    pub best_overheats: usize,
}

/// What a job produced.
#[derive(Debug, Clone)]
pub struct SheetOutcome {
    /// The problem the plan is for.
    pub problem: Problem,
    /// Where its sheet is on the machine, and the rule that found it.
    pub sheet: SheetPlacement,
    /// What the cut spec did (kerf, leads, holes left out), if the job had one.
    pub cut: Option<CutSummary>,
    /// The final plan (metrics from the final simulation).
    pub plan: CutPlan,
    /// What cutting each contour of `plan` did on the raster, in cut order (thermal cost off
    /// too: the final plan is always simulated); overheats sit at the cuts' pierce points.
    pub per_cut: Vec<CutThermal>,
    /// Where each overheat of `plan` was counted (a pierce point or the start of a hot cut
    /// segment), in cut order and sheet coordinates.
    pub overheat_points: Vec<Point>,
    /// The construction's plan.
    pub constructed: CutPlan,
    /// Whether the improvement ran.
    pub improved: bool,
    /// Per-phase figures, in order.
    pub phases: Vec<PhaseFigures>,
    /// Total wall-clock time, s.
    pub seconds: f64,
}

/// Reads the layout and builds the problem (seed 003 §A1, §2).
///
/// # Errors
/// [`JobError::Dxf`] or [`JobError::Layout`], naming the file (or `<layout_json>`) and the
/// entity or field.
pub fn load_problem(job: &SheetJob) -> Result<Problem, JobError> {
    load_placed_problem(job).map(|(problem, _, _)| problem)
}

/// As [`load_problem`], with where the sheet is: the rule that found it and its origin (the
/// operator's [`SheetJob::sheet_origin`] if given); checked against [`SheetJob::travel`].
///
/// # Errors
/// As [`load_problem`], and [`JobError::OutOfTravel`] naming the first part outside the travel.
pub fn load_placed_problem(
    job: &SheetJob,
) -> Result<(Problem, SheetPlacement, Option<CutSummary>), JobError> {
    let ((mut layout, rule), name) = match &job.layout {
        LayoutSource::File(path) => (
            read_layout_with_rule(path, &job.dxf)?,
            path.display().to_string(),
        ),
        LayoutSource::Json(text) => {
            let name = "<layout_json>".to_string();
            let l = Layout::from_json_str(text, &name).map_err(JobError::Json)?;
            ((l, SheetRule::Layout), name)
        }
    };
    if let Some(origin) = job.sheet_origin {
        layout.origin = origin;
    }
    // The raster the sheet needs, before any work on the layout (issue 23: a 10¹² mm sheet);
    // a sheet that is no size at all is the layout's error, below.
    job.thermal.validate()?;
    job.pierce_options.validate()?;
    if layout.sheet.iter().all(|v| v.is_finite() && *v > 0.0) {
        job.thermal
            .raster_size(layout.sheet)
            .map_err(|error| JobError::Raster {
                source_name: name.clone(),
                error,
            })?;
    }
    // And the raster steps cutting the drawn contours takes (a comb of long thin teeth).
    let cut_mm: f64 = layout
        .parts
        .iter()
        .flat_map(|p| std::iter::once(&p.outer).chain(&p.holes))
        .map(|r| ring_perimeter(&r.points, Norm::Hypot))
        .sum();
    job.thermal
        .check_cut_steps(cut_mm)
        .map_err(|error| JobError::Raster {
            source_name: name.clone(),
            error,
        })?;
    let placement = SheetPlacement {
        rule,
        size_mm: layout.sheet,
        origin_mm: layout.origin,
        origin_from: if job.sheet_origin.is_some() {
            OriginFrom::Operator
        } else {
            OriginFrom::Drawing
        },
    };
    let pierce = match job.pierce {
        PierceMode::Fixed => PierceOptions {
            max_candidates: 1,
            ..job.pierce_options
        },
        PierceMode::Free => job.pierce_options,
    };
    // With a cut spec: cut paths offset by the kerf and leads ([`crate::cut`]).
    let (problem, cut) = match &job.cut {
        None => layout
            .to_problem(job.precedence, &pierce)
            .map(|p| (p, None))
            .map_err(|error| JobError::Layout {
                source_name: name.clone(),
                error,
            })?,
        Some(spec) => cut_problem(&layout, job.precedence, &pierce, spec)
            .map(|(p, s)| (p, Some(s)))
            .map_err(|error| match error {
                CutError::Layout(error) => JobError::Layout {
                    source_name: name.clone(),
                    error,
                },
                error => JobError::Cut {
                    source_name: name.clone(),
                    error: Box::new(error),
                },
            })?,
    };
    if let Some(travel) = &job.travel {
        let part_name = |i: usize| match &layout.parts[i].name {
            Some(n) => format!("parts[{i}] ({n})"),
            None => format!("parts[{i}]"),
        };
        check_travel(&problem, travel, part_name).map_err(|error| JobError::OutOfTravel {
            source_name: name,
            error: Box::new(error),
        })?;
    }
    Ok((problem, placement, cut))
}

/// Runs the job (module docs). `progress` gets a report at every phase change and after every
/// improvement iteration; `frame` gets a raster frame every `frame_every` spread steps of the
/// final simulation (seed 003 §A3).
///
/// # Errors
/// [`JobError`]: a bad layout (naming file and entity or field), bad parameters (naming the
/// field), or rules that cannot be met.
pub fn run(
    job: &SheetJob,
    progress: impl FnMut(JobProgress),
    frame_every: u64,
    frame: &mut dyn FnMut(&Frame),
) -> Result<SheetOutcome, JobError> {
    run_until(job, progress, frame_every, frame, &|| false)
}

/// As [`run`], with a cancel hook: once `stop` returns true the improvement phase ends early
/// ([`crate::improve::ImproveOptions::stop`]) and the job finishes with the best plan so far.
///
/// # Errors
/// As [`run`].
pub fn run_until(
    job: &SheetJob,
    progress: impl FnMut(JobProgress),
    frame_every: u64,
    frame: &mut dyn FnMut(&Frame),
    stop: &dyn Fn() -> bool,
) -> Result<SheetOutcome, JobError> {
    // Shared by the improvement's feedback and the best order's run.
    let progress = std::cell::RefCell::new(progress);
    let progress = |p: JobProgress| (progress.borrow_mut())(p);
    let t0 = Instant::now();
    let mut phases = Vec::new();
    let report = |phase: Phase, plan: &CutPlan| JobProgress {
        phase,
        iteration: 0,
        best_cost: plan.cost,
        best_idle_mm: plan.idle_mm,
        best_overheats: plan.overheats,
    };
    progress(report(Phase::Load, &CutPlan::default()));
    let (problem, sheet, cut) = load_placed_problem(job)?;
    phases.push(PhaseFigures {
        phase: Phase::Load,
        seconds: t0.elapsed().as_secs_f64(),
        cost: 0.0,
        idle_mm: 0.0,
        overheats: 0,
    });
    let eval = Evaluator::new(&problem, job.thermal.clone(), job.cost.clone())?;
    let mut params = job.improve_params.clone();
    params.seed = job.seed;
    if job.improve {
        params.validate()?;
    }

    progress(report(Phase::Construction, &CutPlan::default()));
    let t = Instant::now();
    // The best plan's raster run with its per-cut figures, if the improvement already made it.
    let mut simulated: Option<(CutPlan, ThermalOutcome)> = None;
    // The improvement's run of its best order: it streams the frames and keeps its per-cut
    // figures, so the final simulation below is only needed if the start order wins.
    let mut best_run: Option<(CutPlan, ThermalOutcome)> = None;
    let run_best = |best: &[Cut]| {
        progress(report(Phase::Simulation, &eval.assemble(best, None)));
        let (plan, thermal) = simulate(&eval, best, frame_every, &mut *frame);
        best_run = Some((plan.clone(), thermal));
        plan
    };
    let (constructed, best) = if job.improve && !job.policy.is_thermal() {
        // The order alone; its raster run goes alongside the improvement's search.
        let cuts = construct_cuts(&eval, job.policy, job.seed)?;
        let order_s = t.elapsed().as_secs_f64();
        let order = eval.assemble(&cuts, None);
        progress(report(Phase::Construction, &order));
        let t = Instant::now();
        let start = JobProgress {
            best_overheats: 0,
            ..report(Phase::Improvement, &order)
        };
        progress(start);
        let Improved {
            start: constructed,
            best: improved,
        } = improve(
            &eval,
            Start::Cuts(&cuts),
            ImproveOptions {
                params,
                feedback: Some(&mut |p: Progress| {
                    progress(JobProgress {
                        iteration: p.iteration,
                        best_cost: p.best_cost,
                        ..start
                    })
                }),
                stop: Some(stop),
                run_best: Some(Box::new(run_best)),
            },
        )?;
        simulated = best_run.filter(|(plan, _)| *plan == improved);
        phases.push(PhaseFigures {
            seconds: order_s,
            ..figures(Phase::Construction, t, &constructed)
        });
        phases.push(figures(Phase::Improvement, t, &improved));
        (constructed, improved)
    } else {
        let constructed = construct(&eval, job.policy, job.seed)?;
        phases.push(figures(Phase::Construction, t, &constructed));
        progress(report(Phase::Construction, &constructed));
        let best = if job.improve {
            let t = Instant::now();
            let start = report(Phase::Improvement, &constructed);
            progress(start);
            let improved = improve(
                &eval,
                Start::Plan(&constructed),
                ImproveOptions {
                    params,
                    feedback: Some(&mut |p: Progress| {
                        progress(JobProgress {
                            iteration: p.iteration,
                            best_cost: p.best_cost,
                            ..start
                        })
                    }),
                    stop: Some(stop),
                    run_best: Some(Box::new(run_best)),
                },
            )?
            .best;
            simulated = best_run.filter(|(plan, _)| *plan == improved);
            phases.push(figures(Phase::Improvement, t, &improved));
            improved
        } else {
            constructed.clone()
        };
        (constructed, best)
    };

    let t = Instant::now();
    let (plan, thermal) = match simulated {
        Some(done) => done,
        None => {
            progress(report(Phase::Simulation, &best));
            simulate(&eval, &best.cuts, frame_every, frame)
        }
    };
    phases.push(figures(Phase::Simulation, t, &plan));
    progress(report(Phase::Simulation, &plan));
    Ok(SheetOutcome {
        problem,
        sheet,
        cut,
        plan,
        per_cut: thermal.per_cut,
        overheat_points: thermal.overheat_points,
        constructed,
        improved: job.improve,
        phases,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The raster run of `cuts` with frames every `frame_every` steps: the plan and the raster's
/// outcome (per-cut figures, overheat points). Thermal cost off (module docs), the plan keeps
/// its idle-only cost and takes the run's overheats, maximum temperature and time.
fn simulate(
    eval: &Evaluator,
    cuts: &[Cut],
    frame_every: u64,
    frame: &mut dyn FnMut(&Frame),
) -> (CutPlan, ThermalOutcome) {
    let problem = eval.problem;
    let mut sim = eval.sim().with_frames(frame_every.max(1), frame);
    for c in cuts {
        sim.cut(&problem.contours[c.contour], c.pierce);
    }
    let out = sim.finish(problem.start);
    let mut plan = eval.assemble(cuts, Some(&out));
    if !eval.cost_params().thermal {
        plan.overheats = out.overheats;
        plan.max_temp_c = out.max_temp_c;
        plan.time_s = out.time_s;
    }
    (plan, out)
}

fn figures(phase: Phase, t: Instant, plan: &CutPlan) -> PhaseFigures {
    PhaseFigures {
        phase,
        seconds: t.elapsed().as_secs_f64(),
        cost: plan.cost,
        idle_mm: plan.idle_mm,
        overheats: plan.overheats,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(name: &str) -> PathBuf {
        PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../tests/data/sheet"
        ))
        .join(name)
    }

    /// The plate nest with `policy` and a short improvement.
    fn plate_job(policy: Policy) -> SheetJob {
        SheetJob {
            layout: LayoutSource::File(data("plate_holes_nest.json")),
            policy,
            improve_params: ImproveParams {
                max_iterations: 20,
                ..Default::default()
            },
            ..Default::default()
        }
    }

    /// The frames of one raster run of `out`'s plan at `every` steps: its steps, once each
    /// (a second run would start over).
    fn assert_one_run_of_frames(out: &SheetOutcome, job: &SheetJob, frames: &[u64], every: u64) {
        let steps = (out.plan.time_s / job.thermal.dt_s()).round() as u64;
        let expected: Vec<u64> = (1..=steps / every).map(|k| every * k).collect();
        assert_eq!(frames, expected);
    }

    /// A comb of `teeth` teeth 1 mm wide and 9 m long on a 10 × 10 m sheet: ~18 m of cut each.
    fn comb(teeth: usize) -> String {
        let mut points = vec![[0.0, 0.0]];
        for t in 0..teeth {
            let x = 1.0 + 2.0 * t as f64;
            points.extend([[x, 0.0], [x, 9000.0], [x + 1.0, 9000.0], [x + 1.0, 0.0]]);
        }
        points.push([2.0 * teeth as f64 + 1.0, -0.0]);
        points.push([2.0 * teeth as f64 + 1.0, -1.0]);
        points.push([0.0, -1.0]);
        let pts: Vec<String> = points
            .iter()
            .map(|p| format!("[{},{}]", p[0], p[1] + 1.0))
            .collect();
        format!(
            r#"{{"sheet":[10000,10000],"parts":[{{"name":"comb","outer":{{"points":[{}]}}}}]}}"#,
            pts.join(",")
        )
    }

    #[test]
    fn contours_over_the_cut_step_limit_are_refused_before_any_work() {
        let job = |teeth: usize| SheetJob {
            layout: LayoutSource::Json(comb(teeth)),
            improve: false,
            ..Default::default()
        };
        // 2000 teeth: 3.6·10⁷ mm, 9·10⁶ steps at 4 mm, is loaded.
        let p = load_problem(&job(2000)).unwrap();
        assert_eq!(p.contours.len(), 1);
        let e = load_problem(&job(3000)).unwrap_err().to_string();
        assert!(
            e.starts_with("<layout_json>: the contours' cut length of 54")
                && e.ends_with(
                    "mm at cell_mm = 4 mm is 1.350e7 raster steps: the limit is 10000000 steps \
                     (MAX_CUT_STEPS)"
                ),
            "{e}"
        );
    }

    #[test]
    fn a_sheet_over_the_raster_limit_is_refused_before_any_work() {
        let job = SheetJob {
            layout: LayoutSource::Json(
                r#"{"sheet":[1e12,1e12],"parts":[{"outer":{"points":[[10,10],[60,10],[60,60]]}}]}"#
                    .into(),
            ),
            ..Default::default()
        };
        let e = load_problem(&job).unwrap_err().to_string();
        assert_eq!(
            e,
            "<layout_json>: sheet 1000000000000 × 1000000000000 mm at cell_mm = 4 mm is a \
             raster of 6.250e22 cells: the limit is 100000000 cells (MAX_RASTER_CELLS)"
        );
    }

    #[test]
    fn a_job_cuts_every_contour_once_in_a_valid_order_and_reports_frames() {
        let job = plate_job(Policy::PathOverheat);
        let mut phases = Vec::new();
        let mut frames = Vec::new();
        let out = run(&job, |p| phases.push(p.phase), 50, &mut |f| {
            frames.push(f.step)
        })
        .unwrap();
        let mut order = out.plan.order();
        out.problem.precedence.check_order(&order).unwrap();
        order.sort_unstable();
        assert_eq!(order, (0..out.problem.contours.len()).collect::<Vec<_>>());
        // One raster run streamed (the improvement's run of its best order, or the final
        // simulation if there was none).
        assert_one_run_of_frames(&out, &job, &frames, 50);
        assert!(phases.contains(&Phase::Improvement));
        assert_eq!(*phases.last().unwrap(), Phase::Simulation);
        assert!(out.plan.cost <= out.constructed.cost + 1e-9);
        assert_eq!(out.per_cut.len(), out.plan.cuts.len());
        let per_cut: usize = out
            .per_cut
            .iter()
            .map(|c| c.pierce_overheats + c.segment_overheats)
            .sum();
        assert_eq!(per_cut, out.plan.overheats);
        // One overheat point per overheat, each on the sheet.
        assert_eq!(out.overheat_points.len(), out.plan.overheats);
        let [a, b] = out.problem.sheet;
        assert!(out
            .overheat_points
            .iter()
            .all(|p| (0.0..=a).contains(&p[0]) && (0.0..=b).contains(&p[1])));
    }

    /// A policy that does not read the raster: its raster run goes alongside the search, and
    /// the job reports the same construction as the plain one.
    #[test]
    fn nearest_with_improvement_reports_the_evaluated_construction() {
        let job = plate_job(Policy::Nearest);
        let mut frames = Vec::new();
        let out = run(&job, |_| {}, 50, &mut |f| frames.push(f.step)).unwrap();
        let eval = Evaluator::new(&out.problem, job.thermal.clone(), job.cost.clone()).unwrap();
        assert_eq!(
            out.constructed,
            construct(&eval, Policy::Nearest, job.seed).unwrap()
        );
        assert!(
            out.constructed.overheats > 0,
            "the plate's nearest order overheats"
        );
        let kinds: Vec<Phase> = out.phases.iter().map(|p| p.phase).collect();
        assert_eq!(
            kinds,
            [
                Phase::Load,
                Phase::Construction,
                Phase::Improvement,
                Phase::Simulation
            ]
        );
        assert_eq!(out.phases[1].overheats, out.constructed.overheats);
        assert!(out.plan.cost <= out.constructed.cost + 1e-9);
        assert_eq!(out.plan, eval.evaluate(&out.plan.cuts));
        // The improved order won, so its raster run inside the improvement streamed the
        // frames and no other run did.
        assert!(out.plan.cost < out.constructed.cost);
        assert_one_run_of_frames(&out, &job, &frames, 50);
        assert_eq!(out.per_cut.len(), out.plan.cuts.len());
    }

    #[test]
    fn bad_layouts_name_the_source_and_the_entity_or_field() {
        let job = SheetJob {
            layout: LayoutSource::File(data("broken_open_chain.dxf")),
            ..Default::default()
        };
        let e = run(&job, |_| {}, 1, &mut |_| {}).unwrap_err().to_string();
        assert!(
            e.contains("broken_open_chain.dxf") && e.contains("open contour"),
            "{e}"
        );
        let job = SheetJob {
            layout: LayoutSource::Json(r#"{"sheet": [100, 100], "parts": [{"outer": 3}]}"#.into()),
            ..Default::default()
        };
        let e = run(&job, |_| {}, 1, &mut |_| {}).unwrap_err().to_string();
        assert!(
            e.contains("<layout_json>") && e.contains("parts[0].outer"),
            "{e}"
        );
    }

    #[test]
    fn names_parse_both_ways() {
        for p in Policy::ALL {
            assert_eq!(parse_policy(policy_name(p)), Ok(p));
        }
        assert!(parse_policy("fastest")
            .unwrap_err()
            .to_string()
            .contains("fastest"));
        assert_eq!(parse_precedence("relaxed"), Ok(PrecedenceMode::Relaxed));
        assert!(parse_precedence("loose").is_err());
        assert_eq!(PierceMode::parse("fixed"), Ok(PierceMode::Fixed));
    }

    #[test]
    fn fixed_pierce_mode_gives_one_candidate_per_contour() {
        let job = SheetJob {
            layout: LayoutSource::File(data("plate_holes_nest.json")),
            pierce: PierceMode::Fixed,
            ..Default::default()
        };
        let p = load_problem(&job).unwrap();
        assert!(p.contours.iter().all(|c| c.pierce_candidates.len() == 1));
    }

    /// Thermal off (module docs): idle length alone is minimised, and the final plan still
    /// reports what its order does to the sheet (one raster run, streamed).
    #[test]
    fn thermal_off_minimises_idle_and_still_reports_the_overheats() {
        let layout = crate::generator::generate(&crate::generator::GeneratorConfig {
            seed: 7,
            contours: 200,
            ..Default::default()
        });
        let on = SheetJob {
            layout: LayoutSource::Json(layout.to_json()),
            improve_params: ImproveParams {
                max_iterations: 50,
                ..Default::default()
            },
            ..Default::default()
        };
        let off = SheetJob {
            cost: CostParams {
                thermal: parse_thermal("off").unwrap(),
                ..Default::default()
            },
            ..on.clone()
        };
        let mut frames = Vec::new();
        let out = run(&off, |_| {}, 100, &mut |f| frames.push(f.step)).unwrap();
        // The cost is what was minimised: idle length and corner penalties, no heat.
        assert_eq!(out.plan.cost, out.plan.idle_mm + out.plan.lead_in_penalty);
        // The overheats, maximum and time are the raster's for that order.
        let heat = Evaluator::new(&out.problem, off.thermal.clone(), CostParams::default())
            .unwrap()
            .evaluate(&out.plan.cuts);
        assert_eq!(
            (out.plan.overheats, out.plan.max_temp_c, out.plan.time_s),
            (heat.overheats, heat.max_temp_c, heat.time_s)
        );
        assert!(out.plan.overheats > 0);
        assert_eq!(out.per_cut.len(), out.plan.cuts.len());
        assert_one_run_of_frames(&out, &off, &frames, 100);
        // Against the thermal cost: shorter idle travel, more overheats.
        let with_heat = run(&on, |_| {}, u64::MAX, &mut |_| {}).unwrap();
        assert!(out.plan.idle_mm < with_heat.plan.idle_mm);
        assert!(out.plan.overheats > with_heat.plan.overheats);
        assert!(parse_thermal("warm")
            .unwrap_err()
            .to_string()
            .contains("warm"));
    }
}
