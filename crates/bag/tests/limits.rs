//! Hostile sizes and times in otherwise well-formed files: a chunk that declares 2⁴⁰ bytes or
//! expands beyond the ratio limit is refused before it is decompressed, and statistics whose
//! start lies after their end are refused; each error names the file, the offset and the
//! limit or field.

use cell_bag::{repair, BagInfo, BagReader, BagWriter, BagWriterOptions, ChunkLimits};
use cell_msgs::{HeatMap, MachineStatus};

/// MCAP opcodes (https://mcap.dev/spec).
const OP_FOOTER: u8 = 0x02;
const OP_CHUNK: u8 = 0x06;
const OP_STATISTICS: u8 = 0x0B;

fn status(i: u64) -> MachineStatus {
    MachineStatus {
        machine_id: "grbl-sim".into(),
        acked_line: i as u32,
        ..Default::default()
    }
}

/// A finished single-file bag of statuses, as (dir guard, file path, bytes).
fn small_bag() -> (tempfile::TempDir, std::path::PathBuf, Vec<u8>) {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("small");
    let options = BagWriterOptions {
        chunk_size: 512,
        ..Default::default()
    };
    let mut w = BagWriter::create(&bag, options).unwrap();
    for i in 0..40 {
        w.write("/machine_status", &status(i), 1_000 + i).unwrap();
    }
    w.finish().unwrap();
    let file = bag.join("small_0.mcap");
    let bytes = std::fs::read(&file).unwrap();
    (tmp, file, bytes)
}

fn u64_at(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap())
}

/// Offsets of the records with opcode `op` in the data section (walked from the header).
fn records(bytes: &[u8], op: u8) -> Vec<usize> {
    let mut pos = 8;
    let mut found = Vec::new();
    while pos + 9 <= bytes.len() && bytes[pos] != OP_FOOTER {
        if bytes[pos] == op {
            found.push(pos);
        }
        pos += 9 + u64_at(bytes, pos + 1) as usize;
    }
    found
}

/// Opens and reads every message; Ok(count) or the error text.
fn read_all(reader: Result<BagReader, cell_bag::BagError>) -> Result<usize, String> {
    let mut reader = reader.map_err(|e| e.to_string())?;
    let mut n = 0;
    for m in reader.messages() {
        m.map_err(|e| e.to_string())?;
        n += 1;
    }
    Ok(n)
}

#[test]
fn a_chunk_declaring_two_to_the_forty_bytes_is_refused_before_decompression() {
    let (tmp, file, mut bytes) = small_bag();
    let chunk = records(&bytes, OP_CHUNK)[0];
    // Chunk body: message_start_time, message_end_time, uncompressed_size, ...
    let size_at = chunk + 9 + 16;
    bytes[size_at..size_at + 8].copy_from_slice(&(1u64 << 40).to_le_bytes());
    let hostile = tmp.path().join("hostile.mcap");
    std::fs::write(&hostile, &bytes).unwrap();
    let e = read_all(BagReader::open(&hostile)).unwrap_err();
    assert!(e.contains("hostile.mcap"), "{e}");
    assert!(e.contains(&format!("at byte {chunk}:")), "{e}");
    assert!(
        e.contains("1099511627776 bytes uncompressed") && e.contains("limit of 1073741824"),
        "{e}"
    );
    // The original still reads: the limit is not in the way of real chunks.
    assert_eq!(read_all(BagReader::open(&file)), Ok(40));

    // Repair (the summary cut off) stops at that chunk for the same reason.
    std::fs::write(&hostile, &bytes[..bytes.len() - 100]).unwrap();
    let report = repair(&hostile).unwrap();
    let (at, why) = report.files[0].stopped.clone().unwrap();
    assert_eq!(at, chunk as u64);
    assert!(why.contains("limit of 1073741824"), "{why}");
    assert_eq!(report.files[0].messages, 0);
}

#[test]
fn a_chunk_expanding_beyond_the_ratio_is_refused_and_real_ones_read() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("zeros");
    let mut w = BagWriter::create(&bag, BagWriterOptions::default()).unwrap();
    // 2 MiB of zeros: zstd shrinks it far beyond 100:1.
    let map = HeatMap {
        width: 1024,
        height: 512,
        data: vec![0.0; 1024 * 512],
        ..Default::default()
    };
    w.write("/cell/sheet_heat", &map, 1_000).unwrap();
    w.finish().unwrap();
    let file = bag.join("zeros_0.mcap");
    assert_eq!(read_all(BagReader::open(&file)), Ok(1), "default limits");
    let strict = ChunkLimits {
        max_ratio: 100,
        ratio_floor_bytes: 1 << 20,
        ..ChunkLimits::default()
    };
    let e = read_all(BagReader::open(&file).map(|r| r.with_limits(strict))).unwrap_err();
    assert!(e.contains("zeros_0.mcap") && e.contains("at byte "), "{e}");
    assert!(
        e.contains("100:1") && e.contains("above 1048576 bytes"),
        "{e}"
    );
    // The same chunk under a floor above its size reads.
    let floor = ChunkLimits {
        ratio_floor_bytes: 4 << 20,
        ..strict
    };
    assert_eq!(
        read_all(BagReader::open(&file).map(|r| r.with_limits(floor))),
        Ok(1)
    );
}

/// Sets the statistics' start and end times and fixes the summary CRC.
fn set_statistics_times(bytes: &mut [u8], start: u64, end: u64) {
    let footer = bytes.len() - 8 - 29;
    assert_eq!(bytes[footer], OP_FOOTER);
    let summary_start = u64_at(bytes, footer + 9) as usize;
    let mut pos = summary_start;
    while bytes[pos] != OP_STATISTICS {
        pos += 9 + u64_at(bytes, pos + 1) as usize;
        assert!(pos < footer, "no statistics record");
    }
    // message_count u64, schema_count u16, channel_count u32, attachment_count u32,
    // metadata_count u32, chunk_count u32, then the two times.
    let times = pos + 9 + 8 + 2 + 4 * 4;
    bytes[times..times + 8].copy_from_slice(&start.to_le_bytes());
    bytes[times + 8..times + 16].copy_from_slice(&end.to_le_bytes());
    // summary_crc covers the summary section up to the footer's summary_offset_start.
    let crc_at = footer + 9 + 16;
    let crc = crc32fast::hash(&bytes[summary_start..crc_at]);
    bytes[crc_at..crc_at + 4].copy_from_slice(&crc.to_le_bytes());
}

#[test]
fn statistics_with_start_after_end_are_refused_naming_the_file_and_field() {
    let (tmp, file, mut bytes) = small_bag();
    let checked = tmp.path().join("checked.mcap");
    // The CRC fix-up itself is right: the true times read as before.
    set_statistics_times(&mut bytes, 1_000, 1_039);
    std::fs::write(&checked, &bytes).unwrap();
    assert_eq!(
        BagInfo::open(&checked).unwrap().time_range,
        BagInfo::open(&file).unwrap().time_range
    );

    set_statistics_times(&mut bytes, 5_000, 1_000);
    let hostile = tmp.path().join("backwards.mcap");
    std::fs::write(&hostile, &bytes).unwrap();
    for e in [
        BagInfo::open(&hostile).unwrap_err().to_string(),
        read_all(BagReader::open(&hostile)).unwrap_err(),
    ] {
        assert!(e.contains("backwards.mcap"), "{e}");
        assert!(
            e.contains("message_start_time 5000 is after message_end_time 1000"),
            "{e}"
        );
    }
}
