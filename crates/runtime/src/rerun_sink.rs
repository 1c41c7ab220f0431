//! The Rerun sink every node logs to: `--rerun off | save:PATH | connect:ADDR`.
//!
//! # Entity paths
//! One tree for the whole cell, so recordings from several nodes line up in one viewer:
//!
//! | entity path                    | what                                    | logged by        |
//! |--------------------------------|-----------------------------------------|------------------|
//! | `/hotwire/trajectory`          | wire path, XY carriage plane            | planner          |
//! | `/hotwire/trajectory_tip`      | wire path, UV carriage plane            | planner          |
//! | `/hotwire/{root,tip}_{foil,path}` | foil and wire path on each foam face | planner          |
//! | `/hotwire/exposure`            | final exposure profile (HeatMap)        | planner          |
//! | `/hotwire/live/{root,tip}/…`   | current best's profile and matrix       | planner          |
//! | `/hotwire/loss`                | best loss on the `iteration` timeline   | planner          |
//! | `/sheet/toolpath`              | cut order and travel moves              | sequencer        |
//! | `/sheet/heat`                  | sheet temperature raster (HeatMap)      | sequencer        |
//! | `/waam/toolpath`, `/waam/layers` | bead paths, slices                    | slicer           |
//! | `/extrusion/toolpath`          | wing perimeters and spars               | slicer           |
//! | `/emitter/log`                 | each program (job, profile, dialect, lines, SHA-256) and each refused toolpath | emitter |
//! | `/machine/<id>/position`       | machine position now (tool and, on 4-axis machines, second carriage) | machine_bridge |
//! | `/machine/<id>/trace/<n>`      | the path the machine has moved, in chunks | machine_bridge |
//! | `/machine/<id>/{buffer_fill,feed_mm_s,acked_line}` | scalars over time | machine_bridge |
//! | `/machine/log`                 | each program run's outcome and each operator command | machine_bridge |
//! | `/jobs/log`                    | each job's summary rows                 | job_runner       |
//! | `/monitor/<topic>`             | whatever the monitor node received      | monitor          |
//!
//! [`toolpath_entity`] gives the default path for a `Toolpath` by its process. Timelines:
//! `ros_time` (the message header stamp) and `frame` (a per-node counter).
//!
//! A bag converted by `cell bag to-rerun` (`cellsuite::bag_rerun`) uses the same helpers, so
//! the toolpath, machine and emitter entities above look as they did live; what a bag adds:
//!
//! | entity path                    | what                                    | from             |
//! |--------------------------------|-----------------------------------------|------------------|
//! | `<topic>/<frame_id>`           | each `HeatMap` on that topic and frame (e.g. `/cell/exposure/hotwire_root`), as an image over time | [`RerunSink::log_heat_map`] |
//! | `<topic>/<frame_id>/{max,mean,threshold}` | the heat map's largest and mean value and its threshold (the material CSE for exposure) as scalars, so over-exposure shows as `max` above `threshold` | [`RerunSink::log_heat_map_stats`] |
//! | `/emitter/log`                 | each `MachineProgram`'s summary line, as the emitter logs it | [`RerunSink::log_text`] |
//! | `/programs/<job>/<file>`       | each program file's text (a document)   | [`RerunSink::log_text_document`] |
//! | `<topic>`                      | any other cellsuite message, one JSON text line each | [`RerunSink::log_text`] |
//!
//! A converted bag also has the `log_time` timeline: each message's bag log (receive) time,
//! set by [`RerunSink::set_log_time`]; `ros_time` is the header stamp (the log time for a
//! message without one) and `frame` the message's index on its topic.
//!
//! `save:PATH` may contain `{node}`, replaced by the node name, so several nodes launched with
//! one setting write separate `.rrd` files. `connect:ADDR` takes `host:port` (the viewer's gRPC
//! port, 9876 by default) or a full `rerun+http://…/proxy` URL.

use std::path::PathBuf;

use cell_msgs::{HeatMap, MachineStatus, Toolpath, ToolpathSegment};
use rerun::RecordingStream;

