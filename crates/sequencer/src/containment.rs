//! Ring geometry checks and the containment tree of a nested layout (seed 003 §A1; notes §A6:
//! "build the containment tree with point-in-polygon to get the `IN` sets").
//!
//! The signed area, the bounding boxes and the point-in-polygon test (non-zero winding number)
//! come from `cell_geometry`; the self-intersection scan and the crossing search from
//! `cavalier_contours` (already in the workspace for the planner's offsets).
//!
//! **Tree.** For closed, simple, pairwise non-crossing rings, ring `c`'s parent is the
//! smallest-area ring that contains it (its first vertex has non-zero winding number there,
//! after an axis-aligned bounding-box pre-filter). Depth 0 = outer contours of top-level parts,
//! depth 1 = their holes, depth 2 = parts nested inside those holes, and so on: even depth is
//! an outer contour, odd depth a hole.
//!
//! **Degenerate cases.** Fewer than 3 distinct points, zero area, a self-intersection or a
//! vertex outside the sheet `[0, a] × [0, b]` is an error naming the ring ([`check_ring`]).
//! Rings that cross or touch each other are found by [`find_crossing`]; the layout code rejects
//! them before building the tree, which assumes disjoint, nested rings (as the paper does).

use cavalier_contours::polyline::{PlineCreation, PlineSource, PlineSourceMut, Polyline};
use cell_geometry::{bounding_box, point_in_ring_nonzero, signed_area};

use crate::problem::Point;

/// Why a set of rings does not form a valid nested layout (seed 003 §A1).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometryError {
    /// Fewer than three distinct points, or zero area.
    #[error("{ring}: degenerate contour ({points} distinct points, area {area_mm2:.3} mm²)")]
    Degenerate {
        /// Which ring (the caller's name for it: part/hole index, DXF entity…).
        ring: String,
        /// Distinct points.
        points: usize,
        /// Absolute area, mm².
        area_mm2: f64,
    },
    /// The ring crosses itself.
    #[error("{ring}: the contour intersects itself")]
    SelfIntersecting {
        /// Which ring.
        ring: String,
    },
    /// A vertex lies outside the sheet.
    #[error("{ring}: point ({x:.3}, {y:.3}) mm lies outside the sheet {a} × {b} mm")]
    OutsideSheet {
        /// Which ring.
        ring: String,
        /// The vertex, mm.
        x: f64,
        /// The vertex, mm.
        y: f64,
        /// Sheet width, mm.
        a: f64,
        /// Sheet height, mm.
        b: f64,
    },
    /// Two contours cross or touch (seed 003 §A1 assumes disjoint, nested contours).
    #[error("{ring} crosses or touches {other}")]
    Crossing {
        /// One ring.
        ring: String,
        /// The other ring.
        other: String,
    },
    /// A coordinate is NaN or infinite.
    #[error("{ring}: non-finite coordinate")]
    NonFinite {
        /// Which ring.
        ring: String,
    },
}

/// Tolerance for "on the sheet edge", mm.
const SHEET_EPS_MM: f64 = 1e-6;

/// A closed polyline (no bulges) as a cavalier_contours polyline (a contour `C_ij`, seed 003 §A1).
pub fn to_pline(points: &[Point]) -> Polyline<f64> {
    let mut p = Polyline::with_capacity(points.len(), true);
    for q in points {
        p.add(q[0], q[1], 0.0);
    }
    p
}

/// Removes consecutive duplicate points (within `eps_mm`), including a repeated first point at
/// the end, so a contour `C_ij` (seed 003 §A1) is a closed polyline without repeats.
pub fn dedup_ring(points: &[Point], eps_mm: f64) -> Vec<Point> {
    let mut out: Vec<Point> = Vec::with_capacity(points.len());
    for &p in points {
        if out
            .last()
            .is_none_or(|&q| crate::problem::distance(p, q) > eps_mm)
        {
            out.push(p);
        }
    }
    while out.len() > 1 && crate::problem::distance(out[0], *out.last().unwrap()) <= eps_mm {
        out.pop();
    }
    out
}

