//! Lead-ins and lead-outs (issue 19, item 3): the torch pierces on the scrap side and enters
//! the contour's cut path along a lead-in, and leaves it along a lead-out, so the pierce
//! crater and the exit mark never touch the part.
//!
//! Every cut path here goes round with the part on its right ([`crate::kerf`]), so the scrap
//! side is the left: the unit normal `n` is the tangent `t` turned +90°.
//!
//! **Lead-in** onto the entry point `E` of the cut path (tangent `t`, scrap normal `n`), of
//! length `L` (the pierce's distance from the cut path on a straight edge):
//! - `arc`: a quarter circle of radius `L` about `E + L·n`, from the pierce `E + L·n − L·t`,
//!   meeting the path tangentially at `E`;
//! - `line`: straight from `E + L·n`, square to the path;
//! - and, to get round an obstacle, a line from `E + L·(n − t)/√2`, at 45° from behind.
//!
//! **Small holes** (an inscribed diameter below `small_hole_diameter_mm`): the pierce is at the
//! hole's centre (the point farthest inside its cut path) and the lead-in is a half circle
//! from there to the nearest point of the path, meeting it tangentially.
//!
//! **Lead-out**: after the cut closes at `E`, an overcut of `overcut_mm` along the path, then
//! from there (`E'`, tangent `t'`) an arc of radius `lead_out_mm` about `E' + r·n'` turning
//! into the scrap (after an arc lead-in) or a line at 45° forwards into the scrap (after a
//! line lead-in), ending at `E' + r·(n' + t')` and `E' + r·(n' + t')/√2`.
//!
//! **Clearance.** A lead is accepted only if (1) every point of it lies on the sheet (waived
//! for a contour no lead on the sheet fits, e.g. a part on the edge of a sheet taken from the
//! parts' extent: an edge start, [`LeadFinder::off_sheet`]), (2) every
//! point but the one where it joins the path lies on the scrap side of its own drawn contour
//! (outside an outer contour, inside a hole), (3) no part of it comes closer to its own drawn
//! contour than the cut path does (half the kerf; it never cuts into its part), and (4) it keeps
//! `clearance_mm` from every other drawn contour (a full kerf: its own kerf then stays half a
//! kerf clear of the other contour's cut path), and, for a lead-in, (5) its pierce lies at least
//! half as far from the cut path as from the path's tangent where it enters (not across a
//! narrow hole, next to the far side's cut), (6) no farther from the cut path than `L` (an
//! arc entering just after a corner would put it farther: the line is taken instead; a small
//! hole wider than `2·L` is entered like any other), and (7) at least a kerf from its own drawn
//! contour, so the pierce crater stays off the part (a small hole's centre pierce is exempt:
//! it has no room). A lead that fails is tried again shorter
//! (¾, ½, ⅓, ¼ of its length), turned (the other shape, the 45° line), and at other entry
//! points along the contour; the first that passes is kept. A lead-out that fails is
//! shortened (½, ¼) and finally left out. [`Obstacles`] is the grid of drawn edges these
//! distances are measured against.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use cell_geometry::{closest_point_on_segment, point_in_ring_nonzero, segment_distance, Norm};
use cell_profiles::LeadShape;
use serde::{Deserialize, Serialize};

use crate::kerf::CHORD_TOL_MM;
use crate::problem::{distance, ContourRole, Point};

/// How a contour is entered and left from one pierce point (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Lead {
    /// From the pierce point (first) to the entry point on the cut path (last).
    pub lead_in: Vec<Point>,
    /// The cut path's edge the entry point lies on: from `points[entry_edge]` to the next.
    pub entry_edge: usize,
    /// From the entry point (first), once the cut has closed there: the overcut along the
    /// path, then the lead-out; the last point is where the tool leaves. Just `[entry]` when
    /// there is neither.
    pub lead_out: Vec<Point>,
}

impl Lead {
    /// The pierce point.
    pub fn pierce(&self) -> Point {
        self.lead_in[0]
    }

    /// The entry point on the cut path.
    pub fn entry(&self) -> Point {
        self.lead_in[self.lead_in.len() - 1]
    }

    /// Where the tool leaves the cut (end of the lead-out).
    pub fn exit(&self) -> Point {
        self.lead_out[self.lead_out.len() - 1]
    }

