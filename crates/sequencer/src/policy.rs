//! The paper's greedy construction with its four `SelectContour` policies (and one of ours) (seed 003 §A4; notes
//! §A4 for the scoring, which the paper does not give).
//!
//! The loop is the paper's `Main`: while the frontier `W` is not empty, pick a contour and a
//! pierce candidate, cut it (heating the live raster), update `W`. With several pierce
//! candidates each policy also picks the pierce point, which makes the problem a generalised
//! TSP. Every score adds the candidate's corner penalty ([`crate::cost`]) to the idle
//! distance `d`.
//!
//! A candidate's *heat* is read on the live raster before it is cut: the hottest
//! neighbourhood ([`ThermalSim::hot_near_c`]) over its pierce point and points every
//! `segment_mm` along the contour (at most 16), the places the overheat metric checks.
//!
//! - [`Policy::Nearest`]: "shortest path", minimum `d`.
//! - [`Policy::MinOverheat`]: "minimisation of overheating": fewest sample points at or above
//!   `t_max`, then the coolest (heat in 25 °C bins), then minimum `d`.
//! - [`Policy::Random`]: "random transitions", uniform over `W` and the candidates, seeded.
//! - [`Policy::PathOverheat`]: the authors' method, "minimisation of the path and overheating
//!   considering real-time temperature": candidates whose heat is at or above `t_max − delta`
//!   are rejected; the nearest of the rest wins. If every candidate is rejected, the score is
//!   `d + w_overheat_mm · hot + hot_penalty_mm · (heat − (t_max − delta)) / max(delta, 1 °C)`
//!   with `hot` the sample points at or above `t_max` (penalised, not rejected, so the loop
//!   always progresses).
//! - [`Policy::CostGreedy`] (ours, beyond the paper): the step of the plan cost itself,
//!   `d + w_overheat_mm · hot + hot_penalty_mm · [pierce heat ≥ t_max − delta]`, with `hot` as
//!   above: the overheats the metric would count if the contour were cut now.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::cost::Evaluator;
use crate::plan::{Cut, CutPlan};
use crate::precedence::{Frontier, Violation};
use crate::problem::{distance, Point};
use crate::thermal::{point_along, ThermalSim};

/// A `SelectContour` variant (seed 003 §A4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Policy {
    /// Nearest pierce point ("shortest path").
    Nearest,
    /// Minimum overheating.
    MinOverheat,
    /// Random transitions (seeded).
    Random,
    /// Path plus overheating with the live temperature (the authors' method).
    PathOverheat,
    /// Ours, beyond the paper: greedy on the plan cost itself (module docs).
    CostGreedy,
}

impl Policy {
    /// All five: the paper's four in its order, then ours.
    pub const ALL: [Policy; 5] = [
        Policy::Nearest,
        Policy::MinOverheat,
        Policy::Random,
        Policy::PathOverheat,
        Policy::CostGreedy,
    ];

    /// The paper's four, in its order.
    pub const PAPER: [Policy; 4] = [
        Policy::Nearest,
        Policy::MinOverheat,
        Policy::Random,
        Policy::PathOverheat,
    ];

    /// Whether the policy reads the live raster.
    pub fn is_thermal(self) -> bool {
        matches!(
            self,
            Policy::MinOverheat | Policy::PathOverheat | Policy::CostGreedy
        )
    }
}

/// Sample points per contour for the heat reading (module docs): every `segment_mm` along
/// the closed polyline, at most 16, evenly spread when the contour is longer.
fn samples(eval: &Evaluator) -> Vec<Vec<Point>> {
    let seg = eval.thermal_params().segment_mm;
    eval.problem
        .contours
        .iter()
        .map(|c| {
            let mut path = c.points.clone();
            if let Some(&first) = c.points.first() {
                path.push(first);
            }
            let len = c.perimeter();
            let k = ((len / seg).floor() as usize).clamp(1, 16);
            (0..k)
                .map(|i| point_along(&path, i as f64 * len / k as f64))
                .collect()
        })
        .collect()
}

