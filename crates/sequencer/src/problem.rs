//! The sequencing problem (seed 003 §A1): what every policy, the thermal simulation and the
//! improvement phase take as input, independent of where the layout came from (DXF, JSON, the
//! generator).

use cell_geometry::{ring_perimeter, Norm};
use serde::{Deserialize, Serialize};

use crate::leads::Lead;
use crate::precedence::Precedence;

/// A point on the sheet, mm; the sheet spans `0 ≤ x ≤ a`, `0 ≤ y ≤ b`.
pub type Point = [f64; 2];

/// Index of a contour in [`Problem::contours`].
pub type ContourId = usize;

/// What a contour is to its part.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContourRole {
    /// The part's outer contour (seed 003: `C_i1`), cut last in strict mode.
    Outer,
    /// A hole of the part (`C_ij`, j > 1).
    Hole,
}

/// One closed contour to cut.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contour {
    /// The part it belongs to (index into the layout's parts).
    pub part: usize,
    /// Outer contour or hole.
    pub role: ContourRole,
    /// The closed polyline, first point not repeated at the end, mm. Arcs are flattened to
    /// within the layout's chord tolerance before they get here. With a cut spec
    /// ([`crate::cut`]): the cut path, offset by half the kerf, part on its right.
    pub points: Vec<Point>,
    /// Where cutting may start (seed 003's fixed `P_ij` is a single candidate). Without leads
    /// a cut starts and ends at its pierce point, going once round the contour.
    pub pierce_candidates: Vec<Point>,
    /// With kerf and leads ([`crate::cut`]): one [`Lead`] per pierce candidate, from the pierce
    /// onto `points` (then the cut path) and off it again; the cut ends at the lead's exit.
    /// Empty: no leads.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub leads: Vec<Lead>,
    /// With a cut spec: the contour as drawn, `points` being its cut path. Empty: `points` is
    /// the drawn contour ([`Contour::drawn`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub drawn: Vec<Point>,
}

impl Contour {
    /// The length of one full cut round the contour, mm.
    pub fn perimeter(&self) -> f64 {
        ring_perimeter(&self.points, Norm::Hypot)
    }

    /// The contour as drawn (the part's edge): [`Contour::points`] unless a cut spec offset
    /// them by half the kerf.
    pub fn drawn(&self) -> &[Point] {
        if self.drawn.is_empty() {
            &self.points
        } else {
            &self.drawn
        }
    }

    /// The whole path of a cut from pierce candidate `k`: its lead-in, once round the contour
    /// and its lead-out ([`crate::leads::lead_cut_path`]), or without leads
    /// [`crate::thermal::cut_path`] from the pierce point.
    pub fn cut_path(&self, k: usize) -> Vec<Point> {
        match self.leads.get(k) {
            Some(lead) => crate::leads::lead_cut_path(&self.points, lead),
            None => crate::thermal::cut_path(self, self.pierce_candidates[k]),
        }
    }

    /// Where the tool is once the cut from pierce candidate `k` is done: the end of its
    /// lead-out, or without leads the pierce point.
    pub fn exit(&self, k: usize) -> Point {
        match self.leads.get(k) {
            Some(lead) => lead.exit(),
            None => self.pierce_candidates[k],
        }
    }

    /// Where the cut from pierce candidate `k` meets the contour: the lead-in's end, or
    /// without leads the pierce point.
    pub fn entry(&self, k: usize) -> Point {
        match self.leads.get(k) {
            Some(lead) => lead.entry(),
            None => self.pierce_candidates[k],
        }
    }
}

/// A whole sequencing problem.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Problem {
    /// Sheet size `a × b`, mm.
    pub sheet: [f64; 2],
    /// Initial (and final) tool position `P_start`, relative to the sheet like every point
    /// here.
    pub start: Point,
    /// The sheet's lower-left corner in machine coordinates, mm ([`crate::placement`]): the
    /// toolpath and the cut plan emit every point (the start too) at `origin + p`.
    #[serde(default)]
    pub origin: Point,
    /// Every contour of every part.
    pub contours: Vec<Contour>,
    /// The connectivity rules between them.
    pub precedence: Precedence,
}

impl Problem {
    /// A point of the sheet in machine coordinates: `origin + p` ([`crate::placement`]).
    pub fn to_machine(&self, p: Point) -> Point {
        [self.origin[0] + p[0], self.origin[1] + p[1]]
    }
}

/// Euclidean distance, mm, rounded by `hypot` ([`Norm::Hypot`], as every length in this crate).
pub fn distance(a: Point, b: Point) -> f64 {
    Norm::Hypot.distance(a, b)
}
