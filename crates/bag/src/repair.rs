//! [`repair`]: makes a bag readable after its writer died.
//!
//! A killed [`crate::BagWriter`] leaves complete chunks followed by at most one partial record
//! and no summary (see [`crate::writer`]). Repair reads each such file record by record up to
//! the first record that is cut short or fails its checks (a chunk must decompress to its
//! declared size and match its CRC), writes what came before into a new file with a summary
//! section, and swaps it in atomically: the original is first hard-linked to `FILE.orig` (so
//! the path never lacks a file), then the repaired copy, fully written and synced, is renamed
//! over it. Files that already have a readable summary are left alone. Finally
//! `metadata.yaml` is regenerated from every file's summary, since the writer only writes it
//! when a file is closed.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::limits::ChunkLimits;
use crate::metadata::{self, FileStats, TopicStats};
use crate::reader::{self, BagReader};
use crate::scan::{self, Item, MAGIC};
use crate::writer::LIBRARY;
use crate::{BagError, Result};

/// What [`repair`] did to one file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileRepair {
    /// The file.
    pub path: PathBuf,
    /// Where the original was kept, if the file was rewritten.
    pub original: Option<PathBuf>,
    /// Messages in the (repaired) file.
    pub messages: u64,
    /// Bytes of the original that were dropped (the unfinished tail and anything after it).
    pub dropped_bytes: u64,
    /// Where reading stopped and why, if the file was rewritten.
    pub stopped: Option<(u64, String)>,
}

/// What [`repair`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RepairReport {
    /// The bag directory.
    pub dir: PathBuf,
    /// Every file looked at, in split order.
    pub files: Vec<FileRepair>,
    /// The regenerated `metadata.yaml`.
    pub metadata: PathBuf,
}

impl RepairReport {
    /// Files that were rewritten.
    pub fn repaired(&self) -> impl Iterator<Item = &FileRepair> {
        self.files.iter().filter(|f| f.original.is_some())
    }
}

/// Repairs a bag directory (every `*.mcap` in it) or one `.mcap` file (then the metadata of
/// its directory is regenerated from all the directory's files). See the [module docs](self).
pub fn repair(path: impl AsRef<Path>) -> Result<RepairReport> {
    let path = path.as_ref();
    let (dir, targets) = if path.is_dir() {
        (path.to_owned(), reader::mcap_files_in(path)?)
    } else {
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_owned();
        (dir, vec![path.to_owned()])
    };
    let mut files = Vec::new();
    for target in &targets {
        files.push(repair_file(target)?);
    }
    // The metadata describes every file of the directory, repaired just now or not.
    let mut file_stats = Vec::new();
    let mut topics: Vec<TopicStats> = Vec::new();
    for p in reader::mcap_files_in(&dir)? {
        let reader = BagReader::open(&p)?;
        let info = reader.info();
        let name = p
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let mut stats = FileStats::new(name);
        stats.message_count = info.message_count;
        stats.start = info.time_range.map(|r| r.0);
        stats.end = info.time_range.map(|r| r.1);
        file_stats.push(stats);
        for t in &info.topics {
            match topics.iter_mut().find(|x| x.name == t.name) {
                Some(x) => x.message_count += t.message_count,
                None => topics.push(TopicStats {
                    name: t.name.clone(),
                    type_name: t.type_name.clone(),
                    qos_yaml: t.offered_qos_profiles.clone(),
                    type_hash: t.type_hash.clone(),
                    message_count: t.message_count,
                }),
            }
        }
    }
    metadata::build(&file_stats, &topics).write(&dir)?;
    Ok(RepairReport {
        metadata: dir.join(metadata::FILE_NAME),
        dir,
        files,
    })
}

