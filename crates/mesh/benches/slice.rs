//! Slicing bench (issue 8 targets: ≥ 5× trimesh, per-layer area within 0.1 %).
//!
//! Generates a finely tessellated torus (R = 30 mm, r = 10 mm; default 500 × 120 quads =
//! 120 000 triangles), writes it as binary STL to a temp file, slices it at 0.2 mm (mid-layer
//! planes, 100 layers) and prints load and slice times. When a Python with trimesh is found
//! (`TRIMESH_PYTHON`, else `/tmp/venv-mesh/bin/python`, else `python3`), runs
//! `benches/trimesh_peer.py` on the same file and planes and prints its times, the speed-up and
//! the largest relative per-layer net-area difference.
//!
//! `cargo bench -p cell_mesh --bench slice [-- MAJOR MINOR]`; `REPEATS` (default 5).
//! Set up the peer with `python3 -m venv /tmp/venv-mesh &&
//! /tmp/venv-mesh/bin/pip install -r crates/mesh/benches/requirements.txt`.

use std::f64::consts::{PI, TAU};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use cell_mesh::{slice, Mesh, SliceParams};

fn torus_triangles(major_r: f64, minor_r: f64, nu: usize, nv: usize) -> Vec<stl_io::Triangle> {
    let p = |i: usize, j: usize| {
        let u = TAU * (i % nu) as f64 / nu as f64;
        // Half-step phase so no vertex ring sits at a plane height by accident.
        let v = TAU * ((j % nv) as f64 + 0.5) / nv as f64;
        let rr = major_r + minor_r * v.cos();
        stl_io::Vertex::new([
            (rr * u.cos()) as f32,
            (rr * u.sin()) as f32,
            (minor_r * v.sin()) as f32,
        ])
    };
    let n = stl_io::Normal::new([0.0, 0.0, 0.0]);
    let mut out = Vec::with_capacity(2 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            out.push(stl_io::Triangle {
                normal: n,
                vertices: [a, b, c],
            });
            out.push(stl_io::Triangle {
                normal: n,
                vertices: [a, c, d],
            });
        }
    }
    out
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn find_python() -> Option<String> {
    let candidates = [
        std::env::var("TRIMESH_PYTHON").ok(),
        Some("/tmp/venv-mesh/bin/python".to_string()),
        Some("python3".to_string()),
    ];
    candidates.into_iter().flatten().find(|py| {
        Command::new(py)
            .args(["-c", "import trimesh, shapely"])
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false)
    })
}

/// Pulls `"key": number` and `"areas": [..]` out of the peer's one-line JSON (no serde_json
/// dependency for a bench).
fn json_num(s: &str, key: &str) -> Option<f64> {
    let i = s.find(&format!("\"{key}\":"))? + key.len() + 3;
    let rest = s[i..].trim_start();
    let end = rest.find([',', '}']).unwrap_or(rest.len());
    rest[..end].trim().parse().ok()
}