/// Where a node's Rerun data goes.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum RerunTarget {
    /// Nothing is logged.
    #[default]
    Off,
    /// Written to an `.rrd` file; `{node}` in the path is replaced by the node name.
    Save(PathBuf),
    /// Streamed to a running viewer.
    Connect(String),
}

/// A `--rerun` value that is none of `off`, `save:PATH`, `connect:ADDR`.
#[derive(Debug, thiserror::Error)]
#[error("--rerun {0:?}: expected off, save:PATH or connect:HOST:PORT")]
pub struct RerunTargetError(String);

impl std::str::FromStr for RerunTarget {
    type Err = RerunTargetError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.split_once(':') {
            _ if s == "off" => Ok(RerunTarget::Off),
            Some(("save", path)) if !path.is_empty() => Ok(RerunTarget::Save(path.into())),
            Some(("connect", addr)) if !addr.is_empty() => Ok(RerunTarget::Connect(addr.into())),
            _ => Err(RerunTargetError(s.to_string())),
        }
    }
}

impl RerunTarget {
    /// The file a node named `node` saves to, if any.
    pub fn save_path(&self, node: &str) -> Option<PathBuf> {
        match self {
            RerunTarget::Save(p) => Some(p.to_string_lossy().replace("{node}", node).into()),
            _ => None,
        }
    }
}

/// A node's Rerun recording, or nothing when off. Logging never fails a node: errors are
/// reported once through `tracing` and the data is dropped.
#[derive(Clone, Default)]
pub struct RerunSink {
    stream: Option<RecordingStream>,
}

impl std::fmt::Debug for RerunSink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RerunSink")
            .field("enabled", &self.stream.is_some())
            .finish()
    }
}

/// The Rerun application id all cellsuite nodes share.
pub const APPLICATION_ID: &str = "cellsuite";

