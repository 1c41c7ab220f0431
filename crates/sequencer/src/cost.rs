//! The cost of a cut plan (ours; seed 003 §A1 only says "minimise overheats, traded against
//! idle length", notes §A1):
//!
//! `cost = idle_mm + w_overheat_mm · overheats + Σ lead-in penalties`
//!
//! Lead-in penalties, per pierce: `corner_penalty_mm` if the pierce point (with leads: where
//! the lead-in meets the contour) lies within
//! `corner_radius_mm` of a contour vertex that turns by more than `corner_angle_deg` (a pierce
//! on a corner spoils the part edge), and `hot_penalty_mm` if the pierce neighbourhood is at or
//! above `t_max − delta` when pierced (an already hot region). With `thermal` off the thermal
//! raster is not run: cost = idle length + corner penalties.

use cell_geometry::{polyline_length, Norm};
use serde::{Deserialize, Serialize};

use crate::plan::{idle_length, Cut, CutPlan};
use crate::problem::{distance, Problem};
use crate::thermal::{require, SequencerParamError, ThermalOutcome, ThermalParams, ThermalSim};

/// Weights of the cost (module docs). Defaults are ours.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CostParams {
    /// Run the thermal raster and charge overheats and hot pierces. Default true.
    pub thermal: bool,
    /// Cost of one overheat, mm of idle travel. Default 200.
    pub w_overheat_mm: f64,
    /// A pierce this close to a corner vertex is penalised, mm. Default 3.
    pub corner_radius_mm: f64,
    /// A vertex turning by more than this is a corner, degrees. Default 60.
    pub corner_angle_deg: f64,
    /// Penalty of a pierce near a corner, mm. Default 50.
    pub corner_penalty_mm: f64,
    /// Penalty of a pierce at or above `t_max − delta`, mm. Default 50.
    pub hot_penalty_mm: f64,
}

impl Default for CostParams {
    fn default() -> Self {
        CostParams {
            thermal: true,
            w_overheat_mm: 200.0,
            corner_radius_mm: 3.0,
            corner_angle_deg: 60.0,
            corner_penalty_mm: 50.0,
            hot_penalty_mm: 50.0,
        }
    }
}

impl CostParams {
    /// Checks every field.
    ///
    /// # Errors
    /// The first field out of range, by name.
    pub fn validate(&self) -> Result<(), SequencerParamError> {
        let nonneg = |v: f64| v.is_finite() && v >= 0.0;
        require(
            nonneg(self.w_overheat_mm),
            "w_overheat_mm",
            self.w_overheat_mm,
            "must be finite and ≥ 0",
        )?;
        require(
            nonneg(self.corner_radius_mm),
            "corner_radius_mm",
            self.corner_radius_mm,
            "must be finite and ≥ 0",
        )?;
        require(
            nonneg(self.corner_angle_deg) && self.corner_angle_deg <= 180.0,
            "corner_angle_deg",
            self.corner_angle_deg,
            "must lie in [0, 180]",
        )?;
        require(
            nonneg(self.corner_penalty_mm),
            "corner_penalty_mm",
            self.corner_penalty_mm,
            "must be finite and ≥ 0",
        )?;
        require(
            nonneg(self.hot_penalty_mm),
            "hot_penalty_mm",
            self.hot_penalty_mm,
            "must be finite and ≥ 0",
        )?;
        Ok(())
    }
}

/// Why a problem cannot be evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] SequencerParamError),
    /// A contour has no pierce candidate.
    #[error("contour {0} has no pierce candidate")]
    NoPierce(usize),
    /// The precedence rules do not cover the contours.
    #[error("the precedence rules cover {rules} contours, the problem has {contours}")]
    RuleCount {
        /// Contours in the rules.
        rules: usize,
        /// Contours in the problem.
        contours: usize,
    },
}

/// Evaluates plans of one problem (module docs); precomputes per-candidate corner penalties
/// and cut lengths.
#[derive(Debug, Clone)]
pub struct Evaluator<'p> {
    /// The problem.
    pub problem: &'p Problem,
    thermal: ThermalParams,
    cost: CostParams,
    /// `corner[c][k]`: corner penalty of candidate `k` of contour `c`, mm.
    corner: Vec<Vec<f64>>,
    /// `cut_len[c][k]`: cut length from candidate `k`, mm.
    cut_len: Vec<Vec<f64>>,
}

