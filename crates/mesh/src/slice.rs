//! Planar Z-slicing (seed 004 §B3, eqs. 8–11) with a sweep, topological chaining and
//! orientation by nesting.

use rustc_hash::FxHashMap as HashMap;

use rayon::prelude::*;

use crate::error::SliceError;
use crate::mesh::Mesh;
use cell_geometry::{bounding_box, point_in_ring_even_odd, signed_area_from_first_vertex};

/// A point sequence (x, y), mm.
type Ring = Vec<[f64; 2]>;

/// Upper bound on the number of layers one [`slice()`] call produces (guards against absurd
/// layer heights or corrupt coordinates).
pub const MAX_LAYERS: usize = 1_000_000;

/// Slicing parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliceParams {
    /// Distance between planes, mm (seed 004 §B10 example: 1.6 mm).
    pub layer_height_mm: f64,
    /// Height of the first plane, mm. `None`: `z_min + layer_height_mm / 2` (mid-layer slicing,
    /// so each plane cuts through the middle of the bead it stands for; the thesis leaves the
    /// planes to the user, §B3 — this default is our choice).
    pub first_z_mm: Option<f64>,
    /// Largest gap closed when joining open chains end to end, mm (used only for chains the exact
    /// topological linking left open, e.g. triangle soup). `None`: 1e-5 × bbox diagonal.
    pub chain_tolerance_mm: Option<f64>,
}

impl SliceParams {
    /// Mid-layer planes at the given height, default chaining tolerance.
    pub fn new(layer_height_mm: f64) -> Self {
        SliceParams {
            layer_height_mm,
            first_z_mm: None,
            chain_tolerance_mm: None,
        }
    }
}

/// A closed polygon of one layer: points in mm, no repeated last point, at least 3 points.
/// Outer contours run counter-clockwise, holes clockwise.
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    /// Vertices (x, y), mm.
    pub points: Vec<[f64; 2]>,
    /// True for a hole (odd nesting depth).
    pub is_hole: bool,
    /// Index (in [`Layer::contours`]) of the innermost contour enclosing this one.
    pub parent: Option<usize>,
}

impl Contour {
    /// Signed area, mm² (positive for outer contours, negative for holes).
    pub fn signed_area_mm2(&self) -> f64 {
        signed_area_from_first_vertex(&self.points)
    }
}

/// A chain of segments that could not be closed, with its endpoints.
#[derive(Debug, Clone, PartialEq)]
pub struct OpenChain {
    /// Points (x, y), mm, in chain order (at least 2).
    pub points: Vec<[f64; 2]>,
}

impl OpenChain {
    /// First point.
    pub fn start(&self) -> [f64; 2] {
        self.points[0]
    }
    /// Last point.
    pub fn end(&self) -> [f64; 2] {
        self.points[self.points.len() - 1]
    }
}

/// One slice plane's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Layer index, 0 at the first plane.
    pub index: usize,
    /// Plane height, mm.
    pub z_mm: f64,
    /// Closed contours.
    pub contours: Vec<Contour>,
    /// Chains left open (holes in the mesh, soup that does not meet); reported, not dropped.
    pub open_chains: Vec<OpenChain>,
    /// Closed loops dropped because fewer than 3 distinct points remained (slivers).
    pub degenerate_loops: usize,
}

impl Layer {
    /// Net area, mm²: the sum of the contours' signed areas (outers minus holes).
    pub fn net_area_mm2(&self) -> f64 {
        self.contours.iter().map(Contour::signed_area_mm2).sum()
    }
}

/// All layers of one mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerStack {
    /// Layers in increasing z; layer `k` is at `first_z_mm + k · layer_height_mm`.
    pub layers: Vec<Layer>,
    /// Plane spacing, mm.
    pub layer_height_mm: f64,
    /// Height of layer 0, mm.
    pub first_z_mm: f64,
    /// Tolerance used for joining open chains, mm.
    pub chain_tolerance_mm: f64,
}

impl LayerStack {
    /// Total open chains over all layers.
    pub fn open_chain_count(&self) -> usize {
        self.layers.iter().map(|l| l.open_chains.len()).sum()
    }
}

/// What [`slice()`] returns.
pub type LayerStackResult = Result<LayerStack, SliceError>;

