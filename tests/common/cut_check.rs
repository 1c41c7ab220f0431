//! The sheet acceptance check (issue 19): what a program cuts ([`crate::gcode_reader`])
//! against the layout it was made from ([`Reference`]), with the kerf and lead-in of the
//! profile ([`CutParams`]). Shares no code with the emitter or with the sequencer's kerf
//! offset and lead-ins; geometry from [`crate::plane`].
//!
//! Each cut (one heat-on run) is matched to the contour most of its length runs nearest to.
//! The cut's *contour part* runs from its first to its last point within the tolerance of the
//! expected offset `e` (half the kerf when the program offsets the path, 0 when the
//! controller does with G41/G42); before it is the lead-in (from the pierce), after it the
//! lead-out. The checks, each a [`Check`]:
//!
//! - **count**: every contour cut exactly once (a hole too small for the kerf may be left out
//!   when the profile says to skip such holes); every cut follows a contour.
//! - **offset**: every move of the contour part lies `e ± tol` from the nominal contour
//!   (`tol` = [`PATH_TOL_MM`] plus [`ROUNDING_MM`] for the program's 3 decimals): its exact
//!   closest approach (segment to segment) and its farthest point (bounded edge by edge by the
//!   farther of the move's two ends, the move halved where that bound is not tight enough)
//!   both within the band. Arcs are checked through their samples, which lie on the arc.
//! - **side**: the contour part lies on the scrap side (outside an outer contour, inside a
//!   hole); with G41/G42, the compensation side points to the scrap.
//! - **coverage**: the offset contour is traversed whole: for sample points `q` along every
//!   nominal edge (at most [`COVERAGE_STEP_MM`] apart, and at the round joins of convex
//!   corners), `q + e·n` (n the scrap-side normal) is within tolerance (plus the arc
//!   sampling) of the contour part, unless that point is closer than `e` to another stretch of
//!   the contour (past a mitred corner, in a concave corner or a narrow neck, where the true
//!   offset does not pass); and the contour part is no longer than one turn plus the overcut.
//! - **pierce**: on the scrap side, at least one kerf from its contour (the crater stays off
//!   the part), and in no part's material.
//! - **lead length**: the lead-in reaches at most the profile's lead-in length `L` from the
//!   path: the pierce within `√2·L` of where the lead-in meets the cut path (the chord of a
//!   tangent quarter-circle of radius `L`; a straight lead gives `L`) and the lead-in no
//!   longer than that quarter circle, the lead-out likewise; and the pierce at least `L/2`
//!   from the cut path. A small hole (inscribed diameter under the profile's
//!   `small_hole_diameter_mm`) may instead be pierced near its centre, whatever the distance
//!   to the path; a lead-in may be shorter where another contour lies within `L` of the entry.
//! - **lead clearance**: no lead-in or lead-out crosses or comes within half a kerf of another
//!   contour, nor cuts into its own part.
//! - **precedence** (strict): every hole before its part's outer contour; a part lying in a
//!   hole of another part before any hole of that part; each part's contours one after
//!   another.
//! - **heat-on rapid**: no G0 with the heat on.
//! - **drawing**: points of the drawing (DXF vertices, circle quadrants) lie on the reference
//!   contours, so the program cuts where the drawing says.
#![allow(dead_code)] // each test binary uses a different subset

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::gcode_reader::{Compensation, HeatRun, Program, ARC_SAMPLING_MM};
use crate::plane::{
    add, bbox, dist, inscribed_radius, point_in_ring, point_segment, right_of, ring_distance,
    ring_perimeter, scale, segment_segment, signed_area2, sub, unit, SegmentGrid, P,
};

/// How far the cut path may stray from the nominal contour offset by half the kerf (issue 19).
pub const PATH_TOL_MM: f64 = 0.02;

/// Coordinates in the program are rounded (3 decimals: 0.0005 mm per axis).
pub const ROUNDING_MM: f64 = 0.001;

/// Largest spacing of the coverage samples along a nominal edge.
pub const COVERAGE_STEP_MM: f64 = 1.0;

/// How close a drawing point must be to a reference contour.
pub const DRAWING_TOL_MM: f64 = 0.005;

/// What a contour is to its part.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    Outer,
    Hole,
}

/// One nominal contour of the layout.
#[derive(Debug, Clone, PartialEq)]
pub struct RefContour {
    /// `parts[i] (name).outer` or `parts[i] (name).holes[h]`.
    pub name: String,
    pub part: usize,
    pub role: Role,
    /// Closed, first point not repeated.
    pub ring: Vec<P>,
}

