//! `probe` (on the ROS graph `cell_probe`): publishes a known `Toolpath` and a stream of
//! `HeatMap` frames, so an integrator can check a cell's wiring end to end (DDS discovery across
//! hosts, QoS, remapping, the shared-memory fast path, Rerun) before any real job runs.
//!
//! The toolpath is a tapered test block for a 4-axis hot-wire cutter: lead-in, a rectangle cut
//! with both wire ends (root plane and a smaller tip plane), lead-out and a travel home. The heat
//! map is a hot spot sweeping across a sheet.

use std::time::Duration;

use cell_geometry::{resample_max_step, Norm};
use cell_msgs::{
    builtin_interfaces::Time, geometry_msgs::Point, std_msgs::Header, HeatMap, Toolpath,
    ToolpathSegment,
};
use cell_runtime::{CellNode, QosPreset};
use serde::{Deserialize, Serialize};

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ProbeParams {
    /// Job id stamped on the toolpath.
    pub job_id: String,
    /// Test block size in the root plane (mm).
    pub block_width_mm: f64,
    /// Test block height in the root plane (mm).
    pub block_height_mm: f64,
    /// Tip block size as a fraction of the root (taper).
    pub tip_scale: f64,
    /// Distance between root and tip planes (mm).
    pub plane_separation_mm: f64,
    /// Cutting feed (mm/s).
    pub feed_mm_s: f64,
    /// Wire current while cutting (A).
    pub wire_current_a: f64,
    /// Heat-map raster size (cells).
    pub heat_map_width: u32,
    /// Heat-map raster size (cells).
    pub heat_map_height: u32,
    /// Heat-map frames to publish (0: none).
    pub heat_map_frames: u32,
    /// Heat-map frame rate (Hz).
    pub heat_map_rate_hz: f64,
    /// Subscribers to wait for on each topic before publishing (0: publish at once).
    pub wait_for_subscribers: u32,
    /// How long to wait for them (s).
    pub wait_timeout_s: f64,
    /// After publishing, keep running until shutdown so late joiners get the toolpath.
    pub linger: bool,
}

impl Default for ProbeParams {
    fn default() -> Self {
        Self {
            job_id: "probe".into(),
            block_width_mm: 120.0,
            block_height_mm: 40.0,
            tip_scale: 0.75,
            plane_separation_mm: 600.0,
            feed_mm_s: 3.0,
            wire_current_a: 3.0,
            heat_map_width: 256,
            heat_map_height: 256,
            heat_map_frames: 10,
            heat_map_rate_hz: 10.0,
            wait_for_subscribers: 0,
            wait_timeout_s: 10.0,
            linger: false,
        }
    }
}

/// Points along a closed rectangle, `step_mm` apart, starting at its lower-left corner.
fn rectangle(width: f64, height: f64, z: f64, step_mm: f64) -> Vec<Point> {
    let corners = [
        [0.0, 0.0],
        [0.0, height],
        [width, height],
        [width, 0.0],
        [0.0, 0.0],
    ];
    resample_max_step(&corners, step_mm, Norm::Hypot)
        .into_iter()
        .map(|[x, y]| Point { x, y, z })
        .collect()
}

/// The tapered hot-wire test block: lead-in, cut, lead-out, travel home.
pub fn test_block(p: &ProbeParams) -> Toolpath {
    let lead = 10.0;
    let root = rectangle(p.block_width_mm, p.block_height_mm, 0.0, 2.0);
    // The tip outline is the root scaled about the block's centre, in the far plane.
    let (cx, cy) = (p.block_width_mm / 2.0, p.block_height_mm / 2.0);
    let tip: Vec<Point> = root
        .iter()
        .map(|q| Point {
            x: cx + (q.x - cx) * p.tip_scale,
            y: cy + (q.y - cy) * p.tip_scale,
            z: p.plane_separation_mm,
        })
        .collect();
    let pair = |x: f64, y: f64| {
        (
            Point { x, y, z: 0.0 },
            Point {
                x: cx + (x - cx) * p.tip_scale,
                y: cy + (y - cy) * p.tip_scale,
                z: p.plane_separation_mm,
            },
        )
    };
    let segment = |kind: u8, pts: Vec<(Point, Point)>, feed: f64, power: f64| {
        let n = pts.len();
        let (points, secondary_points) = pts.into_iter().unzip();
        ToolpathSegment {
            kind,
            points,
            secondary_points,
            feed_mm_s: vec![feed as f32; n],
            power: vec![power as f32; n],
            ..Default::default()
        }
    };
    let current = p.wire_current_a;
    let segments = vec![
        segment(
            ToolpathSegment::KIND_LEAD,
            vec![pair(-lead, 0.0), pair(0.0, 0.0)],
            p.feed_mm_s,
            current,
        ),
        segment(
            ToolpathSegment::KIND_CUT,
            root.into_iter().zip(tip).collect(),
            p.feed_mm_s,
            current,
        ),
        segment(
            ToolpathSegment::KIND_LEAD,
            vec![pair(0.0, 0.0), pair(-lead, 0.0)],
            p.feed_mm_s,
            current,
        ),
        segment(
            ToolpathSegment::KIND_TRAVEL,
            vec![pair(-lead, 0.0), pair(-lead, -lead)],
            10.0,
            0.0,
        ),
    ];
    Toolpath {
        header: Header {
            stamp: Time::now(),
            frame_id: "cell".into(),
        },
        job_id: p.job_id.clone(),
        process: Toolpath::PROCESS_HOTWIRE,
        power_unit: Toolpath::POWER_WIRE_CURRENT_A,
        plane_separation_mm: p.plane_separation_mm,
        segments,
    }
}

