//! The `recorder` node: writes the cell's topics to a rosbag2-compatible MCAP bag
//! ([`cell_bag::BagWriter`]).
//!
//! Every `discover_every_s` it lists the topics the graph's writers publish
//! ([`CellNode::published_topics`]); each new one whose name matches a `topics` pattern and no
//! `exclude` pattern, and whose type is a `cell_msgs` or standard type this suite knows, gets a
//! subscription with the QoS its writers offer (transient-local plans, best-effort streams,
//! reliable status), so nothing a late join can still get is missed. Large heat maps arriving
//! over the iceoryx2 fast path are recorded like any other message. Messages are written as the
//! CDR they travel as (the Rust types mirror the definitions exactly; the drift test checks
//! that), stamped with their receive time. On shutdown the bag is finished (summary section,
//! `metadata.yaml`); if the process is killed instead, `cell bag repair` restores it.

use std::collections::BTreeSet;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use anyhow::Context as _;
use cell_bag::{BagWriter, BagWriterOptions, QosProfile};
use cell_runtime::graph::PublishedTopic;
use cell_runtime::{CellNode, NodeParamError, QosPreset};
use serde::{Deserialize, Serialize};
use tokio::sync::mpsc;

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RecorderParams {
    /// The bag directory to create (must not exist, or be empty).
    pub output: String,
    /// Regular expressions for the topics to record (whole-name match).
    pub topics: Vec<String>,
    /// Regular expressions for topics never to record.
    pub exclude: Vec<String>,
    /// Split past this size (MB); 0: never.
    pub max_file_size_mb: f64,
    /// Split past this span (s); 0: never.
    pub max_file_duration_s: f64,
    /// How often to look for new topics (s).
    pub discover_every_s: f64,
}

impl Default for RecorderParams {
    fn default() -> Self {
        RecorderParams {
            output: "bag".into(),
            topics: vec![".*".into()],
            exclude: vec!["/rosout".into(), "/parameter_events".into()],
            max_file_size_mb: 0.0,
            max_file_duration_s: 0.0,
            discover_every_s: 0.5,
        }
    }
}

/// Which topics to record.
#[derive(Debug, Clone)]
pub struct TopicFilter {
    include: Vec<regex::Regex>,
    exclude: Vec<regex::Regex>,
}

impl TopicFilter {
    /// Compiles the patterns (each must match the whole name).
    ///
    /// # Errors
    /// A pattern that is not a regular expression, named with its parameter and index.
    pub fn new(include: &[String], exclude: &[String]) -> Result<Self, NodeParamError> {
        let compile = |field: &str, list: &[String]| {
            list.iter()
                .enumerate()
                .map(|(i, p)| {
                    regex::Regex::new(&format!("^(?:{p})$"))
                        .map_err(|e| NodeParamError(format!("{field}[{i}]: {p:?}: {e}")))
                })
                .collect::<Result<Vec<_>, _>>()
        };
        Ok(TopicFilter {
            include: compile("topics", include)?,
            exclude: compile("exclude", exclude)?,
        })
    }

    /// Whether `topic` is recorded.
    pub fn wants(&self, topic: &str) -> bool {
        self.include.iter().any(|r| r.is_match(topic))
            && !self.exclude.iter().any(|r| r.is_match(topic))
    }
}

/// One received message, as it goes into the bag.
struct Sample {
    topic: String,
    ros_type: String,
    cdr: Vec<u8>,
    log_time_ns: u64,
}

fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}

/// The bag's record of a preset's QoS (what the writers offer).
fn bag_qos(preset: QosPreset) -> QosProfile {
    match preset {
        QosPreset::Plan => {
            QosProfile::reliable_transient_local(cell_runtime::qos::PLAN_HISTORY_DEPTH as u32)
        }
        QosPreset::Stream | QosPreset::Clock => QosProfile::best_effort(1),
        QosPreset::Status => QosProfile::reliable_volatile(32),
    }
}

/// Subscribes to `found` with its Rust type and forwards every message to `tx` as CDR.
/// `None` for a type this suite does not know (it cannot be decoded to be re-encoded).
macro_rules! subscribe_known {
    ($($ty:ty => $name:literal),* $(,)?) => {
        fn subscribe(
            node: &CellNode,
            found: &PublishedTopic,
            tx: mpsc::UnboundedSender<Sample>,
        ) -> Option<anyhow::Result<tokio::task::JoinHandle<()>>> {
            match found.ros_type.as_str() {
                $($name => Some(forward::<$ty>(node, found, tx)),)*
                _ => None,
            }
        }
    };
}
cell_msgs::for_each_message!(subscribe_known);

