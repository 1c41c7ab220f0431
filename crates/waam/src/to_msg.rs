//! Planned layers as a `cell_msgs::Toolpath` (process WAAM, power unit arc on/off), for the
//! emitter. Kept apart from the planning modules, which know nothing of the message types.
//!
//! Mapping: deposit segments → `KIND_DEPOSIT`, travel → `KIND_TRAVEL`; per point `feed_mm_s` =
//! speed, `power` = 1 (arc on) or 0, `bead_width_mm` / `bead_height_mm` (0 on travel), normal
//! +Z (the surface normal of a horizontal layer; the emitter points the torch against it),
//! `layer` = the layer index. Not carried by the message: wire feed speed and the interlayer
//! dwell (read them from [`LayerToolpath`]).

use cell_msgs::geometry_msgs::{Point, Vector3};
use cell_msgs::std_msgs::Header;
use cell_msgs::{Toolpath, ToolpathSegment};

use crate::toolpath::{LayerToolpath, SegmentKind};

/// The layers as one toolpath message, segments in order.
pub fn toolpath_msg(layers: &[LayerToolpath], job_id: &str, frame_id: &str) -> Toolpath {
    let mut segments = Vec::new();
    for l in layers {
        for s in &l.segments {
            let kind = match s.kind {
                SegmentKind::Deposit => ToolpathSegment::KIND_DEPOSIT,
                SegmentKind::Travel => ToolpathSegment::KIND_TRAVEL,
            };
            let n = s.points.len();
            segments.push(ToolpathSegment {
                kind,
                layer: l.index as u32,
                points: s
                    .points
                    .iter()
                    .map(|p| Point {
                        x: p.x_mm,
                        y: p.y_mm,
                        z: p.z_mm,
                    })
                    .collect(),
                secondary_points: Vec::new(),
                normals: vec![
                    Vector3 {
                        x: 0.0,
                        y: 0.0,
                        z: 1.0
                    };
                    n
                ],
                feed_mm_s: s.points.iter().map(|p| p.speed_mm_s as f32).collect(),
                power: s
                    .points
                    .iter()
                    .map(|p| if p.arc_on { 1.0 } else { 0.0 })
                    .collect(),
                bead_width_mm: s.points.iter().map(|p| p.bead_width_mm as f32).collect(),
                bead_height_mm: s.points.iter().map(|p| p.bead_height_mm as f32).collect(),
            });
        }
    }
    Toolpath {
        header: Header {
            frame_id: frame_id.into(),
            ..Header::default()
        },
        job_id: job_id.into(),
        process: Toolpath::PROCESS_WAAM,
        power_unit: Toolpath::POWER_ARC_ON,
        plane_separation_mm: 0.0,
        segments,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{plan_stack, LayerPolygons, WaamProcess};

    #[test]
    fn message_mirrors_the_layers() {
        let sq = vec![[0.0, 0.0], [50.0, 0.0], [50.0, 50.0], [0.0, 50.0]];
        let layers: Vec<LayerPolygons> = (0..2)
            .map(|i| LayerPolygons {
                index: i,
                z_mm: 1.6 * (i + 1) as f64,
                outers_and_holes: vec![sq.clone()],
            })
            .collect();
        let tps = plan_stack(&layers, &WaamProcess::default()).unwrap();
        let msg = toolpath_msg(&tps, "job1", "work");
        assert_eq!(msg.process, Toolpath::PROCESS_WAAM);
        assert_eq!(msg.power_unit, Toolpath::POWER_ARC_ON);
        let n: usize = tps.iter().map(|l| l.segments.len()).sum();
        assert_eq!(msg.segments.len(), n);
        for s in &msg.segments {
            let k = s.points.len();
            assert!(k >= 2);
            for len in [
                s.normals.len(),
                s.feed_mm_s.len(),
                s.power.len(),
                s.bead_width_mm.len(),
            ] {
                assert_eq!(len, k);
            }
            let on = s.kind == ToolpathSegment::KIND_DEPOSIT;
            assert!(s.power.iter().all(|&p| p == if on { 1.0 } else { 0.0 }));
            assert_eq!(on, s.bead_width_mm.iter().all(|&w| w > 0.0));
        }
        assert_eq!(msg.segments.last().unwrap().layer, 1);
    }
}
