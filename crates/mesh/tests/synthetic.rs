//! Generated solids: planes through faces and vertices (symbolic perturbation), random convex
//! frustums against their exact cross-sections, and byte-mangled STL that must never panic.

use cell_mesh::{slice, Mesh, MeshOptions, SliceParams, WeldTolerance};
use proptest::prelude::*;

type Tri = [[f64; 3]; 3];

/// Axis box [0,s]^3 with each face split into an n×n grid of quads (2 triangles each),
/// outward winding.
fn grid_box(s: f64, n: usize) -> Vec<Tri> {
    let mut out = Vec::new();
    let step = s / n as f64;
    // (fixed axis, value, outward sign)
    for axis in 0..3 {
        for &(val, sign) in &[(0.0, -1.0), (s, 1.0)] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for i in 0..n {
                for j in 0..n {
                    let p = |a: usize, b: usize| {
                        let mut q = [0.0; 3];
                        q[axis] = val;
                        q[u] = a as f64 * step;
                        q[v] = b as f64 * step;
                        q
                    };
                    let (p00, p10, p11, p01) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                    // u × v = +axis, so CCW in (u, v) faces +axis.
                    if sign > 0.0 {
                        out.push([p00, p10, p11]);
                        out.push([p00, p11, p01]);
                    } else {
                        out.push([p00, p11, p10]);
                        out.push([p00, p01, p11]);
                    }
                }
            }
        }
    }
    out
}

fn mesh(tris: &[Tri]) -> Mesh {
    Mesh::from_triangles("generated", tris, &MeshOptions::default()).unwrap()
}

#[test]
fn cube_with_faces_on_slice_planes() {
    // Side 2, planes at z = 0, 1 (and 2 is not < z_max): the bottom face lies in plane 0.
    for n in [1, 2, 4] {
        let m = mesh(&grid_box(2.0, n));
        assert!(m.report().is_closed_manifold());
        assert_eq!(m.report().inconsistent_edges, 0);
        assert!((m.signed_volume_mm3() - 8.0).abs() < 1e-12);
        let p = SliceParams {
            layer_height_mm: 1.0,
            first_z_mm: Some(0.0),
            chain_tolerance_mm: None,
        };
        let st = slice(&m, &p).unwrap();
        assert_eq!(st.layers.len(), 2, "n={n}");
        // Plane z = 0 holds the bottom face: every corner counts as above, nothing is cut.
        assert!(st.layers[0].contours.is_empty() && st.layers[0].open_chains.is_empty());
        // Plane z = 1 runs through the grid vertices of the side faces when n is even.
        let l = &st.layers[1];
        assert_eq!(l.contours.len(), 1, "n={n}: {l:?}");
        assert!(l.open_chains.is_empty());
        assert_eq!(l.net_area_mm2(), 4.0, "n={n}");
        assert!(!l.contours[0].is_hole);
        // No doubled points (a plane through a vertex must give that vertex once).
        let mut pts = l.contours[0].points.clone();
        pts.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let len = pts.len();
        pts.dedup();
        assert_eq!(
            pts.len(),
            len,
            "n={n}: doubled point in {:?}",
            l.contours[0].points
        );
    }
}

#[test]
fn planes_through_every_vertex_row_of_the_subdivided_cube() {
    // Side 4, 4×4 grid: vertices at z = 0,1,2,3,4; planes exactly at 0..3.
    let m = mesh(&grid_box(4.0, 4));
    let p = SliceParams {
        layer_height_mm: 1.0,
        first_z_mm: Some(0.0),
        chain_tolerance_mm: Some(0.0),
    };
    let st = slice(&m, &p).unwrap();
    assert_eq!(st.layers.len(), 4);
    for l in &st.layers[1..] {
        assert_eq!(l.contours.len(), 1);
        assert_eq!(l.net_area_mm2(), 16.0, "z={}", l.z_mm);
        assert_eq!(
            l.contours[0].points.len(),
            16,
            "4 corners + 3 grid points per side"
        );
    }
}

