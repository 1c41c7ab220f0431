//! [`ChunkLimits`]: how large a chunk may say it is before it is decompressed.
//!
//! An MCAP Chunk record states its `uncompressed_size` (MCAP specification, "Chunk (op=0x06)",
//! <https://mcap.dev/spec#chunk-op0x06>), and zstd data can expand by about 32 000× (a 128 KiB
//! RLE block takes 4 bytes; RFC 8878 §3.1.1.2), so a small hostile file could make a reader
//! decompress gigabytes. Before a chunk is decompressed its declared size is held against an
//! absolute cap and, above a floor, against its compressed size times a ratio; decompression
//! then stops at the declared size (see `scan::decompress`). rosbag2 and [`crate::BagWriter`]
//! close chunks at about 1 MiB (a single larger message makes one chunk of its own size), so
//! the defaults leave real bags alone.

/// Caps on one chunk's decompression; [`ChunkLimits::default`] is what
/// [`crate::BagReader::open`] and [`crate::repair()`] use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChunkLimits {
    /// A chunk may declare at most this many uncompressed bytes (default 1 GiB).
    pub max_uncompressed_bytes: u64,
    /// A chunk declaring more than [`Self::ratio_floor_bytes`] may expand at most this many
    /// times its compressed size (default 1000).
    pub max_ratio: u64,
    /// Chunks declaring up to this many bytes are not held to the ratio (default 64 MiB).
    pub ratio_floor_bytes: u64,
}

impl Default for ChunkLimits {
    fn default() -> Self {
        ChunkLimits {
            max_uncompressed_bytes: 1 << 30,
            max_ratio: 1000,
            ratio_floor_bytes: 64 << 20,
        }
    }
}

impl ChunkLimits {
    /// Checks a chunk declaring `declared` uncompressed bytes from `compressed` bytes of data;
    /// the error says which limit it breaks (the caller adds the file and offset).
    pub fn check(&self, declared: u64, compressed: u64) -> Result<(), String> {
        if declared > self.max_uncompressed_bytes {
            return Err(format!(
                "chunk declares {declared} bytes uncompressed, over the limit of {} bytes \
                 (ChunkLimits::max_uncompressed_bytes); refusing to decompress it",
                self.max_uncompressed_bytes
            ));
        }
        if declared > self.ratio_floor_bytes && declared > compressed.saturating_mul(self.max_ratio)
        {
            return Err(format!(
                "chunk declares {declared} bytes uncompressed from {compressed} compressed, over \
                 the limit of {}:1 for chunks above {} bytes (ChunkLimits::max_ratio); refusing \
                 to decompress it",
                self.max_ratio, self.ratio_floor_bytes
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_size_cap_and_the_ratio_above_the_floor() {
        let limits = ChunkLimits {
            max_uncompressed_bytes: 1000,
            max_ratio: 10,
            ratio_floor_bytes: 100,
        };
        assert!(limits.check(1000, 100).is_ok());
        let e = limits.check(1001, 1001).unwrap_err();
        assert!(
            e.contains("1001 bytes") && e.contains("limit of 1000"),
            "{e}"
        );
        // Below the floor any ratio goes; above it, 10:1 at most.
        assert!(limits.check(100, 1).is_ok());
        assert!(limits.check(500, 50).is_ok());
        let e = limits.check(501, 50).unwrap_err();
        assert!(e.contains("10:1"), "{e}");
        // 2^40 declared from a few bytes: refused, no overflow.
        assert!(ChunkLimits::default().check(1 << 40, u64::MAX).is_err());
        assert!(ChunkLimits::default().check(1 << 20, 10).is_ok());
    }
}
