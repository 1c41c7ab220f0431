//! A bag as a Rerun recording (`cell bag to-rerun BAG --out FILE.rrd`, and `demo-out/bag.rrd`
//! after `cell demo`).
//!
//! Every message is drawn by the same [`RerunSink`] helpers the live nodes call, so a
//! converted bag looks like the nodes' own recordings (the entity table is in
//! [`cell_runtime::rerun_sink`]):
//!
//! | message | drawn as | entity |
//! |---|---|---|
//! | `Toolpath` | line strips per segment ([`RerunSink::log_toolpath`]) | [`toolpath_entity`] (`/hotwire/trajectory` and `_tip`, `/sheet/toolpath`, …) |
//! | `HeatMap` | image ([`RerunSink::log_heat_map`]) and max/mean/threshold scalars ([`RerunSink::log_heat_map_stats`]) | `<topic>/<frame_id>`, e.g. `/cell/exposure/hotwire_root` |
//! | `MachineStatus` | position, trace, buffer fill, feed, acknowledged line ([`MachineStatusLogger`]) | `/machine/<id>/…` |
//! | `MachineProgram` | the emitter's summary line, and each file as a document | `/emitter/log`, `/programs/<job>/<file>` |
//! | `ProgramFile` | the file as a document | `<topic>/<file>` |
//! | any other cellsuite type | one JSON line ([`RerunSink::log_text`]) | `<topic>` |
//!
//! Time: `ros_time` is the header stamp, as the live nodes set it (the bag's log time for a
//! message without a header or with a zero stamp), `log_time` the bag's log time, `frame` the
//! message's index on its topic. Heat maps are split by frame because the planner publishes
//! root and tip profiles on one topic.
//!
//! A message whose type this suite does not know, or that does not decode, is counted, warned
//! about (once per topic) and skipped. The file is written beside `--out` and renamed over it
//! when complete, so a failed conversion never leaves half a recording.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use cell_bag::{BagError, BagMessage, BagReader};
use cell_msgs::builtin_interfaces::Time;
use cell_msgs::{HeatMap, MachineProgram, MachineStatus, ProgramFile, RosMessage, Toolpath};
use cell_runtime::rerun_sink::toolpath_entity;
use cell_runtime::{MachineStatusLogger, RerunSink, RerunTarget};

/// `cell bag to-rerun` options.
#[derive(clap::Args, Debug)]
pub struct ToRerunArgs {
    /// The bag directory or .mcap file.
    pub bag: PathBuf,
    /// The Rerun file to write (default: the bag's path with `.rrd`, e.g. `demo-out/bag.rrd`).
    #[arg(long, value_name = "FILE.rrd")]
    pub out: Option<PathBuf>,
}

/// The default `--out`: `BAG.rrd` beside the bag (`run1/` gives `run1.rrd`, `run1.mcap`
/// gives `run1.rrd`).
pub fn default_out(bag: &Path) -> PathBuf {
    let bag = named(bag);
    if bag.is_dir() {
        let mut name = bag.file_name().unwrap_or_default().to_owned();
        name.push(".rrd");
        bag.with_file_name(name)
    } else {
        bag.with_extension("rrd")
    }
}

/// `path` without a trailing `/`, made absolute when it has no name of its own (`.`, `..`).
fn named(path: &Path) -> PathBuf {
    let path = path.components().as_path();
    match path.file_name() {
        Some(_) => path.to_owned(),
        None => std::fs::canonicalize(path).unwrap_or_else(|_| path.to_owned()),
    }
}

