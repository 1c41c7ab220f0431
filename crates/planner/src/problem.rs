//! The optimisation problem of seed 000 §IV.C: the foil, its surface panels, the wire path
//! parameterised by a cubic B-spline of normal displacements, the feed along it, the lead-in,
//! and the loss every optimiser ([`crate::pso`], [`crate::refine`]) minimises.
//!
//! The design variables are K control values c of a cubic B-spline that moves the
//! fixed-offset baseline along its normals ([`crate::trajectory::Trajectory`]) and, with
//! [`Objective::feed`], K_f control values g of the spline of ln ρ, the feed ratio along the
//! path ([`FeedVariable`]). The loss is
//!
//! L(c, g) = (1/N) Σᵢ (Êᵢ(c, g) − CSE)² + λ Σₖ (c_{k+1} − c_k)² + λ Σₖ (g_{k+1} − g_k)² + μ Σₖ g_k²,
//!
//! the first term the paper's (an unweighted mean over the N surface panels, in the exposure
//! unit of [`crate::exposure`] squared; Êᵢ includes the lead-in's heat,
//! [`Problem::with_lead_in`]), the next two a smoothing penalty (the paper applies "a
//! smoothing" without saying which; λ = [`Objective::smoothing`] in exposure-unit²/mm²; the
//! sums wrap round with periodic spline ends), the last a pull towards the nominal feed
//! (μ = [`FeedVariable::nominal_weight`]). Subject to T ∩ G = ∅: a trajectory or lead-in that
//! crosses the foil or comes closer than [`Objective::min_clearance_mm`] has L = +∞ and is
//! never a best.
//!
//! Not here: the paper's CSE calibration (§IV.D) needs cut parts measured; this crate has no
//! model of the cut chord from the exposure, so no `calibrate_cse` is offered.

use nalgebra::Point2;

use crate::airfoil::Airfoil;
use crate::exposure::{ExposureError, ExposureModel, Panels, WireSegments};
use crate::pso::PsoError;
use crate::spline::SplineEnds;
use crate::trajectory::{is_feasible, Baseline, ControlSpacing, OutlineGrid, Trajectory};

/// What the optimiser minimises (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct Objective {
    /// Exposure model settings.
    pub model: ExposureModel,
    /// Target exposure CSE in the model's unit (dimensionless for the paper's 1/‖R‖, mm⁻¹ for
    /// 1/‖R‖²). `None` (default): the baseline's mean exposure, i.e. "make the exposure as
    /// uniform as possible at the level the usual practice gives".
    pub cse: Option<f64>,
    /// Smoothing weight λ on Σ (c_{k+1} − c_k)² (default 1e-3: negligible against a typical
    /// exposure residual, enough to stop neighbouring controls fighting).
    pub smoothing: f64,
    /// Least allowed distance between trajectory and foil, mm (default 0.1).
    pub min_clearance_mm: f64,
    /// Number of spline control values K (default 32, as in the notes).
    pub control_points: usize,
    /// End condition of the path and feed splines (default [`SplineEnds::Open`]: the first
    /// panels cut want the wire close and slow, the last ones far and fast, and a periodic
    /// spline ties the two together at the entry point; [`SplineEnds::Periodic`] is the
    /// paper's closed path).
    pub ends: SplineEnds,
    /// Where the path and feed controls act along the path (default
    /// [`ControlSpacing::PathPoints`]: clustered at the leading and trailing edges).
    pub spacing: ControlSpacing,
    /// Feed along the path as a second set of design variables (default: on, within
    /// [`FeedVariable::default`]'s band; `None`: constant feed, the paper's experiments). The
    /// wire cannot come closer than the clearance where the surface is under-exposed (the
    /// leading edge), and it cannot move far enough out to take the excess off the last
    /// panels cut; dwell time can do both (crate docs, "Why the swarm stalled").
    pub feed: Option<FeedVariable>,
}

impl Default for Objective {
    fn default() -> Self {
        Self {
            model: ExposureModel::default(),
            cse: None,
            smoothing: 1e-3,
            min_clearance_mm: 0.1,
            control_points: 32,
            ends: SplineEnds::Open,
            spacing: ControlSpacing::PathPoints,
            feed: Some(FeedVariable::default()),
        }
    }
}

