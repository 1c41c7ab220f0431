//! Controller cutter compensation (`cutting.compensation: controller`, LinuxCNC): the program
//! selects the kerf tool, switches `G41`/`G42` on at each contour's entry move and `G40` after
//! its lead-out, with the tool table beside it; and LinuxCNC's own interpreter, given that tool
//! table, moves the torch half a kerf off every contour on its scrap side.

mod common;

use cell_emitter::{compensation, emit_program_with, gcode, EmitError, EmitOptions};
use cell_msgs::{Toolpath, ToolpathSegment};
use cell_profiles::{MachineProfile, MaterialRef};

/// An embedded profile with controller compensation instead of its geometric one.
fn controller(name: &str) -> MachineProfile {
    let text = cell_profiles::EMBEDDED_PROFILES
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap()
        .1
        .replace("compensation: geometric", "compensation: controller");
    MachineProfile::from_yaml_str(&text, &format!("{name}-g41.yaml")).unwrap()
}

/// The program text and the tool table of `tp` on `profile`.
fn emit(tp: &Toolpath, profile: &MachineProfile, options: &EmitOptions) -> (String, String) {
    let program = emit_program_with(tp, profile, "plate", options).unwrap();
    let names: Vec<&str> = program.files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["plate.ngc", compensation::TOOL_TABLE_FILE]);
    (program.files[0].text.clone(), program.files[1].text.clone())
}

/// `tp` mirrored about x = 75: every contour runs the other way round.
fn mirrored(tp: &Toolpath) -> Toolpath {
    let mut m = tp.clone();
    for s in &mut m.segments {
        for p in &mut s.points {
            p.x = 150.0 - p.x;
        }
    }
    m
}

/// The lines of `text` that switch compensation, with the line before each `G40`.
fn switches(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        if l.starts_with("G41") || l.starts_with("G42") {
            out.push(l.split(" X").next().unwrap().to_string());
        } else if *l == "G40" {
            out.push(format!("G40 after {}", lines[i - 1]));
        }
    }
    out
}

#[test]
fn the_kerf_tool_is_selected_and_each_contour_switched_on_at_its_entry() {
    let profile = controller("linuxcnc-plasma");
    let (text, table) = emit(
        &common::sheet_part_with_leads(),
        &profile,
        &EmitOptions::default(),
    );
    // The profile's default material, mild steel 6 mm: kerf 1.5 mm as tool 1's diameter.
    assert!(table.starts_with("T1 P1 D1.5000 ;"), "{table}");
    let lines: Vec<&str> = text.lines().collect();
    let tool = lines.iter().position(|l| *l == "T1 M6").unwrap();
    let start = lines.iter().position(|l| *l == "G64 P0.05").unwrap();
    assert!(start < tool, "{text}");
    assert!(
        lines[tool - 1].contains("tool 1, diameter 1.500 mm = the kerf"),
        "{text}"
    );
    let first_move = lines.iter().position(|l| l.starts_with("G0 X")).unwrap();
    assert!(tool < first_move);
    // The hole (counter-clockwise, scrap inside) on the left, entered on its lead-in arc; the
    // outline (counter-clockwise, scrap outside) on the right, entered on its lead-in line;
    // each switched off after its lead-out, before the arc goes off.
    assert_eq!(
        switches(&text),
        [
            "G41 G3",
            "G40 after G3 X68.000 Y52.000 I-2.000 J0.000",
            "G42 G1",
            "G40 after G2 X52.000 Y23.000 I0.000 J-2.000",
        ],
        "{text}"
    );
    assert!(text.contains("G42 G1 X50.000 Y25.000\n"), "{text}");
    assert_eq!(text.matches("G40\nM5\n").count(), 2, "{text}");
    // Mirrored, both contours run clockwise: the sides swap.
    let (text, _) = emit(
        &mirrored(&common::sheet_part_with_leads()),
        &profile,
        &EmitOptions::default(),
    );
    let words: Vec<String> = switches(&text)
        .into_iter()
        .filter(|s| !s.starts_with("G40"))
        .collect();
    assert_eq!(words, ["G42 G2", "G41 G1"], "{text}");
}

#[test]
fn a_contour_without_a_lead_in_is_named() {
    // The pierce on the contour: the controller's entry move would end in the part.
    let e = gcode::emit(
        &common::sheet_part(),
        &controller("linuxcnc-plasma"),
        "plate",
    )
    .unwrap_err();
    assert_eq!(e, EmitError::NoLeadIn { segment: 1 });
    assert!(e.to_string().starts_with("segment 1: "), "{e}");
}