/// Builds a plan with `policy` (seed 003 §A4 `Main`), then evaluates it with `eval`.
///
/// # Errors
/// [`Violation::Cycle`] if the rules leave contours that can never be cut.
pub fn construct(eval: &Evaluator, policy: Policy, seed: u64) -> Result<CutPlan, Violation> {
    let (cuts, sim) = build(eval, policy, seed)?;
    // The thermal policies drove the raster through exactly these cuts: reuse the run.
    Ok(match sim {
        Some(s) if eval.cost_params().thermal => {
            let out = s.finish(eval.problem.start);
            eval.assemble(&cuts, Some(&out))
        }
        _ => eval.evaluate(&cuts),
    })
}

/// The order `policy` builds (seed 003 §A4 `Main`) without evaluating it: for the policies
/// that do not read the raster, no raster run at all (the improvement can then evaluate it
/// alongside its search, [`crate::improve::Start::Cuts`]).
///
/// # Errors
/// [`Violation::Cycle`] if the rules leave contours that can never be cut.
pub fn construct_cuts(eval: &Evaluator, policy: Policy, seed: u64) -> Result<Vec<Cut>, Violation> {
    build(eval, policy, seed).map(|(cuts, _)| cuts)
}

/// The nearest-pierce order alone (seed 003 §A4 "shortest path"), without the raster run of
/// its evaluation: the reference of the improvement's idle budget.
///
/// # Errors
/// [`Violation::Cycle`] if the rules leave contours that can never be cut.
pub fn nearest_cuts(eval: &Evaluator) -> Result<Vec<Cut>, Violation> {
    build(eval, Policy::Nearest, 0).map(|(cuts, _)| cuts)
}

