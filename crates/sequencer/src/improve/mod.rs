//! Improvement phase after the greedy construction (ours, beyond seed 003 §A4, which only
//! mentions a later 2-opt; notes §A6): it never breaks precedence and never returns a plan
//! worse than its start.
//!
//! 1. **Local search** on a *surrogate* cost. Without the heat proxy (thermal cost off): 2-opt
//!    and Or-opt (runs of 1..=3, either way round) between each contour and its 14 nearest
//!    contours, at any distance along the sequence, with O(1) idle deltas. Then, and always
//!    with the proxy: precedence-aware Or-opt (move a run of 1..=
//!    `or_opt_max_len` cuts within `window` positions), 2-opt (reverse a run of up to
//!    `window` cuts) and pierce re-selection at every position. A move is applied in place,
//!    checked locally (predecessors inside the moved span keep their order; every group stays
//!    contiguous) and kept only if the surrogate drops.
//!
//!    Pruning (none of it changes a plan): both kinds of sweep keep don't-look bits
//!    (Bentley's, as LKH does): a sweep examines only contours near a change since their last
//!    fruitless look, and the remove-and-reinsert step wakes the contours at the edges it
//!    changed. The window sweep keeps every position's surrogate term and its proxy part as
//!    prefix sums, so a move's cost before is two lookups; a move whose idle change alone
//!    exceeds the proxy it could remove is dropped unseen, and the cost after stops summing
//!    once it reaches the cost before (every term is ≥ 0).
//! 2. **Large-neighbourhood search** (GLNS-style remove and reinsert): remove `lns_remove`
//!    cuts close to a random seed cut, reinsert them in their old relative order, each at the
//!    cheapest feasible position with its cheapest pierce candidate; keep the result if the
//!    surrogate does not rise. Without the heat proxy every reinsertion is first polished
//!    with the neighbour-list moves (iterated local search). The best order is polished with
//!    local search once more.
//! 3. The best surrogate plan is evaluated with the full thermal raster ([`Evaluator`]); if its
//!    true cost is above the start's, the start is returned. If it is the start order, no
//!    raster run is needed. From a start order not evaluated yet ([`Start::Cuts`]) the
//!    start's raster run goes on a second thread alongside the search and the best order's run.
//!
//! **Surrogate** = idle length + corner penalties + (thermal cost on) a heat proxy: for every
//! cut `b` and each of the `proxy_lookback` cuts `a` before it, `w_overheat_mm ·
//! proxy_weight · e(a, b) · ½^(s / proxy_half_life_mm)`, where the *exposure* `e(a, b)` counts
//! the places of `b` the overheat metric checks (points every `segment_mm` along it) that lie
//! within `proxy_radius_mm` of `a`'s polyline, and `s` is the cutting (plus pierce dwell at
//! cut speed) between the middle of `a`'s cut and the start of `b`'s, mm. A full raster run
//! per move would cost a whole simulation each; the proxy keeps a move's evaluation local to
//! the moved span.
//!
//! **Pierce term** of the proxy: a cut `b` pierced where the overheat test's window (the raster
//! cells within `overheat_radius_cells` of the pierce point's cell) holds the polyline of one
//! of its look-back cuts `a` costs `(w_overheat_mm +
//! hot_penalty_mm) · proxy_weight` while `a`'s kerf is still above `t_max`, i.e. while the
//! cutting in between (as above) is below `cell_mm · ln((t_melt − ambient)/(t_max − ambient)) /
//! −ln(k_loss)` (a kerf at melting temperature decaying by `k_loss` per step alone; 1290 mm with
//! the defaults). This is what moves pierce points and hole orders away from fresh kerf (most
//! overheats a plain order leaves are pierces of small holes next to the hole cut just before).
//!
//! **Idle budget** (thermal cost on, `idle_budget > 0`; issue 7 target "≤ 1.5× the idle length
//! of nearest-neighbour"): the budget is `idle_budget ×` the idle length of the nearest-pierce
//! order of the same problem ([`crate::policy::nearest_cuts`]). Every move must also keep the
//! idle length within it, or shorten it; a start above the budget can only move towards it.
//! The overheat/idle trade-off is thus a constrained one: the proxy weight can stay high without
//! the idle length running away.
//!
//! **Cancellation**: the search polls [`ImproveOptions::stop`] with the time budget; once it
//! returns true the search ends and the best order so far is evaluated as usual.
//!
//! Deterministic for a seed when the time budget does not bind (`time_budget_ms = 0`).
//!
//! Files: `params` (the knobs), `search` (the state), `proxy` (the heat proxy's tables and
//! terms), `cache` (terms and their prefix sums), `moves`, `window_sweep`, `neighbour_sweep`,
//! `local_search` (step 1), `lns` (step 2 and the whole search), `distance`.

