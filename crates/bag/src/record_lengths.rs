//! Checks every length prefix inside an MCAP record body against the body before `mcap`
//! parses it.
//!
//! `mcap` 0.25 reads a string field (`u32` length, then UTF-8 bytes) by allocating the claimed
//! length before it reads (binrw's `count = len`), so a record of a few bytes whose string says
//! 2³¹ bytes makes it allocate 2 GB. Here each record kind's field layout (MCAP specification,
//! "Records", <https://mcap.dev/spec#records>) is walked over the body, which is already a slice
//! of known length: integers are skipped, strings and byte arrays (`u32`, or `u64` for
//! attachment data and chunk records) and maps (`u32` byte length, then entries) must fit in
//! what is left. Fields after the last known one are allowed (the spec lets records grow).

use mcap::records::op;

/// Checks the body of a record with opcode `op`; the error names the record kind, the field,
/// its byte position in the body and the length it claims. Opcodes without strings, byte
/// arrays or maps (Message, Footer, Summary Offset, Data End) and unknown ones pass.
pub(crate) fn check(op: u8, body: &[u8]) -> Result<(), String> {
    let mut f = Fields {
        body,
        pos: 0,
        origin: 0,
        kind: kind(op),
    };
    match op {
        op::HEADER => {
            f.string("profile")?;
            f.string("library")?;
        }
        op::SCHEMA => {
            f.fixed(2, "id")?;
            f.string("name")?;
            f.string("encoding")?;
            f.bytes32("data")?;
        }
        op::CHANNEL => {
            f.fixed(2 + 2, "id, schema_id")?;
            f.string("topic")?;
            f.string("message_encoding")?;
            f.string_map("metadata")?;
        }
        op::CHUNK => {
            f.fixed(8 + 8 + 8 + 4, "times, uncompressed_size, uncompressed_crc")?;
            f.string("compression")?;
            f.bytes64("records")?;
        }
        op::MESSAGE_INDEX => {
            f.fixed(2, "channel_id")?;
            f.fixed_map("records")?;
        }
        op::CHUNK_INDEX => {
            f.fixed(8 * 4, "times, chunk_start_offset, chunk_length")?;
            f.fixed_map("message_index_offsets")?;
            f.fixed(8, "message_index_length")?;
            f.string("compression")?;
        }
        op::ATTACHMENT => {
            f.fixed(8 + 8, "log_time, create_time")?;
            f.string("name")?;
            f.string("media_type")?;
            f.bytes64("data")?;
            f.fixed(4, "crc")?;
        }
        op::ATTACHMENT_INDEX => {
            f.fixed(8 * 5, "offset, length, times, data_size")?;
            f.string("name")?;
            f.string("media_type")?;
        }
        op::STATISTICS => {
            f.fixed(8 + 2 + 4 * 4 + 8 + 8, "counts, times")?;
            f.fixed_map("channel_message_counts")?;
        }
        op::METADATA => {
            f.string("name")?;
            f.string_map("metadata")?;
        }
        op::METADATA_INDEX => {
            f.fixed(8 + 8, "offset, length")?;
            f.string("name")?;
        }
        _ => {}
    }
    Ok(())
}

/// The spec's name of a record kind, for errors.
fn kind(op: u8) -> &'static str {
    match op {
        op::HEADER => "Header",
        op::SCHEMA => "Schema",
        op::CHANNEL => "Channel",
        op::CHUNK => "Chunk",
        op::MESSAGE_INDEX => "Message Index",
        op::CHUNK_INDEX => "Chunk Index",
        op::ATTACHMENT => "Attachment",
        op::ATTACHMENT_INDEX => "Attachment Index",
        op::STATISTICS => "Statistics",
        op::METADATA => "Metadata",
        op::METADATA_INDEX => "Metadata Index",
        _ => "record",
    }
}

/// A walk over a record body (or a map inside it).
struct Fields<'a> {
    body: &'a [u8],
    pos: usize,
    /// Where `body` starts in the record body (non-zero inside a map), for errors.
    origin: usize,
    kind: &'static str,
}

impl Fields<'_> {
    fn left(&self) -> usize {
        self.body.len() - self.pos
    }

    /// Skips `n` bytes of fixed-size fields.
    fn fixed(&mut self, n: usize, what: &str) -> Result<(), String> {
        if n > self.left() {
            return Err(format!(
                "{} record ends inside `{what}` at byte {}",
                self.kind,
                self.origin + self.pos
            ));
        }
        self.pos += n;
        Ok(())
    }

    /// Reads a little-endian length prefix of `N` bytes and skips that many bytes after it;
    /// returns the bytes.
    fn prefixed<const N: usize>(&mut self, what: &str) -> Result<&[u8], String> {
        let at = self.pos;
        self.fixed(N, what)?;
        let mut raw = [0u8; 8];
        raw[..N].copy_from_slice(&self.body[at..at + N]);
        let claimed = u64::from_le_bytes(raw);
        if claimed > self.left() as u64 {
            return Err(format!(
                "{} record: `{what}` at byte {} claims {claimed} bytes, only {} left",
                self.kind,
                self.origin + at,
                self.left()
            ));
        }
        let start = self.pos;
        self.pos += claimed as usize;
        Ok(&self.body[start..self.pos])
    }

    fn string(&mut self, what: &str) -> Result<(), String> {
        self.prefixed::<4>(what).map(drop)
    }

    fn bytes32(&mut self, what: &str) -> Result<(), String> {
        self.prefixed::<4>(what).map(drop)
    }

    fn bytes64(&mut self, what: &str) -> Result<(), String> {
        self.prefixed::<8>(what).map(drop)
    }

    /// A map or array of fixed-size entries: only its byte length must fit.
    fn fixed_map(&mut self, what: &str) -> Result<(), String> {
        self.prefixed::<4>(what).map(drop)
    }

    /// A `Map<string, string>`: its byte length must fit, and every key and value must fit in
    /// the map.
    fn string_map(&mut self, what: &str) -> Result<(), String> {
        let origin = self.origin + self.pos + 4;
        let kind = self.kind;
        let mut map = Fields {
            body: self.prefixed::<4>(what)?,
            pos: 0,
            origin,
            kind,
        };
        while map.left() > 0 {
            map.string(&format!("{what} key"))?;
            map.string(&format!("{what} value"))?;
        }
        Ok(())
    }
}