/// Frame `index` of a hot spot sweeping diagonally across a `width`×`height` sheet at 293 K,
/// peaking at 893 K; threshold 573 K.
pub fn hot_spot(width: u32, height: u32, index: u32) -> HeatMap {
    let (w, h) = (width.max(1) as f32, height.max(1) as f32);
    let t = (index % 32) as f32 / 32.0;
    let (cx, cy, sigma) = (t * w, t * h, 0.08 * w.min(h));
    let mut data = Vec::with_capacity((width * height) as usize);
    for row in 0..height {
        for col in 0..width {
            let (dx, dy) = (col as f32 - cx, row as f32 - cy);
            data.push(293.0 + 600.0 * (-(dx * dx + dy * dy) / (2.0 * sigma * sigma)).exp());
        }
    }
    HeatMap {
        header: Header {
            stamp: Time::now(),
            frame_id: "sheet".into(),
        },
        quantity: "sheet_temperature".into(),
        unit: "K".into(),
        width,
        height,
        cell_width_mm: 1.0,
        cell_height_mm: 1.0,
        origin: Point::default(),
        threshold: 573.0,
        data,
    }
}

/// Publishes the test block once and the heat-map frames at the configured rate.
pub async fn run(node: CellNode, p: ProbeParams) -> anyhow::Result<()> {
    let toolpaths = node.publisher::<Toolpath>("toolpath", QosPreset::Plan)?;
    let heat = node.publisher::<HeatMap>("heat_map", QosPreset::Stream)?;
    if p.wait_for_subscribers > 0 {
        let timeout = Duration::from_secs_f64(p.wait_timeout_s);
        let n = p.wait_for_subscribers as usize;
        for (topic, ok) in [
            (
                toolpaths.topic(),
                toolpaths.wait_for_subscribers(n, timeout).await,
            ),
            (heat.topic(), heat.wait_for_subscribers(n, timeout).await),
        ] {
            if !ok {
                anyhow::bail!("no subscriber on {topic} after {timeout:?}");
            }
        }
    }
    let block = test_block(&p);
    node.rerun()
        .log_toolpath(cell_runtime::rerun_sink::toolpath_entity(&block), &block);
    toolpaths.publish(block).await?;
    tracing::info!(
        "published test block {:?} on {}",
        p.job_id,
        toolpaths.topic()
    );

    let period = Duration::from_secs_f64(1.0 / p.heat_map_rate_hz.max(0.1));
    let mut ticker = tokio::time::interval(period);
    for i in 0..p.heat_map_frames {
        tokio::select! {
            _ = ticker.tick() => {}
            _ = node.shutdown().requested() => return Ok(()),
        }
        let frame = hot_spot(p.heat_map_width, p.heat_map_height, i);
        node.rerun().set_time(&frame.header.stamp, i as i64);
        node.rerun().log_heat_map("/sheet/heat", &frame);
        heat.publish(frame).await?;
    }
    tracing::info!(
        "published {} heat-map frames on {}",
        p.heat_map_frames,
        heat.topic()
    );
    if p.linger {
        node.shutdown().requested().await;
    }
    Ok(())
}

/// The `probe` binary (also `cell node probe`); on the ROS graph the node is `cell_probe`.
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("cell_probe", argv, run)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test_block_is_a_closed_synchronised_two_plane_cut() {
        let p = ProbeParams::default();
        let tp = test_block(&p);
        let cut = &tp.segments[1];
        assert_eq!(cut.kind, ToolpathSegment::KIND_CUT);
        assert_eq!(cut.points.len(), cut.secondary_points.len());
        assert_eq!(cut.points.len(), cut.feed_mm_s.len());
        let (first, last) = (&cut.points[0], cut.points.last().unwrap());
        assert!((first.x - last.x).abs() < 1e-9 && (first.y - last.y).abs() < 1e-9);
        // Perimeter 2·(120+40) = 320 mm at the root, 0.75 of it at the tip.
        let length = |pts: &[Point]| -> f64 {
            let xy: Vec<[f64; 2]> = pts.iter().map(|p| [p.x, p.y]).collect();
            cell_geometry::polyline_length(&xy, Norm::Hypot)
        };
        assert!((length(&cut.points) - 320.0).abs() < 1e-9);
        assert!((length(&cut.secondary_points) - 240.0).abs() < 1e-9);
        assert!(cut.secondary_points.iter().all(|q| q.z == 600.0));
    }

    #[test]
    fn hot_spot_has_the_stated_range() {
        let h = hot_spot(64, 32, 16);
        assert_eq!(h.data.len(), 64 * 32);
        let max = h.data.iter().cloned().fold(f32::MIN, f32::max);
        let min = h.data.iter().cloned().fold(f32::MAX, f32::min);
        assert!(max > 850.0 && max <= 893.0, "{max}");
        assert!((min - 293.0).abs() < 1.0, "{min}");
    }
}