/// Repairs one file if it has no readable summary.
fn repair_file(path: &Path) -> Result<FileRepair> {
    if let Ok((_, summary)) = reader::open_summary(path) {
        return Ok(FileRepair {
            path: path.to_owned(),
            original: None,
            messages: summary.stats.map_or(0, |s| s.message_count),
            dropped_bytes: 0,
            stopped: None,
        });
    }
    let bytes = std::fs::read(path).map_err(|e| BagError::io(path, e))?;
    // A file killed before its magic was complete holds nothing: it becomes an empty MCAP.
    if bytes.len() < MAGIC.len() && bytes[..] != MAGIC[..bytes.len()]
        || bytes.len() >= MAGIC.len() && bytes[..8] != MAGIC
    {
        return Err(BagError::Corrupt {
            path: path.to_owned(),
            offset: 0,
            reason: "not an MCAP file (bad magic); nothing to repair".into(),
        });
    }
    let tmp = sibling(path, ".repair.tmp");
    let out = File::create(&tmp).map_err(|e| BagError::io(&tmp, e))?;
    let mut profile = "ros2".to_owned();
    let mut pos = MAGIC.len().min(bytes.len());
    // The header comes first; keep its profile.
    if let Ok(Some(framed)) = scan::frame_at(&bytes, pos, 0) {
        if framed.op == mcap::records::op::HEADER {
            if let Ok(mcap::records::Record::Header(h)) = scan::parse_record(&framed) {
                profile = h.profile;
            }
            pos += scan::framed_len(&framed);
        }
    }
    let mut writer = mcap::WriteOptions::new()
        .profile(profile)
        .library(LIBRARY)
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(0)
        .create(BufWriter::new(out))
        .map_err(|e| BagError::mcap(&tmp, e))?;
    let mut schemas: HashMap<u16, Arc<mcap::Schema<'static>>> = HashMap::new();
    let mut channels: HashMap<u16, Arc<mcap::Channel<'static>>> = HashMap::new();
    let mut messages = 0u64;
    let stopped = loop {
        let framed = match scan::frame_at(&bytes, pos, 0) {
            Ok(Some(f)) => f,
            Ok(None) => break (pos as u64, "end of file".to_owned()),
            Err(e) => break (e.offset, e.reason),
        };
        let item = match scan::parse(&framed) {
            Ok(item) => item,
            Err(e) => break (e.offset, e.reason),
        };
        let records;
        let items = match item {
            Item::Chunk { header, data } => {
                match scan::decompress(&header, data, framed.offset, &ChunkLimits::default()) {
                    Ok(r) => records = r,
                    Err(e) => break (e.offset, e.reason),
                }
                match scan::chunk_items(&records, framed.offset) {
                    Ok(items) => items,
                    Err(e) => break (e.offset, e.reason),
                }
            }
            Item::DataEnd | Item::Footer => break (framed.offset, "end of data section".into()),
            other => vec![other],
        };
        // A chunk's content is only used once the whole chunk has checked out.
        if let Err(reason) = copy_items(
            items,
            &mut schemas,
            &mut channels,
            &mut writer,
            &mut messages,
        ) {
            break (framed.offset, reason);
        }
        pos += scan::framed_len(&framed);
    };
    writer.finish().map_err(|e| BagError::mcap(&tmp, e))?;
    let mut sink = writer.into_inner();
    sink.flush().map_err(|e| BagError::io(&tmp, e))?;
    sink.get_ref()
        .sync_all()
        .map_err(|e| BagError::io(&tmp, e))?;
    drop(sink);
    let original = free_name(&sibling(path, ".orig"));
    if std::fs::hard_link(path, &original).is_err() {
        std::fs::copy(path, &original).map_err(|e| BagError::io(&original, e))?;
    }
    std::fs::rename(&tmp, path).map_err(|e| BagError::io(path, e))?;
    Ok(FileRepair {
        path: path.to_owned(),
        original: Some(original),
        messages,
        dropped_bytes: bytes.len() as u64 - pos as u64,
        stopped: Some(stopped),
    })
}

/// Registers schemas and channels and copies messages, keeping the original ids.
fn copy_items<W: Write + std::io::Seek>(
    items: Vec<Item<'_>>,
    schemas: &mut HashMap<u16, Arc<mcap::Schema<'static>>>,
    channels: &mut HashMap<u16, Arc<mcap::Channel<'static>>>,
    writer: &mut mcap::Writer<W>,
    messages: &mut u64,
) -> std::result::Result<(), String> {
    for item in items {
        match item {
            Item::Schema {
                id,
                name,
                encoding,
                data,
            } => {
                schemas.insert(
                    id,
                    Arc::new(mcap::Schema {
                        id,
                        name,
                        encoding,
                        data: data.to_vec().into(),
                    }),
                );
            }
            Item::Channel(c) => {
                let schema = match c.schema_id {
                    0 => None,
                    id => Some(
                        schemas
                            .get(&id)
                            .cloned()
                            .ok_or(format!("channel {} uses unknown schema {id}", c.id))?,
                    ),
                };
                channels.insert(
                    c.id,
                    Arc::new(mcap::Channel {
                        id: c.id,
                        topic: c.topic,
                        schema,
                        message_encoding: c.message_encoding,
                        metadata: BTreeMap::from_iter(c.metadata),
                    }),
                );
            }
            Item::Message { header, data } => {
                let channel = channels
                    .get(&header.channel_id)
                    .ok_or(format!("message on unknown channel {}", header.channel_id))?;
                writer
                    .write(&mcap::Message {
                        channel: channel.clone(),
                        sequence: header.sequence,
                        log_time: header.log_time,
                        publish_time: header.publish_time,
                        data: data.into(),
                    })
                    .map_err(|e| e.to_string())?;
                *messages += 1;
            }
            _ => {}
        }
    }
    Ok(())
}

/// `path` with `suffix` appended to its file name.
fn sibling(path: &Path, suffix: &str) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_owned();
    name.push(suffix);
    path.with_file_name(name)
}

/// `path`, or `path.1`, `path.2`, … whichever does not exist yet.
fn free_name(path: &Path) -> PathBuf {
    std::iter::once(path.to_owned())
        .chain((1..10_000).map(|n| sibling(path, &format!(".{n}"))))
        .find(|p| !p.exists())
        .unwrap_or_else(|| path.to_owned())
}
