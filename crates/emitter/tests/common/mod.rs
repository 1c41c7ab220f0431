//! Small toolpaths, one per process, shared by the golden-file and interpreter tests.

#![allow(dead_code)]

use cell_msgs::geometry_msgs::Point;
use cell_msgs::{Toolpath, ToolpathSegment};

/// A segment of `kind` through `points` (x, y, z) at one feed and power.
pub fn segment(kind: u8, points: &[[f64; 3]], feed_mm_s: f32, power: f32) -> ToolpathSegment {
    ToolpathSegment {
        kind,
        points: points.iter().map(|&[x, y, z]| Point { x, y, z }).collect(),
        feed_mm_s: vec![feed_mm_s; points.len()],
        power: vec![power; points.len()],
        ..Default::default()
    }
}

/// Points on a circle about (cx, cy) at height z, from `from_deg` to `to_deg` in `n` steps.
pub fn arc_points(
    cx: f64,
    cy: f64,
    r: f64,
    z: f64,
    from_deg: f64,
    to_deg: f64,
    n: usize,
) -> Vec<[f64; 3]> {
    (0..=n)
        .map(|k| {
            let t = (from_deg + (to_deg - from_deg) * k as f64 / n as f64).to_radians();
            [cx + r * t.cos(), cy + r * t.sin(), z]
        })
        .collect()
}

/// A 4-axis hot-wire cut: lead-in, a tapered wedge (root 60 mm, tip 40 mm, the tip's points
/// on the second carriage), lead-out. Wire current 3 A, then 2.8 A on the slower return.
pub fn hotwire_panel() -> Toolpath {
    let root = [
        [130.0, 60.0],
        [120.0, 60.0],
        [60.0, 66.0],
        [60.0, 54.0],
        [120.0, 60.0],
        [130.0, 60.0],
    ];
    let tip = [
        [130.0, 60.0],
        [120.0, 60.0],
        [80.0, 64.0],
        [80.0, 56.0],
        [120.0, 60.0],
        [130.0, 60.0],
    ];
    let kinds = [
        (ToolpathSegment::KIND_LEAD, 0..2, 6.0, 3.0),
        (ToolpathSegment::KIND_CUT, 1..5, 5.0, 3.0),
        (ToolpathSegment::KIND_LEAD, 4..6, 6.0, 2.8),
    ];
    let segments = kinds
        .into_iter()
        .map(|(kind, range, feed, current)| {
            let mut s = segment(
                kind,
                &root[range.clone()]
                    .iter()
                    .map(|&[x, y]| [x, y, 0.0])
                    .collect::<Vec<_>>(),
                feed,
                current,
            );
            s.secondary_points = tip[range]
                .iter()
                .map(|&[x, y]| Point { x, y, z: 1000.0 })
                .collect();
            s
        })
        .collect();
    Toolpath {
        job_id: "panel".into(),
        process: Toolpath::PROCESS_HOTWIRE,
        power_unit: Toolpath::POWER_WIRE_CURRENT_A,
        plane_separation_mm: 1000.0,
        segments,
        ..Default::default()
    }
}

/// The same wedge as a straight (untapered) cut for a 2-axis cutter.
pub fn hotwire_straight() -> Toolpath {
    let mut tp = hotwire_panel();
    for s in &mut tp.segments {
        s.secondary_points.clear();
    }
    tp.plane_separation_mm = 0.0;
    tp
}

/// A sheet part: a hole (circle r = 10 at 60, 50) cut first, then the outline (a 80 x 50
/// rectangle from 20, 25 with one rounded corner, r = 8), each reached by a travel move.
/// Power 80 %, cut at 20 mm/s; points every 1.5° on the curves (sagitta < 0.01 mm).
pub fn sheet_part() -> Toolpath {
    let travel =
        |a: [f64; 3], b: [f64; 3]| segment(ToolpathSegment::KIND_TRAVEL, &[a, b], 100.0, 0.0);
    let hole = arc_points(60.0, 50.0, 10.0, 0.0, 0.0, 360.0, 240);
    let mut outline = vec![[20.0, 25.0, 0.0], [92.0, 25.0, 0.0]];
    outline.extend(arc_points(92.0, 33.0, 8.0, 0.0, -90.0, 0.0, 60));
    outline.extend([[100.0, 75.0, 0.0], [20.0, 75.0, 0.0], [20.0, 25.0, 0.0]]);
    let segments = vec![
        travel([0.0, 0.0, 0.0], hole[0]),
        segment(ToolpathSegment::KIND_CUT, &hole, 20.0, 80.0),
        travel(hole[hole.len() - 1], outline[0]),
        segment(ToolpathSegment::KIND_CUT, &outline, 20.0, 80.0),
    ];
    Toolpath {
        job_id: "plate".into(),
        process: Toolpath::PROCESS_SHEET_CUT,
        power_unit: Toolpath::POWER_LASER_PERCENT,
        segments,
        ..Default::default()
    }
}

