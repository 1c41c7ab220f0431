//! Reading bags: [`BagInfo`] (what `ros2 bag info` shows) and [`BagReader`] (messages in
//! log-time order across split files).
//!
//! A bag is a directory (its files from `metadata.yaml`, else every `*_N.mcap` in split order)
//! or a single `.mcap`. Everything is taken from each file's summary section, so opening a bag
//! reads only footers and indexes; a file without one (a killed writer) is refused with an
//! error that says to run [`crate::repair()`]. Only chunked files are read (rosbag2 and this
//! crate always chunk).
//!
//! Messages are merged across files and chunks by log time: chunks are loaded in order of
//! their first message time, only while the earliest pending message could be preceded by
//! them, so memory holds the overlapping chunks, not the bag. Equal times keep file order.

use std::cmp::Ordering as CmpOrdering;
use std::collections::{BinaryHeap, HashMap};
use std::fmt;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use cell_msgs::RosMessage;
use mcap::records::op;

use crate::limits::ChunkLimits;
use crate::metadata::{self, MetadataFile};
use crate::scan::{self, Item, ScanError, MAGIC};
use crate::writer::{QOS_KEY, TYPE_HASH_KEY};
use crate::{BagError, Result};

/// One file of a bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileInfo {
    /// Its path.
    pub path: PathBuf,
    /// Size in bytes.
    pub size: u64,
    /// Messages in it.
    pub message_count: u64,
    /// First and last message log time (ns), if it has messages.
    pub time_range: Option<(u64, u64)>,
    /// Chunks in it.
    pub chunk_count: u32,
}

/// One topic of a bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    /// Topic name.
    pub name: String,
    /// ROS 2 type, e.g. `cell_msgs/msg/Toolpath`.
    pub type_name: String,
    /// Messages over all files.
    pub message_count: u64,
    /// Message encoding (`cdr`).
    pub serialization_format: String,
    /// Offered QoS profiles as the stored YAML string (see [`crate::qos::from_yaml`]).
    pub offered_qos_profiles: String,
    /// REP-2011 type hash `RIHS01_…` from the channel's `topic_type_hash` (as rosbag2 Jazzy
    /// writes it); empty when the bag has none (older bags, types without a hash).
    pub type_hash: String,
}

/// A bag's summary.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BagInfo {
    /// The bag directory or file given.
    pub path: PathBuf,
    /// Storage identifier (`mcap`).
    pub storage: String,
    /// Files in split order.
    pub files: Vec<FileInfo>,
    /// Topics in order of first appearance.
    pub topics: Vec<TopicInfo>,
    /// Messages over all files.
    pub message_count: u64,
    /// First and last message log time (ns), if there are messages.
    pub time_range: Option<(u64, u64)>,
    /// Total size of the files in bytes.
    pub size: u64,
}

impl BagInfo {
    /// Reads the summary of a bag directory or a single `.mcap` file.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        Ok(BagReader::open(path)?.info)
    }

    /// Duration from the first to the last message, in ns.
    pub fn duration_ns(&self) -> u64 {
        self.time_range.map_or(0, |(s, e)| e - s)
    }
}

/// The files of a bag, in split order: those `metadata.yaml` lists, then any other `*.mcap`
/// (see [`mcap_files_in`]).
pub(crate) fn bag_files(dir: &Path) -> Result<Vec<PathBuf>> {
    if dir.join(metadata::FILE_NAME).exists() {
        let meta = MetadataFile::read(dir)?;
        let mut files: Vec<PathBuf> = meta
            .rosbag2_bagfile_information
            .relative_file_paths
            .iter()
            .map(|p| dir.join(Path::new(p).file_name().unwrap_or_default()))
            .collect();
        if let Some(missing) = files.iter().find(|p| !p.exists()) {
            return Err(BagError::Metadata {
                path: dir.join(metadata::FILE_NAME),
                reason: format!("lists {}, which does not exist", missing.display()),
            });
        }
        // Files the metadata does not list yet (opened after it was last written, e.g. by a
        // writer that was killed) are part of the bag too.
        for p in mcap_files_in(dir)? {
            if !files.contains(&p) {
                files.push(p);
            }
        }
        return Ok(files);
    }
    mcap_files_in(dir)
}

