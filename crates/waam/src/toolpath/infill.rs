//! Zig-zag infill: raster lines at an angle clipped to a region (even-odd over outer and holes),
//! chained into zig-zags where the link between two consecutive lines stays inside the region.
//!
//! Hand-written: scanline clipping and the chaining are a few dozen lines, and no workspace
//! crate produces hatch lines (cavalier_contours offsets, it does not hatch).

use super::geom::{dist, segment_cross, NORM, P2};
use cell_geometry::point_in_rings_or_near;

/// Raster lines of `rings` at `angle_deg` from +X, `spacing_mm` apart, centred across the
/// region's extent perpendicular to the lines; each line clipped to the region (even-odd).
/// Returned grouped by scanline (in order across the region), each scanline's pieces ordered
/// along +direction.
pub fn raster_lines(rings: &[Vec<P2>], angle_deg: f64, spacing_mm: f64) -> Vec<Vec<[P2; 2]>> {
    let (s, c) = angle_deg.to_radians().sin_cos();
    // Frame: u along the lines, v across them.
    let to_uv = |p: P2| [p[0] * c + p[1] * s, -p[0] * s + p[1] * c];
    let to_xy = |u: f64, v: f64| [u * c - v * s, u * s + v * c];
    let uv: Vec<Vec<P2>> = rings
        .iter()
        .map(|r| r.iter().map(|&p| to_uv(p)).collect())
        .collect();
    let (mut vmin, mut vmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in uv.iter().flatten() {
        vmin = vmin.min(p[1]);
        vmax = vmax.max(p[1]);
    }
    if !(vmin.is_finite() && vmax > vmin) {
        return Vec::new();
    }
    let span = vmax - vmin;
    let n = (span / spacing_mm).floor() as usize + 1;
    let v0 = vmin + (span - (n - 1) as f64 * spacing_mm) / 2.0;
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let v = v0 + k as f64 * spacing_mm;
        let mut xs: Vec<f64> = Vec::new();
        for r in &uv {
            for i in 0..r.len() {
                let (a, b) = (r[i], r[(i + 1) % r.len()]);
                if (a[1] > v) != (b[1] > v) {
                    xs.push(a[0] + (v - a[1]) / (b[1] - a[1]) * (b[0] - a[0]));
                }
            }
        }
        xs.sort_by(f64::total_cmp);
        let pieces: Vec<[P2; 2]> = xs
            .chunks_exact(2)
            .filter(|w| w[1] - w[0] > 1e-9)
            .map(|w| [to_xy(w[0], v), to_xy(w[1], v)])
            .collect();
        if !pieces.is_empty() {
            out.push(pieces);
        }
    }
    out
}

/// Whether the straight link p→q stays in the region: it crosses no ring edge except at its
/// own ends, and its midpoint is inside (or on the boundary).
fn link_inside(rings: &[Vec<P2>], p: P2, q: P2) -> bool {
    for r in rings {
        for i in 0..r.len() {
            if let Some((t, _)) = segment_cross(p, q, r[i], r[(i + 1) % r.len()]) {
                if t > 1e-6 && t < 1.0 - 1e-6 {
                    // Running along an edge or touching a vertex is fine; crossing is not.
                    let probe = [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])];
                    let eps = 1e-4;
                    let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
                    let l = dx.hypot(dy);
                    let before = [probe[0] - dx / l * eps, probe[1] - dy / l * eps];
                    let after = [probe[0] + dx / l * eps, probe[1] + dy / l * eps];
                    if !(inside_or_near(rings, before) && inside_or_near(rings, after)) {
                        return false;
                    }
                }
            }
        }
    }
    inside_or_near(rings, [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0])
}

/// Inside the region or within 1e-7 mm of its boundary: points computed on an edge count.
fn inside_or_near(rings: &[Vec<P2>], p: P2) -> bool {
    point_in_rings_or_near(p, rings, 1e-7, NORM)
}

/// Zig-zag polylines over `rings`: the raster lines of [`raster_lines`] visited nearest-first
/// (each line entered at its nearer end), consecutive lines joined by a depositing link when
/// the link is at most `link_max_mm` long and stays inside the region; otherwise a new polyline
/// starts (a travel). Deterministic.
pub fn zigzag(
    rings: &[Vec<P2>],
    angle_deg: f64,
    spacing_mm: f64,
    link_max_mm: f64,
    from: Option<P2>,
) -> Vec<Vec<P2>> {
    let lines: Vec<[P2; 2]> = raster_lines(rings, angle_deg, spacing_mm)
        .into_iter()
        .flatten()
        .collect();
    let mut used = vec![false; lines.len()];
    let mut out: Vec<Vec<P2>> = Vec::new();
    let mut cur: Option<P2> = from;
    for _ in 0..lines.len() {
        // Nearest unused line end to the current position (the first line when there is none).
        let mut best: Option<(f64, usize, bool)> = None;
        for (i, l) in lines.iter().enumerate() {
            if used[i] {
                continue;
            }
            let (d0, d1) = match cur {
                Some(c) => (dist(c, l[0]), dist(c, l[1])),
                None => (0.0, 1.0),
            };
            let (d, rev) = if d1 < d0 { (d1, true) } else { (d0, false) };
            if best.is_none_or(|b| d < b.0) {
                best = Some((d, i, rev));
            }
        }
        let Some((d, i, rev)) = best else { break };
        used[i] = true;
        let (a, b) = if rev {
            (lines[i][1], lines[i][0])
        } else {
            (lines[i][0], lines[i][1])
        };
        let linked = match (cur, out.last()) {
            (Some(c), Some(_)) => d <= link_max_mm && link_inside(rings, c, a),
            _ => false,
        };
        if linked {
            let last = out.last_mut().expect("checked above");
            if dist(*last.last().expect("non-empty"), a) > 1e-12 {
                last.push(a);
            }
            last.push(b);
        } else {
            out.push(vec![a, b]);
        }
        cur = Some(b);
    }
    out
}