/// Feed along the path as an optimisation variable: seed 000 writes the exposure as Ê(c, f)
/// without defining f (ambiguity 5 of `docs/notes/swarmcut-model-notes.md`); here f is the feed.
///
/// The wire's heat per millimetre of path relative to the nominal cut, q(u), is what the
/// exposure sees: segment j's contribution is weighted by q(uⱼ)
/// ([`crate::exposure::WireSegments::set_weights`]). Heat per millimetre is power × dwell,
/// so q = γ²/ρ with ρ = feed / nominal feed and γ = current / nominal current (the wire's
/// power ∝ I²R). The design variables are a cubic B-spline s(u) = −ln q (ends as
/// [`Objective::ends`]) over the path's spline parameter u ([`Objective::spacing`]),
/// realised feed first: ρ = e^s clamped to [`FeedVariable::min_ratio`] …
/// [`FeedVariable::max_ratio`], then γ = √(q·ρ) clamped to
/// [`FeedVariable::min_current_ratio`] … [`FeedVariable::max_current_ratio`] (default 1 … 1:
/// constant current, and s is simply ln ρ). Either way the plan drops the constant-kerf
/// current schedule, which would cancel exactly this effect.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct FeedVariable {
    /// Control values of the s = −ln q spline (default 16).
    pub control_points: usize,
    /// Slowest feed as a fraction of the nominal (default 0.5).
    pub min_ratio: f64,
    /// Fastest feed as a fraction of the nominal (default 1.5).
    pub max_ratio: f64,
    /// Weight μ of Σ (ln ρ_k)² in the loss, exposure-unit² (default 1e-3): the feed leaves the
    /// nominal only where that evens the exposure out. Without it the optimum trades a slower
    /// feed everywhere for a wire moved millimetres out, which the exposure cannot tell apart
    /// but the cut's time and the kerf model can.
    pub nominal_weight: f64,
    /// Lowest wire current as a fraction of the nominal (default 1.0: constant current).
    pub min_current_ratio: f64,
    /// Highest wire current as a fraction of the nominal (default 1.0). A wider band lets
    /// the heat leave the feed's band (`cell hotwire --vary-current`); off by default because
    /// the wire's temperature lags a current step by a fraction of a second, which the
    /// exposure model does not describe.
    pub max_current_ratio: f64,
}

impl Default for FeedVariable {
    fn default() -> Self {
        Self {
            control_points: 16,
            min_ratio: 0.5,
            max_ratio: 1.5,
            nominal_weight: 1e-3,
            min_current_ratio: 1.0,
            max_current_ratio: 1.0,
        }
    }
}

impl FeedVariable {
    /// This band within what the machine can do: the fastest ratio at most
    /// `max_feed_mm_s / feed_mm_s` (the slowest one no faster than that).
    pub fn within_machine(self, feed_mm_s: f64, max_feed_mm_s: f64) -> Self {
        let max_ratio = self.max_ratio.min(max_feed_mm_s / feed_mm_s);
        Self {
            max_ratio,
            min_ratio: self.min_ratio.min(max_ratio),
            ..self
        }
    }

    /// This variable with the current free within `(min, max)` × the nominal current.
    pub fn with_current_band(self, (min, max): (f64, f64)) -> Self {
        Self {
            min_current_ratio: min,
            max_current_ratio: max,
            ..self
        }
    }

    /// The current band within the supply: γ at most `max_a / current_a` and at least
    /// `min_a / current_a` (kept ordered).
    pub fn within_supply(self, current_a: f64, min_a: f64, max_a: f64) -> Self {
        let max_current_ratio = self.max_current_ratio.min(max_a / current_a);
        let min_current_ratio = self
            .min_current_ratio
            .max(min_a / current_a)
            .min(max_current_ratio);
        Self {
            min_current_ratio,
            max_current_ratio: max_current_ratio.max(min_current_ratio),
            ..self
        }
    }

    /// (ρ, γ) at u for the s spline `controls` with end condition `ends` (module docs of
    /// [`FeedVariable`]).
    pub fn setting(&self, ends: SplineEnds, controls: &[f64], u: f64) -> (f64, f64) {
        let s = ends.eval(controls, u);
        let rho = s.exp().clamp(self.min_ratio, self.max_ratio);
        let gamma = ((-s).exp() * rho)
            .sqrt()
            .clamp(self.min_current_ratio, self.max_current_ratio);
        (rho, gamma)
    }

    /// Bounds on the s controls: q from γ_min²/ρ_max to γ_max²/ρ_min.
    pub fn control_bounds(&self) -> (f64, f64) {
        (
            self.min_ratio.ln() - 2.0 * self.max_current_ratio.ln(),
            self.max_ratio.ln() - 2.0 * self.min_current_ratio.ln(),
        )
    }
}

/// A fixed problem: foil, surface panels, parameterised trajectory and objective.
#[derive(Debug, Clone)]
pub struct Problem {
    /// The foil outline G, bucketed for the per-evaluation feasibility test.
    pub(crate) grid: OutlineGrid,
    /// The baseline's clearance from G less the required clearance (mm): a path no point of
    /// which moves further than this from the baseline is feasible without a test.
    pub(crate) free_displacement_mm: f64,
    surface: Panels,
    /// The surface's corner points, first the one nearest the wire's entry.
    surface_points: Vec<Point2<f64>>,
    /// Panel i of [`Problem::surface`] is panel (i + shift) mod N counted from the trailing
    /// edge ([`Problem::entering_at`]).
    surface_shift: usize,
    trajectory: Trajectory,
    pub(crate) objective: Objective,
    cse: f64,
    /// Normalised baseline arc length at each wire segment's middle (for the feed spline).
    segment_u: Vec<f64>,
    /// Where the lead-in starts; it runs straight to the path's first point (which moves with
    /// the controls). `None`: the wire starts on the path (the paper's set-up).
    lead_in_start: Option<Point2<f64>>,
    /// A feed ratio per wire segment set from outside ([`Problem::with_feed_profile`]), used
    /// when the feed is not a design variable.
    fixed_feed: Option<Vec<(f64, f64)>>,
    /// The lead-in's length as a design variable: the unit direction its start moves in, and
    /// how far (mm) beyond [`Problem::lead_in_start`] ([`Problem::with_lead_in_reach`]).
    lead_in_reach: Option<(nalgebra::Vector2<f64>, f64)>,
}

