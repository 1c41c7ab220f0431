//! The nested-layout model (seed 003 §A1: sheet `L(a×b)`, parts `S_i` with contours `C_ij`,
//! pierce points `P_ij`, `P_start`), its JSON format, and its conversion to a [`Problem`]:
//! containment tree, precedence (seed 003 §2; notes §A2, §A4) and pierce candidates.
//!
//! # JSON format
//!
//! Lengths in mm; a contour is a closed polyline whose first point is not repeated (a repeated
//! closing point is dropped). Orientation does not matter. Points are relative to the sheet's
//! lower-left corner; the optional `origin` (default `[0, 0]`) is where that corner is on the
//! machine ([`crate::placement`]): the program cuts point `p` at `origin + p`. `pierce` is optional per contour:
//! given, it is the contour's only pierce candidate (the paper's fixed `P_ij`); absent, the
//! candidates are chosen by [`PierceOptions`] ("free" mode). Unknown keys are errors.
//!
//! ```json
//! {
//!   "sheet": [300, 200],
//!   "start": [0, 0],
//!   "parts": [
//!     { "name": "frame",
//!       "outer": { "points": [[10,10],[150,10],[150,150],[10,150]], "pierce": [10,80] },
//!       "holes": [ { "points": [[30,30],[120,30],[120,120],[30,120]] } ] },
//!     { "name": "washer",
//!       "outer": { "points": [[50,50],[90,50],[90,90],[50,90]] } },
//!     { "outer": { "points": [[200,20],[280,20],[240,90]] } }
//!   ]
//! }
//! ```
//!
//! Which contour is nested in which is taken from the containment tree
//! ([`crate::containment`]), not from the file: the "washer" above lies inside the frame's hole
//! and is therefore cut before it. A hole must lie directly inside its own part's outer
//! contour, and an outer contour must not lie directly inside another outer contour (it would
//! overlap that part's material); both are errors naming the part. The shipped example is
//! `tests/data/sheet/example.json`.
//!
//! **Size.** A layout holds at most [`MAX_POINTS`] points in all (the DXF reader's limit,
//! issue 23) and [`MAX_CONTOURS`] contours; both are counted while the JSON is read, so a file
//! of millions of points or rings is refused at the first one over, naming the file, line and
//! field, before the rest is read.

use std::cell::Cell;
use std::path::Path;

use cell_geometry::{distance_to_rings, point_in_ring_nonzero, Norm};
use serde::de::{Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};

use crate::containment::{check_ring, dedup_ring, find_crossing, ContainmentTree, GeometryError};
use crate::dxf::MAX_POINTS;
use crate::precedence::{Precedence, PrecedenceMode, Violation};
use crate::problem::{distance, Contour, ContourId, ContourRole, Point, Problem};
use crate::thermal::{require, SequencerParamError};

/// A nested sheet layout (seed 003 §A1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layout {
    /// Sheet size `a × b`, mm; the sheet spans `[0, a] × [0, b]`.
    pub sheet: [f64; 2],
    /// Initial tool position `P_start`, mm, relative to the sheet like the parts.
    #[serde(default)]
    pub start: Point,
    /// Where the sheet's lower-left corner is in machine coordinates, mm
    /// ([`crate::placement`]): the program cuts point `p` at `origin + p`. Absent = `[0, 0]`.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub origin: Point,
    /// The parts `S_i`.
    #[serde(deserialize_with = "parts_counting_points")]
    pub parts: Vec<Part>,
}

fn is_zero(p: &Point) -> bool {
    *p == [0.0, 0.0]
}

/// Most contours (outer contours and holes) a JSON layout may hold (issue 23): as many as the
/// DXF reader may place entities ([`crate::dxf::MAX_PLACED_ENTITIES`]); a 500-part sheet has
/// a few thousand. A 64 MiB file of empty rings is 2.7·10⁶ of them (4 s and 400 MB to read).
pub const MAX_CONTOURS: usize = 250_000;

thread_local! {
    /// Contours and points read so far of the layout being deserialised on this thread
    /// ([`MAX_CONTOURS`], [`MAX_POINTS`]); reset where its `parts` begin. Serde's derive has
    /// no per-document state, and a layout is read on one thread from start to end.
    static READ: Cell<(usize, usize)> = const { Cell::new((0, 0)) };
}

/// A layout's `parts`, counting their contours and points from zero
/// ([`points_within_limit`]).
fn parts_counting_points<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Part>, D::Error> {
    READ.set((0, 0));
    Vec::<Part>::deserialize(d)
}