/// Every `*.mcap` of `dir`: `*_N.mcap` ordered by `N`, then the others by name.
pub(crate) fn mcap_files_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files: Vec<(bool, Option<u64>, PathBuf)> = std::fs::read_dir(dir)
        .map_err(|e| BagError::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
        .map(|p| (split_index(&p).is_none(), split_index(&p), p))
        .collect();
    files.sort();
    Ok(files.into_iter().map(|(_, _, p)| p).collect())
}

/// `N` of `name_N.mcap`.
fn split_index(path: &Path) -> Option<u64> {
    let stem = path.file_stem()?.to_str()?;
    stem.rsplit_once('_')?.1.parse().ok()
}

/// One message read from a bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BagMessage {
    /// Topic name.
    pub topic: Arc<str>,
    /// ROS 2 type name.
    pub type_name: Arc<str>,
    /// Log (receive) time, ns since the epoch.
    pub log_time_ns: u64,
    /// Publish time, ns since the epoch.
    pub publish_time_ns: u64,
    /// Sequence number on its channel.
    pub sequence: u32,
    /// The serialized message (encapsulation header + CDR), as written.
    pub data: Vec<u8>,
}

impl BagMessage {
    /// Decodes the message as `T`; fails if the bag says it is another type.
    pub fn decode<T: RosMessage>(&self) -> Result<T> {
        let context = || format!("{} ({})", self.topic, self.type_name);
        if &*self.type_name != T::ROS_NAME {
            return Err(BagError::TypeMismatch {
                topic: self.topic.to_string(),
                existing: self.type_name.to_string(),
                requested: T::ROS_NAME.to_owned(),
            });
        }
        T::decode(&self.data).map_err(|source| BagError::Cdr {
            context: context(),
            source,
        })
    }
}

/// A channel as the reader needs it.
#[derive(Debug, Clone)]
struct ChannelRef {
    topic: Arc<str>,
    type_name: Arc<str>,
}

/// An open file of the bag.
struct BagFile {
    path: PathBuf,
    file: File,
    len: u64,
    channels: HashMap<u16, ChannelRef>,
}

/// A chunk to load.
struct ChunkRef {
    file: usize,
    start_time: u64,
    offset: u64,
    length: u64,
}

/// Reads a bag's messages; see the [module docs](self).
pub struct BagReader {
    info: BagInfo,
    files: Vec<BagFile>,
    chunks: Vec<ChunkRef>,
    limits: ChunkLimits,
}