impl RerunSink {
    /// Opens the sink. `recording_id` ties the recordings of one cell run together (the launcher
    /// passes the same one to every node through `CELL_RUN_ID`).
    pub fn open(target: &RerunTarget, node: &str, recording_id: &str) -> anyhow::Result<Self> {
        let builder = rerun::RecordingStreamBuilder::new(APPLICATION_ID).recording_id(recording_id);
        let stream = match target {
            RerunTarget::Off => return Ok(Self::default()),
            RerunTarget::Save(_) => {
                let path = target.save_path(node).expect("save target has a path");
                if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir)
                        .map_err(|e| anyhow::anyhow!("--rerun save:{}: {e}", path.display()))?;
                }
                builder
                    .save(&path)
                    .map_err(|e| anyhow::anyhow!("--rerun save:{}: {e}", path.display()))?
            }
            RerunTarget::Connect(addr) => {
                let url = if addr.contains("://") {
                    addr.clone()
                } else {
                    format!("rerun+http://{addr}/proxy")
                };
                builder
                    .connect_grpc_opts(url.clone())
                    .map_err(|e| anyhow::anyhow!("--rerun connect:{addr} ({url}): {e}"))?
            }
        };
        Ok(Self {
            stream: Some(stream),
        })
    }

    /// The underlying stream, for archetypes this module has no helper for.
    pub fn stream(&self) -> Option<&RecordingStream> {
        self.stream.as_ref()
    }

    /// Whether anything is recorded.
    pub fn is_enabled(&self) -> bool {
        self.stream.is_some()
    }

    /// Sets the `ros_time` timeline from a header stamp and `frame` from a counter.
    pub fn set_time(&self, stamp: &cell_msgs::builtin_interfaces::Time, frame: i64) {
        if let Some(rec) = &self.stream {
            let secs = stamp.sec as f64 + stamp.nanosec as f64 * 1e-9;
            rec.set_duration_secs("ros_time", secs);
            rec.set_time_sequence("frame", frame);
        }
    }

    /// Sets the `log_time` timeline (a timestamp, ns since the epoch): when a bag's recorder
    /// received the message. Only bag conversion sets it; the live nodes have `ros_time`.
    pub fn set_log_time(&self, log_time_ns: u64) {
        if let Some(rec) = &self.stream {
            rec.set_timestamp_nanos_since_epoch("log_time", log_time_ns as i64);
        }
    }

    /// Logs a toolpath as line strips, one per segment, coloured by segment kind. Hot-wire tip
    /// (secondary-plane) points go to `<entity>_tip`.
    pub fn log_toolpath(&self, entity: &str, toolpath: &Toolpath) {
        let Some(rec) = &self.stream else { return };
        let strips = |secondary: bool| -> (Vec<Vec<[f32; 3]>>, Vec<rerun::Color>) {
            toolpath
                .segments
                .iter()
                .filter_map(|seg| {
                    let pts = if secondary {
                        &seg.secondary_points
                    } else {
                        &seg.points
                    };
                    (!pts.is_empty()).then(|| {
                        let strip = pts
                            .iter()
                            .map(|p| [p.x as f32, p.y as f32, p.z as f32])
                            .collect();
                        (strip, segment_color(seg))
                    })
                })
                .unzip()
        };
        let (primary, colors) = strips(false);
        self.report(rec.log(
            entity,
            &rerun::LineStrips3D::new(primary).with_colors(colors),
        ));
        let (secondary, colors) = strips(true);
        if !secondary.is_empty() {
            let tip = format!("{entity}_tip");
            self.report(rec.log(
                tip,
                &rerun::LineStrips3D::new(secondary).with_colors(colors),
            ));
        }
    }

    /// Logs a heat map as a colour-mapped scalar image.
    pub fn log_heat_map(&self, entity: &str, heat: &HeatMap) {
        let Some(rec) = &self.stream else { return };
        let bytes: Vec<u8> = heat.data.iter().flat_map(|v| v.to_le_bytes()).collect();
        let image = rerun::DepthImage::from_data_type_and_bytes(
            bytes,
            [heat.width, heat.height],
            rerun::ChannelDatatype::F32,
        )
        .with_colormap(rerun::components::Colormap::Inferno);
        self.report(rec.log(entity, &image));
    }

    /// Logs a heat map's largest value and the mean of its finite values as the scalars
    /// `<entity>/max` and `<entity>/mean`, and its threshold as `<entity>/threshold` when it
    /// has one (not NaN). For an exposure profile the threshold is the material's CSE, so the
    /// plot shows how far the hottest panel overshoots it while the plan improves. A heat map
    /// without finite values logs nothing.
    pub fn log_heat_map_stats(&self, entity: &str, heat: &HeatMap) {
        let Some(rec) = &self.stream else { return };
        let Some(stats) = HeatMapStats::of(heat) else {
            return;
        };
        for (name, value) in [("max", stats.max), ("mean", stats.mean)] {
            self.report(rec.log(format!("{entity}/{name}"), &rerun::Scalars::single(value)));
        }
        if heat.threshold.is_finite() {
            self.report(rec.log(
                format!("{entity}/threshold"),
                &rerun::Scalars::single(f64::from(heat.threshold)),
            ));
        }
    }

    /// Logs a whole text (a program file) as a document the viewer shows in a text view.
    pub fn log_text_document(&self, entity: &str, text: &str) {
        if let Some(rec) = &self.stream {
            self.report(rec.log(entity, &rerun::TextDocument::new(text)));
        }
    }

    /// Logs a line of text (an event the viewer should show in its log panel).
    pub fn log_text(&self, entity: &str, text: &str) {
        if let Some(rec) = &self.stream {
            self.report(rec.log(entity, &rerun::TextLog::new(text)));
        }
    }

    /// Writes out everything buffered; call before the process exits.
    pub fn flush(&self) {
        if let Some(rec) = &self.stream {
            if let Err(e) = rec.flush_blocking() {
                tracing::warn!("rerun: flush failed: {e}");
            }
        }
    }

    fn report(&self, result: rerun::RecordingStreamResult<()>) {
        if let Err(e) = result {
            tracing::warn!("rerun: {e}");
        }
    }
}

