//! Programs the emitter writes, run through LinuxCNC's real RS274NGC interpreter
//! (`tests/interp/canon.py`, Debian's `linuxcnc-uspace`; `scripts/test` installs it with
//! `tests/interp/install.sh`): accepted, and the interpreter's canonical moves land on the
//! toolpath's points with the toolpath's timing. Without the interpreter each test says so and
//! skips, except under CI, where it fails ([`cell_testkit::require_tool`]).

mod common;

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
    if !cell_testkit::linuxcnc_interpreter_here() {
        return;
    }
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
    if !cell_testkit::linuxcnc_interpreter_here() {
        return;
    }
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

/// Marlin output made readable by LinuxCNC (see `tests/interp/README.md`, dialect table): the
/// printer-only lines (temperatures, messages, E resets, homing, motor off) are dropped, E
/// words stripped (a move left without axes is dropped), `G4 S` becomes `G4 P`, and an `M2`
/// ends the program. Motion is untouched.
fn marlin_for_linuxcnc(text: &str) -> String {
    let printer_only = [
        "M82", "M83", "M84", "M104", "M109", "M140", "M190", "M117", "G28", "G92",
    ];
    let mut out = String::new();
    for line in text.lines() {
        let first = line.split(' ').next().unwrap_or_default();
        if printer_only.contains(&first) {
            continue;
        }
        let words: Vec<String> = line
            .split(' ')
            .filter(|w| !w.starts_with('E'))
            .map(|w| {
                if first == "G4" && w.starts_with('S') {
                    format!("P{}", &w[1..])
                } else {
                    w.to_string()
                }
            })
            .collect();
        let moves_an_axis = words.iter().skip(1).any(|w| !w.starts_with('F'));
        if (first == "G1" || first == "G0") && !moves_an_axis {
            continue;
        }
        out += &words.join(" ");
        out.push('\n');
    }
    out + "M2\n"
}

/// The letters (lower case, as canon.py reports them) a toolpath point is written on, and its
/// values: x, y, (z when the profile writes the point's z), then the second carriage.
fn written(
    profile: &MachineProfile,
    p: &cell_msgs::geometry_msgs::Point,
    s: &cell_msgs::geometry_msgs::Point,
) -> Vec<(String, f64)> {
    let g = profile.gcode.as_ref().unwrap();
    let w = &g.axis_words;
    let lower = |c: char| c.to_ascii_lowercase().to_string();
    let mut out = vec![(lower(w.x), p.x), (lower(w.y), p.y)];
    let heights = g.pierce.as_ref().is_some_and(|p| p.z_cut_mm.is_some());
    if let (Some(z), false) = (w.z, heights) {
        out.push((lower(z), p.z));
    }
    if let (Some(u), Some(v)) = (w.u, w.v) {
        out.push((lower(u), s.x));
        out.push((lower(v), s.y));
    }
    out
}