#[test]
fn octahedron_plane_through_equator_vertices() {
    // |x| + |y| + |z| <= 1; the plane z = 0 holds four vertices; the section is the square
    // |x| + |y| <= 1 of area 2. Planes at ±0.5 give area 2·0.5² = 0.5.
    let v = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
    ];
    let (top, bot) = ([0.0, 0.0, 1.0], [0.0, 0.0, -1.0]);
    let mut tris = Vec::new();
    for i in 0..4 {
        let (a, b) = (v[i], v[(i + 1) % 4]);
        tris.push([a, b, top]);
        tris.push([b, a, bot]);
    }
    let m = mesh(&tris);
    assert!((m.signed_volume_mm3() - 4.0 / 3.0).abs() < 1e-12);
    let p = SliceParams {
        layer_height_mm: 0.5,
        first_z_mm: Some(-1.0),
        chain_tolerance_mm: Some(0.0),
    };
    let st = slice(&m, &p).unwrap();
    let areas: Vec<f64> = st.layers.iter().map(|l| l.net_area_mm2()).collect();
    // z = -1 (apex: nothing), -0.5, 0, 0.5.
    assert_eq!(areas, vec![0.0, 0.5, 2.0, 0.5]);
    assert!(st.layers[0].contours.is_empty());
    assert_eq!(
        st.layers[2].contours[0].points.len(),
        4,
        "no doubled vertex points"
    );
    assert_eq!(st.open_chain_count(), 0);
}

#[test]
fn hole_in_mesh_leaves_an_open_chain_with_endpoints() {
    let mut tris = grid_box(2.0, 2);
    // Drop one side triangle: a hole crossed by plane z = 0.5.
    let idx = tris
        .iter()
        .position(|t| t.iter().all(|p| p[0] == 0.0) && t.iter().any(|p| p[2] == 0.0))
        .unwrap();
    tris.remove(idx);
    let m = mesh(&tris);
    assert_eq!(m.report().boundary_edges, 3);
    assert_eq!(m.report().boundary_loops, 1);
    let p = SliceParams {
        layer_height_mm: 0.5,
        first_z_mm: Some(0.5),
        chain_tolerance_mm: Some(0.0),
    };
    let st = slice(&m, &p).unwrap();
    let l = &st.layers[0];
    assert_eq!(l.open_chains.len(), 1, "{l:?}");
    assert!(l.contours.is_empty());
    let c = &l.open_chains[0];
    assert_eq!(c.start()[0], 0.0);
    assert_eq!(c.end()[0], 0.0);
    // A gap-bridging tolerance closes it again.
    let st = slice(
        &m,
        &SliceParams {
            chain_tolerance_mm: Some(1.5),
            ..p
        },
    )
    .unwrap();
    assert_eq!(st.layers[0].contours.len(), 1);
    assert_eq!(st.layers[0].net_area_mm2(), 4.0);
}

#[test]
fn unwelded_copy_chains_by_tolerance() {
    // Weld tolerance 0 and every triangle jittered by < 1e-9: topology is gone, the tolerance
    // fallback must still close the square.
    let mut tris = grid_box(2.0, 2);
    for (k, t) in tris.iter_mut().enumerate() {
        for p in t.iter_mut() {
            p[0] += (k % 7) as f64 * 1e-10;
        }
    }
    let m = Mesh::from_triangles(
        "jitter",
        &tris,
        &MeshOptions {
            weld: WeldTolerance::AbsoluteMm(0.0),
        },
    )
    .unwrap();
    assert!(m.report().boundary_edges > 0);
    let st = slice(&m, &SliceParams::new(0.5)).unwrap();
    for l in &st.layers {
        assert_eq!(l.contours.len(), 1, "z={}: {l:?}", l.z_mm);
        assert!((l.net_area_mm2() - 4.0).abs() < 1e-8);
    }
}

#[test]
fn bad_slice_params_are_errors() {
    let m = mesh(&grid_box(1.0, 1));
    for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(slice(&m, &SliceParams::new(h)).is_err(), "h={h}");
    }
    assert!(
        slice(&m, &SliceParams::new(1e-9)).is_err(),
        "too many layers"
    );
    let p = SliceParams {
        first_z_mm: Some(f64::NAN),
        ..SliceParams::new(0.1)
    };
    assert!(slice(&m, &p).is_err());
}