#[test]
fn the_job_material_picks_the_kerf_and_a_missing_one_is_named() {
    let profile = controller("linuxcnc-plasma-3015");
    let tp = common::sheet_part_with_leads();
    let material = |name: &str, t: f64| EmitOptions {
        material: Some(MaterialRef {
            material: name.into(),
            thickness_mm: t,
        }),
    };
    let (text, table) = emit(&tp, &profile, &material("stainless_steel", 6.0));
    assert!(table.starts_with("T1 P1 D1.6000 ;"), "{table}");
    assert!(text.contains("diameter 1.600 mm = the kerf"), "{text}");
    // Aluminium 5 mm: between 4 mm (1.1) and 6 mm (1.0).
    let (_, table) = emit(&tp, &profile, &material("aluminium", 5.0));
    assert!(table.starts_with("T1 P1 D1.0500 ;"), "{table}");
    let e = emit_program_with(&tp, &profile, "plate", &material("copper", 6.0)).unwrap_err();
    assert!(matches!(e, EmitError::Kerf { .. }), "{e}");
    assert!(
        e.to_string().contains("\"copper\"") && e.to_string().contains("mild_steel"),
        "{e}"
    );
    // No material in the job and none by default.
    let text = cell_profiles::EMBEDDED_PROFILES
        .iter()
        .find(|(n, _)| *n == "linuxcnc-plasma-3015")
        .unwrap()
        .1
        .replace("compensation: geometric", "compensation: controller")
        .replace(
            "  default_material: {material: mild_steel, thickness_mm: 6.0}\n",
            "",
        );
    let bare = MachineProfile::from_yaml_str(&text, "bare.yaml").unwrap();
    let e = gcode::emit(&tp, &bare, "plate").unwrap_err();
    assert_eq!(
        e.to_string(),
        "machine profile \"linuxcnc-plasma-3015\": controller compensation: no material: give \
         the job's, or set cutting.default_material in the profile"
    );
}

#[test]
fn geometric_profiles_write_no_compensation() {
    for name in [
        "linuxcnc-plasma",
        "linuxcnc-plasma-3015",
        "linuxcnc-laser-3015",
    ] {
        let profile = MachineProfile::resolve(name).unwrap();
        let tp = common::sheet_part_with_leads();
        let program = emit_program_with(&tp, &profile, "plate", &EmitOptions::default()).unwrap();
        assert_eq!(program.files.len(), 1, "{name}");
        let text = &program.files[0].text;
        assert_eq!(text, &gcode::emit(&tp, &profile, "plate").unwrap());
        assert!(
            !text.contains("G41") && !text.contains("G42") && !text.contains("M6"),
            "{name}"
        );
    }
    // Nor does a controller profile on a toolpath that is not sheet cutting.
    let mut tp = common::sheet_part_with_leads();
    tp.process = Toolpath::PROCESS_HOTWIRE;
    let text = gcode::emit(&tp, &controller("linuxcnc-plasma"), "plate").unwrap();
    assert!(!text.contains("G41") && !text.contains("T1"), "{text}");
}

#[test]
fn a_contour_with_no_move_long_enough_to_enter_on_is_named() {
    let tp = Toolpath {
        job_id: "plate".into(),
        process: Toolpath::PROCESS_SHEET_CUT,
        segments: vec![
            common::segment(
                ToolpathSegment::KIND_TRAVEL,
                &[[69.4, 50.0, 0.0], [69.5, 50.0, 0.0]],
                100.0,
                0.0,
            ),
            common::segment(
                ToolpathSegment::KIND_LEAD,
                &[[69.5, 50.0, 0.0], [70.0, 50.0, 0.0]],
                20.0,
                80.0,
            ),
            common::segment(
                ToolpathSegment::KIND_CUT,
                &common::arc_points(60.0, 50.0, 10.0, 0.0, 0.0, 360.0, 240),
                20.0,
                80.0,
            ),
        ],
        ..Default::default()
    };
    let e = gcode::emit(&tp, &controller("linuxcnc-plasma"), "plate").unwrap_err();
    assert_eq!(
        e,
        EmitError::CompensationEntry {
            segment: 1,
            radius_mm: 0.75
        }
    );
    assert!(e.to_string().starts_with("segment 1: "), "{e}");
}