    /// Length of the lead-in path, mm.
    pub fn lead_in_length(&self) -> f64 {
        path_length(&self.lead_in)
    }
}

/// The closed cut path `points` from the entry point `entry` on edge `edge` once round and
/// back to it (points equal to the entry are not repeated).
pub fn loop_from_entry(points: &[Point], edge: usize, entry: Point) -> Vec<Point> {
    let n = points.len();
    let mut out = Vec::with_capacity(n + 2);
    out.push(entry);
    for k in 1..=n {
        let p = points[(edge + k) % n];
        if distance(p, *out.last().unwrap_or(&entry)) > 1e-12 && distance(p, entry) > 1e-12 {
            out.push(p);
        }
    }
    out.push(entry);
    out
}

/// The full path of a cut with its leads: lead-in, the loop round the cut path, lead-out.
pub fn lead_cut_path(points: &[Point], lead: &Lead) -> Vec<Point> {
    let mut path = lead.lead_in.clone();
    path.extend(
        loop_from_entry(points, lead.entry_edge, lead.entry())
            .into_iter()
            .skip(1),
    );
    path.extend(lead.lead_out.iter().skip(1));
    path
}

/// What the leads of one job look like (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeadParams {
    /// The lead-in's shape.
    pub shape: LeadShape,
    /// The lead-in's length `L`, mm.
    pub length_mm: f64,
    /// The lead-out's length, mm (0: none).
    pub lead_out_mm: f64,
    /// Cut on past the entry point along the path before the lead-out, mm.
    pub overcut_mm: f64,
    /// Holes with a smaller inscribed diameter get a centre pierce, mm (0: none).
    pub small_hole_diameter_mm: f64,
    /// How far the cut path lies from the drawn contour, mm (half the kerf; 0 when the
    /// controller compensates).
    pub path_offset_mm: f64,
    /// Least distance from a lead to any other drawn contour, mm.
    pub clearance_mm: f64,
    /// Least distance from a lead-in's pierce to its own drawn contour, mm (a kerf: the pierce
    /// crater is wider than the kerf, and must stay off the part in both compensation modes;
    /// a small hole's centre pierce is exempt, it has no room).
    pub pierce_clearance_mm: f64,
}

/// Grid index of the drawn contours' edges, for the clearance of leads (module docs).
#[derive(Debug, Clone)]
pub struct Obstacles<'a> {
    rings: &'a [Vec<Point>],
    sheet: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    /// Edges per cell, compressed: `edges[start[c]..start[c + 1]]` are `(ring, edge)`.
    start: Vec<u32>,
    edges: Vec<(u32, u32)>,
}

impl<'a> Obstacles<'a> {
    /// Indexes the edges of `rings` (every drawn contour of the sheet) in square cells of
    /// `cell_mm` over the sheet `[0, a] × [0, b]` (points off it fall in the border cells).
    pub fn new(rings: &'a [Vec<Point>], sheet: [f64; 2], cell_mm: f64) -> Self {
        let cell = cell_mm.max(1.0);
        let nx = ((sheet[0] / cell).ceil() as usize).clamp(1, 4096);
        let ny = ((sheet[1] / cell).ceil() as usize).clamp(1, 4096);
        let mut o = Obstacles {
            rings,
            sheet,
            cell,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            edges: Vec::new(),
        };
        // Two passes: count per cell, then fill (cells a sample every half cell touches; a
        // query widens its box by one cell, which covers the corners cut between samples).
        let mut count = vec![0u32; nx * ny];
        o.for_each_edge_cell(|c, _, _| count[c] += 1);
        for (c, &k) in count.iter().enumerate() {
            o.start[c + 1] = o.start[c] + k;
        }
        let mut fill = o.start[..nx * ny].to_vec();
        let mut edges = vec![(0u32, 0u32); o.start[nx * ny] as usize];
        o.for_each_edge_cell(|c, r, i| {
            edges[fill[c] as usize] = (r as u32, i as u32);
            fill[c] += 1;
        });
        o.edges = edges;
        o
    }

    fn cell_of(&self, p: Point) -> (usize, usize) {
        let f = |v: f64, n: usize| ((v / self.cell).floor().max(0.0) as usize).min(n - 1);
        (f(p[0], self.nx), f(p[1], self.ny))
    }

