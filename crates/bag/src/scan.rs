//! Defensive MCAP record parsing shared by the reader and repair.
//!
//! The outer framing (opcode, length) and chunk decompression are done here rather than by the
//! `mcap` crate's readers so that every failure carries a byte offset, a corrupt length can
//! never make us allocate more than the file holds, and records we never write (attachments)
//! are skipped unparsed. Record bodies are parsed by `mcap::parse_record`.

use std::io::Read;

use mcap::records::{op, ChunkHeader, MessageHeader, Record};

use crate::limits::ChunkLimits;
use crate::record_lengths;

/// MCAP magic, at the start and at the end of a file.
pub(crate) const MAGIC: [u8; 8] = [0x89, b'M', b'C', b'A', b'P', 0x30, b'\r', b'\n'];

/// Why parsing stopped, at which file offset.
#[derive(Debug)]
pub(crate) struct ScanError {
    pub offset: u64,
    pub reason: String,
}

impl ScanError {
    pub fn corrupt(offset: u64, reason: impl Into<String>) -> Self {
        Self {
            offset,
            reason: reason.into(),
        }
    }

    /// The bytes simply end (a killed writer), as opposed to bytes that are wrong.
    fn truncated(offset: u64, reason: impl Into<String>) -> Self {
        Self::corrupt(offset, format!("file ends early: {}", reason.into()))
    }
}

/// One framed record: opcode, its offset in `buf`'s file and its body.
pub(crate) struct Framed<'a> {
    pub op: u8,
    pub offset: u64,
    pub body: &'a [u8],
}

/// Reads the record framed at `pos` of `buf`, whose first byte is at file offset `base`.
/// `Ok(None)` at the exact end of `buf`.
pub(crate) fn frame_at(buf: &[u8], pos: usize, base: u64) -> Result<Option<Framed<'_>>, ScanError> {
    let offset = base + pos as u64;
    let rest = buf.get(pos..).unwrap_or_default();
    if rest.is_empty() {
        return Ok(None);
    }
    let Some((head, rest)) = rest.split_first_chunk::<9>() else {
        return Err(ScanError::truncated(
            offset,
            format!("record header cut short ({} of 9 bytes)", rest.len()),
        ));
    };
    let len = u64::from_le_bytes(head[1..9].try_into().unwrap_or_default());
    if len > rest.len() as u64 {
        return Err(ScanError::truncated(
            offset,
            format!(
                "record (opcode {:#04x}) of {len} bytes, only {} left",
                head[0],
                rest.len()
            ),
        ));
    }
    Ok(Some(Framed {
        op: head[0],
        offset,
        body: &rest[..len as usize],
    }))
}

/// Bytes a framed record takes (opcode + length + body).
pub(crate) fn framed_len(f: &Framed<'_>) -> usize {
    9 + f.body.len()
}

/// Records a chunk or a file holds that matter to us.
pub(crate) enum Item<'a> {
    Schema {
        id: u16,
        name: String,
        encoding: String,
        data: &'a [u8],
    },
    Channel(mcap::records::Channel),
    Message {
        header: MessageHeader,
        data: &'a [u8],
    },
    Chunk {
        header: ChunkHeader,
        data: &'a [u8],
    },
    DataEnd,
    Footer,
    /// Indexes, statistics, metadata, attachments, private records: not needed to read messages.
    Other,
}

/// Parses the body of a framed record (only the kinds we use).
pub(crate) fn parse<'a>(f: &Framed<'a>) -> Result<Item<'a>, ScanError> {
    let wanted = matches!(
        f.op,
        op::SCHEMA | op::CHANNEL | op::MESSAGE | op::CHUNK | op::HEADER
    );
    if !wanted {
        return Ok(match f.op {
            op::DATA_END => Item::DataEnd,
            op::FOOTER => Item::Footer,
            _ => Item::Other,
        });
    }
    let record = parse_record(f)?;
    Ok(match record {
        Record::Schema { header, data } => Item::Schema {
            id: header.id,
            name: header.name,
            encoding: header.encoding,
            data: borrowed(data, f)?,
        },
        Record::Channel(c) => Item::Channel(c),
        Record::Message { header, data } => Item::Message {
            header,
            data: borrowed(data, f)?,
        },
        Record::Chunk { header, data } => Item::Chunk {
            header,
            data: borrowed(data, f)?,
        },
        _ => Item::Other,
    })
}

