//! STL input (ASCII and binary, through `stl_io`), vertex welding and topology diagnostics.
//!
//! Seed 004 reads an ASCII STL only (notes B3, `docs/notes/seed-notes-sheet-waam.md`); notes
//! B10 ask to add binary. Both go through `stl_io`; this module only decides the format (many
//! CAD exporters write binary files whose 80-byte header starts with `solid `, which
//! `stl_io`'s probe would take for ASCII), checks lengths and coordinates, welds coincident
//! corners and records what is wrong with the surface.

use rustc_hash::FxHashMap as HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use crate::error::MeshError;

/// How close two STL corners must be to become one vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WeldTolerance {
    /// A fraction of the bounding-box diagonal. The default, `RelativeToBbox(1e-6)`, is about
    /// 16× the relative resolution of the f32 coordinates an STL stores (2⁻²⁴ ≈ 6e-8), so it
    /// joins corners an exporter wrote with different rounding, yet stays far below any feature.
    RelativeToBbox(f64),
    /// An absolute distance in mm (0 welds bit-identical corners only).
    AbsoluteMm(f64),
}

impl Default for WeldTolerance {
    fn default() -> Self {
        WeldTolerance::RelativeToBbox(1e-6)
    }
}

/// Options of mesh construction.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MeshOptions {
    /// Vertex weld tolerance.
    pub weld: WeldTolerance,
}

/// The STL encoding a mesh was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StlFormat {
    /// `solid … facet normal … endsolid` text.
    Ascii,
    /// 80-byte header, u32 count, 50 bytes per triangle.
    Binary,
    /// Built in memory ([`Mesh::from_triangles`]).
    Memory,
}

/// What the loader found out about a mesh. The mesh is still sliced; these are diagnostics.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshReport {
    /// File path or the name given to the constructor.
    pub source: PathBuf,
    /// Encoding.
    pub format: StlFormat,
    /// Triangles in the input.
    pub input_triangles: usize,
    /// Distinct vertices after welding.
    pub vertices: usize,
    /// The weld distance actually used, mm.
    pub weld_tolerance_mm: f64,
    /// Input indices of triangles removed because welding merged two of their corners.
    pub collapsed_triangles: Vec<usize>,
    /// Input indices of kept triangles whose height (2·area / longest edge) is at most the weld
    /// tolerance (needles and caps; exactly zero area when the tolerance is 0).
    pub degenerate_triangles: Vec<usize>,
    /// Edges used by exactly one triangle (holes in the surface).
    pub boundary_edges: usize,
    /// Connected components of the boundary-edge graph (≈ number of holes).
    pub boundary_loops: usize,
    /// Edges used by three or more triangles.
    pub non_manifold_edges: usize,
    /// Two-triangle edges that both triangles traverse in the same direction (flipped winding).
    pub inconsistent_edges: usize,
    /// Bytes after the last announced triangle of a binary STL (ignored).
    pub trailing_bytes: usize,
}

impl MeshReport {
    /// True when every edge has exactly two triangles: the surface is closed and manifold.
    pub fn is_closed_manifold(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0
    }
}

/// A welded, indexed triangle mesh with an edge table, ready for [`crate::slice()`].
///
/// Coordinates are mm (STL has no unit; the file's numbers are taken as mm).
#[derive(Debug, Clone)]
pub struct Mesh {
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    /// Edge id of the triangle side from corner i to corner (i+1) mod 3.
    tri_edges: Vec<[u32; 3]>,
    /// Undirected edges as (lower vertex id, higher vertex id).
    edges: Vec<[u32; 2]>,
    report: MeshReport,
}

impl Mesh {
    /// Reads an ASCII or binary STL file with default options.
    pub fn load_stl(path: impl AsRef<Path>) -> Result<Mesh, MeshError> {
        Self::from_stl_file(path, &MeshOptions::default())
    }

