//! `monitor`: watches a cell's `toolpath`, `heat_map` and `machine_status` topics, logs what it
//! sees to Rerun and prints a one-line summary per message and at exit.
//!
//! With `expect_toolpaths` / `expect_heat_maps` set it exits 0 once it has seen that many (and
//! fails after `timeout_s` otherwise), which makes it the end point of `cell demo` and a quick
//! acceptance check for a newly wired cell.

use std::{fmt, time::Duration};

use cell_msgs::{HeatMap, MachineStatus, Toolpath};
use cell_runtime::{rerun_sink::toolpath_entity, CellNode, QosPreset, Via};
use serde::{Deserialize, Serialize};

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct MonitorParams {
    /// Exit 0 once this many toolpaths arrived (with `expect_heat_maps`); 0: no requirement.
    pub expect_toolpaths: u32,
    /// Exit 0 once this many heat maps arrived (with `expect_toolpaths`); 0: no requirement.
    pub expect_heat_maps: u32,
    /// Give up (exit non-zero) after this long without meeting the expectations (s);
    /// 0: run until shutdown.
    pub timeout_s: f64,
}

impl Default for MonitorParams {
    fn default() -> Self {
        Self {
            expect_toolpaths: 0,
            expect_heat_maps: 0,
            timeout_s: 0.0,
        }
    }
}

/// What the monitor saw.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Summary {
    /// Toolpaths received.
    pub toolpaths: u32,
    /// Heat maps received, by transport.
    pub heat_maps_dds: u32,
    /// Heat maps received over shared memory.
    pub heat_maps_shm: u32,
    /// Machine status messages received.
    pub statuses: u32,
    /// Description of the last toolpath.
    pub last_toolpath: Option<String>,
    /// Description of the last heat map.
    pub last_heat_map: Option<String>,
}

impl Summary {
    fn heat_maps(&self) -> u32 {
        self.heat_maps_dds + self.heat_maps_shm
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} toolpath(s), {} heat map(s) ({} over shared memory, {} over DDS), {} machine status(es)",
            self.toolpaths,
            self.heat_maps(),
            self.heat_maps_shm,
            self.heat_maps_dds,
            self.statuses
        )?;
        if let Some(t) = &self.last_toolpath {
            write!(f, "; last toolpath: {t}")?;
        }
        if let Some(h) = &self.last_heat_map {
            write!(f, "; last heat map: {h}")?;
        }
        Ok(())
    }
}

/// One-line description of a toolpath: job, segments, points, cut length.
pub fn describe_toolpath(tp: &Toolpath) -> String {
    let points: usize = tp.segments.iter().map(|s| s.points.len()).sum();
    let length: f64 = tp
        .segments
        .iter()
        .flat_map(|s| s.points.windows(2))
        .map(|w| {
            ((w[1].x - w[0].x).powi(2) + (w[1].y - w[0].y).powi(2) + (w[1].z - w[0].z).powi(2))
                .sqrt()
        })
        .sum();
    format!(
        "job {:?}, {} segments, {} points, {:.1} mm of path",
        tp.job_id,
        tp.segments.len(),
        points,
        length
    )
}

/// One-line description of a heat map: quantity, size, range.
pub fn describe_heat_map(h: &HeatMap) -> String {
    let (min, max) = h
        .data
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        });
    let over = h.data.iter().filter(|v| **v > h.threshold).count();
    format!(
        "{} {}x{}, {:.1}..{:.1} {}, {} cells over {}",
        h.quantity, h.width, h.height, min, max, h.unit, over, h.threshold
    )
}

/// Watches the topics until the expectations are met, the timeout passes or shutdown.
pub async fn watch(node: &CellNode, p: &MonitorParams) -> anyhow::Result<Summary> {
    let mut toolpaths = node.subscriber::<Toolpath>("toolpath", QosPreset::Plan)?;
    let mut heat = node.subscriber::<HeatMap>("heat_map", QosPreset::Stream)?;
    let mut status = node.subscriber::<MachineStatus>("machine_status", QosPreset::Status)?;
    let expecting = p.expect_toolpaths > 0 || p.expect_heat_maps > 0;
    let deadline = (p.timeout_s > 0.0)
        .then(|| tokio::time::Instant::now() + Duration::from_secs_f64(p.timeout_s));
    let mut s = Summary::default();
    let rerun = node.rerun();
    loop {
        if expecting && s.toolpaths >= p.expect_toolpaths && s.heat_maps() >= p.expect_heat_maps {
            return Ok(s);
        }
        let timeout = async {
            match deadline {
                Some(d) => tokio::time::sleep_until(d).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            Some(r) = toolpaths.recv() => {
                s.toolpaths += 1;
                let text = describe_toolpath(&r.message);
                tracing::info!("toolpath on {}: {text}", toolpaths.topic());
                rerun.set_time(&r.message.header.stamp, s.toolpaths as i64);
                rerun.log_toolpath(toolpath_entity(&r.message), &r.message);
                s.last_toolpath = Some(text);
            }
            Some(r) = heat.recv() => {
                match r.via {
                    Via::SharedMemory => s.heat_maps_shm += 1,
                    Via::Dds => s.heat_maps_dds += 1,
                }
                let text = describe_heat_map(&r.message);
                tracing::debug!("heat map on {} via {:?}: {text}", heat.topic(), r.via);
                rerun.set_time(&r.message.header.stamp, s.heat_maps() as i64);
                rerun.log_heat_map(&format!("/monitor/{}", r.message.quantity), &r.message);
                s.last_heat_map = Some(text);
            }
            Some(r) = status.recv() => {
                s.statuses += 1;
                tracing::info!("machine {} state {} line {}/{}", r.message.machine_id, r.message.state, r.message.acked_line, r.message.total_lines);
            }
            _ = timeout => anyhow::bail!("timed out after {} s; saw {s}", p.timeout_s),
            _ = node.shutdown().requested() => return Ok(s),
        }
    }
}

/// Runs the node and prints the summary on stdout.
pub async fn run(node: CellNode, p: MonitorParams) -> anyhow::Result<()> {
    let summary = watch(&node, &p).await?;
    println!("monitor {}: {summary}", node.fully_qualified_name());
    Ok(())
}

/// The `monitor` binary (also `cell node monitor`).
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("monitor", argv, run)
}
