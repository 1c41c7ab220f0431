//! Every mesh in `tests/data/stl` (repo root) either slices to closed contours whose per-layer
//! net areas match a reference, or fails with a clear error; none panics.

use std::f64::consts::PI;
use std::path::PathBuf;

use cell_mesh::{slice, LayerStack, Mesh, MeshError, SliceParams, StlFormat};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/stl")
        .join(name)
}

fn load(name: &str) -> Mesh {
    Mesh::load_stl(data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn slice_n(mesh: &Mesh, layers: usize) -> (LayerStack, f64) {
    let (lo, hi) = mesh.bbox();
    let h = (hi[2] - lo[2]) / layers as f64;
    (slice(mesh, &SliceParams::new(h)).unwrap(), h)
}

/// All layers closed: no open chain, every contour ≥ 3 points, outers CCW and holes CW.
fn assert_closed_and_oriented(name: &str, st: &LayerStack) {
    for (k, l) in st.layers.iter().enumerate() {
        assert_eq!(l.index, k, "{name}: layer order");
        let z = st.first_z_mm + k as f64 * st.layer_height_mm;
        assert_eq!(l.z_mm, z, "{name}: layer {k} height");
        assert!(
            l.open_chains.is_empty(),
            "{name}: layer {} z={} has open chains {:?}",
            l.index,
            l.z_mm,
            l.open_chains
        );
        for c in &l.contours {
            assert!(c.points.len() >= 3);
            assert_ne!(c.points.first(), c.points.last(), "no repeated last point");
            let a = c.signed_area_mm2();
            assert_eq!(a < 0.0, c.is_hole, "{name}: layer {} orientation", l.index);
        }
    }
}

#[test]
fn watertight_meshes_report_clean_and_integrate_to_their_volume() {
    // Σ net area × h (midpoint rule) against the divergence-theorem volume.
    for (name, rel_tol) in [
        ("20mm-xyz-cube.stl", 1e-3),
        ("angle_block.STL", 2e-3),
        ("busted.STL", 1e-3),
        ("cylinder.stl", 1e-9),
        ("featuretype.STL", 5e-3),
        ("idler_riser.STL", 2e-3),
        ("plate_holes.STL", 1e-3),
        ("torus.STL", 1e-3),
        ("unit_sphere.STL", 1e-3),
    ] {
        let m = load(name);
        let r = m.report();
        assert_eq!(r.format, StlFormat::Binary, "{name}");
        assert!(r.is_closed_manifold(), "{name}: {r:?}");
        assert_eq!(r.inconsistent_edges, 0, "{name}");
        assert!(r.collapsed_triangles.is_empty(), "{name}");
        let (st, h) = slice_n(&m, 200);
        assert_eq!(st.layers.len(), 200, "{name}");
        assert_closed_and_oriented(name, &st);
        let integral: f64 = st.layers.iter().map(|l| l.net_area_mm2()).sum::<f64>() * h;
        let vol = m.signed_volume_mm3();
        assert!(
            ((integral - vol) / vol).abs() < rel_tol,
            "{name}: Σ area·h = {integral}, volume = {vol}"
        );
    }
}

#[test]
fn xyz_cube_is_400_mm2_outside_the_engraved_letters() {
    // 20 mm calibration cube; X/Y/Z letters are engraved 1 mm deep into its faces, so only
    // the layers clear of the letters are 20 × 20 = 400 mm² (exact up to the f32 coordinates:
    // the side is 20 ± 2e-6 mm, so ± 1e-4 mm²).
    let m = load("20mm-xyz-cube.stl");
    let (lo, hi) = m.bbox();
    assert!((hi[2] - lo[2] - 20.0).abs() < 1e-4);
    let st = slice(&m, &SliceParams::new(0.2)).unwrap();
    assert_eq!(st.layers.len(), 100);
    let mut exact = 0;
    for l in &st.layers {
        let dz = l.z_mm - lo[2];
        assert!(l.net_area_mm2() <= 400.0 + 1e-4, "layer {}", l.index);
        if (1.0..5.8).contains(&dz) || (14.0..19.0).contains(&dz) {
            assert_eq!(l.contours.len(), 1, "z={dz}");
            assert!(
                (l.net_area_mm2() - 400.0).abs() < 1e-4,
                "z={dz}: {} mm² vs 400",
                l.net_area_mm2()
            );
            exact += 1;
        }
    }
    assert_eq!(exact, 49);
    // The engraved top and bottom letters are holes at the outermost layers.
    assert!(st.layers[0].contours.iter().any(|c| c.is_hole));
    assert!(st.layers[99].contours.iter().any(|c| c.is_hole));
}

#[test]
fn cylinder_section_is_its_facet_ring_polygon() {
    // Radius 1, height 8; the ring is irregularly spaced, so the exact section is the polygon
    // through the ring vertices: A = ½ Σ sin(Δθ_i) (r = 1), computed here from the vertex angles.
    let m = load("cylinder.stl");
    let mut ang: Vec<f64> = m
        .vertices()
        .iter()
        .filter(|v| v[2] == 0.0 && ((v[0].hypot(v[1])) - 1.0).abs() < 1e-6)
        .map(|v| v[1].atan2(v[0]))
        .collect();
    ang.sort_by(f64::total_cmp);
    let n = ang.len();
    let ring: f64 = (0..n)
        .map(|i| {
            let d = if i + 1 < n {
                ang[i + 1] - ang[i]
            } else {
                ang[0] + 2.0 * PI - ang[i]
            };
            0.5 * d.sin()
        })
        .sum();
    assert!(ring < PI && ring > 0.99 * PI);
    let st = slice(&m, &SliceParams::new(0.1)).unwrap();
    assert_eq!(st.layers.len(), 80);
    for l in &st.layers {
        assert_eq!(l.contours.len(), 1);
        assert!(
            (l.net_area_mm2() - ring).abs() < 1e-5,
            "z={}: {} vs ring polygon {ring} (π r² = {PI})",
            l.z_mm,
            l.net_area_mm2()
        );
    }
}

#[test]
fn unit_sphere_section_between_inscribed_and_circumscribed_disks() {
    // Inscribed polytope: its section lies inside the disk π(1 − z²) and contains the disk
    // π(r_in² − z²), r_in = smallest distance from the centre to a face plane.
    let m = load("unit_sphere.STL");
    let v = m.vertices();
    let r_in = m
        .triangles()
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| v[i as usize]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [
                u[1] * w[2] - u[2] * w[1],
                u[2] * w[0] - u[0] * w[2],
                u[0] * w[1] - u[1] * w[0],
            ];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            ((n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / len).abs()
        })
        .fold(f64::INFINITY, f64::min);
    assert!(r_in > 0.98, "r_in = {r_in}");
    let st = slice(&m, &SliceParams::new(0.05)).unwrap();
    assert_eq!(st.layers.len(), 40);
    for l in &st.layers {
        assert_eq!(l.contours.len(), 1);
        let a = l.net_area_mm2();
        let outer = PI * (1.0 - l.z_mm * l.z_mm);
        let inner = PI * (r_in * r_in - l.z_mm * l.z_mm).max(0.0);
        assert!(
            a <= outer + 1e-9 && a >= inner - 1e-9,
            "z={}: {a} not in [{inner}, {outer}]",
            l.z_mm
        );
    }
}

#[test]
fn torus_has_two_contours_and_annulus_area() {
    // R = 1, r = 0.5: section at height z is an annulus of area 4πR·√(r² − z²).
    let m = load("torus.STL");
    let st = slice(&m, &SliceParams::new(0.02)).unwrap();
    let mut checked = 0;
    for l in &st.layers {
        assert_eq!(l.contours.len(), 2, "z={}", l.z_mm);
        assert_eq!(l.contours.iter().filter(|c| c.is_hole).count(), 1);
        let hole = l.contours.iter().position(|c| c.is_hole).unwrap();
        assert!(l.contours[hole].parent.is_some());
        if l.z_mm.abs() <= 0.35 {
            let exact = 4.0 * PI * (0.25 - l.z_mm * l.z_mm).sqrt();
            let rel = (l.net_area_mm2() - exact) / exact;
            assert!(rel.abs() < 5e-3, "z={}: rel err {rel}", l.z_mm);
            checked += 1;
        }
    }
    assert!(checked >= 30);
}

#[test]
fn plate_holes_is_outer_plus_five_holes_in_every_layer() {
    let m = load("plate_holes.STL");
    assert_eq!(m.report().boundary_edges, 0);
    let st = slice(&m, &SliceParams::new(0.5)).unwrap();
    assert_eq!(
        st.layers.len(),
        25,
        "12.7 mm plate at 0.5 mm, mid-layer planes"
    );
    for l in &st.layers {
        assert_eq!(l.contours.len(), 6, "z={}", l.z_mm);
        let holes: Vec<_> = l.contours.iter().filter(|c| c.is_hole).collect();
        assert_eq!(holes.len(), 5);
        let outer = l.contours.iter().position(|c| !c.is_hole).unwrap();
        assert!(holes.iter().all(|c| c.parent == Some(outer)));
    }
}

#[test]
fn soup_slices_to_reported_open_chains_only() {
    let m = load("soup.stl");
    let r = m.report();
    assert_eq!(r.input_triangles, 100);
    assert_eq!(
        r.boundary_edges, 300,
        "100 separate triangles: every edge is a boundary"
    );
    assert_eq!(r.boundary_loops, 100);
    let (st, _) = slice_n(&m, 20);
    assert!(st.open_chain_count() > 0);
    for l in &st.layers {
        for c in &l.open_chains {
            assert!(c.points.len() >= 2);
            let _ = (c.start(), c.end());
        }
        // Random triangles never close up within 1e-5 of the diagonal.
        assert!(l.contours.is_empty(), "z={}", l.z_mm);
    }
}

#[test]
fn teapot_reports_its_holes_and_still_slices() {
    let m = load("teapot.stl");
    let r = m.report();
    assert_eq!(
        r.boundary_edges, 64,
        "trimesh also counts 64 single-use edges"
    );
    assert!(r.boundary_loops >= 1);
    let (st, _) = slice_n(&m, 50);
    assert!(
        st.open_chain_count() > 0,
        "the open lid/spout rims leave open chains"
    );
    assert!(st.layers.iter().all(|l| !l.contours.is_empty()));
}

#[test]
fn empty_files_fail_naming_the_file() {
    for name in ["empty.stl", "empty_ascii.stl"] {
        match Mesh::load_stl(data(name)) {
            Err(e @ MeshError::Empty { .. }) => assert!(e.to_string().contains(name), "{e}"),
            other => panic!("{name}: expected Empty, got {other:?}"),
        }
    }
}

#[test]
fn truncated_binary_fails_with_triangle_index() {
    let bytes = std::fs::read(data("unit_sphere.STL")).unwrap();
    let cut = &bytes[..84 + 50 * 7 + 13];
    match Mesh::from_stl_bytes("cut.stl", cut, &Default::default()) {
        Err(e @ MeshError::Truncated { triangle: 7, .. }) => {
            assert!(e.to_string().contains("cut.stl"), "{e}")
        }
        other => panic!("expected Truncated at 7, got {other:?}"),
    }
}

#[test]
fn truncated_binary_with_solid_header_is_not_taken_for_ascii() {
    let bytes = std::fs::read(data("angle_block.STL")).unwrap();
    assert!(bytes.starts_with(b"solid "));
    let cut = &bytes[..84 + 50 * 300 + 1];
    match Mesh::from_stl_bytes("angle_cut.stl", cut, &Default::default()) {
        Err(MeshError::Truncated {
            triangle: 300,
            announced: 704,
            ..
        }) => {}
        other => panic!("expected Truncated at 300 of 704, got {other:?}"),
    }
}

#[test]
fn nan_coordinate_fails_with_triangle_index() {
    let mut bytes = std::fs::read(data("cylinder.stl")).unwrap();
    let off = 84 + 50 * 5 + 12 + 4 * 4; // triangle 5, vertex 1, y
    bytes[off..off + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    match Mesh::from_stl_bytes("nan.stl", &bytes, &Default::default()) {
        Err(MeshError::NonFinite {
            triangle: 5,
            vertex: 1,
            ..
        }) => {}
        other => panic!("expected NonFinite at 5/1, got {other:?}"),
    }
    let ascii = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 inf\n\
                 vertex 0 1 0\nendloop\nendfacet\nendsolid x\n";
    let e = Mesh::from_stl_bytes("inf.stl", ascii.as_bytes(), &Default::default()).unwrap_err();
    assert!(matches!(e, MeshError::Parse { triangle: 0, .. }), "{e}");
    assert!(e.to_string().contains("inf.stl"));
}

#[test]
fn ascii_and_binary_give_the_same_slices() {
    // The ASCII path of seed 004 §B3 against the binary file it was written from.
    let m = load("unit_sphere.STL");
    let mut txt = String::from("solid sphere\n");
    for t in m.triangles() {
        txt.push_str("facet normal 0 0 0\nouter loop\n");
        for &i in t {
            let p = m.vertices()[i as usize];
            txt.push_str(&format!(
                "vertex {} {} {}\n",
                p[0] as f32, p[1] as f32, p[2] as f32
            ));
        }
        txt.push_str("endloop\nendfacet\n");
    }
    txt.push_str("endsolid sphere\n");
    let a = Mesh::from_stl_bytes("sphere_ascii.stl", txt.as_bytes(), &Default::default()).unwrap();
    assert_eq!(a.report().format, StlFormat::Ascii);
    let p = SliceParams::new(0.1);
    let (sa, sb) = (slice(&a, &p).unwrap(), slice(&m, &p).unwrap());
    assert_eq!(sa.layers.len(), sb.layers.len());
    for (x, y) in sa.layers.iter().zip(&sb.layers) {
        assert!((x.net_area_mm2() - y.net_area_mm2()).abs() < 1e-9);
    }
}
