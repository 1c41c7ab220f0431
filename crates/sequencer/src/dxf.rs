//! DXF input for nested layouts (issue 7; seed 003 §A1 contours `C_ij`), read with the `dxf`
//! crate.
//!
//! **Entities.** LWPOLYLINE and POLYLINE (bulges become arcs), LINE, ARC, CIRCLE, ELLIPSE
//! and SPLINE (flattened to [`DxfOptions::chord_tol_mm`]), and INSERT (the block's entities,
//! scaled, rotated, arrayed and mirrored as the insert says; nested blocks too). Annotation
//! (text, dimensions, leaders, points, images, hatches, construction lines) is ignored; any
//! other geometry (3DFACE, SOLID, REGION, MLINE, polyface meshes, …) is
//! [`DxfError::Unsupported`] naming the entity, so no outline is silently lost. Closed
//! polylines, circles and full ellipses are contours on their own. Open polylines, LINEs and ARCs are **chained**: an endpoint joins another
//! entity's endpoint within [`DxfOptions::join_tol_mm`] (either direction; pieces are reversed
//! as needed) until the chain returns to its start. A chain that cannot close is
//! [`DxfError::OpenChain`], naming its entities (type, handle, layer) and the dangling end.
//!
//! **Arcs** are flattened to polylines whose chords deviate from the arc by at most
//! [`DxfOptions::chord_tol_mm`] (`cavalier_contours::arcs_to_approx_lines`). Entities with an
//! extrusion direction of −Z (mirrored OCS) are mirrored back (x → −x, bulge → −bulge).
//!
//! **Roles.** Whether a contour is an outer contour or a hole, and of which part, comes from
//! the containment tree ([`Layout::from_rings`]), not from layers or colours.
//!
//! **Sheet** (issue 19, item 1: the program cuts where the drawing says). The first rule that
//! applies ([`SheetRule`]): [`DxfOptions::sheet`] if given (the sheet spans `[0, a] × [0, b]`
//! of the drawing); else the bounding box of the closed contour on layer
//! [`DxfOptions::sheet_layer`]; else the header's `$LIMMIN`/`$LIMMAX`, else its
//! `$EXTMIN`/`$EXTMAX`, when set (not the ±1e20 placeholders, not empty, not the default
//! limits 0,0–12,9) and containing every contour; else the contours' bounding box. The layout's
//! points are relative to that box's lower-left corner and [`Layout::origin`] is the corner, so
//! the program (origin + point) cuts every contour at the drawing's own coordinates.

use std::collections::HashMap;
use std::path::Path;

use cavalier_contours::polyline::{PlineCreation, PlineSource, PlineSourceMut, Polyline};
use dxf::entities::{Entity, EntityType};
use dxf::Drawing;

use crate::containment::bbox;
use crate::layout::{Layout, LayoutError};
use crate::placement::SheetRule;
use crate::problem::{distance, Point};

/// DXF reading options (issue 7).
#[derive(Debug, Clone, PartialEq)]
pub struct DxfOptions {
    /// Maximum distance between an arc and its flattening chords, mm. 0.005 by default: the
    /// cut path must stay within 0.02 mm of the drawn arc offset by half the kerf (issue 19),
    /// and the emitter's arc fitting spends most of that.
    pub chord_tol_mm: f64,
    /// Endpoints closer than this are joined when chaining, mm.
    pub join_tol_mm: f64,
    /// Sheet size `a × b`, mm (overrides the sheet layer).
    pub sheet: Option<[f64; 2]>,
    /// Layer whose closed contour is the sheet outline (case-insensitive).
    pub sheet_layer: String,
    /// `P_start`, mm, in sheet coordinates.
    pub start: Point,
}

impl Default for DxfOptions {
    fn default() -> Self {
        DxfOptions {
            chord_tol_mm: 0.005,
            join_tol_mm: 0.01,
            sheet: None,
            sheet_layer: "SHEET".into(),
            start: [0.0, 0.0],
        }
    }
}

/// One source entity of a contour (issue 7: errors name the entity), for error messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EntityRef {
    /// `LINE`, `ARC`, `CIRCLE`, `LWPOLYLINE`, `POLYLINE`, or `SEGMENT` for other sources.
    pub kind: String,
    /// The DXF handle (hex), empty if the file has none.
    pub handle: String,
    /// The layer.
    pub layer: String,
}

impl std::fmt::Display for EntityRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} #{} on layer '{}'",
            self.kind, self.handle, self.layer
        )
    }
}

fn describe(entities: &[EntityRef]) -> String {
    const SHOWN: usize = 4;
    let mut s: Vec<String> = entities.iter().take(SHOWN).map(|e| e.to_string()).collect();
    if entities.len() > SHOWN {
        s.push(format!("and {} more", entities.len() - SHOWN));
    }
    s.join(", ")
}

/// Errors reading a DXF layout (issue 7).
#[derive(Debug, thiserror::Error)]
pub enum DxfError {
    /// The file cannot be read or parsed by the `dxf` crate.
    #[error("{path}: {message}")]
    Read {
        /// The file.
        path: String,
        /// The parser's message.
        message: String,
    },
    /// Chained entities do not close.
    #[error("{path}: open contour: {} (end at ({:.3}, {:.3}) mm joins nothing within {tol_mm} mm)", describe(.entities), .end[0], .end[1])]
    OpenChain {
        /// The file.
        path: String,
        /// The entities of the open chain, in chain order.
        entities: Vec<EntityRef>,
        /// The dangling end, mm.
        end: Point,
        /// The join tolerance used, mm.
        tol_mm: f64,
    },
    /// A contour is invalid (self-intersecting, degenerate, off the sheet) or the nesting is
    /// inconsistent; the message names the entities.
    #[error("{path}: {source}")]
    Layout {
        /// The file.
        path: String,
        /// The cause.
        source: LayoutError,
    },
    /// A JSON layout cannot be read or does not parse ([`LayoutError::Io`],
    /// [`LayoutError::Json`]: they name the file, and the line and field).
    #[error(transparent)]
    Json(LayoutError),
    /// A non-finite coordinate or parameter.
    #[error("{path}: {entity}: non-finite coordinate")]
    NonFinite {
        /// The file.
        path: String,
        /// The entity.
        entity: EntityRef,
    },
    /// The drawing expands beyond a limit ([`MAX_PLACED_ENTITIES`], [`MAX_POINTS`],
    /// [`MAX_ARC_RADIUS_MM`]); names the entity (for nested INSERTs, the drawing's INSERT
    /// whose expansion crossed it) and the limit.
    #[error("{path}: {entity}: {reason}")]
    TooLarge {
        /// The file.
        path: String,
        /// The entity (boxed: keeps the error as small as the others).
        entity: Box<EntityRef>,
        /// What it would take, then `the limit is … (CONSTANT_NAME)`.
        reason: String,
    },
    /// Geometry the reader cannot turn into contours, or an entity it cannot use.
    #[error("{path}: {entity}: {reason}")]
    Unsupported {
        /// The file.
        path: String,
        /// The entity.
        entity: EntityRef,
        /// Why, and what to do about it.
        reason: String,
    },
}

/// Blocks inside blocks deeper than this are taken for a cycle.
const MAX_BLOCK_DEPTH: usize = 16;

/// Most entities one drawing may place, counted across INSERT recursion (every entity of a
/// block once per array cell of every INSERT above it, annotation included) (issue 23: an
/// 18 KB file of 8 nested 10 × 10 arrays places 10¹⁶). A large nested sheet holds ~500 parts
/// of ~50 entities (25 000); the limit is 10× that, and its pieces stay well under 100 MB.
pub const MAX_PLACED_ENTITIES: usize = 250_000;

/// Most contour points one drawing may flatten to (vertices, and arcs, circles, ellipses and
/// splines at [`DxfOptions::chord_tol_mm`]) (issue 23). A 500-part sheet at the default
/// tolerance has ~2·10⁵ (a 100 mm radius circle is ~300 points); the limit is 5× that and
/// keeps the containment and precedence steps within seconds.
pub const MAX_POINTS: usize = 1_000_000;

/// Largest arc radius flattened, mm: 1000× a 10 m sheet, beyond any cutting table (issue 23).
/// An arc this flat whose sagitta is within the chord tolerance is its chord (that is what
/// the tolerance allows); a larger one is refused: at `tol/r` below ~10⁻¹² the chord-angle
/// formula `2·acos(1 − tol/r)` loses its digits, and such an arc spans kilometres.
pub const MAX_ARC_RADIUS_MM: f64 = 1e7;

/// A 2-D affine map `p ↦ A·p + t` (row-major `[a, b, tx, c, d, ty]`), the placement of an
/// INSERT's block.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Placement([f64; 6]);