/// Slices `mesh` with horizontal planes `z_k = first_z + k·h`, `k = 0, 1, …` while `z_k < z_max`.
///
/// A triangle crosses plane z when some corner is below (`z_v < z`) and some is above
/// (`z_v >= z`): a corner on the plane counts as above (symbolic perturbation of the plane
/// downwards), so every crossing triangle has exactly two crossing sides and each crossing mesh
/// edge gives one point shared by its two triangles. The point on edge P_i–P_j is
/// `P_i + t (P_j − P_i)`, `t = (z − z_i)/(z_j − z_i)` (seed 004 eqs. 8–11), computed once per
/// edge from its lower vertex id, and exactly the vertex when it lies on the plane.
///
/// Cost: O(n log n) for the sort plus O(1) per (triangle, spanned layer) in the sweep; the
/// per-layer chaining runs in parallel and the output order is fixed by the layer index.
pub fn slice(mesh: &Mesh, params: &SliceParams) -> LayerStackResult {
    let h = params.layer_height_mm;
    if !(h.is_finite() && h > 0.0) {
        return Err(SliceError::BadLayerHeight(h));
    }
    let (lo, hi) = mesh.bbox();
    let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let first = params.first_z_mm.unwrap_or(lo[2] + 0.5 * h);
    if !first.is_finite() {
        return Err(SliceError::BadParam {
            field: "first_z_mm",
            value: first,
        });
    }
    let tol = params.chain_tolerance_mm.unwrap_or(1e-5 * diag);
    if !(tol.is_finite() && tol >= 0.0) {
        return Err(SliceError::BadParam {
            field: "chain_tolerance_mm",
            value: tol,
        });
    }
    let span = (hi[2] - first) / h;
    if span.is_nan() || span >= MAX_LAYERS as f64 {
        return Err(SliceError::TooManyLayers {
            layers: span,
            layer_height_mm: h,
            height_mm: hi[2] - first,
            max: MAX_LAYERS,
        });
    }
    let mut zs = Vec::new();
    if span > 0.0 {
        let mut k = 0usize;
        loop {
            let z = first + k as f64 * h;
            if z >= hi[2] {
                break;
            }
            zs.push(z);
            k += 1;
        }
    }

    // Sweep: triangles sorted by lowest z; `active` holds those with z_min < z <= z_max.
    let verts = mesh.vertices();
    let tris = mesh.triangles();
    let zrange: Vec<(f64, f64)> = tris
        .iter()
        .map(|t| {
            let z = t.map(|i| verts[i as usize][2]);
            (z[0].min(z[1]).min(z[2]), z[0].max(z[1]).max(z[2]))
        })
        .collect();
    let mut keyed: Vec<(f64, u32)> = zrange
        .iter()
        .enumerate()
        .map(|(t, r)| (r.0, t as u32))
        .collect();
    keyed.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let order: Vec<u32> = keyed.into_iter().map(|(_, t)| t).collect();
    // Layers go in batches: the sweep collects each batch's crossing triangles, then the batch
    // is chained in parallel, so memory stays bounded by one batch, not the whole stack.
    const BATCH: usize = 64;
    let mut layers: Vec<Layer> = Vec::with_capacity(zs.len());
    let mut active: Vec<u32> = Vec::new();
    let mut next = 0;
    for (b, zb) in zs.chunks(BATCH).enumerate() {
        let mut per_layer: Vec<Vec<u32>> = Vec::with_capacity(zb.len());
        for &z in zb {
            while next < order.len() && zrange[order[next] as usize].0 < z {
                active.push(order[next]);
                next += 1;
            }
            active.retain(|&t| zrange[t as usize].1 >= z);
            per_layer.push(active.clone());
        }
        let batch: Vec<Layer> = per_layer
            .into_par_iter()
            .zip(zb.par_iter())
            .enumerate()
            .map(|(k, (crossing, &z))| slice_layer(mesh, b * BATCH + k, z, &crossing, tol))
            .collect();
        layers.extend(batch);
    }
    Ok(LayerStack {
        layers,
        layer_height_mm: h,
        first_z_mm: first,
        chain_tolerance_mm: tol,
    })
}

