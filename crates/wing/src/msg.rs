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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layers::{Role, Stroke};

    #[test]
    fn strokes_become_deposits_with_flow_and_travels_between() {
        let p = crate::layers::tests::params();
        let stroke = |role, x: f64, z: f64, v| Stroke {
            role,
            points: vec![[x, 0.0, z], [x + 10.0, 0.0, z]],
            feed_mm_s: v,
        };
        let layers = vec![
            Layer {
                index: 0,
                z_mm: 0.3,
                height_mm: 0.3,
                y_mm: 0.0,
                strokes: vec![stroke(Role::Rib, 0.0, 0.3, 30.0)],
            },
            Layer {
                index: 1,
                z_mm: 0.5,
                height_mm: 0.2,
                y_mm: 0.2,
                strokes: vec![
                    stroke(Role::Perimeter, 10.0, 0.5, 40.0),
                    stroke(Role::Spar, 30.0, 0.5, 40.0),
                ],
            },
        ];
        let tp = toolpath(&layers, &p, "t");
        assert_eq!(tp.process, Toolpath::PROCESS_EXTRUSION);
        assert_eq!(tp.power_unit, Toolpath::POWER_EXTRUSION_MM3_S);
        let kinds: Vec<u8> = tp.segments.iter().map(|s| s.kind).collect();
        let (d, t) = (ToolpathSegment::KIND_DEPOSIT, ToolpathSegment::KIND_TRAVEL);
        // Rib → (travel up a layer) → perimeter → (travel) → spar; the perimeter ends where
        // the travel to the spar starts.
        assert_eq!(kinds, vec![d, t, d, t, d]);
        assert_eq!(
            tp.segments.iter().map(|s| s.layer).collect::<Vec<_>>(),
            vec![0, 1, 1, 1, 1]
        );
        assert_eq!(
            tp.segments[0].power,
            vec![0.5 * 0.3 * 30.0; 2],
            "q = w·h·feed, first layer h₀"
        );
        assert_eq!(tp.segments[2].power, vec![0.5f32 * 0.2 * 40.0; 2]);
        assert_eq!(tp.segments[1].feed_mm_s, vec![80.0; 2]);
        assert_eq!(tp.segments[1].points[1].z, 0.5);
    }
}
