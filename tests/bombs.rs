//! Issue 23, item 2: small files that ask for huge work (nested DXF INSERT arrays, a bulge of
//! radius 10¹⁴ mm, a wing of 200 000 lifting-line stations, 1e-9 mm layers, …) are refused
//! within seconds by the real `cell` binary, with an error naming the file, the entity or
//! field, and the limit. The files are in `tests/data/bombs/` (written by `make_bombs.py`
//! there); a process still running after [`KILL_AFTER`] is killed and the test fails.

use std::{
    ffi::OsStr,
    io::Read,
    path::{Path, PathBuf},
    process::{Command, Stdio},
    time::{Duration, Instant},
};

/// A refusal must come within this (debug build, a loaded machine).
const REFUSED_WITHIN: Duration = Duration::from_secs(5);
/// A bomb that goes off is stopped here, before it takes the machine's memory.
const KILL_AFTER: Duration = Duration::from_secs(20);

const EXIT_USAGE: i32 = 64;
const EXIT_DATA: i32 = 65;

fn bomb(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/bombs")
        .join(name)
}

/// Runs `cell args…`; returns the exit code, stderr and the wall time.
fn cell<S: AsRef<OsStr>>(args: &[S]) -> (i32, String, Duration) {
    cell_killed_after(args, KILL_AFTER)
}

/// [`cell`], killed (and the test failed) after `kill_after`.
fn cell_killed_after<S: AsRef<OsStr>>(args: &[S], kill_after: Duration) -> (i32, String, Duration) {
    let t0 = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_cell"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cell runs");
    let mut pipe = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = pipe.read_to_string(&mut s);
        s
    });
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if t0.elapsed() > kill_after {
            let _ = child.kill();
            let _ = child.wait();
            panic!("not done: still running after {kill_after:?} (killed)");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let took = t0.elapsed();
    let stderr = reader.join().expect("stderr reader");
    (status.code().unwrap_or(-1), stderr, took)
}

/// Asserts `cell args…` exits with `code` within [`REFUSED_WITHIN`], its message holding
/// every one of `names`.
fn refused<S: AsRef<OsStr>>(args: &[S], code: i32, names: &[&str]) {
    let (got, stderr, took) = cell(args);
    eprintln!(
        "refused in {:.0} ms: {}",
        took.as_secs_f64() * 1e3,
        stderr.trim()
    );
    assert_eq!(got, code, "exit status; stderr: {stderr}");
    assert!(took < REFUSED_WITHIN, "took {took:?}: {stderr}");
    for name in names {
        assert!(stderr.contains(name), "{name:?} not in: {stderr}");
    }
}

fn out_dir() -> tempfile::TempDir {
    tempfile::tempdir().expect("temp dir")
}

fn sheet(file: &str, names: &[&str]) {
    sheet_layout(&bomb(file), names);
}

/// `cell sheet --layout <layout>` must be refused as bad data, naming each of `names`.
fn sheet_layout(layout: &Path, names: &[&str]) {
    let out = out_dir();
    let args = [
        OsStr::new("sheet"),
        OsStr::new("--layout"),
        layout.as_os_str(),
        OsStr::new("--out"),
        out.path().as_os_str(),
    ];
    refused(&args, EXIT_DATA, names);
}

#[test]
fn nested_insert_arrays_are_refused() {
    // 8 nested 10 × 10 arrays: 10¹⁶ triangles.
    sheet(
        "nested-inserts.dxf",
        &[
            "nested-inserts.dxf: INSERT of block 'L8' #2A on layer 'PARTS'",
            "expanding it places more than 250000 entities",
            "the limit is 250000 placed entities (MAX_PLACED_ENTITIES)",
        ],
    );
}

#[test]
fn a_bulge_of_radius_1e14_mm_is_refused() {
    sheet(
        "huge-bulge.dxf",
        &[
            "huge-bulge.dxf: POLYLINE #2B on layer 'PARTS'",
            "an arc of radius 1.000e14 mm",
            "the limit is 1e7 mm (MAX_ARC_RADIUS_MM)",
        ],
    );
}

#[test]
fn arcs_flattening_to_millions_of_points_are_refused() {
    sheet(
        "many-points.dxf",
        &[
            "many-points.dxf: CIRCLE #",
            "brings the drawing to more than 1000000 points",
            "the limit is 1000000 points (MAX_POINTS)",
        ],
    );
}

#[test]
fn an_ellipse_of_radius_1e12_mm_is_refused_not_coarsened() {
    sheet(
        "huge-ellipse.dxf",
        &[
            "huge-ellipse.dxf: ELLIPSE #2C on layer 'PARTS'",
            "an ellipse of major radius 1.000e12 mm is too large to flatten",
            "the limit is 1e7 mm (MAX_ARC_RADIUS_MM)",
        ],
    );
}

