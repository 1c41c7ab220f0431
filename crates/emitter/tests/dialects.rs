//! Golden programs: one small program per G-code profile, byte for byte (insta snapshots in
//! `tests/snapshots/`; review changes with `cargo insta review`), plus the properties each
//! dialect's program must have whatever the snapshot says.

mod common;

use cell_emitter::gcode;
use cell_profiles::MachineProfile;

fn program(profile: &str, tp: &cell_msgs::Toolpath) -> String {
    let profile = MachineProfile::resolve(profile).unwrap();
    gcode::emit(tp, &profile, &tp.job_id).unwrap()
}

#[test]
fn every_dialect_sample_matches_its_golden_program() {
    for (profile, tp) in common::dialect_samples() {
        insta::assert_snapshot!(profile, program(profile, &tp));
    }
}

#[test]
fn inch_units_divide_every_length_but_not_inverse_time() {
    let text = cell_profiles::EMBEDDED_PROFILES
        .iter()
        .find(|(n, _)| *n == "grbl-laser")
        .unwrap()
        .1
        .replace("decimals: 3", "decimals: 4\n  units: inch");
    let profile = MachineProfile::from_yaml_str(&text, "inch.yaml").unwrap();
    let tp = common::sheet_part();
    let inch = gcode::emit(&tp, &profile, "plate").unwrap();
    insta::assert_snapshot!("grbl-laser-inch", inch);
    assert!(inch.lines().nth(1).unwrap().contains("G20"));
    // The hole's first point, x = 70 mm, and the cut feed 1200 mm/min.
    assert!(inch.contains("G0 X2.7559 Y1.9685\n"), "{inch}");
    assert!(inch.contains(" F47.244"), "{inch}");
}

#[test]
fn each_dialect_keeps_to_its_own_words() {
    for (profile, tp) in common::dialect_samples() {
        let text = program(profile, &tp);
        let limit = gcode::max_line_length(
            MachineProfile::resolve(profile)
                .unwrap()
                .gcode
                .unwrap()
                .dialect,
        );
        assert!(text.lines().all(|l| l.len() <= limit), "{profile}");
        let marlin = profile.starts_with("marlin");
        let ends = text.ends_with("M2\n") || text.ends_with("M30\n");
        assert_eq!(ends, !marlin, "{profile}");
        assert_eq!(text.contains('('), !marlin, "{profile}: comment style");
        assert_eq!(
            text.contains("G93"),
            profile.ends_with("xyuv") || profile.ends_with("xyab")
        );
        assert_eq!(text.contains(" U"), profile.ends_with("xyuv"), "{profile}");
        assert_eq!(text.contains(" A"), profile.ends_with("xyab"), "{profile}");
        let arcs = text
            .lines()
            .filter(|l| l.starts_with("G2 ") || l.starts_with("G3 "))
            .count();
        let fitted = MachineProfile::resolve(profile)
            .unwrap()
            .gcode
            .unwrap()
            .arc_tolerance_mm
            .is_some();
        assert_eq!(arcs > 0, fitted, "{profile}: {arcs} arcs");
    }
}

#[test]
fn sheet_cuts_are_pierced_once_per_contour_and_travel_is_unpowered() {
    for profile in ["grbl-laser", "linuxcnc-plasma"] {
        let text = program(profile, &common::sheet_part());
        let on = if profile == "grbl-laser" {
            "M4 S800"
        } else {
            "M3 S80"
        };
        assert_eq!(
            text.matches(on).count(),
            2,
            "{profile}: one pierce per contour"
        );
        assert_eq!(text.matches("M5").count(), 2, "{profile}");
        assert_eq!(text.matches("G4 P").count(), 2, "{profile}");
        // Between a power-off and the next power-on there are only rapids.
        let mut powered = false;
        for line in text.lines() {
            if line.starts_with("M4") || line.starts_with("M3") {
                powered = true;
            } else if line == "M5" {
                powered = false;
            } else if ["G1", "G2", "G3"].contains(&line.split(' ').next().unwrap()) {
                assert!(powered, "{profile}: a feed move with the power off: {line}");
            }
        }
    }
    // Plasma: pierce high, cut low, travel safe.
    let plasma = program("linuxcnc-plasma", &common::sheet_part());
    let pierce = plasma.find("G0 Z3.800\nM3 S80\nG4 P0.500\nG1 Z1.500 F1200.000\n");
    assert!(pierce.is_some(), "{plasma}");
    assert_eq!(plasma.matches("M5\nG0 Z10.000\n").count(), 2, "{plasma}");
}

