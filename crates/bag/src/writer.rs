//! [`BagWriter`]: MCAP files as rosbag2's MCAP storage plugin writes them.
//!
//! Per file: header profile `ros2`; one schema per message type (name `pkg/msg/Type`,
//! encoding `ros2msg`, data the complete definition with its dependencies); one channel per
//! topic (message encoding `cdr`, metadata `offered_qos_profiles` and `topic_type_hash`, the
//! REP-2011 hash, as Jazzy's MCAP storage writes them); messages as the CDR bytes
//! seen on the wire, log and publish time in ns, a per-topic sequence number from 1. Records
//! go into zstd chunks with message indexes; `finish` writes the summary (schemas, channels,
//! statistics, chunk indexes, summary offsets) and footer so readers can seek. Each split file
//! is self-contained (its own schemas and channels), as in rosbag2.
//!
//! Crash safety: chunks are built in memory (`mcap`'s no-seek mode) and written whole, then the
//! file buffer is flushed to the kernel. A writer killed at any point (SIGKILL included) thus
//! leaves complete chunks plus at most one partial record at the end; [`crate::repair()`] drops
//! that tail and adds the summary. A chunk is closed when its uncompressed size reaches
//! [`BagWriterOptions::chunk_size`] or when it spans [`BagWriterOptions::max_chunk_duration`] of
//! log time, which bounds what a crash can lose on slow topics.
//!
//! Splitting follows rosbag2: before a message is written, the current file is closed if its
//! size on disk reached `max_file_size` or the message's log time is `max_file_duration` or more
//! after the file's first message. Size counts written chunks only, so a file can exceed the
//! limit by up to one chunk (rosbag2's MCAP storage behaves the same).

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use cell_msgs::RosMessage;

use crate::metadata::{self, MetadataFile};
use crate::qos::{self, QosProfile};
use crate::{BagError, Result};

/// The header's library string.
pub const LIBRARY: &str = concat!("cellsuite cell_bag ", env!("CARGO_PKG_VERSION"));

/// Channel metadata key rosbag2 stores the QoS profiles under.
pub const QOS_KEY: &str = "offered_qos_profiles";

/// Channel metadata key rosbag2's MCAP storage (Jazzy, `mcap_storage.cpp`) stores the topic's
/// REP-2011 type hash under (the schema carries none there).
pub const TYPE_HASH_KEY: &str = "topic_type_hash";

/// How a bag is written.
#[derive(Debug, Clone)]
pub struct BagWriterOptions {
    /// Close a chunk once its uncompressed records reach this many bytes.
    pub chunk_size: u64,
    /// Close a chunk once it spans this much log time (bounds what a crash loses).
    pub max_chunk_duration: Option<Duration>,
    /// Start a new file once the current one reaches this many bytes on disk.
    pub max_file_size: Option<u64>,
    /// Start a new file once a message is this much log time after the file's first one.
    pub max_file_duration: Option<Duration>,
    /// zstd level (0: zstd's default, 3).
    pub compression_level: u32,
}

impl Default for BagWriterOptions {
    fn default() -> Self {
        Self {
            chunk_size: 1024 * 1024,
            max_chunk_duration: Some(Duration::from_secs(1)),
            max_file_size: None,
            max_file_duration: None,
            compression_level: 0,
        }
    }
}

/// The name rosbag2 gives split file `index` of bag `bag_name`: `<bag_name>_<index>.mcap`.
pub fn split_file_name(bag_name: &str, index: usize) -> String {
    format!("{bag_name}_{index}.mcap")
}

/// A topic of the bag.
struct Topic {
    name: String,
    type_name: String,
    definition: String,
    qos_yaml: String,
    /// `RIHS01_…` from [`cell_msgs::type_hash()`], empty for a type it does not know.
    type_hash: String,
    count: u64,
    sequence: u32,
}

/// Counts bytes handed to the file so the size split needs no `stat`; positions are tracked
/// here because the MCAP writer only appends and asks for the current position.
struct CountingFile {
    inner: BufWriter<File>,
    written: Arc<AtomicU64>,
}

impl Write for CountingFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.written.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