fn forward<T: cell_msgs::RosMessage>(
    node: &CellNode,
    found: &PublishedTopic,
    tx: mpsc::UnboundedSender<Sample>,
) -> anyhow::Result<tokio::task::JoinHandle<()>> {
    let mut sub = node.subscriber::<T>(&found.topic, found.qos)?;
    let (topic, ros_type) = (found.topic.clone(), found.ros_type.clone());
    Ok(tokio::spawn(async move {
        while let Some(r) = sub.recv().await {
            let log_time_ns = now_ns();
            match cell_msgs::to_cdr(&r.message) {
                Ok(cdr) => {
                    let sample = Sample {
                        topic: topic.clone(),
                        ros_type: ros_type.clone(),
                        cdr,
                        log_time_ns,
                    };
                    if tx.send(sample).is_err() {
                        return;
                    }
                }
                Err(e) => tracing::warn!("{topic}: not recorded: {e}"),
            }
        }
    }))
}

/// Records until shutdown, then finishes the bag.
///
/// # Errors
/// Bad parameters ([`NodeParamError`], exit 64); a bag that cannot be created or written.
pub async fn run(node: CellNode, p: RecorderParams) -> anyhow::Result<()> {
    let filter = TopicFilter::new(&p.topics, &p.exclude)?;
    if !(p.discover_every_s.is_finite() && p.discover_every_s > 0.0) {
        return Err(NodeParamError(format!(
            "discover_every_s: {}: expected > 0",
            p.discover_every_s
        ))
        .into());
    }
    let positive = |v: f64, field: &str| -> Result<Option<f64>, NodeParamError> {
        if v == 0.0 {
            Ok(None)
        } else if v.is_finite() && v > 0.0 {
            Ok(Some(v))
        } else {
            Err(NodeParamError(format!(
                "{field}: {v}: expected > 0, or 0 for never"
            )))
        }
    };
    let options = BagWriterOptions {
        max_file_size: positive(p.max_file_size_mb, "max_file_size_mb")?
            .map(|mb| (mb * 1e6) as u64),
        max_file_duration: positive(p.max_file_duration_s, "max_file_duration_s")?
            .map(Duration::from_secs_f64),
        ..BagWriterOptions::default()
    };
    let mut writer =
        BagWriter::create(&p.output, options).with_context(|| format!("output {}", p.output))?;
    tracing::info!("recording to {}", writer.dir().display());
    let (tx, mut rx) = mpsc::unbounded_channel::<Sample>();
    let mut recorded: BTreeSet<String> = BTreeSet::new();
    let mut skipped: BTreeSet<String> = BTreeSet::new();
    let mut tasks = Vec::new();
    let mut discover = tokio::time::interval(Duration::from_secs_f64(p.discover_every_s));
    let mut count = 0u64;
    loop {
        tokio::select! {
            _ = discover.tick() => {
                for found in node.published_topics() {
                    if recorded.contains(&found.topic) || skipped.contains(&found.topic) || !filter.wants(&found.topic) {
                        continue;
                    }
                    match subscribe(&node, &found, tx.clone()) {
                        Some(Ok(task)) => {
                            writer.add_topic(&found.topic, &found.ros_type, &[bag_qos(found.qos)])?;
                            tracing::info!("recording {} ({})", found.topic, found.ros_type);
                            recorded.insert(found.topic.clone());
                            tasks.push(task);
                        }
                        Some(Err(e)) => tracing::warn!("{}: cannot subscribe: {e:#}", found.topic),
                        None => {
                            tracing::warn!("{}: type {} is not known here; not recorded", found.topic, found.ros_type);
                            skipped.insert(found.topic);
                        }
                    }
                }
            }
            Some(s) = rx.recv() => {
                writer.write_raw(&s.topic, &s.ros_type, &s.cdr, s.log_time_ns)?;
                count += 1;
            }
            _ = node.shutdown().requested() => break,
        }
    }
    for t in tasks {
        t.abort();
    }
    // What already arrived is kept.
    while let Ok(s) = rx.try_recv() {
        writer.write_raw(&s.topic, &s.ros_type, &s.cdr, s.log_time_ns)?;
        count += 1;
    }
    writer.finish()?;
    tracing::info!(
        "recorded {count} messages on {} topics to {}",
        recorded.len(),
        writer.dir().display()
    );
    Ok(())
}

/// The `recorder` binary (also `cell node recorder`).
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("recorder", argv, run)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_params_file_parses_and_matches_the_defaults() {
        let mut sources = cell_runtime::params::ParamSources::default();
        let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/recorder.yaml");
        sources
            .merge_file(std::path::Path::new(file), "/", "recorder")
            .unwrap();
        let p: RecorderParams = sources.parse().unwrap();
        assert_eq!(p, RecorderParams::default());
    }

    #[test]
    fn topics_match_whole_names_and_bad_patterns_are_named() {
        let f = TopicFilter::new(&["/cell/.*".into()], &["/cell/heat_.*".into()]).unwrap();
        assert!(f.wants("/cell/toolpath"));
        assert!(!f.wants("/cell/heat_map"));
        assert!(!f.wants("/other/cell/toolpath"));
        let e = TopicFilter::new(&["(".into()], &[]).unwrap_err().0;
        assert!(e.starts_with("topics[0]"), "{e}");
    }
}