impl Placement {
    const IDENTITY: Placement = Placement([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);

    fn apply(&self, p: Point) -> Point {
        let m = &self.0;
        [
            m[0] * p[0] + m[1] * p[1] + m[2],
            m[3] * p[0] + m[4] * p[1] + m[5],
        ]
    }

    /// `self ∘ inner`: first `inner`, then `self`.
    fn then(&self, inner: &Placement) -> Placement {
        let (a, b) = (&self.0, &inner.0);
        Placement([
            a[0] * b[0] + a[1] * b[3],
            a[0] * b[1] + a[1] * b[4],
            a[0] * b[2] + a[1] * b[5] + a[2],
            a[3] * b[0] + a[4] * b[3],
            a[3] * b[1] + a[4] * b[4],
            a[3] * b[2] + a[4] * b[5] + a[5],
        ])
    }

    fn det(&self) -> f64 {
        self.0[0] * self.0[4] - self.0[1] * self.0[3]
    }

    /// Whether circles stay circles (rotation, uniform scale, mirror), so bulges survive.
    fn is_similarity(&self) -> bool {
        let m = &self.0;
        let (c0, c1) = (m[0] * m[0] + m[3] * m[3], m[1] * m[1] + m[4] * m[4]);
        let dot = m[0] * m[1] + m[3] * m[4];
        (c0 - c1).abs() <= 1e-12 * c0.max(c1) && dot.abs() <= 1e-12 * c0.max(c1)
    }

    /// The largest stretch factor, for scaling the chord tolerance.
    fn max_scale(&self) -> f64 {
        let m = &self.0;
        (m[0] * m[0] + m[3] * m[3])
            .sqrt()
            .max((m[1] * m[1] + m[4] * m[4]).sqrt())
    }

    /// Places a piece: vertices mapped; bulges kept (negated by a mirror) under a similarity,
    /// arcs flattened first under any other map (an arc sheared or stretched is no arc).
    fn place(&self, piece: Piece, chord_tol_mm: f64) -> Piece {
        if *self == Placement::IDENTITY {
            return piece;
        }
        let piece = if self.is_similarity() || piece.vertices.iter().all(|v| v[2] == 0.0) {
            piece
        } else {
            let tol = chord_tol_mm / self.max_scale().max(1e-12);
            let pts = flatten_path(&piece.vertices, piece.closed, tol);
            Piece {
                vertices: pts.iter().map(|p| [p[0], p[1], 0.0]).collect(),
                ..piece
            }
        };
        let flip = if self.det() < 0.0 { -1.0 } else { 1.0 };
        Piece {
            vertices: piece
                .vertices
                .iter()
                .map(|v| {
                    let q = self.apply([v[0], v[1]]);
                    [q[0], q[1], flip * v[2]]
                })
                .collect(),
            ..piece
        }
    }
}

/// A run of polyline vertices `(x, y, bulge)` from its sources (a piece of a contour `C_ij`,
/// seed 003 §A1; issue 7 chaining); in an open piece the last
/// bulge is unused, in a closed one it is the closing segment's.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// Vertices `[x, y, bulge]`, mm.
    pub vertices: Vec<[f64; 3]>,
    /// Whether the piece is already a closed contour.
    pub closed: bool,
    /// Where it came from.
    pub sources: Vec<EntityRef>,
}

impl Piece {
    fn first(&self) -> Point {
        [self.vertices[0][0], self.vertices[0][1]]
    }
    fn last(&self) -> Point {
        let v = self.vertices[self.vertices.len() - 1];
        [v[0], v[1]]
    }
    /// The same path walked backwards (bulges negated and moved to the new segment starts).
    fn reversed(&self) -> Piece {
        let m = self.vertices.len();
        let vertices = (0..m)
            .map(|i| {
                let v = self.vertices[m - 1 - i];
                let bulge = if i + 1 < m {
                    -self.vertices[m - 2 - i][2]
                } else {
                    0.0
                };
                [v[0], v[1], bulge]
            })
            .collect();
        let mut sources = self.sources.clone();
        sources.reverse();
        Piece {
            vertices,
            closed: self.closed,
            sources,
        }
    }
}

/// Chains open pieces into closed ones by joining endpoints within `tol_mm` (issue 7). Closed
/// input pieces pass through; straight two-point pieces no longer than `tol_mm` are dropped.
///
/// # Errors
/// The first chain that cannot close, with the end that found no partner.
pub fn chain_pieces(pieces: Vec<Piece>, tol_mm: f64) -> Result<Vec<Piece>, (Piece, Point)> {
    let tol = tol_mm.max(1e-12);
    let (mut closed, mut open): (Vec<Piece>, Vec<Piece>) =
        pieces.into_iter().partition(|p| p.closed);
    // A straight piece no longer than the tolerance joins both its neighbours' ends at once
    // and would strand itself; it carries no geometry at this tolerance, so it is dropped.
    open.retain(|p| {
        p.vertices.len() > 2 || p.vertices[0][2] != 0.0 || distance(p.first(), p.last()) > tol
    });
    let key = |p: Point| ((p[0] / tol).floor() as i64, (p[1] / tol).floor() as i64);
    let mut index: HashMap<(i64, i64), Vec<(usize, bool)>> = HashMap::new();
    for (i, p) in open.iter().enumerate() {
        index.entry(key(p.first())).or_default().push((i, false));
        index.entry(key(p.last())).or_default().push((i, true));
    }
    let mut used = vec![false; open.len()];
    let find = |at: Point, used: &[bool]| -> Option<(usize, bool)> {
        let (kx, ky) = key(at);
        let mut best: Option<(f64, usize, bool)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for &(j, is_end) in index.get(&(kx + dx, ky + dy)).into_iter().flatten() {
                    if used[j] {
                        continue;
                    }
                    let q = if is_end {
                        open[j].last()
                    } else {
                        open[j].first()
                    };
                    let d = distance(at, q);
                    if d <= tol && best.is_none_or(|(bd, bj, _)| (d, j) < (bd, bj)) {
                        best = Some((d, j, is_end));
                    }
                }
            }
        }
        best.map(|(_, j, e)| (j, e))
    };
    for i in 0..open.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let mut chain = open[i].clone();
        loop {
            let end = chain.last();
            if chain.vertices.len() >= 3 && distance(end, chain.first()) <= tol {
                chain.vertices.pop();
                chain.closed = true;
                closed.push(chain);
                break;
            }
            let Some((j, at_end)) = find(end, &used) else {
                return Err((chain, end));
            };
            used[j] = true;
            let next = if at_end {
                open[j].reversed()
            } else {
                open[j].clone()
            };
            let last = chain.vertices.len() - 1;
            chain.vertices[last][2] = next.vertices[0][2];
            chain.vertices.extend_from_slice(&next.vertices[1..]);
            chain.sources.extend(next.sources);
        }
    }
    Ok(closed)
}

/// Flattens a closed piece's arcs to chords within `chord_tol_mm` (cavalier_contours), giving
/// the polyline contour `C_ij` of seed 003 §A1 (issue 7: arcs flattened to a chord tolerance).
pub fn flatten(piece: &Piece, chord_tol_mm: f64) -> Vec<Point> {
    flatten_path(&piece.vertices, true, chord_tol_mm)
}

/// Flattens `[x, y, bulge]` vertices, open or closed, to chords within `chord_tol_mm`.
fn flatten_path(vertices: &[[f64; 3]], closed: bool, chord_tol_mm: f64) -> Vec<Point> {
    let tol = chord_tol_mm.max(MIN_CHORD_TOL_MM);
    let vertices = &split_major_arcs(vertices, closed);
    let mut p: Polyline<f64> = Polyline::with_capacity(vertices.len(), closed);
    for (i, v) in vertices.iter().enumerate() {
        let next = vertices.get(i + 1).or(closed.then_some(&vertices[0]));
        // An arc whose sagitta is within the tolerance is its own chord (and a very flat one
        // would lose cavalier_contours' `acos(1 − tol/r)` to rounding).
        let flat = next.is_none_or(|w| arc_sagitta(v, w) <= tol);
        p.add(v[0], v[1], if flat { 0.0 } else { v[2] });
    }
    let lines = if p.iter_vertexes().any(|v| v.bulge != 0.0) {
        p.arcs_to_approx_lines(tol).unwrap_or(p)
    } else {
        p
    };
    lines.iter_vertexes().map(|v| [v.x, v.y]).collect()
}

/// The same path with every arc over 180° (|bulge| > 1) split at its midpoint into two.
/// `cavalier_contours` 0.9 flattens an arc through the smaller angle between its end points
/// (`delta_angle`), which for a major arc is the wrong side of the circle.
fn split_major_arcs(vertices: &[[f64; 3]], closed: bool) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(vertices.len());
    for (i, v) in vertices.iter().enumerate() {
        let next = vertices.get(i + 1).or(closed.then_some(&vertices[0]));
        match next {
            Some(w) if v[2].abs() > 1.0 => {
                // The arc's midpoint lies a sagitta off the chord's midpoint, to the right of
                // v → w for a counter-clockwise (positive) bulge; each half sweeps θ/2, so
                // its bulge is tan(θ/8) = tan(atan|b| / 2).
                let (dx, dy) = (w[0] - v[0], w[1] - v[1]);
                let s = v[2] / 2.0;
                let mid = [0.5 * (v[0] + w[0]) + s * dy, 0.5 * (v[1] + w[1]) - s * dx];
                let half = v[2].signum() * (v[2].abs().atan() / 2.0).tan();
                out.push([v[0], v[1], half]);
                out.push([mid[0], mid[1], half]);
            }
            _ => out.push(*v),
        }
    }
    out
}

/// The finest chord tolerance flattening uses, mm.
const MIN_CHORD_TOL_MM: f64 = 1e-6;

/// The sagitta of the arc from `v` (bulge `v[2]`) to `w`: `|bulge|·c/2` for chord `c`, the
/// largest distance between the arc and its chord.
fn arc_sagitta(v: &[f64; 3], w: &[f64; 3]) -> f64 {
    v[2].abs() * distance([v[0], v[1]], [w[0], w[1]]) / 2.0
}

