//! The part as the acceptance test sees it, independent of `cell_mesh`: an STL read with
//! `stl_io`, its inside found by ray parity on a voxel grid, its surface sampled, and the
//! measure of how well a [`Deposit`] contains it.
//!
//! - **Inside**: a vertical ray through each voxel column's centre (nudged off the grid by an
//!   irrational fraction so it misses edges and vertices) crosses the closed surface an even
//!   number of times; voxel centres between the 1st and 2nd, 3rd and 4th, … crossing are inside.
//! - **Surface**: points on every triangle at about the grid spacing, each with the triangle's
//!   outward normal (the winding, oriented by the sign of the enclosed volume).
//! - **Containment**: every inside voxel centre must be in the deposit (no void in the part), and
//!   at every surface point the deposit must reach at least the margin in every direction: the
//!   distance the point's rays (its normal, the six axes and 14 more spread over the sphere)
//!   travel inside the deposit before leaving it. The smallest over the surface is the measured
//!   allowance. Points on the part's bottom face lie on the substrate and are left out.
#![allow(dead_code)] // each test binary uses a different subset

use std::path::Path;

use super::beads::Deposit;

/// A triangle mesh (mm).
#[derive(Debug, Clone)]
pub struct Mesh {
    pub triangles: Vec<[[f64; 3]; 3]>,
}

impl Mesh {
    /// Reads an STL file (ASCII or binary).
    pub fn read(path: &Path) -> Result<Mesh, String> {
        let mut f = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let m = stl_io::read_stl(&mut f).map_err(|e| format!("{}: {e}", path.display()))?;
        let v = |i: usize| {
            let p = m.vertices[i];
            [p[0] as f64, p[1] as f64, p[2] as f64]
        };
        Ok(Mesh {
            triangles: m
                .faces
                .iter()
                .map(|f| [v(f.vertices[0]), v(f.vertices[1]), v(f.vertices[2])])
                .collect(),
        })
    }

    /// Writes a binary STL.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        let tris: Vec<stl_io::Triangle> = self
            .triangles
            .iter()
            .map(|t| {
                let n = normal(t);
                let v = |p: [f64; 3]| stl_io::Vertex::new([p[0] as f32, p[1] as f32, p[2] as f32]);
                stl_io::Triangle {
                    normal: stl_io::Normal::new([n[0] as f32, n[1] as f32, n[2] as f32]),
                    vertices: [v(t[0]), v(t[1]), v(t[2])],
                }
            })
            .collect();
        let mut f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        stl_io::write_stl(&mut f, tris.iter()).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// The mesh scaled by `s` about the origin.
    pub fn scaled(&self, s: f64) -> Mesh {
        self.map(|p| [p[0] * s, p[1] * s, p[2] * s])
    }

    /// The mesh moved by `d`.
    pub fn translated(&self, d: [f64; 3]) -> Mesh {
        self.map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
    }

    fn map(&self, f: impl Fn([f64; 3]) -> [f64; 3]) -> Mesh {
        Mesh {
            triangles: self
                .triangles
                .iter()
                .map(|t| [f(t[0]), f(t[1]), f(t[2])])
                .collect(),
        }
    }

    /// Bounding box (min, max).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in self.triangles.iter().flatten() {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        (lo, hi)
    }

    /// Enclosed volume by the divergence theorem (positive for outward winding).
    pub fn signed_volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|[a, b, c]| dot(*a, cross(*b, *c)) / 6.0)
            .sum()
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    if n > 0.0 {
        [a[0] / n, a[1] / n, a[2] / n]
    } else {
        [0.0; 3]
    }
}
fn normal(t: &[[f64; 3]; 3]) -> [f64; 3] {
    unit(cross(sub(t[1], t[0]), sub(t[2], t[0])))
}

/// Voxel centres inside the mesh, on a grid of `spacing` over its bounding box.
pub struct Voxels {
    pub spacing: f64,
    pub centres: Vec<[f64; 3]>,
    /// Columns whose ray crossed the surface an odd number of times (left out): a mesh that is
    /// not closed there.
    pub odd_columns: usize,
}

