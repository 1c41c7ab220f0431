//! Planned layers as a `cell_msgs::Toolpath` (process WAAM, power unit wire feed m/min), for the
//! emitter. Kept apart from the planning modules, which know nothing of the message types.
//!
//! Mapping: deposit segments → `KIND_DEPOSIT`, travel → `KIND_TRAVEL`; per point `feed_mm_s` =
//! speed, `power` = the wire feed speed WFS in m/min (0: arc off; the emitter's welddata take
//! it), `bead_width_mm` / `bead_height_mm` (0 on travel), normal
//! +Z (the surface normal of a horizontal layer; the emitter points the torch against it),
//! `layer` = the layer index. Not carried by the message: the interlayer dwell (read it from
//! [`LayerToolpath`]).
//!
//! [`toolpath_msg`] puts the points on the slicing planes with the torch along the normal;
//! [`toolpath_msg_for`] applies the process's torch pose ([`crate::torch`]): every point is
//! raised to the tool point height (the layer's top, plus the CTWD if given), and the normal
//! becomes the torch axis tilted by the lead and work angles. The tilt needs the travel
//! direction, which a normal alone cannot carry, so it is taken from the points themselves: at
//! a deposit point, the direction to the next point (the last point: from the one before). A
//! travel move keeps the axis of the bead it leaves at its first point and takes that of the
//! bead it goes to at the others, so the torch turns during the travel, not at a weld start.

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
                    .map(|p| {
                        if p.arc_on {
                            p.wire_feed_m_min as f32
                        } else {
                            0.0
                        }
                    })
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
        power_unit: Toolpath::POWER_WIRE_FEED_M_MIN,
        plane_separation_mm: 0.0,
        segments,
    }
}

/// The layers as one toolpath message with the torch pose `torch` (module docs);
/// `layer_height_mm` is the layer height the stack was sliced with (the job's, which may
/// override the process's).
pub fn toolpath_msg_for(
    layers: &[LayerToolpath],
    torch: &crate::torch::TorchPose,
    layer_height_mm: f64,
    job_id: &str,
    frame_id: &str,
) -> Toolpath {
    let mut msg = toolpath_msg(layers, job_id, frame_id);
    apply_torch(&mut msg, torch, layer_height_mm);
    msg
}