/// The layout the program was made from: every contour, part by part (outer, then holes).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Reference {
    pub contours: Vec<RefContour>,
}

/// One part: name, outer ring, holes.
pub type RefPart = (Option<String>, Vec<P>, Vec<Vec<P>>);

impl Reference {
    /// From parts (outer ring and holes each).
    pub fn from_parts(parts: Vec<RefPart>) -> Self {
        let mut contours = Vec::new();
        for (i, (name, outer, holes)) in parts.into_iter().enumerate() {
            let label = match &name {
                Some(n) => format!("parts[{i}] ({n})"),
                None => format!("parts[{i}]"),
            };
            contours.push(RefContour {
                name: format!("{label}.outer"),
                part: i,
                role: Role::Outer,
                ring: open_ring(outer),
            });
            for (h, ring) in holes.into_iter().enumerate() {
                contours.push(RefContour {
                    name: format!("{label}.holes[{h}]"),
                    part: i,
                    role: Role::Hole,
                    ring: open_ring(ring),
                });
            }
        }
        Reference { contours }
    }

    /// From the JSON layout format (read here with serde_json, not through the sequencer), in
    /// machine coordinates: each point plus the layout's `origin` (the sheet's corner on the
    /// machine, 0, 0 when absent).
    pub fn from_layout_json(text: &str) -> Result<Self, String> {
        let v: serde_json::Value = serde_json::from_str(text).map_err(|e| e.to_string())?;
        let origin = match v.get("origin") {
            Some(o) => [
                o[0].as_f64().ok_or("origin is not [x, y]")?,
                o[1].as_f64().ok_or("origin is not [x, y]")?,
            ],
            None => [0.0, 0.0],
        };
        let ring = |r: &serde_json::Value| -> Result<Vec<P>, String> {
            r["points"]
                .as_array()
                .ok_or("a ring without points")?
                .iter()
                .map(|p| match (p[0].as_f64(), p[1].as_f64()) {
                    (Some(x), Some(y)) => Ok([x + origin[0], y + origin[1]]),
                    _ => Err(format!("point {p} is not [x, y]")),
                })
                .collect()
        };
        let mut parts = Vec::new();
        for part in v["parts"].as_array().ok_or("no parts")? {
            let holes = match part.get("holes").and_then(|h| h.as_array()) {
                Some(hs) => hs.iter().map(ring).collect::<Result<_, _>>()?,
                None => Vec::new(),
            };
            parts.push((
                part.get("name").and_then(|n| n.as_str()).map(str::to_owned),
                ring(&part["outer"])?,
                holes,
            ));
        }
        Ok(Self::from_parts(parts))
    }

    fn parts(&self) -> usize {
        self.contours.iter().map(|c| c.part + 1).max().unwrap_or(0)
    }
}

fn open_ring(mut ring: Vec<P>) -> Vec<P> {
    if ring.len() > 1 && ring.first() == ring.last() {
        ring.pop();
    }
    ring
}

/// The cutting parameters the program was made with (from the machine profile).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutParams {
    pub kerf_mm: f64,
    pub lead_in_mm: f64,
    pub lead_out_mm: f64,
    pub overcut_mm: f64,
    pub small_hole_diameter_mm: f64,
    pub skip_too_small_holes: bool,
    /// G41/G42 in the controller instead of an offset path.
    pub controller_compensation: bool,
}

/// The kinds of finding (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Check {
    Count,
    Offset,
    Side,
    Coverage,
    Pierce,
    LeadLength,
    LeadClearance,
    Precedence,
    HeatOnRapid,
    Drawing,
}

/// One thing wrong with the program.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    pub check: Check,
    pub message: String,
}

/// What the check found, with a few figures of the program.
#[derive(Debug, Clone, Default)]
pub struct Report {
    pub findings: Vec<Finding>,
    /// Heat-on runs read.
    pub runs: usize,
    /// Runs matched to a contour.
    pub matched: usize,
    /// Holes left out as too small (allowed by the profile).
    pub skipped: Vec<String>,
    /// Lead-in lengths of the checked cuts, mm.
    pub lead_in_mm: Vec<f64>,
}

impl Report {
    pub fn count(&self, check: Check) -> usize {
        self.findings.iter().filter(|f| f.check == check).count()
    }

    pub fn is_clean(&self) -> bool {
        self.findings.is_empty()
    }

