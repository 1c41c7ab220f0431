//! The layers as a `cell_msgs::Toolpath` for the emitter (PROCESS_EXTRUSION).
//!
//! The emitter (`cell_emitter::gcode`) turns a deposit move's `power` q \[mm³/s\] into
//! E = q·(L/feed)/(π d²/4), taking q and feed at the move's end point, and wraps every travel
//! segment in its profile's retract and Z-hop. So each deposit point carries
//! q = w·h·feed: E = w·h·L/(π d²/4), the same as [`crate::layers::moves`]. Travel segments
//! carry only the two end points; retract and Z-hop are the machine profile's business.

use cell_msgs::geometry_msgs::Point;
use cell_msgs::{Toolpath, ToolpathSegment};

use crate::layers::{BuildParams, Layer};

/// `layers` as a toolpath: one DEPOSIT segment per stroke (perimeter, spar, rib) with per-point
/// feed and power = w·h·feed \[mm³/s\], a TRAVEL segment from each stroke's end to the next
/// stroke's start, `layer` set on every segment.
pub fn toolpath(layers: &[Layer], p: &BuildParams, job_id: &str) -> Toolpath {
    let pt = |q: [f64; 3]| Point {
        x: q[0],
        y: q[1],
        z: q[2],
    };
    let mut segments = Vec::new();
    let mut last: Option<[f64; 3]> = None;
    for layer in layers {
        for s in &layer.strokes {
            let start = s.points[0];
            if let Some(from) = last.filter(|f| *f != start) {
                let v = p.travel_speed_mm_s as f32;
                segments.push(ToolpathSegment {
                    kind: ToolpathSegment::KIND_TRAVEL,
                    layer: layer.index,
                    points: vec![pt(from), pt(start)],
                    feed_mm_s: vec![v, v],
                    power: vec![0.0, 0.0],
                    ..Default::default()
                });
            }
            let n = s.points.len();
            let q = (p.extrusion_width_mm * layer.height_mm * s.feed_mm_s) as f32;
            segments.push(ToolpathSegment {
                kind: ToolpathSegment::KIND_DEPOSIT,
                layer: layer.index,
                points: s.points.iter().map(|&q| pt(q)).collect(),
                feed_mm_s: vec![s.feed_mm_s as f32; n],
                power: vec![q; n],
                ..Default::default()
            });
            last = s.points.last().copied();
        }
    }
    Toolpath {
        job_id: job_id.to_string(),
        process: Toolpath::PROCESS_EXTRUSION,
        power_unit: Toolpath::POWER_EXTRUSION_MM3_S,
        segments,
        ..Default::default()
    }
}