/// Runs `cell bag to-rerun`: converts, prints the summary, returns the exit status (0; 64 no
/// such bag or an output that cannot be written; 65 a bag that cannot be read).
pub fn run(args: &ToRerunArgs) -> ExitCode {
    let out = args.out.clone().unwrap_or_else(|| default_out(&args.bag));
    let recording_id = format!(
        "bag-{}",
        named(&args.bag)
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
    );
    let options = ConvertOptions {
        recording_id,
        progress: true,
    };
    match convert(&args.bag, &out, &options) {
        Ok(report) => {
            print!("{report}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

/// Entity of the emitter's program summaries (the emitter node logs to the same one).
pub const PROGRAM_LOG: &str = "/emitter/log";

/// Longest JSON text line logged for a message of another type; longer ones are cut (a
/// viewer's log panel is for reading, the bag keeps the message).
const MAX_TEXT_CHARS: usize = 500;

/// How to convert.
#[derive(Debug, Clone)]
pub struct ConvertOptions {
    /// The recording id of the `.rrd`. Keep it different from the live run's, so opening both
    /// files in one viewer shows two recordings instead of merging their entities.
    pub recording_id: String,
    /// Show a progress bar on stderr (drawn only on a terminal).
    pub progress: bool,
}

/// What happened to one topic's messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicReport {
    /// Topic name.
    pub topic: String,
    /// ROS 2 type name.
    pub type_name: String,
    /// Messages drawn.
    pub converted: u64,
    /// Messages skipped (unknown type or undecodable).
    pub skipped: u64,
}

/// The result of a conversion; `Display` prints the summary table.
#[derive(Debug, Clone)]
pub struct ConvertReport {
    /// The bag read.
    pub bag: PathBuf,
    /// The `.rrd` written.
    pub out: PathBuf,
    /// Per topic, in order of first message.
    pub topics: Vec<TopicReport>,
    /// Every file of every `MachineProgram` in the bag, in bag order (once per job and name).
    pub programs: Vec<ProgramSeen>,
}

/// A program file a bag's `MachineProgram` holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramSeen {
    /// The program's job.
    pub job_id: String,
    /// The file name, as the emitter writes it.
    pub file: String,
    /// Lines in the file.
    pub lines: usize,
}

impl ConvertReport {
    /// Messages drawn over all topics.
    pub fn converted(&self) -> u64 {
        self.topics.iter().map(|t| t.converted).sum()
    }

    /// Messages skipped over all topics.
    pub fn skipped(&self) -> u64 {
        self.topics.iter().map(|t| t.skipped).sum()
    }
}

impl fmt::Display for ConvertReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let width = self
            .topics
            .iter()
            .map(|t| t.topic.len())
            .chain(["topic".len()])
            .max()
            .unwrap_or(0);
        writeln!(
            f,
            "{} -> {}: {} messages converted, {} skipped",
            self.bag.display(),
            self.out.display(),
            self.converted(),
            self.skipped()
        )?;
        writeln!(f, "  {:<width$}  converted  skipped  type", "topic")?;
        for t in &self.topics {
            writeln!(
                f,
                "  {:<width$}  {:>9}  {:>7}  {}",
                t.topic, t.converted, t.skipped, t.type_name
            )?;
        }
        Ok(())
    }
}

