//! The program cuts where the drawing says (issue 19, item 1): `cell sheet` on DXF drawings
//! with a 10 mm margin (sheet from `$LIMMIN/$LIMMAX`, from a `SHEET` contour, from the parts'
//! extent), the G-code read back and every pierce and cut coordinate compared with the
//! drawing's entities; `--sheet-origin` shifting everything by exactly its offset; a part
//! outside the machine's travel named before anything is written; a JSON layout's `origin`.

use std::path::{Path, PathBuf};
use std::process::Command;

const CELL: &str = env!("CARGO_BIN_EXE_cell");

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/sheet")
        .join(name)
}

/// A plasma table on LinuxCNC with 3200 × 1800 mm of travel (room for a 3000 × 1500 sheet).
const TABLE_3200: &str = r#"name: plasma-3200
description: "test table: plasma on LinuxCNC, 3200 x 1800 mm"
process: sheet_cut
axes:
  X: [0.0, 3200.0]
  Y: [0.0, 1800.0]
  Z: [0.0, 100.0]
max_feed_mm_s: 150.0
gcode:
  dialect: linuxcnc
  axis_words: {x: X, y: Y, z: Z}
  decimals: 3
  feed_mode: units_per_minute
  power: {on: M3, off: M5, s_per_unit: 1.0}
  pierce: {dwell_s: 0.5, z_pierce_mm: 3.8, z_cut_mm: 1.5, z_travel_mm: 10.0}
  arc_tolerance_mm: 0.02
"#;

/// One `cell sheet` run: its exit status, stderr, and the output directory.
struct Run {
    ok: bool,
    code: Option<i32>,
    stderr: String,
    out: PathBuf,
    _dir: tempfile::TempDir,
}