impl BagReader {
    /// Opens a bag directory or a single `.mcap` file and reads its summaries.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let paths = if path.is_dir() {
            bag_files(path)?
        } else {
            vec![path.to_owned()]
        };
        let mut files = Vec::new();
        let mut chunks = Vec::new();
        let mut file_infos = Vec::new();
        let mut topics: Vec<TopicInfo> = Vec::new();
        for (index, p) in paths.iter().enumerate() {
            let (file, summary) = open_summary(p)?;
            let stats = summary.stats.clone().ok_or_else(|| BagError::Corrupt {
                path: p.clone(),
                offset: file.1,
                reason: "summary has no statistics record".into(),
            })?;
            // Durations are end − start; a file that says otherwise is refused, not trusted.
            if stats.message_count > 0 && stats.message_start_time > stats.message_end_time {
                return Err(BagError::Corrupt {
                    path: p.clone(),
                    offset: file.1,
                    reason: format!(
                        "statistics record: message_start_time {} is after message_end_time {}",
                        stats.message_start_time, stats.message_end_time
                    ),
                });
            }
            let mut channels = HashMap::new();
            let mut ids: Vec<&u16> = summary.channels.keys().collect();
            ids.sort();
            for id in ids {
                let c = &summary.channels[id];
                let type_name = c.schema.as_ref().map_or("", |s| s.name.as_str());
                let count = stats.channel_message_counts.get(id).copied().unwrap_or(0);
                match topics.iter_mut().find(|t| t.name == c.topic) {
                    Some(t) => t.message_count += count,
                    None => topics.push(TopicInfo {
                        name: c.topic.clone(),
                        type_name: type_name.to_owned(),
                        message_count: count,
                        serialization_format: c.message_encoding.clone(),
                        offered_qos_profiles: c.metadata.get(QOS_KEY).cloned().unwrap_or_default(),
                        type_hash: c.metadata.get(TYPE_HASH_KEY).cloned().unwrap_or_default(),
                    }),
                }
                channels.insert(
                    *id,
                    ChannelRef {
                        topic: c.topic.as_str().into(),
                        type_name: type_name.into(),
                    },
                );
            }
            for ci in &summary.chunk_indexes {
                chunks.push(ChunkRef {
                    file: index,
                    start_time: ci.message_start_time,
                    offset: ci.chunk_start_offset,
                    length: ci.chunk_length,
                });
            }
            file_infos.push(FileInfo {
                path: p.clone(),
                size: file.1,
                message_count: stats.message_count,
                time_range: (stats.message_count > 0)
                    .then_some((stats.message_start_time, stats.message_end_time)),
                chunk_count: stats.chunk_count,
            });
            files.push(BagFile {
                path: p.clone(),
                file: file.0,
                len: file.1,
                channels,
            });
        }
        // Stable: equal start times keep file and offset order.
        chunks.sort_by_key(|c| c.start_time);
        let time_range = file_infos
            .iter()
            .filter_map(|f| f.time_range)
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)));
        let info = BagInfo {
            path: path.to_owned(),
            storage: "mcap".into(),
            message_count: file_infos.iter().map(|f| f.message_count).sum(),
            size: file_infos.iter().map(|f| f.size).sum(),
            files: file_infos,
            topics,
            time_range,
        };
        Ok(Self {
            info,
            files,
            chunks,
            limits: ChunkLimits::default(),
        })
    }

    /// Holds every chunk read from now on to `limits` instead of [`ChunkLimits::default`].
    pub fn with_limits(mut self, limits: ChunkLimits) -> Self {
        self.limits = limits;
        self
    }

    /// The bag's summary.
    pub fn info(&self) -> &BagInfo {
        &self.info
    }

    /// Every message in log-time order. After an error the iterator ends.
    pub fn messages(&mut self) -> Messages<'_> {
        Messages {
            reader: self,
            next_chunk: 0,
            heap: BinaryHeap::new(),
            ordinal: 0,
            failed: false,
        }
    }

    /// Reads, checks and decodes one chunk.
    fn load_chunk(&mut self, chunk: usize) -> Result<Vec<BagMessage>> {
        let ChunkRef {
            file,
            offset,
            length,
            ..
        } = self.chunks[chunk];
        let f = &mut self.files[file];
        let corrupt = |offset: u64, reason: String| BagError::Corrupt {
            path: f.path.clone(),
            offset,
            reason,
        };
        if offset.checked_add(length).is_none_or(|end| end > f.len) || length < 9 {
            return Err(corrupt(
                offset,
                format!(
                    "chunk index points past the end of the file ({} bytes)",
                    f.len
                ),
            ));
        }
        let mut buf = vec![0; length as usize];
        f.file
            .seek(SeekFrom::Start(offset))
            .and_then(|_| f.file.read_exact(&mut buf))
            .map_err(|e| BagError::io(&f.path, e))?;
        let scan_err = |e: ScanError| BagError::Corrupt {
            path: f.path.clone(),
            offset: e.offset,
            reason: e.reason,
        };
        let framed = scan::frame_at(&buf, 0, offset)
            .map_err(scan_err)?
            .filter(|fr| fr.op == op::CHUNK && scan::framed_len(fr) == buf.len())
            .ok_or_else(|| corrupt(offset, "chunk index does not point at a chunk".into()))?;
        let Item::Chunk { header, data } = scan::parse(&framed).map_err(scan_err)? else {
            return Err(corrupt(
                offset,
                "chunk index does not point at a chunk".into(),
            ));
        };
        let records = scan::decompress(&header, data, offset, &self.limits).map_err(scan_err)?;
        let mut out = Vec::new();
        for item in scan::chunk_items(&records, offset).map_err(scan_err)? {
            if let Item::Message { header, data } = item {
                let channel = f.channels.get(&header.channel_id).ok_or_else(|| {
                    corrupt(
                        offset,
                        format!(
                            "message on channel {} missing from the summary",
                            header.channel_id
                        ),
                    )
                })?;
                out.push(BagMessage {
                    topic: channel.topic.clone(),
                    type_name: channel.type_name.clone(),
                    log_time_ns: header.log_time,
                    publish_time_ns: header.publish_time,
                    sequence: header.sequence,
                    data: data.to_vec(),
                });
            }
        }
        Ok(out)
    }
}