/// A ring's `points`, refused as soon as the layout's contours pass [`MAX_CONTOURS`] or its
/// points [`MAX_POINTS`] (issue 23: a 64 MiB file holds ~10⁷ points, and the containment and
/// precedence steps after it are superlinear), so no more of the file is read.
fn points_within_limit<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Point>, D::Error> {
    struct Points;
    impl<'de> Visitor<'de> for Points {
        type Value = Vec<Point>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a list of [x, y] points")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let (contours, mut points) = READ.get();
            let contours = contours + 1;
            READ.set((contours, points));
            if contours > MAX_CONTOURS {
                return Err(serde::de::Error::custom(format!(
                    "the layout has more than {MAX_CONTOURS} contours: the limit is \
                     {MAX_CONTOURS} contours (MAX_CONTOURS)"
                )));
            }
            let mut out: Vec<Point> = Vec::new();
            while let Some(p) = seq.next_element()? {
                points += 1;
                READ.set((contours, points));
                if points > MAX_POINTS {
                    return Err(serde::de::Error::custom(format!(
                        "the layout has more than {MAX_POINTS} points: the limit is \
                         {MAX_POINTS} points (MAX_POINTS)"
                    )));
                }
                out.push(p);
            }
            Ok(out)
        }
    }
    d.deserialize_seq(Points)
}

/// One part `S_i`: an outer contour `C_i1` and its holes `C_ij`, j > 1 (seed 003 §A1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Part {
    /// Optional name, used in error messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The outer contour.
    pub outer: Ring,
    /// The holes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub holes: Vec<Ring>,
}

/// One closed contour of a part, with an optional fixed pierce point (seed 003 §A1 `P_ij`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ring {
    /// Closed polyline, mm, first point not repeated.
    #[serde(deserialize_with = "points_within_limit")]
    pub points: Vec<Point>,
    /// Fixed pierce point, mm; `None` = free (candidates from [`PierceOptions`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pierce: Option<Point>,
}

/// Errors reading or converting a layout (seed 003 §A1, §2).
#[derive(Debug, thiserror::Error)]
pub enum LayoutError {
    /// The file cannot be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The JSON is malformed or does not match the format, with the line, column and path of
    /// the offending value (e.g. `parts[2].outer.points[0]`).
    #[error(transparent)]
    Json(#[from] cell_config::ParseError),
    /// A contour is not a valid closed simple polygon on the sheet.
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    /// The nesting contradicts the declared parts (a hole outside its part, parts overlapping).
    #[error("{ring}: {message}")]
    Nesting {
        /// Which ring (part/hole, by index and name).
        ring: String,
        /// What is wrong.
        message: String,
    },
    /// The sheet size is not positive and finite.
    #[error("sheet size {0:?} mm must be positive and finite")]
    Sheet([f64; 2]),
    /// The precedence rules cannot be met (seed 003 §2).
    #[error("precedence: {0}")]
    Precedence(#[from] Violation),
    /// A fixed pierce point is outside the sheet, on the part's side of its contour, or
    /// farther from the contour than [`PierceOptions::max_lead_in_mm`].
    #[error("{ring}: pierce point ({x:.3}, {y:.3}) mm {reason}")]
    Pierce {
        /// Which ring.
        ring: String,
        /// mm.
        x: f64,
        /// mm.
        y: f64,
        /// What is wrong with it.
        reason: String,
    },
}

/// How free pierce candidates are chosen (issue 7: "pierce away from corners").
///
/// **Rule.** Walk the contour by arc length `s ∈ [0, L)`. A *corner* is a vertex whose turn
/// angle (the angle between the incoming and outgoing edge directions) exceeds
/// `corner_angle_deg`; flattened arcs turn by a few degrees per vertex and are not corners.
/// Every corner blocks the arc-length window `±corner_margin_mm` around it. In the remaining
/// *free* length `F`, `k = clamp(ceil(F / spacing_mm), 1, max_candidates)` candidates are placed
/// at free arc lengths `(i + ½)·F/k`, i = 0..k (evenly, never on a window edge). If nothing is
/// free (a small contour with many corners), the single candidate is the midpoint of the longest
/// edge, which is as far from its two end corners as the contour allows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PierceOptions {
    /// Upper bound on candidates per contour.
    pub max_candidates: usize,
    /// Target spacing between candidates along the free length, mm.
    pub spacing_mm: f64,
    /// A vertex turning by more than this is a corner, degrees.
    pub corner_angle_deg: f64,
    /// Arc-length distance kept from every corner, mm.
    pub corner_margin_mm: f64,
    /// A fixed pierce point off its contour is reached by a straight lead-in; it may lie at
    /// most this far from the contour, mm, and only on the scrap side (outside an outer
    /// contour, inside a hole), so the lead-in never scars the part.
    pub max_lead_in_mm: f64,
}

/// Most free pierce candidates per contour (issue 23): 8× the default; the cost tables and
/// the improvement's pierce re-selection at every position grow with it.
pub const MAX_PIERCE_CANDIDATES: usize = 64;

impl PierceOptions {
    /// Checks the sizes it sets.
    ///
    /// # Errors
    /// `max_candidates` over [`MAX_PIERCE_CANDIDATES`], named.
    pub fn validate(&self) -> Result<(), SequencerParamError> {
        require(
            self.max_candidates <= MAX_PIERCE_CANDIDATES,
            "pierce_options.max_candidates",
            self.max_candidates,
            "must be in [0, 64] (MAX_PIERCE_CANDIDATES)",
        )
    }
}

impl Default for PierceOptions {
    fn default() -> Self {
        PierceOptions {
            max_candidates: 8,
            spacing_mm: 50.0,
            corner_angle_deg: 30.0,
            corner_margin_mm: 2.0,
            max_lead_in_mm: 10.0,
        }
    }
}

/// A layout with its containment tree resolved: the `IN` sets of the paper's pseudo-code
/// (seed 003 §A4), per part.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Nesting {
    /// `host[i]`: `(part, hole index)` of the hole part `i` lies directly inside, or `None` for
    /// a top-level part (`IN C_01`).
    pub host: Vec<Option<(usize, usize)>>,
    /// `inside[i][h]`: parts lying directly inside hole `h` of part `i` (`IN C_ij`).
    pub inside: Vec<Vec<Vec<usize>>>,
    /// Nesting depth of each part's outer contour (0, 2, 4, …).
    pub depth: Vec<usize>,
}

