//! `slice.svg`: a picture of a WAAM slice for the operator to check before welding (issue 20,
//! item 6). Two views side by side, in the plate frame, mm:
//!
//! - **Layer** (plan view of one planned layer, y up): the part's section at that layer's
//!   slicing plane (grey, holes open), the machining allowance around it (an orange band
//!   `allowance` wide outside the walls and inside the holes, drawn as a stroke of twice the
//!   allowance along the contours, half of it under the part), the beads as their width (blue,
//!   translucent, so overlaps show darker and gaps show white), their centre lines, the travel
//!   moves (dashed) and the side section's cut line (red).
//! - **Side section** (x–z, a vertical cut at y through the part's centre): per slicing plane
//!   the part's section one layer tall (the layer stack's resolution), the allowance beside it
//!   (and above where the next layer up has no part), and every bead the cut crosses as its
//!   cross-section: the bead model's rectangle (seed 004 eq. 25), the width where the cut meets
//!   the bead's plan shape (its centre line widened by half the width, round ends), the bead
//!   height from eq. 28 laid on the layer's bottom.
//!
//! Groups have ids (`layer-allowance`, `layer-beads`, `layer-part`, `layer-paths`,
//! `layer-travel`, `cut-line`, `section-allowance`, `section-beads`, `section-part`, `title`,
//! `legend`) so a check can find them. Pure: the picture is returned as text.

use std::fmt::Write as _;

use cell_mesh::LayerStack;
use cell_waam::toolpath::{LayerToolpath, SegmentKind};
use svg::node::element::path::Data;
use svg::node::element::{Group, Path, Rectangle, Text};
use svg::Document;
use thiserror::Error;

/// Why no picture could be drawn.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PictureError {
    /// The layer asked for is not planned.
    #[error("--picture-layer {asked}: the slice has layers 0..={last}")]
    NoSuchLayer {
        /// The layer asked for.
        asked: usize,
        /// The last planned layer.
        last: usize,
    },
    /// Nothing was planned.
    #[error("no planned layer to draw")]
    Empty,
}

/// Gap between the two views and around them (mm).
const MARGIN_MM: f64 = 10.0;

