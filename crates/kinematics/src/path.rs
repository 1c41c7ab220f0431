//! Joint solutions along a path of linear moves that keep one arm configuration.
//!
//! ABB's `ConfL \On` makes the controller stop when a linear move cannot end in the
//! programmed configuration (RAPID reference, instruction `ConfL`), so every target of a
//! program must be reached in one arm configuration (`cfx`) with the joints moving
//! continuously from the target before. [`Robot::solve_path`]:
//!
//! 1. checks every target on its own: finite, within reach, and with at least one solution
//!    inside the joint ranges (whole turns of axes 4 and 6 included);
//! 2. tries start solutions at the first target, the usual arm configuration first (lowest
//!    `cfx`, then the one nearest the middle of the joint ranges), and follows each along the
//!    path: every move is cut into steps of at most [`STEP_MM`] and [`STEP_DEG`] of
//!    orientation (position linear, orientation slerp, as the controller moves), and at each
//!    step the solution in the same `cfx` nearest the previous one (every joint taken to the
//!    whole turn nearest its previous value) is kept. A step where that solution leaves a
//!    joint range, changes `cfx` or turns a joint more than [`MAX_JOINT_STEP_DEG`] (a wrist
//!    flip near a singularity) ends that start;
//! 3. returns the first start that reaches the last target, or the problem of the start that
//!    got furthest, naming the target.

use std::f64::consts::TAU;

use thiserror::Error;

use crate::frame::Frame;
use crate::model::{Joints, Robot};

/// Longest step along a move when following the joints, mm.
pub const STEP_MM: f64 = 10.0;
/// Largest orientation change per step, degrees.
pub const STEP_DEG: f64 = 5.0;
/// Largest turn of any joint within one step, degrees; more is a configuration change or a
/// pass close to a singularity.
pub const MAX_JOINT_STEP_DEG: f64 = 45.0;
/// Start solutions tried at the first target.
const MAX_STARTS: usize = 16;
/// Steps a single move is cut into at most.
const MAX_STEPS_PER_MOVE: usize = 2000;

/// One target's joint solution and its ABB configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathSolution {
    /// Joint values, radians.
    pub joints: Joints,
    /// `[cf1, cf4, cf6, cfx]` (see [`crate::confdata`]).
    pub confdata: [i32; 4],
}

/// Why a target cannot be reached in the path's configuration.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ReachProblem {
    /// A position or orientation that is not finite.
    #[error("the target is not finite")]
    NotFinite,
    /// No joint solution at all places the tool there.
    #[error("out of the robot's reach (no joint solution)")]
    OutOfReach,
    /// The straight move to the target leaves the robot's reach on the way.
    #[error("the linear move to it leaves the robot's reach on the way")]
    MoveOutOfReach,
    /// Every solution has a joint outside its range.
    #[error(
        "axis {axis} would be at {value_deg:.1} deg, outside its range [{min_deg}, {max_deg}]"
    )]
    JointLimit {
        /// Axis number 1–6.
        axis: usize,
        /// Its value, degrees.
        value_deg: f64,
        /// Range, degrees.
        min_deg: f64,
        /// Range, degrees.
        max_deg: f64,
    },
    /// Reaching it needs another arm configuration than the path's.
    #[error("the arm configuration would have to change from cfx {from} to cfx {to} (ConfL \\On stops there)")]
    ConfigurationChange {
        /// The path's cfx.
        from: i32,
        /// The only cfx that reaches it.
        to: i32,
    },
    /// A joint would turn by more than [`MAX_JOINT_STEP_DEG`] within one short step.
    #[error("axis {axis} would turn {step_deg:.0} deg within a {STEP_MM} mm step (a wrist flip near a singularity)")]
    JointJump {
        /// Axis number 1–6.
        axis: usize,
        /// The turn, degrees.
        step_deg: f64,
    },
}

/// A target that cannot be reached (index into the targets).
#[derive(Debug, Clone, PartialEq, Error)]
#[error("target {index}: {problem}")]
pub struct PathError {
    /// Index of the target.
    pub index: usize,
    /// What is wrong.
    pub problem: ReachProblem,
}