/// Point where mesh edge `e` crosses plane z (seed 004 eqs. 8–11), from the lower vertex id.
fn edge_point(mesh: &Mesh, e: u32, z: f64) -> [f64; 2] {
    let [i, j] = mesh.edges()[e as usize];
    let a = mesh.vertices()[i as usize];
    let b = mesh.vertices()[j as usize];
    if a[2] == z {
        return [a[0], a[1]];
    }
    if b[2] == z {
        return [b[0], b[1]];
    }
    let t = (z - a[2]) / (b[2] - a[2]);
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

fn slice_layer(mesh: &Mesh, index: usize, z: f64, crossing: &[u32], tol: f64) -> Layer {
    let verts = mesh.vertices();
    let tris = mesh.triangles();
    let tri_edges = mesh.triangle_edges();
    // One segment per crossing triangle, as the two mesh edges it runs between. Direction: from
    // the side going above→below to the side going below→above (material on the left for an
    // outward-wound triangle); orientation is fixed later by nesting anyway.
    let mut segs: Vec<[u32; 2]> = Vec::with_capacity(crossing.len());
    for &t in crossing {
        let tv = tris[t as usize];
        let below = tv.map(|v| verts[v as usize][2] < z);
        let mut from = u32::MAX;
        let mut to = u32::MAX;
        for i in 0..3 {
            let (a, b) = (below[i], below[(i + 1) % 3]);
            if !a && b {
                from = tri_edges[t as usize][i];
            } else if a && !b {
                to = tri_edges[t as usize][i];
            }
        }
        if from != u32::MAX && to != u32::MAX {
            segs.push([from, to]);
        }
    }

    // Nodes = crossed mesh edges; incidence by sorting (edge, segment end) pairs.
    let mut inc: Vec<(u32, u32)> = Vec::with_capacity(segs.len() * 2);
    for (s, sg) in segs.iter().enumerate() {
        inc.push((sg[0], s as u32));
        inc.push((sg[1], s as u32));
    }
    inc.sort_unstable();
    let mut node_start: Vec<usize> = Vec::new(); // into `inc`
    let mut node_pt: Vec<[f64; 2]> = Vec::new();
    let mut seg_nodes: Vec<[u32; 2]> = vec![[u32::MAX; 2]; segs.len()];
    for (k, &(e, s)) in inc.iter().enumerate() {
        if k == 0 || inc[k - 1].0 != e {
            node_start.push(k);
            node_pt.push(edge_point(mesh, e, z));
        }
        let n = (node_start.len() - 1) as u32;
        let sn = &mut seg_nodes[s as usize];
        if segs[s as usize][0] == e && sn[0] == u32::MAX {
            sn[0] = n;
        } else {
            sn[1] = n;
        }
    }
    node_start.push(inc.len());
    let deg = |n: u32| node_start[n as usize + 1] - node_start[n as usize];
    let other_seg = |n: u32, s: u32| -> u32 {
        let (a, b) = (node_start[n as usize], node_start[n as usize + 1]);
        inc[a..b]
            .iter()
            .map(|&(_, t)| t)
            .find(|&t| t != s)
            .unwrap_or(s)
    };
    let other_node = |s: u32, n: u32| -> u32 {
        let sn = seg_nodes[s as usize];
        if sn[0] == n {
            sn[1]
        } else {
            sn[0]
        }
    };

    let mut visited = vec![false; segs.len()];
    let mut open: Vec<Vec<[f64; 2]>> = Vec::new();
    let mut closed: Vec<Vec<[f64; 2]>> = Vec::new();
    // Open chains: walk from every terminal node (degree ≠ 2) along pass-through nodes.
    for n0 in 0..node_pt.len() as u32 {
        if deg(n0) == 2 {
            continue;
        }
        let (a, b) = (node_start[n0 as usize], node_start[n0 as usize + 1]);
        for &(_, first_seg) in &inc[a..b] {
            let mut s = first_seg;
            if visited[s as usize] {
                continue;
            }
            let mut cur = n0;
            let mut pts = vec![node_pt[n0 as usize]];
            loop {
                visited[s as usize] = true;
                let nx = other_node(s, cur);
                pts.push(node_pt[nx as usize]);
                if deg(nx) != 2 {
                    break;
                }
                let s2 = other_seg(nx, s);
                if visited[s2 as usize] {
                    break;
                }
                s = s2;
                cur = nx;
            }
            open.push(pts);
        }
    }
    // The rest are cycles through degree-2 nodes.
    for s0 in 0..segs.len() as u32 {
        if visited[s0 as usize] {
            continue;
        }
        let start = seg_nodes[s0 as usize][0];
        let mut pts = vec![node_pt[start as usize]];
        let (mut s, mut cur) = (s0, start);
        loop {
            visited[s as usize] = true;
            let nx = other_node(s, cur);
            if nx == start {
                break;
            }
            pts.push(node_pt[nx as usize]);
            let s2 = other_seg(nx, s);
            if visited[s2 as usize] {
                break;
            }
            s = s2;
            cur = nx;
        }
        closed.push(pts);
    }

    let (joined_closed, still_open) = join_open_chains(open, tol);
    closed.extend(joined_closed);

    let mut degenerate_loops = 0;
    let mut rings: Vec<Vec<[f64; 2]>> = Vec::with_capacity(closed.len());
    for mut r in closed {
        r.dedup();
        while r.len() > 1 && r.first() == r.last() {
            r.pop();
        }
        if r.len() < 3 || signed_area_from_first_vertex(&r) == 0.0 {
            degenerate_loops += 1;
        } else {
            rings.push(r);
        }
    }
    let contours = orient_by_nesting(rings);
    let open_chains = still_open
        .into_iter()
        .map(|mut p| {
            p.dedup();
            if p.len() == 1 {
                p.push(p[0]);
            }
            OpenChain { points: p }
        })
        .collect();
    Layer {
        index,
        z_mm: z,
        contours,
        open_chains,
        degenerate_loops,
    }
}

/// Joins open chains whose endpoints lie within `tol` (fallback for soup and non-manifold
/// edges). Greedy in input order on a uniform grid of cell `tol`: each chain grows at its tail,
/// then at its head, taking the nearest free endpoint, and closes when its ends meet.
/// Returns (closed rings, chains still open).
fn join_open_chains(chains: Vec<Ring>, tol: f64) -> (Vec<Ring>, Vec<Ring>) {
    if chains.is_empty() {
        return (Vec::new(), Vec::new());
    }
    // With tol = 0 only identical endpoints join: key on the bits and probe one cell.
    let reach: i64 = if tol > 0.0 { 1 } else { 0 };
    let key = |p: [f64; 2]| {
        if tol > 0.0 {
            [(p[0] / tol).floor() as i64, (p[1] / tol).floor() as i64]
        } else {
            [(p[0] + 0.0).to_bits() as i64, (p[1] + 0.0).to_bits() as i64]
        }
    };
    let mut grid: HashMap<[i64; 2], Vec<(u32, bool)>> = HashMap::default(); // (chain, is_tail)
    for (i, c) in chains.iter().enumerate() {
        grid.entry(key(c[0])).or_default().push((i as u32, false));
        grid.entry(key(c[c.len() - 1]))
            .or_default()
            .push((i as u32, true));
    }
    let d2 = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
    let mut used = vec![false; chains.len()];
    let mut closed = Vec::new();
    let mut open = Vec::new();
    for i in 0..chains.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let mut pts = chains[i].clone();
        let mut is_closed = false;
        for _pass in 0..2 {
            loop {
                let tail = pts[pts.len() - 1];
                if pts.len() > 2 && d2(tail, pts[0]) <= tol * tol {
                    is_closed = true;
                    break;
                }
                let k = key(tail);
                let mut best: Option<(f64, u32, bool)> = None;
                for dx in -reach..=reach {
                    for dy in -reach..=reach {
                        let kk = [k[0].saturating_add(dx), k[1].saturating_add(dy)];
                        for &(j, at_tail) in grid.get(&kk).map(|v| v.as_slice()).unwrap_or(&[]) {
                            if used[j as usize] {
                                continue;
                            }
                            let c = &chains[j as usize];
                            let p = if at_tail { c[c.len() - 1] } else { c[0] };
                            let d = d2(tail, p);
                            if d <= tol * tol && best.is_none_or(|b| d < b.0) {
                                best = Some((d, j, at_tail));
                            }
                        }
                    }
                }
                let Some((_, j, at_tail)) = best else { break };
                used[j as usize] = true;
                let c = &chains[j as usize];
                if at_tail {
                    pts.extend(c.iter().rev().skip(1));
                } else {
                    pts.extend(c.iter().skip(1));
                }
            }
            if is_closed {
                break;
            }
            pts.reverse();
        }
        if is_closed {
            closed.push(pts);
        } else {
            open.push(pts);
        }
    }
    (closed, open)
}