/// The greedy loop (seed 003 §A4 `Main`): the cuts, and the raster the thermal policies drove
/// through them.
fn build(
    eval: &Evaluator,
    policy: Policy,
    seed: u64,
) -> Result<(Vec<Cut>, Option<ThermalSim<'static>>), Violation> {
    let problem = eval.problem;
    let rules = &problem.precedence;
    let mut frontier = Frontier::new(rules);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut sim: Option<ThermalSim> = policy.is_thermal().then(|| eval.sim());
    let samples = if policy.is_thermal() {
        samples(eval)
    } else {
        Vec::new()
    };
    let t_max = eval.thermal_params().t_max_c;
    let limit = t_max - eval.thermal_params().delta_c;
    let mut at = problem.start;
    let mut cuts = Vec::with_capacity(problem.contours.len());
    loop {
        let w = frontier.eligible();
        if w.is_empty() {
            break;
        }
        let pick = match policy {
            Policy::Random => {
                let contour = w[rng.random_range(0..w.len())];
                let k = problem.contours[contour].pierce_candidates.len();
                Cut {
                    contour,
                    pierce: rng.random_range(0..k),
                }
            }
            _ => {
                let mut best: Option<((f64, f64, f64), Cut)> = None;
                for &contour in &w {
                    // Contour heat (vertex samples) is shared by its candidates.
                    let (body_hot, body_heat) = match &sim {
                        Some(s) => {
                            samples[contour]
                                .iter()
                                .fold((0usize, f32::MIN), |(n, m), &p| {
                                    let h = s.hot_near_c(p);
                                    (n + usize::from(h >= t_max), m.max(h))
                                })
                        }
                        None => (0, f32::MIN),
                    };
                    for (k, &p) in problem.contours[contour]
                        .pierce_candidates
                        .iter()
                        .enumerate()
                    {
                        let cut = Cut { contour, pierce: k };
                        let d = distance(at, p) + eval.corner_penalty(cut);
                        let key = match (&sim, policy) {
                            (Some(s), Policy::MinOverheat) => {
                                let h = s.hot_near_c(p);
                                let hot = body_hot + usize::from(h >= t_max);
                                let heat = h.max(body_heat);
                                (hot as f64, (heat / 25.0).floor() as f64, d)
                            }
                            (Some(s), Policy::PathOverheat) => {
                                let h = s.hot_near_c(p);
                                let heat = h.max(body_heat);
                                if heat < limit {
                                    (0.0, d, 0.0)
                                } else {
                                    let hot = body_hot + usize::from(h >= t_max);
                                    let over = f64::from(heat - limit)
                                        / f64::from(eval.thermal_params().delta_c.max(1.0));
                                    let cost = eval.cost_params();
                                    (
                                        1.0,
                                        d + cost.w_overheat_mm * hot as f64
                                            + cost.hot_penalty_mm * over,
                                        0.0,
                                    )
                                }
                            }
                            (Some(s), Policy::CostGreedy) => {
                                let h = s.hot_near_c(p);
                                let hot = body_hot + usize::from(h >= t_max);
                                let cost = eval.cost_params();
                                let lead = if h >= limit { cost.hot_penalty_mm } else { 0.0 };
                                (d + cost.w_overheat_mm * hot as f64 + lead, 0.0, 0.0)
                            }
                            _ => (d, 0.0, 0.0),
                        };
                        if best.as_ref().is_none_or(|(b, _)| key < *b) {
                            best = Some((key, cut));
                        }
                    }
                }
                best.map(|(_, c)| c).unwrap_or(Cut {
                    contour: w[0],
                    pierce: 0,
                })
            }
        };
        frontier.cut(pick.contour);
        if let Some(s) = sim.as_mut() {
            s.cut(&problem.contours[pick.contour], pick.pierce);
        }
        // With leads the tool leaves the cut at its lead-out's end.
        at = pick.exit(problem);
        cuts.push(pick);
    }
    if !frontier.is_finished() {
        let stuck = (0..rules.len()).filter(|&c| !frontier.is_cut(c)).collect();
        return Err(Violation::Cycle(stuck));
    }
    Ok((cuts, sim))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cost::{CostParams, Evaluator};
    use crate::fixtures::grid;
    use crate::precedence::PrecedenceMode;
    use crate::thermal::ThermalParams;

    #[test]
    fn every_policy_gives_a_valid_order_in_both_modes() {
        for mode in [PrecedenceMode::Strict, PrecedenceMode::Relaxed] {
            for free in [false, true] {
                let problem = grid(3, 2, 60.0, true, free, mode);
                let eval =
                    Evaluator::new(&problem, ThermalParams::default(), CostParams::default())
                        .unwrap();
                for policy in Policy::ALL {
                    let plan = construct(&eval, policy, 7).unwrap();
                    assert_eq!(plan.cuts.len(), problem.contours.len());
                    assert_eq!(
                        problem.precedence.check_order(&plan.order()),
                        Ok(()),
                        "{policy:?} {mode:?}"
                    );
                    assert!(plan.idle_mm > 0.0 && plan.cut_mm > 0.0);
                }
            }
        }
    }

    #[test]
    fn random_is_seeded() {
        let problem = grid(3, 3, 60.0, true, true, PrecedenceMode::Relaxed);
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let a = construct(&eval, Policy::Random, 1).unwrap();
        assert_eq!(a, construct(&eval, Policy::Random, 1).unwrap());
        assert_ne!(a.cuts, construct(&eval, Policy::Random, 2).unwrap().cuts);
    }

    /// On a dense grid (6 mm gaps, nested parts) the thermal policies overheat less than nearest pierce
    /// (seed 003 §A5: the authors' method gave ~26 % fewer overheats).
    #[test]
    fn thermal_policies_overheat_less_than_nearest() {
        let problem = grid(4, 3, 56.0, true, true, PrecedenceMode::Strict);
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let nearest = construct(&eval, Policy::Nearest, 0).unwrap();
        let min = construct(&eval, Policy::MinOverheat, 0).unwrap();
        let path = construct(&eval, Policy::PathOverheat, 0).unwrap();
        assert!(
            nearest.overheats > 0,
            "nearest should overheat on a dense grid"
        );
        assert!(
            min.overheats < nearest.overheats,
            "min {} vs nearest {}",
            min.overheats,
            nearest.overheats
        );
        assert!(
            path.overheats < nearest.overheats,
            "path {} vs nearest {}",
            path.overheats,
            nearest.overheats
        );
    }
}
