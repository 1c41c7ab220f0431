//! Wire trajectories for the optimiser: the fixed-offset baseline, its parameterisation by a
//! periodic cubic B-spline of normal displacements (seed 000 §IV.C) and the feasibility test
//! T ∩ G = ∅.
//!
//! A trajectory is a closed polyline in mm whose last point repeats its first, anticlockwise
//! from the trailing edge like the foil it cuts.

use cell_geometry::{point_in_ring_even_odd, segment_distance, Norm};
use nalgebra::{Point2, Vector2};

use crate::airfoil::{Airfoil, AirfoilError};
use crate::kerf::{offset_polyline, KerfError};

/// A rejected trajectory input.
#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    /// A parameter is NaN, infinite or out of its domain; `name` names it.
    #[error("{name} = {value} is invalid: must be {requirement}")]
    InvalidParameter {
        /// Parameter name, e.g. `offset_mm`.
        name: String,
        /// The value given.
        value: f64,
        /// The accepted domain.
        requirement: &'static str,
    },
    /// The offset path could not be built.
    #[error(transparent)]
    Kerf(#[from] KerfError),
    /// The offset path could not be resampled.
    #[error(transparent)]
    Airfoil(#[from] AirfoilError),
}

/// The usual practice, and the optimiser's starting point: the foil offset outwards by a fixed
/// distance.
#[derive(Debug, Clone, PartialEq)]
pub struct Baseline {
    points: Vec<Point2<f64>>,
    normals: Vec<Vector2<f64>>,
    arc: Vec<f64>,
}

impl Baseline {
    /// `foil` resampled to `m_points` points with cosine clustering at the LE and TE
    /// ([`Airfoil::resampled_cosine`]), then offset outwards by `offset_mm`
    /// ([`offset_polyline`], round joins). The result starts at the TE, runs anticlockwise and
    /// is closed (the last point repeats the first).
    ///
    /// Resolution: about one path point per foil point, plus the flattened round join at a
    /// sharp trailing edge (≤ 10° per step, about 18 points), so roughly `m_points` + 20
    /// points. Resampling the offset path instead would give exactly `m_points`, but then
    /// the chord across the TE join cuts into the foil at coarse resolution; offsetting the
    /// resampled foil keeps the path exactly `offset_mm` from the resampled polygon. From the
    /// true foil the clearance is `offset_mm` less the sagitta of the resampled chords on
    /// convex stretches (small: cosine spacing clusters points where curvature is high).
    ///
    /// # Errors
    /// `offset_mm` not finite and > 0 or `m_points` < 5 (named), or a failed offset.
    pub fn fixed_offset(
        foil: &Airfoil,
        offset_mm: f64,
        m_points: usize,
    ) -> Result<Self, TrajectoryError> {
        if !(offset_mm.is_finite() && offset_mm > 0.0) {
            return Err(TrajectoryError::InvalidParameter {
                name: "offset_mm".into(),
                value: offset_mm,
                requirement: "finite and > 0",
            });
        }
        if m_points < crate::airfoil::MIN_POINTS {
            return Err(TrajectoryError::InvalidParameter {
                name: "m_points".into(),
                value: m_points as f64,
                requirement: "at least 5",
            });
        }
        let resampled = foil.resampled_cosine(m_points)?;
        Self::from_points(offset_polyline(resampled.points(), offset_mm)?)
    }

    /// A baseline from an explicit closed path (closed here if the last point does not repeat
    /// the first). Computes each vertex's outward unit normal — the right-hand perpendicular of
    /// the sum of the unit directions in and out of the vertex (of the outgoing direction alone
    /// where they cancel) — and its normalised arc length u ∈ [0, 1].
    ///
    /// # Errors
    /// A non-finite point (named `points[i]`), fewer than 3 distinct points.
    pub fn from_points(mut points: Vec<Point2<f64>>) -> Result<Self, TrajectoryError> {
        if let Some(i) = points
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(TrajectoryError::InvalidParameter {
                name: format!("points[{i}]"),
                value: f64::NAN,
                requirement: "finite",
            });
        }
        points.dedup();
        if points.first() != points.last() {
            points.push(points[0]);
        }
        let n = points.len() - 1; // distinct vertices
        if n < 3 {
            return Err(TrajectoryError::InvalidParameter {
                name: "points".into(),
                value: n as f64,
                requirement: "at least 3 distinct points",
            });
        }
        let mut normals = outward_vertex_normals(&points[..n]);
        normals.push(normals[0]);
        let mut arc = Vec::with_capacity(n + 1);
        let mut s = 0.0;
        arc.push(0.0);
        for w in points.windows(2) {
            s += (w[1] - w[0]).norm();
            arc.push(s);
        }
        for a in &mut arc {
            *a /= s;
        }
        Ok(Self {
            points,
            normals,
            arc,
        })
    }

    /// The path points (closed: the last repeats the first).
    pub fn points(&self) -> &[Point2<f64>] {
        &self.points
    }

    /// Outward unit normal at each point.
    pub fn normals(&self) -> &[Vector2<f64>] {
        &self.normals
    }

    /// Normalised arc length of each point, 0 … 1.
    pub fn arc_positions(&self) -> &[f64] {
        &self.arc
    }
}