/// Rounds to 0.01 mm for short files.
fn r(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// The layer to draw: `asked`, or the middle planned layer.
///
/// # Errors
/// [`PictureError::Empty`] with no layers, [`PictureError::NoSuchLayer`] past the last one.
pub fn chosen_layer(layers: &[LayerToolpath], asked: Option<usize>) -> Result<usize, PictureError> {
    let last = layers.len().checked_sub(1).ok_or(PictureError::Empty)?;
    match asked {
        Some(n) if n > last => Err(PictureError::NoSuchLayer { asked: n, last }),
        Some(n) => Ok(n),
        None => Ok(layers.len() / 2),
    }
}

/// The picture of `layers` (planned, plate frame) over the part's `stack` with the machining
/// allowance `allowance_mm`: planned layer `layer` (default: the middle one) and the side
/// section through the part's centre, as SVG text.
///
/// # Errors
/// See [`chosen_layer`].
pub fn slice_svg(
    stack: &LayerStack,
    layers: &[LayerToolpath],
    allowance_mm: f64,
    layer: Option<usize>,
) -> Result<String, PictureError> {
    let chosen = chosen_layer(layers, layer)?;
    let planned = &layers[chosen];
    let layer_height = stack.layer_height_mm;
    let (lo, hi) = plan_bounds(stack, layers);
    let centre_y = 0.5 * (lo[1] + hi[1]);
    let pad = allowance_mm.max(0.0) + max_bead_width(layers);
    let (x0, x1, y0, y1) = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad);
    let top = layers
        .iter()
        .map(|l| l.z_mm + layer_height)
        .chain(stack.layers.iter().map(|l| l.z_mm + layer_height))
        .fold(layer_height, f64::max)
        + allowance_mm.max(0.0);

    // Layer view, y up: SVG y = −y.
    let part_layer = stack.layers.iter().find(|l| l.index == planned.index);
    let contours = Data::new();
    let contours = part_layer
        .map(|l| {
            l.contours
                .iter()
                .fold(contours.clone(), |d, c| ring(d, &c.points))
        })
        .unwrap_or(contours);
    let mut beads = Group::new()
        .set("id", "layer-beads")
        .set("fill", "none")
        .set("stroke", "#1f6fd1")
        .set("stroke-opacity", 0.35)
        .set("stroke-linecap", "round")
        .set("stroke-linejoin", "round");
    let mut centre_lines = Data::new();
    let mut travel = Data::new();
    for s in &planned.segments {
        let pts: Vec<[f64; 2]> = s.points.iter().map(|p| [p.x_mm, p.y_mm]).collect();
        match s.kind {
            SegmentKind::Travel => travel = polyline(travel, &pts),
            SegmentKind::Deposit => {
                centre_lines = polyline(centre_lines, &pts);
                // One stroke when the width is uniform, else one per piece.
                let w0 = s.points[0].bead_width_mm;
                if s.points.iter().all(|p| (p.bead_width_mm - w0).abs() < 1e-6) {
                    beads = beads.add(
                        Path::new()
                            .set("d", polyline(Data::new(), &pts))
                            .set("stroke-width", r(w0)),
                    );
                } else {
                    for (i, w) in s.points.windows(2).enumerate() {
                        beads = beads.add(
                            Path::new()
                                .set("d", polyline(Data::new(), &pts[i..i + 2]))
                                .set("stroke-width", r(w[0].bead_width_mm)),
                        );
                    }
                }
            }
        }
    }
    // The layer view moved so that its top is level with the section's.
    let lift = y1 - top;
    let layer_view = Group::new()
        .set("id", "layer")
        .set("transform", format!("translate(0,{})", r(lift)))
        .add(
            Group::new().set("id", "layer-allowance").add(
                Path::new()
                    .set("d", contours.clone())
                    .set("fill", "none")
                    .set("stroke", "#f08c00")
                    .set("stroke-opacity", 0.55)
                    .set("stroke-width", r(2.0 * allowance_mm.max(0.0)))
                    .set("stroke-linejoin", "round"),
            ),
        )
        .add(beads)
        .add(
            Group::new().set("id", "layer-part").add(
                Path::new()
                    .set("d", contours)
                    .set("fill", "#555")
                    .set("fill-opacity", 0.45)
                    .set("fill-rule", "evenodd")
                    .set("stroke", "black")
                    .set("stroke-width", 0.2),
            ),
        )
        .add(
            Group::new().set("id", "layer-paths").add(
                Path::new()
                    .set("d", centre_lines)
                    .set("fill", "none")
                    .set("stroke", "#0b3d91")
                    .set("stroke-width", 0.15),
            ),
        )
        .add(
            Group::new().set("id", "layer-travel").add(
                Path::new()
                    .set("d", travel)
                    .set("fill", "none")
                    .set("stroke", "#888")
                    .set("stroke-width", 0.15)
                    .set("stroke-dasharray", "1 1"),
            ),
        )
        .add(
            Group::new().set("id", "cut-line").add(
                Path::new()
                    .set(
                        "d",
                        Data::new()
                            .move_to((r(x0), r(-centre_y)))
                            .line_to((r(x1), r(-centre_y))),
                    )
                    .set("stroke", "red")
                    .set("stroke-width", 0.3)
                    .set("stroke-dasharray", "4 1 1 1"),
            ),
        );

    // Side section at y = centre_y, z up: SVG y = −z, placed right of the layer view.
    let shift = (x1 - x0) + MARGIN_MM;
    let rect = |xa: f64, xb: f64, za: f64, zb: f64| {
        Rectangle::new()
            .set("x", r(xa + shift))
            .set("y", r(-zb))
            .set("width", r(xb - xa))
            .set("height", r(zb - za))
    };
    let mut section_part = Group::new()
        .set("id", "section-part")
        .set("fill", "#555")
        .set("fill-opacity", 0.45)
        .set("stroke", "black")
        .set("stroke-width", 0.1);
    let mut section_allowance = Group::new()
        .set("id", "section-allowance")
        .set("fill", "#f08c00")
        .set("fill-opacity", 0.55);
    let a = allowance_mm.max(0.0);
    let spans: Vec<(f64, Vec<[f64; 2]>)> = stack
        .layers
        .iter()
        .map(|l| {
            (
                l.z_mm,
                line_spans(l.contours.iter().map(|c| c.points.as_slice()), centre_y),
            )
        })
        .collect();
    for (k, (z, here)) in spans.iter().enumerate() {
        let (za, zb) = (z - 0.5 * layer_height, z + 0.5 * layer_height);
        for s in here {
            section_part = section_part.add(rect(s[0], s[1], za, zb));
            section_allowance = section_allowance.add(rect(s[0] - a, s[1] + a, za, zb));
            let above = spans.get(k + 1).map(|(_, v)| v.as_slice()).unwrap_or(&[]);
            for open in subtract(*s, above) {
                section_allowance =
                    section_allowance.add(rect(open[0] - a, open[1] + a, zb, zb + a));
            }
        }
    }
    let mut section_beads = Group::new()
        .set("id", "section-beads")
        .set("fill", "#1f6fd1")
        .set("fill-opacity", 0.35)
        .set("stroke", "#0b3d91")
        .set("stroke-width", 0.05);
    for l in layers {
        let base = l.z_mm - 0.5 * layer_height;
        for s in l.segments.iter().filter(|s| s.kind == SegmentKind::Deposit) {
            for w in s.points.windows(2).filter(|w| w[0].arc_on) {
                let half = 0.5 * w[0].bead_width_mm;
                let piece = ([w[0].x_mm, w[0].y_mm], [w[1].x_mm, w[1].y_mm]);
                // Grazing cuts narrower than the drawing's 0.01 mm are left out.
                let span =
                    stadium_span(piece.0, piece.1, half, centre_y).filter(|s| s[1] - s[0] >= 0.01);
                if let Some([xa, xb]) = span {
                    section_beads =
                        section_beads.add(rect(xa, xb, base, base + w[0].bead_height_mm));
                }
            }
        }
    }
    let section_view = Group::new()
        .set("id", "section")
        .add(section_allowance)
        .add(section_beads)
        .add(section_part)
        .add(
            Path::new()
                .set(
                    "d",
                    Data::new()
                        .move_to((r(x0 + shift), 0))
                        .line_to((r(x1 + shift), 0)),
                )
                .set("stroke", "black")
                .set("stroke-width", 0.4),
        );

    // Title and legend above both views.
    let font = (0.015 * (2.0 * (x1 - x0) + MARGIN_MM)).clamp(1.5, 12.0);
    let top_y = -top - 3.5 * font;
    let mut title = String::new();
    let _ = write!(
        title,
        "layer {} of {} at z = {:.2} mm (left), side section at y = {:.2} mm (right); allowance {} mm",
        chosen,
        layers.len(),
        planned.z_mm,
        centre_y,
        allowance_mm
    );
    let title = Group::new().set("id", "title").add(
        Text::new(title)
            .set("x", r(x0))
            .set("y", r(top_y + font))
            .set("font-size", r(font))
            .set("font-family", "sans-serif"),
    );
    let legend = Group::new().set("id", "legend").add(
        Text::new(
            "grey: part section; orange: machining allowance; blue: beads (width and height from \
             the bead model); red: the section's cut",
        )
        .set("x", r(x0))
        .set("y", r(top_y + 2.3 * font))
        .set("font-size", r(0.7 * font))
        .set("font-family", "sans-serif"),
    );
    let width = shift + (x1 - x0);
    let bottom = (-y0 + lift).max(0.0) + MARGIN_MM;
    let doc = Document::new()
        .set(
            "viewBox",
            (
                r(x0 - MARGIN_MM),
                r(top_y - MARGIN_MM),
                r(width + 2.0 * MARGIN_MM),
                r(bottom - top_y + MARGIN_MM),
            ),
        )
        .set("width", format!("{}mm", r(width + 2.0 * MARGIN_MM)))
        .set("height", format!("{}mm", r(bottom - top_y + MARGIN_MM)))
        .add(title)
        .add(legend)
        .add(layer_view)
        .add(section_view);
    Ok(doc.to_string())
}