/// The inside of `mesh` by vertical ray parity.
pub fn voxelise(mesh: &Mesh, spacing: f64) -> Voxels {
    let (lo, hi) = mesh.bounds();
    let n = |i: usize| (((hi[i] - lo[i]) / spacing).ceil() as usize).max(1);
    let (nx, ny, nz) = (n(0), n(1), n(2));
    // Nudge the columns off any round position so that rays miss edges and vertices.
    let nudge = [spacing * 0.013_172_9, spacing * 0.007_718_3];
    let column = |i: usize, j: usize| {
        [
            lo[0] + (i as f64 + 0.5) * spacing + nudge[0],
            lo[1] + (j as f64 + 0.5) * spacing + nudge[1],
        ]
    };
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in tri {
            for k in 0..2 {
                a[k] = a[k].min(p[k]);
                b[k] = b[k].max(p[k]);
            }
        }
        let range = |k: usize, m: usize| {
            let first = ((a[k] - lo[k] - nudge[k]) / spacing - 0.5).ceil().max(0.0) as usize;
            let last = ((b[k] - lo[k] - nudge[k]) / spacing - 0.5).floor();
            if last < 0.0 {
                0..0
            } else {
                first..(last as usize + 1).min(m)
            }
        };
        for j in range(1, ny) {
            for i in range(0, nx) {
                bins[j * nx + i].push(t as u32);
            }
        }
    }
    let mut centres = Vec::new();
    let mut odd_columns = 0;
    let mut crossings = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let [x, y] = column(i, j);
            crossings.clear();
            for &t in &bins[j * nx + i] {
                if let Some(z) = vertical_crossing(&mesh.triangles[t as usize], x, y) {
                    crossings.push(z);
                }
            }
            if crossings.len() % 2 == 1 {
                odd_columns += 1;
                continue;
            }
            crossings.sort_by(f64::total_cmp);
            for pair in crossings.chunks(2) {
                let first = ((pair[0] - lo[2]) / spacing - 0.5).ceil().max(0.0) as usize;
                for k in first..nz {
                    let z = lo[2] + (k as f64 + 0.5) * spacing;
                    if z > pair[1] {
                        break;
                    }
                    centres.push([
                        lo[0] + (i as f64 + 0.5) * spacing,
                        lo[1] + (j as f64 + 0.5) * spacing,
                        z,
                    ]);
                }
            }
        }
    }
    Voxels {
        spacing,
        centres,
        odd_columns,
    }
}

/// Height where the vertical line through (x, y) crosses the triangle, if it does.
fn vertical_crossing(t: &[[f64; 3]; 3], x: f64, y: f64) -> Option<f64> {
    let [a, b, c] = t;
    let d = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1]);
    if d.abs() < 1e-15 {
        return None;
    }
    let l1 = ((b[1] - c[1]) * (x - c[0]) + (c[0] - b[0]) * (y - c[1])) / d;
    let l2 = ((c[1] - a[1]) * (x - c[0]) + (a[0] - c[0]) * (y - c[1])) / d;
    let l3 = 1.0 - l1 - l2;
    (l1 >= 0.0 && l2 >= 0.0 && l3 >= 0.0).then(|| l1 * a[2] + l2 * b[2] + l3 * c[2])
}

/// Points on the surface at most about `spacing` apart, with the outward normal: on each
/// triangle a grid along its two shorter edges from their common vertex, `a + u·e1 + v·(1 − u)·e2`
/// at cell centres (u, v in (0, 1)), so long thin triangles are sampled along their length.
pub fn surface_samples(mesh: &Mesh, spacing: f64) -> Vec<([f64; 3], [f64; 3])> {
    let outward = if mesh.signed_volume() >= 0.0 {
        1.0
    } else {
        -1.0
    };
    let mut out = Vec::new();
    for t in &mesh.triangles {
        let nrm = normal(t).map(|v| v * outward);
        let len = |i: usize| {
            let e = sub(t[(i + 1) % 3], t[i]);
            dot(e, e).sqrt()
        };
        // The vertex opposite the longest edge (edge i runs from vertex i to i + 1).
        let longest = (0..3)
            .max_by(|&a, &b| len(a).total_cmp(&len(b)))
            .unwrap_or(0);
        let a = t[(longest + 2) % 3];
        let (e1, e2) = (sub(t[longest], a), sub(t[(longest + 1) % 3], a));
        let steps = |e: [f64; 3]| ((dot(e, e).sqrt() / spacing).ceil() as usize).max(1);
        let (nu, nv) = (steps(e1), steps(e2));
        for i in 0..nu {
            let u = (i as f64 + 0.5) / nu as f64;
            for j in 0..nv {
                let v = (j as f64 + 0.5) / nv as f64 * (1.0 - u);
                out.push(([0, 1, 2].map(|k| a[k] + u * e1[k] + v * e2[k]), nrm));
            }
        }
    }
    out
}