/// Checks one ring: finite, ≥ 3 distinct points, non-zero area, simple, inside the sheet
/// `L(a×b)` (seed 003 §A1; issue 7: self-intersecting contours are errors).
///
/// # Errors
/// The first [`GeometryError`] found, carrying `name`.
pub fn check_ring(name: &str, points: &[Point], sheet: [f64; 2]) -> Result<(), GeometryError> {
    if points.iter().flatten().any(|v| !v.is_finite()) {
        return Err(GeometryError::NonFinite { ring: name.into() });
    }
    let area = signed_area(points).abs();
    if points.len() < 3 || area <= 1e-9 {
        return Err(GeometryError::Degenerate {
            ring: name.into(),
            points: points.len(),
            area_mm2: area,
        });
    }
    if let Some(p) = points.iter().find(|p| {
        p[0] < -SHEET_EPS_MM
            || p[1] < -SHEET_EPS_MM
            || p[0] > sheet[0] + SHEET_EPS_MM
            || p[1] > sheet[1] + SHEET_EPS_MM
    }) {
        return Err(GeometryError::OutsideSheet {
            ring: name.into(),
            x: p[0],
            y: p[1],
            a: sheet[0],
            b: sheet[1],
        });
    }
    if to_pline(points).scan_for_self_intersect() {
        return Err(GeometryError::SelfIntersecting { ring: name.into() });
    }
    Ok(())
}

/// The containment tree over a list of rings (seed 003 §A1 `IN` sets; notes §A6).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ContainmentTree {
    /// `parent[r]`: the smallest ring containing ring `r`, or `None` at the top level.
    pub parent: Vec<Option<usize>>,
    /// `depth[r]`: number of rings containing `r` (0 = top-level outer contour).
    pub depth: Vec<usize>,
    /// `children[r]`: rings whose parent is `r`, ascending.
    pub children: Vec<Vec<usize>>,
}

impl ContainmentTree {
    /// Builds the tree for rings that are already checked ([`check_ring`]) (seed 003 §A1;
    /// notes §A6: point-in-polygon containment).
    ///
    /// Cost: O(n log n) for the sort plus, per ring, a bounding-box scan over larger rings and a
    /// winding-number test for each box that contains it.
    pub fn build(rings: &[Vec<Point>]) -> Self {
        let n = rings.len();
        let boxes: Vec<[f64; 4]> = rings.iter().map(|r| bbox(r)).collect();
        // Shoelace areas order the rings for the tree (seed 003 §A1, notes §A6).
        let areas: Vec<f64> = rings.iter().map(|r| signed_area(r).abs()).collect();
        // Largest first: a parent always comes before its children.
        let mut by_area: Vec<usize> = (0..n).collect();
        by_area.sort_by(|&i, &j| areas[j].total_cmp(&areas[i]).then(i.cmp(&j)));
        let mut parent = vec![None; n];
        for (k, &r) in by_area.iter().enumerate() {
            let probe = rings[r][0];
            // Candidates: larger rings whose box holds r's box; the smallest that contains wins.
            let mut best: Option<usize> = None;
            for &c in by_area[..k].iter().rev() {
                if !box_contains(boxes[c], boxes[r]) || areas[c] <= areas[r] {
                    continue;
                }
                if point_in_ring_nonzero(probe, &rings[c]) {
                    best = Some(c);
                    break;
                }
            }
            parent[r] = best;
        }
        let mut depth = vec![0; n];
        for &r in &by_area {
            depth[r] = parent[r].map_or(0, |p| depth[p] + 1);
        }
        let mut children = vec![Vec::new(); n];
        for (r, p) in parent.iter().enumerate() {
            if let Some(p) = *p {
                children[p].push(r);
            }
        }
        ContainmentTree {
            parent,
            depth,
            children,
        }
    }
}