/// The outward unit normal at each vertex of the closed anticlockwise polygon `ring` (distinct
/// points, closing segment implied): the right-hand perpendicular of the sum of the unit
/// directions in and out of the vertex, or of the outgoing direction alone where they cancel.
pub(crate) fn outward_vertex_normals(ring: &[Point2<f64>]) -> Vec<Vector2<f64>> {
    let n = ring.len();
    let dir = |k: usize| (ring[(k + 1) % n] - ring[k % n]).normalize();
    (0..n)
        .map(|k| {
            let (d_in, d_out) = (dir(k + n - 1), dir(k));
            let s = d_in + d_out;
            let t = if s.norm() > 1e-12 {
                s.normalize()
            } else {
                d_out
            };
            Vector2::new(t.y, -t.x)
        })
        .collect()
}

pub use crate::spline::periodic_cubic_bspline;
use crate::spline::SplineEnds;

/// Where along the path the spline's control values act: the spline parameter u of each
/// baseline vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ControlSpacing {
    /// u = normalised arc length: controls evenly spaced along the path (seed 000, the
    /// notes).
    ArcLength,
    /// u = vertex index / vertex count: the baseline is the offset of a foil resampled with
    /// cosine spacing ([`Baseline::fixed_offset`]), so the controls cluster at the leading and
    /// trailing edges like the surface panels do, where the exposure changes fastest (default;
    /// crate docs, "Why the swarm stalled").
    #[default]
    PathPoints,
}

/// A baseline displaced along its normals by a cubic B-spline of K control values (seed 000
/// §IV.C; periodic or open ends, [`SplineEnds`]): vertex = baseline vertex + δ(u)·n, u its
/// normalised arc length. The basis is precomputed, so [`Trajectory::path_into`] costs four
/// multiply-adds per vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    baseline: Baseline,
    /// The spline parameter of each baseline vertex, 0 … 1 ([`ControlSpacing`]).
    u: Vec<f64>,
    k: usize,
    idx: Vec<[usize; 4]>,
    w: Vec<[f64; 4]>,
}

impl Trajectory {
    /// Parameterises `baseline` with `control_points` (K) control values of a periodic spline
    /// (the paper's).
    ///
    /// # Errors
    /// `control_points` < 4.
    pub fn new(baseline: Baseline, control_points: usize) -> Result<Self, TrajectoryError> {
        Self::with_ends(
            baseline,
            control_points,
            SplineEnds::Periodic,
            ControlSpacing::ArcLength,
        )
    }

    /// Parameterises `baseline` with K = `control_points` control values of a spline with the
    /// given end condition. With open ends the path's last point need not repeat its first.
    ///
    /// # Errors
    /// `control_points` < 4.
    pub fn with_ends(
        baseline: Baseline,
        control_points: usize,
        ends: SplineEnds,
        spacing: ControlSpacing,
    ) -> Result<Self, TrajectoryError> {
        if control_points < 4 {
            return Err(TrajectoryError::InvalidParameter {
                name: "control_points".into(),
                value: control_points as f64,
                requirement: "at least 4",
            });
        }
        let u: Vec<f64> = match spacing {
            ControlSpacing::ArcLength => baseline.arc.clone(),
            ControlSpacing::PathPoints => {
                let m = (baseline.points.len() - 1) as f64;
                (0..baseline.points.len()).map(|i| i as f64 / m).collect()
            }
        };
        let (idx, w) = u.iter().map(|&u| ends.basis(control_points, u)).unzip();
        Ok(Self {
            baseline,
            u,
            k: control_points,
            idx,
            w,
        })
    }

    /// Number of control values K.
    pub fn control_points(&self) -> usize {
        self.k
    }