/// How many points [`flatten_path`] makes of `piece` at `chord_tol_mm` once a placement
/// stretching it by at most `scale` is applied: one per vertex, plus per arc of radius `r`
/// and sweep `θ` (`θ = 4·atan|bulge|`) `⌈θ / 2·acos(1 − tol/r)⌉ − 1` (cavalier_contours'
/// count), none for an arc within the tolerance of its chord.
///
/// # Errors
/// The radius (mm) of an arc larger than [`MAX_ARC_RADIUS_MM`] that is not within the
/// tolerance of its chord.
fn flattened_points(piece: &Piece, chord_tol_mm: f64, scale: f64) -> Result<usize, f64> {
    let tol = chord_tol_mm.max(MIN_CHORD_TOL_MM);
    let v = &split_major_arcs(&piece.vertices, piece.closed);
    let mut count = v.len();
    for (i, a) in v.iter().enumerate() {
        let Some(b) = v.get(i + 1).or(piece.closed.then_some(&v[0])) else {
            break;
        };
        let sagitta = scale * arc_sagitta(a, b);
        if a[2] == 0.0 || sagitta <= tol {
            continue;
        }
        let chord = scale * distance([a[0], a[1]], [b[0], b[1]]);
        let sweep = 4.0 * a[2].abs().atan();
        let radius = chord / (2.0 * (sweep / 2.0).sin());
        if radius.is_nan() || radius > MAX_ARC_RADIUS_MM {
            return Err(radius);
        }
        let step = 2.0 * (1.0 - tol / radius).acos();
        count = count.saturating_add(((sweep / step).ceil() as usize).saturating_sub(1));
    }
    Ok(count)
}

/// Reads a DXF file into a [`Layout`] (module docs; issue 7, seed 003 §A1).
///
/// # Errors
/// [`DxfError`], naming the file and, where it applies, the entities.
pub fn read_dxf(path: impl AsRef<Path>, opt: &DxfOptions) -> Result<Layout, DxfError> {
    let path = path.as_ref();
    let drawing = load_drawing(path)?;
    layout_from_drawing(&drawing, &path.display().to_string(), opt)
}

fn load_drawing(path: &Path) -> Result<Drawing, DxfError> {
    Drawing::load_file(path).map_err(|e| DxfError::Read {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}

/// Reads a layout from a `.dxf` file ([`read_dxf`]) or, for any other extension, from the
/// JSON format ([`Layout::from_json_file`]) (issue 7: `--layout FILE.dxf|json`).
///
/// # Errors
/// [`DxfError`]; JSON errors come as [`DxfError::Json`].
pub fn read_layout(path: impl AsRef<Path>, opt: &DxfOptions) -> Result<Layout, DxfError> {
    read_layout_with_rule(path, opt).map(|(layout, _)| layout)
}

/// As [`read_layout`], with the rule that found the sheet ([`SheetRule::Layout`] for JSON).
///
/// # Errors
/// As [`read_layout`].
pub fn read_layout_with_rule(
    path: impl AsRef<Path>,
    opt: &DxfOptions,
) -> Result<(Layout, SheetRule), DxfError> {
    let path = path.as_ref();
    let is_dxf = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("dxf"));
    if is_dxf {
        let drawing = load_drawing(path)?;
        layout_from_drawing_with_rule(&drawing, &path.display().to_string(), opt)
    } else {
        let layout = Layout::from_json_file(path).map_err(DxfError::Json)?;
        Ok((layout, SheetRule::Layout))
    }
}

/// Converts a loaded drawing into a [`Layout`] (issue 7, seed 003 §A1); `name` names the
/// source in errors.
///
/// # Errors
/// As [`read_dxf`].
pub fn layout_from_drawing(
    drawing: &Drawing,
    name: &str,
    opt: &DxfOptions,
) -> Result<Layout, DxfError> {
    layout_from_drawing_with_rule(drawing, name, opt).map(|(layout, _)| layout)
}

/// As [`layout_from_drawing`], with the rule that found the sheet (module docs).
///
/// # Errors
/// As [`read_dxf`].
pub fn layout_from_drawing_with_rule(
    drawing: &Drawing,
    name: &str,
    opt: &DxfOptions,
) -> Result<(Layout, SheetRule), DxfError> {
    let mut pieces = Vec::new();
    let mut reader = Reader {
        drawing,
        name,
        opt,
        pieces: &mut pieces,
        placed: 0,
        points: 0,
        root: None,
    };
    reader.collect(drawing.entities(), &Placement::IDENTITY, None, 0)?;
    let closed =
        chain_pieces(pieces, opt.join_tol_mm).map_err(|(chain, end)| DxfError::OpenChain {
            path: name.into(),
            entities: chain.sources,
            end,
            tol_mm: opt.join_tol_mm,
        })?;
    let mut rings = Vec::new();
    let mut names = Vec::new();
    let mut sheet_box = None;
    for piece in &closed {
        let ring = flatten(piece, opt.chord_tol_mm);
        let on_sheet_layer = piece
            .sources
            .iter()
            .all(|s| s.layer.eq_ignore_ascii_case(&opt.sheet_layer));
        if on_sheet_layer && sheet_box.is_none() {
            sheet_box = Some(bbox(&ring));
            continue;
        }
        names.push(describe(&piece.sources));
        rings.push(ring);
    }
    let all: Vec<Point> = rings.iter().flatten().copied().collect();
    let (rule, sheet_box) = match (opt.sheet, sheet_box) {
        (Some(s), _) => (SheetRule::Option, [0.0, 0.0, s[0], s[1]]),
        (None, Some(b)) => (SheetRule::SheetLayer, b),
        (None, None) if all.is_empty() => (SheetRule::Parts, [0.0, 0.0, 1.0, 1.0]),
        (None, None) => header_sheet(drawing, bbox(&all)),
    };
    // Sheet-relative inside; the origin gives the drawing's coordinates back.
    let origin = [sheet_box[0], sheet_box[1]];
    let sheet = [sheet_box[2] - sheet_box[0], sheet_box[3] - sheet_box[1]];
    for ring in &mut rings {
        for p in ring.iter_mut() {
            p[0] -= origin[0];
            p[1] -= origin[1];
        }
    }
    let mut layout =
        Layout::from_rings(sheet, opt.start, rings, &names).map_err(|source| DxfError::Layout {
            path: name.into(),
            source,
        })?;
    layout.origin = origin;
    Ok((layout, rule))
}

/// The sheet from the DXF header when there is no sheet contour (module docs): `$LIMMIN`/
/// `$LIMMAX`, else `$EXTMIN`/`$EXTMAX`, the first that is set and contains `parts` (the parts'
/// bounding box `[x0, y0, x1, y1]`), else `parts` itself.
fn header_sheet(drawing: &Drawing, parts: [f64; 4]) -> (SheetRule, [f64; 4]) {
    let h = &drawing.header;
    let boxes = [
        (
            SheetRule::Limits,
            &h.minimum_drawing_limits,
            &h.maximum_drawing_limits,
        ),
        (
            SheetRule::Extents,
            &h.minimum_drawing_extents,
            &h.maximum_drawing_extents,
        ),
    ];
    for (rule, lo, hi) in boxes {
        let b = [lo.x, lo.y, hi.x, hi.y];
        // Unset headers hold 0 × 0 boxes, ±1e20 placeholders, or the dxf crate's (and
        // AutoCAD's imperial) default limits 0,0–12,9.
        let set = b.iter().all(|v| v.is_finite() && v.abs() < 1e19)
            && b[2] > b[0]
            && b[3] > b[1]
            && !(rule == SheetRule::Limits && b == [0.0, 0.0, 12.0, 9.0]);
        let eps = HEADER_BOX_EPS_MM;
        let contains = b[0] <= parts[0] + eps
            && b[1] <= parts[1] + eps
            && b[2] >= parts[2] - eps
            && b[3] >= parts[3] - eps;
        if set && contains {
            // Clamped to the parts: a box a rounding error short is taken as touching them.
            let b = [
                b[0].min(parts[0]),
                b[1].min(parts[1]),
                b[2].max(parts[2]),
                b[3].max(parts[3]),
            ];
            return (rule, b);
        }
    }
    (SheetRule::Parts, parts)
}

/// A header box within this of the parts' extent still contains them, mm (header values are
/// often written with fewer digits than the geometry).
const HEADER_BOX_EPS_MM: f64 = 1e-3;

/// Walks entities (and the blocks INSERTs place) into [`Piece`]s.
struct Reader<'a> {
    drawing: &'a Drawing,
    name: &'a str,
    opt: &'a DxfOptions,
    pieces: &'a mut Vec<Piece>,
    /// Entities placed so far, across INSERT recursion ([`MAX_PLACED_ENTITIES`]).
    placed: usize,
    /// Flattened points so far ([`MAX_POINTS`]).
    points: usize,
    /// The drawing-level entity being expanded (limits name it for nested INSERTs).
    root: Option<EntityRef>,
}

/// The INSERT a block's entities are placed by: its block name, handle and layer.
#[derive(Clone)]
struct Via {
    block: String,
    handle: String,
    layer: String,
}