impl Run {
    fn report(&self) -> serde_json::Value {
        let text = std::fs::read_to_string(self.out.join("report.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    }

    fn program(&self) -> Program {
        Program::parse(&std::fs::read_to_string(self.out.join("program.ngc")).unwrap())
    }
}

/// `cell sheet --layout <layout> <args>` on the 3200 × 1800 table unless `args` names a
/// profile.
fn cell_sheet(layout: &Path, args: &[&str]) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let profile = dir.path().join("plasma-3200.yaml");
    std::fs::write(&profile, TABLE_3200).unwrap();
    let out = dir.path().join("out");
    let mut cmd = Command::new(CELL);
    cmd.args(["sheet", "--seed", "1", "--layout"])
        .arg(layout)
        .arg("--out")
        .arg(&out)
        .args(args);
    if !args.contains(&"--profile") {
        cmd.arg("--profile").arg(&profile);
    }
    let run = cmd.output().unwrap();
    Run {
        ok: run.status.success(),
        code: run.status.code(),
        stderr: String::from_utf8_lossy(&run.stderr).into_owned(),
        out,
        _dir: dir,
    }
}

/// What a G-code program does in XY, read with its own small parser (G0–G3 with I/J, M3/M5).
#[derive(Debug, Default)]
struct Program {
    /// Where the torch fired (M3), in order.
    pierces: Vec<[f64; 2]>,
    /// The end point of every feed move (G1/G2/G3) with the torch on.
    cut_points: Vec<[f64; 2]>,
    /// Every X/Y position the program moves to, in order (rapids included).
    positions: Vec<[f64; 2]>,
}

impl Program {
    fn parse(text: &str) -> Program {
        let mut p = Program::default();
        let (mut at, mut motion, mut torch) = ([f64::NAN; 2], 0u32, false);
        for raw in text.lines() {
            let line = raw.split(';').next().unwrap_or("");
            let line: String = {
                // Strip (comments).
                let mut depth = 0;
                line.chars()
                    .filter(|c| {
                        match c {
                            '(' => depth += 1,
                            ')' => {
                                depth -= 1;
                                return false;
                            }
                            _ => {}
                        }
                        depth == 0
                    })
                    .collect()
            };
            let mut words = Vec::new();
            let chars: Vec<char> = line.chars().filter(|c| !c.is_whitespace()).collect();
            let mut i = 0;
            while i < chars.len() {
                let letter = chars[i].to_ascii_uppercase();
                let start = i + 1;
                i = start;
                while i < chars.len() && (chars[i].is_ascii_digit() || "+-.".contains(chars[i])) {
                    i += 1;
                }
                let value: f64 = chars[start..i]
                    .iter()
                    .collect::<String>()
                    .parse()
                    .unwrap_or_else(|_| panic!("bad word in {raw:?}"));
                words.push((letter, value));
            }
            let mut moved = false;
            let mut to = at;
            for &(letter, value) in &words {
                match letter {
                    'G' if [0.0, 1.0, 2.0, 3.0].contains(&value) => motion = value as u32,
                    'M' if value == 3.0 => {
                        torch = true;
                        p.pierces.push(at);
                    }
                    'M' if value == 5.0 => torch = false,
                    'X' => {
                        to[0] = value;
                        moved = true;
                    }
                    'Y' => {
                        to[1] = value;
                        moved = true;
                    }
                    _ => {}
                }
            }
            if moved {
                at = to;
                p.positions.push(at);
                if torch && motion != 0 {
                    p.cut_points.push(at);
                }
            }
        }
        p
    }
}

/// The contours of the `margin_*.dxf` drawings (see `tests/data/sheet/README.md`), moved by
/// `o`: a plate with a round hole and a slot, a triangle, a disc in the far corner.
enum Shape {
    /// Straight edges of a closed polygon.
    Polygon(Vec<[f64; 2]>),
    /// A circle: centre, radius.
    Circle([f64; 2], f64),
    /// A slot: the two straight sides' ends (left bottom, right top), semicircular ends.
    Slot([f64; 2], [f64; 2]),
}

fn drawing(o: [f64; 2]) -> Vec<(&'static str, Shape)> {
    let t = |x: f64, y: f64| [x + o[0], y + o[1]];
    let (x0, y0) = (10.101, 10.150);
    vec![
        (
            "plate",
            Shape::Polygon(vec![
                t(x0, y0),
                t(x0 + 200.0, y0),
                t(x0 + 200.0, y0 + 100.0),
                t(x0, y0 + 100.0),
            ]),
        ),
        ("round hole", Shape::Circle(t(x0 + 50.0, y0 + 50.0), 20.0)),
        (
            "slot",
            Shape::Slot(t(x0 + 100.0, y0 + 35.0), t(x0 + 160.0, y0 + 65.0)),
        ),
        (
            "triangle",
            Shape::Polygon(vec![t(1500.0, 700.0), t(1600.0, 700.0), t(1550.0, 790.0)]),
        ),
        ("disc", Shape::Circle(t(2960.0, 1460.0), 30.0)),
    ]
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn dist_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

impl Shape {
    /// Distance from `p` to the contour, mm.
    fn distance(&self, p: [f64; 2]) -> f64 {
        match self {
            Shape::Polygon(v) => (0..v.len())
                .map(|i| dist_to_segment(p, v[i], v[(i + 1) % v.len()]))
                .fold(f64::INFINITY, f64::min),
            Shape::Circle(c, r) => (dist(p, *c) - r).abs(),
            Shape::Slot(lo, hi) => {
                let r = (hi[1] - lo[1]) / 2.0;
                let cy = lo[1] + r;
                let sides = dist_to_segment(p, *lo, [hi[0], lo[1]]).min(dist_to_segment(
                    p,
                    [lo[0], hi[1]],
                    *hi,
                ));
                // Each end cap is the outer half of its circle.
                let cap = |cx: f64, outward: f64| {
                    if (p[0] - cx) * outward >= 0.0 {
                        (dist(p, [cx, cy]) - r).abs()
                    } else {
                        f64::INFINITY
                    }
                };
                sides.min(cap(hi[0], 1.0)).min(cap(lo[0], -1.0))
            }
        }
    }
}

/// Checks `program` against the drawing moved by `o`: every pierce and every cut coordinate
/// within 0.01 mm of a drawn contour (plus 0.05 mm on curves: a pierce may sit mid-chord), and each contour pierced exactly once. The table
/// profile has no `cutting:` section, so the cuts are on the drawn lines (no kerf, no leads).
fn assert_cut_in_place(program: &Program, o: [f64; 2], what: &str) {
    const TOL_MM: f64 = 0.01;
    const CHORD_TOL_MM: f64 = 0.05;
    let shapes = drawing(o);
    // How far beyond its kind's slack the nearest contour is, and its name.
    let nearest = |p: [f64; 2]| {
        shapes
            .iter()
            .map(|(name, s)| {
                let slack = match s {
                    Shape::Polygon(_) => 0.0,
                    Shape::Circle(..) | Shape::Slot(..) => CHORD_TOL_MM,
                };
                ((s.distance(p) - slack).max(0.0), *name)
            })
            .fold((f64::INFINITY, ""), |a, b| if b.0 < a.0 { b } else { a })
    };
    // Some cut on every drawn contour (circles may come as a few G2/G3 arcs).
    assert!(
        program.cut_points.len() >= shapes.len(),
        "{what}: {program:?}"
    );
    for &p in &program.cut_points {
        let (d, name) = nearest(p);
        assert!(
            d <= TOL_MM,
            "{what}: cut point {p:?} is {d:.4} mm from the drawing's nearest contour ({name})"
        );
    }
    let mut pierced: Vec<&str> = program
        .pierces
        .iter()
        .map(|&p| {
            let (d, name) = nearest(p);
            assert!(d <= TOL_MM, "{what}: pierce {p:?} is {d:.4} mm from {name}");
            name
        })
        .collect();
    pierced.sort_unstable();
    let mut want: Vec<&str> = shapes.iter().map(|(n, _)| *n).collect();
    want.sort_unstable();
    assert_eq!(pierced, want, "{what}: one pierce per contour");
}

fn assert_sheet(report: &serde_json::Value, rule: &str, size: [f64; 2], origin: [f64; 2]) {
    let s = &report["sheet"];
    assert_eq!(s["rule"], rule, "{s}");
    let pair = |v: &serde_json::Value| [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()];
    let (got_size, got_origin) = (pair(&s["size_mm"]), pair(&s["origin_mm"]));
    // The parts' extent is that of the flattened curves: up to the DXF chord tolerance
    // (0.005 mm) inside the drawn circles.
    for k in 0..2 {
        assert!((got_size[k] - size[k]).abs() < 0.006, "{s}");
        assert!((got_origin[k] - origin[k]).abs() < 0.006, "{s}");
    }
}

/// The issue's case: no `SHEET` layer, `$LIMMIN/$LIMMAX` of a 3000 × 1500 sheet, parts 10 mm
/// in from its edges; and the same drawing with a `SHEET` contour, and with no header at all.
#[test]
fn a_drawing_is_cut_at_its_own_coordinates_whatever_finds_the_sheet() {
    let cases = [
        (
            "margin_limits.dxf",
            "limits",
            [3000.0, 1500.0],
            [0.0, 0.0],
            [0.0, 0.0],
        ),
        (
            "margin_sheet_layer.dxf",
            "sheet_layer",
            [3000.0, 1500.0],
            [100.0, 200.0],
            [100.0, 200.0],
        ),
        (
            "margin_no_header.dxf",
            "parts",
            [2990.0 - 10.101, 1490.0 - 10.150],
            [10.101, 10.150],
            [0.0, 0.0],
        ),
    ];
    for (file, rule, size, origin, moved) in cases {
        let run = cell_sheet(&data(file), &[]);
        assert!(run.ok, "{file}: {}", run.stderr);
        let report = run.report();
        assert_sheet(&report, rule, size, origin);
        assert_eq!(report["sheet"]["origin_from"], "drawing");
        let program = run.program();
        assert_cut_in_place(&program, moved, file);
        // The program starts at the sheet's corner (the start point is sheet-relative).
        assert_eq!(program.positions[0], origin, "{file}");
    }
}

#[test]
fn sheet_origin_shifts_every_coordinate_by_exactly_its_offset() {
    let layout = data("margin_limits.dxf");
    let base = cell_sheet(&layout, &[]);
    let moved = cell_sheet(&layout, &["--sheet-origin", "100,50"]);
    assert!(base.ok && moved.ok, "{} {}", base.stderr, moved.stderr);
    assert_sheet(&moved.report(), "limits", [3000.0, 1500.0], [100.0, 50.0]);
    assert_eq!(moved.report()["sheet"]["origin_from"], "operator");
    let (a, b) = (base.program(), moved.program());
    assert_eq!(a.positions.len(), b.positions.len());
    for (p, q) in a.positions.iter().zip(&b.positions) {
        // Both written to 3 decimals.
        assert!(
            (q[0] - p[0] - 100.0).abs() < 1.5e-3 && (q[1] - p[1] - 50.0).abs() < 1.5e-3,
            "{p:?} → {q:?}"
        );
    }
    assert_cut_in_place(&b, [100.0, 50.0], "--sheet-origin 100,50");
    let bad = cell_sheet(&layout, &["--sheet-origin", "100"]);
    assert_eq!(bad.code, Some(64), "a usage error: {}", bad.stderr);
    assert!(bad.stderr.contains("expected X,Y in mm"), "{}", bad.stderr);
}

#[test]
fn a_part_outside_the_machines_travel_is_named_and_nothing_is_written() {
    // The 1250 × 1250 table: the disc at X 2930..2990 mm (with its kerf and leads) is off it.
    let run = cell_sheet(
        &data("margin_limits.dxf"),
        &["--profile", "linuxcnc-plasma"],
    );
    assert_eq!(run.code, Some(65), "{}", run.stderr);
    assert!(
        run.stderr.contains("margin_limits.dxf")
            && run.stderr.contains("parts[1] (CIRCLE #")
            && run.stderr.contains("spans X 29")
            && run
                .stderr
                .contains("outside the X travel 0.000..1250.000 mm of machine 'linuxcnc-plasma'"),
        "{}",
        run.stderr
    );
    assert!(!run.out.join("program.ngc").exists());
    assert!(!run.out.join("report.json").exists());
    // On the big table it fits, until the operator moves the sheet 300 mm to the right.
    let run = cell_sheet(&data("margin_limits.dxf"), &["--sheet-origin", "300,0"]);
    assert_eq!(run.code, Some(65), "{}", run.stderr);
    assert!(
        run.stderr.contains("spans X 3230.000..3290.000")
            && run.stderr.contains("(sheet origin (300.000, 0.000) mm)")
            && run.stderr.contains("X travel 0.000..3200.000"),
        "{}",
        run.stderr
    );
    // Or 20 mm to the left: the plate (the first part) starts at X −9.899 mm.
    let run = cell_sheet(&data("margin_limits.dxf"), &["--sheet-origin", "-20,0"]);
    assert_eq!(run.code, Some(65), "{}", run.stderr);
    assert!(
        run.stderr.contains("parts[0] (LWPOLYLINE #")
            && run.stderr.contains("spans X -9.899..190.101")
            && run.stderr.contains("(sheet origin (-20.000, 0.000) mm)"),
        "{}",
        run.stderr
    );
}

#[test]
fn a_json_layout_is_placed_at_its_origin_and_small_dxf_is_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(data("example.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["origin"] = serde_json::json!([500.0, 300.0]);
    let file = dir.path().join("placed.json");
    std::fs::write(&file, json.to_string()).unwrap();
    let placed = cell_sheet(&file, &[]);
    let plain = cell_sheet(&data("example.json"), &[]);
    assert!(placed.ok && plain.ok, "{}", placed.stderr);
    assert_sheet(&placed.report(), "layout", [300.0, 200.0], [500.0, 300.0]);
    assert_sheet(&plain.report(), "layout", [300.0, 200.0], [0.0, 0.0]);
    let (a, b) = (plain.program(), placed.program());
    assert_eq!(b.positions[0], [500.0, 300.0]);
    for (p, q) in a.pierces.iter().zip(&b.pierces) {
        assert!((q[0] - p[0] - 500.0).abs() < 1.5e-3 && (q[1] - p[1] - 300.0).abs() < 1.5e-3);
    }
    // The CutPlan's pierce points are machine coordinates too.
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(placed.out.join("plan.json")).unwrap())
            .unwrap();
    for (p, q) in plan["pierce_points"]
        .as_array()
        .unwrap()
        .iter()
        .zip(&b.pierces)
    {
        let x = p["x"].as_f64().unwrap();
        let y = p["y"].as_f64().unwrap();
        assert!(
            (x - q[0]).abs() < 1e-3 && (y - q[1]).abs() < 1e-3,
            "{p} vs {q:?}"
        );
    }
    // small.dxf's SHEET outline sits at 0,0: its program is where it always was.
    let small = cell_sheet(&data("small.dxf"), &[]);
    assert!(small.ok, "{}", small.stderr);
    assert_sheet(&small.report(), "sheet_layer", [300.0, 200.0], [0.0, 0.0]);
}

#[test]
fn a_notch_narrower_than_the_kerf_is_named_on_stderr_and_in_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let layout = dir.path().join("comb.json");
    // A plate with a 1 mm slot 30 mm deep in its top edge: a 1.5 mm plasma kerf cannot enter.
    std::fs::write(
        &layout,
        r#"{"sheet": [300, 200], "start": [0, 0], "parts": [{"name": "comb", "outer": {"points":
            [[10,10],[110,10],[110,110],[60.5,110],[60.5,80],[59.5,80],[59.5,110],[10,110]]}}]}"#,
    )
    .unwrap();
    let profile =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("config/machines/linuxcnc-plasma-3015.yaml");
    let run = cell_sheet(&layout, &["--profile", profile.to_str().unwrap()]);
    assert!(run.ok, "{}", run.stderr);
    assert!(
        run.stderr.contains("warning: ")
            && run
                .stderr
                .contains("comb.json: parts[0] (comb).outer: the kerf misses")
            && run.stderr.contains("narrower than the 1.5 mm kerf"),
        "{}",
        run.stderr
    );
    let report = run.report();
    let warnings = report["cut"]["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].as_str().unwrap().contains("(comb)"));
    // The part is still cut, round the slot.
    assert_eq!(report["contours"], 1);
}
