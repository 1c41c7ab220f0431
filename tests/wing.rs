//! `cell wing` (issue 8, seed 002): the G-Wing spec of Table 2/3 designed and written as Marlin
//! programs, one per printable section, with a report whose figures match the programs.

use std::path::Path;
use std::process::Command;

const CELL: &str = env!("CARGO_BIN_EXE_cell");

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(path)
        .display()
        .to_string()
}

#[test]
fn cell_wing_writes_one_marlin_program_per_section_and_a_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("wing");
    let run = Command::new(CELL)
        .args(["wing", "--config", &repo("config/wings/gwing-table2.yaml")])
        .arg("--out")
        .arg(&out)
        .args(["--sections", "0,1", "--layers", "3"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    // The notes' worked example: a centre section and four 130 mm sections per side.
    assert_eq!(report["sections_in_design"], 9, "{report}");
    let sections = report["sections"].as_array().unwrap();
    assert_eq!(sections.len(), 2);
    assert_eq!(sections[0]["side"], "centre");
    let filament_area = std::f64::consts::PI * 1.75 * 1.75 / 4.0; // Table 3: 1.75 mm filament
    let mut mass = 0.0;
    for s in sections {
        assert_eq!(s["layers"], 3);
        let file = out.join(s["program"].as_str().unwrap());
        let gcode = std::fs::read_to_string(&file).unwrap();
        assert_eq!(
            gcode.lines().count() as u64,
            s["program_lines"].as_u64().unwrap(),
            "{}",
            file.display()
        );
        assert!(gcode.contains("M82"), "absolute extrusion");
        let volume = s["deposited_volume_mm3"].as_f64().unwrap();
        let e = cell_emitter::gcode::extruded_length_mm(&gcode);
        assert!(
            (e - volume / filament_area).abs() < 0.01 * volume / filament_area,
            "{}: E {e:.3} mm for {volume:.1} mm³",
            file.display()
        );
        // PLA, 1240 kg/m³ (Table 3).
        let m = s["mass_g"].as_f64().unwrap();
        assert!((m - volume * 1.24e-3).abs() < 1e-6 * m.max(1.0), "{s}");
        assert!(s["build_time_with_acceleration_s"].as_f64() >= s["build_time_s"].as_f64());
        // Build time three ways (Pronterface's method and Marlin's planner add acceleration
        // to Σ L/v: 3–11 % on these sections), of the moves and of the program as written.
        let t = |k: &str| {
            s["times"][k]
                .as_f64()
                .unwrap_or_else(|| panic!("times.{k}: {s}"))
        };
        for k in ["pronterface_s", "marlin_s"] {
            let over = t(k) / t("feeds_only_s") - 1.0;
            assert!(
                (0.0..0.15).contains(&over),
                "{k}: {over:.3} over Σ L/v: {s}"
            );
        }
        assert!(t("program_marlin_s") > 0.0 && t("program_pronterface_s") > 0.0);
        mass += m;
    }
    assert!((report["total_mass_g"].as_f64().unwrap() - mass).abs() < 1e-9);
}

#[test]
fn cell_wing_names_a_bad_spec_and_bad_options() {
    let dir = tempfile::tempdir().unwrap();
    let spec = std::fs::read_to_string(repo("config/wings/gwing-table2.yaml")).unwrap();
    let bad = dir.path().join("typo.yaml");
    std::fs::write(&bad, spec.replace("span_mm:", "spam_mm:")).unwrap();
    let run = |args: &[&str]| {
        let o = Command::new(CELL)
            .arg("wing")
            .args(args)
            .arg("--out")
            .arg(dir.path().join("out"))
            .output()
            .unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, stderr) = run(&["--config", bad.to_str().unwrap()]);
    assert_eq!(code, Some(65), "{stderr}");
    assert!(
        stderr.contains("typo.yaml") && stderr.contains("spam_mm"),
        "{stderr}"
    );
    let good = repo("config/wings/gwing-table2.yaml");
    let (code, stderr) = run(&["--config", &good, "--sections", "42"]);
    assert_eq!(code, Some(64), "{stderr}");
    assert!(stderr.contains("--sections 42"), "{stderr}");
    let (code, stderr) = run(&["--config", &good, "--profile", "grbl-laser"]);
    assert_eq!(code, Some(64), "{stderr}");
    assert!(stderr.contains("not an extrusion profile"), "{stderr}");
    assert!(!dir.path().join("out").join("report.json").exists());
}

/// Every design case of seed 002 Table 1 through `cell wing --spec` (issue 24): the case, the
/// solved planform and each condition, requested against achieved, on stdout and in
/// report.json; a design field no wing can meet is named with the file (exit 65).
#[test]
fn cell_wing_reports_each_design_case() {
    let dir = tempfile::tempdir().unwrap();
    for (file, case) in cell_wing::design::EXAMPLE_SPECS {
        // The two-point cases (seed 002 Table 1) meet two conditions.
        let conditions = if matches!(case, "two_lift" | "two_cl" | "lift_and_cl") {
            2
        } else {
            1
        };
        let out = dir.path().join(file);
        let run = Command::new(CELL)
            .args([
                "wing",
                "--spec",
                &repo(&format!("config/wings/{file}.yaml")),
            ])
            .arg("--out")
            .arg(&out)
            .args(["--sections", "0", "--layers", "2"])
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&run.stdout);
        assert!(
            run.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        assert!(
            stdout.starts_with(&format!("design {case} (")),
            "{file}: {stdout}"
        );
        assert_eq!(
            stdout.matches("  condition ").count(),
            conditions,
            "{stdout}"
        );
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap())
                .unwrap();
        let design = &report["design"];
        assert_eq!(design["case"], case, "{design}");
        assert!((design["aspect_ratio"].as_f64().unwrap() - 8.0).abs() < 1e-9);
        assert!(
            design["lift_slope_per_rad"].as_f64().unwrap() > 4.0,
            "{design}"
        );
        let conds = design["conditions"].as_array().unwrap();
        assert_eq!(conds.len(), conditions, "{design}");
        assert_eq!(report["c_l"], conds[0]["c_l"]);
        assert_eq!(design["delta_alpha_deg"].is_null(), conditions == 1);
        for c in conds {
            // Direct design asks for no lift; every inverse case meets its target.
            match c["target_error"].as_f64() {
                Some(e) => assert!(e < 1e-9, "{file}: {c}"),
                None => assert_eq!(case, "direct"),
            }
        }
    }
    // ℓ₂ − ℓ₁ changes sign near the tips (elliptic at 0.3, bell at 1.0): named, exit 65.
    let spec = std::fs::read_to_string(repo("config/wings/two-point-lift.yaml"))
        .unwrap()
        .replace(
            "first: {lift: bell, c_l: 0.2}",
            "first: {lift: elliptic, c_l: 0.3}",
        )
        .replace(
            "second: {lift: elliptic, c_l: 1.0}",
            "second: {lift: bell, c_l: 1.0}",
        )
        .replace("../airfoils/ag24.dat", &repo("config/airfoils/ag24.dat"));
    let bad = dir.path().join("crossing.yaml");
    std::fs::write(&bad, spec).unwrap();
    let run = Command::new(CELL)
        .args(["wing", "--spec"])
        .arg(&bad)
        .arg("--out")
        .arg(dir.path().join("bad"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(65), "{stderr}");
    assert!(
        stderr.contains("crossing.yaml: field `aero.design.second`: ℓ₂ − ℓ₁ must keep one sign"),
        "{stderr}"
    );
}
