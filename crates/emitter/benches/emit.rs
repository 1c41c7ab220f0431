//! Emitter throughput: points/s and program MB/s for large toolpaths, per profile, with and
//! without arc fitting.
//!
//! `cargo bench -p cell_emitter --bench emit` (plain binary: prints a table). Toolpaths:
//! - a sheet of 40 × 25 circular holes (r = 4 mm, 0.25° steps: 1440 points each) on
//!   `grbl-laser` (arcs) and on the same profile without `arc_tolerance_mm`;
//! - a 100 000-point 4-axis hot-wire sweep on `linuxcnc-xyuv` (G93).

use std::time::Instant;

use cell_msgs::geometry_msgs::Point;
use cell_msgs::{Toolpath, ToolpathSegment};
use cell_profiles::MachineProfile;

fn holes() -> Toolpath {
    let mut segments = Vec::new();
    let mut at = Point::default();
    for row in 0..25 {
        for col in 0..40 {
            let (cx, cy) = (10.0 + 14.0 * f64::from(col), 10.0 + 14.0 * f64::from(row));
            let pts: Vec<Point> = (0..=1440)
                .map(|k| {
                    let t = f64::from(k).to_radians() / 4.0;
                    Point {
                        x: cx + 4.0 * t.cos(),
                        y: cy + 4.0 * t.sin(),
                        z: 0.0,
                    }
                })
                .collect();
            segments.push(ToolpathSegment {
                kind: ToolpathSegment::KIND_TRAVEL,
                points: vec![at, pts[0]],
                feed_mm_s: vec![100.0; 2],
                power: vec![0.0; 2],
                ..Default::default()
            });
            at = pts[pts.len() - 1];
            segments.push(ToolpathSegment {
                kind: ToolpathSegment::KIND_CUT,
                feed_mm_s: vec![20.0; pts.len()],
                power: vec![80.0; pts.len()],
                points: pts,
                ..Default::default()
            });
        }
    }
    Toolpath {
        segments,
        ..Default::default()
    }
}

fn sweep() -> Toolpath {
    let n = 100_000;
    let points: Vec<Point> = (0..n)
        .map(|k| {
            let t = f64::from(k) / f64::from(n);
            Point {
                x: 100.0 + 300.0 * t,
                y: 150.0 + 80.0 * (20.0 * t).sin(),
                z: 0.0,
            }
        })
        .collect();
    let secondary = points
        .iter()
        .map(|p| Point {
            x: p.x + 20.0,
            y: p.y * 0.9,
            z: 1000.0,
        })
        .collect();
    Toolpath {
        segments: vec![ToolpathSegment {
            kind: ToolpathSegment::KIND_CUT,
            feed_mm_s: vec![5.0; n as usize],
            power: vec![3.0; n as usize],
            points,
            secondary_points: secondary,
            ..Default::default()
        }],
        ..Default::default()
    }
}

fn main() {
    let laser = MachineProfile::resolve("grbl-laser").unwrap();
    let mut no_arcs = laser.clone();
    if let Some(g) = no_arcs.gcode.as_mut() {
        g.arc_tolerance_mm = None;
    }
    let cases = [
        ("holes, grbl-laser, arcs 0.01 mm", holes(), laser),
        ("holes, grbl-laser, lines only", holes(), no_arcs),
        (
            "sweep, linuxcnc-xyuv, G93",
            sweep(),
            MachineProfile::resolve("linuxcnc-xyuv").unwrap(),
        ),
    ];
    println!(
        "{:<34} {:>9} {:>9} {:>9} {:>12} {:>8}",
        "case", "points", "lines", "ms", "points/s", "MB/s"
    );
    for (name, tp, profile) in cases {
        let points: usize = tp.segments.iter().map(|s| s.points.len()).sum();
        let mut best = f64::INFINITY;
        let mut text = String::new();
        for _ in 0..3 {
            let t = Instant::now();
            text = cell_emitter::gcode::emit(&tp, &profile, "bench").unwrap();
            best = best.min(t.elapsed().as_secs_f64());
        }
        println!(
            "{name:<34} {points:>9} {:>9} {:>9.1} {:>12.0} {:>8.1}",
            text.lines().count(),
            best * 1e3,
            points as f64 / best,
            text.len() as f64 / best / 1e6
        );
    }
}