impl Reader<'_> {
    fn collect<'e>(
        &mut self,
        entities: impl Iterator<Item = &'e Entity>,
        at: &Placement,
        via: Option<&Via>,
        depth: usize,
    ) -> Result<(), DxfError> {
        for e in entities {
            let mut source = EntityRef {
                kind: entity_kind(e).into(),
                handle: e.common.handle.as_string(),
                layer: e.common.layer.clone(),
            };
            if let Some(v) = via {
                source.kind = format!(
                    "{} (block '{}' placed by INSERT #{})",
                    source.kind, v.block, v.handle
                );
                // Block entities on layer 0 take the layer of their INSERT (DXF rule).
                if source.layer == "0" {
                    source.layer = v.layer.clone();
                }
            }
            if depth == 0 {
                self.root = Some(match &e.specific {
                    EntityType::Insert(ins) => EntityRef {
                        kind: format!("INSERT of block '{}'", ins.name),
                        ..source.clone()
                    },
                    _ => source.clone(),
                });
            }
            // Limits name the drawing's entity whose expansion crosses them.
            let too_large = |what: String, limit: String, name: &'static str| DxfError::TooLarge {
                path: self.name.into(),
                entity: Box::new(self.root.clone().unwrap_or_else(|| source.clone())),
                reason: format!("{what}: the limit is {limit} ({name})"),
            };
            self.placed += 1;
            if self.placed > MAX_PLACED_ENTITIES {
                let what = if depth == 0 {
                    format!("the drawing places more than {MAX_PLACED_ENTITIES} entities")
                } else {
                    format!(
                        "expanding it places more than {MAX_PLACED_ENTITIES} entities (INSERT \
                         arrays multiply: rows × columns at each of its {depth} nesting levels)"
                    )
                };
                return Err(too_large(
                    what,
                    format!("{MAX_PLACED_ENTITIES} placed entities"),
                    "MAX_PLACED_ENTITIES",
                ));
            }
            let unsupported = |reason: String| DxfError::Unsupported {
                path: self.name.into(),
                entity: source.clone(),
                reason,
            };
            if let EntityType::Insert(ins) = &e.specific {
                if depth >= MAX_BLOCK_DEPTH {
                    return Err(unsupported(format!(
                        "blocks nested more than {MAX_BLOCK_DEPTH} deep (a block that contains itself?)"
                    )));
                }
                let block = self
                    .drawing
                    .blocks()
                    .find(|b| b.name.eq_ignore_ascii_case(&ins.name))
                    .ok_or_else(|| unsupported(format!("block '{}' is not defined", ins.name)))?;
                let placements = insert_placements(ins, [block.base_point.x, block.base_point.y])
                    .map_err(unsupported)?;
                let inner = Via {
                    block: block.name.clone(),
                    handle: source.handle.clone(),
                    layer: source.layer.clone(),
                };
                for p in placements {
                    self.collect(block.entities.iter(), &at.then(&p), Some(&inner), depth + 1)?;
                }
                continue;
            }
            // The entity itself, when the limit names the INSERT that placed it.
            let inner = if depth > 0 {
                format!("{source}: ")
            } else {
                String::new()
            };
            let tol = self.opt.chord_tol_mm;
            let piece =
                entity_piece(e, source.clone(), tol, at.max_scale()).map_err(|e| match e {
                    PieceError::Unsupported(reason) => unsupported(reason),
                    PieceError::TooLarge {
                        what,
                        limit,
                        constant,
                    } => too_large(format!("{inner}{what}"), limit, constant),
                })?;
            let Some(piece) = piece else {
                continue;
            };
            if piece.vertices.iter().flatten().any(|v| !v.is_finite()) {
                return Err(DxfError::NonFinite {
                    path: self.name.into(),
                    entity: source,
                });
            }
            let n = flattened_points(&piece, tol, at.max_scale()).map_err(|radius| {
                let what = format!(
                    "{inner}an arc of radius {radius:.3e} mm with a sagitta over the chord \
                     tolerance ({tol} mm) is too large to flatten"
                );
                too_large(
                    what,
                    format!("{MAX_ARC_RADIUS_MM:e} mm"),
                    "MAX_ARC_RADIUS_MM",
                )
            })?;
            self.points = self.points.saturating_add(n);
            if self.points > MAX_POINTS {
                let what = format!(
                    "{inner}flattened at {tol} mm it brings the drawing to more than \
                     {MAX_POINTS} points (this entity: {n})"
                );
                return Err(too_large(
                    what,
                    format!("{MAX_POINTS} points"),
                    "MAX_POINTS",
                ));
            }
            self.pieces.push(at.place(piece, self.opt.chord_tol_mm));
        }
        Ok(())
    }
}

/// The placements of an INSERT's block, one per array cell: `p ↦ location + R·(S·(p − base)
/// + (col·column_spacing, row·row_spacing))`, then mirrored in x when the extrusion is −Z.
fn insert_placements(ins: &dxf::entities::Insert, base: Point) -> Result<Vec<Placement>, String> {
    let values = [
        ins.location.x,
        ins.location.y,
        ins.x_scale_factor,
        ins.y_scale_factor,
        ins.rotation,
        ins.column_spacing,
        ins.row_spacing,
    ];
    if values.iter().any(|v| !v.is_finite()) {
        return Err("non-finite placement".into());
    }
    if ins.x_scale_factor == 0.0 || ins.y_scale_factor == 0.0 {
        return Err("zero scale factor".into());
    }
    let (cols, rows) = (ins.column_count.max(1), ins.row_count.max(1));
    if i32::from(cols) * i32::from(rows) > 10_000 {
        return Err(format!("array of {cols} × {rows} copies is too large"));
    }
    let (sin, cos) = ins.rotation.to_radians().sin_cos();
    let (sx, sy) = (ins.x_scale_factor, ins.y_scale_factor);
    let mirror = if ins.extrusion_direction.z < 0.0 {
        -1.0
    } else {
        1.0
    };
    let mut out = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let (ox, oy) = (
                f64::from(c) * ins.column_spacing,
                f64::from(r) * ins.row_spacing,
            );
            // Local: q = S·(p − base) + o; world: location + R·q.
            let local = Placement([sx, 0.0, ox - sx * base[0], 0.0, sy, oy - sy * base[1]]);
            let world = Placement([cos, -sin, ins.location.x, sin, cos, ins.location.y]);
            let flip = Placement([mirror, 0.0, 0.0, 0.0, 1.0, 0.0]);
            out.push(flip.then(&world.then(&local)));
        }
    }
    Ok(out)
}

/// The DXF name of an entity, for messages.
fn entity_kind(e: &Entity) -> &'static str {
    match &e.specific {
        EntityType::Line(_) => "LINE",
        EntityType::Arc(_) => "ARC",
        EntityType::Circle(_) => "CIRCLE",
        EntityType::Ellipse(_) => "ELLIPSE",
        EntityType::Spline(_) => "SPLINE",
        EntityType::LwPolyline(_) => "LWPOLYLINE",
        EntityType::Polyline(_) => "POLYLINE",
        EntityType::Insert(_) => "INSERT",
        EntityType::Face3D(_) => "3DFACE",
        EntityType::Solid3D(_) => "3DSOLID",
        EntityType::Body(_) => "BODY",
        EntityType::Region(_) => "REGION",
        EntityType::Helix(_) => "HELIX",
        EntityType::MLine(_) => "MLINE",
        EntityType::Solid(_) => "SOLID",
        EntityType::Trace(_) => "TRACE",
        EntityType::Wipeout(_) => "WIPEOUT",
        EntityType::ProxyEntity(_) => "ACAD_PROXY_ENTITY",
        EntityType::Text(_) => "TEXT",
        EntityType::MText(_) => "MTEXT",
        _ => "annotation",
    }
}

/// Why an entity gives no piece.
#[derive(Debug)]
enum PieceError {
    /// Geometry this reader cannot use: why, and what to do about it.
    Unsupported(String),
    /// Flattening it crosses a limit ([`DxfError::TooLarge`]).
    TooLarge {
        /// What it would take.
        what: String,
        /// The limit, with its unit.
        limit: String,
        /// The limit's constant.
        constant: &'static str,
    },
}

impl From<String> for PieceError {
    fn from(reason: String) -> Self {
        PieceError::Unsupported(reason)
    }
}

impl From<&str> for PieceError {
    fn from(reason: &str) -> Self {
        PieceError::Unsupported(reason.into())
    }
}

/// The polyline piece of one entity: `Ok(None)` for annotation, an error for geometry this
/// reader cannot use or whose flattening crosses a limit. ELLIPSE and SPLINE come flattened
/// so that, once placed by a map stretching by at most `scale`, their chords stay within
/// `chord_tol_mm` of the curve.
fn entity_piece(
    e: &Entity,
    source: EntityRef,
    chord_tol_mm: f64,
    scale: f64,
) -> Result<Option<Piece>, PieceError> {
    let closed_curve = |pts: Vec<Point>| -> Result<Option<Piece>, PieceError> {
        if pts.iter().flatten().any(|v| !v.is_finite()) {
            return Err("non-finite coordinate or parameter".into());
        }
        let closed = pts.len() > 2 && distance(pts[0], pts[pts.len() - 1]) <= 1e-9;
        let mut vertices: Vec<[f64; 3]> = pts.iter().map(|p| [p[0], p[1], 0.0]).collect();
        if closed {
            vertices.pop();
        }
        Ok(Some(Piece {
            vertices,
            closed,
            sources: vec![source.clone()],
        }))
    };
    // Mirrored object coordinate system (extrusion −Z): x → −x, arcs turn the other way.
    let mirror = |z: f64| if z < 0.0 { -1.0 } else { 1.0 };
    let (vertices, closed) = match &e.specific {
        EntityType::Line(l) => (vec![[l.p1.x, l.p1.y, 0.0], [l.p2.x, l.p2.y, 0.0]], false),
        EntityType::Arc(a) => {
            let m = mirror(a.normal.z);
            let (a0, a1) = (a.start_angle.to_radians(), a.end_angle.to_radians());
            let mut sweep = (a1 - a0).rem_euclid(std::f64::consts::TAU);
            if sweep <= 1e-12 {
                sweep = std::f64::consts::TAU;
            }
            let (c, r) = (a.center.clone(), a.radius);
            let at = |t: f64| [m * (c.x + r * t.cos()), c.y + r * t.sin()];
            let (p0, p1) = (at(a0), at(a1));
            if sweep >= std::f64::consts::TAU - 1e-12 {
                // A full-circle ARC is a circle.
                let (q, b) = (at(a0 + std::f64::consts::PI), m);
                (vec![[p0[0], p0[1], b], [q[0], q[1], b]], true)
            } else {
                let bulge = m * (sweep / 4.0).tan();
                (vec![[p0[0], p0[1], bulge], [p1[0], p1[1], 0.0]], false)
            }
        }
        EntityType::Circle(c) => {
            let m = mirror(c.normal.z);
            let (x, y, r) = (m * c.center.x, c.center.y, c.radius);
            (vec![[x - r, y, 1.0], [x + r, y, 1.0]], true)
        }
        EntityType::LwPolyline(p) => {
            let m = mirror(p.extrusion_direction.z);
            let v = p
                .vertices
                .iter()
                .map(|v| [m * v.x, v.y, m * v.bulge])
                .collect();
            (v, p.is_closed())
        }
        // Polyface and polygon meshes (flags 16, 64) are surfaces, not contours.
        EntityType::Polyline(p) if p.flags & (16 | 64) != 0 => {
            return Err(
                "a polyface or polygon mesh is a surface, not an outline; export \
                        the part's outline as polylines"
                    .into(),
            )
        }
        EntityType::Polyline(p) => {
            let m = mirror(p.normal.z);
            let v = p
                .vertices()
                .map(|v| [m * v.location.x, v.location.y, m * v.bulge])
                .collect();
            (v, p.is_closed())
        }
        EntityType::Ellipse(el) => {
            return closed_curve(flatten_ellipse(el, chord_tol_mm, scale)?);
        }
        EntityType::Spline(sp) => {
            let local_tol = chord_tol_mm.max(MIN_CHORD_TOL_MM) / scale.max(1e-12);
            return closed_curve(flatten_spline(sp, local_tol)?);
        }
        EntityType::Face3D(_)
        | EntityType::Solid3D(_)
        | EntityType::Body(_)
        | EntityType::Region(_)
        | EntityType::Helix(_)
        | EntityType::MLine(_)
        | EntityType::Solid(_)
        | EntityType::Trace(_)
        | EntityType::Wipeout(_)
        | EntityType::ProxyEntity(_) => {
            return Err(
                "this geometry cannot be read as a cutting contour; explode it to \
                        polylines, lines and arcs in the CAD program"
                    .into(),
            )
        }
        _ => return Ok(None),
    };
    if vertices.is_empty() {
        return Ok(None);
    }
    Ok(Some(Piece {
        vertices,
        closed,
        sources: vec![source],
    }))
}

