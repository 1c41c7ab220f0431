//! Crash safety: a writer killed with SIGKILL mid-write leaves a bag that [`cell_bag::repair`]
//! makes readable up to its last completed chunk, and third-party readers then read it.
//! Also: truncated and byte-flipped files give errors naming the file, never panics.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use cell_bag::{repair, BagError, BagInfo, BagReader, BagWriter, BagWriterOptions};
use cell_msgs::MachineStatus;
use proptest::prelude::*;

const CHILD_ENV: &str = "CELL_BAG_CRASH_CHILD";

fn status(i: u64) -> MachineStatus {
    MachineStatus {
        machine_id: "grbl-sim".into(),
        state: MachineStatus::STATE_RUNNING,
        acked_line: i as u32,
        axis_names: vec!["X".into(), "Y".into()],
        axis_positions: vec![i as f64, -(i as f64)],
        ..Default::default()
    }
}

/// In the child: writes statuses (small chunks, small split files) until killed.
#[test]
fn crash_child() {
    let Ok(dir) = std::env::var(CHILD_ENV) else {
        return; // Only does something when started by `sigkill_mid_write_then_repair`.
    };
    let options = BagWriterOptions {
        chunk_size: 2048,
        max_file_size: Some(16 * 1024),
        ..Default::default()
    };
    let dir = Path::new(&dir);
    let mut w = BagWriter::create(dir, options).unwrap();
    // Writes until the third split file holds complete chunks, then stops mid-file and says
    // so; the parent kills it there, so the last file is never finished (killing at a random
    // moment could land between two files, leaving nothing to repair).
    let mut in_third_file = 0;
    for i in 0.. {
        w.write("/machine_status", &status(i), 1_000_000_000 + i * 1_000_000)
            .unwrap();
        if dir.join("killed_2.mcap").exists() {
            in_third_file += 1;
            if in_third_file == 200 {
                std::fs::write(dir.join("ready"), b"").unwrap();
                std::thread::sleep(Duration::from_secs(120));
            }
        }
    }
}

#[test]
fn sigkill_mid_write_then_repair() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("killed");
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "crash_child", "--nocapture"])
        .env(CHILD_ENV, &bag)
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    // Kill once a few files have been split off and the current one holds chunks.
    let deadline = Instant::now() + Duration::from_secs(60);
    while !bag.join("ready").exists() {
        assert!(Instant::now() < deadline, "child wrote too little");
        std::thread::sleep(Duration::from_millis(5));
    }
    std::fs::remove_file(bag.join("ready")).unwrap();
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();

    // The last file has no summary: reading says so and names it.
    let err = BagInfo::open(&bag).unwrap_err();
    assert!(matches!(err, BagError::Unfinished { .. }), "{err}");
    assert!(err.to_string().contains(".mcap"), "{err}");

    let report = repair(&bag).unwrap();
    let repaired: Vec<_> = report.repaired().collect();
    assert_eq!(repaired.len(), 1, "{report:?}");
    assert!(repaired[0].original.as_ref().unwrap().exists());
    let files: Vec<_> = report
        .files
        .iter()
        .map(|f| f.path.file_name().unwrap().to_owned())
        .collect();
    assert!(files.len() >= 3, "{files:?}");

    // Everything up to the last complete chunk is there, in order, with no gaps.
    let mut reader = BagReader::open(&bag).unwrap();
    let total = reader.info().message_count;
    assert!(total > 0);
    let mut n = 0;
    for m in reader.messages() {
        let m = m.unwrap();
        let s: MachineStatus = m.decode().unwrap();
        assert_eq!(
            s.acked_line as u64, n,
            "messages are contiguous from the start"
        );
        assert_eq!(m.log_time_ns, 1_000_000_000 + n * 1_000_000);
        n += 1;
    }
    assert_eq!(n, total);
    let meta = cell_bag::MetadataFile::read(&bag)
        .unwrap()
        .rosbag2_bagfile_information;
    assert_eq!(meta.message_count, total);
    assert_eq!(meta.relative_file_paths.len(), files.len());

    // A second repair finds nothing to do.
    assert_eq!(repair(&bag).unwrap().repaired().count(), 0);

    // And the third-party readers read the repaired bag.
    let Some(lines) = common::third_party_read(&bag) else {
        return;
    };
    for reader in ["mcap", "rosbags"] {
        assert_eq!(
            lines.iter().filter(|l| l["reader"] == reader).count() as u64,
            total,
            "{reader}"
        );
    }
}

/// A small finished single-file bag, as bytes.
fn small_bag() -> (tempfile::TempDir, Vec<u8>) {
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
    w.write("/cell/toolpath", &common::toolpath("j"), 5_000)
        .unwrap();
    w.finish().unwrap();
    let bytes = std::fs::read(bag.join("small_0.mcap")).unwrap();
    (tmp, bytes)
}

/// Opens and reads every message of `file`; Ok(count) or the error text.
fn read_all(file: &Path) -> Result<usize, String> {
    let mut reader = BagReader::open(file).map_err(|e| e.to_string())?;
    let mut n = 0;
    for m in reader.messages() {
        m.map_err(|e| e.to_string())?;
        n += 1;
    }
    Ok(n)
}

#[test]
fn truncated_files_are_errors_naming_the_file_and_repairable() {
    let (tmp, bytes) = small_bag();
    let file = tmp.path().join("cut.mcap");
    let len = bytes.len();
    for cut in [
        0,
        3,
        8,
        20,
        len / 4,
        len / 2,
        len - 200,
        len - 30,
        len - 9,
        len - 1,
    ] {
        std::fs::write(&file, &bytes[..cut]).unwrap();
        let err = read_all(&file).unwrap_err();
        assert!(err.contains("cut.mcap"), "cut at {cut}: {err}");
        // Repair keeps what came before the cut; below the magic it is not an MCAP at all.
        match repair(&file) {
            Ok(report) => {
                let got = read_all(&file).unwrap();
                assert_eq!(got as u64, report.files[0].messages, "cut at {cut}");
            }
            Err(e) => assert!(
                cut < 8 && cut > 0 || e.to_string().contains("cut.mcap"),
                "cut at {cut}: {e}"
            ),
        }
        for extra in std::fs::read_dir(tmp.path()).unwrap() {
            let p = extra.unwrap().path();
            if p.is_file() {
                std::fs::remove_file(p).unwrap();
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Random byte flips: reading gives the messages or an error naming the file, never a panic.
    #[test]
    fn byte_flips_never_panic(flips in proptest::collection::vec((any::<prop::sample::Index>(), 1u8..=255), 1..4)) {
        let (tmp, mut bytes) = small_bag();
        for (at, mask) in flips {
            let i = at.index(bytes.len());
            bytes[i] ^= mask;
        }
        let file = tmp.path().join("flipped.mcap");
        std::fs::write(&file, &bytes).unwrap();
        if let Err(e) = read_all(&file) {
            prop_assert!(e.contains("flipped.mcap"), "{}", e);
        }
        let _ = repair(&file); // must not panic either
    }
}