/// Opens a file and reads its summary section: (file and its length, summary).
pub(crate) fn open_summary(path: &Path) -> Result<((File, u64), mcap::Summary)> {
    let mut file = File::open(path).map_err(|e| BagError::io(path, e))?;
    let len = file.metadata().map_err(|e| BagError::io(path, e))?.len();
    let mut head = [0u8; 8];
    let mut tail = [0u8; 8];
    let head_ok = file.read_exact(&mut head).is_ok() && head == MAGIC;
    if !head_ok {
        return Err(BagError::Corrupt {
            path: path.to_owned(),
            offset: 0,
            reason: "not an MCAP file (bad magic)".into(),
        });
    }
    let tail_ok = len >= 16
        && file.seek(SeekFrom::Start(len - 8)).is_ok()
        && file.read_exact(&mut tail).is_ok()
        && tail == MAGIC;
    if !tail_ok {
        return Err(BagError::Unfinished {
            path: path.to_owned(),
            reason: format!("no closing magic at byte {}", len.saturating_sub(8)),
        });
    }
    check_summary_lengths(&mut file, path, len)?;
    let mut reader = mcap::sans_io::SummaryReader::new_with_options(
        mcap::sans_io::SummaryReaderOptions::default().with_file_size(len),
    );
    let corrupt = |reason: String| BagError::Corrupt {
        path: path.to_owned(),
        // The footer: opcode, length, two offsets, CRC, then the magic.
        offset: len.saturating_sub(8 + 29),
        reason,
    };
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| corrupt(format!("summary section: {e}")))? {
            mcap::sans_io::SummaryReadEvent::ReadRequest(n) => {
                let read = file
                    .read(reader.insert(n))
                    .map_err(|e| BagError::io(path, e))?;
                reader.notify_read(read);
            }
            mcap::sans_io::SummaryReadEvent::SeekRequest(to) => {
                let pos = file.seek(to).map_err(|e| BagError::io(path, e))?;
                reader.notify_seeked(pos);
            }
        }
    }
    let summary = reader.finish().ok_or_else(|| BagError::Unfinished {
        path: path.to_owned(),
        reason: "the footer points at no summary".into(),
    })?;
    Ok(((file, len), summary))
}