impl Layout {
    /// Parses the JSON format (module docs; seed 003 §A1 model); `path` only names the source
    /// in errors.
    ///
    /// # Errors
    /// [`LayoutError::Json`] with the field path, line and column.
    pub fn from_json_str(text: &str, path: &str) -> Result<Self, LayoutError> {
        Ok(cell_config::from_json_str(text, path)?)
    }

    /// Reads a JSON layout file (seed 003 §A1 model, module docs).
    ///
    /// # Errors
    /// [`LayoutError::Io`] or [`LayoutError::Json`], naming the file.
    pub fn from_json_file(path: impl AsRef<Path>) -> Result<Self, LayoutError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| LayoutError::Io {
            path: name.clone(),
            source,
        })?;
        Self::from_json_str(&text, &name)
    }

    /// The layout as pretty JSON (the format in the module docs; seed 003 §A1).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a layout always serialises")
    }

    /// Total number of contours `Σ m_i` (seed 003 §A1).
    pub fn contour_count(&self) -> usize {
        self.parts.iter().map(|p| 1 + p.holes.len()).sum()
    }

    /// Builds a layout from loose closed rings (e.g. from DXF): the containment tree decides
    /// which ring is an outer contour (even depth) and which a hole (odd depth) and of which
    /// part (seed 003 §A1; notes §A6). `names[r]` names ring `r` in errors.
    ///
    /// Parts are numbered in the order of their outer rings; holes in ring order.
    ///
    /// # Errors
    /// [`LayoutError::Geometry`] for a degenerate, self-intersecting or off-sheet ring, or two
    /// rings that cross.
    pub fn from_rings(
        sheet: [f64; 2],
        start: Point,
        rings: Vec<Vec<Point>>,
        names: &[String],
    ) -> Result<Self, LayoutError> {
        check_sheet(sheet)?;
        let rings: Vec<Vec<Point>> = rings.iter().map(|r| dedup_ring(r, 1e-9)).collect();
        let name = |r: usize| names.get(r).cloned().unwrap_or_else(|| format!("ring {r}"));
        for (r, ring) in rings.iter().enumerate() {
            check_ring(&name(r), ring, sheet)?;
        }
        if let Some((r, o)) = find_crossing(&rings) {
            return Err(GeometryError::Crossing {
                ring: name(r),
                other: name(o),
            }
            .into());
        }
        let tree = ContainmentTree::build(&rings);
        let mut part_of = vec![usize::MAX; rings.len()];
        let mut parts = Vec::new();
        for (r, ring) in rings.iter().enumerate() {
            if tree.depth[r].is_multiple_of(2) {
                part_of[r] = parts.len();
                parts.push(Part {
                    name: names.get(r).cloned(),
                    outer: Ring {
                        points: ring.clone(),
                        pierce: None,
                    },
                    holes: Vec::new(),
                });
            }
        }
        for (r, ring) in rings.iter().enumerate() {
            if !tree.depth[r].is_multiple_of(2) {
                let host = tree.parent[r].expect("odd depth has a parent");
                parts[part_of[host]].holes.push(Ring {
                    points: ring.clone(),
                    pierce: None,
                });
            }
        }
        Ok(Layout {
            sheet,
            start,
            origin: [0.0, 0.0],
            parts,
        })
    }

    /// Checks every contour and resolves the nesting (the paper's `IN` sets, seed 003 §A4).
    ///
    /// # Errors
    /// [`LayoutError::Geometry`] for a bad contour or two contours that cross,
    /// [`LayoutError::Nesting`] when the
    /// containment tree contradicts the declared parts.
    pub fn nesting(&self) -> Result<Nesting, LayoutError> {
        check_sheet(self.sheet)?;
        let (rings, owner) = self.flat_rings();
        for (r, ring) in rings.iter().enumerate() {
            check_ring(&self.ring_name(owner[r]), ring, self.sheet)?;
        }
        if let Some((r, o)) = find_crossing(&rings) {
            return Err(GeometryError::Crossing {
                ring: self.ring_name(owner[r]),
                other: self.ring_name(owner[o]),
            }
            .into());
        }
        let tree = ContainmentTree::build(&rings);
        let n = self.parts.len();
        let mut host = vec![None; n];
        let mut inside: Vec<Vec<Vec<usize>>> = self
            .parts
            .iter()
            .map(|p| vec![Vec::new(); p.holes.len()])
            .collect();
        let mut depth = vec![0; n];
        for (r, &(part, hole)) in owner.iter().enumerate() {
            let parent = tree.parent[r].map(|p| owner[p]);
            match (hole, parent) {
                // A hole sits directly in its own part's outer contour.
                (Some(_), Some((pp, None))) if pp == part => {}
                (Some(_), _) => {
                    return Err(LayoutError::Nesting {
                        ring: self.ring_name(owner[r]),
                        message: match parent {
                            None => "the hole is not inside its part's outer contour".into(),
                            Some(o) => format!(
                                "the hole lies directly inside {}, not in its part's outer contour",
                                self.ring_name(o)
                            ),
                        },
                    })
                }
                (None, None) => {}
                (None, Some((pp, Some(h)))) => {
                    host[part] = Some((pp, h));
                    inside[pp][h].push(part);
                }
                (None, Some(o)) => {
                    return Err(LayoutError::Nesting {
                        ring: self.ring_name(owner[r]),
                        message: format!(
                            "the part lies inside the material of {} (parts overlap)",
                            self.ring_name(o)
                        ),
                    })
                }
            }
            if hole.is_none() {
                depth[part] = tree.depth[r];
            }
        }
        Ok(Nesting {
            host,
            inside,
            depth,
        })
    }

    /// Converts to a [`Problem`] (seed 003 §A1, §2): contours numbered part by part (outer contour first, then the
    /// holes), precedence in `mode` (see [`precedence_from_nesting`]), pierce candidates per
    /// [`PierceOptions`] unless fixed. The precedence is checked for cycles.
    ///
    /// # Errors
    /// Any [`LayoutError`] from [`Layout::nesting`], a fixed pierce point off the sheet, or a
    /// precedence cycle.
    pub fn to_problem(
        &self,
        mode: PrecedenceMode,
        pierce: &PierceOptions,
    ) -> Result<Problem, LayoutError> {
        let nesting = self.nesting()?;
        let mut contours = Vec::with_capacity(self.contour_count());
        for (i, part) in self.parts.iter().enumerate() {
            let rings = std::iter::once((&part.outer, ContourRole::Outer, None)).chain(
                part.holes
                    .iter()
                    .enumerate()
                    .map(|(h, r)| (r, ContourRole::Hole, Some(h))),
            );
            for (ring, role, hole) in rings {
                let points = dedup_ring(&ring.points, 1e-9);
                let pierce_candidates = match ring.pierce {
                    Some(p) => {
                        if let Err(reason) =
                            check_fixed_pierce(p, &points, role, self.sheet, pierce)
                        {
                            return Err(LayoutError::Pierce {
                                ring: self.ring_name((i, hole)),
                                x: p[0],
                                y: p[1],
                                reason,
                            });
                        }
                        vec![p]
                    }
                    None => free_pierce_candidates(&points, pierce),
                };
                contours.push(Contour {
                    part: i,
                    role,
                    points,
                    pierce_candidates,
                    leads: Vec::new(),
                    drawn: Vec::new(),
                });
            }
        }
        let precedence = precedence_from_nesting(self, &nesting, mode);
        precedence.check_acyclic()?;
        Ok(Problem {
            sheet: self.sheet,
            start: self.start,
            origin: self.origin,
            contours,
            precedence,
        })
    }

    /// The contour id of part `i`'s outer contour `C_i1` (seed 003 §A1) in
    /// [`Layout::to_problem`]'s numbering; its holes follow it.
    pub fn first_contour_ids(&self) -> Vec<ContourId> {
        let mut ids = Vec::with_capacity(self.parts.len());
        let mut next = 0;
        for p in &self.parts {
            ids.push(next);
            next += 1 + p.holes.len();
        }
        ids
    }

    fn flat_rings(&self) -> (Vec<Vec<Point>>, Vec<RingOwner>) {
        let mut rings = Vec::with_capacity(self.contour_count());
        let mut owner = Vec::with_capacity(self.contour_count());
        for (i, p) in self.parts.iter().enumerate() {
            rings.push(dedup_ring(&p.outer.points, 1e-9));
            owner.push((i, None));
            for (h, r) in p.holes.iter().enumerate() {
                rings.push(dedup_ring(&r.points, 1e-9));
                owner.push((i, Some(h)));
            }
        }
        (rings, owner)
    }

    /// `parts[i] (name).outer` or `parts[i] (name).holes[h]`: how errors name a contour.
    pub(crate) fn ring_name(&self, (part, hole): RingOwner) -> String {
        let named = match &self.parts[part].name {
            Some(n) => format!("parts[{part}] ({n})"),
            None => format!("parts[{part}]"),
        };
        match hole {
            None => format!("{named}.outer"),
            Some(h) => format!("{named}.holes[{h}]"),
        }
    }
}