/// Checks that the interpreter's feed and arc moves trace the toolpath's cut and deposit
/// points in order (each point on its move within `tolerance`, every move ending on a point),
/// with the toolpath's total cutting time.
fn check_trace(tp: &Toolpath, profile: &MachineProfile, json: &Value, tolerance: f64) {
    // Expected points, consecutive repeats dropped, and the expected cutting time.
    let mut expected: Vec<Vec<(String, f64)>> = Vec::new();
    let mut seconds = 0.0;
    for seg in tp
        .segments
        .iter()
        .filter(|s| s.kind != cell_msgs::ToolpathSegment::KIND_TRAVEL)
    {
        for (k, p) in seg.points.iter().enumerate() {
            let s = seg.secondary_points.get(k).unwrap_or(p);
            let here = written(profile, p, s);
            if let Some(prev) = expected.last() {
                let dp = |i: usize| (here[i].1 - prev[i].1).powi(2);
                let primary = (dp(0) + dp(1)).sqrt();
                let secondary = if here.len() >= 4 {
                    (dp(here.len() - 2) + dp(here.len() - 1)).sqrt()
                } else {
                    0.0
                };
                if primary.max(secondary) < 1e-9 {
                    continue;
                }
                if k > 0 {
                    seconds += primary.max(secondary) / f64::from(seg.feed_mm_s[k]);
                }
            }
            expected.push(here);
        }
    }
    let value = |m: &Value, axis: &str| m[axis].as_f64().unwrap();
    let at = |m: &Value, letters: &[(String, f64)]| -> Vec<f64> {
        letters.iter().map(|(l, _)| value(m, l)).collect()
    };
    let letters = expected[0].clone();
    let planar = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    let mut k = 0;
    let mut interpreted_seconds = 0.0;
    let mut prev: Option<Vec<f64>> = None;
    for m in json["moves"].as_array().unwrap() {
        let end = at(m, &letters);
        let cutting = m["kind"] == "feed" || m["kind"] == "arc";
        if let (true, Some(start)) = (cutting, prev.as_ref()) {
            if planar(start, &end) > 1e-9 {
                interpreted_seconds += m["duration_s"].as_f64().unwrap();
                loop {
                    assert!(
                        k < expected.len(),
                        "line {}: a cutting move past the toolpath's end",
                        m["line"]
                    );
                    let want: Vec<f64> = expected[k].iter().map(|(_, v)| *v).collect();
                    k += 1;
                    if planar(&want, &end) <= 1.5e-3 {
                        break;
                    }
                    let off = if m["kind"] == "arc" {
                        let c = [
                            m["centre"]["x"].as_f64().unwrap(),
                            m["centre"]["y"].as_f64().unwrap(),
                        ];
                        ((want[0] - c[0]).hypot(want[1] - c[1]) - m["radius"].as_f64().unwrap())
                            .abs()
                    } else {
                        // Distance from the straight move, over all written axes.
                        let d: Vec<f64> = end.iter().zip(start).map(|(e, s)| e - s).collect();
                        let len2: f64 = d.iter().map(|v| v * v).sum();
                        let t = (want
                            .iter()
                            .zip(start)
                            .zip(&d)
                            .map(|((w, s), d)| (w - s) * d)
                            .sum::<f64>()
                            / len2)
                            .clamp(0.0, 1.0);
                        want.iter()
                            .zip(start)
                            .zip(&d)
                            .map(|((w, s), d)| (w - s - t * d).powi(2))
                            .sum::<f64>()
                            .sqrt()
                    };
                    assert!(
                        off <= tolerance,
                        "line {}: toolpath point {} is {off} mm off the move",
                        m["line"],
                        k - 1
                    );
                }
            }
        }
        prev = Some(end);
    }
    // The first point is where the first cutting move starts, not a move's end: it may remain.
    assert!(
        k >= expected.len() - 1,
        "{} of {} toolpath points traced",
        k,
        expected.len()
    );
    let rel = (interpreted_seconds - seconds).abs() / seconds;
    assert!(
        rel < 5e-3,
        "cutting time {interpreted_seconds} s vs {seconds} s"
    );
}

/// Machine axes for canon.py: the profile's axes without the extruder.
fn canon_axes(profile: &MachineProfile) -> String {
    let e = profile
        .gcode
        .as_ref()
        .and_then(|g| g.extrusion.as_ref())
        .map(|e| e.axis);
    profile.axes.keys().filter(|&&a| Some(a) != e).collect()
}

#[test]
fn every_dialect_sample_is_accepted_and_traces_its_toolpath() {
    if !cell_testkit::linuxcnc_interpreter_here() {
        return;
    }
    for (name, tp) in common::dialect_samples() {
        let profile = MachineProfile::resolve(name).unwrap();
        let g = profile.gcode.as_ref().unwrap();
        let mut text = gcode::emit(&tp, &profile, &tp.job_id).unwrap();
        if g.dialect == cell_profiles::Dialect::Marlin {
            // Unfiltered, LinuxCNC refuses the printer's words: the filter is needed, not decorative.
            let (code, json) = interpret(&text, &canon_axes(&profile));
            assert_eq!(code, 1, "{name}: {}", json["error"]);
            text = marlin_for_linuxcnc(&text);
        }
        let (code, json) = interpret(&text, &canon_axes(&profile));
        assert_eq!(code, 0, "{name}: {}\n{text}", json["error"]);
        let tolerance = g.arc_tolerance_mm.unwrap_or(0.0) + 2e-3;
        check_trace(&tp, &profile, &json, tolerance);
        // Power: one switch-on per pierce (sheet) or one for the whole cut (hot wire); off at the end.
        let spindle = json["spindle"].as_array().unwrap();
        let ons = spindle.iter().filter(|s| s["state"] != "off").count();
        let want_ons = match (g.power.is_some(), g.pierce.is_some()) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => tp
                .segments
                .iter()
                .filter(|s| s.kind == cell_msgs::ToolpathSegment::KIND_CUT)
                .count(),
        };
        // Changes of S while on are reported as further "on" events: count switch-ons only.
        let switch_ons = spindle
            .windows(2)
            .filter(|w| w[0]["state"] == "off" && w[1]["state"] != "off")
            .count()
            + usize::from(spindle.first().is_some_and(|s| s["state"] != "off"));
        assert!(ons >= want_ons, "{name}: {spindle:?}");
        assert_eq!(switch_ons, want_ons, "{name}: {spindle:?}");
        if want_ons > 0 {
            assert_eq!(spindle.last().unwrap()["state"], "off", "{name}");
        }
    }
}