#[test]
fn extrusion_pushes_the_filament_the_flow_needs_and_retracts_around_travel() {
    for mode in ["absolute", "relative"] {
        let text = cell_profiles::EMBEDDED_PROFILES
            .iter()
            .find(|(n, _)| *n == "marlin-extruder")
            .unwrap()
            .1
            .replace("mode: absolute", &format!("mode: {mode}"));
        let profile = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap();
        let tp = common::printed_layers();
        let program = gcode::emit(&tp, &profile, "rib").unwrap();
        // Filament for the deposit: Σ flow · (length / feed) / filament area.
        let area = std::f64::consts::PI * 1.75f64.powi(2) / 4.0;
        let mut want = 0.0;
        for seg in tp
            .segments
            .iter()
            .filter(|s| s.kind == cell_msgs::ToolpathSegment::KIND_DEPOSIT)
        {
            for k in 1..seg.points.len() {
                let (a, b) = (seg.points[k - 1], seg.points[k]);
                let len = ((b.x - a.x).powi(2) + (b.y - a.y).powi(2)).sqrt();
                want += f64::from(seg.power[k]) * len / f64::from(seg.feed_mm_s[k]) / area;
            }
        }
        let e_words: Vec<f64> = program
            .lines()
            .filter_map(|l| l.split(' ').find(|w| w.starts_with('E')))
            .map(|w| w[1..].parse().unwrap())
            .collect();
        let pushed = if mode == "relative" {
            e_words.iter().sum::<f64>()
        } else {
            *e_words.last().unwrap()
        };
        // Arcs are a hair longer than the chords they replace; rounding to 1e-5 per move.
        assert!(
            (pushed - want).abs() < 2e-3 * want,
            "{mode}: {pushed} vs {want}"
        );
        // One retract before the travel between layers, one prime after it, each 0.8 mm.
        let retracts = program
            .lines()
            .filter(|l| l.starts_with("G1 E") && l.ends_with("F2100.000"))
            .count();
        assert_eq!(retracts, 2, "{mode}:\n{program}");
        // The shipped profile lifts only over beads of the layer: the climb to layer 2
        // crosses none, so no Z-hop (a profile that lifts for every travel does).
        assert!(!program.contains("G0 Z"), "{mode}:\n{program}");
        let always = text.replace(
            "z_hop_only_when_crossing: true",
            "z_hop_only_when_crossing: false",
        );
        let always = MachineProfile::from_yaml_str(&always, "m.yaml").unwrap();
        let lifted = gcode::emit(&tp, &always, "rib").unwrap();
        assert!(lifted.contains("G0 Z0.600"), "Z-hop above layer 1");
        // Marlin's G0 runs at the modal feed: every G0 must find the travel's 120 mm/s in
        // force, not the last retract's or deposit's.
        let mut modal_f = None;
        for line in program.lines() {
            if let Some(f) = line.split(' ').find_map(|w| w.strip_prefix('F')) {
                modal_f = Some(f.parse::<f64>().unwrap());
            }
            if line.starts_with("G0 ") {
                assert_eq!(modal_f, Some(120.0 * 60.0), "{mode}: {line}\n{program}");
            }
        }
        assert!(program.contains("M83") == (mode == "relative"));
    }
}

/// Z-hop only over printed parts (`z_hop_only_when_crossing`): in a square skin with spars,
/// the travel from one spar's end to the next lifts only where it crosses a spar already
/// printed in its layer; beads of the layer below do not count.
#[test]
fn extrusion_lifts_only_for_travel_over_beads_of_the_layer() {
    use cell_msgs::ToolpathSegment as S;
    let on = |layer: u32, kind: u8, pts: &[[f64; 2]]| {
        let z = 0.2 * f64::from(layer + 1);
        let pts: Vec<[f64; 3]> = pts.iter().map(|q| [q[0], q[1], z]).collect();
        let power = if kind == S::KIND_DEPOSIT { 2.7 } else { 0.0 };
        S {
            layer,
            ..common::segment(kind, &pts, 30.0, power)
        }
    };
    let (d, t) = (S::KIND_DEPOSIT, S::KIND_TRAVEL);
    let skin = [
        [100.0, 100.0],
        [110.0, 100.0],
        [110.0, 110.0],
        [100.0, 110.0],
        [100.0, 100.0],
    ];
    let tp = cell_msgs::Toolpath {
        job_id: "hops".into(),
        process: cell_msgs::Toolpath::PROCESS_EXTRUSION,
        power_unit: cell_msgs::Toolpath::POWER_EXTRUSION_MM3_S,
        segments: vec![
            on(0, t, &[[0.0, 0.0], [100.0, 100.0]]),
            on(0, d, &skin),
            on(0, t, &[[100.0, 100.0], [105.0, 101.0]]),
            on(0, d, &[[105.0, 101.0], [105.0, 109.0]]),
            // Leaves the spar's end, crosses nothing.
            on(0, t, &[[105.0, 109.0], [108.0, 109.0]]),
            on(0, d, &[[108.0, 109.0], [108.0, 101.0]]),
            // Crosses the spar at x = 105: lifted.
            on(0, t, &[[108.0, 101.0], [102.0, 105.0]]),
            on(0, d, &[[102.0, 105.0], [102.0, 109.0]]),
            // Up a layer, then across the layer below's spars: not lifted.
            on(1, t, &[[102.0, 109.0], [101.0, 101.0]]),
            on(1, d, &[[101.0, 101.0], [101.0, 102.0]]),
            on(1, t, &[[101.0, 102.0], [109.0, 105.0]]),
            on(1, d, &[[109.0, 105.0], [109.0, 106.0]]),
        ],
        ..Default::default()
    };
    let shipped = MachineProfile::resolve("marlin-extruder").unwrap();
    let program = gcode::emit(&tp, &shipped, "hops").unwrap();
    let lines: Vec<&str> = program.lines().collect();
    let hops: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].starts_with("G0 Z"))
        .collect();
    assert_eq!(hops.len(), 2, "one lift and its lower:\n{program}");
    assert!(
        lines[hops[0] + 1].starts_with("G0 X102.000 Y105.000"),
        "{program}"
    );
    // Every travel still retracts and primes.
    let retracts = lines.iter().filter(|l| l.starts_with("G1 E")).count();
    assert_eq!(retracts, 2 * 5, "{program}");
    let mut always = shipped.clone();
    if let Some(e) = always.gcode.as_mut().and_then(|g| g.extrusion.as_mut()) {
        e.z_hop_only_when_crossing = false;
    }
    let every = gcode::emit(&tp, &always, "hops").unwrap();
    assert_eq!(
        every.lines().filter(|l| l.starts_with("G0 Z")).count(),
        2 * 5
    );
}

