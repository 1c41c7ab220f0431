//! Planar geometry for the toolpath planner: inward offsets through `cavalier_contours`' Shape
//! API, arc flattening, and the few predicates (point in region, ray casts, segment crossings)
//! that no workspace crate offers on plain `[f64; 2]` rings.

use cavalier_contours::polyline::{
    seg_arc_radius_and_center, PlineCreation, PlineSource, PlineSourceMut, PlineVertex, Polyline,
};
use cavalier_contours::shape_algorithms::{Shape, ShapeOffsetOptions};

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

/// Euclidean distance.
pub fn dist(a: P2, b: P2) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Signed area of a ring (positive for CCW).
pub fn signed_area(ring: &[P2]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        / 2.0
}

/// Even-odd point-in-region test over all rings (outer and holes).
pub fn inside(rings: &[Vec<P2>], p: P2) -> bool {
    let mut c = false;
    for r in rings {
        let n = r.len();
        for i in 0..n {
            let (a, b) = (r[i], r[(i + 1) % n]);
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < x {
                    c = !c;
                }
            }
        }
    }
    c
}

/// Distance from `p` to the segment a–b.
pub fn dist_to_segment(p: P2, a: P2, b: P2) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

/// Distance from `p` to the nearest ring edge.
pub fn dist_to_boundary(rings: &[Vec<P2>], p: P2) -> f64 {
    let mut best = f64::INFINITY;
    for r in rings {
        for i in 0..r.len() {
            best = best.min(dist_to_segment(p, r[i], r[(i + 1) % r.len()]));
        }
    }
    best
}

/// Inside the region or within `eps` of its boundary.
pub fn inside_or_on(rings: &[Vec<P2>], p: P2, eps: f64) -> bool {
    inside(rings, p) || dist_to_boundary(rings, p) <= eps
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

/// Bounding box (min, max) of all ring points.
pub fn bbox(rings: &[Vec<P2>]) -> (P2, P2) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in rings.iter().flatten() {
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    (lo, hi)
}

/// The closed ring as an explicitly closed polyline that starts at arc length `shift_mm` (mod
/// the perimeter) from the ring's lowest-leftmost vertex (min x + y, then min x): a start that
/// does not depend on where the offset algorithm happened to start the ring.
pub fn closed_from_arc_length(ring: &[P2], shift_mm: f64) -> Vec<P2> {
    let n = ring.len();
    let key = |p: &P2| (p[0] + p[1], p[0]);
    let first = (0..n)
        .min_by(|&a, &b| {
            key(&ring[a])
                .partial_cmp(&key(&ring[b]))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .unwrap_or(0);
    let mut r: Vec<P2> = ring[first..]
        .iter()
        .chain(&ring[..first])
        .copied()
        .collect();
    let perimeter: f64 = (0..n).map(|i| dist(r[i], r[(i + 1) % n])).sum();
    let mut s = if perimeter > 0.0 {
        shift_mm.rem_euclid(perimeter)
    } else {
        0.0
    };
    for i in 0..n {
        let (a, b) = (r[i], r[(i + 1) % n]);
        let l = dist(a, b);
        if s < l {
            let t = s / l;
            let start = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            let mut out = Vec::with_capacity(n + 2);
            out.push(start);
            if t > 0.0 {
                out.extend(r[i + 1..].iter().chain(&r[..=i]).copied());
            } else {
                out.extend(r[i + 1..].iter().chain(&r[..i]).copied());
                // `start` is vertex i itself; the loop returns to it below.
            }
            if dist(*out.last().unwrap_or(&start), start) > 1e-12 {
                out.push(start);
            }
            out.dedup_by(|x, y| dist(*x, *y) < 1e-12);
            return out;
        }
        s -= l;
    }
    r.push(r[0]);
    r
}

/// Length of an open polyline.
pub fn polyline_length(pts: &[P2]) -> f64 {
    pts.windows(2).map(|w| dist(w[0], w[1])).sum()
}

/// The polyline with extra points so that no piece is longer than `max_mm`.
pub fn resample(pts: &[P2], max_mm: f64) -> Vec<P2> {
    let mut out = Vec::with_capacity(pts.len());
    for w in pts.windows(2) {
        let l = dist(w[0], w[1]);
        let k = (l / max_mm).ceil().max(1.0) as usize;
        for j in 0..k {
            let t = j as f64 / k as f64;
            out.push([
                w[0][0] + t * (w[1][0] - w[0][0]),
                w[0][1] + t * (w[1][1] - w[0][1]),
            ]);
        }
    }
    if let Some(&l) = pts.last() {
        out.push(l);
    }
    out
}
