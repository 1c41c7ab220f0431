//! `metadata.yaml`, rosbag2's description of a bag directory.
//!
//! Written in rosbag2's metadata **version 8** layout (`rosbag2_storage/yaml.hpp`, as ROS 2 Iron
//! wrote it and Jazzy reads it): version 5's per-file `files` list, version 6's `custom_data`,
//! version 7's per-topic `type_description_hash` (the REP-2011 `RIHS01_…` hash, from
//! [`cell_msgs::type_hash()`]; empty for a type without one, as rosbag2 writes it) and version 8's
//! `ros_distro`. Version 9, which Jazzy writes, only changes `offered_qos_profiles` from a YAML
//! string with rmw enum integers into a YAML list with policy names; Humble's rosbag2 cannot
//! parse that list, so version 8 is the newest every rosbag2 from Humble on (and `rosbags`)
//! reads. Reading accepts versions 5 to 9 (a version 9 list is kept as its YAML text, which
//! [`crate::qos::from_yaml`] parses).
//!
//! `compression_format`/`compression_mode` are empty strings: the MCAP chunks are compressed
//! inside the file (as rosbag2's MCAP storage does with its zstd presets), so rosbag2's own
//! file/message compression is off. Writing `zstd`/`file` there would make readers try to
//! decompress whole `.mcap` files.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::BagError;

/// The metadata version written.
pub const VERSION: u32 = 8;

/// `ros_distro` written: the distribution whose type hashes (RIHS01) and layouts the bag follows.
pub const ROS_DISTRO: &str = "jazzy";

/// The file name rosbag2 uses.
pub const FILE_NAME: &str = "metadata.yaml";

/// Root of `metadata.yaml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MetadataFile {
    /// The only key.
    pub rosbag2_bagfile_information: BagMetadata,
}

/// `rosbag2_bagfile_information`, field order as rosbag2 writes it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BagMetadata {
    /// Metadata layout version ([`VERSION`]).
    pub version: u32,
    /// Storage plugin: `mcap`.
    pub storage_identifier: String,
    /// Last minus first message time.
    pub duration: Nanoseconds,
    /// First message time.
    pub starting_time: NanosecondsSinceEpoch,
    /// Messages in the whole bag.
    pub message_count: u64,
    /// Every topic with its message count.
    pub topics_with_message_count: Vec<TopicWithMessageCount>,
    /// rosbag2 compression format (empty: see the module docs).
    #[serde(default)]
    pub compression_format: String,
    /// rosbag2 compression mode (empty: see the module docs).
    #[serde(default)]
    pub compression_mode: String,
    /// File names relative to the bag directory, in split order.
    pub relative_file_paths: Vec<String>,
    /// Per-file information, in split order.
    #[serde(default)]
    pub files: Vec<FileInformation>,
    /// User key/value pairs (version 6; none written).
    #[serde(default)]
    pub custom_data: BTreeMap<String, String>,
    /// ROS distribution that wrote the bag (version 8; [`ROS_DISTRO`]).
    #[serde(default)]
    pub ros_distro: String,
}

/// `duration:` (nanoseconds).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Nanoseconds {
    /// Nanoseconds.
    pub nanoseconds: u64,
}

/// `starting_time:` (nanoseconds since the Unix epoch).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct NanosecondsSinceEpoch {
    /// Nanoseconds since the epoch.
    pub nanoseconds_since_epoch: u64,
}

/// One entry of `topics_with_message_count`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TopicWithMessageCount {
    /// The topic.
    pub topic_metadata: TopicMetadata,
    /// Its messages in the whole bag.
    pub message_count: u64,
}

/// `topic_metadata:`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TopicMetadata {
    /// Topic name, e.g. `/cell/toolpath`.
    pub name: String,
    /// ROS 2 type, e.g. `cell_msgs/msg/Toolpath`.
    #[serde(rename = "type")]
    pub type_name: String,
    /// `cdr`.
    pub serialization_format: String,
    /// QoS profiles as a YAML string (see [`crate::qos`]); a version 9 list is read as its text.
    #[serde(default, deserialize_with = "qos_text")]
    pub offered_qos_profiles: String,
    /// REP-2011 type hash `RIHS01_…` (version 7; empty when unknown).
    #[serde(default)]
    pub type_description_hash: String,
}