#[test]
fn a_json_layout_of_a_million_points_is_refused() {
    // One ring of 1 000 001 points (~8 MB), written here rather than kept in the repository.
    let dir = out_dir();
    let json = dir.path().join("many-points.json");
    let ring: Vec<String> = (0..1_000_001)
        .map(|i| format!("[{},{}]", i % 1000, i / 1000))
        .collect();
    let text = format!(
        "{{\"sheet\": [1000, 1000],\n \"parts\": [{{\"outer\": {{\"points\": [{}]}}}}]}}\n",
        ring.join(",")
    );
    std::fs::write(&json, text).expect("write layout");
    sheet_layout(
        &json,
        &[
            "many-points.json:2: field `parts[0].outer.points`",
            "the layout has more than 1000000 points",
            "the limit is 1000000 points (MAX_POINTS)",
        ],
    );
}

#[test]
fn a_json_layout_of_a_quarter_million_empty_rings_is_refused() {
    // 250 001 parts of no points (~6 MB); the 64 MiB file cap alone let 2.7·10⁶ through.
    let dir = out_dir();
    let json = dir.path().join("many-rings.json");
    let parts = vec![r#"{"outer": {"points": []}}"#; 250_001].join(",\n");
    std::fs::write(
        &json,
        format!("{{\"sheet\": [100, 100], \"parts\": [\n{parts}]}}\n"),
    )
    .expect("write layout");
    sheet_layout(
        &json,
        &[
            "many-rings.json:250002: field `parts[250000].outer.points`",
            "the layout has more than 250000 contours",
            "the limit is 250000 contours (MAX_CONTOURS)",
        ],
    );
}

#[test]
fn a_comb_of_54_km_of_cut_is_refused_before_its_raster_run() {
    // 3000 teeth 1 mm wide and 9 m long on a 10 × 10 m sheet (12 004 points, ~170 KB): 54 km
    // of cut, 1.35·10⁷ raster steps at 4 mm, hours of CPU per raster run.
    let dir = out_dir();
    let json = dir.path().join("comb.json");
    std::fs::write(&json, comb_layout(3000)).expect("write layout");
    sheet_layout(
        &json,
        &[
            "comb.json: the contours' cut length of 54",
            "at cell_mm = 4 mm is 1.350e7 raster steps",
            "the limit is 10000000 steps (MAX_CUT_STEPS)",
        ],
    );
}

/// A layout of one part, a comb of `teeth` teeth 1 mm wide, 9 m long and 1 mm apart, on a
/// 10 × 10 m sheet.
fn comb_layout(teeth: usize) -> String {
    let mut points = vec!["[0,1]".to_string()];
    for t in 0..teeth {
        let x = 1 + 2 * t;
        points.extend([
            format!("[{x},1]"),
            format!("[{x},9001]"),
            format!("[{},9001]", x + 1),
            format!("[{},1]", x + 1),
        ]);
    }
    let end = 1 + 2 * teeth;
    points.extend([format!("[{end},1]"), format!("[{end},0]"), "[0,0]".into()]);
    format!(
        "{{\"sheet\": [10000, 10000],\n \"parts\": [{{\"outer\": {{\"points\": [{}]}}}}]}}\n",
        points.join(",")
    )
}

#[test]
fn a_comb_of_36_km_under_the_caps_is_planned_in_seconds() {
    // 2000 teeth (8004 points): 36 km of cut, 9·10⁶ raster steps, under MAX_CUT_STEPS. Its
    // 1 mm gaps are narrower than the 1.5 mm kerf, so each is an uncut stretch of 9 + 1 + 9 m;
    // finding them sampled 10⁸ points against 8000 path points (minutes, GBs) until the search
    // became exact (cell_sequencer::kerf::uncut_stretch).
    let dir = out_dir();
    let json = dir.path().join("comb.json");
    std::fs::write(&json, comb_layout(2000)).expect("write layout");
    // The stock plasma profile with a 10 × 10 m table, so the comb goes through every phase.
    let stock = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/machines/linuxcnc-plasma.yaml");
    let stock = std::fs::read_to_string(stock).expect("stock profile");
    let big = stock
        .replace("  X: [0.0, 1250.0]", "  X: [0.0, 10000.0]")
        .replace("  Y: [0.0, 1250.0]", "  Y: [0.0, 10000.0]");
    assert_ne!(big, stock, "the profile's travel lines moved");
    let profile = dir.path().join("big-plasma.yaml");
    std::fs::write(&profile, big).expect("write profile");
    let out = out_dir();
    let args = [
        OsStr::new("sheet"),
        OsStr::new("--layout"),
        json.as_os_str(),
        OsStr::new("--profile"),
        profile.as_os_str(),
        OsStr::new("--sheet-origin"),
        OsStr::new("10,10"),
        OsStr::new("--out"),
        out.path().as_os_str(),
    ];
    // A hang guard only: a debug build on a loaded machine takes seconds.
    let (code, stderr, took) = cell_killed_after(&args, Duration::from_secs(60));
    eprintln!("planned in {:.1} s: {}", took.as_secs_f64(), stderr.trim());
    assert_eq!(code, 0, "exit status; stderr: {stderr}");
    assert!(out.path().join("program.ngc").is_file(), "no program");
    // One gap's walls and bottom, 18 001 mm, less the little the kerf reaches at its mouth.
    let missed: f64 = stderr
        .split("the kerf misses ")
        .nth(1)
        .and_then(|rest| rest.split(" mm").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no uncut stretch reported: {stderr}"));
    assert!((missed - 18001.0).abs() < 0.5, "{missed} mm: {stderr}");
}

#[test]
fn a_sheet_of_1e12_mm_is_refused_before_its_raster() {
    sheet(
        "huge-sheet.json",
        &[
            "huge-sheet.json: sheet 1000000000000 × 1000000000000 mm at cell_mm = 4 mm",
            "a raster of 6.250e22 cells",
            "the limit is 100000000 cells (MAX_RASTER_CELLS)",
        ],
    );
}

fn wing(file: &str, names: &[&str]) {
    let out = out_dir();
    let config = bomb(file);
    let args = [
        OsStr::new("wing"),
        OsStr::new("--config"),
        config.as_os_str(),
        OsStr::new("--out"),
        out.path().as_os_str(),
    ];
    refused(&args, EXIT_DATA, names);
}

#[test]
fn a_wing_of_200000_stations_is_refused() {
    wing(
        "wing-stations.yaml",
        &[
            "wing-stations.yaml: field `aero.stations`: 200000 is out of range",
            "must be in [2, 2000] (MAX_STATIONS)",
        ],
    );
}

#[test]
fn a_wing_of_1e_9_mm_layers_is_refused() {
    wing(
        "wing-layer-height.yaml",
        &[
            "wing-layer-height.yaml: field `build.layer_height_mm`: 0.000000001 mm",
            "(MAX_LAYERS_PER_SECTION)",
        ],
    );
}

fn slice(stl: &Path, process: &str, names: &[&str]) {
    let out = out_dir();
    let process = if process.is_empty() {
        PathBuf::from("waam")
    } else {
        bomb(process)
    };
    let args = [
        OsStr::new("slice"),
        OsStr::new("--stl"),
        stl.as_os_str(),
        OsStr::new("--process"),
        process.as_os_str(),
        OsStr::new("--out"),
        out.path().as_os_str(),
    ];
    refused(&args, EXIT_DATA, names);
}

fn cube() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/stl/20mm-xyz-cube.stl")
}

#[test]
fn waam_layers_of_1e_9_mm_are_refused() {
    slice(
        &cube(),
        "waam-layer-height.yaml",
        &[
            "20mm-xyz-cube.stl: layer_height_mm = 0.000000001 mm makes",
            "the limit is 20000 layers (MAX_DEPOSIT_LAYERS)",
        ],
    );
}

#[test]
fn a_trillion_perimeters_are_refused() {
    slice(
        &cube(),
        "waam-perimeters.yaml",
        &[
            "waam-perimeters.yaml: field `perimeters`: 1000000000000 is out of range",
            "must be in [0, 50] (MAX_PERIMETERS)",
        ],
    );
}

#[test]
fn an_stl_announcing_4_billion_triangles_is_refused() {
    slice(
        &bomb("huge-count.stl"),
        "",
        &["huge-count.stl", "4294967295 triangles"],
    );
}

fn hotwire(extra: &[&OsStr], names: &[&str]) {
    let out = out_dir();
    let mut args = vec![
        OsStr::new("hotwire"),
        OsStr::new("--chord"),
        OsStr::new("200"),
        OsStr::new("--out"),
        out.path().as_os_str(),
    ];
    args.extend_from_slice(extra);
    refused(&args, EXIT_USAGE, names);
}

#[test]
fn an_airfoil_of_too_many_points_is_refused() {
    // 20 001 coordinate lines (~400 KB), written here rather than kept in the repository.
    let dir = out_dir();
    let dat = dir.path().join("many.dat");
    let n = 20_001;
    let mut text = String::from("MANY POINTS\n");
    for i in 0..n {
        let x = 1.0 - i as f64 / (n - 1) as f64;
        text.push_str(&format!("{x:.6} {:.6}\n", 0.01 * (i % 3) as f64));
    }
    std::fs::write(&dat, text).expect("write .dat");
    hotwire(
        &[OsStr::new("--airfoil"), dat.as_os_str()],
        &[
            "--airfoil: ",
            "many.dat:20002: more than 20000 coordinate lines",
            "(MAX_POINTS)",
        ],
    );
}

#[test]
fn swarm_sizes_beyond_their_limits_are_refused() {
    for (flag, value, names) in [
        (
            "--iterations",
            "1000000000",
            ["--iterations: iterations = 1000000000", "(MAX_ITERATIONS)"],
        ),
        (
            "--particles",
            "1000000000",
            ["--particles: particles = 1000000000", "(MAX_PARTICLES)"],
        ),
        (
            "--panels",
            "1000000000",
            ["--panels: panels = 1000000000", "(MAX_PANELS)"],
        ),
    ] {
        hotwire(
            &[
                OsStr::new("--airfoil"),
                OsStr::new("s1223"),
                OsStr::new(flag),
                OsStr::new(value),
            ],
            &names,
        );
    }
}