/// Largest and mean value of a heat map's finite cells (see [`RerunSink::log_heat_map_stats`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeatMapStats {
    /// The largest finite value.
    pub max: f64,
    /// The mean of the finite values.
    pub mean: f64,
}

impl HeatMapStats {
    /// Statistics over the finite values (NaN marks a cell without data); `None` when there
    /// are none.
    pub fn of(heat: &HeatMap) -> Option<Self> {
        let (mut max, mut sum, mut n) = (f64::NEG_INFINITY, 0.0, 0usize);
        for v in heat.data.iter().filter(|v| v.is_finite()) {
            let v = f64::from(*v);
            max = max.max(v);
            sum += v;
            n += 1;
        }
        (n > 0).then(|| Self {
            max,
            mean: sum / n as f64,
        })
    }
}

/// Points per trace chunk entity: each chunk is logged once, so a long job costs O(points).
const TRACE_CHUNK_POINTS: usize = 64;

/// Smallest move (mm) that adds a point to a trace.
const TRACE_MIN_STEP_MM: f32 = 0.01;

/// Logs `MachineStatus` messages (see the module table): the position now, the path moved so
/// far as line-strip chunks under `trace/` (a chunk per 64 points or whenever the machine
/// stops running; cleared when a new job starts) and the buffer
/// fill, feed and acknowledged line as scalars. Keeps one trace per machine; the live bridge
/// and bag conversion use the same logger, so both draw the same thing.
#[derive(Debug, Default)]
pub struct MachineStatusLogger {
    traces: std::collections::HashMap<String, MachineTrace>,
}

#[derive(Debug, Default)]
struct MachineTrace {
    job_id: String,
    /// Points not yet logged as a chunk, after the previous chunk's last point.
    pending: Vec<[[f32; 3]; 2]>,
    chunks: u64,
    /// Whether the machine reports a second carriage (drawn as a second strip).
    has_second: bool,
}

impl MachineTrace {
    /// Logs the pending points as the next `trace/<n>` chunk, if they make a line.
    fn write_chunk(&mut self, sink: &RerunSink, rec: &RecordingStream, base: &str) {
        if self.pending.len() < 2 {
            return;
        }
        let mut strips = vec![self.pending.iter().map(|p| p[0]).collect::<Vec<_>>()];
        if self.has_second {
            strips.push(self.pending.iter().map(|p| p[1]).collect());
        }
        sink.report(rec.log(
            format!("{base}/trace/{}", self.chunks),
            &rerun::LineStrips3D::new(strips),
        ));
        self.chunks += 1;
        // The next chunk starts where this one ended, so the path has no gaps.
        let last = *self.pending.last().expect("two points or more");
        self.pending = vec![last];
    }
}

/// The tool point (X, Y, Z) and the second carriage (U, V, W, or A, B, C on Mach3-style
/// 4-axis foam cutters), from named axes; absent axes are 0.
fn carriage_points(status: &MachineStatus) -> Option<([f32; 3], Option<[f32; 3]>)> {
    let get = |name: &str| {
        status
            .axis_names
            .iter()
            .position(|n| n.eq_ignore_ascii_case(name))
            .and_then(|i| status.axis_positions.get(i))
            .map(|v| *v as f32)
    };
    let pick = |names: [&str; 3]| {
        let v = names.map(&get);
        v.iter()
            .any(Option::is_some)
            .then(|| v.map(|x| x.unwrap_or(0.0)))
    };
    let tool = pick(["X", "Y", "Z"])?;
    let second = pick(["U", "V", "W"]).or_else(|| pick(["A", "B", "C"]));
    Some((tool, second))
}

impl MachineStatusLogger {
    /// Logs a controller's heater readings at the sink's current time, as scalars
    /// `/machine/<id>/temperature/<heater>` and `…/<heater>_target` (°C): a printer's heat-up,
    /// print and cool-down beside its position.
    pub fn log_heaters(&self, sink: &RerunSink, machine_id: &str, heaters: &[(&str, f64, f64)]) {
        let Some(rec) = sink.stream() else { return };
        for (name, current, target) in heaters {
            let base = format!("/machine/{machine_id}/temperature/{name}");
            sink.report(rec.log(base.as_str(), &rerun::Scalars::single(*current)));
            sink.report(rec.log(format!("{base}_target"), &rerun::Scalars::single(*target)));
        }
    }