impl Robot {
    /// Joint solutions for `targets` (TCP frames in the world) with `tool` (tool0 → TCP), one
    /// arm configuration throughout (module docs).
    ///
    /// # Errors
    /// [`PathError`] naming the first target that cannot be reached that way.
    pub fn solve_path(
        &self,
        targets: &[Frame],
        tool: &Frame,
    ) -> Result<Vec<PathSolution>, PathError> {
        let Some(first) = targets.first() else {
            return Ok(Vec::new());
        };
        let fail = |index, problem| PathError { index, problem };
        let mut solutions: Vec<Vec<Joints>> = Vec::with_capacity(targets.len());
        for (i, t) in targets.iter().enumerate() {
            if !t.is_valid() || !tool.is_valid() {
                return Err(fail(i, ReachProblem::NotFinite));
            }
            let s = self.inverse(t, tool);
            if s.is_empty() {
                return Err(fail(i, ReachProblem::OutOfReach));
            }
            if s.iter().all(|q| self.nearest_in_limits(q).is_none()) {
                return Err(fail(i, self.limit_problem(&s)));
            }
            solutions.push(s);
        }
        let mut starts = self.inverse_within_limits(first, tool);
        let key = |q: &Joints| (self.cfx(q).unwrap_or(8), self.off_centre(q));
        starts.sort_by(|a, b| {
            key(a)
                .partial_cmp(&key(b))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        let mut furthest: Option<PathError> = None;
        for start in starts.iter().take(MAX_STARTS) {
            match self.follow(start, targets, &solutions, tool) {
                Ok(path) => return Ok(path),
                Err(e) => {
                    if furthest.as_ref().is_none_or(|f| e.index > f.index) {
                        furthest = Some(e);
                    }
                }
            }
        }
        Err(furthest.unwrap_or(fail(0, ReachProblem::OutOfReach)))
    }

    /// Follows the path from `start` (module docs, step 2).
    fn follow(
        &self,
        start: &Joints,
        targets: &[Frame],
        solutions: &[Vec<Joints>],
        tool: &Frame,
    ) -> Result<Vec<PathSolution>, PathError> {
        let cfx = self.cfx(start).unwrap_or(-1);
        let mut prev = *start;
        let solution = |q: &Joints| PathSolution {
            joints: *q,
            confdata: self.confdata(q).unwrap_or([0, 0, 0, cfx]),
        };
        let mut out = vec![solution(start)];
        for i in 1..targets.len() {
            let (a, b) = (&targets[i - 1], &targets[i]);
            let steps = ((a.distance_mm(b) / STEP_MM).max(a.angle_to(b).to_degrees() / STEP_DEG))
                .ceil()
                .clamp(1.0, MAX_STEPS_PER_MOVE as f64) as usize;
            for k in 1..=steps {
                let between;
                let candidates = if k == steps {
                    &solutions[i]
                } else {
                    between = self.inverse(&a.interpolate(b, k as f64 / steps as f64), tool);
                    if between.is_empty() {
                        return Err(PathError {
                            index: i,
                            problem: ReachProblem::MoveOutOfReach,
                        });
                    }
                    &between
                };
                prev = self
                    .next_step(&prev, cfx, candidates)
                    .map_err(|problem| PathError { index: i, problem })?;
            }
            out.push(solution(&prev));
        }
        Ok(out)
    }

    /// The solution in `cfx` nearest `prev`, or why there is none.
    fn next_step(
        &self,
        prev: &Joints,
        cfx: i32,
        candidates: &[Joints],
    ) -> Result<Joints, ReachProblem> {
        let mut best: Option<(f64, usize, Joints)> = None;
        let mut other_cfx = None;
        let mut limit = None;
        for c in candidates {
            let mut q = *c;
            for (v, p) in q.iter_mut().zip(prev) {
                *v += TAU * ((p - *v) / TAU).round();
            }
            let this = self.cfx(&q).unwrap_or(-1);
            if this != cfx {
                other_cfx.get_or_insert(this);
                continue;
            }
            if let Some((axis, value)) = self.first_violation(&q) {
                limit.get_or_insert((axis, value));
                continue;
            }
            let (axis, step) = q
                .iter()
                .zip(prev)
                .map(|(a, b)| (a - b).abs())
                .enumerate()
                .fold((0, 0.0), |m, (i, d)| if d > m.1 { (i, d) } else { m });
            if best.as_ref().is_none_or(|b| step < b.0) {
                best = Some((step, axis, q));
            }
        }
        match (best, other_cfx, limit) {
            (Some((step, _, q)), _, _) if step.to_degrees() <= MAX_JOINT_STEP_DEG => Ok(q),
            (Some((step, axis, _)), _, _) => Err(ReachProblem::JointJump {
                axis: axis + 1,
                step_deg: step.to_degrees(),
            }),
            (None, _, Some((axis, value))) => Err(self.joint_limit(axis, value)),
            (None, Some(to), None) => Err(ReachProblem::ConfigurationChange { from: cfx, to }),
            (None, None, None) => Err(ReachProblem::MoveOutOfReach),
        }
    }

    /// `q` with every joint moved by whole turns into its range, if possible.
    fn nearest_in_limits(&self, q: &Joints) -> Option<Joints> {
        let mut out = *q;
        for (axis, v) in out.iter_mut().enumerate() {
            *v = *self.turn_variants(axis, *v).first()?;
        }
        Some(out)
    }

    /// The joint-limit problem of the solution nearest its ranges.
    fn limit_problem(&self, solutions: &[Joints]) -> ReachProblem {
        let excess = |axis: usize, v: f64| {
            let [lo, hi] = self.limits_rad()[axis];
            (lo - v).max(v - hi).max(0.0)
        };
        let worst = solutions
            .iter()
            .map(|q| {
                (0..6)
                    .filter(|&a| self.turn_variants(a, q[a]).is_empty())
                    .map(|a| (excess(a, q[a]), a, q[a]))
                    .fold((0.0, 0, 0.0), |m, e| if e.0 > m.0 { e } else { m })
            })
            .min_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(std::cmp::Ordering::Equal));
        let (_, axis, value) = worst.unwrap_or((0.0, 0, 0.0));
        self.joint_limit(axis, value)
    }

    fn joint_limit(&self, axis: usize, value: f64) -> ReachProblem {
        let [lo, hi] = self.limits_rad()[axis];
        ReachProblem::JointLimit {
            axis: axis + 1,
            value_deg: value.to_degrees(),
            min_deg: (lo.to_degrees() * 1e6).round() / 1e6,
            max_deg: (hi.to_degrees() * 1e6).round() / 1e6,
        }
    }

    /// Σ ((q − centre) / half range)² over the axes: 0 in the middle of every range.
    fn off_centre(&self, q: &Joints) -> f64 {
        q.iter()
            .zip(self.limits_rad())
            .map(|(v, [lo, hi])| ((v - (lo + hi) / 2.0) / ((hi - lo) / 2.0)).powi(2))
            .sum()
    }
}