/// Nesting depth by point-in-polygon (bounding boxes first); even depth → outer, made
/// counter-clockwise; odd → hole, made clockwise. Parent = smallest enclosing ring.
fn orient_by_nesting(mut rings: Vec<Vec<[f64; 2]>>) -> Vec<Contour> {
    let n = rings.len();
    let bb: Vec<_> = rings.iter().map(bounding_box).collect();
    let area: Vec<f64> = rings
        .iter()
        .map(|r| signed_area_from_first_vertex(r).abs())
        .collect();
    let mut out = Vec::with_capacity(n);
    let mut meta = Vec::with_capacity(n);
    for i in 0..n {
        let p = rings[i][0];
        let mut depth = 0;
        let mut parent: Option<usize> = None;
        for j in 0..n {
            if i == j || area[j] <= area[i] {
                continue;
            }
            let (lo, hi) = bb[j];
            if p[0] < lo[0] || p[0] > hi[0] || p[1] < lo[1] || p[1] > hi[1] {
                continue;
            }
            // Walked backwards, as this test always has: the same crossing abscissae.
            if point_in_ring_even_odd(p, rings[j].iter().rev()) {
                depth += 1;
                if parent.is_none_or(|q| area[j] < area[q]) {
                    parent = Some(j);
                }
            }
        }
        meta.push((depth % 2 == 1, parent));
    }
    for (r, (is_hole, parent)) in rings.iter_mut().zip(meta) {
        let ccw = signed_area_from_first_vertex(r) > 0.0;
        if ccw == is_hole {
            r.reverse();
        }
        out.push(Contour {
            points: std::mem::take(r),
            is_hole,
            parent,
        });
    }
    out
}