/// Frustum of a convex polygon: bottom P0 at z0, top s·P0 + (dx, dy) at z0 + H. Sides are
/// planar quads split into two triangles; caps are fans. The section at fraction t is
/// P0 scaled by (1 − t + t·s) (then shifted), so its area is A0·(1 − t + t·s)².
fn frustum(poly: &[[f64; 2]], s: f64, d: [f64; 2], z0: f64, hgt: f64) -> Vec<Tri> {
    let n = poly.len();
    let b: Vec<[f64; 3]> = poly.iter().map(|p| [p[0], p[1], z0]).collect();
    let t: Vec<[f64; 3]> = poly
        .iter()
        .map(|p| [s * p[0] + d[0], s * p[1] + d[1], z0 + hgt])
        .collect();
    let mut out = Vec::new();
    for i in 0..n {
        let j = (i + 1) % n;
        out.push([b[i], b[j], t[j]]);
        out.push([b[i], t[j], t[i]]);
    }
    for i in 1..n - 1 {
        out.push([b[0], b[i + 1], b[i]]);
        out.push([t[0], t[i], t[i + 1]]);
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn random_convex_frustums_slice_to_one_exact_contour(
        angles in prop::collection::btree_set(0u32..3600, 3..24),
        rx in 1.0f64..30.0,
        ry in 1.0f64..30.0,
        s in 0.2f64..2.0,
        dx in -5.0f64..5.0,
        dy in -5.0f64..5.0,
        z0 in -20.0f64..20.0,
        hgt in 1.0f64..40.0,
        layer in 0.05f64..2.0,
    ) {
        // Points on an ellipse at sorted angles: a convex polygon, counter-clockwise.
        let poly: Vec<[f64; 2]> = angles
            .iter()
            .map(|&a| {
                let th = a as f64 / 3600.0 * std::f64::consts::TAU;
                [rx * th.cos(), ry * th.sin()]
            })
            .collect();
        let a0 = cell_geometry::signed_area_from_first_vertex(&poly);
        prop_assume!(a0 > 1e-3 * rx * ry);
        let m = mesh(&frustum(&poly, s, [dx, dy], z0, hgt));
        prop_assert!(m.report().is_closed_manifold());
        let st = slice(&m, &SliceParams::new(layer)).unwrap();
        prop_assert!(!st.layers.is_empty());
        for l in &st.layers {
            prop_assert_eq!(l.contours.len(), 1, "z={}", l.z_mm);
            prop_assert!(l.open_chains.is_empty());
            prop_assert!(!l.contours[0].is_hole);
            let t = (l.z_mm - z0) / hgt;
            let exact = a0 * (1.0 - t + t * s).powi(2);
            let got = l.net_area_mm2();
            prop_assert!(((got - exact) / exact).abs() < 1e-9, "z={} got {} exact {}", l.z_mm, got, exact);
        }
    }

    #[test]
    fn mangled_stl_bytes_never_panic(
        cut in 0usize..40_000,
        flips in prop::collection::vec((0usize..40_000, any::<u8>()), 0..8),
        truncate in any::<bool>(),
        solid_header in any::<bool>(),
    ) {
        // cylinder.stl has a zero header; angle_block.STL is binary behind a "solid " header.
        let name = if solid_header { "angle_block.STL" } else { "cylinder.stl" };
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/data/stl")
            .join(name);
        let mut bytes = std::fs::read(path).unwrap();
        for (pos, val) in flips {
            let k = pos % bytes.len();
            bytes[k] = val;
        }
        if truncate {
            bytes.truncate(cut % (bytes.len() + 1));
        }
        if let Ok(m) = Mesh::from_stl_bytes("mangled.stl", &bytes, &MeshOptions::default()) {
            let (lo, hi) = m.bbox();
            let h = ((hi[2] - lo[2]) / 20.0).max(1e-3);
            // Ok or Err (e.g. too many layers after a flipped exponent), never a panic.
            let _ = slice(&m, &SliceParams::new(h));
        }
    }

    #[test]
    fn mangled_ascii_never_panics(
        cut in 0usize..2000,
        flips in prop::collection::vec((0usize..2000, 32u8..127), 0..6),
    ) {
        let mut bytes = ASCII_TET.as_bytes().to_vec();
        for (pos, val) in flips {
            let k = pos % bytes.len();
            bytes[k] = val;
        }
        bytes.truncate(cut % (bytes.len() + 1));
        if let Ok(m) = Mesh::from_stl_bytes("mangled_ascii.stl", &bytes, &MeshOptions::default()) {
            let _ = slice(&m, &SliceParams::new(0.1));
        }
    }
}

const ASCII_TET: &str = "solid tet
facet normal 0 0 -1
outer loop
vertex 0 0 0
vertex 0 1 0
vertex 1 0 0
endloop
endfacet
facet normal 0 -1 0
outer loop
vertex 0 0 0
vertex 1 0 0
vertex 0 0 1
endloop
endfacet
facet normal -1 0 0
outer loop
vertex 0 0 0
vertex 0 0 1
vertex 0 1 0
endloop
endfacet
facet normal 1 1 1
outer loop
vertex 1 0 0
vertex 0 1 0
vertex 0 0 1
endloop
endfacet
endsolid tet
";

#[test]
fn ascii_tetrahedron_slices() {
    let m = Mesh::from_stl_bytes("tet.stl", ASCII_TET.as_bytes(), &MeshOptions::default()).unwrap();
    assert!(m.report().is_closed_manifold());
    assert_eq!(m.report().inconsistent_edges, 0);
    let st = slice(
        &m,
        &SliceParams {
            layer_height_mm: 0.25,
            first_z_mm: Some(0.0),
            chain_tolerance_mm: None,
        },
    )
    .unwrap();
    // Section at z is the triangle x, y >= 0, x + y <= 1 − z: area (1 − z)²/2.
    for l in &st.layers[1..] {
        let exact = (1.0 - l.z_mm).powi(2) / 2.0;
        assert!((l.net_area_mm2() - exact).abs() < 1e-12, "z={}", l.z_mm);
    }
}

fn shifted(tris: &[Tri], d: [f64; 3]) -> Vec<Tri> {
    tris.iter()
        .map(|t| t.map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]]))
        .collect()
}