/// Plan bounds of the part's contours and the planned points.
fn plan_bounds(stack: &LayerStack, layers: &[LayerToolpath]) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let contour_points = stack
        .layers
        .iter()
        .flat_map(|l| &l.contours)
        .flat_map(|c| c.points.iter().copied());
    let path_points = layers
        .iter()
        .flat_map(|l| &l.segments)
        .flat_map(|s| &s.points)
        .map(|p| [p.x_mm, p.y_mm]);
    for p in contour_points.chain(path_points) {
        for i in 0..2 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    if !lo[0].is_finite() {
        return ([0.0; 2], [1.0; 2]);
    }
    (lo, hi)
}

fn max_bead_width(layers: &[LayerToolpath]) -> f64 {
    layers
        .iter()
        .flat_map(|l| &l.segments)
        .flat_map(|s| &s.points)
        .map(|p| p.bead_width_mm)
        .fold(0.0, f64::max)
}

/// A closed ring added to `d` (y flipped).
fn ring(d: Data, pts: &[[f64; 2]]) -> Data {
    if pts.len() < 2 {
        return d;
    }
    polyline(d, pts).close()
}

/// An open polyline added to `d` (y flipped).
fn polyline(mut d: Data, pts: &[[f64; 2]]) -> Data {
    for (i, p) in pts.iter().enumerate() {
        let at = (r(p[0]), r(-p[1]));
        d = if i == 0 { d.move_to(at) } else { d.line_to(at) };
    }
    d
}