impl<'p> Evaluator<'p> {
    /// Checks the parameters and the problem and precomputes the static tables.
    ///
    /// # Errors
    /// [`EvalError`] naming the bad field or contour.
    pub fn new(
        problem: &'p Problem,
        thermal: ThermalParams,
        cost: CostParams,
    ) -> Result<Self, EvalError> {
        thermal.validate()?;
        cost.validate()?;
        if problem.precedence.len() != problem.contours.len() {
            return Err(EvalError::RuleCount {
                rules: problem.precedence.len(),
                contours: problem.contours.len(),
            });
        }
        if let Some(c) = problem
            .contours
            .iter()
            .position(|c| c.pierce_candidates.is_empty())
        {
            return Err(EvalError::NoPierce(c));
        }
        // The sheet's raster, without allocating it.
        thermal.raster_size(problem.sheet)?;
        let cos_limit = (180.0 - cost.corner_angle_deg).to_radians().cos();
        let corner = problem
            .contours
            .iter()
            .map(|c| {
                let n = c.points.len();
                let corners: Vec<_> = (0..n)
                    .filter(|&i| {
                        let (a, b, d) = (
                            c.points[(i + n - 1) % n],
                            c.points[i],
                            c.points[(i + 1) % n],
                        );
                        let u = [a[0] - b[0], a[1] - b[1]];
                        let v = [d[0] - b[0], d[1] - b[1]];
                        let (lu, lv) = (u[0].hypot(u[1]), v[0].hypot(v[1]));
                        if lu == 0.0 || lv == 0.0 {
                            return false;
                        }
                        // Interior angle below 180° − corner_angle ⇔ turn above corner_angle.
                        (u[0] * v[0] + u[1] * v[1]) / (lu * lv) > cos_limit
                    })
                    .map(|i| c.points[i])
                    .collect();
                // With leads the cut meets the contour at the lead-in's end, not the pierce.
                (0..c.pierce_candidates.len())
                    .map(|k| c.entry(k))
                    .map(|p| {
                        if corners
                            .iter()
                            .any(|&q| distance(p, q) <= cost.corner_radius_mm)
                        {
                            cost.corner_penalty_mm
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect();
        let cut_len = problem
            .contours
            .iter()
            .map(|c| {
                (0..c.pierce_candidates.len())
                    .map(|k| polyline_length(&c.cut_path(k), Norm::Hypot))
                    .collect()
            })
            .collect();
        Ok(Evaluator {
            problem,
            thermal,
            cost,
            corner,
            cut_len,
        })
    }

    /// The thermal raster constants (validated).
    pub fn thermal_params(&self) -> &ThermalParams {
        &self.thermal
    }

    /// The cost weights (validated).
    pub fn cost_params(&self) -> &CostParams {
        &self.cost
    }

    /// Corner penalty of a cut, mm.
    pub fn corner_penalty(&self, cut: Cut) -> f64 {
        self.corner[cut.contour][cut.pierce]
    }

    /// The cost of idle length plus corner penalties alone (no raster).
    pub fn static_cost(&self, cuts: &[Cut]) -> f64 {
        idle_length(self.problem, cuts) + cuts.iter().map(|&c| self.corner_penalty(c)).sum::<f64>()
    }

    /// A fresh raster of this problem's sheet, tool at the start.
    pub fn sim<'f>(&self) -> ThermalSim<'f> {
        ThermalSim::new(self.problem.sheet, self.problem.start, &self.thermal)
            .expect("validated in Evaluator::new")
    }

    /// Evaluates a full cut sequence (module docs): runs the raster unless thermal cost is off.
    ///
    /// # Panics
    /// If a cut names a contour or pierce candidate the problem does not have (plans from
    /// [`crate::policy`] and [`crate::improve`] never do).
    pub fn evaluate(&self, cuts: &[Cut]) -> CutPlan {
        self.evaluate_with(cuts, self.sim())
    }

    /// As [`Evaluator::evaluate`], driving a given raster (e.g. one with a frame observer).
    pub fn evaluate_with(&self, cuts: &[Cut], mut sim: ThermalSim<'_>) -> CutPlan {
        if !self.cost.thermal {
            return self.assemble(cuts, None);
        }
        for c in cuts {
            sim.cut(&self.problem.contours[c.contour], c.pierce);
        }
        let out = sim.finish(self.problem.start);
        self.assemble(cuts, Some(&out))
    }

    /// The plan of `cuts` whose raster run gave `thermal` (`None`: thermal cost off, or not
    /// simulated). Used when a policy already drove the raster through the same cuts.
    pub fn assemble(&self, cuts: &[Cut], thermal: Option<&ThermalOutcome>) -> CutPlan {
        let idle_mm = idle_length(self.problem, cuts);
        let cut_mm = cuts.iter().map(|c| self.cut_len[c.contour][c.pierce]).sum();
        let corner: f64 = cuts.iter().map(|&c| self.corner_penalty(c)).sum();
        let out = match thermal {
            Some(out) if self.cost.thermal => out,
            _ => {
                return CutPlan {
                    cuts: cuts.to_vec(),
                    idle_mm,
                    cut_mm,
                    overheats: 0,
                    max_temp_c: self.thermal.ambient_c,
                    lead_in_penalty: corner,
                    time_s: 0.0,
                    cost: idle_mm + corner,
                }
            }
        };
        let hot_limit = self.thermal.t_max_c - self.thermal.delta_c;
        let hot = out
            .per_cut
            .iter()
            .filter(|r| r.pierce_temp_c >= hot_limit)
            .count() as f64
            * self.cost.hot_penalty_mm;
        let lead_in_penalty = corner + hot;
        CutPlan {
            cuts: cuts.to_vec(),
            idle_mm,
            cut_mm,
            overheats: out.overheats,
            max_temp_c: out.max_temp_c,
            lead_in_penalty,
            time_s: out.time_s,
            cost: idle_mm + self.cost.w_overheat_mm * out.overheats as f64 + lead_in_penalty,
        }
    }
}