mod cache;
mod distance;
mod lns;
mod local_search;
mod moves;
mod neighbour_sweep;
mod params;
mod proxy;
mod search;
mod window_sweep;

use crate::cost::Evaluator;
use crate::plan::{Cut, CutPlan};
use crate::problem::ContourId;
use crate::thermal::SequencerParamError;

pub use params::{
    ImproveParams, MAX_IMPROVE_ITERATIONS, MAX_LNS_REMOVE, MAX_LOCAL_SWEEPS, MAX_OR_OPT_LEN,
    MAX_WINDOW,
};

/// Progress report for the action feedback (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// LNS iterations done.
    pub iteration: usize,
    /// Best surrogate cost so far (the true cost is only known at the end).
    pub best_cost: f64,
}

/// Where an improvement starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start<'a> {
    /// An evaluated plan: its true cost is known.
    Plan(&'a CutPlan),
    /// An order not evaluated yet (e.g. the nearest-pierce order of
    /// [`crate::policy::construct_cuts`]): its raster run goes on a second thread alongside the
    /// search and then the best order's own run (unless the best is the start order), so the
    /// wall time is about the search plus one raster run. Same results as
    /// [`Evaluator::evaluate`] then [`Start::Plan`].
    Cuts(&'a [Cut]),
}

/// How one improvement runs: its knobs and the caller's hooks. `ImproveOptions::default()`
/// searches with the default knobs, reports nothing, never stops early and evaluates the best
/// order with [`Evaluator::evaluate`].
#[derive(Default)]
pub struct ImproveOptions<'a> {
    /// The knobs of the search.
    pub params: ImproveParams,
    /// Called after every LNS iteration.
    pub feedback: Option<&'a mut dyn FnMut(Progress)>,
    /// Polled between moves and LNS iterations (e.g. an action's cancel flag): once it returns
    /// true the search ends, and the best order so far gets its true evaluation (still never
    /// worse than the start).
    pub stop: Option<&'a dyn Fn() -> bool>,
    /// The best order's evaluation, e.g. a raster run that streams frames; it must return
    /// [`Evaluator::evaluate`]'s plan. Called at most once, on the calling thread, and not when
    /// the best order is the start order. `None`: [`Evaluator::evaluate`].
    pub run_best: Option<RunBest<'a>>,
}

impl std::fmt::Debug for ImproveOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ImproveOptions")
            .field("params", &self.params)
            .field("feedback", &self.feedback.is_some())
            .field("stop", &self.stop.is_some())
            .field("run_best", &self.run_best.is_some())
            .finish()
    }
}

/// The best order's evaluation hook of [`ImproveOptions::run_best`].
pub type RunBest<'a> = Box<dyn FnOnce(&[Cut]) -> CutPlan + 'a>;

/// What an improvement returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Improved {
    /// The start plan, evaluated.
    pub start: CutPlan,
    /// The improved plan, never worse than the start.
    pub best: CutPlan,
}