impl Seek for CountingFile {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        match pos {
            SeekFrom::Current(0) => Ok(self.written.load(Ordering::Relaxed)),
            other => {
                let at = self.inner.seek(other)?;
                self.written.store(at, Ordering::Relaxed);
                Ok(at)
            }
        }
    }
}

/// The file being written.
struct OpenFile {
    path: PathBuf,
    writer: mcap::Writer<CountingFile>,
    written: Arc<AtomicU64>,
    /// Topic index → channel id in this file.
    channels: HashMap<usize, u16>,
    /// Topic type → schema id in this file.
    schemas: HashMap<String, u16>,
    /// Uncompressed bytes in the open chunk.
    chunk_bytes: u64,
    chunk_start: Option<u64>,
    stats: metadata::FileStats,
}

/// Writes a rosbag2 MCAP bag directory. See the [module docs](self) for the format.
pub struct BagWriter {
    dir: PathBuf,
    name: String,
    options: BagWriterOptions,
    topics: Vec<Topic>,
    by_name: HashMap<String, usize>,
    file: Option<OpenFile>,
    done_files: Vec<metadata::FileStats>,
    finished: Option<MetadataFile>,
}

impl BagWriter {
    /// Creates the bag directory `dir` (its last component names the bag and its files).
    /// Fails if `dir` exists and is not empty.
    pub fn create(dir: impl AsRef<Path>, options: BagWriterOptions) -> Result<Self> {
        let dir = dir.as_ref().to_owned();
        if let Ok(mut entries) = std::fs::read_dir(&dir) {
            if entries.next().is_some() {
                return Err(BagError::Exists { path: dir });
            }
        }
        std::fs::create_dir_all(&dir).map_err(|e| BagError::io(&dir, e))?;
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| "rosbag2".to_owned());
        let mut writer = Self {
            dir,
            name,
            options,
            topics: Vec::new(),
            by_name: HashMap::new(),
            file: None,
            done_files: Vec::new(),
            finished: None,
        };
        writer.open_file()?;
        Ok(writer)
    }

    /// The bag directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Registers `topic` with a `cell_msgs` type and its publishers' QoS profiles. Optional:
    /// the first write registers a topic with [`QosProfile::default`]. Registering an existing
    /// topic again with the same type is a no-op.
    pub fn add_topic(&mut self, topic: &str, ros_type: &str, qos: &[QosProfile]) -> Result<()> {
        if let Some(&i) = self.by_name.get(topic) {
            return self.check_type(i, ros_type).map(|_| ());
        }
        let definition = cell_msgs::registry::full_definition(ros_type)
            .map_err(|_| BagError::UnknownType(ros_type.to_owned()))?;
        self.add_topic_with_definition(topic, ros_type, &definition, qos)
    }

    /// Registers `topic` with a type this crate does not know, given its complete `ros2msg`
    /// definition (the `.msg` text, then each dependency after a line of 80 `=` and
    /// `MSG: pkg/msg/Type`).
    pub fn add_topic_with_definition(
        &mut self,
        topic: &str,
        ros_type: &str,
        definition: &str,
        qos: &[QosProfile],
    ) -> Result<()> {
        if let Some(&i) = self.by_name.get(topic) {
            return self.check_type(i, ros_type).map(|_| ());
        }
        self.by_name.insert(topic.to_owned(), self.topics.len());
        self.topics.push(Topic {
            name: topic.to_owned(),
            type_name: ros_type.to_owned(),
            definition: definition.to_owned(),
            qos_yaml: qos::to_yaml(qos),
            type_hash: cell_msgs::type_hash(ros_type)
                .map(|h| h.to_string())
                .unwrap_or_default(),
            count: 0,
            sequence: 0,
        });
        Ok(())
    }

    fn check_type(&self, i: usize, ros_type: &str) -> Result<usize> {
        let existing = &self.topics[i].type_name;
        if existing != ros_type {
            return Err(BagError::TypeMismatch {
                topic: self.topics[i].name.clone(),
                existing: existing.clone(),
                requested: ros_type.to_owned(),
            });
        }
        Ok(i)
    }

    /// Writes a typed message; the bytes are those [`RosMessage::encode`] puts on the wire.
    pub fn write<T: RosMessage>(&mut self, topic: &str, msg: &T, log_time_ns: u64) -> Result<()> {
        let bytes = msg.encode().map_err(|source| BagError::Cdr {
            context: format!("{topic} ({})", T::ROS_NAME),
            source,
        })?;
        self.write_raw(topic, T::ROS_NAME, &bytes, log_time_ns)
    }

    /// Writes a serialized message (4-byte encapsulation header + CDR body) received at
    /// `log_time_ns` (ns since the epoch); publish time is the same.
    pub fn write_raw(
        &mut self,
        topic: &str,
        ros_type: &str,
        cdr: &[u8],
        log_time_ns: u64,
    ) -> Result<()> {
        self.write_raw_published(topic, ros_type, cdr, log_time_ns, log_time_ns)
    }

    /// Like [`Self::write_raw`] with a separate publish time (e.g. the DDS source timestamp).
    pub fn write_raw_published(
        &mut self,
        topic: &str,
        ros_type: &str,
        cdr: &[u8],
        log_time_ns: u64,
        publish_time_ns: u64,
    ) -> Result<()> {
        if self.finished.is_some() {
            return Err(BagError::Finished);
        }
        let topic_index = match self.by_name.get(topic) {
            Some(&i) => self.check_type(i, ros_type)?,
            None => {
                self.add_topic(topic, ros_type, &[QosProfile::default()])?;
                self.topics.len() - 1
            }
        };
        self.maybe_split(log_time_ns)?;
        let channel = self.channel(topic_index)?;
        let t = &mut self.topics[topic_index];
        t.sequence = t.sequence.wrapping_add(1);
        t.count += 1;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: t.sequence,
            log_time: log_time_ns,
            publish_time: publish_time_ns,
        };
        let file = self.file.as_mut().ok_or(BagError::Finished)?;
        file.writer
            .write_to_known_channel(&header, cdr)
            .map_err(|e| BagError::mcap(&file.path, e))?;
        file.stats.add(log_time_ns);
        // Message record: opcode, length, channel, sequence, two times, data.
        file.chunk_bytes += 31 + cdr.len() as u64;
        let chunk_start = *file.chunk_start.get_or_insert(log_time_ns);
        let too_long = self
            .options
            .max_chunk_duration
            .is_some_and(|d| log_time_ns.saturating_sub(chunk_start) >= d.as_nanos() as u64);
        if file.chunk_bytes >= self.options.chunk_size || too_long {
            // Writes the chunk and its message indexes and hands them to the kernel.
            file.writer
                .flush()
                .map_err(|e| BagError::mcap(&file.path, e))?;
            file.chunk_bytes = 0;
            file.chunk_start = None;
        }
        Ok(())
    }

    /// The channel of a topic in the current file, registering schema and channel on first use.
    fn channel(&mut self, topic_index: usize) -> Result<u16> {
        let file = self.file.as_mut().ok_or(BagError::Finished)?;
        if let Some(&id) = file.channels.get(&topic_index) {
            return Ok(id);
        }
        let t = &self.topics[topic_index];
        let schema = match file.schemas.get(&t.type_name) {
            Some(&id) => id,
            None => {
                let id = file
                    .writer
                    .add_schema(&t.type_name, "ros2msg", t.definition.as_bytes())
                    .map_err(|e| BagError::mcap(&file.path, e))?;
                file.schemas.insert(t.type_name.clone(), id);
                file.chunk_bytes += (t.definition.len() + t.type_name.len() + 23) as u64;
                id
            }
        };
        let metadata = BTreeMap::from([
            (QOS_KEY.to_owned(), t.qos_yaml.clone()),
            (TYPE_HASH_KEY.to_owned(), t.type_hash.clone()),
        ]);
        let id = file
            .writer
            .add_channel(schema, &t.name, "cdr", &metadata)
            .map_err(|e| BagError::mcap(&file.path, e))?;
        file.chunk_bytes += (t.name.len() + t.qos_yaml.len() + t.type_hash.len() + 60) as u64;
        file.channels.insert(topic_index, id);
        Ok(id)
    }

    fn maybe_split(&mut self, log_time_ns: u64) -> Result<()> {
        let Some(file) = &self.file else {
            return Err(BagError::Finished);
        };
        if file.stats.message_count == 0 {
            return Ok(());
        }
        let size = self
            .options
            .max_file_size
            .is_some_and(|max| file.written.load(Ordering::Relaxed) >= max);
        let duration = match (self.options.max_file_duration, file.stats.start) {
            (Some(max), Some(start)) => log_time_ns.saturating_sub(start) >= max.as_nanos() as u64,
            _ => false,
        };
        if size || duration {
            self.close_file()?;
            // Keeps metadata.yaml current, so a crash later leaves the closed files described.
            self.metadata().write(&self.dir)?;
            self.open_file()?;
        }
        Ok(())
    }

    fn open_file(&mut self) -> Result<()> {
        let index = self.done_files.len();
        let name = split_file_name(&self.name, index);
        let path = self.dir.join(&name);
        let file = File::create(&path).map_err(|e| BagError::io(&path, e))?;
        let written = Arc::new(AtomicU64::new(0));
        let sink = CountingFile {
            inner: BufWriter::with_capacity(1 << 16, file),
            written: written.clone(),
        };
        let options = mcap::WriteOptions::new()
            .profile("ros2")
            .library(LIBRARY)
            .compression(Some(mcap::Compression::Zstd))
            .compression_level(self.options.compression_level)
            // Chunks in memory, written whole: see the module docs on crash safety.
            .disable_seeking(true)
            .chunk_size(None)
            // One thread: the recorder shares the machine with the nodes it records.
            .compression_threads(0);
        let writer = options.create(sink).map_err(|e| BagError::mcap(&path, e))?;
        self.file = Some(OpenFile {
            path,
            writer,
            written,
            channels: HashMap::new(),
            schemas: HashMap::new(),
            chunk_bytes: 0,
            chunk_start: None,
            stats: metadata::FileStats::new(name),
        });
        Ok(())
    }

    fn close_file(&mut self) -> Result<()> {
        let Some(mut file) = self.file.take() else {
            return Ok(());
        };
        file.writer
            .finish()
            .map_err(|e| BagError::mcap(&file.path, e))?;
        let mut sink = file.writer.into_inner();
        sink.flush().map_err(|e| BagError::io(&file.path, e))?;
        sink.inner
            .get_ref()
            .sync_all()
            .map_err(|e| BagError::io(&file.path, e))?;
        self.done_files.push(file.stats);
        Ok(())
    }

    /// The metadata as it stands (closed files, the open one, every topic).
    fn metadata(&self) -> MetadataFile {
        let files: Vec<metadata::FileStats> = self
            .done_files
            .iter()
            .chain(self.file.as_ref().map(|f| &f.stats))
            .cloned()
            .collect();
        let topics: Vec<metadata::TopicStats> = self
            .topics
            .iter()
            .map(|t| metadata::TopicStats {
                name: t.name.clone(),
                type_name: t.type_name.clone(),
                qos_yaml: t.qos_yaml.clone(),
                type_hash: t.type_hash.clone(),
                message_count: t.count,
            })
            .collect();
        metadata::build(&files, &topics)
    }

    /// Closes the current file (summary and footer) and writes `metadata.yaml`. Idempotent;
    /// writing afterwards is an error.
    pub fn finish(&mut self) -> Result<&MetadataFile> {
        if self.finished.is_none() {
            self.close_file()?;
            let metadata = self.metadata();
            metadata.write(&self.dir)?;
            self.finished = Some(metadata);
        }
        self.finished.as_ref().ok_or(BagError::Finished)
    }
}

impl Drop for BagWriter {
    /// Finishes the bag if [`BagWriter::finish`] was not called; errors are lost here, so call
    /// `finish` to see them.
    fn drop(&mut self) {
        let _ = self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_names_are_rosbag2s() {
        assert_eq!(split_file_name("run", 0), "run_0.mcap");
        assert_eq!(
            split_file_name("rosbag2_2026_11_22", 12),
            "rosbag2_2026_11_22_12.mcap"
        );
    }
}
