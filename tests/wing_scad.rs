//! The G-Wing OpenSCAD output (issue 24 item 2, seed 002 §CAD File Generation): `cell wing`
//! writes `.scad` models from the design; Debian's `openscad` renders them to STL, and the
//! solids must match the design (volume ∫A·c(y)² dy, span) and, sliced with our own slicer
//! (`cell_mesh::slice`), the G-code `cell wing` wrote for the same section, layer by layer.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use cell_mesh::{slice, Mesh, SliceParams};
use cell_wing::spec::{Wing, WingSpec};

const CELL: &str = env!("CARGO_BIN_EXE_cell");
const SPEC: &str = "config/wings/gwing-table2.yaml";
/// The section compared with its G-code: the first right-wing section (y 25 → 155 mm, the
/// largest chords of a side).
const SECTION: usize = 1;
/// Table 3's extrusion width, the spar walls' width \[mm\].
const WIDTH_MM: f64 = 0.5;
/// The Marlin profile's arc-fitting tolerance (config/machines/marlin-extruder.yaml) \[mm\].
const ARC_TOLERANCE_MM: f64 = 0.01;
/// Half the G-code's last digit (3 decimals) \[mm\].
const ROUNDING_MM: f64 = 0.0005;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn have_openscad() -> bool {
    cell_testkit::require_command("openscad", "--version", "apt-get install openscad")
}

/// Renders `part` of `scad` to an STL beside it; fails on any OpenSCAD warning or error.
fn render(scad: &Path, part: &str) -> (Mesh, Duration) {
    let stl = scad.with_extension(format!("{part}.stl"));
    let start = Instant::now();
    let run = Command::new("openscad")
        .arg("-D")
        .arg(format!("part=\"{part}\""))
        .arg("-o")
        .arg(&stl)
        .arg(scad)
        .output()
        .unwrap();
    let took = start.elapsed();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{}: {stderr}", scad.display());
    for word in ["WARNING", "ERROR", "DEPRECATED"] {
        assert!(
            !stderr.contains(word),
            "{} ({part}): {stderr}",
            scad.display()
        );
    }
    (Mesh::load_stl(&stl).unwrap(), took)
}

/// Shoelace area and centroid of a closed polygon (x, y).
fn area_centroid(points: &[[f64; 2]]) -> (f64, [f64; 2]) {
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for (p, q) in points.iter().zip(points.iter().cycle().skip(1)) {
        let cross = p[0] * q[1] - q[0] * p[1];
        a += cross;
        cx += (p[0] + q[0]) * cross;
        cy += (p[1] + q[1]) * cross;
    }
    (0.5 * a, [cx / (3.0 * a), cy / (3.0 * a)])
}