fn check_sheet(sheet: [f64; 2]) -> Result<(), LayoutError> {
    if sheet.iter().all(|v| v.is_finite() && *v > 0.0) {
        Ok(())
    } else {
        Err(LayoutError::Sheet(sheet))
    }
}

/// `(part, None)` for a part's outer contour, `(part, Some(hole))` for a hole.
type RingOwner = (usize, Option<usize>);

/// The precedence rules from the containment tree (seed 003 §2; notes §A2, §A4), with contours
/// numbered as in [`Layout::to_problem`].
///
/// - **Strict** (§2, notes §A2 reading of `0 < Q_k1 − Q_kb < m_k`): every hole of a part before
///   its outer contour, and each part is one contiguous group; the parts lying directly inside
///   any hole of part `i` (`IN C_il`) are finished (outer contour cut) before **any** hole of
///   `i` is cut (`Q_k1 < min_l Q_il`). Deep nesting applies the same rule level by level.
/// - **Relaxed** (the pseudo-code §A4, generalised to deep nesting as notes §A4 suggest): a
///   contour becomes cuttable once everything inside it is cut — a hole after the outer contour
///   of every part lying directly inside it (those wait on their own holes, and so on down), an
///   outer contour after its own holes. No groups.
pub fn precedence_from_nesting(
    layout: &Layout,
    nesting: &Nesting,
    mode: PrecedenceMode,
) -> Precedence {
    let first = layout.first_contour_ids();
    let total = layout.contour_count();
    let mut predecessors = vec![Vec::new(); total];
    let mut groups = Vec::new();
    for (i, part) in layout.parts.iter().enumerate() {
        let outer = first[i];
        let holes: Vec<ContourId> = (1..=part.holes.len()).map(|h| outer + h).collect();
        predecessors[outer].extend(&holes);
        match mode {
            PrecedenceMode::Strict => {
                let nested: Vec<ContourId> = nesting.inside[i]
                    .iter()
                    .flatten()
                    .map(|&k| first[k])
                    .collect();
                for &h in &holes {
                    predecessors[h].extend(&nested);
                }
                groups.push(std::iter::once(outer).chain(holes).collect());
            }
            PrecedenceMode::Relaxed => {
                for (h, inside) in nesting.inside[i].iter().enumerate() {
                    predecessors[outer + 1 + h].extend(inside.iter().map(|&k| first[k]));
                }
            }
        }
    }
    Precedence {
        predecessors,
        groups,
    }
}

