//! rosbag2-compatible MCAP bags for cellsuite: a pure library, no DDS.
//!
//! A bag is a directory `NAME/` holding `NAME_0.mcap`, `NAME_1.mcap`, … (one per split) and a
//! `metadata.yaml`, laid out as rosbag2's MCAP storage plugin writes them, so `ros2 bag
//! info/play`, the `mcap` tools and `rosbags` read our bags and we read theirs.
//!
//! - [`BagWriter`] writes messages given as raw CDR (`topic`, ROS type, bytes, time) or typed
//!   ([`cell_msgs::RosMessage`]); see [`writer`] for the MCAP layout and the crash-safety design.
//! - [`BagInfo`] summarises a bag (what `ros2 bag info` prints, via `Display`) and
//!   [`BagReader`] iterates its messages in log-time order across split files.
//! - [`repair()`] makes a bag whose writer was killed readable again.
//! - [`ChunkLimits`] caps what one chunk may decompress to (a hostile file cannot exhaust
//!   memory).
//!
//! Every error names the file it concerns, and the byte offset when one is known; corrupt or
//! truncated input is an error, never a panic.

#![warn(missing_docs)]

use std::path::{Path, PathBuf};

pub mod limits;
pub mod metadata;
pub mod qos;
pub mod reader;
mod record_lengths;
pub mod repair;
mod scan;
pub mod writer;

pub use limits::ChunkLimits;
pub use metadata::{BagMetadata, MetadataFile};
pub use qos::QosProfile;
pub use reader::{BagInfo, BagMessage, BagReader, FileInfo, TopicInfo};
pub use repair::{repair, FileRepair, RepairReport};
pub use writer::{split_file_name, BagWriter, BagWriterOptions};

/// What went wrong with a bag. File-related variants carry the path.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    /// A file could not be read, written or created.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not a valid MCAP where this offset points.
    #[error("{}: at byte {offset}: {reason}", path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// Byte offset in the file (for records inside a chunk: the chunk's offset).
        offset: u64,
        /// What is wrong.
        reason: String,
    },
    /// The file ends before its summary section and footer: the writer did not finish.
    #[error(
        "{}: no summary section ({reason}); the writer did not finish, run repair on the bag",
        path.display()
    )]
    Unfinished {
        /// The file.
        path: PathBuf,
        /// What was found instead.
        reason: String,
    },
    /// `metadata.yaml` is malformed or disagrees with the files.
    #[error("{}: {reason}", path.display())]
    Metadata {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A message type has no known definition (register it with
    /// [`BagWriter::add_topic_with_definition`]).
    #[error("unknown message type `{0}`: no definition in cell_msgs")]
    UnknownType(String),
    /// A topic was used with two different types.
    #[error("topic `{topic}` has type `{existing}`, not `{requested}`")]
    TypeMismatch {
        /// The topic.
        topic: String,
        /// The type it was registered with.
        existing: String,
        /// The type asked for now.
        requested: String,
    },
    /// The output directory exists and is not empty (rosbag2 refuses this too).
    #[error("{}: bag directory exists and is not empty", path.display())]
    Exists {
        /// The directory.
        path: PathBuf,
    },
    /// The writer was used after [`BagWriter::finish`] or after an error that closed a file.
    #[error("bag writer is finished")]
    Finished,
    /// A message could not be serialized or deserialized.
    #[error("{context}: {source}")]
    Cdr {
        /// Topic and type concerned.
        context: String,
        /// The CDR error.
        source: cell_msgs::CdrError,
    },
    /// The MCAP library refused to write.
    #[error("{}: {source}", path.display())]
    Mcap {
        /// The file.
        path: PathBuf,
        /// The library's error.
        source: mcap::McapError,
    },
}

impl BagError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_owned(),
            source,
        }
    }

    pub(crate) fn mcap(path: &Path, source: mcap::McapError) -> Self {
        match source {
            mcap::McapError::Io(source) => Self::io(path, source),
            source => Self::Mcap {
                path: path.to_owned(),
                source,
            },
        }
    }
}

/// Result with [`BagError`].
pub type Result<T, E = BagError> = std::result::Result<T, E>;