    /// Reads an ASCII or binary STL file.
    pub fn from_stl_file(path: impl AsRef<Path>, opts: &MeshOptions) -> Result<Mesh, MeshError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        Self::from_stl_bytes(path, &bytes, opts)
    }

    /// Parses STL bytes; `name` only labels errors and the report. Never panics.
    pub fn from_stl_bytes(
        name: impl AsRef<Path>,
        bytes: &[u8],
        opts: &MeshOptions,
    ) -> Result<Mesh, MeshError> {
        let file = name.as_ref().to_path_buf();
        let (raw, format, trailing_bytes) = parse_stl(&file, bytes)?;
        let mut mesh = build(file, &raw, format, opts)?;
        mesh.report.trailing_bytes = trailing_bytes;
        Ok(mesh)
    }

    /// Builds a mesh from corner triples (for generated solids and tests). Corner order gives the
    /// winding; the slicer does not rely on it (contour orientation comes from nesting).
    pub fn from_triangles(
        name: impl AsRef<Path>,
        triangles: &[[[f64; 3]; 3]],
        opts: &MeshOptions,
    ) -> Result<Mesh, MeshError> {
        let file = name.as_ref().to_path_buf();
        let raw: Vec<[[f64; 3]; 3]> = triangles.to_vec();
        for (t, tri) in raw.iter().enumerate() {
            for (v, p) in tri.iter().enumerate() {
                if let Some(c) = p.iter().find(|c| !c.is_finite()) {
                    return Err(MeshError::NonFinite {
                        file,
                        triangle: t,
                        vertex: v,
                        value: *c as f32,
                    });
                }
            }
        }
        build(file, &raw, StlFormat::Memory, opts)
    }

    /// Welded vertices, mm.
    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.vertices
    }

    /// Kept triangles as vertex indices (collapsed ones removed).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Undirected edges (lower id, higher id).
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Edge ids of each triangle's sides (corner i → corner (i+1) mod 3).
    pub fn triangle_edges(&self) -> &[[u32; 3]] {
        &self.tri_edges
    }

    /// Diagnostics.
    pub fn report(&self) -> &MeshReport {
        &self.report
    }

    /// Axis-aligned bounding box `(min, max)` of the welded vertices, mm.
    pub fn bbox(&self) -> ([f64; 3], [f64; 3]) {
        bbox_of(self.vertices.iter())
    }

    /// Enclosed volume, mm³, by the divergence theorem: Σ v0·(v1×v2)/6 over triangles.
    /// Meaningful for closed, consistently wound meshes (positive for outward normals).
    pub fn signed_volume_mm3(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize]);
                a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0])
            })
            .sum::<f64>()
            / 6.0
    }
}

