//! Programs the emitter writes, run through LinuxCNC's real RS274NGC interpreter
//! (`tests/interp/canon.py`, Debian's `linuxcnc-uspace`; CI installs it with
//! `tests/interp/install.sh`): accepted, and the interpreter's canonical moves land on the
//! toolpath's points with the toolpath's timing.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use cell_emitter::gcode;
use cell_msgs::Toolpath;
use cell_planner::job::{plan, AirfoilSource, HotwireJob, TipSection};
use cell_planner::pso::PsoConfig;
use cell_planner::wing::Placement;
use cell_profiles::MachineProfile;
use serde_json::Value;

fn canon_py() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/interp/canon.py")
}

/// Runs the interpreter harness: (exit code, its JSON).
fn interpret(text: &str, axes: &str) -> (i32, Value) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("program.ngc");
    std::fs::write(&file, text).unwrap();
    let out = std::process::Command::new("python3")
        .arg(canon_py())
        .arg(&file)
        .arg(axes)
        .output()
        .expect("python3 runs");
    let code = out.status.code().unwrap_or(-1);
    assert_ne!(
        code,
        3,
        "LinuxCNC's interpreter is missing: run `bash tests/interp/install.sh` ({})",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "canon.py output is not JSON ({e}): {}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    (code, json)
}

fn job(tip: Option<TipSection>) -> HotwireJob {
    HotwireJob {
        root_airfoil: AirfoilSource::parse("s1223"),
        chord_mm: 180.0,
        tip,
        span_mm: 400.0,
        panels: 40,
        pso: PsoConfig {
            particles: 4,
            iterations: 10,
            ..PsoConfig::default()
        },
        ..HotwireJob::default()
    }
}

/// The distinct (x, y, u, v, duration s, feed mm/s) the program should move through after its
/// first point, rounded as written (3 decimals).
fn expected_moves(tp: &Toolpath) -> Vec<[f64; 6]> {
    let r = |v: f64| (v * 1000.0).round() / 1000.0;
    let mut out: Vec<[f64; 6]> = Vec::new();
    let mut at: Option<[f64; 4]> = None;
    for seg in &tp.segments {
        for (k, p) in seg.points.iter().enumerate() {
            let s = seg.secondary_points.get(k).copied().unwrap_or(*p);
            let here = [r(p.x), r(p.y), r(s.x), r(s.y)];
            match at {
                None => at = Some(here),
                Some(prev) if prev == here => {}
                Some(prev) => {
                    let dp = ((p.x - prev[0]).powi(2) + (p.y - prev[1]).powi(2)).sqrt();
                    let ds = ((s.x - prev[2]).powi(2) + (s.y - prev[3]).powi(2)).sqrt();
                    let feed = f64::from(seg.feed_mm_s[k]);
                    let duration = dp.max(ds) / feed;
                    out.push([here[0], here[1], here[2], here[3], duration, feed]);
                    at = Some(here);
                }
            }
        }
    }
    out
}

fn check_against_toolpath(tp: &Toolpath, json: &Value, four_axis: bool) {
    let moves: Vec<&Value> = json["moves"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["kind"] == "feed")
        .collect();
    let expected = expected_moves(tp);
    assert_eq!(moves.len(), expected.len(), "one G1 per distinct point");
    for (k, (m, e)) in moves.iter().zip(&expected).enumerate() {
        let got = |axis: &str| m[axis].as_f64().unwrap();
        let (gu, gv) = if four_axis {
            (got("u"), got("v"))
        } else {
            (got("x"), got("y"))
        };
        for (g, want) in [(got("x"), e[0]), (got("y"), e[1]), (gu, e[2]), (gv, e[3])] {
            assert!((g - want).abs() < 1e-6, "move {k}: {g} vs {want}");
        }
        // The interpreter's duration of each move is the toolpath's (both carriages together),
        // up to the coordinates' rounding to 0.001 mm (which matters on the shortest moves).
        let d = m["duration_s"].as_f64().unwrap();
        let tolerance = 2e-3 * e[4] + 0.0015 / e[5];
        assert!(
            (d - e[4]).abs() <= tolerance,
            "move {k}: {d} s vs {} s",
            e[4]
        );
    }
}

#[test]
fn tapered_panel_on_linuxcnc_xyuv_is_accepted_with_its_points_and_timing() {
    let tip = TipSection {
        airfoil: AirfoilSource::parse("e387"),
        chord_mm: 120.0,
        placement: Placement {
            sweep_mm: 40.0,
            twist_deg: -2.0,
            pivot_chord_fraction: 0.25,
        },
    };
    let planned = plan(&job(Some(tip)), |_| ControlFlow::Continue(())).unwrap();
    let tp = planned.to_toolpath("panel-1");
    let profile = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
    let text = gcode::emit(&tp, &profile, "panel-1").unwrap();
    let (code, json) = interpret(&text, "XYUV");
    assert_eq!(code, 0, "{}", json["error"]);
    assert_eq!(json["ok"], true);
    check_against_toolpath(&tp, &json, true);
    // Inverse time throughout, the wire heated before the first cut move, then switched off.
    assert!(json["moves"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["kind"] == "feed")
        .all(|m| m["feed_mode"] == "inverse_time"));
    assert_eq!(json["dwells"][0]["seconds"], 2.0);
    let spindle = json["spindle"].as_array().unwrap();
    assert_eq!(spindle.first().unwrap()["state"], "cw");
    assert_eq!(spindle.last().unwrap()["state"], "off");

    // The harness is a real check: drop the F word of the first G1 and the interpreter refuses
    // the program at that line (G93 needs F on every feed move).
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let first_g1 = lines.iter().position(|l| l.starts_with("G1 ")).unwrap();
    lines[first_g1] = lines[first_g1]
        .split(' ')
        .filter(|w| !w.starts_with('F'))
        .collect::<Vec<_>>()
        .join(" ");
    let broken = lines.join("\n") + "\n";
    let cut_f = first_g1 + 1;
    let (code, json) = interpret(&broken, "XYUV");
    assert_eq!(code, 1);
    assert_eq!(json["error"]["line"], cut_f as u64, "{}", json["error"]);
    assert!(
        json["error"]["message"]
            .as_str()
            .unwrap()
            .contains("F word missing"),
        "{}",
        json["error"]
    );
}

#[test]
fn straight_cut_on_grbl_xy_is_accepted_with_its_points_and_timing() {
    let planned = plan(&job(None), |_| ControlFlow::Continue(())).unwrap();
    let profile = MachineProfile::resolve("grbl-xy").unwrap();
    // Planned for the 4-axis default; a straight cut's UV equals its XY, so it fits the
    // 2-axis machine as long as it lies inside its travel.
    let tp = planned.to_toolpath("straight-1");
    let text = gcode::emit(&tp, &profile, "straight-1").unwrap();
    assert!(!text.contains(" U") && !text.contains("G93"));
    let (code, json) = interpret(&text, "XYZ");
    assert_eq!(code, 0, "{}", json["error"]);
    check_against_toolpath(&tp, &json, false);
    assert!(json["moves"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["kind"] == "feed")
        .all(|m| m["feed_mode"] == "units_per_minute"));
}