/// `offered_qos_profiles`: a YAML string up to version 8, a YAML list from version 9.
fn qos_text<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<String, D::Error> {
    match serde_norway::Value::deserialize(deserializer)? {
        serde_norway::Value::String(text) => Ok(text),
        serde_norway::Value::Null => Ok(String::new()),
        list @ serde_norway::Value::Sequence(_) => serde_norway::to_string(&list)
            .map(|text| text.trim_end().to_owned())
            .map_err(serde::de::Error::custom),
        other => Err(serde::de::Error::custom(format!(
            "offered_qos_profiles: expected a string or a list, got {other:?}"
        ))),
    }
}

/// One entry of `files`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileInformation {
    /// File name relative to the bag directory.
    pub path: String,
    /// First message time in this file.
    pub starting_time: NanosecondsSinceEpoch,
    /// Last minus first message time in this file.
    pub duration: Nanoseconds,
    /// Messages in this file.
    pub message_count: u64,
}

impl MetadataFile {
    /// The YAML text.
    pub fn to_yaml(&self) -> String {
        // Plain structs of strings and integers always serialize.
        serde_norway::to_string(self).unwrap_or_default()
    }

    /// Parses `metadata.yaml` text; `path` only names the file in errors.
    pub fn from_yaml(text: &str, path: &Path) -> Result<Self, BagError> {
        serde_norway::from_str(text).map_err(|e| BagError::Metadata {
            path: path.to_owned(),
            reason: e.to_string(),
        })
    }

    /// Reads `dir/metadata.yaml`.
    pub fn read(dir: &Path) -> Result<Self, BagError> {
        let path = dir.join(FILE_NAME);
        let text = std::fs::read_to_string(&path).map_err(|e| BagError::io(&path, e))?;
        Self::from_yaml(&text, &path)
    }

    /// Writes `dir/metadata.yaml` atomically (temporary file, then rename), so a crash leaves
    /// the previous version or the new one, never half a file.
    pub fn write(&self, dir: &Path) -> Result<(), BagError> {
        let path = dir.join(FILE_NAME);
        let tmp = dir.join(format!(".{FILE_NAME}.tmp"));
        std::fs::write(&tmp, self.to_yaml()).map_err(|e| BagError::io(&tmp, e))?;
        std::fs::rename(&tmp, &path).map_err(|e| BagError::io(&path, e))
    }
}

/// Counts of one file, gathered while writing or from its summary.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct FileStats {
    pub name: String,
    pub message_count: u64,
    pub start: Option<u64>,
    pub end: Option<u64>,
}

impl FileStats {
    pub fn new(name: String) -> Self {
        Self {
            name,
            message_count: 0,
            start: None,
            end: None,
        }
    }

    pub fn add(&mut self, log_time: u64) {
        self.message_count += 1;
        self.start = Some(self.start.map_or(log_time, |s| s.min(log_time)));
        self.end = Some(self.end.map_or(log_time, |e| e.max(log_time)));
    }
}

/// One topic across the bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct TopicStats {
    pub name: String,
    pub type_name: String,
    pub qos_yaml: String,
    /// `RIHS01_…`, empty when unknown.
    pub type_hash: String,
    pub message_count: u64,
}

