//! Acceptance of sheet cutting for real parts (issue 19): an independent check of what the
//! program cuts. `cell sheet` runs on a layout with a machine profile; the written
//! `program.ngc` is read back with this test's own G-code reader (`common/gcode_reader.rs`,
//! no code shared with the emitter) and checked against the layout (`common/cut_check.rs`):
//! every contour cut exactly once, the cut path within 0.02 mm of the nominal contour offset by
//! half the kerf on the scrap side and covering it, each pierce on the scrap side about a
//! lead-in length from its contour, no lead crossing or grazing another contour, strict
//! precedence, and, for DXF input, the parts cut at the drawing's own coordinates.
//!
//! The input side may use the libraries (the generator, the DXF reader, the profile's kerf
//! table); the program side may not. The kerf and lead lengths come from the profile used.
//!
//! Layouts: the nested generator at 50 contours (plasma, 1250 × 1250 table, improved as `cell
//! sheet` does by default) and 1000 contours (smaller parts, laser 3000 × 1500: plasma cannot
//! cut their 2–3 mm holes; thermal construction, no improvement), the dense perforated
//! generator at 5000 contours (plasma 4000 × 2000; `--thermal off`, no improvement), the real
//! plate outlines, and DXF files with a sheet outline, with `$LIMMIN/$LIMMAX` only, with no
//! header at all (a 10 mm margin the program must keep), and placed by the operator
//! (`--sheet-origin`). The improvement phase is left out of the two large runs to keep a debug
//! build on two cores at about a minute per run (it changes the order and the pierce chosen,
//! not how a cut is made; the smaller runs cover it).

#[path = "common/cut_check.rs"]
mod cut_check;
#[path = "common/gcode_reader.rs"]
mod gcode_reader;
#[path = "common/model_program.rs"]
mod model_program;
#[path = "common/plane.rs"]
mod plane;

use std::path::{Path, PathBuf};

use cut_check::{check, check_drawing, dxf_drawing_points, Check, CutParams, Reference, Report};
use gcode_reader::{read, Compensation};
use model_program::{program, ModelCut};
use plane::P;

const CELL: &str = env!("CARGO_BIN_EXE_cell");

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

// ---------------------------------------------------------------------------------------------
// The reader on hand-written G-code.

#[test]
fn the_reader_follows_lines_arcs_modes_and_the_heat() {
    let text = "%
N10 G21 G90 G91.1 (units, absolute, incremental arc centres) ; and a comment
N20 G0 X10 Y0 Z10
N30 G0 Z3.8
N40 m3 s100
N50 G4 P0.5
N60 G1 Z1.5 F2400
N70 G1 X20
N80 G3 X20 Y0 I0 J5 (a full circle about 20, 5)
N90 G2 X30 Y10 R10 (a quarter circle about 30, 0)
N100 G91 G1 X-5
N110 G90 M5
N120 G20 G0 X1 Y1
M3
G1 X2
g 1 y 2 . 5
M5
M2
%
";
    let p = read(text).unwrap();
    assert!(p.ended);
    assert_eq!(p.runs.len(), 2);
    let first = &p.runs[0];
    assert_eq!(first.pierce, [10.0, 0.0]);
    assert_eq!(first.line, 5);
    assert_eq!(first.pierce_dwell_s, 0.5);
    let tau = std::f64::consts::TAU;
    let expected = 10.0 + tau * 5.0 + tau * 10.0 / 4.0 + 5.0;
    // Chords are a little shorter than their arcs (≈ θ²/24 of the length).
    assert!(
        (first.length() - expected).abs() < 0.02,
        "{} vs {expected}",
        first.length()
    );
    assert_eq!(*first.path.last().unwrap(), [25.0, 10.0]);
    assert!(first.rapids_with_heat.is_empty());
    // Arc samples lie on their circles, chords within the sampling tolerance.
    for w in first.path.windows(2) {
        let on_circle = |p: P, c: P, r: f64| ((p[0] - c[0]).hypot(p[1] - c[1]) - r).abs() < 1e-9;
        let chord = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        if on_circle(w[0], [20.0, 5.0], 5.0) && on_circle(w[1], [20.0, 5.0], 5.0) {
            let sagitta = 5.0 - (25.0 - chord * chord / 4.0).sqrt();
            assert!(
                sagitta <= gcode_reader::ARC_SAMPLING_MM + 1e-12,
                "{sagitta}"
            );
        }
    }
    // The full circle reaches its top, and nothing goes above it.
    assert!(first
        .path
        .iter()
        .any(|&q| (q[0] - 20.0).abs() < 0.5 && q[1] > 9.99));
    assert!(first.path.iter().all(|&q| q[1] <= 10.0 + 1e-9));
    // Inches: 25.4 mm per unit; spaces inside words.
    let second = &p.runs[1];
    assert_eq!(second.pierce, [25.4, 25.4]);
    let expected = [[25.4, 25.4], [50.8, 25.4], [50.8, 63.5]];
    assert_eq!(second.path.len(), 3);
    for (got, want) in second.path.iter().zip(expected) {
        assert!(plane::dist(*got, want) < 1e-9, "{got:?} vs {want:?}");
    }
    assert_eq!(p.rapids.len(), 2, "{:?}", p.rapids);
}