    fn for_each_edge_cell(&self, mut visit: impl FnMut(usize, usize, usize)) {
        for (r, ring) in self.rings.iter().enumerate() {
            let n = ring.len();
            for i in 0..n {
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                let steps = (distance(a, b) / (self.cell / 2.0)).ceil().max(1.0) as usize;
                let mut last = usize::MAX;
                for k in 0..=steps {
                    let f = k as f64 / steps as f64;
                    let (x, y) = self.cell_of([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]);
                    let c = y * self.nx + x;
                    if c != last {
                        visit(c, r, i);
                        last = c;
                    }
                }
            }
        }
    }

    /// The least distances from the polyline `path` to the edges of ring `own` and to those of
    /// every other ring, mm; a distance beyond `reach_mm` may come out as +∞ (edges whose
    /// bounding box lies farther from the path's are not measured).
    pub fn distances(&self, path: &[Point], own: usize, reach_mm: f64) -> (f64, f64) {
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for p in path {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let (x0, y0) = self.cell_of([lo[0] - reach_mm, lo[1] - reach_mm]);
        let (x1, y1) = self.cell_of([hi[0] + reach_mm, hi[1] + reach_mm]);
        let (x0, y0) = (x0.saturating_sub(1), y0.saturating_sub(1));
        let (x1, y1) = ((x1 + 1).min(self.nx - 1), (y1 + 1).min(self.ny - 1));
        let (mut own_d, mut other_d) = (f64::INFINITY, f64::INFINITY);
        // Boxes more than `reach` apart need no distance.
        let apart = |lo: [f64; 2], hi: [f64; 2], a: Point, b: Point| {
            a[0].min(b[0]) > hi[0] + reach_mm
                || a[0].max(b[0]) < lo[0] - reach_mm
                || a[1].min(b[1]) > hi[1] + reach_mm
                || a[1].max(b[1]) < lo[1] - reach_mm
        };
        for y in y0..=y1 {
            for x in x0..=x1 {
                let c = y * self.nx + x;
                for &(r, i) in &self.edges[self.start[c] as usize..self.start[c + 1] as usize] {
                    let ring = &self.rings[r as usize];
                    let (a, b) = (ring[i as usize], ring[(i as usize + 1) % ring.len()]);
                    if apart(lo, hi, a, b) {
                        continue;
                    }
                    let (elo, ehi) = (
                        [a[0].min(b[0]), a[1].min(b[1])],
                        [a[0].max(b[0]), a[1].max(b[1])],
                    );
                    let d = path
                        .windows(2)
                        .filter(|w| !apart(elo, ehi, w[0], w[1]))
                        .map(|w| segment_distance(w[0], w[1], a, b, Norm::Sqrt))
                        .fold(f64::INFINITY, f64::min);
                    if r as usize == own {
                        own_d = own_d.min(d);
                    } else {
                        other_d = other_d.min(d);
                    }
                }
            }
        }
        (own_d, other_d)
    }

    /// Whether every point of `path` lies on the sheet.
    fn on_sheet(&self, path: &[Point]) -> bool {
        let eps = 1e-9;
        path.iter().all(|p| {
            (-eps..=self.sheet[0] + eps).contains(&p[0])
                && (-eps..=self.sheet[1] + eps).contains(&p[1])
        })
    }
}

/// One contour to lead into: its drawn ring (index `ring` in the [`Obstacles`]), its role and
/// its cut path (part on the right).
#[derive(Debug, Clone, Copy)]
pub struct LeadTarget<'a> {
    /// Index of the drawn ring in the obstacles.
    pub ring: usize,
    /// Outer contour or hole.
    pub role: ContourRole,
    /// The cut path, part on the right.
    pub path: &'a [Point],
}

/// How the leads of one contour came out.
#[derive(Debug, Clone, PartialEq)]
pub struct ContourLeads {
    /// One lead per pierce candidate.
    pub leads: Vec<Lead>,
    /// Whether the (single) lead is a small hole's centre pierce.
    pub centre_pierce: bool,
}

/// A closed path with its cumulative arc lengths.
struct Walk<'a> {
    pts: &'a [Point],
    at: Vec<f64>,
    total: f64,
}

impl<'a> Walk<'a> {
    fn new(pts: &'a [Point]) -> Self {
        let n = pts.len();
        let mut at = Vec::with_capacity(n + 1);
        at.push(0.0);
        for i in 0..n {
            at.push(at[i] + distance(pts[i], pts[(i + 1) % n]));
        }
        let total = at[n];
        Walk { pts, at, total }
    }

