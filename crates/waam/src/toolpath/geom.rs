//! Planar geometry for the toolpath planner: inward offsets through `cavalier_contours`' Shape
//! API, arc flattening, ray casts and segment crossings on plain `[f64; 2]` rings. Areas,
//! point-in-region, distances and resampling come from `cell_geometry`, with lengths rounded
//! by [`NORM`].

use cavalier_contours::polyline::{
    seg_arc_radius_and_center, PlineCreation, PlineSource, PlineSourceMut, PlineVertex, Polyline,
};
use cavalier_contours::shape_algorithms::{Shape, ShapeOffsetOptions};
use cell_geometry::{AsPoint2, Norm};

/// A 2D point (mm).
pub type P2 = [f64; 2];

/// The region bounded by `rings` (outer CCW, holes CW) offset inward by `dist_mm` ≥ 0, as rings
/// with the same convention. Round joins (cavalier_contours) are flattened to chords within
/// `tol_mm`. Islands and holes are handled together by `Shape::parallel_offset`: a hole grows
/// while the outer shrinks, and loops that meet are merged.
pub fn inset(rings: &[Vec<P2>], dist_mm: f64, tol_mm: f64) -> Vec<Vec<P2>> {
    if dist_mm <= 0.0 {
        return rings.to_vec();
    }
    let plines = rings.iter().map(|r| {
        let mut pl = Polyline::with_capacity(r.len(), true);
        for p in r {
            pl.add(p[0], p[1], 0.0);
        }
        pl
    });
    let shape = Shape::from_plines(plines);
    // Positive offsets go to the left of travel: inside a CCW outer, outside a CW hole.
    let out = shape.parallel_offset(dist_mm, &ShapeOffsetOptions::default());
    out.ccw_plines
        .iter()
        .chain(out.cw_plines.iter())
        .map(|ip| flatten(&ip.polyline, tol_mm))
        .filter(|r| r.len() >= 3)
        .collect()
}

/// The closed polyline's vertices with each arc replaced by chords whose sagitta is ≤ `tol_mm`.
fn flatten(pline: &Polyline<f64>, tol_mm: f64) -> Vec<P2> {
    let n = pline.vertex_count();
    let mut out = Vec::with_capacity(2 * n);
    for i in 0..n {
        let (v1, v2): (PlineVertex<f64>, PlineVertex<f64>) = (pline.at(i), pline.at((i + 1) % n));
        out.push([v1.x, v1.y]);
        if v1.bulge == 0.0 || v1.pos().fuzzy_eq(v2.pos()) {
            continue;
        }
        let (radius, c) = seg_arc_radius_and_center(v1, v2);
        let sweep = 4.0 * v1.bulge.atan();
        // Sagitta r(1 − cos(θ/2)) ≤ tol.
        let max_step = 2.0 * (1.0 - (tol_mm / radius).min(1.0)).acos();
        let steps = (sweep.abs() / max_step.max(1e-3)).ceil().max(1.0) as usize;
        let a0 = (v1.y - c.y).atan2(v1.x - c.x);
        for j in 1..steps {
            let a = a0 + sweep * j as f64 / steps as f64;
            out.push([c.x + radius * a.cos(), c.y + radius * a.sin()]);
        }
    }
    out.dedup_by(|a, b| dist(*a, *b) < 1e-9);
    out
}

/// How the toolpath planner rounds lengths: `hypot` (its results are pinned with it).
pub const NORM: Norm = Norm::Hypot;

/// Euclidean distance, rounded by [`NORM`].
pub fn dist(a: impl AsPoint2, b: impl AsPoint2) -> f64 {
    NORM.distance(a, b)
}

/// Parameter (t along p→q, u along a→b) of the intersection of segments p–q and a–b, if they
/// are not parallel and cross within both.
pub fn segment_cross(p: P2, q: P2, a: P2, b: P2) -> Option<(f64, f64)> {
    let r = [q[0] - p[0], q[1] - p[1]];
    let s = [b[0] - a[0], b[1] - a[1]];
    let den = r[0] * s[1] - r[1] * s[0];
    if den.abs() < 1e-15 {
        return None;
    }
    let ap = [a[0] - p[0], a[1] - p[1]];
    let t = (ap[0] * s[1] - ap[1] * s[0]) / den;
    let u = (ap[0] * r[1] - ap[1] * r[0]) / den;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)).then_some((t, u))
}

/// Distance from `p` along the unit direction `dir` to the nearest ring edge, if any is hit
/// (hits closer than 1e-9 are ignored, so a point on a wall sees past that wall).
pub fn ray_hit(rings: &[Vec<P2>], p: P2, dir: P2, max_mm: f64) -> Option<f64> {
    let q = [p[0] + dir[0] * max_mm, p[1] + dir[1] * max_mm];
    let mut best: Option<f64> = None;
    for r in rings {
        for i in 0..r.len() {
            if let Some((t, _)) = segment_cross(p, q, r[i], r[(i + 1) % r.len()]) {
                let d = t * max_mm;
                if d > 1e-9 && best.is_none_or(|b| d < b) {
                    best = Some(d);
                }
            }
        }
    }
    best
}