#[test]
fn the_reader_notes_compensation_and_heat_on_rapids() {
    let text = "G21 G90\nG0 X1 Y1\nM3 S50\nG42 D1\nG1 X5\nG0 X9\nG40\nM5\nM2\n";
    let p = read(text).unwrap();
    assert!(p.compensation_used);
    assert_eq!(p.d_words, vec![1.0]);
    let run = &p.runs[0];
    assert_eq!(run.move_compensation, vec![Compensation::Right; 2]);
    assert_eq!(run.rapids_with_heat, vec![6]);
    // S0 switches a laser off as M5 does.
    let p = read("G0 X0 Y0\nM4 S0\nG1 X5\nS100\nM4\nG1 X9\nM5\n").unwrap();
    assert_eq!(p.runs.len(), 1);
    assert_eq!(p.runs[0].path, vec![[5.0, 0.0], [9.0, 0.0]]);
}

#[test]
fn the_reader_refuses_what_it_cannot_follow() {
    let refused = |text: &str| read(text).unwrap_err().to_string();
    let e = refused("G21\nG92 X0 Y0\n");
    assert!(e.starts_with("program line 2: G92 is not supported"), "{e}");
    let e = refused("G1 X1 G0 Y1\n");
    assert!(e.contains("two motion words"), "{e}");
    let e = refused("X5\n");
    assert!(e.contains("without a motion mode"), "{e}");
    let e = refused("G0 X0 Y0\nG2 X10 Y0 I1 J0\n");
    assert!(
        e.starts_with("program line 2: arc end radius 9.0000 differs"),
        "{e}"
    );
    let e = refused("G0 X0 (unclosed\n");
    assert!(e.contains("unclosed comment"), "{e}");
    let e = refused("#1=5\n");
    assert!(e.contains("not a word letter"), "{e}");
    let e = refused("G18\n");
    assert!(e.contains("G18 is not supported"), "{e}");
    let e = refused("G2 X10 Y0 R2\n");
    assert!(e.contains("shorter than half the chord"), "{e}");
    let e = refused("M2\nG0 X1\n");
    assert!(e.contains("after the program end"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// The checker on hand-made programs that must pass and must fail.

const KERF: f64 = 1.5;
const LEAD: f64 = 5.0;

fn params() -> CutParams {
    CutParams {
        kerf_mm: KERF,
        lead_in_mm: LEAD,
        lead_out_mm: 0.0,
        overcut_mm: 0.0,
        small_hole_diameter_mm: 12.0,
        skip_too_small_holes: false,
        controller_compensation: false,
    }
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<P> {
    vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
}

fn polygon_circle(c: P, r: f64, n: usize) -> Vec<P> {
    (0..n)
        .map(|k| {
            let a = k as f64 / n as f64 * std::f64::consts::TAU;
            [c[0] + r * a.cos(), c[1] + r * a.sin()]
        })
        .collect()
}

/// A plate with a square hole and a small round hole, an L-shaped part (a concave corner), and
/// a frame whose hole holds a nested insert 4 mm from the hole's edge.
fn model_reference() -> Reference {
    Reference::from_parts(vec![
        (
            Some("plate".into()),
            rect(10.0, 10.0, 70.0, 50.0),
            vec![
                rect(20.0, 20.0, 34.0, 34.0),
                polygon_circle([55.0, 30.0], 4.0, 32),
            ],
        ),
        (
            Some("ell".into()),
            vec![
                [90.0, 10.0],
                [130.0, 10.0],
                [130.0, 25.0],
                [105.0, 25.0],
                [105.0, 50.0],
                [90.0, 50.0],
            ],
            vec![],
        ),
        (
            Some("frame".into()),
            rect(10.0, 70.0, 90.0, 130.0),
            vec![rect(20.0, 80.0, 80.0, 120.0)],
        ),
        (Some("insert".into()), rect(35.0, 84.0, 65.0, 110.0), vec![]),
    ])
}

/// The model cuts of [`model_reference`] by contour id (plate 0–2, ell 3, frame 4–5, insert
/// 6), each offset by half the kerf with a lead-in square to one edge.
fn model_cuts() -> Vec<ModelCut> {
    let r = model_reference();
    let e = KERF / 2.0;
    let ring = |c: usize| r.contours[c].ring.clone();
    let small_lead = 4.0 * (std::f64::consts::PI / 32.0).cos() - e;
    vec![
        ModelCut::new(&ring(0), false, e, LEAD, 0),
        ModelCut::new(&ring(1), true, e, LEAD, 0),
        // The small hole: pierced at its centre.
        ModelCut::new(&ring(2), true, e, small_lead, 0),
        ModelCut::new(&ring(3), false, e, LEAD, 0),
        ModelCut::new(&ring(4), false, e, LEAD, 0),
        // The frame's hole from its top edge, the insert from its left edge: clear of each other.
        ModelCut::new(&ring(5), true, e, LEAD, 2),
        ModelCut::new(&ring(6), false, e, LEAD, 3),
    ]
}

/// A valid order: holes before their outer contour, the insert before the frame's hole.
const GOOD_ORDER: [usize; 7] = [1, 2, 0, 3, 6, 5, 4];

fn model_program(order: &[usize], edit: impl Fn(usize, &mut ModelCut)) -> String {
    let cuts = model_cuts();
    let picked: Vec<ModelCut> = order
        .iter()
        .map(|&c| {
            let mut cut = cuts[c].clone();
            edit(c, &mut cut);
            cut
        })
        .collect();
    program(&picked)
}

fn check_model(text: &str, p: &CutParams) -> Report {
    let prog = read(text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    check(&model_reference(), &prog, p)
}

#[test]
fn a_correct_program_passes() {
    let r = check_model(&model_program(&GOOD_ORDER, |_, _| {}), &params());
    assert!(r.is_clean(), "{}", r.summary());
    assert_eq!((r.runs, r.matched), (7, 7));
    // Within the tolerance is still fine: 0.015 mm too far out on the plate.
    let r = check_model(
        &model_program(&GOOD_ORDER, |c, cut| {
            if c == 0 {
                cut.offset += 0.015;
            }
        }),
        &params(),
    );
    assert!(r.is_clean(), "{}", r.summary());
    // Controller compensation: the nominal contour with G41/G42 to the scrap side.
    let controller = CutParams {
        controller_compensation: true,
        ..params()
    };
    let text = model_program(&GOOD_ORDER, |_, cut| cut.controller = true);
    assert!(text.contains("G41") && text.contains("G42"), "{text}");
    let r = check_model(&text, &controller);
    assert!(r.is_clean(), "{}", r.summary());
}

#[test]
fn a_program_without_kerf_compensation_fails() {
    let r = check_model(
        &model_program(&GOOD_ORDER, |_, cut| {
            cut.offset = 0.0;
            cut.lead = 0.0;
        }),
        &params(),
    );
    assert_eq!(r.count(Check::Offset), 7, "{}", r.summary());
    assert_eq!(r.count(Check::Pierce), 7, "pierced on the part's edge");
    assert!(
        r.summary().contains("no kerf compensation"),
        "{}",
        r.summary()
    );
}

#[test]
fn a_path_off_the_offset_or_on_the_wrong_side_fails() {
    let r = check_model(
        &model_program(&GOOD_ORDER, |c, cut| {
            if c == 0 {
                cut.offset += 0.03;
            }
        }),
        &params(),
    );
    assert_eq!(r.count(Check::Offset), 1, "{}", r.summary());
    assert!(
        r.summary().contains("parts[0] (plate).outer"),
        "{}",
        r.summary()
    );
    // The square hole offset into the part: right distance, wrong side.
    let r = check_model(
        &model_program(&GOOD_ORDER, |c, cut| {
            if c == 1 {
                cut.offset = -KERF / 2.0;
            }
        }),
        &params(),
    );
    assert_eq!(r.count(Check::Side), 1, "{}", r.summary());
    assert!(r.count(Check::LeadClearance) >= 1, "{}", r.summary());
    // Controller compensation to the part's side.
    let controller = CutParams {
        controller_compensation: true,
        ..params()
    };
    let text = model_program(&GOOD_ORDER, |_, cut| cut.controller = true)
        .replace("G41", "G4x")
        .replace("G42", "G41")
        .replace("G4x", "G42");
    let r = check_model(&text, &controller);
    assert_eq!(r.count(Check::Side), 7, "{}", r.summary());
}

#[test]
fn a_missing_repeated_or_partial_cut_fails() {
    let r = check_model(&model_program(&[1, 2, 0, 6, 5, 4], |_, _| {}), &params());
    assert_eq!(r.count(Check::Count), 1, "{}", r.summary());
    assert!(
        r.summary().contains("(ell).outer is never cut"),
        "{}",
        r.summary()
    );
    let r = check_model(
        &model_program(&[1, 2, 0, 3, 3, 6, 5, 4], |_, _| {}),
        &params(),
    );
    assert!(
        r.summary().contains("(ell).outer is cut 2 times"),
        "{}",
        r.summary()
    );
    let r = check_model(
        &model_program(&GOOD_ORDER, |c, cut| {
            if c == 0 {
                cut.fraction = 0.5;
            }
        }),
        &params(),
    );
    assert_eq!(r.count(Check::Coverage), 1, "{}", r.summary());
    // A cut that follows nothing.
    let mut text = model_program(&GOOD_ORDER, |_, _| {});
    text = text.replace(
        "G0 X0 Y0\nM2",
        "G0 X200 Y200\nM3 S100\nG1 X220 Y200\nM5\nG0 X0 Y0\nM2",
    );
    let r = check_model(&text, &params());
    assert!(
        r.summary().contains("follows no contour"),
        "{}",
        r.summary()
    );
}

#[test]
fn a_program_against_the_precedence_fails() {
    // The plate's outer contour before its holes.
    let r = check_model(&model_program(&[0, 1, 2, 3, 6, 5, 4], |_, _| {}), &params());
    assert_eq!(r.count(Check::Precedence), 2, "{}", r.summary());
    // The frame's hole before the insert lying in it.
    let r = check_model(&model_program(&[1, 2, 0, 3, 5, 4, 6], |_, _| {}), &params());
    assert_eq!(r.count(Check::Precedence), 1, "{}", r.summary());
    assert!(
        r.summary().contains("(insert).outer lies in"),
        "{}",
        r.summary()
    );
    // The plate interrupted by the ell.
    let r = check_model(&model_program(&[1, 3, 2, 0, 6, 5, 4], |_, _| {}), &params());
    assert_eq!(r.count(Check::Precedence), 1, "{}", r.summary());
    assert!(r.summary().contains("not cut in one go"), "{}", r.summary());
}

#[test]
fn bad_pierces_and_leads_fail() {
    // The insert entered from its bottom edge: the lead-in crosses the frame's hole edge and
    // the pierce lands in the frame.
    let r = check_model(
        &model_program(&GOOD_ORDER, |c, cut| {
            if c == 6 {
                cut.lead_edge = 0;
            }
        }),
        &params(),
    );
    assert_eq!(r.count(Check::LeadClearance), 1, "{}", r.summary());
    assert!(r.summary().contains("(frame).holes[0]"), "{}", r.summary());
    assert!(
        r.summary().contains("in the material of parts[2]"),
        "{}",
        r.summary()
    );
    // A pierce half a millimetre from the path: too close, and a lead-in cut short for nothing.
    let r = check_model(
        &model_program(&GOOD_ORDER, |c, cut| {
            if c == 3 {
                cut.lead = 0.5;
            }
        }),
        &params(),
    );
    assert_eq!(r.count(Check::Pierce), 1, "{}", r.summary());
    assert_eq!(r.count(Check::LeadLength), 1, "{}", r.summary());
    // A lead-in longer than the profile's: the pierce too far out, the lead too long.
    let r = check_model(
        &model_program(&GOOD_ORDER, |c, cut| {
            if c == 3 {
                cut.lead = 8.0;
            }
        }),
        &params(),
    );
    assert_eq!(r.count(Check::LeadLength), 2, "{}", r.summary());
    // The small hole pierced off centre with a short lead.
    let r = check_model(
        &model_program(&GOOD_ORDER, |c, cut| {
            if c == 2 {
                cut.lead = 1.0;
            }
        }),
        &params(),
    );
    assert!(
        r.summary().contains("not at the small hole's centre"),
        "{}",
        r.summary()
    );
    // A rapid with the heat on.
    let text = model_program(&GOOD_ORDER, |_, _| {}).replacen("G1 X", "G0 X", 1);
    let r = check_model(&text, &params());
    assert_eq!(r.count(Check::HeatOnRapid), 1, "{}", r.summary());
}

#[test]
fn drawing_points_must_lie_on_the_layout() {
    let dxf = std::fs::read_to_string(repo("tests/data/sheet/margin_no_header.dxf")).unwrap();
    let points = dxf_drawing_points(&dxf, "SHEET");
    assert!(!points.is_empty());
    assert!(
        points.iter().any(|(p, _)| *p == [10.101, 10.15]),
        "{points:?}"
    );
    let reference = dxf_reference(&repo("tests/data/sheet/margin_no_header.dxf"), None);
    let mut r = Report::default();
    check_drawing(&reference, &points, &mut r);
    assert!(r.is_clean(), "{}", r.summary());
    // The same parts moved by the 10 mm margin are not where the drawing says.
    let moved = Reference::from_parts(
        reference
            .contours
            .iter()
            .map(|c| {
                let ring = c
                    .ring
                    .iter()
                    .map(|p| [p[0] - 10.101, p[1] - 10.15])
                    .collect();
                (None, ring, vec![])
            })
            .collect(),
    );
    let mut r = Report::default();
    check_drawing(&moved, &points, &mut r);
    assert!(r.count(Check::Drawing) >= 1, "{}", r.summary());
}

// ---------------------------------------------------------------------------------------------
// The acceptance runs: `cell sheet`, then the check.

/// The cutting parameters of a profile (read with `cell_profiles`: the input side).
fn cut_params(profile: &Path) -> CutParams {
    let p = cell_profiles::MachineProfile::load(profile)
        .unwrap_or_else(|e| panic!("{}: {e}", profile.display()));
    let c = p
        .cutting
        .as_ref()
        .unwrap_or_else(|| panic!("{} has no cutting section", profile.display()));
    let m = c
        .default_material
        .as_ref()
        .unwrap_or_else(|| panic!("{}: no default material", profile.display()));
    CutParams {
        kerf_mm: c.kerf_mm(&m.material, m.thickness_mm).unwrap(),
        lead_in_mm: c.lead_in.length_mm,
        lead_out_mm: c.lead_out_mm,
        overcut_mm: c.overcut_mm,
        small_hole_diameter_mm: c.small_hole_diameter_mm,
        skip_too_small_holes: c.too_small_holes == cell_profiles::TooSmallHoles::Skip,
        controller_compensation: c.compensation == cell_profiles::Compensation::Controller,
    }
}

/// A DXF layout as the sequencer's reader sees it, arcs flattened far finer than the check's
/// tolerance (points relative to the sheet, `origin` its corner in the drawing).
fn dxf_layout(path: &Path) -> cell_sequencer::layout::Layout {
    let opt = cell_sequencer::dxf::DxfOptions {
        chord_tol_mm: 0.001,
        ..Default::default()
    };
    cell_sequencer::dxf::read_dxf(path, &opt).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The contours of a DXF in machine coordinates: the drawing's own, or with the sheet's corner
/// placed at `origin`.
fn dxf_reference(path: &Path, origin: Option<P>) -> Reference {
    let layout = dxf_layout(path);
    let o = origin.unwrap_or(layout.origin);
    let place =
        |ring: &[P]| -> Vec<P> { ring.iter().map(|p| [p[0] + o[0], p[1] + o[1]]).collect() };
    Reference::from_parts(
        layout
            .parts
            .iter()
            .map(|part| {
                (
                    part.name.clone(),
                    place(&part.outer.points),
                    part.holes.iter().map(|h| place(&h.points)).collect(),
                )
            })
            .collect(),
    )
}

/// What one `cell sheet` run wrote.
struct SheetRun {
    _dir: tempfile::TempDir,
    out: PathBuf,
    program: String,
    report: serde_json::Value,
}

/// Runs `cell sheet` on `layout` with the profile file `profile` and `extra` options.
fn cell_sheet(layout: &Path, profile: &Path, extra: &[&str]) -> SheetRun {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let run = std::process::Command::new(CELL)
        .arg("sheet")
        .arg("--layout")
        .arg(layout)
        .arg("--out")
        .arg(&out)
        .arg("--profile")
        .arg(profile)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "cell sheet {}: {}",
        layout.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    eprintln!("{}", String::from_utf8_lossy(&run.stdout).trim());
    SheetRun {
        program: std::fs::read_to_string(out.join("program.ngc")).unwrap(),
        report: serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap())
            .unwrap(),
        out,
        _dir: dir,
    }
}

/// Reads the program and checks it; fails the test with the findings.
fn accept(
    what: &str,
    reference: &Reference,
    run: &SheetRun,
    params: &CutParams,
    drawing: &[(P, String)],
) {
    let started = std::time::Instant::now();
    let program = read(&run.program).unwrap_or_else(|e| panic!("{what}: {e}"));
    let mut report = check(reference, &program, params);
    check_drawing(reference, drawing, &mut report);
    eprintln!(
        "{what}: checked in {:.1} s",
        started.elapsed().as_secs_f64()
    );
    let phases: Vec<String> = run.report["phases"]
        .as_array()
        .map(|ps| {
            ps.iter()
                .map(|p| {
                    format!(
                        "{} {:.1} s",
                        p["phase"].as_str().unwrap_or("?"),
                        p["seconds"].as_f64().unwrap_or(0.0)
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    eprintln!("{what}: phases {}", phases.join(", "));
    let leads = &report.lead_in_mm;
    let mean = leads.iter().sum::<f64>() / leads.len().max(1) as f64;
    eprintln!(
        "{what}: {} contours, kerf {} mm, lead-in {} mm (mean measured {mean:.3} mm); {}",
        reference.contours.len(),
        params.kerf_mm,
        params.lead_in_mm,
        report.summary()
    );
    assert!(report.is_clean(), "{what}: {}", report.summary());
}

/// Writes a layout to JSON in `dir` and returns its path.
fn write_layout(dir: &Path, name: &str, layout: &cell_sequencer::layout::Layout) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, layout.to_json()).unwrap();
    path
}

fn json_acceptance(what: &str, layout: &Path, profile: &str, extra: &[&str]) {
    let profile = repo(&format!("config/machines/{profile}.yaml"));
    let params = cut_params(&profile);
    let reference = Reference::from_layout_json(&std::fs::read_to_string(layout).unwrap()).unwrap();
    let run = cell_sheet(layout, &profile, extra);
    accept(what, &reference, &run, &params, &[]);
}

#[test]
fn generator_50_contours_on_the_plasma_table() {
    let dir = tempfile::tempdir().unwrap();
    let layout = cell_sequencer::generator::generate(&cell_sequencer::generator::GeneratorConfig {
        seed: 11,
        contours: 50,
        // Parts of 60 mm and more: their smallest holes (about 4 mm) are still plasma work.
        part_size_mm: [60.0, 250.0],
        ..Default::default()
    });
    let path = write_layout(dir.path(), "gen50.json", &layout);
    json_acceptance(
        "generator, 50 contours",
        &path,
        "linuxcnc-plasma",
        &["--seed", "1"],
    );
}

#[test]
fn generator_1000_contours_on_the_laser_table() {
    let dir = tempfile::tempdir().unwrap();
    let layout = cell_sequencer::generator::generate(&cell_sequencer::generator::GeneratorConfig {
        seed: 19,
        contours: 1000,
        part_size_mm: [20.0, 120.0],
        ..Default::default()
    });
    let path = write_layout(dir.path(), "gen1000.json", &layout);
    json_acceptance(
        "generator, 1000 contours",
        &path,
        "linuxcnc-laser-3015",
        &["--policy", "path_overheat", "--no-improve"],
    );
}

#[test]
fn perforated_5000_contours_on_the_large_plasma_table() {
    let dir = tempfile::tempdir().unwrap();
    let layout = cell_sequencer::generator::generate_perforated(
        &cell_sequencer::generator::PerforatedConfig {
            seed: 19,
            contours: 5000,
            ..Default::default()
        },
    );
    let path = write_layout(dir.path(), "perforated5000.json", &layout);
    json_acceptance(
        "perforated, 5000 contours",
        &path,
        "linuxcnc-plasma-4020",
        &["--thermal", "off", "--no-improve"],
    );
}

#[test]
fn real_plate_outlines() {
    json_acceptance(
        "plate_holes_nest.json",
        &repo("tests/data/sheet/plate_holes_nest.json"),
        "linuxcnc-plasma",
        &[],
    );
}

/// `cell sheet` on a DXF, checked against the drawing: the parts at the drawing's own
/// coordinates (or moved by the operator's `--sheet-origin`).
fn dxf_acceptance(name: &str, profile: &str, sheet_origin: Option<P>) {
    let path = repo(&format!("tests/data/sheet/{name}"));
    let profile = repo(&format!("config/machines/{profile}.yaml"));
    let params = cut_params(&profile);
    let mut extra = Vec::new();
    let origin_arg;
    if let Some(o) = sheet_origin {
        origin_arg = format!("{},{}", o[0], o[1]);
        extra = vec!["--sheet-origin", origin_arg.as_str()];
    }
    let run = cell_sheet(&path, &profile, &extra);
    let reference = dxf_reference(&path, sheet_origin);
    // The drawing's points, moved as the operator moved the sheet's corner.
    let corner = dxf_layout(&path).origin;
    let shift = sheet_origin.map_or([0.0, 0.0], |o| [o[0] - corner[0], o[1] - corner[1]]);
    let text = std::fs::read_to_string(&path).unwrap();
    let drawing: Vec<(P, String)> = dxf_drawing_points(&text, "SHEET")
        .into_iter()
        .map(|(p, w)| ([p[0] + shift[0], p[1] + shift[1]], w))
        .collect();
    assert!(!drawing.is_empty(), "{name}: no drawing points read");
    let from = run.report["sheet"]["origin_from"].as_str().unwrap_or("");
    assert_eq!(
        from,
        if sheet_origin.is_some() {
            "operator"
        } else {
            "drawing"
        },
        "{name}: {}",
        run.report["sheet"]
    );
    accept(name, &reference, &run, &params, &drawing);
}

#[test]
fn dxf_with_a_sheet_outline() {
    dxf_acceptance("small.dxf", "linuxcnc-plasma", None);
    // Its sheet sits at (100, 200) in the drawing: the parts reach X 3090 mm.
    dxf_acceptance("margin_sheet_layer.dxf", "linuxcnc-plasma-4020", None);
}

#[test]
fn dxf_with_limits_and_no_sheet_outline() {
    dxf_acceptance("margin_limits.dxf", "linuxcnc-plasma-3015", None);
}

#[test]
fn dxf_with_a_10_mm_margin_and_no_header_is_cut_in_place() {
    dxf_acceptance("margin_no_header.dxf", "linuxcnc-plasma-3015", None);
}

#[test]
fn dxf_placed_on_the_machine_by_the_operator() {
    dxf_acceptance(
        "margin_no_header.dxf",
        "linuxcnc-plasma-3015",
        Some([30.0, 20.0]),
    );
}

/// The plasma profile with LinuxCNC's cutter compensation instead of the offset path, written
/// into `dir`.
fn controller_profile(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(repo("config/machines/linuxcnc-plasma.yaml")).unwrap();
    assert!(text.contains("compensation: geometric"), "{text}");
    let profile = dir.join("linuxcnc-plasma-g41.yaml");
    std::fs::write(
        &profile,
        text.replace("compensation: geometric", "compensation: controller"),
    )
    .unwrap();
    profile
}

#[test]
fn controller_compensation_refuses_a_hole_with_no_room_for_its_lead() {
    // In the plate, a hole holding a nested disc leaves no lead-in a kerf off the part and
    // 1.5 kerfs clear of the disc (the controller shifts the programmed lead by half a kerf):
    // one error naming the hole, nothing written.
    let dir = tempfile::tempdir().unwrap();
    let profile = controller_profile(dir.path());
    let out = dir.path().join("out");
    let run = std::process::Command::new(CELL)
        .arg("sheet")
        .arg("--layout")
        .arg(repo("tests/data/sheet/plate_holes_nest.json"))
        .arg("--out")
        .arg(&out)
        .arg("--profile")
        .arg(&profile)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(65), "{stderr}");
    assert!(
        stderr.contains("holes[4]") && stderr.contains("no lead-in"),
        "{stderr}"
    );
    assert!(!out.join("program.ngc").exists());
}

#[test]
fn controller_compensation_on_the_example_layout() {
    let dir = tempfile::tempdir().unwrap();
    let profile = controller_profile(dir.path());
    let params = cut_params(&profile);
    assert!(params.controller_compensation);
    let layout = repo("tests/data/sheet/example.json");
    let reference =
        Reference::from_layout_json(&std::fs::read_to_string(&layout).unwrap()).unwrap();
    let run = cell_sheet(&layout, &profile, &[]);
    // The program selects a tool whose diameter in the table beside it is the kerf.
    let program = read(&run.program).unwrap();
    assert!(program.compensation_used, "no G41/G42 in the program");
    let tools: Vec<f64> = program.t_words.clone();
    assert!(!tools.is_empty(), "no tool selected for the compensation");
    let table = std::fs::read_to_string(run.out.join("tool.tbl"))
        .unwrap_or_else(|e| panic!("tool.tbl beside program.ngc: {e}"));
    let diameter = table
        .lines()
        .map(|l| {
            l.split(';')
                .next()
                .unwrap_or("")
                .split_whitespace()
                .collect::<Vec<_>>()
        })
        .find(|words| {
            words
                .iter()
                .any(|w| w.strip_prefix('T').and_then(|t| t.parse::<f64>().ok()) == Some(tools[0]))
        })
        .and_then(|words| {
            words
                .iter()
                .find_map(|w| w.strip_prefix('D').and_then(|d| d.parse::<f64>().ok()))
        })
        .unwrap_or_else(|| panic!("tool T{} has no diameter in tool.tbl:\n{table}", tools[0]));
    assert!(
        (diameter - params.kerf_mm).abs() < 1e-3,
        "tool diameter {diameter} mm, kerf {} mm",
        params.kerf_mm
    );
    accept(
        "plate_holes_nest.json, controller compensation",
        &reference,
        &run,
        &params,
        &[],
    );
}