#[test]
fn two_cubes_sharing_an_edge_are_reported_and_still_close() {
    // Cubes [0,2]³ and [2,4]×[2,4]×[0,2] touch along the vertical edge x = y = 2: four
    // triangles use each of its sub-edges.
    let mut tris = grid_box(2.0, 1);
    tris.extend(shifted(&grid_box(2.0, 1), [2.0, 2.0, 0.0]));
    let m = mesh(&tris);
    assert!(m.report().non_manifold_edges >= 1, "{:?}", m.report());
    let st = slice(&m, &SliceParams::new(0.5)).unwrap();
    for l in &st.layers {
        assert!(l.open_chains.is_empty(), "z={}: {l:?}", l.z_mm);
        assert!((l.net_area_mm2() - 8.0).abs() < 1e-12, "z={}", l.z_mm);
    }
}

#[test]
fn flipped_triangle_is_reported_and_slicing_is_unaffected() {
    let mut tris = grid_box(2.0, 2);
    tris[5].swap(1, 2);
    let m = mesh(&tris);
    assert_eq!(m.report().inconsistent_edges, 3);
    assert!(m.report().is_closed_manifold());
    let st = slice(&m, &SliceParams::new(0.25)).unwrap();
    for l in &st.layers {
        assert_eq!(l.contours.len(), 1);
        assert_eq!(l.net_area_mm2(), 4.0);
    }
}

#[test]
fn collapsed_and_degenerate_triangles_are_listed() {
    let mut tris = grid_box(2.0, 1);
    let n = tris.len();
    // Two corners 1e-9 apart: collapsed by the weld (tolerance 1e-6 × diag ≈ 3.5e-6).
    tris.push([[0.0, 0.0, 0.0], [1e-9, 0.0, 0.0], [0.0, 1.0, 1.0]]);
    // Collinear corners: kept, but degenerate.
    tris.push([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]);
    let m = mesh(&tris);
    assert_eq!(m.report().collapsed_triangles, vec![n]);
    assert_eq!(m.report().degenerate_triangles, vec![n + 1]);
    assert_eq!(m.triangles().len(), n + 1);
    let _ = slice(&m, &SliceParams::new(0.5)).unwrap();
}

#[test]
fn slicing_is_deterministic() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/stl/featuretype.STL");
    let m = Mesh::load_stl(path).unwrap();
    let p = SliceParams::new(0.01);
    let a = slice(&m, &p).unwrap();
    for _ in 0..3 {
        assert_eq!(slice(&m, &p).unwrap(), a);
    }
}
