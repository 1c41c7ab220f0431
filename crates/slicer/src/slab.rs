//! Deposit layers (issue 20, item 1): layer k is the slab z ∈ [z_min + k·h, z_min + (k+1)·h]
//! of the part, and its region is the union of the part's sections over that slab widened by
//! the machining allowance a up and down (z ∈ [slab bottom − a, slab top + a]), so that a sloped
//! or stepped wall, an overhang's underside and the top are covered with the allowance too.
//! There are ⌈(height + a)/h⌉ layers: the last bead's top is at least a above the part's top.
//! The bottom rests on the build plate and gets no allowance.
//!
//! The sections are cut on a fine grid of planes (at most 0.25 mm or h/4 apart, the first and
//! last 0.01 mm inside the part) with [`cell_mesh::slice()`]; between two planes a wall moves
//! monotonically for all but a curved face's extremum, so the union over the planes in a
//! window is the union over the window within that grid's sagitta.

use cell_mesh::{Contour, Layer, LayerStack, Mesh, SliceError, SliceParams};
use cell_waam::toolpath::region;

/// Finest plane spacing (mm).
const MAX_PLANE_STEP_MM: f64 = 0.25;

/// How far inside the part's z-extent the first and last planes lie (mm).
const END_INSET_MM: f64 = 0.01;

/// The deposit layers of `mesh` (in its own frame): layer k at the slab's middle height
/// `z_min + (k + ½)·h`, its contours the union region (outer CCW, holes CW, nesting parents
/// set) and the open chains of the plane nearest the slab's middle.
///
/// `layer_done(done, total)` is called after each layer; when it returns false the work stops
/// and `Ok(None)` is returned (a cancelled job: thin layers make this phase long).
///
/// # Errors
/// As [`cell_mesh::slice()`] (bad layer height, too many layers).
pub fn deposit_layers(
    mesh: &Mesh,
    h: f64,
    allowance_mm: f64,
    layer_done: &mut dyn FnMut(usize, usize) -> bool,
) -> Result<Option<LayerStack>, SliceError> {
    if !(h.is_finite() && h > 0.0) {
        return Err(SliceError::BadLayerHeight(h));
    }
    let (lo, hi) = mesh.bbox();
    let height = hi[2] - lo[2];
    let inset = END_INSET_MM.min(height / 4.0);
    let span = height - 2.0 * inset;
    let m = (span / MAX_PLANE_STEP_MM.min(h / 4.0)).ceil().max(1.0);
    let step = if span > 0.0 { span / m } else { h };
    let planes = cell_mesh::slice(
        mesh,
        &SliceParams {
            layer_height_mm: step,
            first_z_mm: Some(lo[2] + inset),
            chain_tolerance_mm: None,
        },
    )?;
    let n = if height > 0.0 {
        ((height + allowance_mm) / h).ceil() as usize
    } else {
        0
    };
    let mut layers = Vec::with_capacity(n);
    for k in 0..n {
        let (bottom, top) = (lo[2] + k as f64 * h, lo[2] + (k + 1) as f64 * h);
        let (wlo, whi) = (bottom - allowance_mm, top + allowance_mm);
        let in_window: Vec<&Layer> = planes
            .layers
            .iter()
            .filter(|p| p.z_mm >= wlo - 1e-9 && p.z_mm <= whi + 1e-9)
            .collect();
        // A window between two planes (a layer thinner than the grid) takes the nearer one.
        let chosen: Vec<&Layer> = if in_window.is_empty() {
            let mid = 0.5 * (bottom + top);
            planes
                .layers
                .iter()
                .min_by(|a, b| (a.z_mm - mid).abs().total_cmp(&(b.z_mm - mid).abs()))
                .into_iter()
                .collect()
        } else {
            in_window
        };
        // One plane at a time: a boolean union of many nearly coincident sections (a prism's
        // planes differ only in where they cross the side triangles' diagonals) is very slow
        // in one go, and fast two by two.
        let mut shapes: Vec<region::Shape> = Vec::new();
        for p in &chosen {
            let mut rings: Vec<Vec<[f64; 2]>> = shapes.iter().flatten().cloned().collect();
            rings.extend(p.contours.iter().map(|c| c.points.clone()));
            shapes = region::union(&rings);
        }
        let mid = 0.5 * (bottom + top);
        let open_chains = planes
            .layers
            .iter()
            .filter(|p| p.z_mm >= bottom && p.z_mm <= top)
            .min_by(|a, b| (a.z_mm - mid).abs().total_cmp(&(b.z_mm - mid).abs()))
            .map(|p| p.open_chains.clone())
            .unwrap_or_default();
        layers.push(Layer {
            index: k,
            z_mm: mid,
            contours: contours_of(&shapes),
            open_chains,
            degenerate_loops: 0,
        });
        if !layer_done(k + 1, n) {
            return Ok(None);
        }
    }
    Ok(Some(LayerStack {
        layers,
        layer_height_mm: h,
        first_z_mm: lo[2] + 0.5 * h,
        chain_tolerance_mm: planes.chain_tolerance_mm,
    }))
}

/// Shapes (outer then holes) as contours with nesting: a hole's parent is its outer, an outer's
/// the innermost hole of another shape that encloses it.
fn contours_of(shapes: &[region::Shape]) -> Vec<Contour> {
    let mut out: Vec<Contour> = Vec::new();
    let mut holes: Vec<usize> = Vec::new();
    let mut outers: Vec<usize> = Vec::new();
    for s in shapes {
        let outer = out.len();
        outers.push(outer);
        for (i, r) in s.iter().enumerate() {
            if i > 0 {
                holes.push(out.len());
            }
            out.push(Contour {
                points: r.clone(),
                is_hole: i > 0,
                parent: (i > 0).then_some(outer),
            });
        }
    }
    for &o in &outers {
        let p = out[o].points[0];
        let parent = holes
            .iter()
            .copied()
            .filter(|&h| cell_geometry::point_in_ring_even_odd(p, &out[h].points))
            .min_by(|&a, &b| {
                out[a]
                    .signed_area_mm2()
                    .abs()
                    .total_cmp(&out[b].signed_area_mm2().abs())
            });
        out[o].parent = parent;
    }
    out
}
