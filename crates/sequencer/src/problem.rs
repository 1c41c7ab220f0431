//! The sequencing problem (seed 003 §A1): what every policy, the thermal simulation and the
//! improvement phase take as input, independent of where the layout came from (DXF, JSON, the
//! generator).

use cell_geometry::{ring_perimeter, Norm};
use serde::{Deserialize, Serialize};

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
    /// within the layout's chord tolerance before they get here.
    pub points: Vec<Point>,
    /// Where cutting may start (seed 003's fixed `P_ij` is a single candidate). A cut starts
    /// and ends at its pierce point, going once round the contour.
    pub pierce_candidates: Vec<Point>,
}

impl Contour {
    /// The length of one full cut round the contour, mm.
    pub fn perimeter(&self) -> f64 {
        ring_perimeter(&self.points, Norm::Hypot)
    }
}

/// A whole sequencing problem.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Problem {
    /// Sheet size `a × b`, mm.
    pub sheet: [f64; 2],
    /// Initial (and final) tool position `P_start`.
    pub start: Point,
    /// Every contour of every part.
    pub contours: Vec<Contour>,
    /// The connectivity rules between them.
    pub precedence: Precedence,
}

/// Euclidean distance, mm, rounded by `hypot` ([`Norm::Hypot`], as every length in this crate).
pub fn distance(a: Point, b: Point) -> f64 {
    Norm::Hypot.distance(a, b)
}