// ---- LinuxCNC's interpreter -------------------------------------------------------------

/// The tool table as the standalone `rs274` reads it: its canon is an inch machine
/// (`GET_EXTERNAL_LENGTH_UNITS` 1/25.4 in LinuxCNC's `saicanon.cc`), so tool diameters are
/// inches there, where a metric LinuxCNC reads the same file in mm.
fn for_standalone_rs274(table: &str) -> String {
    let d = table
        .split_whitespace()
        .find_map(|w| w.strip_prefix('D'))
        .and_then(|v| v.parse::<f64>().ok())
        .unwrap();
    format!("T1 P1 D{:.7}\n", d / 25.4)
}

/// The numbers in a canonical call's parentheses.
fn args(call: &str) -> Vec<f64> {
    let inner = &call[call.find('(').unwrap() + 1..call.rfind(')').unwrap()];
    inner
        .split(',')
        .map(|a| a.trim().parse().unwrap_or(f64::NAN))
        .collect()
}

/// Points every ≤ 0.05 mm along the XY moves made while the torch is on, one list per switch-on.
fn torch_paths(calls: &str) -> Vec<Vec<[f64; 2]>> {
    let (mut at, mut on) = ([0.0f64, 0.0], false);
    let mut paths: Vec<Vec<[f64; 2]>> = Vec::new();
    for call in calls.lines() {
        if call.starts_with("START_SPINDLE") {
            on = true;
            paths.push(vec![at]);
        } else if call.starts_with("STOP_SPINDLE") {
            on = false;
        } else if call.starts_with("STRAIGHT_TRAVERSE") || call.starts_with("STRAIGHT_FEED") {
            let a = args(call);
            let end = [a[0], a[1]];
            if on {
                let n = ((end[0] - at[0]).hypot(end[1] - at[1]) / 0.05)
                    .ceil()
                    .max(1.0);
                for k in 1..=n as usize {
                    let t = k as f64 / n;
                    let p = [at[0] + t * (end[0] - at[0]), at[1] + t * (end[1] - at[1])];
                    paths.last_mut().unwrap().push(p);
                }
            }
            at = end;
        } else if call.starts_with("ARC_FEED") {
            let a = args(call);
            let (end, c, rotation) = ([a[0], a[1]], [a[2], a[3]], a[4]);
            let (r0, r1) = (
                (at[0] - c[0]).hypot(at[1] - c[1]),
                (end[0] - c[0]).hypot(end[1] - c[1]),
            );
            let t0 = (at[1] - c[1]).atan2(at[0] - c[0]);
            let t1 = (end[1] - c[1]).atan2(end[0] - c[0]);
            let tau = std::f64::consts::TAU;
            let mut sweep = if rotation > 0.0 {
                (t1 - t0).rem_euclid(tau)
            } else {
                -(t0 - t1).rem_euclid(tau)
            };
            if sweep.abs() < 1e-9 {
                sweep = tau * rotation.signum();
            }
            let n = (sweep.abs() * r0.max(r1) / 0.05).ceil().max(1.0);
            for k in 1..=n as usize {
                let t = k as f64 / n;
                let (ang, r) = (t0 + t * sweep, r0 + t * (r1 - r0));
                paths
                    .last_mut()
                    .unwrap()
                    .push([c[0] + r * ang.cos(), c[1] + r * ang.sin()]);
            }
            at = end;
        }
    }
    paths
}

fn distance_to_ring(p: [f64; 2], ring: &[[f64; 2]]) -> f64 {
    ring.windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let len2 = d[0] * d[0] + d[1] * d[1];
            let t = (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0);
            (p[0] - a[0] - t * d[0]).hypot(p[1] - a[1] - t * d[1])
        })
        .fold(f64::INFINITY, f64::min)
}

fn inside(p: [f64; 2], ring: &[[f64; 2]]) -> bool {
    let mut odd = false;
    for w in ring.windows(2) {
        let (a, b) = (w[0], w[1]);
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
        {
            odd = !odd;
        }
    }
    odd
}