    /// The undisplaced path.
    pub fn baseline(&self) -> &Baseline {
        &self.baseline
    }

    /// The spline parameter of each path point, 0 … 1.
    pub fn parameters(&self) -> &[f64] {
        &self.u
    }

    /// The displaced path for `controls` (mm along the outward normal; positive moves the wire
    /// away from the foil) into `out` (cleared first). Closed like the baseline: u = 0 and
    /// u = 1 have the same δ and normal. Entries beyond `controls.len()` count as 0.
    pub fn path_into(&self, controls: &[f64], out: &mut Vec<Point2<f64>>) {
        out.clear();
        let c = |i: usize| controls.get(i).copied().unwrap_or(0.0);
        for (k, (p, n)) in self
            .baseline
            .points
            .iter()
            .zip(&self.baseline.normals)
            .enumerate()
        {
            let (idx, w) = (self.idx[k], self.w[k]);
            let d = w[0] * c(idx[0]) + w[1] * c(idx[1]) + w[2] * c(idx[2]) + w[3] * c(idx[3]);
            out.push(p + n * d);
        }
    }

    /// [`Trajectory::path_into`] into a new vector.
    pub fn path(&self, controls: &[f64]) -> Vec<Point2<f64>> {
        let mut out = Vec::with_capacity(self.baseline.points.len());
        self.path_into(controls, &mut out);
        out
    }
}

/// True if segment c–d lies wholly outside the box [x_lo, x_hi] × [y_lo, y_hi].
#[inline(always)]
fn outside_box(c: Point2<f64>, d: Point2<f64>, [x_lo, x_hi, y_lo, y_hi]: [f64; 4]) -> bool {
    c.x.max(d.x) < x_lo || c.x.min(d.x) > x_hi || c.y.max(d.y) < y_lo || c.y.min(d.y) > y_hi
}

/// Smallest distance between the polyline `path` (open, or closed by repeating its first point)
/// and the closed polygon `outline` (closing segment implied), or 0 when they intersect or the
/// path lies inside the outline. Segment–segment distances, not just vertices.
/// `limit_mm`: pairs whose bounding boxes are further apart than this are skipped, so the
/// result is exact when it is below `limit_mm` and otherwise only known to be ≥ `limit_mm`
/// (pass `f64::INFINITY` for the exact value).
pub fn clearance_mm(path: &[Point2<f64>], outline: &[Point2<f64>], limit_mm: f64) -> f64 {
    let n = outline.len();
    if path.is_empty() || n < 2 {
        return f64::INFINITY;
    }
    if point_in_ring_even_odd(path[0], outline) {
        return 0.0;
    }
    let mut best = limit_mm;
    for s in path.windows(2) {
        let (a, b) = (s[0], s[1]);
        let (lo_x, hi_x) = (a.x.min(b.x) - best, a.x.max(b.x) + best);
        let (lo_y, hi_y) = (a.y.min(b.y) - best, a.y.max(b.y) + best);
        for i in 0..n {
            let (c, d) = (outline[i], outline[(i + 1) % n]);
            if outside_box(c, d, [lo_x, hi_x, lo_y, hi_y]) {
                continue;
            }
            let dist = segment_distance(a, b, c, d, Norm::Sqrt);
            if dist < best {
                best = dist;
                if best == 0.0 {
                    return 0.0;
                }
            }
        }
    }
    best
}

/// True when the closed trajectory `path` keeps at least `min_clearance_mm` from the foil
/// `outline` and does not intersect it (T ∩ G = ∅, seed 000 §IV.C, with a margin).
pub fn is_feasible(path: &[Point2<f64>], outline: &[Point2<f64>], min_clearance_mm: f64) -> bool {
    let limit = min_clearance_mm.max(0.0);
    let c = clearance_mm(path, outline, limit.max(f64::MIN_POSITIVE));
    c >= limit && c > 0.0
}

/// The foil outline bucketed in a uniform grid, so that the feasibility test T ∩ G = ∅
/// (seed 000 §IV.C) of a path costs about O(path) instead of O(path × outline):
/// [`OutlineGrid::is_feasible`] gives exactly [`is_feasible`]'s answer. Hand-written (about 60
/// lines) because a general spatial index (e.g. an R-tree) costs more per query than this
/// needs: a few hundred short path segments per candidate, each touching one to four cells.
#[derive(Debug, Clone, PartialEq)]
pub struct OutlineGrid {
    outline: Vec<Point2<f64>>,
    /// Lower-left corner of cell (0, 0) and the cell size, mm.
    origin: Point2<f64>,
    cell: f64,
    nx: usize,
    ny: usize,
    /// Cell c holds outline segments `items[start[c]..start[c + 1]]` (segment i runs
    /// outline[i] → outline[i + 1], the last one closes the polygon).
    start: Vec<u32>,
    items: Vec<u32>,
}