/// Reusable buffers for one loss evaluation (no allocation per evaluation once warm).
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    path: Vec<Point2<f64>>,
    wire: WireSegments,
    exposure: Vec<f64>,
    weights: Vec<f64>,
    lead: [Point2<f64>; 2],
    lead_wire: WireSegments,
    lead_exposure: Vec<f64>,
    regularisation: Vec<f64>,
}

impl Problem {
    /// Sets up the problem: G = `foil` (its full-resolution points, for feasibility), the
    /// surface = `foil` resampled to `surface_panels` points ([`Airfoil::resampled_cosine`]),
    /// the trajectory = `baseline` with [`Objective::control_points`] controls, and CSE
    /// resolved (the baseline mean exposure when [`Objective::cse`] is `None`).
    ///
    /// # Errors
    /// Invalid objective values (named); a baseline closer than the clearance.
    pub fn new(
        foil: &Airfoil,
        surface_panels: usize,
        baseline: Baseline,
        objective: Objective,
    ) -> Result<Self, PsoError> {
        objective.model.validate()?;
        for (name, v) in [
            ("smoothing", objective.smoothing),
            ("min_clearance_mm", objective.min_clearance_mm),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(PsoError::InvalidParameter {
                    name,
                    value: v,
                    requirement: "finite and >= 0",
                });
            }
        }
        if let Some(f) = objective.feed {
            if !(f.min_ratio.is_finite()
                && f.min_ratio > 0.0
                && f.max_ratio.is_finite()
                && f.max_ratio >= f.min_ratio)
            {
                return Err(PsoError::InvalidParameter {
                    name: "feed.min_ratio",
                    value: f.min_ratio,
                    requirement: "0 < min_ratio <= max_ratio, both finite",
                });
            }
            if !(f.nominal_weight.is_finite() && f.nominal_weight >= 0.0) {
                return Err(PsoError::InvalidParameter {
                    name: "feed.nominal_weight",
                    value: f.nominal_weight,
                    requirement: "finite and >= 0",
                });
            }
            if !(f.min_current_ratio.is_finite()
                && f.min_current_ratio > 0.0
                && f.max_current_ratio.is_finite()
                && f.max_current_ratio >= f.min_current_ratio)
            {
                return Err(PsoError::InvalidParameter {
                    name: "feed.min_current_ratio",
                    value: f.min_current_ratio,
                    requirement: "0 < min_current_ratio <= max_current_ratio, both finite",
                });
            }
            if f.control_points == 0 {
                return Err(PsoError::InvalidParameter {
                    name: "feed.control_points",
                    value: 0.0,
                    requirement: ">= 1",
                });
            }
        }
        if let Some(c) = objective.cse {
            if !c.is_finite() {
                return Err(PsoError::InvalidParameter {
                    name: "cse",
                    value: c,
                    requirement: "finite",
                });
            }
        }
        let outline = foil.points().to_vec();
        if !is_feasible(baseline.points(), &outline, objective.min_clearance_mm) {
            return Err(PsoError::InfeasibleBaseline {
                clearance_mm: crate::trajectory::clearance_mm(
                    baseline.points(),
                    &outline,
                    f64::INFINITY,
                ),
            });
        }
        let mut surface_points = foil.resampled_cosine(surface_panels)?.points().to_vec();
        surface_points.dedup();
        if surface_points.len() > 1 && surface_points.first() == surface_points.last() {
            surface_points.pop();
        }
        let surface = Panels::from_points(&surface_points)?;
        // The clearance is ≥ the required one (checked above); 1e-9 mm for rounding.
        let free_displacement_mm =
            crate::trajectory::clearance_mm(baseline.points(), &outline, f64::INFINITY)
                - objective.min_clearance_mm
                - 1e-9;
        let (trajectory, segment_u) = parameterise(baseline, &objective)?;
        let mut p = Self {
            grid: OutlineGrid::new(&outline),
            free_displacement_mm,
            surface,
            surface_points,
            surface_shift: 0,
            trajectory,
            objective,
            cse: 0.0,
            segment_u,
            lead_in_start: None,
            fixed_feed: None,
            lead_in_reach: None,
        };
        p.resolve_cse()?;
        Ok(p)
    }

    /// The same problem with the wire entering the loop at baseline vertex `vertex` instead of
    /// vertex 0 (the trailing edge): the baseline and the surface are both restarted there
    /// (the surface at its corner nearest the new first path point), so the causal mask's
    /// search window follows the new cutting order. Exposures stay in this order;
    /// [`Problem::trailing_edge_order`] puts them back. Call before adding a lead-in or a feed
    /// profile.
    ///
    /// # Errors
    /// `vertex` past the baseline; a lead-in already set.
    pub fn entering_at(mut self, vertex: usize) -> Result<Self, PsoError> {
        let base = self.trajectory.baseline().points();
        let m = base.len() - 1;
        if vertex >= m || self.lead_in_start.is_some() || self.fixed_feed.is_some() {
            return Err(PsoError::InvalidParameter {
                name: "entry_vertex",
                value: vertex as f64,
                requirement: "a baseline vertex, before any lead-in or feed profile is set",
            });
        }
        let mut ring = base[vertex..m].to_vec();
        ring.extend_from_slice(&base[..vertex]);
        let baseline = Baseline::from_points(ring)?;
        let first = baseline.points()[0];
        let n = self.surface_points.len();
        let nearest = (0..n)
            .min_by(|&a, &b| {
                (self.surface_points[a] - first)
                    .norm()
                    .total_cmp(&(self.surface_points[b] - first).norm())
            })
            .unwrap_or(0);
        self.surface_points.rotate_left(nearest);
        self.surface = Panels::from_points(&self.surface_points)?;
        self.surface_shift = (self.surface_shift + nearest) % n;
        (self.trajectory, self.segment_u) = parameterise(baseline, &self.objective)?;
        self.resolve_cse()?;
        Ok(self)
    }

    /// Per-panel values of this problem (in its cutting order) in trailing-edge order: the
    /// order of the foil's surface from vertex 0.
    pub fn trailing_edge_order(&self, values: &[f64]) -> Vec<f64> {
        let mut out = values.to_vec();
        if !out.is_empty() {
            let shift = self.surface_shift % out.len();
            out.rotate_right(shift);
        }
        out
    }

    /// The same problem with a straight lead-in from `start` to the path's first point: its
    /// heat counts for every panel (the wire is on it before it cuts anything), so the first
    /// panels cut are not starved of exposure. CSE is resolved again when it is the baseline's
    /// mean. The lead-in must keep the clearance from the foil like the path.
    ///
    /// # Errors
    /// A non-finite `start`; a baseline lead-in closer to the foil than the clearance.
    pub fn with_lead_in(mut self, start: Point2<f64>) -> Result<Self, PsoError> {
        if !(start.x.is_finite() && start.y.is_finite()) {
            return Err(PsoError::InvalidParameter {
                name: "lead_in_start",
                value: f64::NAN,
                requirement: "finite",
            });
        }
        let lead = [start, self.trajectory.baseline().points()[0]];
        if !self
            .grid
            .is_feasible(&lead, self.objective.min_clearance_mm)
        {
            return Err(PsoError::InfeasibleBaseline {
                clearance_mm: crate::trajectory::clearance_mm(
                    &lead,
                    self.grid.outline(),
                    f64::INFINITY,
                ),
            });
        }
        self.lead_in_start = Some(start);
        self.resolve_cse()?;
        Ok(self)
    }

    /// The same problem with the feed and current along the path given rather than
    /// optimised: segment j runs at (ρ, γ) = `setting(u_j)` × the nominal feed and current,
    /// u_j the baseline's normalised arc length at the segment's middle (the tip face of a
    /// tapered panel, which moves in step with the root's optimised feed on the one wire).
    /// Ignored while the feed is a design variable. CSE is resolved again when it is the
    /// baseline's mean.
    ///
    /// # Errors
    /// A ratio that is not finite and > 0 (named `feed_profile`).
    pub fn with_feed_profile(
        mut self,
        setting: impl Fn(f64) -> (f64, f64),
    ) -> Result<Self, PsoError> {
        let ratios: Vec<(f64, f64)> = self
            .trajectory
            .baseline()
            .arc_positions()
            .windows(2)
            .map(|w| setting(0.5 * (w[0] + w[1])))
            .collect();
        let bad = |v: f64| !(v.is_finite() && v > 0.0);
        if let Some(&(rho, gamma)) = ratios.iter().find(|(r, g)| bad(*r) || bad(*g)) {
            return Err(PsoError::InvalidParameter {
                name: "feed_profile",
                value: if bad(rho) { rho } else { gamma },
                requirement: "finite and > 0 at every segment",
            });
        }
        self.fixed_feed = Some(ratios);
        self.resolve_cse()?;
        Ok(self)
    }

    /// The same problem with the lead-in's length a design variable (the last one): its start
    /// may move up to `reach_mm` further along `direction` (pointing away from the path; the
    /// job passes the chord line behind the trailing edge). A longer lead-in heats the first panels cut longer before the wire reaches them
    /// (seed 000's causal mask gives them nothing else); it needs that much more foam behind
    /// the entry point.
    ///
    /// # Errors
    /// No lead-in yet ([`Problem::with_lead_in`] first), `reach_mm` not finite and ≥ 0, a
    /// longest lead-in that breaks the clearance.
    pub fn with_lead_in_reach(
        mut self,
        direction: nalgebra::Vector2<f64>,
        reach_mm: f64,
    ) -> Result<Self, PsoError> {
        let Some(start) = self.lead_in_start else {
            return Err(PsoError::InvalidParameter {
                name: "lead_in_reach_mm",
                value: reach_mm,
                requirement: "a lead-in to lengthen (with_lead_in first)",
            });
        };
        if !(reach_mm.is_finite() && reach_mm >= 0.0) {
            return Err(PsoError::InvalidParameter {
                name: "lead_in_reach_mm",
                value: reach_mm,
                requirement: "finite and >= 0",
            });
        }
        let entry = self.trajectory.baseline().points()[0];
        let direction = direction
            .try_normalize(1e-12)
            .ok_or(PsoError::InvalidParameter {
                name: "lead_in_direction",
                value: direction.norm(),
                requirement: "a non-zero vector",
            })?;
        let longest = [start + direction * reach_mm, entry];
        if !self
            .grid
            .is_feasible(&longest, self.objective.min_clearance_mm)
        {
            return Err(PsoError::InfeasibleBaseline {
                clearance_mm: crate::trajectory::clearance_mm(
                    &longest,
                    self.grid.outline(),
                    f64::INFINITY,
                ),
            });
        }
        self.lead_in_reach = Some((direction, reach_mm));
        Ok(self)
    }

    /// The lead-in's start, if the problem has one ([`Problem::with_lead_in`]).
    pub fn lead_in_start(&self) -> Option<Point2<f64>> {
        self.lead_in_start
    }

    /// CSE = the objective's, else the baseline's mean exposure.
    fn resolve_cse(&mut self) -> Result<(), PsoError> {
        self.cse = match self.objective.cse {
            Some(c) => c,
            None => {
                let e = self.exposure(&vec![0.0; self.dimension()])?;
                e.iter().sum::<f64>() / e.len() as f64
            }
        };
        Ok(())
    }

    /// The resolved CSE target.
    pub fn cse(&self) -> f64 {
        self.cse
    }

    /// The objective settings.
    pub fn objective(&self) -> &Objective {
        &self.objective
    }

    /// The surface panels.
    pub fn surface(&self) -> &Panels {
        &self.surface
    }

    /// The parameterised trajectory.
    pub fn trajectory(&self) -> &Trajectory {
        &self.trajectory
    }

    /// Number of design variables: the K path controls, then the feed controls if the feed
    /// is a variable ([`Objective::feed`]).
    pub fn dimension(&self) -> usize {
        self.trajectory.control_points()
            + self.objective.feed.map_or(0, |f| f.control_points)
            + usize::from(self.lead_in_reach.is_some())
    }

    /// The feed controls of a design vector (empty without a feed variable).
    fn feed_controls<'a>(&self, controls: &'a [f64]) -> &'a [f64] {
        let k = self.trajectory.control_points();
        let end = k + self.objective.feed.map_or(0, |f| f.control_points);
        &controls[k.min(controls.len())..end.min(controls.len())]
    }

    /// Where the lead-in starts for a design vector: the fixed start, moved back along the
    /// lead's line by the last design variable when the length is one
    /// ([`Problem::with_lead_in_reach`]).
    pub fn lead_start(&self, controls: &[f64]) -> Option<Point2<f64>> {
        let start = self.lead_in_start?;
        Some(match self.lead_in_reach {
            Some((direction, _)) => {
                let extra = controls.get(self.dimension() - 1).copied().unwrap_or(0.0);
                start + direction * extra
            }
            None => start,
        })
    }

    /// Box bounds (lower, upper) on the design variables that every optimiser keeps to:
    ///
    /// - a path control ≥ −(baseline clearance − required clearance): the spline's weights are
    ///   ≥ 0 and sum to 1, so no point then moves further inwards than that and the path keeps
    ///   the clearance wherever the baseline's normals point away from the foil. Not needed for
    ///   feasibility (the loss tests it), but the optimum presses against it (the leading edge
    ///   wants the wire as close as it may come), and a swarm or a Gauss–Newton step that knows
    ///   the bound slides along it instead of wasting its moves on infeasible points. No upper
    ///   bound;
    /// - a feed control within [`FeedVariable::control_bounds`]: the heat stays within what
    ///   the feed and current bands can give, for the same reason.
    pub fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        let k = self.trajectory.control_points();
        let inward = self.free_displacement_mm.max(0.0);
        let mut lower = vec![-inward; k];
        let mut upper = vec![f64::INFINITY; k];
        if let Some(f) = self.objective.feed {
            let (lo, hi) = f.control_bounds();
            lower.extend(std::iter::repeat_n(lo, f.control_points));
            upper.extend(std::iter::repeat_n(hi, f.control_points));
        }
        if let Some((_, reach)) = self.lead_in_reach {
            lower.push(0.0);
            upper.push(reach);
        }
        (lower, upper)
    }

    /// The wire path for the design vector `controls` (its first K values).
    ///
    /// With open spline ends the path ends with a straight join from its last point back to
    /// its first (possibly of zero length): the wire closes the loop so the part comes free,
    /// and the join is cut like the rest (it can be the nearest wire to the last panels).
    pub fn path(&self, controls: &[f64]) -> Vec<Point2<f64>> {
        let mut out = Vec::new();
        self.path_into(controls, &mut out);
        out
    }

    fn path_into(&self, controls: &[f64], out: &mut Vec<Point2<f64>>) {
        self.trajectory.path_into(controls, out);
        if self.objective.ends == SplineEnds::Open {
            out.push(out[0]);
        }
    }

    /// The feed ratio ρ of each wire segment for `controls` (all 1 without a feed variable;
    /// the given profile's with [`Problem::with_feed_profile`]).
    pub fn feed_ratios(&self, controls: &[f64]) -> Vec<f64> {
        self.settings(controls)
            .into_iter()
            .map(|(rho, _)| rho)
            .collect()
    }

    /// The current ratio γ of each wire segment for `controls` (all 1 unless the feed
    /// variable's current band is wider, [`FeedVariable::max_current_ratio`]).
    pub fn current_ratios(&self, controls: &[f64]) -> Vec<f64> {
        self.settings(controls)
            .into_iter()
            .map(|(_, gamma)| gamma)
            .collect()
    }

    /// (ρ, γ) of each wire segment.
    fn settings(&self, controls: &[f64]) -> Vec<(f64, f64)> {
        let mut out = Vec::with_capacity(self.segment_u.len() + 1);
        self.for_each_setting(controls, |rho, gamma| out.push((rho, gamma)));
        out
    }

    /// The heat weight q = γ²/ρ of each wire segment ([`FeedVariable`]) into `out`.
    fn feed_weights_into(&self, controls: &[f64], out: &mut Vec<f64>) {
        out.clear();
        self.for_each_setting(controls, |rho, gamma| out.push(gamma * gamma / rho));
    }

    /// Calls `each(ρ, γ)` for every wire segment in order: from the feed variable, else the
    /// given profile ([`Problem::with_feed_profile`]), else (1, 1); with open spline ends the
    /// closing join ([`Problem::path`]) repeats the last segment's setting.
    fn for_each_setting(&self, controls: &[f64], mut each: impl FnMut(f64, f64)) {
        let k = self.trajectory.control_points();
        let mut last = (1.0, 1.0);
        let mut emit = |setting: (f64, f64)| {
            last = setting;
            each(setting.0, setting.1);
        };
        match (self.objective.feed, &self.fixed_feed) {
            (Some(f), _) if controls.len() > k => {
                let (ends, g) = (self.objective.ends, self.feed_controls(controls));
                for &u in &self.segment_u {
                    emit(f.setting(ends, g, u));
                }
            }
            (_, Some(fixed)) => fixed.iter().for_each(|&setting| emit(setting)),
            _ => self.segment_u.iter().for_each(|_| emit((1.0, 1.0))),
        }
        if self.objective.ends == SplineEnds::Open {
            each(last.0, last.1);
        }
    }

    /// The wire segments of `controls`' path, weighted by the feed (1/ρ per segment).
    ///
    /// # Errors
    /// A degenerate path (non-finite controls).
    pub fn wire(&self, controls: &[f64]) -> Result<WireSegments, PsoError> {
        let mut wire = WireSegments::from_points(&self.path(controls))?;
        let mut weights = Vec::new();
        self.feed_weights_into(controls, &mut weights);
        wire.set_weights(&weights)?;
        Ok(wire)
    }

    /// True if the path for `controls` satisfies T ∩ G = ∅ with the clearance.
    pub fn is_feasible(&self, controls: &[f64]) -> bool {
        self.grid
            .is_feasible(&self.path(controls), self.objective.min_clearance_mm)
    }

    /// Exposure of every surface panel for `controls`, the lead-in's heat included.
    ///
    /// # Errors
    /// A degenerate path (non-finite controls).
    pub fn exposure(&self, controls: &[f64]) -> Result<Vec<f64>, PsoError> {
        let wire = self.wire(controls)?;
        let mut out = vec![0.0; self.surface.len()];
        self.objective
            .model
            .exposure_into(&self.surface, &wire, &mut out)?;
        if let Some(start) = self.lead_start(controls) {
            add_lead_in_exposure(
                &self.objective.model,
                &self.surface,
                &[start, self.path(controls)[0]],
                &mut WireSegments::default(),
                &mut Vec::new(),
                &mut out,
            )?;
        }
        Ok(out)
    }

    /// Every wire segment's contribution to every panel for `controls`, feed-weighted:
    /// `(rows = segments, cols = panels, values)` as [`ExposureModel::exposure_matrix`].
    ///
    /// # Errors
    /// A degenerate path (non-finite controls).
    pub fn exposure_matrix(&self, controls: &[f64]) -> Result<(usize, usize, Vec<f32>), PsoError> {
        Ok(self
            .objective
            .model
            .exposure_matrix_of(&self.surface, &self.wire(controls)?)?)
    }

    /// T ∩ G = ∅ with the clearance for `path` = the trajectory of `controls`, answered
    /// without geometry when no path point moves further from the baseline than
    /// `free_displacement_mm` (a point of a path segment is then within that distance of the
    /// baseline segment's corresponding point, so the clearance cannot drop below the
    /// required one): first by the largest control value (the B-spline's weights are ≥ 0 and
    /// sum to 1, so no displacement exceeds it), then by the largest displacement itself; else
    /// by the outline grid ([`OutlineGrid::is_feasible`]).
    pub(crate) fn is_clear(&self, controls: &[f64], path: &[Point2<f64>]) -> bool {
        let free = self.free_displacement_mm;
        let k = self.trajectory.control_points().min(controls.len());
        if free > 0.0 {
            if controls[..k].iter().all(|c| c.abs() < free) {
                return true;
            }
            let base = self.trajectory.baseline().points();
            if path.len() == base.len()
                && path
                    .iter()
                    .zip(base)
                    .all(|(p, b)| (p - b).norm_squared() < free * free)
            {
                return true;
            }
        }
        self.grid.is_feasible(path, self.objective.min_clearance_mm)
    }

    /// Fills `scratch.exposure` with the exposure of `controls`' path (lead-in included) and
    /// returns true, or returns false for an infeasible or degenerate path or non-finite
    /// controls. Allocates nothing once `scratch` is warm; the feasibility test needs no
    /// geometry while the path stays near the baseline, else visits only the outline near the
    /// path ([`OutlineGrid`]), and the exposure takes the model's fast path when it has one
    /// ([`ExposureModel::exposure_into`]).
    pub fn evaluate(&self, controls: &[f64], scratch: &mut Scratch) -> bool {
        if controls.iter().any(|c| !c.is_finite()) {
            return false;
        }
        self.path_into(controls, &mut scratch.path);
        if !self.is_clear(controls, &scratch.path) || scratch.wire.set(&scratch.path).is_err() {
            return false;
        }
        if self.objective.feed.is_some() || self.fixed_feed.is_some() {
            self.feed_weights_into(controls, &mut scratch.weights);
            if scratch.wire.set_weights(&scratch.weights).is_err() {
                return false;
            }
        }
        scratch.exposure.resize(self.surface.len(), 0.0);
        if self
            .objective
            .model
            .exposure_into(&self.surface, &scratch.wire, &mut scratch.exposure)
            .is_err()
        {
            return false;
        }
        if let Some(start) = self.lead_start(controls) {
            scratch.lead = [start, scratch.path[0]];
            if !self
                .grid
                .is_feasible(&scratch.lead, self.objective.min_clearance_mm)
                || add_lead_in_exposure(
                    &self.objective.model,
                    &self.surface,
                    &scratch.lead,
                    &mut scratch.lead_wire,
                    &mut scratch.lead_exposure,
                    &mut scratch.exposure,
                )
                .is_err()
            {
                return false;
            }
        }
        true
    }

    /// The regularisation residuals, appended to `out`: √λ·(c_{k+1} − c_k) for neighbouring
    /// path controls and, separately, feed controls (cyclic pairs with periodic spline ends,
    /// consecutive ones with open ends, where the first and last pass are meant to differ),
    /// then √μ·c_k for every feed control (ln ρ: the feed stays nominal unless moving it evens
    /// the exposure out; μ = [`FeedVariable::nominal_weight`]).
    fn regularisation_into(&self, controls: &[f64], out: &mut Vec<f64>) {
        let root = self.objective.smoothing.sqrt();
        let cyclic = self.objective.ends == SplineEnds::Periodic;
        let k = self.trajectory.control_points().min(controls.len());
        for c in [&controls[..k], self.feed_controls(controls)] {
            let m = c.len();
            let pairs = if cyclic { m } else { m.saturating_sub(1) };
            out.extend((0..pairs).map(|i| root * (c[(i + 1) % m] - c[i])));
        }
        if let Some(f) = self.objective.feed {
            let root = f.nominal_weight.sqrt();
            out.extend(self.feed_controls(controls).iter().map(|c| root * c));
        }
    }

    /// The loss L(c) (module docs); +∞ for an infeasible or degenerate path or non-finite
    /// controls ([`Problem::evaluate`]).
    pub fn loss(&self, controls: &[f64], scratch: &mut Scratch) -> f64 {
        if !self.evaluate(controls, scratch) {
            return f64::INFINITY;
        }
        let n = scratch.exposure.len() as f64;
        let fit = scratch
            .exposure
            .iter()
            .map(|e| (e - self.cse).powi(2))
            .sum::<f64>()
            / n;
        let mut reg = std::mem::take(&mut scratch.regularisation);
        reg.clear();
        self.regularisation_into(controls, &mut reg);
        let l = fit + reg.iter().map(|r| r * r).sum::<f64>();
        scratch.regularisation = reg;
        if l.is_nan() {
            f64::INFINITY
        } else {
            l
        }
    }

    /// The residuals r with ‖r‖² = L(c), into `out`: (Eᵢ − CSE)/√N for every panel, then the
    /// regularisation's (module docs). False where L = +∞.
    pub fn residuals_into(
        &self,
        controls: &[f64],
        scratch: &mut Scratch,
        out: &mut Vec<f64>,
    ) -> bool {
        if !self.evaluate(controls, scratch) {
            return false;
        }
        let scale = (scratch.exposure.len() as f64).sqrt().recip();
        out.clear();
        out.extend(scratch.exposure.iter().map(|e| (e - self.cse) * scale));
        self.regularisation_into(controls, out);
        out.iter().all(|r| r.is_finite())
    }
}

