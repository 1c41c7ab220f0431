//! Stock (CAM blank) model: every deposited piece of the toolpath as a closed box, written as a
//! binary STL (seed 004 §4.8, notes B9).
//!
//! The thesis's CATIA macro places, for each row with E = 1 whose next row also has E = 1, an
//! axis system with y along the weld and z opposite the nozzle, sketches a rectangle of width
//! LW and height h **centred on the point** in the local x–z plane, and extrudes it along y to
//! the next point. Here each such piece becomes one box of 8 corners and 12 triangles with
//! outward normals. Boxes are not unioned (neither were the thesis's extrusions): each box is
//! watertight on its own, so the file's volume is Σ w·h·L; where boxes overlap at corners CAM
//! sees their union.

use std::io::{self, Write};

use stl_io::{Normal, Triangle, Vertex};

use crate::toolpath::{LayerToolpath, SegmentKind};

/// One bead box: the piece from `start` to `end` (mm) with width and height (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeadBox {
    /// Start point (the row's point).
    pub start: [f64; 3],
    /// End point (the next row's point).
    pub end: [f64; 3],
    /// Width LW (mm), across the weld in the horizontal plane.
    pub width_mm: f64,
    /// Height h (mm), vertical, centred on the points.
    pub height_mm: f64,
}

impl BeadBox {
    /// Length of the box along the weld (mm).
    pub fn length_mm(&self) -> f64 {
        let d = sub(self.end, self.start);
        dot(d, d).sqrt()
    }

    /// Volume w·h·L (mm³); exact for horizontal pieces (the box is a parallelepiped otherwise,
    /// whose volume is w·h·L_xy).
    pub fn volume_mm3(&self) -> f64 {
        let d = sub(self.end, self.start);
        self.width_mm * self.height_mm * d[0].hypot(d[1])
    }

    /// The 12 triangles (outward normals, counter-clockwise seen from outside), or none for a
    /// degenerate piece (zero horizontal length, width or height).
    pub fn triangles(&self) -> Vec<Triangle> {
        let d = sub(self.end, self.start);
        let lxy = d[0].hypot(d[1]);
        if lxy <= 1e-12 || self.width_mm <= 0.0 || self.height_mm <= 0.0 {
            return Vec::new();
        }
        // Local frame: y along the weld (horizontal), z up (opposite the nozzle), x = y × z.
        let y = [d[0] / lxy, d[1] / lxy, 0.0];
        let x = [y[1], -y[0], 0.0];
        let hw = self.width_mm / 2.0;
        let hh = self.height_mm / 2.0;
        let corner = |p: [f64; 3], sx: f64, sz: f64| {
            [p[0] + x[0] * sx * hw, p[1] + x[1] * sx * hw, p[2] + sz * hh]
        };
        // Corners 0–3 at the start, 4–7 at the end: (−x,−z), (+x,−z), (+x,+z), (−x,+z).
        let mut c = [[0.0; 3]; 8];
        for (k, p) in [self.start, self.end].into_iter().enumerate() {
            c[4 * k] = corner(p, -1.0, -1.0);
            c[4 * k + 1] = corner(p, 1.0, -1.0);
            c[4 * k + 2] = corner(p, 1.0, 1.0);
            c[4 * k + 3] = corner(p, -1.0, 1.0);
        }
        // Quads as corner indices, counter-clockwise seen from outside (x, y, z right-handed).
        const QUADS: [[usize; 4]; 6] = [
            [0, 1, 2, 3], // start face (−y)
            [4, 7, 6, 5], // end face (+y)
            [0, 4, 5, 1], // bottom (−z)
            [3, 2, 6, 7], // top (+z)
            [1, 5, 6, 2], // +x side
            [0, 3, 7, 4], // −x side
        ];
        let mut out = Vec::with_capacity(12);
        for q in QUADS {
            for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let (a, b, cc) = (c[t[0]], c[t[1]], c[t[2]]);
                let n = cross(sub(b, a), sub(cc, a));
                let l = dot(n, n).sqrt();
                let n = [n[0] / l, n[1] / l, n[2] / l];
                out.push(Triangle {
                    normal: Normal::new([n[0] as f32, n[1] as f32, n[2] as f32]),
                    vertices: [v(a), v(b), v(cc)],
                });
            }
        }
        out
    }
}

fn v(p: [f64; 3]) -> Vertex {
    Vertex::new([p[0] as f32, p[1] as f32, p[2] as f32])
}
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The boxes of every depositing piece of the layers (seed 004 §4.8: rows with E = 1 whose next
/// row also has E = 1), with the width and height of the piece's first point.
pub fn bead_boxes(layers: &[LayerToolpath]) -> Vec<BeadBox> {
    let mut out = Vec::new();
    for l in layers {
        for s in l.segments.iter().filter(|s| s.kind == SegmentKind::Deposit) {
            for w in s.points.windows(2) {
                if !(w[0].arc_on && w[1].arc_on) {
                    continue;
                }
                let b = BeadBox {
                    start: [w[0].x_mm, w[0].y_mm, w[0].z_mm],
                    end: [w[1].x_mm, w[1].y_mm, w[1].z_mm],
                    width_mm: w[0].bead_width_mm,
                    height_mm: w[0].bead_height_mm,
                };
                if b.volume_mm3() > 0.0 {
                    out.push(b);
                }
            }
        }
    }
    out
}

/// All boxes' triangles, 12 per box in box order.
pub fn stock_triangles(boxes: &[BeadBox]) -> Vec<Triangle> {
    boxes.iter().flat_map(BeadBox::triangles).collect()
}

/// Writes the boxes as a binary STL (`stl_io`).
///
/// # Errors
/// The writer's errors.
pub fn write_stock_stl<W: Write>(w: &mut W, boxes: &[BeadBox]) -> io::Result<()> {
    let tris = stock_triangles(boxes);
    stl_io::write_stl(w, tris.iter())
}