/// `mcap::parse_record` over a framed record, once [`record_lengths::check`] has held every
/// length prefix in it to the body (`mcap` allocates a string's claimed length before reading).
pub(crate) fn parse_record<'a>(f: &Framed<'a>) -> Result<Record<'a>, ScanError> {
    let corrupt = |e: &dyn std::fmt::Display| {
        ScanError::corrupt(f.offset, format!("record opcode {:#04x}: {e}", f.op))
    };
    record_lengths::check(f.op, f.body).map_err(|e| corrupt(&e))?;
    mcap::parse_record(f.op, f.body).map_err(|e| corrupt(&e))
}

/// `parse_record` borrows payloads from its input; get the slice back with our lifetime.
fn borrowed<'a>(data: std::borrow::Cow<'_, [u8]>, f: &Framed<'a>) -> Result<&'a [u8], ScanError> {
    // Locate the payload in the body by address: no copy, no unsafe.
    let start = (data.as_ptr() as usize).checked_sub(f.body.as_ptr() as usize);
    start
        .and_then(|start| f.body.get(start..start + data.len()))
        .ok_or_else(|| ScanError::corrupt(f.offset, "record payload not found in its body"))
}

/// Decompresses and checks a chunk; `offset` is the chunk record's file offset (for errors).
/// The declared size is first held to `limits` ([`ChunkLimits`]), so nothing is decompressed
/// for a chunk that claims too much.
pub(crate) fn decompress(
    header: &ChunkHeader,
    data: &[u8],
    offset: u64,
    limits: &ChunkLimits,
) -> Result<Vec<u8>, ScanError> {
    let size = header.uncompressed_size;
    limits
        .check(size, data.len() as u64)
        .map_err(|reason| ScanError::corrupt(offset, reason))?;
    let out = match header.compression.as_str() {
        "" => data.to_vec(),
        "zstd" => {
            let mut out = Vec::new();
            // Bounded by what the frame really holds and by the declared size (+1 to detect
            // overlong output, which `limits` has capped), so a corrupt size cannot make us
            // allocate it up front.
            zstd::stream::read::Decoder::with_buffer(data)
                .and_then(|d| d.take(size.saturating_add(1)).read_to_end(&mut out))
                .map_err(|e| ScanError::corrupt(offset, format!("chunk zstd data: {e}")))?;
            out
        }
        other => {
            return Err(ScanError::corrupt(
                offset,
                format!("chunk compression `{other}` is not supported (zstd or none)"),
            ))
        }
    };
    if out.len() as u64 != size {
        return Err(ScanError::corrupt(
            offset,
            format!(
                "chunk decompresses to {} bytes, header says {size}",
                out.len()
            ),
        ));
    }
    if header.uncompressed_crc != 0 {
        let crc = crc32fast::hash(&out);
        if crc != header.uncompressed_crc {
            return Err(ScanError::corrupt(
                offset,
                format!(
                    "chunk CRC mismatch (stored {:08x}, computed {crc:08x})",
                    header.uncompressed_crc
                ),
            ));
        }
    }
    Ok(out)
}

/// Parses the records inside a decompressed chunk; errors point at the chunk's `offset`.
pub(crate) fn chunk_items(records: &[u8], offset: u64) -> Result<Vec<Item<'_>>, ScanError> {
    let mut items = Vec::new();
    let mut pos = 0;
    loop {
        let framed = frame_at(records, pos, 0).map_err(|e| {
            ScanError::corrupt(
                offset,
                format!("inside chunk at byte {}: {}", e.offset, e.reason),
            )
        })?;
        let Some(framed) = framed else { break };
        pos += framed_len(&framed);
        let item = parse(&framed).map_err(|e| {
            ScanError::corrupt(
                offset,
                format!("inside chunk at byte {}: {}", e.offset, e.reason),
            )
        })?;
        items.push(item);
    }
    Ok(items)
}
