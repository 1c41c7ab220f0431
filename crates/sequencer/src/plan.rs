//! The cut plan: the order of (contour, pierce point) and its metrics (seed 003 §A1 `R` and
//! `Tr(R)`, notes §A6 outputs).

use serde::{Deserialize, Serialize};

use crate::problem::{distance, ContourId, Point, Problem};

/// One contour cut: which contour, from which of its pierce candidates (seed 003 §A1 `P_ij`;
/// free candidates make it a generalised TSP).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Cut {
    /// The contour.
    pub contour: ContourId,
    /// Index into its `pierce_candidates`.
    pub pierce: usize,
}

impl Cut {
    /// The pierce point in `problem`.
    pub fn point(&self, problem: &Problem) -> Point {
        problem.contours[self.contour].pierce_candidates[self.pierce]
    }

    /// Where the tool is when this cut is done: the end of its lead-out, or without leads the
    /// pierce point ([`crate::problem::Contour::exit`]).
    pub fn exit(&self, problem: &Problem) -> Point {
        problem.contours[self.contour].exit(self.pierce)
    }

    /// The whole path of this cut, pierce to exit ([`crate::problem::Contour::cut_path`]).
    pub fn path(&self, problem: &Problem) -> Vec<Point> {
        problem.contours[self.contour].cut_path(self.pierce)
    }
}

/// A whole plan with its metrics (seed 003 §A1, notes §A6).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CutPlan {
    /// The cuts in order.
    pub cuts: Vec<Cut>,
    /// Idle (travel) length from the start through every pierce point (from each cut's exit,
    /// with leads) and back, mm.
    pub idle_mm: f64,
    /// Cut length (sum of contour perimeters plus the leads), mm.
    pub cut_mm: f64,
    /// Overheats (our metric, [`crate::thermal`] docs); 0 when thermal cost is off.
    pub overheats: usize,
    /// Hottest metal cell, °C; ambient when thermal cost is off.
    pub max_temp_c: f32,
    /// Lead-in penalties, mm-equivalent ([`crate::cost`]).
    pub lead_in_penalty: f64,
    /// Simulated time, s (0 when thermal cost is off).
    pub time_s: f64,
    /// The cost the improvement minimises ([`crate::cost`]).
    pub cost: f64,
}

impl CutPlan {
    /// The contour order.
    pub fn order(&self) -> Vec<ContourId> {
        self.cuts.iter().map(|c| c.contour).collect()
    }
}

/// Idle length of a cut sequence, start and back, mm (seed 003 §A1): from the start to the
/// first pierce, from each cut's exit to the next pierce, and from the last exit back.
pub fn idle_length(problem: &Problem, cuts: &[Cut]) -> f64 {
    let mut at = problem.start;
    let mut sum = 0.0;
    for c in cuts {
        sum += distance(at, c.point(problem));
        at = c.exit(problem);
    }
    sum + distance(at, problem.start)
}
