//! `metadata.yaml`, rosbag2's description of a bag directory.
//!
//! Written in rosbag2's metadata **version 5** layout (ROS 2 Humble, `metadata_io.cpp`): the
//! last version that needs no RIHS01 type hash (version 7 adds `type_description_hash`, which
//! would need the type-description hashing of rosidl) and the oldest that has the per-file
//! `files` list. rosbag2 Humble and later, and `rosbags`, read it.
//!
//! `compression_format`/`compression_mode` are empty strings: the MCAP chunks are compressed
//! inside the file (as rosbag2's MCAP storage does with its zstd presets), so rosbag2's own
//! file/message compression is off. Writing `zstd`/`file` there would make readers try to
//! decompress whole `.mcap` files.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::BagError;

/// The metadata version written.
pub const VERSION: u32 = 5;

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
    /// QoS profiles as a YAML string (see [`crate::qos`]).
    #[serde(default)]
    pub offered_qos_profiles: String,
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
        },
    }
}