fn json_areas(s: &str) -> Option<Vec<f64>> {
    let i = s.find("\"areas\":")? + 8;
    let rest = &s[i..];
    let (a, b) = (rest.find('[')?, rest.find(']')?);
    rest[a + 1..b]
        .split(',')
        .filter(|t| !t.trim().is_empty())
        .map(|t| t.trim().parse().ok())
        .collect()
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let (nu, nv) = (
        args.first().copied().unwrap_or(500),
        args.get(1).copied().unwrap_or(120),
    );
    let repeats: usize = std::env::var("REPEATS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5)
        .max(1);
    let (major_r, minor_r, h) = (30.0, 10.0, 0.2);

    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("torus_bench.stl");
    let tris = torus_triangles(major_r, minor_r, nu, nv);
    {
        let mut f = std::io::BufWriter::new(std::fs::File::create(&path).expect("create"));
        stl_io::write_stl(&mut f, tris.iter()).expect("write stl");
    }
    println!(
        "mesh: torus R={major_r} r={minor_r} mm, {} triangles, binary STL {}",
        tris.len(),
        path.display()
    );

    let t0 = Instant::now();
    let mesh = Mesh::load_stl(&path).expect("load");
    let load_s = t0.elapsed().as_secs_f64();
    let r = mesh.report();
    println!(
        "load+weld: {:.1} ms ({} vertices, closed manifold: {})",
        load_s * 1e3,
        r.vertices,
        r.is_closed_manifold()
    );

    let params = SliceParams::new(h);
    let mut times = Vec::new();
    let mut stack = None;
    for _ in 0..repeats {
        let t0 = Instant::now();
        let s = slice(&mesh, &params).expect("slice");
        times.push(t0.elapsed().as_secs_f64());
        stack = Some(s);
    }
    let ours_s = median(times);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let ours_1t = median(
        (0..repeats)
            .map(|_| {
                pool.install(|| {
                    let t0 = Instant::now();
                    let _ = slice(&mesh, &params).expect("slice");
                    t0.elapsed().as_secs_f64()
                })
            })
            .collect(),
    );
    let stack = stack.expect("one run");
    let n = stack.layers.len();
    let areas: Vec<f64> = stack.layers.iter().map(|l| l.net_area_mm2()).collect();
    let contours: usize = stack.layers.iter().map(|l| l.contours.len()).sum();
    // Analytic annulus 4πR√(r² − z²) for orientation (the mesh is a faceted approximation).
    let max_analytic = stack
        .layers
        .iter()
        .filter(|l| l.z_mm.abs() < 0.8 * minor_r)
        .map(|l| {
            let exact = 4.0 * PI * major_r * (minor_r * minor_r - l.z_mm * l.z_mm).sqrt();
            ((l.net_area_mm2() - exact) / exact).abs()
        })
        .fold(0.0, f64::max);
    println!(
        "cell_mesh: {n} layers at {h} mm, {contours} contours, {} open chains; slice {:.2} ms \
         (median of {repeats}, rayon default pool), {:.2} ms on 1 thread; |Δ| vs analytic \
         annulus (|z| < 0.8 r) ≤ {:.4} %",
        stack.open_chain_count(),
        ours_s * 1e3,
        ours_1t * 1e3,
        max_analytic * 100.0
    );

    let Some(py) = find_python() else {
        println!("trimesh peer: no Python with trimesh found (set TRIMESH_PYTHON); skipped");
        return;
    };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/trimesh_peer.py");
    let out = Command::new(&py)
        .arg(&script)
        .arg(&path)
        .arg(format!("{:.17e}", stack.first_z_mm))
        .arg(format!("{h:.17e}"))
        .arg(n.to_string())
        .arg(repeats.min(3).to_string())
        .output()
        .expect("run peer");
    if !out.status.success() {
        println!(
            "trimesh peer failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        return;
    }
    let s = String::from_utf8_lossy(&out.stdout);
    let (Some(sec), Some(sec_area), Some(their_areas)) = (
        json_num(&s, "section_s"),
        json_num(&s, "section_area_s"),
        json_areas(&s),
    ) else {
        println!("trimesh peer: unreadable output: {s}");
        return;
    };
    let load_py = json_num(&s, "load_s").unwrap_or(f64::NAN);
    let max_rel = areas
        .iter()
        .zip(&their_areas)
        .map(|(a, b)| ((a - b) / b.abs().max(1e-12)).abs())
        .fold(0.0, f64::max);
    println!(
        "trimesh ({py}): load {:.1} ms, section_multiplane {:.2} ms, section + polygons/area \
         {:.2} ms",
        load_py * 1e3,
        sec * 1e3,
        sec_area * 1e3
    );
    println!(
        "speed-up: {:.1}x vs section + area (target >= 5x), {:.1}x vs section only; layers \
         compared {} / {}",
        sec_area / ours_s,
        sec / ours_s,
        their_areas.len(),
        n
    );
    println!(
        "max relative per-layer net-area difference: {:.2e} ({:.5} %, target <= 0.1 %)",
        max_rel,
        max_rel * 100.0
    );
}