    /// Logs one status at the sink's current time.
    pub fn log(&mut self, sink: &RerunSink, status: &MachineStatus) {
        let Some(rec) = sink.stream() else { return };
        let base = format!("/machine/{}", status.machine_id);
        let trace = self.traces.entry(status.machine_id.clone()).or_default();
        if trace.job_id != status.job_id {
            if trace.chunks > 0 || !trace.pending.is_empty() {
                sink.report(rec.log(format!("{base}/trace"), &rerun::Clear::recursive()));
            }
            *trace = MachineTrace {
                job_id: status.job_id.clone(),
                ..MachineTrace::default()
            };
        }
        if let Some((tool, second)) = carriage_points(status) {
            let mut points = vec![tool];
            points.extend(second);
            sink.report(rec.log(
                format!("{base}/position"),
                &rerun::Points3D::new(points).with_radii([1.5]),
            ));
            let here = [tool, second.unwrap_or(tool)];
            let moved = trace.pending.last().is_none_or(|last| {
                let d = |a: [f32; 3], b: [f32; 3]| {
                    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f32>().sqrt()
                };
                d(last[0], here[0]) > TRACE_MIN_STEP_MM || d(last[1], here[1]) > TRACE_MIN_STEP_MM
            });
            if moved {
                trace.pending.push(here);
            }
            // A full chunk goes out, and so does the rest once the machine stops moving, so a
            // finished job's whole path is in the recording.
            let stopped = status.state != MachineStatus::STATE_RUNNING;
            trace.has_second |= second.is_some();
            if trace.pending.len() > TRACE_CHUNK_POINTS || stopped {
                trace.write_chunk(sink, rec, &base);
            }
        }
        for (name, value) in [
            ("buffer_fill", f64::from(status.buffer_fill)),
            ("feed_mm_s", f64::from(status.feed_mm_s)),
            ("acked_line", f64::from(status.acked_line)),
        ] {
            sink.report(rec.log(format!("{base}/{name}"), &rerun::Scalars::single(value)));
        }
    }
}

impl MachineStatusLogger {
    /// Logs every machine's pending trace points, so a recording that ends mid-job (or
    /// before the status after the last move) still holds the whole path moved.
    pub fn flush(&mut self, sink: &RerunSink) {
        let Some(rec) = sink.stream() else { return };
        for (machine_id, trace) in &mut self.traces {
            trace.write_chunk(sink, rec, &format!("/machine/{machine_id}"));
        }
    }
}

/// Default entity path for a toolpath, by process (see the table in the module docs).
pub fn toolpath_entity(toolpath: &Toolpath) -> &'static str {
    match toolpath.process {
        Toolpath::PROCESS_HOTWIRE => "/hotwire/trajectory",
        Toolpath::PROCESS_SHEET_CUT => "/sheet/toolpath",
        Toolpath::PROCESS_WAAM => "/waam/toolpath",
        Toolpath::PROCESS_EXTRUSION => "/extrusion/toolpath",
        _ => "/toolpath",
    }
}