    /// Findings per check, the first few of each spelt out.
    pub fn summary(&self) -> String {
        let mut by: BTreeMap<Check, Vec<&str>> = BTreeMap::new();
        for f in &self.findings {
            by.entry(f.check).or_default().push(&f.message);
        }
        let mut s = format!(
            "{} findings ({} cuts read, {} matched, {} holes skipped as too small)",
            self.findings.len(),
            self.runs,
            self.matched,
            self.skipped.len()
        );
        for (check, messages) in by {
            let _ = write!(s, "\n  {check:?} ({}):", messages.len());
            for m in messages.iter().take(3) {
                let _ = write!(s, "\n    - {m}");
            }
            if messages.len() > 3 {
                let _ = write!(s, "\n    - … and {} more", messages.len() - 3);
            }
        }
        s
    }

    fn add(&mut self, check: Check, message: String) {
        self.findings.push(Finding { check, message });
    }
}

/// The reference contours in a grid, with what the checks ask of them.
struct Sheet<'a> {
    reference: &'a Reference,
    grid: SegmentGrid,
    boxes: Vec<[P; 2]>,
    /// Ring orientation: true if counter-clockwise.
    ccw: Vec<bool>,
}

impl<'a> Sheet<'a> {
    fn new(reference: &'a Reference) -> Self {
        let mut grid = SegmentGrid::new(4.0);
        for (c, rc) in reference.contours.iter().enumerate() {
            grid.insert_ring(&rc.ring, c as u32);
        }
        Sheet {
            reference,
            grid,
            boxes: reference.contours.iter().map(|c| bbox(&c.ring)).collect(),
            ccw: reference
                .contours
                .iter()
                .map(|c| signed_area2(&c.ring) > 0.0)
                .collect(),
        }
    }

    fn name(&self, c: usize) -> &str {
        &self.reference.contours[c].name
    }

    /// The nearest contour to `p` within `r`, and its distance.
    fn nearest(&self, p: P, r: f64, scratch: &mut Vec<u32>) -> Option<(usize, f64)> {
        self.grid.near(p, p, r, scratch);
        scratch
            .iter()
            .map(|&i| self.grid.segments[i as usize])
            .map(|(a, b, tag)| (tag as usize, point_segment(p, a, b)))
            .filter(|&(_, d)| d <= r)
            .min_by(|x, y| x.1.total_cmp(&y.1))
    }

    /// Closest approach of the move `a`–`b` to contour `c` (exact), and its farthest point's
    /// distance from the contour (an upper bound within `limit`, else a value above `limit`
    /// that some point of the move reaches or nearly reaches), looking within `r`.
    ///
    /// Each edge's distance is convex along the move, so the farther end bounds it; the
    /// contour's distance is the least of them, so the least of those bounds bounds it. Where
    /// that bound exceeds `limit` (ends nearest to different edges), the move is halved until
    /// the bound holds or a point is found beyond `limit`.
    fn move_bounds(
        &self,
        c: usize,
        a: P,
        b: P,
        r: f64,
        limit: f64,
        scratch: &mut Vec<u32>,
    ) -> (f64, f64) {
        self.grid.near(a, b, r, scratch);
        let edges: Vec<(P, P)> = scratch
            .iter()
            .map(|&i| self.grid.segments[i as usize])
            .filter(|s| s.2 as usize == c)
            .map(|(p, q, _)| (p, q))
            .collect();
        let lower = edges
            .iter()
            .map(|&(p, q)| segment_segment(a, b, p, q))
            .fold(r, f64::min);
        (lower, farthest(&edges, a, b, limit, 24))
    }

    /// True if `p` lies in some part's material (inside an outer contour, in none of its holes).
    fn in_material(&self, p: P) -> Option<usize> {
        let inside = |c: usize| {
            let [lo, hi] = self.boxes[c];
            p[0] >= lo[0]
                && p[0] <= hi[0]
                && p[1] >= lo[1]
                && p[1] <= hi[1]
                && point_in_ring(p, &self.reference.contours[c].ring)
        };
        let contours = &self.reference.contours;
        (0..contours.len())
            .filter(|&c| contours[c].role == Role::Outer && inside(c))
            .find(|&o| {
                !(0..contours.len()).any(|h| {
                    contours[h].role == Role::Hole
                        && contours[h].part == contours[o].part
                        && inside(h)
                })
            })
            .map(|o| contours[o].part)
    }

    /// The scrap-side unit normal of edge `i` of contour `c`.
    fn scrap_normal(&self, c: usize, i: usize) -> P {
        let ring = &self.reference.contours[c].ring;
        let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
        let right = right_of(unit(sub(b, a)));
        // Right of a counter-clockwise ring's edge is outside it.
        let outward = if self.ccw[c] {
            right
        } else {
            scale(right, -1.0)
        };
        match self.reference.contours[c].role {
            Role::Outer => outward,
            Role::Hole => scale(outward, -1.0),
        }
    }
}