#[test]
fn a_hostile_job_id_cannot_add_a_command_in_any_dialect() {
    let hostile = "x)\nM3 S9999 (\r; G0 X0 %\n{profile}";
    for (name, tp) in common::dialect_samples() {
        let profile = MachineProfile::resolve(name).unwrap();
        let clean = gcode::emit(&tp, &profile, "x").unwrap();
        let text = gcode::emit(&tp, &profile, hostile).unwrap();
        assert_eq!(text.lines().count(), clean.lines().count(), "{name}");
        assert!(
            !text.contains("S9999\n") && !text.contains('%'),
            "{name}: {text}"
        );
        // Only the comment and the {job} templates differ.
        for (a, b) in text.lines().zip(clean.lines()) {
            if a != b {
                assert!(
                    a.starts_with('(') || a.starts_with(';') || a.starts_with("M117"),
                    "{name}: {a}"
                );
            }
        }
    }
}

/// The sample toolpaths in `tests/data/toolpaths/` (the README's `cell emit` examples) are these
/// fixtures; `UPDATE_SAMPLES=1 cargo test -p cell_emitter --test dialects` rewrites them.
#[test]
fn sample_toolpath_files_are_the_fixtures() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/toolpaths");
    for (file, tp) in [
        ("panel.json", common::hotwire_panel()),
        ("straight.json", common::hotwire_straight()),
        ("plate.json", common::sheet_part()),
        ("rib.json", common::printed_layers()),
        ("wall.json", common::waam_wall()),
    ] {
        let json = serde_json::to_string_pretty(&tp).unwrap() + "\n";
        let path = dir.join(file);
        if std::env::var_os("UPDATE_SAMPLES").is_some() {
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(&path, &json).unwrap();
        }
        let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            on_disk == json,
            "{file} differs from its fixture: rerun with UPDATE_SAMPLES=1"
        );
        // Read back (serde_json may differ in the last bit of a float): the same points to 1e-9.
        let back: cell_msgs::Toolpath = cell_msgs::json::from_str(&on_disk).unwrap();
        let flat = |t: &cell_msgs::Toolpath| -> Vec<f64> {
            t.segments
                .iter()
                .flat_map(|s| s.points.iter().flat_map(|p| [p.x, p.y, p.z]))
                .collect()
        };
        let (a, b) = (flat(&back), flat(&tp));
        assert_eq!(a.len(), b.len(), "{file}");
        assert!(
            a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-9),
            "{file}"
        );
    }
    // The robot sample emits for the WAAM cell (the RW7 robot works in its base frame).
    let robot = MachineProfile::resolve("abb-irb2600-waam").unwrap();
    let program = cell_emitter::emit_program(&common::waam_wall(), &robot, "wall").unwrap();
    let names: Vec<&str> = program.files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["WAAM_wall.mod", "WAAM_wall.pgf"]);
}

#[test]
fn marlin_programs_are_gcode_files_and_cnc_programs_ngc() {
    // Marlin's SD card lists only `.gcode`, `.gco` and `.g` files.
    for (name, tp) in common::dialect_samples() {
        let profile = MachineProfile::resolve(name).unwrap();
        let program = cell_emitter::emit_program(&tp, &profile, "part").unwrap();
        let want = if program.dialect == "marlin" {
            "part.gcode"
        } else {
            "part.ngc"
        };
        assert_eq!(program.files[0].name, want, "{name}");
    }
}
