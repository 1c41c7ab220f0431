//! Planar regions for the coverage planner, through `i_overlay` (boolean operations, offsets
//! and strokes on polygons with holes): the union of a layer's sections, the part grown by the
//! machining allowance, a bead's footprint and what the beads leave uncovered.
//!
//! A region is a list of shapes; a shape is its outer ring (counter-clockwise) followed by its
//! holes (clockwise), no repeated last point. Round joins and caps are chords inscribed in the
//! true arc (at most `tol_mm` inside it), so a footprint is never larger than the bead.

use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::overlay::FloatOverlay;
use i_overlay::float::single::SingleFloatOverlay;
use i_overlay::mesh::outline::offset::OutlineOffset;
use i_overlay::mesh::stroke::offset::StrokeOffset;
use i_overlay::mesh::style::{LineCap, LineJoin, OutlineStyle, StrokeStyle};

use super::geom::P2;

/// A shape: outer ring then holes.
pub type Shape = Vec<Vec<P2>>;

/// Points of a ring closer than this (mm) to the one kept before them are dropped.
const MIN_EDGE_MM: f64 = 1e-3;

/// A spike's shorter edge is below this (mm): a genuinely acute corner is kept.
const SPIKE_EDGE_MM: f64 = 0.01;

/// The ring without near-duplicate points (closer than `MIN_EDGE_MM`) and without spikes (a
/// vertex where the ring turns back on itself, cos < −0.999, along an edge shorter than
/// `SPIKE_EDGE_MM`): the integer snapping of the
/// boolean operations leaves such micro zig-zags, and a stroke along one cuts a notch.
pub fn clean_ring(ring: &[P2]) -> Vec<P2> {
    let mut out: Vec<P2> = Vec::with_capacity(ring.len());
    for &p in ring {
        if out
            .last()
            .is_none_or(|q| (p[0] - q[0]).hypot(p[1] - q[1]) >= MIN_EDGE_MM)
        {
            out.push(p);
        }
    }
    while out.len() > 1 {
        let (a, b) = (out[0], out[out.len() - 1]);
        if (a[0] - b[0]).hypot(a[1] - b[1]) < MIN_EDGE_MM {
            out.pop();
        } else {
            break;
        }
    }
    let mut changed = true;
    while changed && out.len() >= 3 {
        changed = false;
        let n = out.len();
        let mut keep = vec![true; n];
        for i in 0..n {
            let (a, v, b) = (out[(i + n - 1) % n], out[i], out[(i + 1) % n]);
            let (d1, d2) = ([v[0] - a[0], v[1] - a[1]], [b[0] - v[0], b[1] - v[1]]);
            let (l1, l2) = (d1[0].hypot(d1[1]), d2[0].hypot(d2[1]));
            let turns_back = (d1[0] * d2[0] + d1[1] * d2[1]) < -0.999 * l1 * l2;
            if turns_back && l1.min(l2) < SPIKE_EDGE_MM && keep[(i + n - 1) % n] {
                keep[i] = false;
                changed = true;
            }
        }
        let mut k = keep.iter();
        out.retain(|_| *k.next().unwrap_or(&true));
    }
    out
}

/// Every ring of every shape cleaned ([`clean_ring`]); rings left with fewer than 3 points and
/// shapes that lose their outer ring are dropped.
fn clean(shapes: Vec<Shape>) -> Vec<Shape> {
    shapes
        .into_iter()
        .filter_map(|s| {
            let mut rings = s.iter().map(|r| clean_ring(r));
            let outer = rings.next().filter(|r| r.len() >= 3)?;
            let mut shape = vec![outer];
            shape.extend(rings.filter(|r| r.len() >= 3));
            Some(shape)
        })
        .collect()
}

/// The angle step (radians) of a round join or cap of radius `r_mm` whose chords stay within
/// `tol_mm` of the arc: sagitta r(1 − cos(θ/2)) ≤ tol.
fn round_step(r_mm: f64, tol_mm: f64) -> f64 {
    if r_mm <= tol_mm {
        return std::f64::consts::FRAC_PI_4;
    }
    (2.0 * (1.0 - tol_mm / r_mm).acos()).clamp(0.02, std::f64::consts::FRAC_PI_4)
}