/// The farthest distance of the move `a`–`b` from the polyline `edges` (see
/// [`Sheet::move_bounds`]), refined by halving at most `depth` times.
fn farthest(edges: &[(P, P)], a: P, b: P, limit: f64, depth: u32) -> f64 {
    let at = |p: P| {
        edges
            .iter()
            .map(|&(u, v)| point_segment(p, u, v))
            .fold(f64::INFINITY, f64::min)
    };
    let reached = at(a).max(at(b));
    if reached > limit {
        return reached;
    }
    let bound = edges
        .iter()
        .map(|&(u, v)| point_segment(a, u, v).max(point_segment(b, u, v)))
        .fold(f64::INFINITY, f64::min);
    if bound <= limit || depth == 0 {
        return bound;
    }
    let m = scale(add(a, b), 0.5);
    farthest(edges, a, m, limit, depth - 1).max(farthest(edges, m, b, limit, depth - 1))
}

/// Parameters of one check run derived from [`CutParams`].
struct Band {
    /// Expected distance of the contour part from the nominal contour.
    e: f64,
    tol: f64,
    half_kerf: f64,
}

/// Checks `program` against `reference` (module docs).
pub fn check(reference: &Reference, program: &Program, params: &CutParams) -> Report {
    let sheet = Sheet::new(reference);
    let band = Band {
        e: if params.controller_compensation {
            0.0
        } else {
            params.kerf_mm / 2.0
        },
        tol: PATH_TOL_MM + ROUNDING_MM,
        half_kerf: params.kerf_mm / 2.0,
    };
    let mut report = Report {
        runs: program.runs.len(),
        ..Report::default()
    };
    let mut scratch = Vec::new();
    let mut cuts_of: Vec<Vec<usize>> = vec![Vec::new(); reference.contours.len()];
    for (k, run) in program.runs.iter().enumerate() {
        if !run.rapids_with_heat.is_empty() {
            report.add(
                Check::HeatOnRapid,
                format!(
                    "cut {k}: G0 with the heat on at line(s) {:?}",
                    run.rapids_with_heat
                ),
            );
        }
        let reach = params.kerf_mm + 1.0;
        match match_run(&sheet, run, reach, &mut scratch) {
            Some(c) => {
                cuts_of[c].push(k);
                report.matched += 1;
                check_run(&sheet, k, run, c, params, &band, &mut report, &mut scratch);
            }
            None => report.add(
                Check::Count,
                format!(
                    "cut {k} (pierce at line {}, ({:.3}, {:.3})) follows no contour",
                    run.line, run.pierce[0], run.pierce[1]
                ),
            ),
        }
    }
    for (c, cuts) in cuts_of.iter().enumerate() {
        let rc = &reference.contours[c];
        match cuts.len() {
            1 => {}
            0 if params.skip_too_small_holes
                && rc.role == Role::Hole
                && 2.0 * inscribed_radius(&rc.ring) < params.small_hole_diameter_mm =>
            {
                report.skipped.push(rc.name.clone());
            }
            0 => report.add(Check::Count, format!("{} is never cut", rc.name)),
            n => report.add(
                Check::Count,
                format!("{} is cut {n} times (cuts {cuts:?})", rc.name),
            ),
        }
    }
    check_precedence(reference, &cuts_of, &mut report);
    report
}

