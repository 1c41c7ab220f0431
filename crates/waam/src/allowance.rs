//! The machining allowance a planned layer leaves (issue 20, item 1): how far the deposit
//! reaches beyond the part's section, measured on the deposit model the planner uses (each
//! bead's path swept by a disk of its width, [`crate::toolpath::cover::bead_footprint`]).
//!
//! The allowance at a point p of the part section's boundary is the signed distance from p to
//! the footprint's boundary, positive inside the footprint. The layer's value is the least over
//! points every `step_mm` along the section's rings and, for each piece of the section the
//! footprint leaves uncovered (a void inside, a bite at the edge), minus the radius of the
//! largest disk in that piece (found by bisection on inward offsets to 0.01 mm; pieces thinner than
//! 0.02 mm are where two beads just touch): a void is short of material by that much.

use cell_geometry::{distance_to_rings, point_in_rings_even_odd, resample_max_step};

use crate::toolpath::cover::{bead_footprint, PlannedBead};
use crate::toolpath::geom::{NORM, P2};
use crate::toolpath::region;
use crate::toolpath::{LayerToolpath, SegmentKind};

/// Uncovered pieces no thicker than twice this (mm) are cracks where beads touch, not voids.
pub const CRACK_HALF_MM: f64 = 0.01;

/// The least allowance of one layer and where it occurs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerAllowance {
    /// Least signed distance (mm) from the part section's boundary to the deposit's boundary
    /// (negative: part left uncovered by that much).
    pub min_mm: f64,
    /// Where (mm, x y).
    pub at_mm: [f64; 2],
}

/// The deposit pieces of a planned layer as planned beads (one per deposit segment).
fn layer_beads(layer: &LayerToolpath) -> Vec<PlannedBead> {
    layer
        .segments
        .iter()
        .filter(|s| s.kind == SegmentKind::Deposit)
        .map(|s| {
            let pts: Vec<P2> = s.points.iter().map(|p| [p.x_mm, p.y_mm]).collect();
            let closed = pts.len() > 3 && pts.first() == pts.last();
            PlannedBead {
                role: s.role,
                widths: s.points.iter().map(|p| p.bead_width_mm).collect(),
                pts,
                closed,
            }
        })
        .collect()
}

/// The least allowance of `layer` around the part section `part_rings` (outer CCW, holes CW),
/// boundary sampled every `step_mm`, footprint chords within `tol_mm`. `None` when the section
/// is empty.
pub fn layer_allowance(
    part_rings: &[Vec<P2>],
    layer: &LayerToolpath,
    step_mm: f64,
    tol_mm: f64,
) -> Option<LayerAllowance> {
    if part_rings.is_empty() {
        return None;
    }
    let prints: Vec<region::Shape> = layer_beads(layer)
        .iter()
        .flat_map(|b| bead_footprint(b, tol_mm))
        .collect();
    let deposit: Vec<Vec<P2>> = region::union_shapes(&prints)
        .into_iter()
        .flatten()
        .collect();
    let mut best: Option<LayerAllowance> = None;
    let mut take = |min_mm: f64, at_mm: P2| {
        if best.is_none_or(|b| min_mm < b.min_mm) {
            best = Some(LayerAllowance { min_mm, at_mm });
        }
    };
    for ring in part_rings {
        let mut closed = ring.clone();
        closed.push(ring[0]);
        for p in resample_max_step(&closed, step_mm, NORM) {
            if deposit.is_empty() {
                take(f64::NEG_INFINITY, p);
                continue;
            }
            let d = distance_to_rings(p, &deposit, NORM);
            let inside = point_in_rings_even_odd(p, &deposit);
            take(if inside { d } else { -d }, p);
        }
    }
    let covered = region::union_shapes(&prints);
    for piece in region::difference(&region::union(part_rings), &covered) {
        let one = std::slice::from_ref(&piece);
        // Cracks where two beads just touch (chords of their round ends) are not voids.
        if region::shrink(one, CRACK_HALF_MM, tol_mm).is_empty() {
            continue;
        }
        let (mut lo, mut hi) = (CRACK_HALF_MM, 1.0);
        while !region::shrink(one, hi, tol_mm).is_empty() {
            lo = hi;
            hi *= 2.0;
        }
        while hi - lo > 0.01 {
            let m = 0.5 * (lo + hi);
            if region::shrink(one, m, tol_mm).is_empty() {
                hi = m;
            } else {
                lo = m;
            }
        }
        take(-hi, piece[0][0]);
    }
    best
}
