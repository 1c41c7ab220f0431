//! STL meshes (`Mesh::from_stl_bytes`, ASCII and binary), then a slice into at most 16 layers.

use cell_mesh::{slice, Mesh, MeshOptions, SliceParams};

use crate::{seed_files, Target};

const TOKENS: &[&str] = &[
    "solid ",
    "facet normal 0 0 1\n",
    "outer loop\n",
    "vertex ",
    "endloop\n",
    "endfacet\n",
    "endsolid",
    "1e308 ",
    "nan ",
    "-0 ",
    "\u{0}\u{0}\u{0}\u{0}",
    "\u{ff}\u{ff}\u{ff}\u{7f}",
];

fn stl(data: &[u8]) {
    let Ok(mesh) = Mesh::from_stl_bytes("input.stl", data, &MeshOptions::default()) else {
        return;
    };
    let _ = mesh.report().is_closed_manifold();
    let z: Vec<f64> = mesh.vertices().iter().map(|v| v[2]).collect();
    let (lo, hi) = z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let height = ((hi - lo) / 16.0).max(1e-3);
    if height.is_finite() {
        let _ = slice(&mesh, &SliceParams::new(height));
    }
}

fn seeds() -> Vec<Vec<u8>> {
    seed_files("tests/data/stl", &[".stl"], 64 << 10)
}

/// The STL target.
pub fn targets() -> Vec<Target> {
    vec![Target {
        name: "stl",
        about: "STL bytes (Mesh::from_stl_bytes), then slicing",
        run: stl,
        seeds,
        tokens: TOKENS,
        max_len: 64 << 10,
    }]
}