fn segment_color(seg: &ToolpathSegment) -> rerun::Color {
    match seg.kind {
        ToolpathSegment::KIND_CUT => rerun::Color::from_rgb(230, 80, 40),
        ToolpathSegment::KIND_TRAVEL => rerun::Color::from_rgb(120, 120, 120),
        ToolpathSegment::KIND_DEPOSIT => rerun::Color::from_rgb(240, 180, 30),
        _ => rerun::Color::from_rgb(60, 140, 230),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn carriage_points_come_from_named_axes() {
        let status = |names: &[&str], pos: &[f64]| MachineStatus {
            axis_names: names.iter().map(|s| s.to_string()).collect(),
            axis_positions: pos.to_vec(),
            ..MachineStatus::default()
        };
        let (tool, second) =
            carriage_points(&status(&["X", "Y", "U", "V"], &[1.0, 2.0, 3.0, 4.0])).unwrap();
        assert_eq!((tool, second), ([1.0, 2.0, 0.0], Some([3.0, 4.0, 0.0])));
        let (tool, second) =
            carriage_points(&status(&["X", "Y", "A", "B"], &[1.0, 2.0, 3.0, 4.0])).unwrap();
        assert_eq!((tool, second), ([1.0, 2.0, 0.0], Some([3.0, 4.0, 0.0])));
        let (tool, second) = carriage_points(&status(&["X", "Y", "Z"], &[1.0, 2.0, 3.0])).unwrap();
        assert_eq!((tool, second), ([1.0, 2.0, 3.0], None));
        assert!(carriage_points(&status(&[], &[])).is_none());
        // Fewer positions than names (a controller reporting fewer axes): the rest are absent.
        let (tool, second) = carriage_points(&status(&["X", "Y", "U"], &[1.0, 2.0])).unwrap();
        assert_eq!((tool, second), ([1.0, 2.0, 0.0], None));
    }

    /// A job shorter than a chunk, cut off while still RUNNING: `flush` alone puts its
    /// path in the file (the demo's bridge is stopped before its next status tick).
    #[test]
    fn flush_writes_a_running_jobs_short_trace() {
        let dir = tempfile::tempdir().unwrap();
        let target = RerunTarget::Save(dir.path().join("{node}.rrd"));
        let sink = RerunSink::open(&target, "bridge", "test-run").unwrap();
        let mut logger = MachineStatusLogger::default();
        for x in [0.0, 5.0, 10.0] {
            logger.log(
                &sink,
                &MachineStatus {
                    machine_id: "sim".into(),
                    job_id: "job-1".into(),
                    state: MachineStatus::STATE_RUNNING,
                    axis_names: vec!["X".into(), "Y".into(), "U".into(), "V".into()],
                    axis_positions: vec![x, 1.0, x, 2.0],
                    ..MachineStatus::default()
                },
            );
        }
        let written = |sink: &RerunSink| {
            sink.flush();
            let file = std::fs::File::open(dir.path().join("bridge.rrd")).unwrap();
            let messages: Vec<_> =
                re_log_encoding::DecoderApp::decode_eager(std::io::BufReader::new(file))
                    .unwrap()
                    .collect::<Result<_, _>>()
                    .unwrap();
            format!("{messages:?}").contains("/machine/sim/trace/0")
        };
        assert!(!written(&sink), "3 points are below a chunk");
        logger.flush(&sink);
        assert!(written(&sink), "flush writes the pending points");
    }

    #[test]
    fn heat_map_stats_skip_cells_without_data() {
        let heat = |data: Vec<f32>| HeatMap {
            width: data.len() as u32,
            height: 1,
            data,
            ..HeatMap::default()
        };
        let stats = HeatMapStats::of(&heat(vec![1.0, f32::NAN, 5.0, 0.0])).unwrap();
        assert_eq!(
            stats,
            HeatMapStats {
                max: 5.0,
                mean: 2.0
            }
        );
        assert_eq!(HeatMapStats::of(&heat(vec![f32::NAN])), None);
        assert_eq!(HeatMapStats::of(&heat(vec![])), None);
    }

    #[test]
    fn parses_targets() {
        assert_eq!("off".parse::<RerunTarget>().unwrap(), RerunTarget::Off);
        assert_eq!(
            "save:out/{node}.rrd"
                .parse::<RerunTarget>()
                .unwrap()
                .save_path("planner"),
            Some(PathBuf::from("out/planner.rrd"))
        );
        assert_eq!(
            "connect:127.0.0.1:9876".parse::<RerunTarget>().unwrap(),
            RerunTarget::Connect("127.0.0.1:9876".into())
        );
        for bad in ["", "on", "save:", "connect:", "file:x.rrd"] {
            let err = bad.parse::<RerunTarget>().unwrap_err().to_string();
            assert!(
                err.contains("expected off, save:PATH or connect:HOST:PORT"),
                "{err}"
            );
        }
    }
}
