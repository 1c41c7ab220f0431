//! DXF input for nested layouts (issue 7; seed 003 §A1 contours `C_ij`), read with the `dxf`
//! crate.
//!
//! **Entities.** LWPOLYLINE and POLYLINE (bulges become arcs), LINE, ARC and CIRCLE; every
//! other entity (text, dimensions, …) is ignored. Closed polylines and circles are contours on
//! their own. Open polylines, LINEs and ARCs are **chained**: an endpoint joins another
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
//! **Sheet.** [`DxfOptions::sheet`] if given; else the closed contour on layer
//! [`DxfOptions::sheet_layer`] (its bounding box; the drawing is shifted so that its lower-left
//! corner is the origin); else the bounding box of all contours, shifted to the origin.

use std::collections::HashMap;
use std::path::Path;

use cavalier_contours::polyline::{PlineCreation, PlineSource, PlineSourceMut, Polyline};
use dxf::entities::{Entity, EntityType};
use dxf::Drawing;

use crate::containment::bbox;
use crate::layout::{Layout, LayoutError};
use crate::problem::{distance, Point};

/// DXF reading options (issue 7).
#[derive(Debug, Clone, PartialEq)]
pub struct DxfOptions {
    /// Maximum distance between an arc and its flattening chords, mm.
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
            chord_tol_mm: 0.05,
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
    /// A non-finite coordinate or parameter.
    #[error("{path}: {entity}: non-finite coordinate")]
    NonFinite {
        /// The file.
        path: String,
        /// The entity.
        entity: EntityRef,
    },
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
    let mut p: Polyline<f64> = Polyline::with_capacity(piece.vertices.len(), true);
    for v in &piece.vertices {
        p.add(v[0], v[1], v[2]);
    }
    let lines = if p.iter_vertexes().any(|v| v.bulge != 0.0) {
        p.arcs_to_approx_lines(chord_tol_mm.max(1e-6)).unwrap_or(p)
    } else {
        p
    };
    lines.iter_vertexes().map(|v| [v.x, v.y]).collect()
}

/// Reads a DXF file into a [`Layout`] (module docs; issue 7, seed 003 §A1).
///
/// # Errors
/// [`DxfError`], naming the file and, where it applies, the entities.
pub fn read_dxf(path: impl AsRef<Path>, opt: &DxfOptions) -> Result<Layout, DxfError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let drawing = Drawing::load_file(path).map_err(|e| DxfError::Read {
        path: name.clone(),
        message: e.to_string(),
    })?;
    layout_from_drawing(&drawing, &name, opt)
}

/// Reads a layout from a `.dxf` file ([`read_dxf`]) or, for any other extension, from the
/// JSON format ([`Layout::from_json_file`]) (issue 7: `--layout FILE.dxf|json`).
///
/// # Errors
/// [`DxfError`]; JSON errors come as [`DxfError::Layout`].
pub fn read_layout(path: impl AsRef<Path>, opt: &DxfOptions) -> Result<Layout, DxfError> {
    let path = path.as_ref();
    let is_dxf = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("dxf"));
    if is_dxf {
        read_dxf(path, opt)
    } else {
        Layout::from_json_file(path).map_err(|source| DxfError::Layout {
            path: path.display().to_string(),
            source,
        })
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
    let mut pieces = Vec::new();
    for e in drawing.entities() {
        if let Some(p) = entity_piece(e) {
            if p.vertices.iter().flatten().any(|v| !v.is_finite()) {
                return Err(DxfError::NonFinite {
                    path: name.into(),
                    entity: p.sources[0].clone(),
                });
            }
            pieces.push(p);
        }
    }
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
    let (shift, sheet) = match (opt.sheet, sheet_box) {
        (Some(s), _) => ([0.0, 0.0], s),
        (None, Some(b)) => ([b[0], b[1]], [b[2] - b[0], b[3] - b[1]]),
        (None, None) => {
            let all: Vec<Point> = rings.iter().flatten().copied().collect();
            let b = bbox(&all);
            if all.is_empty() {
                ([0.0, 0.0], [1.0, 1.0])
            } else {
                ([b[0], b[1]], [b[2] - b[0], b[3] - b[1]])
            }
        }
    };
    for ring in &mut rings {
        for p in ring.iter_mut() {
            p[0] -= shift[0];
            p[1] -= shift[1];
        }
    }
    Layout::from_rings(sheet, opt.start, rings, &names).map_err(|source| DxfError::Layout {
        path: name.into(),
        source,
    })
}

/// The polyline piece of one supported entity, or `None` for unsupported entities.
fn entity_piece(e: &Entity) -> Option<Piece> {
    let source = |kind: &str| EntityRef {
        kind: kind.into(),
        handle: e.common.handle.as_string(),
        layer: e.common.layer.clone(),
    };
    // Mirrored object coordinate system (extrusion −Z): x → −x, arcs turn the other way.
    let mirror = |z: f64| if z < 0.0 { -1.0 } else { 1.0 };
    let (vertices, closed, kind) = match &e.specific {
        EntityType::Line(l) => (
            vec![[l.p1.x, l.p1.y, 0.0], [l.p2.x, l.p2.y, 0.0]],
            false,
            "LINE",
        ),
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
                (vec![[p0[0], p0[1], b], [q[0], q[1], b]], true, "ARC")
            } else {
                let bulge = m * (sweep / 4.0).tan();
                (
                    vec![[p0[0], p0[1], bulge], [p1[0], p1[1], 0.0]],
                    false,
                    "ARC",
                )
            }
        }
        EntityType::Circle(c) => {
            let m = mirror(c.normal.z);
            let (x, y, r) = (m * c.center.x, c.center.y, c.radius);
            (vec![[x - r, y, 1.0], [x + r, y, 1.0]], true, "CIRCLE")
        }
        EntityType::LwPolyline(p) => {
            let m = mirror(p.extrusion_direction.z);
            let v = p
                .vertices
                .iter()
                .map(|v| [m * v.x, v.y, m * v.bulge])
                .collect();
            (v, p.is_closed(), "LWPOLYLINE")
        }
        // Polyface and polygon meshes (flags 16, 64) are surfaces, not contours.
        EntityType::Polyline(p) if p.flags & (16 | 64) != 0 => return None,
        EntityType::Polyline(p) => {
            let m = mirror(p.normal.z);
            let v = p
                .vertices()
                .map(|v| [m * v.location.x, v.location.y, m * v.bulge])
                .collect();
            (v, p.is_closed(), "POLYLINE")
        }
        _ => return None,
    };
    if vertices.is_empty() {
        return None;
    }
    Some(Piece {
        vertices,
        closed,
        sources: vec![source(kind)],
    })
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
        let area = crate::containment::signed_area(&pts).abs();
        assert!((area - std::f64::consts::PI).abs() < 0.01, "area {area}");
    }
}