impl OutlineGrid {
    /// Buckets the closed polygon `outline` (closing segment implied) in square cells of the
    /// mean segment length.
    pub fn new(outline: &[Point2<f64>]) -> Self {
        let n = outline.len();
        let (mut lo, mut hi) = (
            Point2::new(f64::INFINITY, f64::INFINITY),
            Point2::new(-f64::INFINITY, -f64::INFINITY),
        );
        for p in outline {
            lo = Point2::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = Point2::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        let seg = |i: usize| (outline[i], outline[(i + 1) % n]);
        let perimeter: f64 = (0..n).map(|i| (seg(i).1 - seg(i).0).norm()).sum();
        let extent = (hi.x - lo.x).max(hi.y - lo.y);
        let mut grid = Self {
            outline: outline.to_vec(),
            origin: lo,
            cell: 1.0,
            nx: 0,
            ny: 0,
            start: vec![0],
            items: Vec::new(),
        };
        if n < 2 || !(perimeter.is_finite() && extent.is_finite() && perimeter > 0.0) {
            return grid; // no cells: `is_feasible` falls back to the plain test.
        }
        // Mean segment length, but at most 4096 cells a side.
        grid.cell = (perimeter / n as f64).max(extent / 4096.0);
        grid.nx = ((hi.x - lo.x) / grid.cell).floor() as usize + 1;
        grid.ny = ((hi.y - lo.y) / grid.cell).floor() as usize + 1;
        let mut count = vec![0u32; grid.nx * grid.ny + 1];
        let cells_of = |g: &Self, i: usize| {
            let (c, d) = seg(i);
            g.cells(c.x.min(d.x), c.y.min(d.y), c.x.max(d.x), c.y.max(d.y))
        };
        for i in 0..n {
            if let Some((x0, y0, x1, y1)) = cells_of(&grid, i) {
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        count[y * grid.nx + x + 1] += 1;
                    }
                }
            }
        }
        for c in 1..count.len() {
            count[c] += count[c - 1];
        }
        let mut fill = count.clone();
        grid.items = vec![0; count[count.len() - 1] as usize];
        for i in 0..n {
            if let Some((x0, y0, x1, y1)) = cells_of(&grid, i) {
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let c = y * grid.nx + x;
                        grid.items[fill[c] as usize] = i as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        grid.start = count;
        grid
    }

    /// Inclusive cell ranges covering the box, clamped to the grid; `None` if they miss it.
    fn cells(&self, x0: f64, y0: f64, x1: f64, y1: f64) -> Option<(usize, usize, usize, usize)> {
        let fx = |x: f64| (x - self.origin.x) / self.cell;
        let fy = |y: f64| (y - self.origin.y) / self.cell;
        let (a, b, c, d) = (fx(x0), fy(y0), fx(x1), fy(y1));
        let (nx, ny) = (self.nx as f64, self.ny as f64);
        // NaN fails every comparison: treated as missing the grid.
        if !(c >= 0.0 && d >= 0.0 && a < nx && b < ny) {
            return None;
        }
        // `as usize` truncates, i.e. floors a value ≥ 0 (f64::floor is a libm call on x86-64).
        let clamp = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
        Some((
            clamp(a, self.nx),
            clamp(b, self.ny),
            clamp(c, self.nx),
            clamp(d, self.ny),
        ))
    }

    /// The outline as given.
    pub fn outline(&self) -> &[Point2<f64>] {
        &self.outline
    }

    /// Exactly [`is_feasible`]`(path, outline, min_clearance_mm)`, visiting only outline
    /// segments in the cells near each path segment.
    pub fn is_feasible(&self, path: &[Point2<f64>], min_clearance_mm: f64) -> bool {
        let outline = &self.outline;
        let n = outline.len();
        if self.nx == 0 {
            return is_feasible(path, outline, min_clearance_mm);
        }
        let limit = min_clearance_mm.max(0.0);
        let lim = limit.max(f64::MIN_POSITIVE);
        if path.is_empty() {
            return true;
        }
        if point_in_ring_even_odd(path[0], outline) {
            return false;
        }
        // The smallest distance below `lim` found so far (as `clearance_mm` with limit `lim`).
        let mut best = lim;
        for s in path.windows(2) {
            let (a, b) = (s[0], s[1]);
            let (lo_x, hi_x) = (a.x.min(b.x) - lim, a.x.max(b.x) + lim);
            let (lo_y, hi_y) = (a.y.min(b.y) - lim, a.y.max(b.y) + lim);
            let Some((x0, y0, x1, y1)) = self.cells(lo_x, lo_y, hi_x, hi_y) else {
                continue;
            };
            for y in y0..=y1 {
                let row = y * self.nx;
                let items =
                    &self.items[self.start[row + x0] as usize..self.start[row + x1 + 1] as usize];
                for &i in items {
                    let i = i as usize;
                    let (c, d) = (outline[i], outline[(i + 1) % n]);
                    if outside_box(c, d, [lo_x, hi_x, lo_y, hi_y]) {
                        continue;
                    }
                    // Most candidates are clearly further than `best`: a test without
                    // square roots or divisions rules them out first.
                    if !maybe_closer(a, b, c, d, best) {
                        continue;
                    }
                    let dist = segment_distance(a, b, c, d, Norm::Sqrt);
                    if dist < best {
                        best = dist;
                        if !(best >= limit && best > 0.0) {
                            return false;
                        }
                    }
                }
            }
        }
        best >= limit && best > 0.0
    }
}

/// False only when segments ab and cd certainly do not come closer than `limit` (> 0): they
/// do not cross, and every endpoint is at least `limit`·(1 + 1e-9) from the other segment
/// (squared distances, no square root or division). True otherwise, including when rounding
/// could matter: the caller then computes [`segment_distance`].
#[inline]
fn maybe_closer(
    a: Point2<f64>,
    b: Point2<f64>,
    c: Point2<f64>,
    d: Point2<f64>,
    limit: f64,
) -> bool {
    let l2 = limit * limit * (1.0 + 1e-9);
    // Is p within √l2 of segment qr?
    let near = |p: Point2<f64>, q: Point2<f64>, r: Point2<f64>| {
        let (qr, qp) = (r - q, p - q);
        let (dot, len2) = (qr.dot(&qp), qr.norm_squared());
        if dot <= 0.0 {
            qp.norm_squared() < l2
        } else if dot >= len2 {
            (p - r).norm_squared() < l2
        } else {
            let cross = qr.perp(&qp);
            cross * cross < l2 * len2
        }
    };
    let orient = |p: Point2<f64>, q: Point2<f64>, r: Point2<f64>| (q - p).perp(&(r - p));
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    (d1 * d2 <= 0.0 && d3 * d4 <= 0.0)
        || near(a, c, d)
        || near(b, c, d)
        || near(c, a, b)
        || near(d, a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::airfoil::test_foil as foil;

    #[test]
    fn bspline_partition_of_unity_and_periodicity() {
        let c = [1.0; 7];
        for k in 0..50 {
            let u = k as f64 / 50.0;
            assert!((periodic_cubic_bspline(&c, u) - 1.0).abs() < 1e-12);
        }
        let c: Vec<f64> = (0..8).map(|i| (i as f64).sin()).collect();
        let (a, b) = (
            periodic_cubic_bspline(&c, 0.0),
            periodic_cubic_bspline(&c, 1.0),
        );
        assert!((a - b).abs() < 1e-12);
        // At a knot the value is (c_{k−1} + 4 c_k + c_{k+1}) / 6.
        let v = periodic_cubic_bspline(&c, 3.0 / 8.0);
        assert!((v - (c[2] + 4.0 * c[3] + c[4]) / 6.0).abs() < 1e-12);
        assert_eq!(periodic_cubic_bspline(&[], 0.3), 0.0);
    }

    #[test]
    fn baseline_starts_at_te_is_closed_and_clear() {
        for name in ["s1223", "clarky", "e387", "naca0012"] {
            let f = foil(name, 200.0);
            let b = Baseline::fixed_offset(&f, 0.5, 100).unwrap();
            let p = b.points();
            assert!((100..=130).contains(&p.len()), "{name}: {} points", p.len());
            assert_eq!(p.first(), p.last());
            assert!(
                nalgebra::distance(&p[0], &f.trailing_edge()) < 1.0,
                "{name}"
            );
            let c = clearance_mm(p, f.points(), f64::INFINITY);
            assert!(c > 0.3 && c <= 0.5 + 1e-9, "{name}: clearance {c}");
            // Outward normals: displacing by +0.2 mm increases the clearance.
            let t = Trajectory::new(b.clone(), 32).unwrap();
            let out = t.path(&[0.2; 32]);
            assert!(
                clearance_mm(&out, f.points(), f64::INFINITY) > c + 0.15,
                "{name}"
            );
            assert_eq!(t.path(&[0.0; 32]), p.to_vec());
        }
    }

    #[test]
    fn intersecting_path_is_infeasible() {
        let f = foil("clarky", 200.0);
        let b = Baseline::fixed_offset(&f, 0.5, 100).unwrap();
        let t = Trajectory::new(b, 32).unwrap();
        assert!(is_feasible(&t.path(&[0.0; 32]), f.points(), 0.1));
        // Pull one stretch 2 mm inwards: it crosses the surface.
        let mut c = [0.0; 32];
        c[10] = -2.0;
        let bad = t.path(&c);
        assert_eq!(clearance_mm(&bad, f.points(), f64::INFINITY), 0.0);
        assert!(!is_feasible(&bad, f.points(), 0.1));
        // 0.45 mm inwards everywhere: no crossing, but closer than 0.1 mm.
        let close = t.path(&[-0.45; 32]);
        assert!(!is_feasible(&close, f.points(), 0.1));
        // Entirely inside the foil: no crossing either, still infeasible.
        let inside: Vec<_> = f
            .points()
            .iter()
            .map(|p| nalgebra::center(p, &Point2::new(100.0, 2.0)))
            .collect();
        assert_eq!(clearance_mm(&inside, f.points(), f64::INFINITY), 0.0);
    }

    /// The grid test gives the plain test's answer on swarm-like candidates (normal
    /// displacements, many of them crossing or too close), on several foils and clearances.
    #[test]
    fn outline_grid_agrees_with_the_plain_feasibility_test() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let (mut feasible, mut infeasible) = (0, 0);
        for name in ["s1223", "clarky", "e387", "naca0012"] {
            let f = foil(name, 200.0);
            let grid = OutlineGrid::new(f.points());
            for m in [60, 300] {
                let t = Trajectory::new(Baseline::fixed_offset(&f, 0.5, m).unwrap(), 32).unwrap();
                for k in 0..100 {
                    let spread = [0.05, 0.3, 1.0, 4.0][k % 4];
                    let c: Vec<f64> = (0..32).map(|_| rng.random_range(-spread..spread)).collect();
                    let path = t.path(&c);
                    for clearance in [0.0, 0.1, 0.45, 2.0] {
                        let plain = is_feasible(&path, f.points(), clearance);
                        assert_eq!(grid.is_feasible(&path, clearance), plain, "{name} {k}");
                        if plain {
                            feasible += 1;
                        } else {
                            infeasible += 1;
                        }
                    }
                }
            }
        }
        assert!(
            feasible > 500 && infeasible > 500,
            "{feasible} {infeasible}"
        );
        // A path entirely inside, one far outside, a degenerate outline.
        let f = foil("clarky", 200.0);
        let grid = OutlineGrid::new(f.points());
        let inside: Vec<_> = f
            .points()
            .iter()
            .map(|p| nalgebra::center(p, &Point2::new(100.0, 2.0)))
            .collect();
        assert!(!grid.is_feasible(&inside, 0.1));
        let far: Vec<_> = f
            .points()
            .iter()
            .map(|p| p + Vector2::new(0.0, 500.0))
            .collect();
        assert!(grid.is_feasible(&far, 0.1));
        let one = OutlineGrid::new(&[Point2::new(0.0, 0.0)]);
        assert!(one.is_feasible(&far, 0.1));
    }

    #[test]
    fn bad_parameters_are_named() {
        let f = foil("e387", 100.0);
        let e = Baseline::fixed_offset(&f, -1.0, 50).unwrap_err();
        assert!(e.to_string().starts_with("offset_mm"), "{e}");
        let e = Baseline::fixed_offset(&f, 0.5, 3).unwrap_err();
        assert!(e.to_string().starts_with("m_points"), "{e}");
        let b = Baseline::fixed_offset(&f, 0.5, 50).unwrap();
        let e = Trajectory::new(b, 2).unwrap_err();
        assert!(e.to_string().starts_with("control_points"), "{e}");
        let e = Baseline::from_points(vec![Point2::new(f64::NAN, 0.0); 4]).unwrap_err();
        assert!(e.to_string().starts_with("points[0]"), "{e}");
    }
}