    /// The edge, point and unit tangent at arc length `s` (taken modulo the length).
    fn at_length(&self, s: f64) -> (usize, Point, Point) {
        let n = self.pts.len();
        let s = if self.total > 0.0 {
            s.rem_euclid(self.total)
        } else {
            0.0
        };
        let i = match self.at[..n].binary_search_by(|v| v.total_cmp(&s)) {
            Ok(i) => i,
            Err(i) => i.saturating_sub(1),
        };
        let (a, b) = (self.pts[i], self.pts[(i + 1) % n]);
        let len = self.at[i + 1] - self.at[i];
        let f = if len > 0.0 {
            (s - self.at[i]) / len
        } else {
            0.0
        };
        let p = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
        (i, p, unit([b[0] - a[0], b[1] - a[1]]))
    }

    /// The arc length of the path point nearest `q`.
    fn project(&self, q: Point) -> f64 {
        let n = self.pts.len();
        let mut best = (f64::INFINITY, 0.0);
        for i in 0..n {
            let (a, b) = (self.pts[i], self.pts[(i + 1) % n]);
            let c: Point = closest_point_on_segment(q, a, b).into();
            let d = distance(c, q);
            if d < best.0 {
                best = (d, self.at[i] + distance(a, c));
            }
        }
        best.1
    }

    /// The path from arc length `s` forwards by `len` (first point at `s`).
    fn forward(&self, s: f64, len: f64) -> Vec<Point> {
        let (i, p, _) = self.at_length(s);
        let mut out = vec![p];
        let n = self.pts.len();
        let mut left = len.min(self.total);
        let mut at = p;
        let mut k = i;
        while left > 1e-12 {
            let next = self.pts[(k + 1) % n];
            let d = distance(at, next);
            if d >= left {
                let f = left / d;
                out.push([at[0] + f * (next[0] - at[0]), at[1] + f * (next[1] - at[1])]);
                break;
            }
            if d > 0.0 {
                out.push(next);
            }
            left -= d;
            at = next;
            k = (k + 1) % n;
        }
        out
    }
}

fn unit(v: Point) -> Point {
    let l = v[0].hypot(v[1]);
    if l > 0.0 {
        [v[0] / l, v[1] / l]
    } else {
        [1.0, 0.0]
    }
}

fn add(p: Point, v: Point, f: f64) -> Point {
    [p[0] + f * v[0], p[1] + f * v[1]]
}

fn left(t: Point) -> Point {
    [-t[1], t[0]]
}

fn path_length(path: &[Point]) -> f64 {
    path.windows(2).map(|w| distance(w[0], w[1])).sum()
}

/// Points of the arc about `c` of radius `r` from angle `a0` turning by `sweep` (signed,
/// counter-clockwise positive), chords within [`CHORD_TOL_MM`] of it, both ends included.
fn arc(c: Point, r: f64, a0: f64, sweep: f64) -> Vec<Point> {
    let step = if r > CHORD_TOL_MM {
        2.0 * (1.0 - CHORD_TOL_MM / r).acos()
    } else {
        PI
    };
    let n = (sweep.abs() / step).ceil().max(1.0) as usize;
    (0..=n)
        .map(|k| {
            let a = a0 + sweep * k as f64 / n as f64;
            [c[0] + r * a.cos(), c[1] + r * a.sin()]
        })
        .collect()
}

/// The lead-in shapes tried (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum InShape {
    Arc,
    Line,
    Angled,
}

fn lead_in_path(shape: InShape, e: Point, t: Point, len: f64) -> Vec<Point> {
    let n = left(t);
    let mut path = match shape {
        InShape::Arc => {
            let c = add(e, n, len);
            let a_e = (-n[1]).atan2(-n[0]);
            arc(c, len, a_e - PI / 2.0, PI / 2.0)
        }
        InShape::Line => vec![add(e, n, len), e],
        InShape::Angled => vec![add(e, [n[0] - t[0], n[1] - t[1]], len * FRAC_1_SQRT_2), e],
    };
    let last = path.len() - 1;
    path[last] = e;
    path
}