fn length(points: &[[f64; 2]]) -> f64 {
    points
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

/// The deposit strokes of a Marlin program per layer Z: each stroke the XY points of
/// consecutive extruding moves (G1/G2/G3 with X or Y and a rising E; arcs flattened to ≤ 0.05
/// mm chords, from the start point's radius about I, J to the end point).
fn gcode_strokes(text: &str) -> Vec<(f64, Vec<Vec<[f64; 2]>>)> {
    let mut layers: Vec<(f64, Vec<Vec<[f64; 2]>>)> = Vec::new();
    let (mut at, mut e, mut stroke) = ([0.0f64; 3], 0.0f64, Vec::<[f64; 2]>::new());
    let flush = |stroke: &mut Vec<[f64; 2]>, z: f64, layers: &mut Vec<(f64, Vec<_>)>| {
        if stroke.len() >= 2 {
            match layers.last_mut() {
                Some((lz, strokes)) if (*lz - z).abs() < 1e-9 => strokes.push(stroke.clone()),
                _ => layers.push((z, vec![stroke.clone()])),
            }
        }
        stroke.clear();
    };
    for line in text.lines() {
        let line = line.split(';').next().unwrap_or("");
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some(&g) = words.first() else { continue };
        if !matches!(g, "G0" | "G1" | "G2" | "G3") {
            continue;
        }
        let word = |c: char| {
            words
                .iter()
                .find_map(|w| w.strip_prefix(c))
                .map(|v| v.parse::<f64>().unwrap())
        };
        let to = [
            word('X').unwrap_or(at[0]),
            word('Y').unwrap_or(at[1]),
            word('Z').unwrap_or(at[2]),
        ];
        let new_e = word('E').unwrap_or(e);
        let deposits = g != "G0" && new_e > e && (word('X').is_some() || word('Y').is_some());
        if deposits && (to[2] - at[2]).abs() < 1e-9 {
            if stroke.is_empty() {
                stroke.push([at[0], at[1]]);
            }
            if g == "G1" {
                stroke.push([to[0], to[1]]);
            } else {
                let c = [at[0] + word('I').unwrap(), at[1] + word('J').unwrap()];
                let r = (at[0] - c[0]).hypot(at[1] - c[1]);
                let a0 = (at[1] - c[1]).atan2(at[0] - c[0]);
                let a1 = (to[1] - c[1]).atan2(to[0] - c[0]);
                let tau = std::f64::consts::TAU;
                let sweep = if g == "G3" {
                    (a1 - a0).rem_euclid(tau)
                } else {
                    -(a0 - a1).rem_euclid(tau)
                };
                let n = ((sweep.abs() * r / 0.05).ceil() as usize).max(1);
                for k in 1..n {
                    let a = a0 + sweep * k as f64 / n as f64;
                    stroke.push([c[0] + r * a.cos(), c[1] + r * a.sin()]);
                }
                stroke.push([to[0], to[1]]);
            }
        } else {
            flush(&mut stroke, at[2], &mut layers);
        }
        at = to;
        e = new_e;
    }
    flush(&mut stroke, at[2], &mut layers);
    layers
}

/// ∫A·c(y)² dy over [y0, y1]: A the unit airfoil's shoelace area, c linear between the LLT
/// stations' chords (y_j = (−½ + (j + ½)/n)·b) and held beyond them, by the midpoint rule on
/// 0.01 mm steps.
fn design_volume_mm3(wing: &Wing, y0: f64, y1: f64) -> f64 {
    let pts: Vec<[f64; 2]> = wing.airfoil.points().iter().map(|p| [p.x, p.y]).collect();
    let (area, _) = area_centroid(&pts);
    let b = wing.spec.aero.span_mm;
    let chords: Vec<f64> = wing.aero.chord_over_b.iter().map(|c| c * b).collect();
    let n = chords.len();
    let chord = |y: f64| {
        let s = ((y / b + 0.5) * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
        let i = (s.floor() as usize).min(n - 2);
        chords[i] + (chords[i + 1] - chords[i]) * (s - i as f64)
    };
    let steps = ((y1 - y0) / 0.01).ceil() as usize;
    let dy = (y1 - y0) / steps as f64;
    (0..steps)
        .map(|k| area * chord(y0 + (k as f64 + 0.5) * dy).powi(2) * dy)
        .sum()
}

#[test]
fn openscad_model_matches_the_design_and_the_gcode_layers() {
    if !have_openscad() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    let run = Command::new(CELL)
        .args(["wing", "--config"])
        .arg(repo(SPEC))
        .arg("--out")
        .arg(out)
        .args(["--sections", &SECTION.to_string()])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let section = &report["sections"][0];
    let scad = out.join(section["scad"].as_str().unwrap());
    let gcode = std::fs::read_to_string(out.join(section["program"].as_str().unwrap())).unwrap();
    let wing = Wing::design(WingSpec::load(repo(SPEC)).unwrap()).unwrap();
    let design = wing.sections[SECTION];
    let height = design.height_mm();

    // The OML: one closed solid, the section's height, the design's volume.
    let (oml, oml_time) = render(&scad, "oml");
    assert!(oml.report().is_closed_manifold(), "{:?}", oml.report());
    let (lo, hi) = oml.bbox();
    assert!(
        lo[2].abs() < 1e-4 && (hi[2] - height).abs() < 1e-4,
        "Z {} → {} for a {height} mm section",
        lo[2],
        hi[2]
    );
    let volume = oml.signed_volume_mm3();
    let expected = design_volume_mm3(&wing, design.y_bed_mm, design.y_top_mm);
    let volume_error = volume / expected - 1.0;
    assert!(
        volume_error.abs() < 1e-4,
        "OML {volume:.1} mm³, design ∫A·c² dy {expected:.1} mm³"
    );

    // Layer by layer against the G-code's perimeter (each layer's first stroke), at the
    // G-code's own layer heights (Z = h₀ + k·h; the last, at the section's top face, left out).
    let strokes = gcode_strokes(&gcode);
    assert_eq!(strokes.len() as u64, section["layers"].as_u64().unwrap());
    let (h0, h) = (
        wing.spec.build.first_layer_height_mm,
        wing.spec.build.layer_height_mm,
    );
    let planes = slice(
        &oml,
        &SliceParams {
            layer_height_mm: h,
            first_z_mm: Some(h0),
            chain_tolerance_mm: None,
        },
    )
    .unwrap();
    let (spars, spar_time) = render(&scad, "spars");
    let spar_planes = slice(
        &spars,
        &SliceParams {
            layer_height_mm: h,
            first_z_mm: Some(h0),
            chain_tolerance_mm: None,
        },
    )
    .unwrap();
    let compared = strokes.len() - 1;
    assert!(planes.layers.len() >= compared && spar_planes.layers.len() >= compared);
    let (mut worst_area, mut worst_shift, mut worst_spar) = (0.0f64, 0.0f64, 0.0f64);
    let sp = &wing.spars;
    let switches: Vec<f64> = (1..sp.y_over_b.len())
        .filter(|&j| sp.x_over_c[j].len() != sp.x_over_c[j - 1].len())
        .map(|j| 0.5 * (sp.y_over_b[j] + sp.y_over_b[j - 1]) * wing.spec.aero.span_mm)
        .collect();
    let mut ties = 0;
    for (k, (z, layer)) in strokes.iter().take(compared).enumerate() {
        let plane = &planes.layers[k];
        assert!(
            (plane.z_mm - z).abs() < 1e-6,
            "layer {k}: {} vs {z}",
            plane.z_mm
        );
        assert_eq!(plane.contours.len(), 1, "layer {k}: one OML contour");
        let (stl_area, stl_centre) = area_centroid(&plane.contours[0].points);
        let perimeter = &layer[0];
        let (g_area, g_centre) = area_centroid(perimeter);
        let g_area = g_area.abs();
        // The G-code path lies within the arc tolerance plus rounding of the design polygon,
        // so the areas differ by at most that band times the perimeter's length.
        let bound = length(perimeter) * (ARC_TOLERANCE_MM + ROUNDING_MM);
        assert!(
            (stl_area - g_area).abs() <= bound,
            "layer {k} (Z {z}): OpenSCAD {stl_area:.2} mm², G-code {g_area:.2} mm², bound {bound:.2}"
        );
        worst_area = worst_area.max((stl_area / g_area - 1.0).abs());
        let shift = (stl_centre[0] - g_centre[0]).hypot(stl_centre[1] - g_centre[1]);
        assert!(shift < 0.02, "layer {k}: centroids {shift:.4} mm apart");
        worst_shift = worst_shift.max(shift);
        if k == 0 {
            continue; // the first layer is a solid rib, not spars
        }
        // Where the spar count changes between stations the walls switch at the midpoint; a
        // layer exactly there is a tie (the G-code takes the outer station's spars, the slicer
        // the wall below the plane), so it is left out.
        let y = design.y_bed_mm + design.direction() * z;
        if switches.iter().any(|s| (s - y).abs() < 1e-6) {
            ties += 1;
            continue;
        }
        // Spars: one wall per G-code spar line, w × its length.
        let lines = &layer[1..];
        let walls = &spar_planes.layers[k];
        assert_eq!(
            walls.contours.len(),
            lines.len(),
            "layer {k} (Z {z}): spar walls vs G-code spar lines"
        );
        let wall_area: f64 = walls.contours.iter().map(|c| c.signed_area_mm2()).sum();
        let line_area: f64 = lines.iter().map(|l| WIDTH_MM * length(l)).sum();
        // Each line's two ends are rounded to 0.001 mm: w·2·rounding per line. Between
        // stations the walls are ruled (linear in y) while the G-code evaluates the skins at
        // the interpolated x/c; scad.rs splits intervals so a spar moves ≤ w per piece, which
        // keeps that difference far below 0.1 % of the length (measured: ≤ 0.06 %).
        let bound = lines.len() as f64 * WIDTH_MM * 4.0 * ROUNDING_MM + 1e-3 * line_area;
        assert!(
            (wall_area - line_area).abs() <= bound,
            "layer {k}: walls {wall_area:.3} mm², lines {line_area:.3} mm²"
        );
        worst_spar = worst_spar.max((wall_area / line_area - 1.0).abs());
    }

    assert!(ties <= 3, "{ties} layers on a spar switch");

    // The centre and left sections' build orientations (the centre's is a mirror image, the
    // left's a rotation): closed solids of the right volume and height.
    for index in [0, 2] {
        let design = wing.sections[index];
        let file = out.join(format!("section-{index}.scad"));
        std::fs::write(&file, cell_wing::scad::section_scad(&wing, index).unwrap()).unwrap();
        let (mesh, _) = render(&file, "oml");
        assert!(mesh.report().is_closed_manifold(), "section {index}");
        let (lo, hi) = mesh.bbox();
        assert!(lo[2].abs() < 1e-4 && (hi[2] - design.height_mm()).abs() < 1e-4);
        let (v, want) = (
            mesh.signed_volume_mm3(),
            design_volume_mm3(
                &wing,
                design.y_bed_mm.min(design.y_top_mm),
                design.y_bed_mm.max(design.y_top_mm),
            ),
        );
        assert!(
            (v / want - 1.0).abs() < 1e-4,
            "section {index}: {v} vs {want} mm³"
        );
        let (spars, _) = render(&file, "spars");
        assert!(
            spars.signed_volume_mm3() > 0.0,
            "section {index}: spar walls inside out"
        );
    }

    // The whole wing: its span and volume.
    let whole = out.join(report["scad"].as_str().unwrap());
    let (wing_oml, wing_time) = render(&whole, "oml");
    let (lo, hi) = wing_oml.bbox();
    let span = wing.spec.aero.span_mm;
    assert!(
        (hi[1] - lo[1] - span).abs() < 1e-3 && (hi[1] + lo[1]).abs() < 1e-3,
        "Y {} → {} for a {span} mm span",
        lo[1],
        hi[1]
    );
    let wing_volume = wing_oml.signed_volume_mm3();
    let wing_expected = design_volume_mm3(&wing, -0.5 * span, 0.5 * span);
    assert!(
        (wing_volume / wing_expected - 1.0).abs() < 1e-4,
        "wing OML {wing_volume:.0} mm³, design {wing_expected:.0} mm³"
    );
    eprintln!(
        "wing_scad: section {SECTION}: OML {volume:.1} mm³ vs design {expected:.1} mm³ \
         ({:+.2e}); {compared} layers: area ≤ {:.3} %, centroid ≤ {worst_shift:.4} mm, spars ≤ \
         {:.3} % ({ties} on a switch left out); wing {wing_volume:.0} vs {wing_expected:.0} mm³, span {:.3} mm; openscad {:.2} s \
         OML, {:.2} s spars, {:.2} s whole wing",
        volume_error,
        100.0 * worst_area,
        100.0 * worst_spar,
        hi[1] - lo[1],
        oml_time.as_secs_f64(),
        spar_time.as_secs_f64(),
        wing_time.as_secs_f64(),
    );
}
