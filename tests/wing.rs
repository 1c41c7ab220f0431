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