fn lead_out_path(arc_shape: bool, e: Point, t: Point, len: f64) -> Vec<Point> {
    let n = left(t);
    let mut path = if arc_shape {
        let c = add(e, n, len);
        let a_e = (-n[1]).atan2(-n[0]);
        arc(c, len, a_e, PI / 2.0)
    } else {
        vec![e, add(e, [n[0] + t[0], n[1] + t[1]], len * FRAC_1_SQRT_2)]
    };
    path[0] = e;
    path
}

/// The half circle from `o` to `e` whose tangent at `e` runs along `t`.
fn half_circle(o: Point, e: Point, t: Point) -> Vec<Point> {
    let c = [(o[0] + e[0]) / 2.0, (o[1] + e[1]) / 2.0];
    let r = distance(o, e) / 2.0;
    let a_o = (o[1] - c[1]).atan2(o[0] - c[0]);
    // Counter-clockwise if the centre lies left of the direction at e.
    let ce = [c[0] - e[0], c[1] - e[1]];
    let ccw = t[0] * ce[1] - t[1] * ce[0] > 0.0;
    let mut path = arc(c, r, a_o, if ccw { PI } else { -PI });
    path[0] = o;
    let last = path.len() - 1;
    path[last] = e;
    path
}

/// The point farthest inside the closed path (its pole) and that distance (the inscribed
/// circle's radius), by a grid search refined five times.
pub fn pole(path: &[Point]) -> (Point, f64) {
    let n = path.len();
    let signed = |p: Point| {
        let d = (0..n)
            .map(|i| {
                cell_geometry::point_segment_distance(p, path[i], path[(i + 1) % n], Norm::Sqrt)
            })
            .fold(f64::INFINITY, f64::min);
        if point_in_ring_nonzero(p, path) {
            d
        } else {
            -d
        }
    };
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for p in path {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let mut best = (
        [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0],
        f64::NEG_INFINITY,
    );
    best.1 = signed(best.0);
    let grid = 8;
    let mut step = [(hi[0] - lo[0]) / grid as f64, (hi[1] - lo[1]) / grid as f64];
    for j in 0..grid {
        for i in 0..grid {
            let p = [
                lo[0] + (i as f64 + 0.5) * step[0],
                lo[1] + (j as f64 + 0.5) * step[1],
            ];
            let d = signed(p);
            if d > best.1 {
                best = (p, d);
            }
        }
    }
    for _ in 0..6 {
        step = [step[0] / 2.0, step[1] / 2.0];
        let centre = best.0;
        for j in -2..=2 {
            for i in -2..=2 {
                let p = [
                    centre[0] + i as f64 * step[0] / 2.0,
                    centre[1] + j as f64 * step[1] / 2.0,
                ];
                let d = signed(p);
                if d > best.1 {
                    best = (p, d);
                }
            }
        }
    }
    best
}

/// Lead finder for one job: the obstacles, the parameters and the sheet.
pub struct LeadFinder<'a> {
    /// The drawn contours.
    pub obstacles: &'a Obstacles<'a>,
    /// Lead shapes and clearances.
    pub params: LeadParams,
    /// Whether a lead may leave the sheet (rule 1 waived): for a part on the sheet's edge
    /// that no lead on the sheet fits, an edge start.
    pub off_sheet: bool,
}

/// Fractions of the lead length tried, longest first (module docs).
const SHORTER: [f64; 5] = [1.0, 0.75, 0.5, 1.0 / 3.0, 0.25];

/// Entry points tried evenly round a contour when none of the preferred ones takes a lead.
const FALLBACK_ENTRIES: usize = 32;