/// Checks the interpreter's torch path of each contour (the k-th switch-on cuts the k-th cut
/// segment of `tp`, whose scrap lies inside when `scrap_inside[k]`): never closer to the
/// contour than half the kerf, always on the scrap side, and all the way round it at half the
/// kerf, within `tolerance` (the arc fit's, plus the interpreter's 4 decimals).
fn check_offset(tp: &Toolpath, calls: &str, radius: f64, tolerance: f64, scrap_inside: &[bool]) {
    let rings: Vec<Vec<[f64; 2]>> = tp
        .segments
        .iter()
        .filter(|s| s.kind == ToolpathSegment::KIND_CUT)
        .map(|s| s.points.iter().map(|p| [p.x, p.y]).collect())
        .collect();
    let paths = torch_paths(calls);
    assert_eq!(paths.len(), rings.len(), "one switch-on per contour");
    for (k, (path, ring)) in paths.iter().zip(&rings).enumerate() {
        for &p in path {
            let d = distance_to_ring(p, ring);
            assert!(
                d >= radius - tolerance,
                "contour {k}: {p:?} is {d} mm from it"
            );
            assert_eq!(
                inside(p, ring),
                scrap_inside[k],
                "contour {k}: {p:?} off the scrap side"
            );
        }
        // All the way round: every point of the contour has the torch half a kerf away.
        for w in ring.windows(2) {
            for t in [0.0, 0.25, 0.5, 0.75] {
                let c = [
                    w[0][0] + t * (w[1][0] - w[0][0]),
                    w[0][1] + t * (w[1][1] - w[0][1]),
                ];
                let nearest = path
                    .iter()
                    .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    nearest <= radius + tolerance,
                    "contour {k}: the torch never passes {c:?} at {radius} mm ({nearest})"
                );
            }
        }
    }
}

/// The arc fit's tolerance plus 2 µm for the interpreter's 4 decimals.
fn tolerance(profile: &MachineProfile) -> f64 {
    profile
        .gcode
        .as_ref()
        .unwrap()
        .arc_tolerance_mm
        .unwrap_or(0.0)
        + 2e-3
}

#[test]
fn linuxcnc_offsets_the_torch_half_a_kerf_to_the_scrap_side() {
    if !cell_testkit::linuxcnc_interpreter_here() {
        return;
    }
    let profile = controller("linuxcnc-plasma");
    // The hole first (scrap inside), then the outline (scrap outside); either way round.
    for (what, tp) in [
        ("counter-clockwise", common::sheet_part_with_leads()),
        ("clockwise", mirrored(&common::sheet_part_with_leads())),
    ] {
        let (text, table) = emit(&tp, &profile, &EmitOptions::default());
        let (code, calls, err) = common::rs274(&text, Some(&for_standalone_rs274(&table)));
        assert_eq!(code, 0, "{what}: {err}\n{text}");
        assert_eq!(calls.matches("CHANGE_TOOL(1)").count(), 1, "{what}");
        check_offset(&tp, &calls, 0.75, tolerance(&profile), &[true, false]);
    }
    // The check is real: with G41 and G42 swapped the torch runs on the part.
    let tp = common::sheet_part_with_leads();
    let (text, table) = emit(&tp, &profile, &EmitOptions::default());
    let swapped = text
        .replace("G41 ", "G4X ")
        .replace("G42 ", "G41 ")
        .replace("G4X ", "G42 ");
    let (code, calls, _) = common::rs274(&swapped, Some(&for_standalone_rs274(&table)));
    if code == 0 {
        let caught =
            std::panic::catch_unwind(|| check_offset(&tp, &calls, 0.75, 0.022, &[true, false]));
        assert!(caught.is_err(), "swapped sides went unnoticed");
    }
    // And so is the tool table: with the kerf read as 1.5 inches the entry moves are refused.
    let (code, _, err) = common::rs274(&text, Some(&table));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("cutter compensation"), "{err}");
}

#[test]
fn every_shipped_linuxcnc_sheet_profile_runs_with_controller_compensation() {
    if !cell_testkit::linuxcnc_interpreter_here() {
        return;
    }
    for name in [
        "linuxcnc-plasma",
        "linuxcnc-plasma-3015",
        "linuxcnc-plasma-4020",
        "linuxcnc-laser-3015",
    ] {
        let profile = controller(name);
        let tp = common::sheet_part_with_leads();
        let (text, table) = emit(&tp, &profile, &EmitOptions::default());
        let kerf: f64 = table
            .split_whitespace()
            .find_map(|w| w.strip_prefix('D'))
            .unwrap()
            .parse()
            .unwrap();
        let (code, calls, err) = common::rs274(&text, Some(&for_standalone_rs274(&table)));
        assert_eq!(code, 0, "{name}: {err}");
        check_offset(&tp, &calls, kerf / 2.0, tolerance(&profile), &[true, false]);
    }
}