/// Raises every point to the tool point height and tilts the normals (module docs).
fn apply_torch(msg: &mut Toolpath, torch: &crate::torch::TorchPose, layer_height_mm: f64) {
    let dz = torch.height_above_slice_mm(layer_height_mm);
    for s in &mut msg.segments {
        for p in &mut s.points {
            p.z += dz;
        }
    }
    if torch.is_upright() {
        return;
    }
    let axis = |v: [f64; 3]| Vector3 {
        x: v[0],
        y: v[1],
        z: v[2],
    };
    // Deposits: the axis from each point's travel direction.
    for s in msg
        .segments
        .iter_mut()
        .filter(|s| s.kind != ToolpathSegment::KIND_TRAVEL)
    {
        let p = &s.points;
        let dir = |i: usize, j: usize| [p[j].x - p[i].x, p[j].y - p[i].y, 0.0];
        let horizontal = |d: [f64; 3]| d[0].hypot(d[1]) > 1e-9;
        s.normals = (0..p.len())
            .map(|i| {
                // The next piece with a horizontal length, else the last one before.
                let ahead = (i + 1..p.len()).map(|j| dir(i, j)).find(|d| horizontal(*d));
                let behind = (0..i).rev().map(|j| dir(j, i)).find(|d| horizontal(*d));
                axis(torch.axis(ahead.or(behind).unwrap_or([0.0; 3])))
            })
            .collect();
    }
    // Travels: the axis of the bead left at the first point, of the next bead after it.
    let up = Vector3 {
        x: 0.0,
        y: 0.0,
        z: 1.0,
    };
    for i in 0..msg.segments.len() {
        if msg.segments[i].kind != ToolpathSegment::KIND_TRAVEL {
            continue;
        }
        let deposit = |s: &ToolpathSegment| s.kind != ToolpathSegment::KIND_TRAVEL;
        let before = msg.segments[..i]
            .iter()
            .rev()
            .find(|s| deposit(s))
            .and_then(|s| s.normals.last().copied());
        let after = msg.segments[i + 1..]
            .iter()
            .find(|s| deposit(s))
            .and_then(|s| s.normals.first().copied());
        let n = msg.segments[i].points.len();
        msg.segments[i].normals = (0..n)
            .map(|k| {
                let own = if k == 0 { before } else { after };
                own.or(after).or(before).unwrap_or(up)
            })
            .collect();
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
        assert_eq!(msg.power_unit, Toolpath::POWER_WIRE_FEED_M_MIN);
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
            // The wire feed of the process while the arc is on (seed 004 Chart 2), 0 off.
            let wfs = WaamProcess::default().wire_feed_m_min as f32;
            assert!(s.power.iter().all(|&p| p == if on { wfs } else { 0.0 }));
            assert_eq!(on, s.bead_width_mm.iter().all(|&w| w > 0.0));
        }
        assert_eq!(msg.segments.last().unwrap().layer, 1);
    }

    /// Two square layers sliced mid-layer (z = 0.8, 2.4 for 1.6 mm layers).
    fn two_layers(process: &WaamProcess) -> Vec<LayerToolpath> {
        let sq = vec![[0.0, 0.0], [60.0, 0.0], [60.0, 40.0], [0.0, 40.0]];
        let layers: Vec<LayerPolygons> = (0..2)
            .map(|i| LayerPolygons {
                index: i,
                z_mm: 1.6 * i as f64 + 0.8,
                outers_and_holes: vec![sq.clone()],
            })
            .collect();
        plan_stack(&layers, process).unwrap()
    }

    #[test]
    fn the_torch_leads_and_leans_along_the_travel_direction() {
        let mut process = WaamProcess::default();
        process.torch.lead_angle_deg = 12.0; // push
        process.torch.work_angle_deg = -5.0;
        let msg = toolpath_msg_for(&two_layers(&process), &process.torch, 1.6, "j", "work");
        let mut checked = 0;
        for (si, s) in msg.segments.iter().enumerate() {
            if s.kind == ToolpathSegment::KIND_TRAVEL {
                // A travel leaves with the axis of the bead before it, arrives with the next's.
                let prev = msg.segments[..si]
                    .iter()
                    .rev()
                    .find(|s| s.kind != ToolpathSegment::KIND_TRAVEL);
                let next = msg.segments[si + 1..]
                    .iter()
                    .find(|s| s.kind != ToolpathSegment::KIND_TRAVEL);
                if let Some(prev) = prev {
                    assert_eq!(s.normals[0], *prev.normals.last().unwrap());
                }
                if let Some(next) = next {
                    assert_eq!(s.normals.last().unwrap(), &next.normals[0]);
                }
                continue;
            }
            for i in 0..s.points.len() - 1 {
                let (p, q, n) = (&s.points[i], &s.points[i + 1], &s.normals[i]);
                let len = (q.x - p.x).hypot(q.y - p.y);
                if len < 1e-6 {
                    continue;
                }
                let t = [(q.x - p.x) / len, (q.y - p.y) / len];
                let l = [-t[1], t[0]];
                let along = n.x * t[0] + n.y * t[1];
                let side = n.x * l[0] + n.y * l[1];
                // Push: the axis leans back against the travel, the tool points ahead.
                let lead = (-along).atan2(n.z).to_degrees();
                let work = side.atan2(n.z).to_degrees();
                assert!(
                    (lead - 12.0).abs() < 1e-9,
                    "segment {si} point {i}: lead {lead}"
                );
                assert!(
                    (work + 5.0).abs() < 1e-9,
                    "segment {si} point {i}: work {work}"
                );
                let norm = (n.x * n.x + n.y * n.y + n.z * n.z).sqrt();
                assert!((norm - 1.0).abs() < 1e-12);
                checked += 1;
            }
        }
        assert!(checked > 8, "{checked}");
        // Upright by default: the normals stay +Z.
        let msg = toolpath_msg_for(
            &two_layers(&WaamProcess::default()),
            &Default::default(),
            1.6,
            "j",
            "w",
        );
        assert!(msg
            .segments
            .iter()
            .flat_map(|s| &s.normals)
            .all(|n| (n.x, n.y, n.z) == (0.0, 0.0, 1.0)));
    }

    #[test]
    fn the_tool_point_is_on_the_layer_top_or_the_ctwd_above_it() {
        let mut process = WaamProcess::default();
        let layers = two_layers(&process);
        let heights = |msg: &Toolpath, layer: u32| -> Vec<f64> {
            msg.segments
                .iter()
                .filter(|s| s.layer == layer && s.kind == ToolpathSegment::KIND_DEPOSIT)
                .flat_map(|s| s.points.iter().map(|p| p.z))
                .collect()
        };
        // The slicing planes are mid-layer; the wire tip goes to the layer tops 1.6 and 3.2.
        let plain = toolpath_msg(&layers, "j", "w");
        assert!(heights(&plain, 0).iter().all(|&z| (z - 0.8).abs() < 1e-9));
        let msg = toolpath_msg_for(&layers, &process.torch, 1.6, "j", "w");
        assert!(heights(&msg, 0).iter().all(|&z| (z - 1.6).abs() < 1e-9));
        assert!(heights(&msg, 1).iter().all(|&z| (z - 3.2).abs() < 1e-9));
        process.torch.ctwd_mm = Some(15.0);
        let msg = toolpath_msg_for(&layers, &process.torch, 1.6, "j", "w");
        assert!(heights(&msg, 0).iter().all(|&z| (z - 16.6).abs() < 1e-9));
        // A bad torch is named.
        let e = WaamProcess::from_yaml_str("torch: {lead_angle_deg: 50}\n", "p.yaml").unwrap_err();
        assert!(e.to_string().contains("torch.lead_angle_deg"), "{e}");
    }
}
