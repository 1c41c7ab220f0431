//! rosbag2 MCAP bags: the reader (summary, then every message decoded by its registered type),
//! and repair (the scanner that walks a damaged file record by record, the rewrite, the new
//! `metadata.yaml`), on files in a tmpfs scratch directory (both take a path).

use std::path::Path;

use cell_bag::{repair, BagReader, BagWriter, BagWriterOptions};
use cell_msgs::std_msgs::StringMsg;

use crate::{scratch_dir, Target};

const TOKENS: &[&str] = &[
    "\u{89}MCAP0\r\n",
    "ros2msg",
    "cdr",
    "std_msgs/msg/String",
    "cell_msgs/msg/MachineStatus",
    "/chatter",
    "offered_qos_profiles",
    "\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}",
    "\u{ff}\u{ff}\u{ff}\u{ff}\u{ff}\u{ff}\u{ff}\u{7f}",
];

/// Reads at most this many messages of one input (a bag can claim billions).
const MESSAGES: usize = 10_000;

fn read_all(path: &Path) {
    let Ok(mut reader) = BagReader::open(path) else {
        return;
    };
    let _ = reader.info().duration_ns();
    for message in reader.messages().take(MESSAGES) {
        let Ok(m) = message else { break };
        let _ = cell_msgs::dynamic::decode(&m.type_name, &m.data);
    }
}

fn fresh(what: &str) -> std::path::PathBuf {
    let dir = scratch_dir(what);
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::create_dir_all(&dir);
    dir
}

fn reader(data: &[u8]) {
    let path = fresh("bag_reader").join("fuzz_0.mcap");
    if std::fs::write(&path, data).is_ok() {
        read_all(&path);
    }
}

fn repair_target(data: &[u8]) {
    let dir = fresh("bag_repair");
    if std::fs::write(dir.join("fuzz_0.mcap"), data).is_err() {
        return;
    }
    if repair(&dir).is_ok() {
        read_all(&dir);
    }
}

/// Bags the library writes: finished, and cut off mid-file as a crash leaves them.
fn seeds() -> Vec<Vec<u8>> {
    let dir = fresh("bag_seed").join("seed");
    let options = BagWriterOptions {
        chunk_size: 256,
        ..BagWriterOptions::default()
    };
    let Ok(mut w) = BagWriter::create(&dir, options) else {
        return Vec::new();
    };
    for i in 0..20u64 {
        let msg = StringMsg {
            data: format!("message {i}"),
        };
        let _ = w.write("/chatter", &msg, 1_000 + i * 1_000_000);
        let status = cell_msgs::MachineStatus::default();
        let _ = w.write("/machine_status", &status, 2_000 + i * 1_000_000);
    }
    let _ = w.finish();
    let mut out: Vec<Vec<u8>> = std::fs::read_dir(&dir)
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
        .filter_map(|p| std::fs::read(p).ok())
        .collect();
    if let Some(full) = out.first().cloned() {
        out.push(full[..full.len() * 2 / 3].to_vec());
    }
    out
}

/// The bag targets.
pub fn targets() -> Vec<Target> {
    vec![
        Target {
            name: "bag_reader",
            about: "MCAP bag reader: summary, chunks, messages decoded by type",
            run: reader,
            seeds,
            tokens: TOKENS,
            max_len: 1 << 16,
        },
        Target {
            name: "bag_repair",
            about: "bag repair: record scanner, rewrite, metadata.yaml",
            run: repair_target,
            seeds,
            tokens: TOKENS,
            max_len: 1 << 16,
        },
    ]
}