/// The sheet part of [`sheet_part`] the way the sequencer writes it with lead-ins: each
/// contour entered along a lead-in from its scrap side and left along a tangent lead-out (a
/// quarter arc of r = 2 turning into the scrap). The hole (counter-clockwise from 70, 50) is
/// entered on a quarter arc of r = 3 from (67, 47) inside it; the outline (counter-clockwise
/// from 50, 25 on its bottom edge) on a 5 mm line from (50, 20) below it. Power 80 %,
/// 20 mm/s.
pub fn sheet_part_with_leads() -> Toolpath {
    let travel =
        |a: [f64; 3], b: [f64; 3]| segment(ToolpathSegment::KIND_TRAVEL, &[a, b], 100.0, 0.0);
    let cut = |kind: u8, pts: &[[f64; 3]]| segment(kind, pts, 20.0, 80.0);
    let hole = arc_points(60.0, 50.0, 10.0, 0.0, 0.0, 360.0, 240);
    let hole_lead_in = arc_points(67.0, 50.0, 3.0, 0.0, -90.0, 0.0, 30);
    let mut outline = vec![[50.0, 25.0, 0.0], [92.0, 25.0, 0.0]];
    outline.extend(arc_points(92.0, 33.0, 8.0, 0.0, -90.0, 0.0, 60));
    outline.extend([
        [100.0, 75.0, 0.0],
        [20.0, 75.0, 0.0],
        [20.0, 25.0, 0.0],
        [50.0, 25.0, 0.0],
    ]);
    let segments = vec![
        travel([0.0, 0.0, 0.0], hole_lead_in[0]),
        cut(ToolpathSegment::KIND_LEAD, &hole_lead_in),
        cut(ToolpathSegment::KIND_CUT, &hole),
        cut(
            ToolpathSegment::KIND_LEAD,
            &arc_points(68.0, 50.0, 2.0, 0.0, 0.0, 90.0, 20),
        ),
        travel([68.0, 52.0, 0.0], [50.0, 20.0, 0.0]),
        cut(
            ToolpathSegment::KIND_LEAD,
            &[[50.0, 20.0, 0.0], [50.0, 25.0, 0.0]],
        ),
        cut(ToolpathSegment::KIND_CUT, &outline),
        cut(
            ToolpathSegment::KIND_LEAD,
            &arc_points(50.0, 23.0, 2.0, 0.0, 90.0, 0.0, 20),
        ),
        travel([52.0, 23.0, 0.0], [0.0, 0.0, 0.0]),
    ];
    Toolpath {
        job_id: "plate".into(),
        process: Toolpath::PROCESS_SHEET_CUT,
        power_unit: Toolpath::POWER_LASER_PERCENT,
        segments,
        ..Default::default()
    }
}

/// Flow of a 0.45 x 0.2 mm bead at `feed` mm/s (mm³/s).
pub fn bead_flow(feed: f64) -> f64 {
    0.45 * 0.2 * feed
}

/// Two printed layers (z = 0.2, 0.4) of a wing-rib-like loop (a 40 x 20 mm slot with
/// round ends, r = 10), each started at a different point, with a travel between them.
pub fn printed_layers() -> Toolpath {
    let feed = 30.0;
    let flow = bead_flow(feed) as f32;
    let lap = |z: f64| {
        let mut pts = vec![[100.0, 90.0, z], [120.0, 90.0, z]];
        pts.extend(
            arc_points(120.0, 100.0, 10.0, z, -90.0, 90.0, 120)
                .into_iter()
                .skip(1),
        );
        pts.push([100.0, 110.0, z]);
        pts.extend(
            arc_points(100.0, 100.0, 10.0, z, 90.0, 270.0, 120)
                .into_iter()
                .skip(1),
        );
        pts
    };
    let first = lap(0.2);
    // The second layer starts on the far side, so the seams don't stack.
    let mut second = lap(0.4);
    let half = second.len() / 2;
    second.rotate_left(half);
    second.push(second[0]);
    second.retain({
        let mut prev: Option<[f64; 3]> = None;
        move |p| {
            let keep = prev != Some(*p);
            prev = Some(*p);
            keep
        }
    });
    let segments = vec![
        segment(
            ToolpathSegment::KIND_TRAVEL,
            &[[0.0, 0.0, 5.0], first[0]],
            120.0,
            0.0,
        ),
        segment(ToolpathSegment::KIND_DEPOSIT, &first, feed as f32, flow),
        segment(
            ToolpathSegment::KIND_TRAVEL,
            &[first[first.len() - 1], second[0]],
            120.0,
            0.0,
        ),
        segment(ToolpathSegment::KIND_DEPOSIT, &second, feed as f32, flow),
    ];
    Toolpath {
        job_id: "rib".into(),
        process: Toolpath::PROCESS_EXTRUSION,
        power_unit: Toolpath::POWER_EXTRUSION_MM3_S,
        segments,
        ..Default::default()
    }
}