fn bbox_of<'a>(pts: impl Iterator<Item = &'a [f64; 3]>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in pts {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

type RawTriangles = Vec<[[f64; 3]; 3]>;

/// Decides the encoding and runs `stl_io`; returns corners as f64 plus trailing byte count.
fn parse_stl(file: &Path, bytes: &[u8]) -> Result<(RawTriangles, StlFormat, usize), MeshError> {
    if bytes.is_empty() {
        return Err(MeshError::Empty {
            file: file.to_path_buf(),
        });
    }
    let starts_solid = bytes.starts_with(b"solid");
    let announced = (bytes.len() >= 84)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let binary_len = announced.map(|n| 84 + 50 * n);
    let exact_binary = binary_len == Some(bytes.len() as u64);
    // Text STL has no NUL byte; binary nearly always has some (attribute bytes, small floats).
    // This catches truncated binaries whose header starts with "solid".
    let looks_binary = bytes[..bytes.len().min(4096)].contains(&0);
    let (format, trailing) = if exact_binary {
        (StlFormat::Binary, 0)
    } else if starts_solid && !looks_binary {
        (StlFormat::Ascii, 0)
    } else {
        match (announced, binary_len) {
            (Some(n), Some(expected)) if expected > bytes.len() as u64 => {
                return Err(MeshError::Truncated {
                    file: file.to_path_buf(),
                    len_bytes: bytes.len(),
                    announced: n,
                    expected_bytes: expected,
                    triangle: (bytes.len() as u64 - 84) / 50,
                })
            }
            (Some(_), Some(expected)) => (StlFormat::Binary, bytes.len() - expected as usize),
            _ => {
                return Err(MeshError::Parse {
                    file: file.to_path_buf(),
                    triangle: 0,
                    message: format!(
                        "not ASCII (no leading `solid`) and shorter ({} bytes) than the 84-byte \
                         binary header",
                        bytes.len()
                    ),
                })
            }
        }
    };
    if format == StlFormat::Binary && announced == Some(0) {
        return Err(MeshError::Empty {
            file: file.to_path_buf(),
        });
    }
    // stl_io probes for ASCII by a leading "solid "; hide that from it in binary files.
    let patched;
    let input: &[u8] = if format == StlFormat::Binary && starts_solid {
        let mut b = bytes.to_vec();
        b[..5].copy_from_slice(b"SOLID");
        patched = b;
        &patched
    } else {
        bytes
    };
    let mut cursor = Cursor::new(input);
    let reader = stl_io::create_stl_reader(&mut cursor).map_err(|e| MeshError::Parse {
        file: file.to_path_buf(),
        triangle: 0,
        message: e.to_string(),
    })?;
    let mut out = Vec::new();
    for (t, tri) in reader.enumerate() {
        let tri = tri.map_err(|e| MeshError::Parse {
            file: file.to_path_buf(),
            triangle: t,
            message: e.to_string(),
        })?;
        let mut corners = [[0.0f64; 3]; 3];
        for (v, (vert, out)) in tri.vertices.iter().zip(corners.iter_mut()).enumerate() {
            for (&c, o) in vert.0.iter().zip(out.iter_mut()) {
                if !c.is_finite() {
                    return Err(MeshError::NonFinite {
                        file: file.to_path_buf(),
                        triangle: t,
                        vertex: v,
                        value: c,
                    });
                }
                *o = c as f64;
            }
        }
        out.push(corners);
    }
    if out.is_empty() {
        return Err(MeshError::Empty {
            file: file.to_path_buf(),
        });
    }
    Ok((out, format, trailing))
}

/// Welds corners, drops collapsed triangles, builds the edge table and the report.
fn build(
    file: PathBuf,
    raw: &[[[f64; 3]; 3]],
    format: StlFormat,
    opts: &MeshOptions,
) -> Result<Mesh, MeshError> {
    if raw.is_empty() {
        return Err(MeshError::Empty { file });
    }
    if raw.len() > (u32::MAX / 3) as usize {
        return Err(MeshError::TooLarge {
            file,
            triangles: raw.len(),
        });
    }
    let (lo, hi) = bbox_of(raw.iter().flatten());
    let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let tol = match opts.weld {
        WeldTolerance::RelativeToBbox(f) => f * diag,
        WeldTolerance::AbsoluteMm(d) => d,
    };
    if !tol.is_finite() || tol < 0.0 {
        return Err(MeshError::BadTolerance(tol));
    }

    // Pass 1: bit-identical corners (the common case) share an id.
    let mut exact: HashMap<[u64; 3], u32> = HashMap::default();
    let mut uniq: Vec<[f64; 3]> = Vec::new();
    let corner_ids: Vec<[u32; 3]> = raw
        .iter()
        .map(|tri| {
            tri.map(|p| {
                let key = p.map(|c| (c + 0.0).to_bits()); // +0.0 folds -0.0 into 0.0
                *exact.entry(key).or_insert_with(|| {
                    uniq.push(p);
                    (uniq.len() - 1) as u32
                })
            })
        })
        .collect();
    drop(exact);

    // Pass 2: within-tolerance welding on a uniform grid of cell = tol (first come, first
    // served, so the result depends only on input order).
    let mut remap: Vec<u32> = (0..uniq.len() as u32).collect();
    let mut vertices: Vec<[f64; 3]> = Vec::with_capacity(uniq.len());
    if tol > 0.0 {
        // Cells of 4·tol: a neighbour cell can hold a match only when the point is within tol
        // of the shared face, so most points probe one cell instead of 27.
        let size = 4.0 * tol;
        let reach = tol * (1.0 + 1e-9);
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::default();
        for (i, p) in uniq.iter().enumerate() {
            let c = p.map(|x| (x / size).floor() as i64);
            let mut offs: [[i64; 3]; 3] = [[0; 3]; 3];
            let mut nof = [1usize; 3];
            for k in 0..3 {
                let lo = c[k] as f64 * size;
                if p[k] - lo <= reach {
                    offs[k][nof[k]] = -1;
                    nof[k] += 1;
                }
                if lo + size - p[k] <= reach {
                    offs[k][nof[k]] = 1;
                    nof[k] += 1;
                }
            }
            let mut found = None;
            'search: for &dx in &offs[0][..nof[0]] {
                for &dy in &offs[1][..nof[1]] {
                    for &dz in &offs[2][..nof[2]] {
                        let key = [
                            c[0].saturating_add(dx),
                            c[1].saturating_add(dy),
                            c[2].saturating_add(dz),
                        ];
                        if let Some(list) = grid.get(&key) {
                            for &w in list {
                                let q = vertices[w as usize];
                                let d2 = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>();
                                if d2 <= tol * tol {
                                    found = Some(w);
                                    break 'search;
                                }
                            }
                        }
                    }
                }
            }
            remap[i] = match found {
                Some(w) => w,
                None => {
                    vertices.push(*p);
                    let w = (vertices.len() - 1) as u32;
                    grid.entry(c).or_default().push(w);
                    w
                }
            };
        }
    } else {
        vertices = uniq;
    }

    let mut triangles = Vec::with_capacity(raw.len());
    let mut kept_input = Vec::with_capacity(raw.len());
    let mut collapsed = Vec::new();
    for (t, ids) in corner_ids.iter().enumerate() {
        let v = ids.map(|i| remap[i as usize]);
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            collapsed.push(t);
        } else {
            triangles.push(v);
            kept_input.push(t);
        }
    }

    // Edge table: per undirected edge, use count and the directed uses.
    let mut edge_ids: HashMap<(u32, u32), u32> =
        HashMap::with_capacity_and_hasher(triangles.len() * 3 / 2, Default::default());
    let mut edges: Vec<[u32; 2]> = Vec::new();
    let mut uses: Vec<(u32, i32)> = Vec::new(); // (count, net direction: +1 lo→hi, −1 hi→lo)
    let tri_edges: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| {
            let mut e = [0u32; 3];
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                let key = (a.min(b), a.max(b));
                let id = *edge_ids.entry(key).or_insert_with(|| {
                    edges.push([key.0, key.1]);
                    uses.push((0, 0));
                    (edges.len() - 1) as u32
                });
                uses[id as usize].0 += 1;
                uses[id as usize].1 += if a < b { 1 } else { -1 };
                e[i] = id;
            }
            e
        })
        .collect();
    drop(edge_ids);

    let mut boundary_edges = 0;
    let mut non_manifold_edges = 0;
    let mut inconsistent_edges = 0;
    let mut uf = UnionFind::new(vertices.len());
    for (e, &(count, dir)) in edges.iter().zip(&uses) {
        match count {
            1 => {
                boundary_edges += 1;
                uf.union(e[0], e[1]);
            }
            2 if dir != 0 => inconsistent_edges += 1,
            2 => {}
            _ => non_manifold_edges += 1,
        }
    }
    let boundary_loops = {
        let mut roots: Vec<u32> = edges
            .iter()
            .zip(&uses)
            .filter(|(_, u)| u.0 == 1)
            .map(|(e, _)| uf.find(e[0]))
            .collect();
        roots.sort_unstable();
        roots.dedup();
        roots.len()
    };

    let degenerate_triangles = triangles
        .iter()
        .zip(&kept_input)
        .filter(|(t, _)| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            let ab = sub(b, a);
            let ac = sub(c, a);
            let bc = sub(c, b);
            let cr = cross(ab, ac);
            let twice_area = norm(cr);
            let longest = norm(ab).max(norm(ac)).max(norm(bc));
            twice_area <= tol * longest
        })
        .map(|(_, &t)| t)
        .collect();

    let report = MeshReport {
        source: file,
        format,
        input_triangles: raw.len(),
        vertices: vertices.len(),
        weld_tolerance_mm: tol,
        collapsed_triangles: collapsed,
        degenerate_triangles,
        boundary_edges,
        boundary_loops,
        non_manifold_edges,
        inconsistent_edges,
        trailing_bytes: 0,
    };
    Ok(Mesh {
        vertices,
        triangles,
        tri_edges,
        edges,
        report,
    })
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

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Minimal union-find for counting boundary loops (a dozen lines; no crate needed for this).
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }
    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = p;
        }
        x
    }
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
}