/// Why a conversion failed.
#[derive(Debug, thiserror::Error)]
pub enum ConvertError {
    /// The bag cannot be read (missing, truncated, corrupt, unfinished).
    #[error("{0}")]
    Bag(BagError),
    /// The bag's writer did not finish it.
    #[error("{source}: `cell bag repair {}`", bag.display())]
    Unfinished {
        /// The bag given.
        bag: PathBuf,
        /// The reader's error, naming the file.
        source: BagError,
    },
    /// The output file cannot be written.
    #[error("--out {}: {message}", path.display())]
    Output {
        /// The `.rrd` asked for.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

impl ConvertError {
    /// The exit status for `cell`: 64 for an output that cannot be written (a bad command
    /// line), 65 for a bag that cannot be read.
    pub fn exit_code(&self) -> u8 {
        match self {
            ConvertError::Output { .. } => cell_runtime::EXIT_USAGE,
            ConvertError::Bag(_) | ConvertError::Unfinished { .. } => cell_runtime::EXIT_DATA,
        }
    }

    fn bag(bag: &Path, e: BagError) -> Self {
        match e {
            e @ BagError::Unfinished { .. } => ConvertError::Unfinished {
                bag: bag.to_owned(),
                source: e,
            },
            e => ConvertError::Bag(e),
        }
    }
}

/// Converts the bag at `bag` (a directory or one `.mcap`) into the Rerun recording `out`; see
/// the [module docs](self).
///
/// # Errors
/// [`ConvertError::Unfinished`] or [`ConvertError::Bag`] when the bag cannot be read (nothing
/// is written); [`ConvertError::Output`] when `out` cannot be written.
pub fn convert(
    bag: &Path,
    out: &Path,
    options: &ConvertOptions,
) -> Result<ConvertReport, ConvertError> {
    let mut reader = BagReader::open(bag).map_err(|e| ConvertError::bag(bag, e))?;
    let output = |message: String| ConvertError::Output {
        path: out.to_owned(),
        message,
    };
    let name = out
        .file_name()
        .ok_or_else(|| output("not a file name".into()))?;
    if out.is_dir() {
        return Err(output("is a directory".into()));
    }
    let mut tmp_name = name.to_owned();
    tmp_name.push(".tmp");
    let tmp = out.with_file_name(tmp_name);
    let sink = RerunSink::open(
        &RerunTarget::Save(tmp.clone()),
        "bag",
        &options.recording_id,
    )
    .map_err(|e| output(format!("{e:#}")))?;

    let bar = if options.progress {
        indicatif::ProgressBar::new(reader.info().message_count)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} messages, ETA {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut converter = Converter {
        sink: &sink,
        machines: MachineStatusLogger::default(),
        topics: BTreeMap::new(),
        order: Vec::new(),
        programs: Vec::new(),
    };
    let mut failed = None;
    for message in reader.messages() {
        match message {
            Ok(m) => {
                if let Some(warning) = converter.convert(&m) {
                    bar.suspend(|| eprintln!("warning: {warning}"));
                }
            }
            Err(e) => failed = Some(e),
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    converter.machines.flush(&sink);
    let topics = converter.report();
    let programs = converter.programs;
    sink.flush();
    // Dropping the last handle finishes the file (footer included) before it is renamed.
    drop(sink);
    if let Some(e) = failed {
        let _ = std::fs::remove_file(&tmp);
        return Err(ConvertError::bag(bag, e));
    }
    std::fs::rename(&tmp, out).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        output(e.to_string())
    })?;
    Ok(ConvertReport {
        bag: bag.to_owned(),
        out: out.to_owned(),
        topics,
        programs,
    })
}

/// Conversion state: the sink, the machine traces and the per-topic counts.
struct Converter<'a> {
    sink: &'a RerunSink,
    machines: MachineStatusLogger,
    topics: BTreeMap<String, TopicReport>,
    /// Topics in order of first message, for the report.
    order: Vec<String>,
    programs: Vec<ProgramSeen>,
}

impl Converter<'_> {
    /// Draws one message; returns a warning the first time a topic's message is skipped.
    fn convert(&mut self, m: &BagMessage) -> Option<String> {
        let topic = &*m.topic;
        if !self.topics.contains_key(topic) {
            self.order.push(topic.to_owned());
            self.topics.insert(
                topic.to_owned(),
                TopicReport {
                    topic: topic.to_owned(),
                    type_name: m.type_name.to_string(),
                    converted: 0,
                    skipped: 0,
                },
            );
        }
        let frame = {
            let t = &self.topics[topic];
            (t.converted + t.skipped) as i64
        };
        self.sink.set_log_time(m.log_time_ns);
        let result = self.draw(m, frame);
        let report = self.topics.get_mut(topic).expect("inserted above");
        match result {
            Ok(()) => {
                report.converted += 1;
                None
            }
            Err(why) => {
                report.skipped += 1;
                (report.skipped == 1).then(|| {
                    format!(
                        "{topic} ({}): {why}; skipping such messages (counted in the summary)",
                        m.type_name
                    )
                })
            }
        }
    }

    /// Sets `ros_time` from a header stamp (the log time when the stamp is zero) and `frame`.
    fn set_time(&self, stamp: &Time, m: &BagMessage, frame: i64) {
        let stamp = if stamp.sec == 0 && stamp.nanosec == 0 {
            Time {
                sec: (m.log_time_ns / 1_000_000_000) as i32,
                nanosec: (m.log_time_ns % 1_000_000_000) as u32,
            }
        } else {
            *stamp
        };
        self.sink.set_time(&stamp, frame);
    }

    fn draw(&mut self, m: &BagMessage, frame: i64) -> Result<(), String> {
        let decode_error = |e: BagError| format!("cannot decode: {e}");
        match &*m.type_name {
            Toolpath::ROS_NAME => {
                let toolpath: Toolpath = m.decode().map_err(decode_error)?;
                self.set_time(&toolpath.header.stamp, m, frame);
                self.sink
                    .log_toolpath(toolpath_entity(&toolpath), &toolpath);
            }
            HeatMap::ROS_NAME => {
                let heat: HeatMap = m.decode().map_err(decode_error)?;
                self.set_time(&heat.header.stamp, m, frame);
                let entity = heat_map_entity(&m.topic, &heat);
                self.sink.log_heat_map(&entity, &heat);
                self.sink.log_heat_map_stats(&entity, &heat);
            }
            MachineStatus::ROS_NAME => {
                let status: MachineStatus = m.decode().map_err(decode_error)?;
                self.set_time(&status.header.stamp, m, frame);
                self.machines.log(self.sink, &status);
            }
            MachineProgram::ROS_NAME => {
                let program: MachineProgram = m.decode().map_err(decode_error)?;
                self.set_time(&program.header.stamp, m, frame);
                self.sink
                    .log_text(PROGRAM_LOG, &cell_emitter::program::summary(&program));
                for file in &program.files {
                    let seen = ProgramSeen {
                        job_id: program.job_id.clone(),
                        file: file.name.clone(),
                        lines: file.text.lines().count(),
                    };
                    if !self
                        .programs
                        .iter()
                        .any(|p| (&p.job_id, &p.file) == (&seen.job_id, &seen.file))
                    {
                        self.programs.push(seen);
                    }
                    self.sink.log_text_document(
                        &format!("/programs/{}/{}", program.job_id, file.name),
                        &file.text,
                    );
                }
            }
            ProgramFile::ROS_NAME => {
                let file: ProgramFile = m.decode().map_err(decode_error)?;
                self.set_time(&Time::default(), m, frame);
                self.sink
                    .log_text_document(&format!("{}/{}", m.topic, file.name), &file.text);
            }
            other => {
                let value = decode_json(other, &m.data)
                    .ok_or_else(|| "not a cellsuite message type".to_string())?
                    .map_err(|e| format!("cannot decode: {e}"))?;
                let stamp = header_stamp(&value).unwrap_or_default();
                self.set_time(&stamp, m, frame);
                self.sink.log_text(&m.topic, &text_line(&value));
            }
        }
        Ok(())
    }

    fn report(&mut self) -> Vec<TopicReport> {
        self.order
            .iter()
            .filter_map(|t| self.topics.remove(t))
            .collect()
    }
}

/// `<topic>/<frame_id>`, or the topic when the heat map has no frame: one image per raster
/// source, since a topic may carry several (the planner's root and tip profiles).
pub fn heat_map_entity(topic: &str, heat: &HeatMap) -> String {
    let frame = heat.header.frame_id.trim_matches('/');
    if frame.is_empty() {
        topic.to_owned()
    } else {
        format!("{}/{frame}", topic.trim_end_matches('/'))
    }
}

/// Decodes a message of any cellsuite type to JSON; `None` for a type this suite does not know.
fn decode_json(type_name: &str, data: &[u8]) -> Option<Result<serde_json::Value, String>> {
    fn decode<T: RosMessage>(data: &[u8]) -> Result<serde_json::Value, String> {
        let value = T::decode(data).map_err(|e| e.to_string())?;
        serde_json::to_value(value).map_err(|e| e.to_string())
    }
    macro_rules! by_name {
        ($($ty:ty => $name:literal),* $(,)?) => {
            match type_name {
                $($name => Some(decode::<$ty>(data)),)*
                _ => None,
            }
        };
    }
    cell_msgs::for_each_message!(by_name)
}

/// The `header.stamp` of a decoded message, if it has one.
fn header_stamp(value: &serde_json::Value) -> Option<Time> {
    serde_json::from_value(value.get("header")?.get("stamp")?.clone()).ok()
}

/// One line of compact JSON, cut at [`MAX_TEXT_CHARS`] characters.
fn text_line(value: &serde_json::Value) -> String {
    let text = value.to_string();
    match text.char_indices().nth(MAX_TEXT_CHARS) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_out_is_beside_the_bag() {
        let dir = tempfile::tempdir().unwrap();
        let bag = dir.path().join("run1");
        std::fs::create_dir(&bag).unwrap();
        assert_eq!(default_out(&bag), dir.path().join("run1.rrd"));
        let mut slash = bag.clone().into_os_string();
        slash.push("/");
        assert_eq!(default_out(Path::new(&slash)), dir.path().join("run1.rrd"));
        let file = dir.path().join("run2_0.mcap");
        assert_eq!(default_out(&file), dir.path().join("run2_0.rrd"));
        let here = default_out(Path::new("."));
        assert_eq!(here.extension().unwrap(), "rrd");
        assert_ne!(here.file_name().unwrap(), "..rrd");
    }

    #[test]
    fn heat_maps_are_split_by_frame() {
        let mut heat = HeatMap::default();
        assert_eq!(heat_map_entity("/cell/exposure", &heat), "/cell/exposure");
        heat.header.frame_id = "hotwire_tip".into();
        assert_eq!(
            heat_map_entity("/cell/exposure", &heat),
            "/cell/exposure/hotwire_tip"
        );
    }

    #[test]
    fn other_types_become_json_lines_with_their_stamp() {
        let command = cell_msgs::MachineCommand {
            machine_id: "grbl-sim".into(),
            ..Default::default()
        };
        let value = decode_json(
            cell_msgs::MachineCommand::ROS_NAME,
            &command.encode().unwrap(),
        )
        .expect("a cellsuite type")
        .unwrap();
        assert!(text_line(&value).contains("\"machine_id\":\"grbl-sim\""));
        assert!(decode_json("other_msgs/msg/Thing", &[]).is_none());
        let long = serde_json::Value::String("x".repeat(2 * MAX_TEXT_CHARS));
        assert_eq!(text_line(&long).chars().count(), MAX_TEXT_CHARS + 1);
        let status = MachineStatus {
            header: cell_msgs::std_msgs::Header {
                stamp: Time { sec: 7, nanosec: 9 },
                frame_id: String::new(),
            },
            ..Default::default()
        };
        let value = serde_json::to_value(&status).unwrap();
        assert_eq!(header_stamp(&value), Some(Time { sec: 7, nanosec: 9 }));
    }
}