/// Frames each record of the summary section (from the footer's `summary_start` to the footer)
/// and holds its length prefixes to its body ([`crate::record_lengths`]) before `mcap`'s
/// summary reader parses it: that reader allocates whatever a string claims. A footer that
/// does not parse is left to the summary reader to report.
fn check_summary_lengths(file: &mut File, path: &Path, len: u64) -> Result<()> {
    // Footer record (opcode, length, summary_start, summary_offset_start, CRC), then the magic.
    const FOOTER_AND_MAGIC: u64 = 1 + 8 + 8 + 8 + 4 + 8;
    let Some(footer_at) = len.checked_sub(FOOTER_AND_MAGIC) else {
        return Ok(());
    };
    let mut footer = [0u8; 17];
    file.seek(SeekFrom::Start(footer_at))
        .and_then(|_| file.read_exact(&mut footer))
        .map_err(|e| BagError::io(path, e))?;
    let summary_start = u64::from_le_bytes(footer[9..17].try_into().unwrap_or_default());
    if footer[0] != op::FOOTER || summary_start < MAGIC.len() as u64 || summary_start > footer_at {
        return Ok(());
    }
    let corrupt = |offset: u64, reason: String| BagError::Corrupt {
        path: path.to_owned(),
        offset,
        reason,
    };
    file.seek(SeekFrom::Start(summary_start))
        .map_err(|e| BagError::io(path, e))?;
    let mut section = std::io::BufReader::new(&mut *file).take(footer_at - summary_start);
    let mut offset = summary_start;
    let mut head = [0u8; 9];
    let mut body = Vec::new();
    while offset < footer_at {
        section
            .read_exact(&mut head)
            .map_err(|_| corrupt(offset, "summary record header runs into the footer".into()))?;
        // The spec puts only schema, channel, index and statistics records (then summary
        // offsets) in the summary; a chunk there would be decompressed by mcap's summary
        // reader, which a fuzzed file made spin for ever (crates/fuzz/corpus/bag_reader).
        if matches!(
            head[0],
            op::HEADER
                | op::FOOTER
                | op::MESSAGE
                | op::CHUNK
                | op::MESSAGE_INDEX
                | op::ATTACHMENT
                | op::METADATA
                | op::DATA_END
        ) {
            return Err(corrupt(
                offset,
                format!(
                    "record opcode {:#04x} does not belong in the summary section",
                    head[0]
                ),
            ));
        }
        let body_len = u64::from_le_bytes(head[1..9].try_into().unwrap_or_default());
        let left = footer_at - offset - 9;
        if body_len > left {
            return Err(corrupt(
                offset,
                format!(
                    "summary record (opcode {:#04x}) of {body_len} bytes runs past the summary \
                     section ({left} bytes left before the footer)",
                    head[0]
                ),
            ));
        }
        body.clear();
        body.resize(body_len as usize, 0);
        section
            .read_exact(&mut body)
            .map_err(|e| BagError::io(path, e))?;
        crate::record_lengths::check(head[0], &body)
            .map_err(|e| corrupt(offset, format!("record opcode {:#04x}: {e}", head[0])))?;
        offset += 9 + body_len;
    }
    file.seek(SeekFrom::Start(0))
        .map_err(|e| BagError::io(path, e))?;
    Ok(())
}

/// A message waiting in the merge, ordered by (log time, read order), smallest first.
struct Pending(u64, u64, BagMessage);

impl PartialEq for Pending {
    fn eq(&self, other: &Self) -> bool {
        (self.0, self.1) == (other.0, other.1)
    }
}
impl Eq for Pending {}
impl PartialOrd for Pending {
    fn partial_cmp(&self, other: &Self) -> Option<CmpOrdering> {
        Some(self.cmp(other))
    }
}
impl Ord for Pending {
    fn cmp(&self, other: &Self) -> CmpOrdering {
        // Reversed: BinaryHeap is a max-heap.
        (other.0, other.1).cmp(&(self.0, self.1))
    }
}

/// Iterator over a bag's messages in log-time order, from [`BagReader::messages`].
pub struct Messages<'a> {
    reader: &'a mut BagReader,
    next_chunk: usize,
    heap: BinaryHeap<Pending>,
    ordinal: u64,
    failed: bool,
}