/// A WAAM wall for a robot: two 120 mm beads (layers at z = 2 and 3.6 mm), the torch normal
/// straight up, 8 mm/s then 10 mm/s (one speeddata and one welddata each) at a wire feed of
/// 5.53 m/min (the power, as `cell_waam::to_msg` writes it), with an approach and a travel
/// between.
pub fn waam_wall() -> Toolpath {
    let bead = |z: f64, reverse: bool| {
        let mut pts: Vec<[f64; 3]> = (0..=4)
            .map(|k| [100.0 + 30.0 * f64::from(k), 100.0, z])
            .collect();
        if reverse {
            pts.reverse();
        }
        pts
    };
    let (first, second) = (bead(2.0, false), bead(3.6, true));
    let mut segments = vec![
        segment(
            ToolpathSegment::KIND_TRAVEL,
            &[[100.0, 100.0, 50.0], first[0]],
            100.0,
            0.0,
        ),
        segment(ToolpathSegment::KIND_DEPOSIT, &first, 8.0, 5.53),
        segment(
            ToolpathSegment::KIND_TRAVEL,
            &[first[4], [220.0, 100.0, 20.0], second[0]],
            100.0,
            0.0,
        ),
        segment(ToolpathSegment::KIND_DEPOSIT, &second, 10.0, 5.53),
    ];
    for s in &mut segments {
        s.normals = vec![
            cell_msgs::geometry_msgs::Vector3 {
                x: 0.0,
                y: 0.0,
                z: 1.0
            };
            s.points.len()
        ];
        s.layer = u32::from(s.points[0].z > 3.0);
    }
    Toolpath {
        job_id: "wall".into(),
        process: Toolpath::PROCESS_WAAM,
        power_unit: Toolpath::POWER_WIRE_FEED_M_MIN,
        segments,
        ..Default::default()
    }
}

/// The fixture for each G-code profile: (profile, toolpath).
pub fn dialect_samples() -> Vec<(&'static str, Toolpath)> {
    vec![
        ("linuxcnc-xyuv", hotwire_panel()),
        ("grbl-xyuv", hotwire_panel()),
        ("mach3-xyab", hotwire_panel()),
        ("grbl-xy", hotwire_straight()),
        ("grbl-laser", sheet_part()),
        ("linuxcnc-plasma", sheet_part()),
        ("linuxcnc-plasma-3015", sheet_part()),
        ("linuxcnc-plasma-4020", sheet_part()),
        ("linuxcnc-laser-3015", sheet_part()),
        ("marlin-extruder", printed_layers()),
    ]
}

/// Runs the standalone `rs274` (X Y Z A B C only) through `tests/interp/rs274.py
/// --moves-only` on `text`, with `tool_table` (LinuxCNC's format) when given: (exit code,
/// canonical calls, stderr).
pub fn rs274(text: &str, tool_table: Option<&str>) -> (i32, String, String) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("program.ngc");
    std::fs::write(&file, text).unwrap();
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/interp/rs274.py");
    let mut command = std::process::Command::new("python3");
    command.arg(script).arg("--moves-only");
    if let Some(table) = tool_table {
        let tbl = dir.path().join("tool.tbl");
        std::fs::write(&tbl, table).unwrap();
        command.arg("--tool-table").arg(tbl);
    }
    let out = command.arg(&file).output().expect("python3 runs");
    let code = out.status.code().unwrap_or(-1);
    assert_ne!(
        code, 3,
        "rs274 is missing: run `bash tests/interp/install.sh`"
    );
    (
        code,
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