/// Points along an ELLIPSE (WCS centre and major axis, minor axis `ratio · (n × major)`),
/// from its start to its end parameter, with chords deviating at most `chord_tol_mm` once
/// placed by a map stretching by at most `scale` (step `2·acos(1 − tol/a)` on the major
/// radius `a`, which bounds the deviation): `⌈sweep / step⌉ + 1` points, at least 9.
///
/// # Errors
/// Never coarsened to fit (issue 23): a major radius, placed, over [`MAX_ARC_RADIUS_MM`], or
/// a flattening of more than [`MAX_POINTS`] points, is [`PieceError::TooLarge`].
fn flatten_ellipse(
    el: &dxf::entities::Ellipse,
    chord_tol_mm: f64,
    scale: f64,
) -> Result<Vec<Point>, PieceError> {
    let (m, n) = (&el.major_axis, &el.normal);
    let given = [
        el.center.x,
        el.center.y,
        m.x,
        m.y,
        m.z,
        n.x,
        n.y,
        n.z,
        el.minor_axis_ratio,
        el.start_parameter,
        el.end_parameter,
    ];
    if given.iter().any(|v| !v.is_finite()) {
        return Err("non-finite coordinate or parameter".into());
    }
    let n_len = (n.x * n.x + n.y * n.y + n.z * n.z).sqrt();
    let (nx, ny, nz) = if n_len > 0.0 {
        (n.x / n_len, n.y / n_len, n.z / n_len)
    } else {
        (0.0, 0.0, 1.0)
    };
    let k = el.minor_axis_ratio;
    let minor = [k * (ny * m.z - nz * m.y), k * (nz * m.x - nx * m.z)];
    let a = (m.x * m.x + m.y * m.y).sqrt();
    let t0 = el.start_parameter;
    let mut sweep = (el.end_parameter - t0).rem_euclid(std::f64::consts::TAU);
    if sweep <= 1e-12 {
        sweep = std::f64::consts::TAU;
    }
    let placed_radius = a * scale;
    if placed_radius > MAX_ARC_RADIUS_MM {
        return Err(PieceError::TooLarge {
            what: format!(
                "an ellipse of major radius {placed_radius:.3e} mm is too large to flatten"
            ),
            limit: format!("{MAX_ARC_RADIUS_MM:e} mm"),
            constant: "MAX_ARC_RADIUS_MM",
        });
    }
    // In the ellipse's own units: the placement stretches the chords' deviation by `scale`.
    let tol = chord_tol_mm.max(MIN_CHORD_TOL_MM) / scale.max(1e-12);
    let step = if a > tol {
        2.0 * (1.0 - tol / a).acos()
    } else {
        std::f64::consts::FRAC_PI_2
    };
    // As f64 first: a step rounded to 0 gives infinitely many, refused below.
    let segments = (sweep / step).ceil().max(8.0);
    let points = segments + 1.0;
    if points > MAX_POINTS as f64 {
        return Err(PieceError::TooLarge {
            what: format!(
                "flattened at {chord_tol_mm} mm the ELLIPSE (major radius {placed_radius:.3e} \
                 mm) needs {points:.0} points"
            ),
            limit: format!("{MAX_POINTS} points"),
            constant: "MAX_POINTS",
        });
    }
    let count = segments as usize;
    let mut points: Vec<Point> = (0..=count)
        .map(|i| {
            let t = t0 + sweep * i as f64 / count as f64;
            let (s, c) = t.sin_cos();
            [
                el.center.x + c * m.x + s * minor[0],
                el.center.y + c * m.y + s * minor[1],
            ]
        })
        .collect();
    if sweep == std::f64::consts::TAU {
        // Closed exactly: sin(2π) ≠ 0 puts the last point microns off the first on a
        // kilometre ellipse, which would leave it open.
        points[count] = points[0];
    }
    Ok(points)
}