/// The 6 axis directions and 14 more (a Fibonacci sphere).
fn directions() -> Vec<[f64; 3]> {
    let mut d = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let n = 14;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let a = golden * i as f64;
        d.push([r * a.cos(), r * a.sin(), z]);
    }
    d
}

/// How the deposit contains the part.
#[derive(Debug, Clone)]
pub struct Containment {
    pub spacing_mm: f64,
    pub part_volume_mm3: f64,
    pub part_voxels: usize,
    /// Inside voxel centres not in the deposit, and the first few of them.
    pub voxels_outside: usize,
    pub voxels_outside_at: Vec<[f64; 3]>,
    pub odd_columns: usize,
    pub surface_samples: usize,
    /// Surface points not in the deposit at all.
    pub surface_outside: usize,
    /// Surface points whose allowance is below the margin asked.
    pub surface_below_margin: usize,
    /// The smallest allowance over the surface (0 when some point is outside) and where.
    pub min_allowance_mm: f64,
    pub min_allowance_at: [f64; 3],
    /// Heights (mm, rounded to 0.1) of the surface points below the margin, distinct, sorted.
    pub short_heights: Vec<f64>,
    /// Deposit volume: voxel centres of its bounding box in the beads' union.
    pub deposited_volume_mm3: f64,
}

/// Measures how `deposit` contains `mesh` with the margin `margin_mm`, on a grid of
/// `spacing_mm`. Allowances are measured up to `margin_mm + 1`.
pub fn measure(mesh: &Mesh, deposit: &Deposit, spacing_mm: f64, margin_mm: f64) -> Containment {
    let voxels = voxelise(mesh, spacing_mm);
    let outside: Vec<[f64; 3]> = voxels
        .centres
        .iter()
        .copied()
        .filter(|p| !deposit.contains(*p))
        .collect();
    let dirs = directions();
    let cap = margin_mm + 1.0;
    let samples = surface_samples(mesh, spacing_mm);
    let mut c = Containment {
        spacing_mm,
        part_volume_mm3: mesh.signed_volume().abs(),
        part_voxels: voxels.centres.len(),
        voxels_outside: outside.len(),
        voxels_outside_at: outside.iter().take(5).copied().collect(),
        odd_columns: voxels.odd_columns,
        surface_samples: 0,
        surface_outside: 0,
        surface_below_margin: 0,
        min_allowance_mm: cap,
        min_allowance_at: [f64::NAN; 3],
        short_heights: Vec::new(),
        deposited_volume_mm3: 0.0,
    };
    let mut short = std::collections::BTreeSet::new();
    for (p, n) in samples {
        if p[2] <= 1e-6 && n[2] < -0.5 {
            continue; // on the substrate
        }
        c.surface_samples += 1;
        let allowance = if deposit.contains(p) {
            std::iter::once(n)
                .chain(dirs.iter().copied())
                .map(|d| deposit.exit_distance(p, d, cap))
                .fold(cap, f64::min)
        } else {
            c.surface_outside += 1;
            0.0
        };
        if allowance < margin_mm {
            c.surface_below_margin += 1;
            short.insert((p[2] * 10.0).round() as i64);
        }
        if allowance < c.min_allowance_mm {
            c.min_allowance_mm = allowance;
            c.min_allowance_at = p;
        }
    }
    c.short_heights = short.into_iter().map(|z| z as f64 / 10.0).collect();
    let (lo, hi) = deposit.bounds();
    if lo[0].is_finite() {
        let n = |i: usize| ((hi[i] - lo[i]) / spacing_mm).ceil() as usize;
        let mut inside = 0usize;
        for k in 0..n(2) {
            for j in 0..n(1) {
                for i in 0..n(0) {
                    let p = [
                        lo[0] + (i as f64 + 0.5) * spacing_mm,
                        lo[1] + (j as f64 + 0.5) * spacing_mm,
                        lo[2].max(0.0) + (k as f64 + 0.5) * spacing_mm,
                    ];
                    if p[2] < hi[2] && deposit.contains(p) {
                        inside += 1;
                    }
                }
            }
        }
        c.deposited_volume_mm3 = inside as f64 * spacing_mm.powi(3);
    }
    c
}