/// The contour most of the run's length is nearest to (within `reach`), if it has a majority.
fn match_run(sheet: &Sheet, run: &HeatRun, reach: f64, scratch: &mut Vec<u32>) -> Option<usize> {
    const SAMPLES: usize = 48;
    let total = run.length();
    if total <= 0.0 {
        return None;
    }
    let mut votes: BTreeMap<usize, usize> = BTreeMap::new();
    let (mut seg, mut walked) = (0, 0.0);
    for s in 0..SAMPLES {
        let want = (s as f64 + 0.5) / SAMPLES as f64 * total;
        while seg + 2 < run.path.len() && walked + dist(run.path[seg], run.path[seg + 1]) < want {
            walked += dist(run.path[seg], run.path[seg + 1]);
            seg += 1;
        }
        let (a, b) = (run.path[seg], run.path[seg + 1]);
        let len = dist(a, b);
        let t = if len > 0.0 {
            ((want - walked) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let p = add(a, scale(sub(b, a), t));
        if let Some((c, _)) = sheet.nearest(p, reach, scratch) {
            *votes.entry(c).or_default() += 1;
        }
    }
    let (&c, &n) = votes.iter().max_by_key(|(_, &n)| n)?;
    (2 * n > SAMPLES).then_some(c)
}

/// All checks of one cut `k` matched to contour `c`.
#[allow(clippy::too_many_arguments)]
fn check_run(
    sheet: &Sheet,
    k: usize,
    run: &HeatRun,
    c: usize,
    params: &CutParams,
    band: &Band,
    report: &mut Report,
    scratch: &mut Vec<u32>,
) {
    let rc = &sheet.reference.contours[c];
    let what = format!("cut {k} (line {}) of {}", run.line, rc.name);
    let path = &run.path;
    let e = band.e;
    check_pierce(sheet, &what, run, c, params, report);

    // The contour part: first to last point on the offset band.
    let look = e + band.tol + 1.0;
    let near: Vec<f64> = path
        .iter()
        .map(|&p| sheet.grid.distance(p, Some(c as u32), look, scratch))
        .collect();
    let on = |d: f64| (d - e).abs() <= band.tol;
    let (Some(a), Some(b)) = (
        near.iter().position(|&d| on(d)),
        near.iter().rposition(|&d| on(d)),
    ) else {
        let mut ds: Vec<f64> = near.iter().map(|d| d.min(look)).collect();
        ds.sort_by(f64::total_cmp);
        report.add(
            Check::Offset,
            format!(
                "{what}: no point of the path lies {e:.3} ± {:.3} mm from the contour (median {:.3} mm{})",
                band.tol,
                ds[ds.len() / 2],
                if ds[ds.len() / 2] < band.tol { ": no kerf compensation" } else { "" }
            ),
        );
        return;
    };

    // Offset band and side along the contour part.
    let mut worst: Option<(f64, usize)> = None;
    for i in a..b {
        let (lower, upper) =
            sheet.move_bounds(c, path[i], path[i + 1], look, e + band.tol, scratch);
        let off = (e - lower).max(upper - e);
        if off > band.tol && worst.is_none_or(|(w, _)| off > w) {
            worst = Some((off, i));
        }
    }
    if let Some((off, i)) = worst {
        report.add(
            Check::Offset,
            format!(
                "{what}: the move at line {} ({:.3}, {:.3}) strays {off:.3} mm from the {e:.3} mm offset (tolerance {:.3})",
                run.move_line[i], path[i][0], path[i][1], band.tol
            ),
        );
    }
    check_side(sheet, &what, run, c, a, b, params, report);

    // Coverage of the offset contour by the contour part.
    let mut part_grid = SegmentGrid::new(2.0);
    let mut part_len = 0.0;
    for i in a..b {
        part_grid.insert(path[i], path[i + 1], 0);
        part_len += dist(path[i], path[i + 1]);
    }
    let cover_tol = band.tol + ARC_SAMPLING_MM;
    let ring = &rc.ring;
    let n = ring.len();
    let (mut targets, mut missed, mut first_miss) = (0, 0, None);
    let mut try_target = |t: P, scratch: &mut Vec<u32>| {
        // Closer than e to another stretch of the contour: past a mitred corner, in a concave
        // corner or a narrow neck, where the true offset does not pass.
        if e > 0.0 && sheet.grid.distance(t, Some(c as u32), e, scratch) < e - 1e-9 {
            return;
        }
        targets += 1;
        if part_grid
            .distance(t, None, cover_tol, scratch)
            .is_infinite()
        {
            missed += 1;
            first_miss.get_or_insert(t);
        }
    };
    for i in 0..n {
        let (p, q) = (ring[i], ring[(i + 1) % n]);
        let normal = sheet.scrap_normal(c, i);
        let steps = (dist(p, q) / COVERAGE_STEP_MM).ceil().max(1.0) as usize;
        for j in 0..steps {
            let s = (j as f64 + 0.5) / steps as f64;
            let on_edge = add(p, scale(sub(q, p), s));
            try_target(add(on_edge, scale(normal, e)), scratch);
        }
        // The round join at the vertex q (swallowed at a concave vertex).
        if e > 0.0 {
            let bisector = unit(add(normal, sheet.scrap_normal(c, (i + 1) % n)));
            try_target(add(q, scale(bisector, e)), scratch);
        }
    }
    if missed > 0 {
        let t = first_miss.expect("a miss has a point");
        report.add(
            Check::Coverage,
            format!(
                "{what}: {missed} of {targets} points of the offset contour are not cut, the first at ({:.3}, {:.3})",
                t[0], t[1]
            ),
        );
    }
    let one_turn = ring_perimeter(ring) + std::f64::consts::TAU * e;
    let allowed = one_turn + params.overcut_mm + params.lead_in_mm + params.lead_out_mm + 1.0;
    if part_len > allowed {
        report.add(
            Check::Coverage,
            format!("{what}: runs {part_len:.1} mm along the contour, more than one turn ({one_turn:.1} mm) and the overcut"),
        );
    }

    // Leads (module docs): the lead-in's reach is the profile's lead-in length, or, for a small
    // hole pierced at its centre, the distance from the centre to the cut path.
    let lead_in: f64 = (0..a).map(|i| dist(path[i], path[i + 1])).sum();
    let lead_out: f64 = (b..path.len() - 1)
        .map(|i| dist(path[i], path[i + 1]))
        .sum();
    report.lead_in_mm.push(lead_in);
    let l = params.lead_in_mm;
    let from_path = ring_distance(run.pierce, ring) - e;
    let small_hole = || {
        rc.role == Role::Hole && 2.0 * inscribed_radius(ring) < params.small_hole_diameter_mm * 1.05
    };
    let centred = || ring_distance(run.pierce, ring) >= 0.8 * inscribed_radius(ring);
    let reach = if from_path > l && small_hole() && centred() {
        from_path
    } else {
        l
    };
    let entry = path[a];
    let chord = dist(run.pierce, entry);
    if chord > std::f64::consts::SQRT_2 * reach + 0.05 {
        report.add(
            Check::LeadLength,
            format!(
                "{what}: pierce {chord:.3} mm from where its lead-in meets the cut path, beyond a quarter circle of the lead-in's {reach:.3} mm"
            ),
        );
    }
    let quarter = std::f64::consts::FRAC_PI_2;
    if lead_in > quarter * reach + 0.05 {
        report.add(
            Check::LeadLength,
            format!(
                "{what}: lead-in runs {lead_in:.3} mm, more than a quarter turn of {reach:.3} mm"
            ),
        );
    }
    if lead_out > quarter * params.lead_out_mm + 0.05 {
        report.add(
            Check::LeadLength,
            format!(
                "{what}: lead-out runs {lead_out:.3} mm, more than a quarter turn of the profile's {:.3} mm",
                params.lead_out_mm
            ),
        );
    }
    if l > 0.0 && from_path < 0.5 * l {
        let small_hole = small_hole();
        let centred = small_hole && centred();
        let reach = l + params.kerf_mm;
        sheet.grid.near(entry, entry, reach, scratch);
        let obstructed = scratch.iter().any(|&i| {
            let (p, q, tag) = sheet.grid.segments[i as usize];
            tag as usize != c && point_segment(entry, p, q) <= reach
        });
        if !centred && !obstructed {
            report.add(
                Check::LeadLength,
                format!(
                    "{what}: pierce only {from_path:.3} mm from the cut path (lead-in {:.3} mm){}",
                    params.lead_in_mm,
                    if small_hole {
                        ", and not at the small hole's centre"
                    } else {
                        ", with nothing in the way of a full lead-in"
                    }
                ),
            );
        }
    }
    // Lead clearance: other contours at least half a kerf away, and the own part not cut.
    let lead_moves = (0..a).chain(b..path.len() - 1);
    for i in lead_moves {
        let (p, q) = (path[i], path[i + 1]);
        sheet
            .grid
            .near(p, q, band.half_kerf.max(e) + band.tol, scratch);
        let mut own = f64::INFINITY;
        for &s in scratch.iter() {
            let (u, v, tag) = sheet.grid.segments[s as usize];
            let d = segment_segment(p, q, u, v);
            if tag as usize == c {
                own = own.min(d);
            } else if d < band.half_kerf - ROUNDING_MM {
                report.add(
                    Check::LeadClearance,
                    format!(
                        "{what}: the {} at line {} passes {d:.3} mm from {} (half the kerf is {:.3} mm)",
                        if i < a { "lead-in" } else { "lead-out" },
                        run.move_line[i],
                        sheet.name(tag as usize),
                        band.half_kerf
                    ),
                );
                return;
            }
        }
        if !params.controller_compensation && own < e - band.tol {
            report.add(
                Check::LeadClearance,
                format!(
                    "{what}: the {} at line {} comes {own:.3} mm from its own contour and cuts into the part",
                    if i < a { "lead-in" } else { "lead-out" },
                    run.move_line[i]
                ),
            );
            return;
        }
    }
}

/// Pierce on the scrap side, a kerf clear of its contour, in no part's material.
fn check_pierce(
    sheet: &Sheet,
    what: &str,
    run: &HeatRun,
    c: usize,
    params: &CutParams,
    report: &mut Report,
) {
    let rc = &sheet.reference.contours[c];
    let p = run.pierce;
    let at = format!("({:.3}, {:.3})", p[0], p[1]);
    let gap = ring_distance(p, &rc.ring);
    let inside = point_in_ring(p, &rc.ring);
    if gap < params.kerf_mm {
        report.add(
            Check::Pierce,
            format!("{what}: pierce at {at} is {gap:.3} mm from the contour, less than one kerf ({:.3} mm)", params.kerf_mm),
        );
    } else if inside != (rc.role == Role::Hole) {
        report.add(
            Check::Pierce,
            format!(
                "{what}: pierce at {at} is on the part's side ({})",
                if inside {
                    "inside the outer contour"
                } else {
                    "outside the hole"
                }
            ),
        );
    } else if let Some(part) = sheet.in_material(p) {
        report.add(
            Check::Pierce,
            format!("{what}: pierce at {at} lies in the material of parts[{part}]"),
        );
    }
}

/// The contour part on the scrap side (geometric offset), or the G41/G42 side pointing to the
/// scrap (controller compensation).
#[allow(clippy::too_many_arguments)]
fn check_side(
    sheet: &Sheet,
    what: &str,
    run: &HeatRun,
    c: usize,
    a: usize,
    b: usize,
    params: &CutParams,
    report: &mut Report,
) {
    let rc = &sheet.reference.contours[c];
    let scrap_inside = rc.role == Role::Hole;
    let path = &run.path;
    let probes = 8.min(b.saturating_sub(a)).max(1);
    for s in 0..probes {
        let i = (a + s * (b - a) / probes).min(b);
        let probe = if params.controller_compensation {
            if i >= b {
                continue;
            }
            let dir = unit(sub(path[i + 1], path[i]));
            let side = match run.move_compensation[i] {
                Compensation::Left => scale(right_of(dir), -1.0),
                Compensation::Right => right_of(dir),
                Compensation::Off => {
                    report.add(
                        Check::Side,
                        format!(
                            "{what}: the move at line {} runs without G41/G42",
                            run.move_line[i]
                        ),
                    );
                    return;
                }
            };
            let mid = scale(add(path[i], path[i + 1]), 0.5);
            add(mid, scale(side, params.kerf_mm.max(0.1) / 2.0))
        } else {
            path[i]
        };
        if point_in_ring(probe, &rc.ring) != scrap_inside {
            report.add(
                Check::Side,
                format!(
                    "{what}: the cut at ({:.3}, {:.3}) is on the part's side of the contour",
                    probe[0], probe[1]
                ),
            );
            return;
        }
    }
}

/// Strict precedence (module docs), on the order of the first cut of each contour.
fn check_precedence(reference: &Reference, cuts_of: &[Vec<usize>], report: &mut Report) {
    let contours = &reference.contours;
    let pos = |c: usize| cuts_of[c].first().copied();
    let parts = reference.parts();
    let mut outer = vec![usize::MAX; parts];
    let mut holes: Vec<Vec<usize>> = vec![Vec::new(); parts];
    for (c, rc) in contours.iter().enumerate() {
        match rc.role {
            Role::Outer => outer[rc.part] = c,
            Role::Hole => holes[rc.part].push(c),
        }
    }
    for part in 0..parts {
        let Some(o) = pos(outer[part]) else { continue };
        for &h in &holes[part] {
            if pos(h).is_some_and(|hp| hp > o) {
                report.add(
                    Check::Precedence,
                    format!("{} is cut after its part's outer contour", contours[h].name),
                );
            }
        }
        let mut at: Vec<usize> = std::iter::once(o)
            .chain(holes[part].iter().filter_map(|&h| pos(h)))
            .collect();
        at.sort_unstable();
        if at.last().unwrap_or(&0) - at[0] + 1 != at.len() {
            report.add(
                Check::Precedence,
                format!("parts[{part}] is not cut in one go (cuts {at:?})"),
            );
        }
    }
    // The hole each part lies directly in: the smallest hole of another part containing it.
    let boxes: Vec<[P; 2]> = contours.iter().map(|c| bbox(&c.ring)).collect();
    let area: Vec<f64> = contours
        .iter()
        .map(|c| signed_area2(&c.ring).abs())
        .collect();
    for (part, &o) in outer.iter().enumerate() {
        let [lo, hi] = boxes[o];
        let host = (0..contours.len())
            .filter(|&h| contours[h].role == Role::Hole && contours[h].part != part)
            .filter(|&h| {
                let [hl, hh] = boxes[h];
                hl[0] <= lo[0] && hl[1] <= lo[1] && hh[0] >= hi[0] && hh[1] >= hi[1]
            })
            .filter(|&h| point_in_ring(contours[o].ring[0], &contours[h].ring))
            .min_by(|&x, &y| area[x].total_cmp(&area[y]));
        let (Some(h), Some(inner)) = (host, pos(o)) else {
            continue;
        };
        let host_part = contours[h].part;
        if let Some(first_hole) = holes[host_part].iter().filter_map(|&x| pos(x)).min() {
            if first_hole < inner {
                report.add(
                    Check::Precedence,
                    format!(
                        "{} lies in {} but is cut after a hole of that part",
                        contours[o].name, contours[h].name
                    ),
                );
            }
        }
    }
}

/// Points of a DXF drawing that a contour must pass through: LWPOLYLINE vertices, LINE ends and
/// the four quadrant points of each CIRCLE, of the top-level ENTITIES section (not blocks),
/// outside `skip_layer` (the sheet outline). A minimal reading of the DXF text, independent of
/// the sequencer's DXF reader; entities in a mirrored OCS (extrusion z = −1) are left out.
pub fn dxf_drawing_points(text: &str, skip_layer: &str) -> Vec<(P, String)> {
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let pairs: Vec<(i32, &str)> = lines
        .chunks(2)
        .filter_map(|c| Some((c.first()?.parse().ok()?, *c.get(1)?)))
        .collect();
    let mut out = Vec::new();
    let mut in_entities = false;
    let mut i = 0;
    while i < pairs.len() {
        let (code, value) = pairs[i];
        if code == 2 && value == "ENTITIES" {
            in_entities = true;
        }
        if code == 0 && value == "ENDSEC" {
            in_entities = false;
        }
        if !in_entities || code != 0 || !matches!(value, "LWPOLYLINE" | "LINE" | "CIRCLE") {
            i += 1;
            continue;
        }
        let kind = value;
        let mut j = i + 1;
        let (mut layer, mut xs, mut ys, mut r, mut mirrored) =
            ("", Vec::new(), Vec::new(), None, false);
        while j < pairs.len() && pairs[j].0 != 0 {
            let (c, v) = pairs[j];
            let num = v.parse::<f64>().ok();
            match c {
                8 => layer = v,
                10 | 11 => xs.extend(num),
                20 | 21 => ys.extend(num),
                40 if kind == "CIRCLE" => r = num,
                230 => mirrored = num.is_some_and(|z| z < 0.0),
                _ => {}
            }
            j += 1;
        }
        i = j;
        if mirrored || layer.eq_ignore_ascii_case(skip_layer) {
            continue;
        }
        let label = format!("{kind} on layer '{layer}'");
        match (kind, r) {
            ("CIRCLE", Some(r)) if !xs.is_empty() && !ys.is_empty() => {
                let c = [xs[0], ys[0]];
                for d in [[r, 0.0], [0.0, r], [-r, 0.0], [0.0, -r]] {
                    out.push((add(c, d), label.clone()));
                }
            }
            _ => out.extend(xs.iter().zip(&ys).map(|(&x, &y)| ([x, y], label.clone()))),
        }
    }
    out
}

/// Every drawing point lies on some reference contour (within [`DRAWING_TOL_MM`]).
pub fn check_drawing(reference: &Reference, points: &[(P, String)], report: &mut Report) {
    let sheet = Sheet::new(reference);
    let mut scratch = Vec::new();
    let mut missed = 0;
    for (p, what) in points {
        if sheet
            .grid
            .distance(*p, None, DRAWING_TOL_MM, &mut scratch)
            .is_infinite()
        {
            missed += 1;
            if missed <= 3 {
                let near = sheet
                    .nearest(*p, 50.0, &mut scratch)
                    .map(|(c, d)| (sheet.name(c).to_owned(), d));
                report.add(
                    Check::Drawing,
                    format!(
                        "the drawing's {what} point ({:.3}, {:.3}) lies on no contour of the layout (nearest: {near:?})",
                        p[0], p[1]
                    ),
                );
            }
        }
    }
    if missed > 3 {
        report.add(
            Check::Drawing,
            format!("… {missed} of {} drawing points in all", points.len()),
        );
    }
}