/// The region filled by `rings` under the non-zero rule (outer rings counter-clockwise, holes
/// clockwise: overlapping outers merge, a hole of one section inside another section's solid is
/// filled), as shapes.
pub fn union(rings: &[Vec<P2>]) -> Vec<Shape> {
    if rings.is_empty() {
        return Vec::new();
    }
    clean(FloatOverlay::with_subj(&rings.to_vec()).overlay(OverlayRule::Subject, FillRule::NonZero))
}

/// The union of several regions.
pub fn union_shapes(shapes: &[Shape]) -> Vec<Shape> {
    let rings: Vec<Vec<P2>> = shapes.iter().flatten().cloned().collect();
    union(&rings)
}

/// `a` minus `b`.
pub fn difference(a: &[Shape], b: &[Shape]) -> Vec<Shape> {
    if a.is_empty() {
        return Vec::new();
    }
    if b.is_empty() {
        return a.to_vec();
    }
    clean(
        a.to_vec()
            .overlay(&b.to_vec(), OverlayRule::Difference, FillRule::NonZero),
    )
}

/// The region grown by `d_mm` ≥ 0 (outer rings outwards, holes inwards, round joins): the
/// Minkowski sum with a disk of radius `d_mm`, chords within `tol_mm`.
pub fn grow(shapes: &[Shape], d_mm: f64, tol_mm: f64) -> Vec<Shape> {
    if shapes.is_empty() {
        return Vec::new();
    }
    if d_mm <= 0.0 {
        return union_shapes(shapes);
    }
    let style = OutlineStyle::new(d_mm).line_join(LineJoin::Round(round_step(d_mm, tol_mm)));
    clean(shapes.to_vec().outline(&style))
}

/// The region shrunk by `d_mm` ≥ 0 (outer rings inwards, holes outwards; reflex corners round,
/// convex corners sharp): the Minkowski difference with a disk of radius `d_mm`. Pieces that
/// vanish are gone; a piece pinched off becomes its own shape.
pub fn shrink(shapes: &[Shape], d_mm: f64, tol_mm: f64) -> Vec<Shape> {
    if shapes.is_empty() {
        return Vec::new();
    }
    if d_mm <= 0.0 {
        return union_shapes(shapes);
    }
    let style = OutlineStyle::new(-d_mm).line_join(LineJoin::Round(round_step(d_mm, tol_mm)));
    clean(shapes.to_vec().outline(&style))
}

/// The footprint of a bead of width `width_mm` along `path`: the path swept by a disk of
/// diameter `width_mm` (round joins and round ends), chords within `tol_mm`.
pub fn footprint(path: &[P2], width_mm: f64, closed: bool, tol_mm: f64) -> Vec<Shape> {
    if path.is_empty() || width_mm <= 0.0 {
        return Vec::new();
    }
    let step = round_step(width_mm / 2.0, tol_mm);
    if path.len() == 1 || path.windows(2).all(|w| w[0] == w[1]) {
        return vec![vec![disk(path[0], width_mm / 2.0, step)]];
    }
    let style = StrokeStyle::new(width_mm)
        .line_join(LineJoin::Round(step))
        .start_cap(LineCap::Round(step))
        .end_cap(LineCap::Round(step));
    let mut pts: Vec<P2> = Vec::with_capacity(path.len());
    for &p in path {
        if pts
            .last()
            .is_none_or(|q: &P2| (p[0] - q[0]).hypot(p[1] - q[1]) >= MIN_EDGE_MM)
        {
            pts.push(p);
        }
    }
    if pts.len() == 1 {
        return vec![vec![disk(pts[0], width_mm / 2.0, step)]];
    }
    clean(pts.stroke(style, closed))
}

/// A polygon inscribed in the circle (centre `c`, radius `r`), chords of angle ≤ `step`.
pub fn disk(c: P2, r: f64, step: f64) -> Vec<P2> {
    let n = ((std::f64::consts::TAU / step).ceil() as usize).max(8);
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [c[0] + r * a.cos(), c[1] + r * a.sin()]
        })
        .collect()
}

/// Area (mm²) of a shape: outer minus holes.
pub fn shape_area(shape: &Shape) -> f64 {
    shape
        .iter()
        .map(|r| cell_geometry::signed_area(r))
        .sum::<f64>()
        .abs()
}

/// Axis-aligned bounding box of a shape (min, max).
pub fn shape_bbox(shape: &Shape) -> (P2, P2) {
    let (lo, hi) = cell_geometry::bounding_box(shape.iter().flatten());
    ([lo.x, lo.y], [hi.x, hi.y])
}