#[test]
fn planned_panels_run_on_every_four_axis_dialect() {
    if !cell_testkit::linuxcnc_interpreter_here() {
        return;
    }
    let tip = TipSection {
        airfoil: AirfoilSource::parse("e387"),
        chord_mm: 120.0,
        placement: Placement {
            sweep_mm: 20.0,
            twist_deg: -1.0,
            pivot_chord_fraction: 0.25,
        },
    };
    for name in ["grbl-xyuv", "mach3-xyab"] {
        let mut j = job(Some(tip.clone()));
        j.machine = MachineProfile::resolve(name).unwrap();
        let planned = plan(&j, |_| ControlFlow::Continue(())).unwrap();
        let tp = planned.to_toolpath("panel-2");
        let profile = MachineProfile::resolve(name).unwrap();
        let text = gcode::emit(&tp, &profile, "panel-2").unwrap();
        let (code, json) = interpret(&text, &canon_axes(&profile));
        assert_eq!(code, 0, "{name}: {}", json["error"]);
        check_trace(&tp, &profile, &json, 2e-3);
    }
}

#[test]
fn the_trace_check_catches_a_point_the_program_misses() {
    if !cell_testkit::linuxcnc_interpreter_here() {
        return;
    }
    let profile = MachineProfile::resolve("grbl-laser").unwrap();
    let tp = common::sheet_part();
    let text = gcode::emit(&tp, &profile, "plate").unwrap();
    let (code, json) = interpret(&text, "XY");
    assert_eq!(code, 0);
    // The same program checked against a toolpath with one hole point pushed 0.05 mm out.
    let mut moved = tp.clone();
    moved.segments[1].points[100].x += 0.05;
    let caught = std::panic::catch_unwind(|| check_trace(&moved, &profile, &json, 0.012));
    assert!(
        caught.is_err(),
        "a point 0.05 mm off the program went unnoticed"
    );
    // And against a slower toolpath: the cutting time no longer matches.
    let mut slower = tp.clone();
    for s in &mut slower.segments {
        s.feed_mm_s.iter_mut().for_each(|f| *f *= 0.98);
    }
    let caught = std::panic::catch_unwind(|| check_trace(&slower, &profile, &json, 0.012));
    assert!(caught.is_err(), "a 2 % feed difference went unnoticed");
}

#[test]
fn xyzabc_programs_pass_the_standalone_rs274_too() {
    if !cell_testkit::linuxcnc_interpreter_here() {
        return;
    }
    for (name, tp) in common::dialect_samples() {
        let profile = MachineProfile::resolve(name).unwrap();
        let g = profile.gcode.as_ref().unwrap();
        let letters = [
            Some(g.axis_words.x),
            Some(g.axis_words.y),
            g.axis_words.z,
            g.axis_words.u,
            g.axis_words.v,
        ];
        if letters.iter().flatten().any(|l| !"XYZABC".contains(*l)) {
            continue; // U/V programs: canon.py only
        }
        let mut text = gcode::emit(&tp, &profile, &tp.job_id).unwrap();
        if g.dialect == cell_profiles::Dialect::Marlin {
            text = marlin_for_linuxcnc(&text);
        }
        let (code, calls, err) = common::rs274(&text, None);
        assert_eq!(code, 0, "{name}: {err}");
        // As many feed moves and arcs as the program has G1/G2/G3 lines that move an axis.
        let feeds = calls
            .lines()
            .filter(|l| l.starts_with("STRAIGHT_FEED") || l.starts_with("ARC_FEED"))
            .count();
        let written = text
            .lines()
            .filter(|l| ["G1", "G2", "G3"].contains(&l.split(' ').next().unwrap()))
            .count();
        assert_eq!(feeds, written, "{name}");
    }
    // And it is a real check: a G2 whose centre is off by 1 mm is refused.
    let profile = MachineProfile::resolve("grbl-laser").unwrap();
    let text = gcode::emit(&common::sheet_part(), &profile, "plate").unwrap();
    let broken = text.replacen(" I0.000 J8.000", " I0.000 J9.000", 1);
    assert_ne!(broken, text);
    let (code, _, err) = common::rs274(&broken, None);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("Radius to end of arc differs from radius to start"),
        "{err}"
    );
}