/// Points along a SPLINE (a NURBS curve of its degree, knots, control points and weights),
/// each knot span bisected until the chord's midpoint lies within `chord_tol_mm` of the curve.
///
/// Hand-written (de Boor's algorithm in homogeneous coordinates, about 30 lines): the NURBS
/// crates either lack rational curves or bring a geometry kernel this reader does not need.
fn flatten_spline(sp: &dxf::entities::Spline, chord_tol_mm: f64) -> Result<Vec<Point>, String> {
    let p = usize::try_from(sp.degree_of_curve).unwrap_or(0);
    let (knots, cps) = (&sp.knot_values, &sp.control_points);
    let n = cps.len();
    if n == 0 {
        return Err(
            "a SPLINE given by fit points only is not supported; convert it to a \
                    control-point spline or a polyline"
                .into(),
        );
    }
    if p == 0 || n <= p || knots.len() != n + p + 1 {
        return Err(format!(
            "invalid SPLINE: degree {}, {n} control points and {} knots (need degree ≥ 1, more \
             control points than the degree and control points + degree + 1 knots)",
            sp.degree_of_curve,
            knots.len()
        ));
    }
    if !sp.weight_values.is_empty() && sp.weight_values.len() != n {
        return Err(format!(
            "invalid SPLINE: {} weights for {n} control points",
            sp.weight_values.len()
        ));
    }
    if knots.iter().any(|k| !k.is_finite()) || knots.windows(2).any(|w| w[1] < w[0]) {
        return Err("invalid SPLINE: knots must be finite and non-decreasing".into());
    }
    let weight = |i: usize| sp.weight_values.get(i).copied().unwrap_or(1.0);
    if (0..n).any(|i| !weight(i).is_finite() || weight(i) <= 0.0) {
        return Err("invalid SPLINE: weights must be positive and finite".into());
    }
    // Homogeneous control points (w·x, w·y, w).
    let hom: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let w = weight(i);
            [w * cps[i].x, w * cps[i].y, w]
        })
        .collect();
    let at = |u: f64| -> Point {
        let mut k = p;
        while k < n - 1 && u >= knots[k + 1] {
            k += 1;
        }
        let mut d: Vec<[f64; 3]> = (0..=p).map(|j| hom[j + k - p]).collect();
        for r in 1..=p {
            for j in (r..=p).rev() {
                let i = j + k - p;
                let span = knots[i + p + 1 - r] - knots[i];
                let alpha = if span > 0.0 {
                    (u - knots[i]) / span
                } else {
                    0.0
                };
                let prev = d[j - 1];
                for (c, v) in d[j].iter_mut().enumerate() {
                    *v = (1.0 - alpha) * prev[c] + alpha * *v;
                }
            }
        }
        [d[p][0] / d[p][2], d[p][1] / d[p][2]]
    };
    let tol = chord_tol_mm.max(1e-6);
    let mut out = vec![at(knots[p])];
    for span in knots[p..=n].windows(2) {
        if span[1] <= span[0] {
            continue;
        }
        // Four pieces per span first (a cubic span can turn back on itself), then bisection.
        let mut stack: Vec<(f64, f64, u32)> = (0..4)
            .rev()
            .map(|q| {
                let h = (span[1] - span[0]) / 4.0;
                (span[0] + h * q as f64, span[0] + h * (q + 1) as f64, 0)
            })
            .collect();
        while let Some((u0, u1, depth)) = stack.pop() {
            let (a, b, mid) = (at(u0), at(u1), at(0.5 * (u0 + u1)));
            let chord_mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            if depth < 16 && distance(mid, chord_mid) > tol {
                let um = 0.5 * (u0 + u1);
                stack.push((um, u1, depth + 1));
                stack.push((u0, um, depth + 1));
            } else {
                out.push(b);
                if out.len() > MAX_POINTS {
                    return Err(format!(
                        "flattened at {tol} mm the SPLINE has more than {MAX_POINTS} points: \
                         the limit is {MAX_POINTS} points (MAX_POINTS)"
                    ));
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn src(k: &str) -> Vec<EntityRef> {
        vec![EntityRef {
            kind: k.into(),
            handle: "1".into(),
            layer: "0".into(),
        }]
    }

    fn seg(a: Point, b: Point, bulge: f64) -> Piece {
        Piece {
            vertices: vec![[a[0], a[1], bulge], [b[0], b[1], 0.0]],
            closed: false,
            sources: src("LINE"),
        }
    }

    #[test]
    fn chains_close_with_reversal_and_tolerance() {
        // A square from four segments, one reversed and one end off by 5 µm.
        let pieces = vec![
            seg([0.0, 0.0], [10.0, 0.0], 0.0),
            seg([10.0, 10.0], [10.0, 0.000_005], 0.0),
            seg([10.0, 10.0], [0.0, 10.0], 0.0),
            seg([0.0, 10.0], [0.0, 0.0], 0.0),
        ];
        let closed = chain_pieces(pieces, 0.01).unwrap();
        assert_eq!(closed.len(), 1);
        assert_eq!(closed[0].vertices.len(), 4);
        assert_eq!(closed[0].sources.len(), 4);
        let open = chain_pieces(vec![seg([0.0, 0.0], [1.0, 0.0], 0.0)], 0.01).unwrap_err();
        assert_eq!(open.1, [1.0, 0.0]);
    }

    #[test]
    fn self_intersecting_entity_is_named() {
        use dxf::entities::LwPolyline;
        use dxf::LwPolylineVertex;
        let mut d = Drawing::new();
        let mut lw = LwPolyline::default();
        for (x, y) in [(0.0, 0.0), (10.0, 10.0), (10.0, 0.0), (0.0, 4.0)] {
            lw.vertices.push(LwPolylineVertex {
                x,
                y,
                ..Default::default()
            });
        }
        lw.set_is_closed(true);
        let mut e = Entity::new(EntityType::LwPolyline(lw));
        e.common.layer = "BAD".into();
        d.add_entity(e);
        let opt = DxfOptions {
            sheet: Some([20.0, 20.0]),
            ..Default::default()
        };
        let err = layout_from_drawing(&d, "bow.dxf", &opt)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("bow.dxf: LWPOLYLINE #")
                && err.ends_with("on layer 'BAD': the contour intersects itself"),
            "{err}"
        );
    }

    fn circle(x: f64, y: f64, r: f64) -> Entity {
        Entity::new(EntityType::Circle(dxf::entities::Circle {
            center: dxf::Point::new(x, y, 0.0),
            radius: r,
            ..Default::default()
        }))
    }

    /// Degree-2 rational B-spline of a full circle: 9 control points on the square around it,
    /// corner weights √2/2 (the textbook exact NURBS circle).
    fn nurbs_circle(cx: f64, cy: f64, r: f64) -> Entity {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let sq = [
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (-1.0, 1.0),
            (-1.0, 0.0),
            (-1.0, -1.0),
            (0.0, -1.0),
            (1.0, -1.0),
            (1.0, 0.0),
        ];
        let mut sp = dxf::entities::Spline {
            degree_of_curve: 2,
            knot_values: vec![
                0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0,
            ],
            weight_values: (0..9).map(|i| if i % 2 == 1 { w } else { 1.0 }).collect(),
            control_points: sq
                .iter()
                .map(|&(x, y)| dxf::Point::new(cx + r * x, cy + r * y, 0.0))
                .collect(),
            ..Default::default()
        };
        sp.set_is_rational(true);
        sp.set_is_closed(true);
        Entity::new(EntityType::Spline(sp))
    }

    fn ring_areas(l: &Layout) -> Vec<f64> {
        let mut a: Vec<f64> = l
            .parts
            .iter()
            .flat_map(|p| std::iter::once(&p.outer).chain(&p.holes))
            .map(|r| cell_geometry::signed_area(&r.points).abs())
            .collect();
        a.sort_by(f64::total_cmp);
        a
    }

    #[test]
    fn ellipse_spline_and_nested_inserts_become_contours() {
        let mut d = Drawing::new();
        // A NURBS circle r = 50 as a part's outer contour, an ELLIPSE 20 × 10 as its hole.
        d.add_entity(nurbs_circle(100.0, 100.0, 50.0));
        d.add_entity(Entity::new(EntityType::Ellipse(dxf::entities::Ellipse {
            center: dxf::Point::new(100.0, 100.0, 0.0),
            major_axis: dxf::Vector::new(0.0, 20.0, 0.0),
            minor_axis_ratio: 0.5,
            ..Default::default()
        })));
        // Annotation is ignored.
        d.add_entity(Entity::new(EntityType::Text(dxf::entities::Text {
            value: "PART 1".into(),
            ..Default::default()
        })));
        // Block WASHER: a 6 × 6 square of LINEs (base (3, 3)) around a circle r = 1. Block
        // PAIR holds two WASHERs 10 mm apart; the drawing places PAIR scaled 2, rotated 90°,
        // as a 2-row array, so 4 washers (12 × 12 squares, r = 2 holes) at (300, 50 + …).
        let mut washer = dxf::Block {
            name: "WASHER".into(),
            base_point: dxf::Point::new(3.0, 3.0, 0.0),
            ..Default::default()
        };
        for (a, b) in [
            ((0., 0.), (6., 0.)),
            ((6., 0.), (6., 6.)),
            ((0., 6.), (6., 6.)),
            ((0., 0.), (0., 6.)),
        ] {
            washer
                .entities
                .push(Entity::new(EntityType::Line(dxf::entities::Line {
                    p1: dxf::Point::new(a.0, a.1, 0.0),
                    p2: dxf::Point::new(b.0, b.1, 0.0),
                    ..Default::default()
                })));
        }
        washer.entities.push(circle(3.0, 3.0, 1.0));
        d.add_block(washer);
        let mut pair = dxf::Block {
            name: "PAIR".into(),
            ..Default::default()
        };
        for x in [0.0, 10.0] {
            pair.entities
                .push(Entity::new(EntityType::Insert(dxf::entities::Insert {
                    name: "washer".into(), // block names are case-insensitive
                    location: dxf::Point::new(x, 0.0, 0.0),
                    ..Default::default()
                })));
        }
        d.add_block(pair);
        d.add_entity(Entity::new(EntityType::Insert(dxf::entities::Insert {
            name: "PAIR".into(),
            location: dxf::Point::new(300.0, 50.0, 0.0),
            x_scale_factor: 2.0,
            y_scale_factor: 2.0,
            rotation: 90.0,
            row_count: 2,
            row_spacing: 40.0,
            ..Default::default()
        })));
        // ELLIPSE and SPLINE exist from R13 on; the dxf crate writes R12 unless told.
        d.header.version = dxf::enums::AcadVersion::R2000;
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("mixed.dxf");
        d.save_file(&file).unwrap();
        let opt = DxfOptions {
            sheet: Some([400.0, 300.0]),
            chord_tol_mm: 0.01,
            ..Default::default()
        };
        let l = read_dxf(&file, &opt).unwrap();
        let mem = layout_from_drawing(&d, "mem", &opt).unwrap();
        assert_eq!(mem.parts.len(), 5, "in memory: {:?}", ring_areas(&mem));
        assert_eq!(
            l.parts.len(),
            5,
            "one round part and four washers: {:?}",
            ring_areas(&l)
        );
        let areas = ring_areas(&l);
        let pi = std::f64::consts::PI;
        let close = |got: f64, want: f64, rel: f64| (got - want).abs() <= rel * want;
        assert!(
            areas[..4].iter().all(|&a| close(a, pi * 4.0, 1e-2)),
            "{areas:?}"
        );
        assert!(
            areas[4..8].iter().all(|&a| close(a, 144.0, 1e-9)),
            "{areas:?}"
        );
        assert!(
            close(areas[8], pi * 200.0, 1e-3),
            "ellipse 20 × 10: {}",
            areas[8]
        );
        assert!(
            close(areas[9], pi * 2500.0, 1e-3),
            "NURBS circle r 50: {}",
            areas[9]
        );
        // Every flattened NURBS point lies on the circle within the chord tolerance.
        let round = l
            .parts
            .iter()
            .find(|p| p.holes.len() == 1 && p.outer.points.len() > 40);
        let outer = &round.expect("the round part").outer.points;
        for q in outer {
            let r = distance(*q, [100.0, 100.0]);
            assert!((r - 50.0).abs() < 1e-9, "NURBS point {q:?} at radius {r}");
        }
        // The washers: rotated 90° then arrayed along the rotated y (−x in the drawing).
        let mut centres: Vec<(i64, i64)> = l
            .parts
            .iter()
            .filter(|p| p.outer.points.len() == 4)
            .map(|p| {
                let b = bbox(&p.outer.points);
                (
                    ((b[0] + b[2]) / 2.0).round() as i64,
                    ((b[1] + b[3]) / 2.0).round() as i64,
                )
            })
            .collect();
        centres.sort();
        assert_eq!(centres, vec![(260, 50), (260, 70), (300, 50), (300, 70)]);
    }

    #[test]
    fn unreadable_geometry_and_missing_blocks_are_named() {
        let opt = DxfOptions {
            sheet: Some([100.0, 100.0]),
            ..Default::default()
        };
        let mut d = Drawing::new();
        d.add_entity(circle(50.0, 50.0, 10.0));
        let mut face = Entity::new(EntityType::Face3D(Default::default()));
        face.common.layer = "CUT".into();
        d.add_entity(face);
        let e = layout_from_drawing(&d, "f.dxf", &opt)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("f.dxf: 3DFACE #")
                && e.contains("on layer 'CUT': this geometry cannot be read"),
            "{e}"
        );
        let mut d = Drawing::new();
        d.add_entity(Entity::new(EntityType::Insert(dxf::entities::Insert {
            name: "NOPE".into(),
            ..Default::default()
        })));
        let e = layout_from_drawing(&d, "i.dxf", &opt)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("INSERT #") && e.ends_with("block 'NOPE' is not defined"),
            "{e}"
        );
        // A block that places itself.
        let mut d = Drawing::new();
        let mut b = dxf::Block {
            name: "LOOP".into(),
            ..Default::default()
        };
        b.entities
            .push(Entity::new(EntityType::Insert(dxf::entities::Insert {
                name: "LOOP".into(),
                ..Default::default()
            })));
        d.add_block(b);
        d.add_entity(Entity::new(EntityType::Insert(dxf::entities::Insert {
            name: "LOOP".into(),
            ..Default::default()
        })));
        let e = layout_from_drawing(&d, "l.dxf", &opt)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("block 'LOOP'") && e.contains("nested more than 16 deep"),
            "{e}"
        );
        // A spline given only by fit points.
        let mut d = Drawing::new();
        d.add_entity(Entity::new(EntityType::Spline(dxf::entities::Spline {
            degree_of_curve: 3,
            fit_points: vec![
                dxf::Point::new(1.0, 1.0, 0.0),
                dxf::Point::new(5.0, 5.0, 0.0),
            ],
            ..Default::default()
        })));
        let e = layout_from_drawing(&d, "s.dxf", &opt)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s.dxf: SPLINE #") && e.contains("fit points only"),
            "{e}"
        );
    }

    /// Every ring point in drawing coordinates (origin + sheet-relative), sorted.
    fn drawing_points(l: &Layout) -> Vec<[i64; 2]> {
        let mut v: Vec<[i64; 2]> = l
            .parts
            .iter()
            .flat_map(|p| std::iter::once(&p.outer).chain(&p.holes))
            .flat_map(|r| &r.points)
            .map(|q| {
                let m = [q[0] + l.origin[0], q[1] + l.origin[1]];
                [(m[0] * 1e6).round() as i64, (m[1] * 1e6).round() as i64]
            })
            .collect();
        v.sort_unstable();
        v
    }

    fn square_drawing(x: f64, y: f64, s: f64, layer: &str) -> Entity {
        use dxf::entities::LwPolyline;
        use dxf::LwPolylineVertex;
        let mut lw = LwPolyline::default();
        for (px, py) in [(x, y), (x + s, y), (x + s, y + s), (x, y + s)] {
            lw.vertices.push(LwPolylineVertex {
                x: px,
                y: py,
                ..Default::default()
            });
        }
        lw.set_is_closed(true);
        let mut e = Entity::new(EntityType::LwPolyline(lw));
        e.common.layer = layer.into();
        e
    }

    #[test]
    fn the_sheet_rule_keeps_the_drawings_coordinates() {
        let p = |x: f64, y: f64| dxf::Point::new(x, y, 0.0);
        // Two parts with a 10 mm margin: extent (10, 10.15)..(290, 190).
        let parts = |d: &mut Drawing| {
            d.add_entity(square_drawing(10.0, 10.15, 50.0, "PARTS"));
            d.add_entity(square_drawing(250.0, 150.0, 40.0, "PARTS"));
        };
        let near =
            |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9;
        let rule_of = |d: &Drawing| {
            let (l, rule) =
                layout_from_drawing_with_rule(d, "m.dxf", &DxfOptions::default()).unwrap();
            (rule, l.sheet, l.origin, l)
        };
        let mut plain = Drawing::new();
        parts(&mut plain);
        // The dxf crate's default header: limits 0,0-12,9, extents 0 x 0: both unset.
        let (rule, sheet, origin, reference) = rule_of(&plain);
        assert_eq!((rule, origin), (SheetRule::Parts, [10.0, 10.15]));
        assert!(near(sheet, [280.0, 179.85]), "{sheet:?}");
        let want = drawing_points(&reference);
        assert_eq!(want.first(), Some(&[10_000_000, 10_150_000]));
        // Limits containing the parts: the sheet; extents beside them are not consulted.
        let mut d = plain.clone();
        d.header.minimum_drawing_limits = p(0.0, 0.0);
        d.header.maximum_drawing_limits = p(300.0, 200.0);
        d.header.minimum_drawing_extents = p(1e20, 1e20);
        d.header.maximum_drawing_extents = p(-1e20, -1e20);
        let (rule, sheet, origin, l) = rule_of(&d);
        assert_eq!(
            (rule, sheet, origin),
            (SheetRule::Limits, [300.0, 200.0], [0.0, 0.0])
        );
        assert_eq!(drawing_points(&l), want);
        // Limits that cut a part off: the extents (written with fewer digits) instead.
        d.header.maximum_drawing_limits = p(250.0, 200.0);
        d.header.minimum_drawing_extents = p(10.0, 10.1500004);
        d.header.maximum_drawing_extents = p(290.0, 190.0);
        let (rule, sheet, origin, l) = rule_of(&d);
        assert_eq!((rule, origin), (SheetRule::Extents, [10.0, 10.15]));
        assert!(near(sheet, [280.0, 179.85]), "{sheet:?}");
        assert_eq!(drawing_points(&l), want);
        // Neither contains the parts: their extent.
        d.header.maximum_drawing_extents = p(200.0, 190.0);
        assert_eq!(rule_of(&d).0, SheetRule::Parts);
        // A SHEET contour wins over the header, wherever it is.
        d.add_entity(square_drawing(-100.0, -50.0, 500.0, "sheet"));
        let (rule, sheet, origin, l) = rule_of(&d);
        assert_eq!(
            (rule, sheet, origin),
            (SheetRule::SheetLayer, [500.0, 500.0], [-100.0, -50.0])
        );
        assert_eq!(drawing_points(&l), want);
        // A given sheet size: the drawing's [0, a] x [0, b], not moved.
        let opt = DxfOptions {
            sheet: Some([400.0, 300.0]),
            ..Default::default()
        };
        let (l, rule) = layout_from_drawing_with_rule(&plain, "m.dxf", &opt).unwrap();
        assert_eq!((rule, l.origin), (SheetRule::Option, [0.0, 0.0]));
        assert_eq!(drawing_points(&l), want);
    }

    #[test]
    fn reversed_arcs_keep_their_geometry() {
        // Half circle from (0,0) to (2,0), bulge 1 (counter-clockwise, below the chord).
        let p = seg([0.0, 0.0], [2.0, 0.0], 1.0);
        let r = p.reversed();
        assert_eq!(r.vertices, vec![[2.0, 0.0, -1.0], [0.0, 0.0, 0.0]]);
        // Two half circles make a circle of radius 1 whatever their direction.
        let circle =
            chain_pieces(vec![p, seg([0.0, 0.0], [2.0, 0.0], -1.0).reversed()], 1e-9).unwrap();
        let pts = flatten(&circle[0], 0.001);
        let area = cell_geometry::signed_area(&pts).abs();
        assert!((area - std::f64::consts::PI).abs() < 0.01, "area {area}");
    }

    /// Runs only the entity walk: (entities placed, points counted) or the limit's error.
    fn expand(d: &Drawing) -> Result<(usize, usize), DxfError> {
        expand_at(d, DxfOptions::default().chord_tol_mm)
    }

    /// As [`expand`], flattening at `chord_tol_mm`.
    fn expand_at(d: &Drawing, chord_tol_mm: f64) -> Result<(usize, usize), DxfError> {
        let opt = DxfOptions {
            chord_tol_mm,
            ..Default::default()
        };
        let mut pieces = Vec::new();
        let mut r = Reader {
            drawing: d,
            name: "b.dxf",
            opt: &opt,
            pieces: &mut pieces,
            placed: 0,
            points: 0,
            root: None,
        };
        r.collect(d.entities(), &Placement::IDENTITY, None, 0)?;
        Ok((r.placed, r.points))
    }

    fn text() -> Entity {
        Entity::new(EntityType::Text(Default::default()))
    }

    #[test]
    fn placed_entities_are_capped_across_insert_arrays() {
        // Block T holds m TEXTs, placed 3 times by one INSERT: 1 + 3·m entities.
        let m = (MAX_PLACED_ENTITIES - 1) / 3;
        let mut d = Drawing::new();
        let mut b = dxf::Block {
            name: "T".into(),
            ..Default::default()
        };
        b.entities = (0..m).map(|_| text()).collect();
        d.add_block(b);
        d.add_entity(Entity::new(EntityType::Insert(dxf::entities::Insert {
            name: "T".into(),
            column_count: 3,
            column_spacing: 1.0,
            ..Default::default()
        })));
        assert_eq!(1 + 3 * m, MAX_PLACED_ENTITIES);
        assert_eq!(expand(&d).unwrap().0, MAX_PLACED_ENTITIES);
        d.add_entity(text());
        let e = expand(&d).unwrap_err().to_string();
        assert!(
            e.contains("the drawing places more than 250000 entities")
                && e.ends_with("the limit is 250000 placed entities (MAX_PLACED_ENTITIES)"),
            "{e}"
        );
    }

    #[test]
    fn nested_insert_arrays_are_refused_naming_the_outer_insert() {
        // L0 holds a TEXT; Lk places L(k-1) in a 10 × 10 array; the drawing places L8.
        let mut d = Drawing::new();
        let mut b = dxf::Block {
            name: "L0".into(),
            ..Default::default()
        };
        b.entities.push(text());
        d.add_block(b);
        for k in 1..=8 {
            let mut b = dxf::Block {
                name: format!("L{k}"),
                ..Default::default()
            };
            b.entities
                .push(Entity::new(EntityType::Insert(dxf::entities::Insert {
                    name: format!("L{}", k - 1),
                    column_count: 10,
                    row_count: 10,
                    column_spacing: 10f64.powi(k),
                    row_spacing: 10f64.powi(k),
                    ..Default::default()
                })));
            d.add_block(b);
        }
        let mut top = Entity::new(EntityType::Insert(dxf::entities::Insert {
            name: "L8".into(),
            ..Default::default()
        }));
        top.common.layer = "PARTS".into();
        d.add_entity(top);
        let t0 = std::time::Instant::now();
        let e = layout_from_drawing(&d, "bomb.dxf", &DxfOptions::default())
            .unwrap_err()
            .to_string();
        assert!(t0.elapsed().as_secs_f64() < 5.0, "{:?}", t0.elapsed());
        assert!(
            e.starts_with("bomb.dxf: INSERT of block 'L8' #")
                && e.contains("on layer 'PARTS': expanding it places more than 250000")
                && e.ends_with("(MAX_PLACED_ENTITIES)"),
            "{e}"
        );
    }

    #[test]
    fn flattened_points_are_capped() {
        use dxf::entities::LwPolyline;
        use dxf::LwPolylineVertex;
        let ring = |n: usize| {
            let mut lw = LwPolyline {
                vertices: (0..n)
                    .map(|i| {
                        let t = i as f64 / n as f64 * std::f64::consts::TAU;
                        LwPolylineVertex {
                            x: 1000.0 * t.cos(),
                            y: 1000.0 * t.sin(),
                            ..Default::default()
                        }
                    })
                    .collect(),
                ..Default::default()
            };
            lw.set_is_closed(true);
            Entity::new(EntityType::LwPolyline(lw))
        };
        let mut d = Drawing::new();
        d.add_entity(ring(MAX_POINTS));
        assert_eq!(expand(&d).unwrap(), (1, MAX_POINTS));
        let mut d = Drawing::new();
        d.add_entity(ring(MAX_POINTS + 1));
        let e = expand(&d).unwrap_err().to_string();
        assert!(
            e.contains("LWPOLYLINE #")
                && e.contains(
                    "brings the drawing to more than 1000000 points (this entity: 1000001)"
                )
                && e.ends_with("the limit is 1000000 points (MAX_POINTS)"),
            "{e}"
        );
        // A circle of radius 10¹⁴ mm would be ~10⁸ points at 0.005 mm.
        let mut d = Drawing::new();
        d.add_entity(circle(0.0, 0.0, 1e6));
        d.add_entity(circle(0.0, 0.0, 1e14));
        let e = expand(&d).unwrap_err().to_string();
        assert!(
            e.contains("an arc of radius 1.000e14 mm") && e.ends_with("(MAX_ARC_RADIUS_MM)"),
            "{e}"
        );
    }

    /// A full ELLIPSE of major radius `a` along x, minor `a/2`.
    fn ellipse(a: f64) -> Entity {
        Entity::new(EntityType::Ellipse(dxf::entities::Ellipse {
            major_axis: dxf::Vector::new(a, 0.0, 0.0),
            minor_axis_ratio: 0.5,
            ..Default::default()
        }))
    }

    /// Points a full ellipse of major radius `a` flattens to at `tol` (its docs' formula).
    fn ellipse_points(a: f64, tol: f64) -> usize {
        (std::f64::consts::TAU / (2.0 * (1.0 - tol / a).acos())).ceil() as usize
    }

    #[test]
    fn ellipses_are_refused_never_coarsened() {
        let one = |e: Entity, tol: f64| {
            let mut d = Drawing::new();
            d.add_entity(e);
            expand_at(&d, tol)
        };
        // At the radius limit, at 0.001 mm: 222 144 points (the old reader stopped at 10⁵).
        let n = ellipse_points(MAX_ARC_RADIUS_MM, 0.001);
        assert!(n > 200_000, "{n}");
        assert_eq!(one(ellipse(MAX_ARC_RADIUS_MM), 0.001).unwrap(), (1, n));
        let e = one(ellipse(MAX_ARC_RADIUS_MM * (1.0 + 1e-9)), 0.001)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("b.dxf: ELLIPSE #")
                && e.ends_with(
                    " on layer '0': an ellipse of major radius 1.000e7 mm is too large to \
                     flatten: the limit is 1e7 mm (MAX_ARC_RADIUS_MM)"
                ),
            "{e}"
        );
        // Points: 702 481 at 10⁻⁵ mm for 1 km are made; 2.2·10⁶ for 10 km are refused.
        let n = ellipse_points(1e6, 1e-5);
        assert!(n > 700_000 && n < MAX_POINTS, "{n}");
        assert_eq!(one(ellipse(1e6), 1e-5).unwrap(), (1, n));
        let e = one(ellipse(1e7), 1e-5).unwrap_err().to_string();
        assert!(
            e.starts_with("b.dxf: ELLIPSE #")
                && e.contains(" on layer '0': flattened at 0.00001 mm the ELLIPSE")
                && e.contains(&format!("needs {} points", ellipse_points(1e7, 1e-5) + 1))
                && e.ends_with("the limit is 1000000 points (MAX_POINTS)"),
            "{e}"
        );
        // Placed by an INSERT scaled 10×, an ellipse is flattened as the larger one it
        // becomes; at 1000× it is over the radius limit, and the INSERT is named.
        let scaled = |scale: f64| {
            let mut d = Drawing::new();
            let mut block = dxf::Block {
                name: "E".into(),
                ..Default::default()
            };
            block.entities.push(ellipse(1e4));
            d.add_block(block);
            d.add_entity(Entity::new(EntityType::Insert(dxf::entities::Insert {
                name: "E".into(),
                x_scale_factor: scale,
                y_scale_factor: scale,
                ..Default::default()
            })));
            expand_at(&d, 0.005)
        };
        assert_eq!(scaled(10.0).unwrap().1, ellipse_points(1e5, 0.005));
        let e = scaled(1e4).unwrap_err().to_string();
        assert!(
            e.starts_with("b.dxf: INSERT of block 'E' #")
                && e.contains(": ELLIPSE (block 'E' placed by INSERT #")
                && e.contains("an ellipse of major radius 1.000e8 mm")
                && e.ends_with("(MAX_ARC_RADIUS_MM)"),
            "{e}"
        );
    }

    #[test]
    fn the_point_count_is_what_flattening_makes() {
        for (bulge, chord, tol) in [
            (1.0, 2.0, 0.005),
            (0.3, 50.0, 0.005),
            (-0.05, 300.0, 0.01),
            (5.0, 1.0, 0.001),
            (1e-9, 100.0, 0.005),
        ] {
            let piece = Piece {
                vertices: vec![[0.0, 0.0, bulge], [chord, 0.0, 0.0]],
                closed: false,
                sources: src("ARC"),
            };
            let made = flatten_path(&piece.vertices, false, tol).len();
            assert_eq!(
                flattened_points(&piece, tol, 1.0),
                Ok(made),
                "{bulge} {chord}"
            );
            // Stretched 10× and flattened at 10× the tolerance: the same chords.
            assert_eq!(flattened_points(&piece, tol * 10.0, 10.0), Ok(made));
        }
    }

    #[test]
    fn arcs_over_half_a_circle_keep_their_side() {
        // ARC r = 10 from 0° to 270°: bulge tan(67.5°) > 1.
        let arc = Entity::new(EntityType::Arc(dxf::entities::Arc {
            center: dxf::Point::new(0.0, 0.0, 0.0),
            radius: 10.0,
            start_angle: 0.0,
            end_angle: 270.0,
            ..Default::default()
        }));
        let piece = entity_piece(&arc, src("ARC")[0].clone(), 0.005, 1.0)
            .unwrap()
            .unwrap();
        assert!(piece.vertices[0][2] > 1.0, "{:?}", piece.vertices);
        let pts = flatten_path(&piece.vertices, false, 0.005);
        assert_eq!(flattened_points(&piece, 0.005, 1.0), Ok(pts.len()));
        for q in &pts {
            assert!((distance(*q, [0.0, 0.0]) - 10.0).abs() < 1e-9, "{q:?}");
            // Nothing in the quarter the arc leaves out (x > 0, y < 0).
            assert!(!(q[0] > 1e-6 && q[1] < -1e-6), "{q:?}");
        }
        let (first, last) = (pts[0], pts[pts.len() - 1]);
        assert!(distance(first, [10.0, 0.0]) < 1e-9 && distance(last, [0.0, -10.0]) < 1e-9);
        assert!(
            pts.iter().any(|q| distance(*q, [-10.0, 0.0]) < 0.5),
            "passes 180°"
        );
    }

    #[test]
    fn arc_radius_limit_and_flat_arcs() {
        // A half circle of radius exactly the limit is flattened; a hair larger is refused.
        let half = |r: f64| Piece {
            vertices: vec![[0.0, 0.0, 1.0], [2.0 * r, 0.0, 0.0]],
            closed: false,
            sources: src("ARC"),
        };
        let n = flattened_points(&half(MAX_ARC_RADIUS_MM), 0.005, 1.0).unwrap();
        assert!(n > 1000 && n < MAX_POINTS, "{n}");
        let r = flattened_points(&half(MAX_ARC_RADIUS_MM * (1.0 + 1e-9)), 0.005, 1.0);
        assert!(r.is_err_and(|r| r > MAX_ARC_RADIUS_MM));
        // A bulge of radius 10¹⁴ mm over 100 mm sags 1.25e-11 mm: it is its chord.
        let flat = [[0.0, 0.0, 5e-13], [100.0, 0.0, 0.0]];
        assert_eq!(
            flatten_path(&flat, false, 0.005),
            vec![[0.0, 0.0], [100.0, 0.0]]
        );
    }
}