/// Checks a fixed pierce point (seed 003 §A1 `P_ij`): on the sheet, within
/// [`PierceOptions::max_lead_in_mm`] of the contour, and not on the part's side of it (the
/// straight lead-in from the pierce to the contour, [`crate::thermal::cut_path`], would cut
/// into the part). Returns the reason it is refused.
fn check_fixed_pierce(
    p: Point,
    ring: &[Point],
    role: ContourRole,
    sheet: [f64; 2],
    opt: &PierceOptions,
) -> Result<(), String> {
    let [a, b] = sheet;
    if !p.iter().all(|v| v.is_finite()) {
        return Err("is not finite".into());
    }
    if !(0.0..=a).contains(&p[0]) || !(0.0..=b).contains(&p[1]) {
        return Err("is outside the sheet".into());
    }
    let gap = distance_to_rings(p, std::slice::from_ref(&ring), Norm::Hypot);
    if gap > opt.max_lead_in_mm {
        return Err(format!(
            "is {gap:.3} mm from its contour; a lead-in may be at most max_lead_in_mm = {} mm",
            opt.max_lead_in_mm
        ));
    }
    // On the contour itself (within a micron) is always fine.
    if gap > 1e-3 {
        let inside = point_in_ring_nonzero(p, ring);
        match role {
            ContourRole::Outer if inside => {
                return Err("lies inside the part; pierce an outer contour from outside".into())
            }
            ContourRole::Hole if !inside => {
                return Err("lies outside the hole, in the part; pierce a hole from inside".into())
            }
            _ => {}
        }
    }
    Ok(())
}

