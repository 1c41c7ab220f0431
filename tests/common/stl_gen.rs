//! Closed triangle meshes the WAAM acceptance test generates: a thin-walled box (a rectangular
//! tube, the classic WAAM wall) and a round pin. Outward winding throughout.
#![allow(dead_code)] // each test binary uses a different subset

use super::voxels::Mesh;

/// Two triangles of the quad `a b c d` (counter-clockwise seen from outside).
fn quad(out: &mut Vec<[[f64; 3]; 3]>, a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) {
    out.push([a, b, c]);
    out.push([a, c, d]);
}

/// An open-topped and open-bottomed rectangular tube: outer `length × width`, walls `wall`
/// thick, `height` tall, its bottom at z = 0 and its outer corner at the origin.
pub fn thin_walled_box(length: f64, width: f64, wall: f64, height: f64) -> Mesh {
    let ring = |inset: f64| {
        [
            [inset, inset],
            [length - inset, inset],
            [length - inset, width - inset],
            [inset, width - inset],
        ]
    };
    let (outer, inner) = (ring(0.0), ring(wall));
    let at = |p: [f64; 2], z: f64| [p[0], p[1], z];
    let mut t = Vec::new();
    for i in 0..4 {
        let j = (i + 1) % 4;
        let (o0, o1, i0, i1) = (outer[i], outer[j], inner[i], inner[j]);
        quad(
            &mut t,
            at(o0, 0.0),
            at(o1, 0.0),
            at(o1, height),
            at(o0, height),
        );
        quad(
            &mut t,
            at(i1, 0.0),
            at(i0, 0.0),
            at(i0, height),
            at(i1, height),
        );
        quad(
            &mut t,
            at(o0, height),
            at(o1, height),
            at(i1, height),
            at(i0, height),
        );
        quad(&mut t, at(o1, 0.0), at(o0, 0.0), at(i0, 0.0), at(i1, 0.0));
    }
    Mesh { triangles: t }
}

/// A cylinder of `diameter` and `height` on `sides` facets, its axis on z from z = 0.
pub fn pin(diameter: f64, height: f64, sides: usize) -> Mesh {
    let r = diameter / 2.0;
    let p = |i: usize, z: f64| {
        let a = std::f64::consts::TAU * (i % sides) as f64 / sides as f64;
        [r * a.cos(), r * a.sin(), z]
    };
    let mut t = Vec::new();
    for i in 0..sides {
        quad(
            &mut t,
            p(i, 0.0),
            p(i + 1, 0.0),
            p(i + 1, height),
            p(i, height),
        );
        t.push([[0.0, 0.0, height], p(i, height), p(i + 1, height)]);
        t.push([[0.0, 0.0, 0.0], p(i + 1, 0.0), p(i, 0.0)]);
    }
    Mesh { triangles: t }
}

/// A box of `size` with a corner at the origin.
pub fn cuboid(size: [f64; 3]) -> Mesh {
    let [x, y, z] = size;
    let p = |i: usize, j: usize, k: usize| [i as f64 * x, j as f64 * y, k as f64 * z];
    let mut t = Vec::new();
    quad(&mut t, p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0));
    quad(&mut t, p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1));
    quad(&mut t, p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1));
    quad(&mut t, p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0));
    quad(&mut t, p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0));
    quad(&mut t, p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1));
    Mesh { triangles: t }
}
