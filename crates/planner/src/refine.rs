//! Local refinement after the swarm: Levenberg–Marquardt on the exposure residuals.
//!
//! The loss is a sum of squares, L(c) = ‖r(c)‖² with rᵢ = (Eᵢ(c) − CSE)/√N and the smoothing
//! residuals ([`Problem::residuals_into`]). Away from the switches of the visibility χ and the
//! causal cut point, each Eᵢ is a smooth function of the control values (closed-form
//! integrals of smooth path geometry, seed 000 eq. 5), so a Gauss–Newton model of L is good
//! near a minimum and the swarm's slow endgame (it reaches a basin in a few hundred
//! iterations, then halves the residual over thousands) is replaced by a few dozen steps:
//!
//! (JᵀJ + μ·diag(JᵀJ)) δ = −Jᵀr,  c ← c + δ if L(c + δ) < L(c) (then μ ← μ/3), else μ ← 4μ,
//!
//! with J the Jacobian ∂r/∂c by forward differences (one loss evaluation per design variable,
//! evaluated in parallel; a backward difference where the forward point is infeasible). A
//! step that would break the clearance has L = +∞ and is refused like any worse step, so the
//! iterate stays feasible; the largest control change per step is capped at
//! [`RefineConfig::max_step_mm`] (a trust region in mm, since the Gauss–Newton model of
//! E ∝ ln ‖R‖ is poor far from the current path).
//!
//! Why hand-written: the `levenberg-marquardt` crate's problem trait has no way to refuse a
//! step as infeasible (a non-finite residual ends its run) and brings its own MINPACK-style
//! scaling; the iteration above is 60 lines over `nalgebra`'s Cholesky, which the crate uses
//! anyway.

use std::ops::ControlFlow;

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use crate::problem::{Problem, Scratch};

/// Refinement settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RefineConfig {
    /// Most Levenberg–Marquardt iterations (default 60; 0 switches refinement off).
    pub iterations: usize,
    /// Forward-difference step for the Jacobian, in the design variables' unit (mm for the
    /// path, ln ρ for the feed; default 2e-3: the f32 exposure kernel's rounding, ~1e-6 of E,
    /// is then ~1e-3 of a typical difference).
    pub step: f64,
    /// Largest change of any design variable in one step (default 1.0).
    pub max_step_mm: f64,
    /// Stop when an accepted step lowers the loss by less than this fraction of it
    /// (default 1e-4).
    pub tolerance: f64,
}

impl Default for RefineConfig {
    fn default() -> Self {
        Self {
            iterations: 60,
            step: 2e-3,
            max_step_mm: 1.0,
            tolerance: 1e-4,
        }
    }
}

/// What [`refine`] reports after each iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineProgress {
    /// Iterations done (1-based).
    pub iteration: usize,
    /// Loss after it.
    pub loss: f64,
}

/// The refinement's result.
#[derive(Debug, Clone, PartialEq)]
pub struct RefineResult {
    /// The refined design vector (the start if no step helped).
    pub controls: Vec<f64>,
    /// Its loss.
    pub loss: f64,
    /// The start's loss.
    pub start_loss: f64,
    /// Iterations run.
    pub iterations: usize,
    /// Loss evaluations made.
    pub evaluations: usize,
    /// (iteration, loss) after every accepted step.
    pub history: Vec<(usize, f64)>,
    /// True if the progress callback stopped the run.
    pub cancelled: bool,
}