/// Free pierce candidates on a closed polyline by the corner-avoiding rule of
/// [`PierceOptions`] (issue 7; seed 003 §A1 lists free pierce points as the GTSP variant).
pub fn free_pierce_candidates(points: &[Point], opt: &PierceOptions) -> Vec<Point> {
    let n = points.len();
    if n == 0 {
        return Vec::new();
    }
    if n < 3 {
        return vec![points[0]];
    }
    let edge_len: Vec<f64> = (0..n)
        .map(|i| distance(points[i], points[(i + 1) % n]))
        .collect();
    let total: f64 = edge_len.iter().sum();
    if total <= 0.0 {
        return vec![points[0]];
    }
    // Arc length at each vertex.
    let mut at = vec![0.0; n];
    for i in 1..n {
        at[i] = at[i - 1] + edge_len[i - 1];
    }
    let limit = opt.corner_angle_deg.to_radians();
    let corners: Vec<f64> = (0..n)
        .filter(|&i| {
            let (p, q, r) = (points[(i + n - 1) % n], points[i], points[(i + 1) % n]);
            let (u, v) = ([q[0] - p[0], q[1] - p[1]], [r[0] - q[0], r[1] - q[1]]);
            let turn = (u[0] * v[1] - u[1] * v[0])
                .atan2(u[0] * v[0] + u[1] * v[1])
                .abs();
            turn > limit
        })
        .map(|i| at[i])
        .collect();
    // Free intervals of [0, total): the complement of the corner windows (wrapping).
    let margin = opt.corner_margin_mm.max(0.0);
    let mut free: Vec<(f64, f64)> = Vec::new();
    if corners.is_empty() {
        free.push((0.0, total));
    } else {
        for (k, &c) in corners.iter().enumerate() {
            let next = if k + 1 < corners.len() {
                corners[k + 1]
            } else {
                corners[0] + total
            };
            let (s, e) = (c + margin, next - margin);
            if e > s {
                free.push((s, e));
            }
        }
    }
    let free_len: f64 = free.iter().map(|(s, e)| e - s).sum();
    if free_len <= 1e-9 {
        let i = (0..n)
            .max_by(|&a, &b| edge_len[a].total_cmp(&edge_len[b]).then(b.cmp(&a)))
            .unwrap_or(0);
        let (p, q) = (points[i], points[(i + 1) % n]);
        return vec![[(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0]];
    }
    let k =
        ((free_len / opt.spacing_mm.max(1e-9)).ceil() as usize).clamp(1, opt.max_candidates.max(1));
    let mut out = Vec::with_capacity(k);
    for j in 0..k {
        let mut want = (j as f64 + 0.5) * free_len / k as f64;
        for &(s, e) in &free {
            if want <= e - s {
                out.push(point_at(points, &at, &edge_len, (s + want) % total));
                break;
            }
            want -= e - s;
        }
    }
    out
}

/// The point at arc length `s` along the closed polyline.
fn point_at(points: &[Point], at: &[f64], edge_len: &[f64], s: f64) -> Point {
    let n = points.len();
    let i = match at.binary_search_by(|v| v.total_cmp(&s)) {
        Ok(i) => return points[i],
        Err(i) => i.saturating_sub(1),
    };
    let t = if edge_len[i] > 0.0 {
        (s - at[i]) / edge_len[i]
    } else {
        0.0
    };
    let (p, q) = (points[i], points[(i + 1) % n]);
    [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::precedence::Frontier;

    fn rect(x: f64, y: f64, w: f64, h: f64) -> Ring {
        Ring {
            points: vec![[x, y], [x + w, y], [x + w, y + h], [x, y + h]],
            pierce: None,
        }
    }

    /// The structure of the paper's pseudo-code (seed 003 §A4), made concrete:
    /// part 0 (`D_1`) with holes `C_12` (contour 1) and `C_13` (contour 2); part 1 (`D_2`)
    /// nested in `C_12` with hole `C_22` (contour 4); part 2 (`D_3`) top-level without holes
    /// (contour 5).
    pub(crate) fn paper_example() -> Layout {
        Layout {
            sheet: [400.0, 200.0],
            start: [0.0, 0.0],
            origin: [0.0, 0.0],
            parts: vec![
                Part {
                    name: Some("D1".into()),
                    outer: rect(10.0, 10.0, 250.0, 180.0),
                    holes: vec![
                        rect(20.0, 20.0, 150.0, 150.0),
                        rect(200.0, 20.0, 40.0, 40.0),
                    ],
                },
                Part {
                    name: Some("D2".into()),
                    outer: rect(40.0, 40.0, 100.0, 100.0),
                    holes: vec![rect(60.0, 60.0, 20.0, 20.0)],
                },
                Part {
                    name: Some("D3".into()),
                    outer: rect(300.0, 20.0, 50.0, 50.0),
                    holes: vec![],
                },
            ],
        }
    }

    /// Cuts always the lowest eligible contour and records W before every cut.
    fn w_sequence(rules: &Precedence) -> Vec<Vec<ContourId>> {
        let mut f = Frontier::new(rules);
        let mut seq = Vec::new();
        while let Some(&c) = f.eligible().first() {
            seq.push(f.eligible());
            f.cut(c);
        }
        assert!(f.is_finished());
        seq
    }

    #[test]
    fn paper_pseudo_code_w_sequence() {
        let l = paper_example();
        let p = l
            .to_problem(PrecedenceMode::Relaxed, &PierceOptions::default())
            .unwrap();
        // GenerateW: C_13 (2), C_22 (4), C_31 (5). Cutting C_13 leaves C_11 waiting on C_12;
        // cutting C_22 frees C_21 (3); cutting C_21 empties IN C_12, so C_12 (1) joins W; then
        // C_11 (0) once both holes are cut.
        assert_eq!(
            w_sequence(&p.precedence),
            vec![
                vec![2, 4, 5],
                vec![4, 5],
                vec![3, 5],
                vec![1, 5],
                vec![0, 5],
                vec![5]
            ],
            "seed 003 §A4 GenerateW / CutAndUpdate"
        );
        let s = l
            .to_problem(PrecedenceMode::Strict, &PierceOptions::default())
            .unwrap();
        // Strict: D2 (its hole, then its outer) before any hole of D1; each part contiguous.
        assert_eq!(
            w_sequence(&s.precedence),
            vec![
                vec![4, 5],
                vec![3],
                vec![1, 2, 5],
                vec![2],
                vec![0],
                vec![5]
            ],
            "seed 003 §2: Q_k1 < min_l Q_il, contiguous parts"
        );
        assert_eq!(p.contours[1].role, ContourRole::Hole);
        assert_eq!(p.contours[3].part, 1);
    }

    #[test]
    fn nesting_sets() {
        let n = paper_example().nesting().unwrap();
        assert_eq!(n.host, vec![None, Some((0, 0)), None]);
        assert_eq!(n.inside[0], vec![vec![1], vec![]]);
        assert_eq!(n.depth, vec![0, 2, 0]);
    }

    #[test]
    fn json_round_trip_and_errors_name_the_field() {
        let l = paper_example();
        let back = Layout::from_json_str(&l.to_json(), "x").unwrap();
        assert_eq!(back, l);
        let bad = r#"{"sheet":[10,10],"parts":[{"outer":{"points":[[0,0],[1,"a"]]}}]}"#;
        let e = Layout::from_json_str(bad, "bad.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.json:1: field `parts[0].outer.points[1][1]`"),
            "{e}"
        );
        let typo = r#"{"sheet":[10,10],"parts":[{"outer":{"points":[], "pierse":[0,0]}}]}"#;
        let e = Layout::from_json_str(typo, "t.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("pierse"), "{e}");
    }

    /// A layout of `n` points: a triangle, then one ring of `n - 3` points.
    fn layout_of_points(n: usize) -> String {
        let ring: Vec<String> = (0..n - 3).map(|i| format!("[{},1]", i % 7)).collect();
        format!(
            r#"{{"sheet":[10,10],"parts":[{{"outer":{{"points":[[0,0],[1,0],[0,1]]}}}},
{{"name":"many","outer":{{"points":[{}]}}}}]}}"#,
            ring.join(",")
        )
    }

    #[test]
    fn pierce_candidates_are_capped() {
        let at = PierceOptions {
            max_candidates: MAX_PIERCE_CANDIDATES,
            ..Default::default()
        };
        assert_eq!(at.validate(), Ok(()));
        let e = PierceOptions {
            max_candidates: MAX_PIERCE_CANDIDATES + 1,
            ..at
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert_eq!(
            e,
            "parameter `pierce_options.max_candidates` = 65: must be in [0, 64] \
             (MAX_PIERCE_CANDIDATES)"
        );
    }

    #[test]
    fn layout_contours_are_capped() {
        let of = |n: usize| {
            let ring = r#"{"outer":{"points":[[0,0],[1,0],[0,1]]}}"#;
            format!(
                r#"{{"sheet":[10,10],"parts":[{}]}}"#,
                vec![ring; n].join(",\n")
            )
        };
        let at = Layout::from_json_str(&of(MAX_CONTOURS), "at.json").unwrap();
        assert_eq!(at.contour_count(), MAX_CONTOURS);
        let e = Layout::from_json_str(&of(MAX_CONTOURS + 1), "over.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("over.json:250001: field `parts[250000].outer.points`")
                && e.ends_with(
                    "more than 250000 contours: the limit is 250000 contours (MAX_CONTOURS)"
                ),
            "{e}"
        );
    }

    #[test]
    fn layout_points_are_capped_across_rings() {
        let at = Layout::from_json_str(&layout_of_points(MAX_POINTS), "at.json").unwrap();
        let read: usize = at.parts.iter().map(|p| p.outer.points.len()).sum();
        assert_eq!(read, MAX_POINTS);
        // The count starts again with every layout.
        Layout::from_json_str(&layout_of_points(MAX_POINTS), "again.json").unwrap();
        let e = Layout::from_json_str(&layout_of_points(MAX_POINTS + 1), "over.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("over.json:2: field `parts[1].outer.points`")
                && e.contains("more than 1000000 points: the limit is 1000000 points (MAX_POINTS)"),
            "{e}"
        );
    }

    #[test]
    fn nesting_errors_name_the_part() {
        let mut l = paper_example();
        l.parts[2].holes.push(rect(0.5, 0.5, 3.0, 3.0));
        let e = l.nesting().unwrap_err().to_string();
        assert!(
            e.starts_with("parts[2] (D3).holes[0]: the hole is not inside"),
            "{e}"
        );
        let mut l = paper_example();
        l.parts[2].outer = rect(215.0, 100.0, 10.0, 10.0); // in D1's material
        let e = l.nesting().unwrap_err().to_string();
        assert!(e.contains("parts overlap"), "{e}");
        let mut l = paper_example();
        l.parts[2].outer = rect(250.0, 100.0, 30.0, 30.0); // straddles D1's outer edge
        let e = l.nesting().unwrap_err().to_string();
        assert_eq!(
            e,
            "parts[0] (D1).outer crosses or touches parts[2] (D3).outer"
        );
        let mut l = paper_example();
        l.parts[2].outer = rect(390.0, 20.0, 50.0, 50.0);
        let e = l.nesting().unwrap_err().to_string();
        assert!(e.starts_with("parts[2] (D3).outer: point (440.000"), "{e}");
    }

    #[test]
    fn from_rings_assigns_holes_by_depth() {
        let l = paper_example();
        let rings: Vec<Vec<Point>> = l
            .parts
            .iter()
            .flat_map(|p| std::iter::once(&p.outer).chain(&p.holes))
            .map(|r| r.points.clone())
            .collect();
        let back = Layout::from_rings(l.sheet, l.start, rings, &[]).unwrap();
        assert_eq!(back.parts.len(), 3);
        assert_eq!(back.parts[0].holes.len(), 2);
        assert_eq!(back.parts[1].holes.len(), 1);
        assert_eq!(back.contour_count(), 6);
    }

    #[test]
    fn pierce_candidates_avoid_corners() {
        let opt = PierceOptions {
            max_candidates: 8,
            spacing_mm: 25.0,
            corner_angle_deg: 30.0,
            corner_margin_mm: 5.0,
            ..PierceOptions::default()
        };
        let sq = rect(0.0, 0.0, 100.0, 100.0).points;
        let c = free_pierce_candidates(&sq, &opt);
        assert_eq!(c.len(), 8, "free length 4·90 = 360 mm, capped at 8");
        for p in &c {
            for q in &sq {
                assert!(distance(*p, *q) >= 5.0 - 1e-9, "{p:?} near corner {q:?}");
            }
        }
        // A circle has no corners: candidates spread evenly over it.
        let circle: Vec<Point> = (0..64)
            .map(|i| {
                let a = i as f64 / 64.0 * std::f64::consts::TAU;
                [50.0 + 10.0 * a.cos(), 50.0 + 10.0 * a.sin()]
            })
            .collect();
        assert_eq!(free_pierce_candidates(&circle, &opt).len(), 3);
        // A tiny square: nothing is free, so the midpoint of the longest edge.
        let tiny = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]];
        assert_eq!(free_pierce_candidates(&tiny, &opt), vec![[2.0, 0.0]]);
        // A fixed pierce point is the only candidate.
        let mut l = paper_example();
        l.parts[2].outer.pierce = Some([300.0, 40.0]);
        let p = l.to_problem(PrecedenceMode::Strict, &opt).unwrap();
        assert_eq!(p.contours[5].pierce_candidates, vec![[300.0, 40.0]]);
    }

    #[test]
    fn fixed_pierce_points_must_lead_in_from_scrap() {
        let opt = PierceOptions::default();
        let refused = |part: usize, hole: Option<usize>, at: Point| {
            let mut l = paper_example();
            let ring = match hole {
                Some(h) => &mut l.parts[part].holes[h],
                None => &mut l.parts[part].outer,
            };
            ring.pierce = Some(at);
            l.to_problem(PrecedenceMode::Strict, &opt)
                .err()
                .map(|e| e.to_string())
        };
        // D3's outer is the square (300, 20)–(350, 70).
        assert_eq!(
            refused(2, None, [295.0, 40.0]),
            None,
            "5 mm lead-in from outside"
        );
        assert_eq!(refused(2, None, [300.0, 40.0]), None, "on the contour");
        let e = refused(2, None, [310.0, 40.0]).unwrap();
        assert!(e.contains("D3") && e.contains("inside the part"), "{e}");
        let e = refused(2, None, [280.0, 40.0]).unwrap();
        assert!(e.contains("20.000 mm from its contour"), "{e}");
        let e = refused(2, None, [f64::NAN, 40.0]).unwrap();
        assert!(e.contains("not finite"), "{e}");
        // D1's second hole is (200, 20)–(240, 60): pierce it from inside.
        assert_eq!(refused(0, Some(1), [205.0, 40.0]), None);
        let e = refused(0, Some(1), [197.0, 40.0]).unwrap();
        assert!(
            e.contains("holes[1]") && e.contains("pierce a hole from inside"),
            "{e}"
        );
    }
}