/// `baseline` parameterised by `objective`'s spline settings, and the spline parameter at
/// each wire segment's middle (where the feed spline is evaluated).
fn parameterise(
    baseline: Baseline,
    objective: &Objective,
) -> Result<(Trajectory, Vec<f64>), PsoError> {
    let trajectory = Trajectory::with_ends(
        baseline,
        objective.control_points,
        objective.ends,
        objective.spacing,
    )?;
    let segment_u = trajectory
        .parameters()
        .windows(2)
        .map(|w| 0.5 * (w[0] + w[1]))
        .collect();
    Ok((trajectory, segment_u))
}

/// Adds the heat of the straight lead-in `lead` to `out` (one value per panel of `surface`):
/// `model` with the causal mask off, since the wire is on the lead-in before it cuts any
/// panel, so all of it counts for every panel. `wire` and `extra` are reusable buffers.
pub(crate) fn add_lead_in_exposure(
    model: &ExposureModel,
    surface: &Panels,
    lead: &[Point2<f64>; 2],
    wire: &mut WireSegments,
    extra: &mut Vec<f64>,
    out: &mut [f64],
) -> Result<(), ExposureError> {
    wire.set(lead)?;
    extra.resize(surface.len(), 0.0);
    ExposureModel {
        causal: crate::exposure::Causal::Off,
        ..*model
    }
    .exposure_into(surface, wire, extra)?;
    for (e, x) in out.iter_mut().zip(extra.iter()) {
        *e += x;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airfoil::test_foil;
    use crate::exposure::Causal;

    fn problem(model: ExposureModel) -> Problem {
        let foil = test_foil("e387", 200.0);
        let baseline = Baseline::fixed_offset(&foil, 0.5, 120).unwrap();
        let objective = Objective {
            model,
            feed: None,
            ..Objective::default()
        };
        Problem::new(&foil, 80, baseline, objective).unwrap()
    }

    /// Without the causal mask the closed baseline heats every panel the same wherever the
    /// wire enters, so a restarted problem's exposure, put back in trailing-edge order, is the
    /// original's; with the mask it differs (the cutting order matters), and the restarted
    /// surface begins next to the new entry.
    #[test]
    fn entering_elsewhere_restarts_path_and_surface_together() {
        let off = ExposureModel {
            causal: Causal::Off,
            ..ExposureModel::default()
        };
        let zero = vec![0.0; 32];
        let original = problem(off).exposure(&zero).unwrap();
        for vertex in [0, 37, 90] {
            let p = problem(off).entering_at(vertex).unwrap();
            let back = p.trailing_edge_order(&p.exposure(&zero).unwrap());
            for (i, (a, b)) in original.iter().zip(&back).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-3 * a.abs().max(1.0),
                    "{vertex} {i}: {a} {b}"
                );
            }
            let first = p.trajectory().baseline().points()[0];
            assert!((p.surface().midpoint(0) - first).norm() < 10.0, "{vertex}");
        }
        let masked = problem(ExposureModel::default());
        let e0 = masked.exposure(&zero).unwrap();
        let restarted = problem(ExposureModel::default()).entering_at(60).unwrap();
        let e1 = restarted.trailing_edge_order(&restarted.exposure(&zero).unwrap());
        assert!(e0.iter().zip(&e1).any(|(a, b)| (a - b).abs() > 0.1));
        // A vertex past the baseline, or after a lead-in, is refused by name.
        let n = masked.trajectory().baseline().points().len();
        let e = problem(off).entering_at(n).unwrap_err();
        assert!(e.to_string().starts_with("entry_vertex"), "{e}");
        let with_lead = problem(off).with_lead_in(Point2::new(215.0, 0.0)).unwrap();
        assert!(with_lead.entering_at(3).is_err());
    }
}