/// Finds the first pair of rings that cross or touch (seed 003 §A1: contours are disjoint),
/// comparing only rings whose bounding boxes overlap (sort and sweep along x) with
/// cavalier_contours' polyline intersection; `None` if the rings are pairwise disjoint.
///
/// Cost: O(n log n) plus one intersection query per overlapping box pair (in a nested layout:
/// about one per ring, parent and child).
pub fn find_crossing(rings: &[Vec<Point>]) -> Option<(usize, usize)> {
    let boxes: Vec<[f64; 4]> = rings.iter().map(|r| bbox(r)).collect();
    let plines: Vec<Polyline<f64>> = rings.iter().map(|r| to_pline(r)).collect();
    let mut by_x: Vec<usize> = (0..rings.len()).collect();
    by_x.sort_by(|&i, &j| boxes[i][0].total_cmp(&boxes[j][0]).then(i.cmp(&j)));
    let mut active: Vec<usize> = Vec::new();
    for &r in &by_x {
        active.retain(|&a| boxes[a][2] >= boxes[r][0]);
        for &a in &active {
            let overlap_y = boxes[a][1] <= boxes[r][3] && boxes[r][1] <= boxes[a][3];
            if overlap_y {
                let hits = plines[a].find_intersects(&plines[r]);
                if !hits.basic_intersects.is_empty() || !hits.overlapping_intersects.is_empty() {
                    return Some((a.min(r), a.max(r)));
                }
            }
        }
        active.push(r);
    }
    None
}

/// Axis-aligned bounding box `[xmin, ymin, xmax, ymax]` of a contour (seed 003 §A1), mm;
/// infinite (empty) for no points ([`cell_geometry::bounding_box`] in this crate's layout).
pub fn bbox(points: &[Point]) -> [f64; 4] {
    let (lo, hi) = bounding_box(points);
    [lo.x, lo.y, hi.x, hi.y]
}

fn box_contains(outer: [f64; 4], inner: [f64; 4]) -> bool {
    outer[0] <= inner[0] && outer[1] <= inner[1] && outer[2] >= inner[2] && outer[3] >= inner[3]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x: f64, y: f64, s: f64) -> Vec<Point> {
        vec![[x, y], [x + s, y], [x + s, y + s], [x, y + s]]
    }

    #[test]
    fn nested_squares_get_depths() {
        let rings = vec![
            square(10.0, 10.0, 10.0), // a part nested in hole 3
            square(200.0, 0.0, 5.0),  // top level
            square(0.0, 0.0, 100.0),  // top level, big
            square(5.0, 5.0, 50.0),   // hole of 2
            square(12.0, 12.0, 2.0),  // hole of 0
        ];
        let t = ContainmentTree::build(&rings);
        assert_eq!(t.parent, vec![Some(3), None, None, Some(2), Some(0)]);
        assert_eq!(t.depth, vec![2, 0, 0, 1, 3]);
        assert_eq!(t.children[2], vec![3]);
    }

    #[test]
    fn bad_rings_are_named() {
        let sheet = [100.0, 100.0];
        let bow = vec![[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 4.0]];
        assert_eq!(
            check_ring("part 3 outer", &bow, sheet),
            Err(GeometryError::SelfIntersecting {
                ring: "part 3 outer".into()
            })
        );
        let out = square(95.0, 0.0, 10.0);
        let e = check_ring("part 1 hole 0", &out, sheet).unwrap_err();
        assert!(
            e.to_string().starts_with("part 1 hole 0: point (105.000"),
            "{e}"
        );
        let line = vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
        assert!(matches!(
            check_ring("x", &line, sheet),
            Err(GeometryError::Degenerate { .. })
        ));
        assert!(check_ring("ok", &square(0.0, 0.0, 100.0), sheet).is_ok());
    }

    #[test]
    fn crossings_are_found() {
        let rings = vec![
            square(0.0, 0.0, 100.0),
            square(10.0, 10.0, 10.0),
            square(50.0, 50.0, 10.0),
        ];
        assert_eq!(find_crossing(&rings), None);
        let rings = vec![square(0.0, 0.0, 100.0), square(90.0, 10.0, 20.0)];
        assert_eq!(find_crossing(&rings), Some((0, 1)));
        let rings = vec![square(0.0, 0.0, 10.0), square(10.0, 0.0, 10.0)];
        assert_eq!(find_crossing(&rings), Some((0, 1)), "shared edge");
    }

    #[test]
    fn area_and_dedup() {
        assert_eq!(signed_area(&square(0.0, 0.0, 2.0)), 4.0);
        let r = dedup_ring(
            &[[0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 0.0]],
            1e-9,
        );
        assert_eq!(r, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]);
    }
}