/// The x intervals where the line y = `y` is inside the rings (even–odd).
fn line_spans<'a>(rings: impl Iterator<Item = &'a [[f64; 2]]>, y: f64) -> Vec<[f64; 2]> {
    let mut xs = Vec::new();
    for pts in rings {
        for i in 0..pts.len() {
            let (p, q) = (pts[i], pts[(i + 1) % pts.len()]);
            if (p[1] > y) != (q[1] > y) {
                xs.push(p[0] + (y - p[1]) * (q[0] - p[0]) / (q[1] - p[1]));
            }
        }
    }
    xs.sort_by(f64::total_cmp);
    xs.chunks_exact(2).map(|c| [c[0], c[1]]).collect()
}

/// The parts of `span` no interval of `cover` covers.
fn subtract(span: [f64; 2], cover: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut open = vec![span];
    for c in cover {
        open = open
            .into_iter()
            .flat_map(|s| {
                let mut out = Vec::new();
                if c[0] > s[0] {
                    out.push([s[0], s[1].min(c[0])]);
                }
                if c[1] < s[1] {
                    out.push([s[0].max(c[1]), s[1]]);
                }
                out.into_iter().filter(|o| o[1] > o[0] + 1e-9)
            })
            .collect();
    }
    open
}

/// The x interval where the line y = `y` is within `half` of the piece a–b (its plan shape: a
/// rectangle with round ends, convex, so the union of the three parts' intervals is one).
fn stadium_span(a: [f64; 2], b: [f64; 2], half: f64, y: f64) -> Option<[f64; 2]> {
    let mut span: Option<[f64; 2]> = None;
    let mut join = |s: [f64; 2]| {
        if s[1] >= s[0] {
            span = Some(span.map_or(s, |t| [t[0].min(s[0]), t[1].max(s[1])]));
        }
    };
    for c in [a, b] {
        let dy = y - c[1];
        if dy.abs() <= half {
            let s = (half * half - dy * dy).sqrt();
            join([c[0] - s, c[0] + s]);
        }
    }
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len = dx.hypot(dy);
    if len > 0.0 {
        let u = [dx / len, dy / len];
        let n = [-u[1], u[0]];
        // Along the line x ↦ (x, y): s(x) = (x − a.x)·u.x + (y − a.y)·u.y ∈ [0, len] and
        // q(x) = (x − a.x)·n.x + (y − a.y)·n.y ∈ [−half, half].
        let mut lo = f64::NEG_INFINITY;
        let mut hi = f64::INFINITY;
        for (k, offset, range) in [
            (u[0], (y - a[1]) * u[1], [0.0, len]),
            (n[0], (y - a[1]) * n[1], [-half, half]),
        ] {
            if k.abs() < 1e-12 {
                if offset < range[0] || offset > range[1] {
                    return span;
                }
            } else {
                let (t0, t1) = (
                    (range[0] - offset) / k + a[0],
                    (range[1] - offset) / k + a[0],
                );
                lo = lo.max(t0.min(t1));
                hi = hi.min(t0.max(t1));
            }
        }
        join([lo, hi]);
    }
    span
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bead_along_the_cut_spans_its_length_and_round_ends() {
        let s = stadium_span([0.0, 0.0], [10.0, 0.0], 2.0, 0.0).unwrap();
        assert!(
            (s[0] + 2.0).abs() < 1e-9 && (s[1] - 12.0).abs() < 1e-9,
            "{s:?}"
        );
        // Across the cut: its width.
        let s = stadium_span([5.0, -10.0], [5.0, 10.0], 2.0, 0.0).unwrap();
        assert!(
            (s[0] - 3.0).abs() < 1e-9 && (s[1] - 7.0).abs() < 1e-9,
            "{s:?}"
        );
        // At 45°: the width over sin 45°.
        let s = stadium_span([-10.0, -10.0], [10.0, 10.0], 1.0, 0.0).unwrap();
        assert!((s[1] - s[0] - 2.0 * 2f64.sqrt()).abs() < 1e-9, "{s:?}");
        assert_eq!(stadium_span([0.0, 5.0], [10.0, 5.0], 2.0, 0.0), None);
    }

    #[test]
    fn spans_and_their_uncovered_parts() {
        let square = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        let hole = [[3.0, 3.0], [3.0, 7.0], [7.0, 7.0], [7.0, 3.0]];
        let spans = line_spans([&square[..], &hole[..]].into_iter(), 5.0);
        assert_eq!(spans, vec![[0.0, 3.0], [7.0, 10.0]]);
        assert_eq!(
            subtract([0.0, 10.0], &[[2.0, 4.0], [6.0, 12.0]]),
            vec![[0.0, 2.0], [4.0, 6.0]]
        );
    }

    #[test]
    fn the_layer_is_the_middle_one_unless_asked() {
        assert_eq!(chosen_layer(&[], None), Err(PictureError::Empty));
    }
}
