//! Length prefixes inside MCAP records that claim more than the record holds: a Channel whose
//! topic says 2³¹ bytes (in the summary, read by `BagReader::open`) and a Chunk whose
//! compression string says 2³² − 1 bytes (in the data section, read by `repair`). `mcap` would
//! allocate the claimed size before reading; each must instead be refused at once with the
//! file, the record's byte offset and the field, and no allocation anywhere near that size.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use cell_bag::{repair, BagReader};

/// The system allocator, remembering the largest single allocation asked of it.
struct LargestAllocation;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded unchanged to `System`; only a size is recorded.
unsafe impl GlobalAlloc for LargestAllocation {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        System.alloc_zeroed(layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static ALLOCATOR: LargestAllocation = LargestAllocation;

/// Far above anything these few-hundred-byte files need, far below what they claim.
const MAX_ALLOCATION: usize = 64 << 20;

/// MCAP magic and opcodes (https://mcap.dev/spec).
const MAGIC: [u8; 8] = [0x89, b'M', b'C', b'A', b'P', 0x30, b'\r', b'\n'];
const OP_HEADER: u8 = 0x01;
const OP_FOOTER: u8 = 0x02;
const OP_CHANNEL: u8 = 0x04;
const OP_CHUNK: u8 = 0x06;
const OP_DATA_END: u8 = 0x0F;

/// Appends a record (opcode, u64 body length, body); returns its offset.
fn record(file: &mut Vec<u8>, op: u8, body: &[u8]) -> u64 {
    let at = file.len() as u64;
    file.push(op);
    file.extend((body.len() as u64).to_le_bytes());
    file.extend(body);
    at
}

/// A string field whose length prefix says `claimed` but which holds `text`.
fn string(claimed: u32, text: &str) -> Vec<u8> {
    let mut s = claimed.to_le_bytes().to_vec();
    s.extend(text.as_bytes());
    s
}

/// Magic and a Header record.
fn start() -> Vec<u8> {
    let mut file = MAGIC.to_vec();
    let header = [string(4, "ros2"), string(1, "t")].concat();
    record(&mut file, OP_HEADER, &header);
    file
}

/// Writes `bytes` as `name` in a fresh directory.
fn write(name: &str, bytes: &[u8]) -> (tempfile::TempDir, std::path::PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    (tmp, path)
}

fn assert_no_large_allocation() {
    let largest = LARGEST.load(Ordering::Relaxed);
    assert!(
        largest < MAX_ALLOCATION,
        "largest allocation {largest} bytes"
    );
}

/// A finished file whose summary holds one Channel with `channel` as its body; returns the
/// bytes and the Channel record's offset.
fn summary_with_channel(channel: &[u8]) -> (Vec<u8>, u64) {
    let mut file = start();
    record(&mut file, OP_DATA_END, &0u32.to_le_bytes());
    let summary_start = file.len() as u64;
    let at = record(&mut file, OP_CHANNEL, channel);
    let footer = [
        summary_start.to_le_bytes().as_slice(),
        &0u64.to_le_bytes(),
        &0u32.to_le_bytes(),
    ]
    .concat();
    record(&mut file, OP_FOOTER, &footer);
    file.extend(MAGIC);
    (file, at)
}

#[test]
fn a_channel_topic_claiming_2_gb_is_refused_with_file_and_offset() {
    // id, schema_id, topic (says 2³¹ bytes, holds 2), message_encoding, metadata.
    let channel = [
        1u16.to_le_bytes().as_slice(),
        &0u16.to_le_bytes(),
        &string(1 << 31, "/t"),
    ]
    .concat();
    let (bytes, at) = summary_with_channel(&channel);
    let (_tmp, path) = write("topic.mcap", &bytes);
    let e = BagReader::open(&path)
        .err()
        .expect("open must fail")
        .to_string();
    assert!(
        e.contains("topic.mcap")
            && e.contains(&format!("at byte {at}:"))
            && e.contains("Channel")
            && e.contains("`topic`")
            && e.contains("2147483648"),
        "{e}"
    );
    assert_no_large_allocation();
}

#[test]
fn a_channel_metadata_value_claiming_more_than_its_map_is_refused() {
    // A well-formed topic and encoding, then a metadata map of 12 bytes whose one value says
    // 2³⁰ bytes.
    let map = [string(1, "k"), string(1 << 30, "v")].concat();
    let channel = [
        1u16.to_le_bytes().as_slice(),
        &0u16.to_le_bytes(),
        &string(2, "/t"),
        &string(3, "cdr"),
        &(map.len() as u32).to_le_bytes(),
        &map,
    ]
    .concat();
    let (bytes, at) = summary_with_channel(&channel);
    let (_tmp, path) = write("metadata.mcap", &bytes);
    let e = BagReader::open(&path)
        .err()
        .expect("open must fail")
        .to_string();
    assert!(
        e.contains("metadata.mcap")
            && e.contains(&format!("at byte {at}:"))
            && e.contains("metadata value")
            && e.contains("1073741824"),
        "{e}"
    );
    assert_no_large_allocation();
}

#[test]
fn a_chunk_compression_claiming_4_gb_stops_repair_at_the_chunk() {
    // An unfinished file (no footer): repair scans it and meets a Chunk whose compression
    // string says 2³² − 1 bytes.
    let mut bytes = start();
    let chunk = [
        [0u8; 8 + 8 + 8 + 4].as_slice(),
        &string(u32::MAX, "zstd"),
        &0u64.to_le_bytes(),
    ]
    .concat();
    let at = record(&mut bytes, OP_CHUNK, &chunk);
    let (_tmp, path) = write("chunk.mcap", &bytes);
    let report = repair(&path).unwrap();
    let (offset, reason) = report.files[0].stopped.clone().expect("file was rewritten");
    assert_eq!(offset, at, "{reason}");
    assert!(
        reason.contains("Chunk")
            && reason.contains("`compression`")
            && reason.contains("4294967295"),
        "{reason}"
    );
    assert_eq!(report.files[0].messages, 0);
    assert_eq!(BagReader::open(&path).unwrap().info().message_count, 0);
    assert_no_large_allocation();
}