/// `metadata.yaml` for these files (in split order) and topics. A bag or file without
/// messages gets start 0 and duration 0.
pub(crate) fn build(files: &[FileStats], topics: &[TopicStats]) -> MetadataFile {
    let start = files.iter().filter_map(|f| f.start).min();
    let end = files.iter().filter_map(|f| f.end).max();
    let span = |start: Option<u64>, end: Option<u64>| Nanoseconds {
        nanoseconds: end.zip(start).map_or(0, |(e, s)| e.saturating_sub(s)),
    };
    MetadataFile {
        rosbag2_bagfile_information: BagMetadata {
            version: VERSION,
            storage_identifier: "mcap".to_owned(),
            duration: span(start, end),
            starting_time: NanosecondsSinceEpoch {
                nanoseconds_since_epoch: start.unwrap_or(0),
            },
            message_count: files.iter().map(|f| f.message_count).sum(),
            topics_with_message_count: topics
                .iter()
                .map(|t| TopicWithMessageCount {
                    topic_metadata: TopicMetadata {
                        name: t.name.clone(),
                        type_name: t.type_name.clone(),
                        serialization_format: "cdr".to_owned(),
                        offered_qos_profiles: t.qos_yaml.clone(),
                        type_description_hash: t.type_hash.clone(),
                    },
                    message_count: t.message_count,
                })
                .collect(),
            compression_format: String::new(),
            compression_mode: String::new(),
            relative_file_paths: files.iter().map(|f| f.name.clone()).collect(),
            files: files
                .iter()
                .map(|f| FileInformation {
                    path: f.name.clone(),
                    starting_time: NanosecondsSinceEpoch {
                        nanoseconds_since_epoch: f.start.unwrap_or(0),
                    },
                    duration: span(f.start, f.end),
                    message_count: f.message_count,
                })
                .collect(),
            custom_data: BTreeMap::new(),
            ros_distro: ROS_DISTRO.to_owned(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qos::{self, QosProfile};

    fn parse(text: &str) -> BagMetadata {
        MetadataFile::from_yaml(text, Path::new("metadata.yaml"))
            .unwrap_or_else(|e| panic!("{e}"))
            .rosbag2_bagfile_information
    }

    /// A Humble bag (version 5): no hash, no distro, QoS as a string.
    #[test]
    fn reads_version_5() {
        let meta = parse(
            "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  \
             duration:\n    nanoseconds: 10\n  starting_time:\n    nanoseconds_since_epoch: 7\n  \
             message_count: 2\n  topics_with_message_count:\n    - topic_metadata:\n        \
             name: /chatter\n        type: std_msgs/msg/String\n        \
             serialization_format: cdr\n        offered_qos_profiles: \"- history: 1\\n  \
             depth: 10\\n  reliability: 1\\n  durability: 2\\n\"\n      message_count: 2\n  \
             compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n    \
             - b_0.mcap\n  files:\n    - path: b_0.mcap\n      starting_time:\n        \
             nanoseconds_since_epoch: 7\n      duration:\n        nanoseconds: 10\n      \
             message_count: 2\n",
        );
        let topic = &meta.topics_with_message_count[0].topic_metadata;
        assert_eq!(
            (meta.version, topic.type_description_hash.as_str()),
            (5, "")
        );
        assert_eq!(
            qos::from_yaml(&topic.offered_qos_profiles).unwrap(),
            [Some(QosProfile::reliable_volatile(10))]
        );
        assert!(meta.ros_distro.is_empty() && meta.custom_data.is_empty());
    }

    /// A Jazzy bag (version 9, rosbag2 `yaml.hpp`): QoS as a list with policy names.
    #[test]
    fn reads_version_9() {
        let hash = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18";
        let meta = parse(&format!(
            "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: mcap\n  \
             duration:\n    nanoseconds: 10\n  starting_time:\n    nanoseconds_since_epoch: 7\n  \
             message_count: 2\n  topics_with_message_count:\n    - topic_metadata:\n        \
             name: /chatter\n        type: std_msgs/msg/String\n        \
             serialization_format: cdr\n        offered_qos_profiles:\n          \
             - history: keep_last\n            depth: 16\n            reliability: reliable\n            \
             durability: transient_local\n            deadline:\n              sec: 9223372036\n              \
             nsec: 854775807\n            liveliness: automatic\n        \
             type_description_hash: {hash}\n      message_count: 2\n  compression_format: \"\"\n  \
             compression_mode: \"\"\n  relative_file_paths:\n    - b_0.mcap\n  files:\n    \
             - path: b_0.mcap\n      starting_time:\n        nanoseconds_since_epoch: 7\n      \
             duration:\n        nanoseconds: 10\n      message_count: 2\n  custom_data:\n    \
             operator: me\n  ros_distro: jazzy\n"
        ));
        let topic = &meta.topics_with_message_count[0].topic_metadata;
        assert_eq!(
            (meta.version, topic.type_description_hash.as_str()),
            (9, hash)
        );
        assert_eq!(
            qos::from_yaml(&topic.offered_qos_profiles).unwrap(),
            [Some(QosProfile::reliable_transient_local(16))]
        );
        assert_eq!(meta.ros_distro, "jazzy");
        assert_eq!(meta.custom_data["operator"], "me");
    }

    #[test]
    fn writes_version_8_with_hashes() {
        let files = [FileStats::new("b_0.mcap".into())];
        let topics = [TopicStats {
            name: "/toolpath".into(),
            type_name: "cell_msgs/msg/Toolpath".into(),
            qos_yaml: qos::to_yaml(&[QosProfile::default()]),
            type_hash: "RIHS01_00".into(),
            message_count: 0,
        }];
        let text = build(&files, &topics).to_yaml();
        assert!(text.contains("\n  version: 8\n"), "{text}");
        assert!(
            text.contains("\n      type_description_hash: RIHS01_00\n"),
            "{text}"
        );
        assert!(
            text.ends_with("\n  custom_data: {}\n  ros_distro: jazzy\n"),
            "{text}"
        );
        let back = MetadataFile::from_yaml(&text, Path::new("m")).unwrap();
        assert_eq!(back, build(&files, &topics));
    }
}