impl Iterator for Messages<'_> {
    type Item = Result<BagMessage>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        while let Some(chunk) = self.reader.chunks.get(self.next_chunk) {
            if self.heap.peek().is_some_and(|top| top.0 < chunk.start_time) {
                break;
            }
            match self.reader.load_chunk(self.next_chunk) {
                Ok(messages) => {
                    for m in messages {
                        self.heap.push(Pending(m.log_time_ns, self.ordinal, m));
                        self.ordinal += 1;
                    }
                }
                Err(e) => {
                    self.failed = true;
                    return Some(Err(e));
                }
            }
            self.next_chunk += 1;
        }
        self.heap.pop().map(|p| Ok(p.2))
    }
}

impl fmt::Display for BagInfo {
    /// The layout of `ros2 bag info` (times in UTC).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const W: usize = 19;
        for (i, file) in self.files.iter().enumerate() {
            let label = if i == 0 { "Files:" } else { "" };
            let name = file.path.file_name().unwrap_or_default().to_string_lossy();
            writeln!(f, "{label:<W$}{name}")?;
        }
        writeln!(f, "{:<W$}{}", "Bag size:", human_size(self.size))?;
        writeln!(f, "{:<W$}{}", "Storage id:", self.storage)?;
        let d = self.duration_ns();
        writeln!(
            f,
            "{:<W$}{}.{:09}s",
            "Duration:",
            d / 1_000_000_000,
            d % 1_000_000_000
        )?;
        if let Some((start, end)) = self.time_range {
            writeln!(f, "{:<W$}{}", "Start:", format_time(start))?;
            writeln!(f, "{:<W$}{}", "End:", format_time(end))?;
        }
        writeln!(f, "{:<W$}{}", "Messages:", self.message_count)?;
        if self.topics.is_empty() {
            writeln!(f, "Topic information: ")?;
        }
        for (i, t) in self.topics.iter().enumerate() {
            let label = if i == 0 { "Topic information:" } else { "" };
            writeln!(
                f,
                "{label:<W$}Topic: {} | Type: {} | Count: {} | Serialization Format: {}",
                t.name, t.type_name, t.message_count, t.serialization_format
            )?;
        }
        Ok(())
    }
}

/// Size like `ros2 bag info`: B, KiB, MiB, GiB with up to two decimals.
pub fn human_size(bytes: u64) -> String {
    let mut value = bytes as f64;
    for unit in ["B", "KiB", "MiB", "GiB"] {
        if value < 1024.0 || unit == "GiB" {
            return if unit == "B" {
                format!("{bytes} B")
            } else {
                format!("{:.2} {unit}", value)
            };
        }
        value /= 1024.0;
    }
    unreachable!("the loop returns at GiB")
}

/// `Nov 22 2026 14:10:01.123456789 (1795356601.123456789)`, in UTC.
fn format_time(ns: u64) -> String {
    let secs = ns / 1_000_000_000;
    let nanos = ns % 1_000_000_000;
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    const MONTHS: [&str; 12] = [
        "Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec",
    ];
    format!(
        "{} {:>2} {year} {:02}:{:02}:{:02}.{nanos:09} ({secs}.{nanos:09})",
        MONTHS[(month - 1) as usize],
        day,
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_and_size_formatting() {
        assert_eq!(
            format_time(1_700_000_000_123_456_789),
            "Nov 14 2023 22:13:20.123456789 (1700000000.123456789)"
        );
        assert_eq!(
            format_time(0),
            "Jan  1 1970 00:00:00.000000000 (0.000000000)"
        );
        assert_eq!(human_size(512), "512 B");
        assert_eq!(human_size(3 * 1024 * 1024 / 2), "1.50 MiB");
    }

    #[test]
    fn split_index_orders_numerically() {
        assert_eq!(split_index(Path::new("/b/run_10.mcap")), Some(10));
        assert_eq!(split_index(Path::new("/b/x.mcap")), None);
    }
}