impl LeadFinder<'_> {
    /// Whether `path` (a lead joining the cut path at its first or last point) is clear
    /// (module docs, rules 1–4).
    fn clear(
        &self,
        target: &LeadTarget,
        nominal: &[Point],
        path: &[Point],
        join_last: bool,
    ) -> bool {
        if path.len() < 2 || !(self.off_sheet || self.obstacles.on_sheet(path)) {
            return false;
        }
        let free = if join_last {
            &path[..path.len() - 1]
        } else {
            &path[1..]
        };
        let want_inside = target.role == ContourRole::Hole;
        if free
            .iter()
            .any(|&p| point_in_ring_nonzero(p, nominal) != want_inside)
        {
            return false;
        }
        let p = &self.params;
        let reach = p.clearance_mm.max(p.path_offset_mm);
        let (own, other) = self.obstacles.distances(path, target.ring, reach);
        let own_ok = if p.path_offset_mm > 0.0 {
            // Flattened corner arcs of the cut path lie up to the chord tolerance closer.
            own >= p.path_offset_mm - CHORD_TOL_MM - 1e-6
        } else {
            // On the drawn contour itself: only the joining segment may touch it.
            let inner = if join_last {
                &path[..path.len() - 1]
            } else {
                &path[1..]
            };
            inner.len() < 2 || self.obstacles.distances(inner, target.ring, 0.0).0 > 0.0
        };
        own_ok && other >= p.clearance_mm && other > 0.0
    }

    /// Rule 7 (module docs): the pierce lies at least [`LeadParams::pierce_clearance_mm`]
    /// from its own drawn contour.
    fn pierce_off_part(&self, nominal: &[Point], lead_in: &[Point]) -> bool {
        cell_geometry::distance_to_rings(lead_in[0], std::slice::from_ref(&nominal), Norm::Hypot)
            >= self.params.pierce_clearance_mm - 1e-9
    }

    /// Rules 5 and 6 (module docs): the pierce of `lead_in`, entering the path at its end
    /// along `t`, lies at least half its reach from the path (the reach: how far it lies off
    /// the path's tangent there), so it is not across a narrow hole from where it enters; and
    /// no farther from the path than the lead-in length.
    fn faces_entry(&self, target: &LeadTarget, lead_in: &[Point], t: Point) -> bool {
        let (s, e) = (lead_in[0], lead_in[lead_in.len() - 1]);
        let n = left(t);
        let reach = (s[0] - e[0]) * n[0] + (s[1] - e[1]) * n[1];
        let to_path =
            cell_geometry::distance_to_rings(s, std::slice::from_ref(&target.path), Norm::Hypot);
        to_path >= 0.5 * reach - 1e-9 && to_path <= self.params.length_mm + 1e-9
    }

    /// A lead-out after the entry at arc length `s`: overcut, then the longest clear lead-out
    /// (module docs); `[entry]` when there is neither.
    fn lead_out(
        &self,
        target: &LeadTarget,
        nominal: &[Point],
        walk: &Walk,
        s: f64,
        arc_shape: bool,
        cap: f64,
    ) -> Vec<Point> {
        let p = &self.params;
        let mut out = walk.forward(s, p.overcut_mm);
        let end = *out.last().unwrap_or(&walk.pts[0]);
        let (_, _, t) = walk.at_length(s + p.overcut_mm.min(walk.total));
        let len = p.lead_out_mm.min(cap);
        if len > 0.0 {
            for f in [1.0, 0.5, 0.25] {
                for shape in [arc_shape, !arc_shape] {
                    let lo = lead_out_path(shape, end, t, len * f);
                    if self.clear(target, nominal, &lo, false) {
                        out.extend(lo.into_iter().skip(1));
                        return out;
                    }
                }
            }
        }
        out
    }

    /// The first clear lead-in at arc length `s` (module docs), longest first, at most `cap`
    /// long, with its lead-out.
    fn lead_at(
        &self,
        target: &LeadTarget,
        nominal: &[Point],
        walk: &Walk,
        s: f64,
        cap: f64,
    ) -> Option<Lead> {
        let p = &self.params;
        let (edge, e, t) = walk.at_length(s);
        let preferred = match p.shape {
            LeadShape::Arc => [InShape::Arc, InShape::Line, InShape::Angled],
            LeadShape::Line => [InShape::Line, InShape::Arc, InShape::Angled],
        };
        let full = p.length_mm.min(cap);
        if full <= 0.0 {
            return None;
        }
        for f in SHORTER {
            for shape in preferred {
                let lead_in = lead_in_path(shape, e, t, full * f);
                if self.clear(target, nominal, &lead_in, true)
                    && self.faces_entry(target, &lead_in, t)
                    && self.pierce_off_part(nominal, &lead_in)
                {
                    let arc_shape = shape == InShape::Arc;
                    let lead_out = self.lead_out(target, nominal, walk, s, arc_shape, cap);
                    return Some(Lead {
                        lead_in,
                        entry_edge: edge,
                        lead_out,
                    });
                }
            }
        }
        None
    }

    /// The leads of one contour (module docs): a small hole's centre pierce if it fits, else a
    /// clear lead at each of the `entries` (points near the cut path, e.g. the corner-avoiding
    /// pierce candidates of the drawn contour) that takes one, else at the first of
    /// `FALLBACK_ENTRIES` even entries round the contour that does. `nominal` is the drawn
    /// ring.
    ///
    /// # Errors
    /// No lead fits anywhere: the reason, for the message naming the contour.
    pub fn contour_leads(
        &self,
        target: &LeadTarget,
        nominal: &[Point],
        entries: &[Point],
    ) -> Result<ContourLeads, String> {
        let p = &self.params;
        let walk = Walk::new(target.path);
        if target.path.len() < 3 || walk.total <= 0.0 {
            return Err("the cut path is degenerate".into());
        }
        let mut cap = f64::INFINITY;
        if target.role == ContourRole::Hole && p.small_hole_diameter_mm > 0.0 {
            let (o, r) = pole(target.path);
            if 2.0 * (r + p.path_offset_mm) < p.small_hole_diameter_mm && r > 0.0 {
                let s = walk.project(o);
                let (edge, e, t) = walk.at_length(s);
                let lead_in = half_circle(o, e, t);
                if self.clear(target, nominal, &lead_in, true)
                    && self.faces_entry(target, &lead_in, t)
                {
                    let lead_out = self.lead_out(target, nominal, &walk, s, true, r / 2.0);
                    return Ok(ContourLeads {
                        leads: vec![Lead {
                            lead_in,
                            entry_edge: edge,
                            lead_out,
                        }],
                        centre_pierce: true,
                    });
                }
                // An island in the way: ordinary leads, no longer than the hole allows.
                cap = r;
            }
        }
        let leads: Vec<Lead> = entries
            .iter()
            .filter_map(|&q| self.lead_at(target, nominal, &walk, walk.project(q), cap))
            .collect();
        if !leads.is_empty() {
            return Ok(ContourLeads {
                leads,
                centre_pierce: false,
            });
        }
        let want = entries.len().max(1);
        let leads: Vec<Lead> = (0..FALLBACK_ENTRIES)
            .filter_map(|j| {
                let s = (j as f64 + 0.5) * walk.total / FALLBACK_ENTRIES as f64;
                self.lead_at(target, nominal, &walk, s, cap)
            })
            .take(want)
            .collect();
        if leads.is_empty() {
            Err(format!(
                "no lead-in of at least {:.3} mm fits anywhere round it on the scrap side \
                 ({:.3} mm clear of the other contours)",
                p.length_mm * SHORTER[SHORTER.len() - 1],
                p.clearance_mm
            ))
        } else {
            Ok(ContourLeads {
                leads,
                centre_pierce: false,
            })
        }
    }

    /// The lead of a fixed pierce point `pierce` (the layout's `P_ij`): a straight lead-in
    /// from it to the nearest point of the cut path, or, when it lies on the drawn contour
    /// (within the cut path's offset), an ordinary lead entering there.
    ///
    /// # Errors
    /// Its lead-in is not clear (module docs): the reason.
    pub fn fixed_lead(
        &self,
        target: &LeadTarget,
        nominal: &[Point],
        pierce: Point,
    ) -> Result<Lead, String> {
        let walk = Walk::new(target.path);
        let s = walk.project(pierce);
        let (edge, e, _) = walk.at_length(s);
        let on_contour =
            cell_geometry::distance_to_rings(pierce, std::slice::from_ref(&nominal), Norm::Hypot)
                <= self.params.path_offset_mm + 1e-3;
        if on_contour {
            return self
                .lead_at(target, nominal, &walk, s, f64::INFINITY)
                .ok_or_else(|| "no lead-in fits at the fixed pierce point".to_string());
        }
        let lead_in = vec![pierce, e];
        if !self.clear(target, nominal, &lead_in, true) {
            return Err(format!(
                "the lead-in from the fixed pierce point cuts into its part or comes within \
                 {:.3} mm of another contour",
                self.params.clearance_mm
            ));
        }
        let arc_shape = self.params.shape == LeadShape::Arc;
        let lead_out = self.lead_out(target, nominal, &walk, s, arc_shape, f64::INFINITY);
        Ok(Lead {
            lead_in,
            entry_edge: edge,
            lead_out,
        })
    }
}

#[cfg(test)]
mod tests;