/// Improves `start` (module docs) as `options` say.
///
/// # Errors
/// An invalid [`ImproveParams`] field, or a start order naming a contour or pierce candidate
/// the problem does not have (field `start.cuts`).
pub fn improve(
    eval: &Evaluator,
    start: Start<'_>,
    options: ImproveOptions<'_>,
) -> Result<Improved, SequencerParamError> {
    let ImproveOptions {
        params,
        feedback,
        stop,
        run_best,
    } = options;
    let mut no_feedback = |_: Progress| {};
    let feedback: &mut dyn FnMut(Progress) = match feedback {
        Some(f) => f,
        None => &mut no_feedback,
    };
    let stop = stop.unwrap_or(&|| false);
    let run_best = |cuts: &[Cut]| match run_best {
        Some(run) => run(cuts),
        None => eval.evaluate(cuts),
    };
    match start {
        Start::Plan(start) => {
            let best = improve_plan(eval, start, &params, feedback, stop, run_best)?;
            Ok(Improved {
                start: start.clone(),
                best,
            })
        }
        Start::Cuts(start) => improve_cuts(eval, start, &params, feedback, stop, run_best),
    }
}

/// [`improve`] from an evaluated plan.
fn improve_plan(
    eval: &Evaluator,
    start: &CutPlan,
    params: &ImproveParams,
    feedback: &mut dyn FnMut(Progress),
    stop: &dyn Fn() -> bool,
    run_best: impl FnOnce(&[Cut]) -> CutPlan,
) -> Result<CutPlan, SequencerParamError> {
    if !searchable(eval, &start.cuts, params)? {
        return Ok(start.clone());
    }
    let best = lns::search(eval, &start.cuts, params, feedback, stop);
    // The start order again: its true cost is known, no raster run needed.
    if best == start.cuts {
        return Ok(start.clone());
    }
    let plan = run_best(&best);
    Ok(if plan.cost <= start.cost {
        plan
    } else {
        start.clone()
    })
}

/// [`improve`] from an order not evaluated yet ([`Start::Cuts`]).
fn improve_cuts(
    eval: &Evaluator,
    start: &[Cut],
    params: &ImproveParams,
    feedback: &mut dyn FnMut(Progress),
    stop: &dyn Fn() -> bool,
    run_best: impl FnOnce(&[Cut]) -> CutPlan,
) -> Result<Improved, SequencerParamError> {
    if !searchable(eval, start, params)? {
        let plan = eval.evaluate(start);
        return Ok(Improved {
            start: plan.clone(),
            best: plan,
        });
    }
    // The start's run goes on a second thread and may still be running while the best
    // order's run goes on this one: the wall time is the search plus one raster run.
    let (start_plan, best_plan) = std::thread::scope(|scope| {
        let start_run = scope.spawn(|| eval.evaluate(start));
        let best = lns::search(eval, start, params, feedback, stop);
        let best_plan = (best != start).then(|| run_best(&best));
        let start_plan = match start_run.join() {
            Ok(plan) => plan,
            Err(panic) => std::panic::resume_unwind(panic),
        };
        (start_plan, best_plan)
    });
    let better = match best_plan {
        Some(plan) if plan.cost <= start_plan.cost => plan,
        _ => start_plan.clone(),
    };
    Ok(Improved {
        start: start_plan,
        best: better,
    })
}

/// Checks the parameters and the start order; whether there is anything to search (at least
/// two cuts in a feasible order).
fn searchable(
    eval: &Evaluator,
    start: &[Cut],
    params: &ImproveParams,
) -> Result<bool, SequencerParamError> {
    params.validate()?;
    let problem = eval.problem;
    if let Some(c) = start.iter().find(|c| {
        problem
            .contours
            .get(c.contour)
            .is_none_or(|k| c.pierce >= k.pierce_candidates.len())
    }) {
        return Err(SequencerParamError::Invalid {
            field: "start.cuts",
            value: format!("{c:?}"),
            reason: "names a contour or pierce candidate the problem does not have",
        });
    }
    let order: Vec<ContourId> = start.iter().map(|c| c.contour).collect();
    Ok(start.len() >= 2 && problem.precedence.check_order(&order).is_ok())
}

#[cfg(test)]
mod tests;