/// Refines `start` on `problem` (module docs). `progress` is called after every iteration;
/// [`ControlFlow::Break`] stops the run with the best so far. A start with L = +∞ is returned
/// unchanged.
pub fn refine(
    problem: &Problem,
    start: &[f64],
    config: &RefineConfig,
    mut progress: impl FnMut(RefineProgress) -> ControlFlow<()>,
) -> RefineResult {
    let dim = start.len();
    let mut scratch = Scratch::default();
    let mut r = Vec::new();
    let mut x = start.to_vec();
    // The start is clamped into the bounds (the swarm keeps to them; a caller's may not).
    let (lo, hi) = problem.bounds();
    for ((v, l), u) in x.iter_mut().zip(&lo).zip(&hi) {
        *v = v.clamp(*l, *u);
    }
    let feasible = problem.residuals_into(&x, &mut scratch, &mut r);
    let mut loss = if feasible {
        r.iter().map(|v| v * v).sum::<f64>()
    } else {
        f64::INFINITY
    };
    let mut result = RefineResult {
        controls: x.clone(),
        loss,
        start_loss: loss,
        iterations: 0,
        evaluations: 1,
        history: vec![(0, loss)],
        cancelled: false,
    };
    if !feasible || config.iterations == 0 || dim == 0 {
        return result;
    }
    let (lower, upper) = problem.bounds();
    let mut mu = 1e-3;
    let h = config.step;
    for it in 1..=config.iterations {
        // Forward differences (backward at an upper bound or where forward is infeasible), one
        // column per design variable, in parallel.
        let columns: Vec<Option<Vec<f64>>> = (0..dim)
            .into_par_iter()
            .map_init(
                || (Scratch::default(), Vec::new()),
                |(scratch, out), d| {
                    let mut probe = x.clone();
                    let signs = if x[d] + h > upper[d] {
                        [-1.0, 1.0]
                    } else {
                        [1.0, -1.0]
                    };
                    for sign in signs {
                        probe[d] = x[d] + sign * h;
                        if problem.residuals_into(&probe, scratch, out) {
                            return Some(
                                out.iter()
                                    .zip(&r)
                                    .map(|(a, b)| (a - b) / (sign * h))
                                    .collect(),
                            );
                        }
                    }
                    None
                },
            )
            .collect();
        result.evaluations += dim;
        let jac = DMatrix::from_fn(r.len(), dim, |i, d| {
            columns[d].as_ref().map_or(0.0, |c| c[i])
        });
        let grad = jac.transpose() * DVector::from_column_slice(&r);
        // Variables held at a bound that the descent direction pushes against stay there; the
        // step is solved for the others (a projected Gauss–Newton step).
        let free: Vec<usize> = (0..dim)
            .filter(|&d| {
                let at_lower = x[d] <= lower[d] + 1e-12 && grad[d] > 0.0;
                let at_upper = x[d] >= upper[d] - 1e-12 && grad[d] < 0.0;
                columns[d].is_some() && !at_lower && !at_upper
            })
            .collect();
        if free.is_empty() {
            break;
        }
        let jf = jac.select_columns(&free);
        let jtj = jf.transpose() * &jf;
        let gf = DVector::from_iterator(free.len(), free.iter().map(|&d| grad[d]));
        let mut accepted = false;
        for _ in 0..16 {
            let mut a = jtj.clone();
            for d in 0..free.len() {
                a[(d, d)] += mu * jtj[(d, d)].max(1e-12);
            }
            let Some(chol) = a.cholesky() else {
                mu *= 4.0;
                continue;
            };
            let mut step = chol.solve(&(-&gf));
            let largest = step.amax();
            if largest > config.max_step_mm {
                step *= config.max_step_mm / largest;
            }
            let mut trial = x.clone();
            for (q, &d) in free.iter().enumerate() {
                trial[d] = (x[d] + step[q]).clamp(lower[d], upper[d]);
            }
            let mut trial_r = Vec::new();
            result.evaluations += 1;
            let trial_loss = if problem.residuals_into(&trial, &mut scratch, &mut trial_r) {
                trial_r.iter().map(|v| v * v).sum::<f64>()
            } else {
                f64::INFINITY
            };
            if trial_loss < loss {
                let gain = (loss - trial_loss) / loss;
                x = trial;
                r = trial_r;
                loss = trial_loss;
                mu = (mu / 3.0).max(1e-9);
                accepted = gain >= config.tolerance;
                result.history.push((it, loss));
                break;
            }
            mu *= 4.0;
        }
        result.iterations = it;
        result.controls.clone_from(&x);
        result.loss = loss;
        if progress(RefineProgress {
            iteration: it,
            loss,
        })
        .is_break()
        {
            result.cancelled = true;
            break;
        }
        if !accepted {
            break;
        }
    }
    result
}
