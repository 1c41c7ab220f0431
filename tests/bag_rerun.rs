//! `cell bag to-rerun`: a bag with a real planner toolpath, exposure heat maps, a machine's
//! status series and its program becomes a Rerun recording that Rerun's own tool accepts, with
//! the live nodes' entities; bad input is one error line and exit 64/65, never a panic.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use cell_bag::{BagWriter, BagWriterOptions};
use cell_msgs::builtin_interfaces::Time;
use cell_msgs::std_msgs::Header;
use cell_msgs::{
    HeatMap, MachineCommand, MachineProgram, MachineStatus, ProgramFile, RosMessage, Toolpath,
};

/// 2026-11-22 12:00:00 UTC, in ns: the bag's first log time.
const T0_NS: u64 = 1_795_348_800_000_000_000;

fn cell(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cell"))
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run cell")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn stamp(ns: u64) -> Time {
    Time {
        sec: (ns / 1_000_000_000) as i32,
        nanosec: (ns % 1_000_000_000) as u32,
    }
}

/// The planner's 4-axis S1223 wing (`tests/data/toolpaths/wing.json`).
fn wing() -> Toolpath {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/toolpaths/wing.json"
    );
    cell_msgs::json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A 1-row exposure profile as the planner publishes it (frame = section, threshold = CSE).
fn profile(frame: &str, scale: f32, ns: u64) -> HeatMap {
    let data: Vec<f32> = (0..200)
        .map(|i| scale * (1.0 + (i as f32 * 0.05).sin()))
        .collect();
    HeatMap {
        header: Header {
            stamp: stamp(ns),
            frame_id: frame.into(),
        },
        quantity: "exposure_profile".into(),
        unit: "1".into(),
        width: data.len() as u32,
        height: 1,
        cell_width_mm: 1.0,
        cell_height_mm: 1.0,
        threshold: 1.5,
        data,
        ..HeatMap::default()
    }
}

/// Writes a bag of what the demo cell publishes, plus one message of a type this suite does
/// not know and one that does not decode. Returns the bag directory.
fn write_bag(dir: &Path) -> PathBuf {
    let bag = dir.join("run1");
    // Small chunks, so the truncation test can cut a file that still holds complete ones.
    let options = BagWriterOptions {
        chunk_size: 16 * 1024,
        ..BagWriterOptions::default()
    };
    let mut w = BagWriter::create(&bag, options).unwrap();
    let ms = |ms: u64| T0_NS + ms * 1_000_000;
    for (i, frame) in ["hotwire_root", "hotwire_tip"].iter().enumerate() {
        for k in 0..3u64 {
            let t = ms(100 * k + i as u64);
            w.write(
                "/cell/exposure",
                &profile(frame, 1.0 - 0.1 * k as f32, t),
                t,
            )
            .unwrap();
        }
    }
    let mut toolpath = wing();
    toolpath.header.stamp = stamp(ms(500));
    w.write("/cell/toolpath", &toolpath, ms(500)).unwrap();
    let program_text = "G21 G90 G93\nG1 X10 Y10 U10 V10 F2\nM2\n";
    let program = MachineProgram {
        header: Header {
            stamp: stamp(ms(600)),
            frame_id: String::new(),
        },
        job_id: "wing".into(),
        dialect: "grbl".into(),
        machine_profile: "grbl-xyuv".into(),
        files: vec![ProgramFile {
            name: "wing.ngc".into(),
            text: program_text.into(),
        }],
        line_count: 3,
        sha256: "0".repeat(64),
    };
    w.write("/cell/machine_program", &program, ms(600)).unwrap();
    // The machine moves along the wing's first cut for 100 status ticks, then stops.
    for i in 0..100u64 {
        let t = ms(700 + 100 * i);
        let x = i as f64;
        let status = MachineStatus {
            header: Header {
                stamp: stamp(t),
                frame_id: "grbl-sim".into(),
            },
            machine_id: "grbl-sim".into(),
            state: if i < 99 {
                MachineStatus::STATE_RUNNING
            } else {
                MachineStatus::STATE_IDLE
            },
            job_id: "wing".into(),
            acked_line: i as u32,
            total_lines: 3,
            axis_names: ["X", "Y", "U", "V"].map(String::from).to_vec(),
            axis_positions: vec![x, 60.0 + x / 10.0, x - 5.0, 60.0],
            buffer_fill: 0.5,
            feed_mm_s: 2.0,
            ..MachineStatus::default()
        };
        w.write("/cell/machine_status", &status, t).unwrap();
    }
    let hold = MachineCommand {
        machine_id: "grbl-sim".into(),
        command: MachineCommand::COMMAND_HOLD,
        value: 0,
    };
    w.write("/cell/machine_command", &hold, ms(900)).unwrap();
    w.add_topic_with_definition("/cell/other", "other_msgs/msg/Thing", "int32 x\n", &[])
        .unwrap();
    w.write_raw(
        "/cell/other",
        "other_msgs/msg/Thing",
        &[0, 1, 0, 0, 7, 0, 0, 0],
        ms(950),
    )
    .unwrap();
    // A Toolpath whose CDR ends after the encapsulation header.
    w.write_raw("/cell/broken", Toolpath::ROS_NAME, &[0, 1, 0, 0], ms(960))
        .unwrap();
    w.finish().unwrap();
    bag
}

#[test]
fn a_bag_becomes_a_recording_drawn_like_the_live_nodes() {
    let dir = tempfile::tempdir().unwrap();
    let bag = write_bag(dir.path());
    let rrd = dir.path().join("out/run1.rrd");
    let out = cell(&[
        "bag",
        "to-rerun",
        bag.to_str().unwrap(),
        "--out",
        rrd.to_str().unwrap(),
    ]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "stdout:\n{stdout}\nstderr:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // The summary: every message counted, the two bad ones skipped and warned about once.
    assert!(
        stdout.contains("109 messages converted, 2 skipped"),
        "{stdout}"
    );
    let row = |topic: &str| {
        stdout
            .lines()
            .find(|l| l.split_whitespace().next() == Some(topic))
            .unwrap_or_else(|| panic!("no row for {topic} in {stdout}"))
            .split_whitespace()
            .skip(1)
            .take(2)
            .collect::<Vec<_>>()
    };
    assert_eq!(row("/cell/machine_status"), ["100", "0"]);
    assert_eq!(row("/cell/exposure"), ["6", "0"]);
    assert_eq!(row("/cell/toolpath"), ["1", "0"]);
    assert_eq!(row("/cell/machine_program"), ["1", "0"]);
    assert_eq!(row("/cell/machine_command"), ["1", "0"]);
    assert_eq!(row("/cell/other"), ["0", "1"]);
    assert_eq!(row("/cell/broken"), ["0", "1"]);
    for warned in ["/cell/other", "/cell/broken"] {
        assert_eq!(
            stderr.matches(&format!("warning: {warned} ")).count(),
            1,
            "{stderr}"
        );
    }
    assert!(!dir.path().join("out/run1.rrd.tmp").exists());

    let dump = common::rrd_dump(&rrd);
    for entity in [
        // The planner's toolpath, through log_toolpath at toolpath_entity.
        "\"/hotwire/trajectory\"",
        "/hotwire/trajectory_tip",
        // Heat maps per topic and frame, and their exposure scalars.
        "\"/cell/exposure/hotwire_root\"",
        "\"/cell/exposure/hotwire_tip\"",
        "/cell/exposure/hotwire_root/max",
        "/cell/exposure/hotwire_root/mean",
        "/cell/exposure/hotwire_tip/threshold",
        // MachineStatusLogger: position, trace chunks (100 points: a full chunk and the rest
        // when the machine stops), scalars.
        "/machine/grbl-sim/position",
        "/machine/grbl-sim/trace/0",
        "/machine/grbl-sim/trace/1",
        "/machine/grbl-sim/feed_mm_s",
        // The program: the emitter's summary line and the file as a document.
        "/emitter/log",
        "/programs/wing/wing.ngc",
        // Another known type as a text line under its topic.
        "\"/cell/machine_command\"",
        // Both timelines.
        "log_time",
        "ros_time",
    ] {
        assert!(dump.contains(entity), "{} has no {entity}", rrd.display());
    }
    assert!(!dump.contains("/cell/other"), "a skipped message was drawn");
    assert!(
        dump.contains("job wing: profile grbl-xyuv, dialect grbl, 3 lines"),
        "the emitter's summary line"
    );

    // Rerun's own tool (PyPI rerun-sdk of the crate's version) accepts the file.
    common::rrd_verify(&rrd);

    // Without --out, the recording goes beside the bag as BAG.rrd.
    let out = cell(&["bag", "to-rerun", bag.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(dir.path().join("run1.rrd").is_file());
}

#[test]
fn bad_bags_and_outputs_are_one_error_line_never_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let bag = write_bag(dir.path());
    let rrd = dir.path().join("cut.rrd");
    let assert_error = |out: &Output, code: i32, needles: &[&str]| {
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        let line = stderr
            .lines()
            .find(|l| l.starts_with("error:"))
            .unwrap_or_else(|| panic!("no error line in {stderr}"));
        for needle in needles {
            assert!(stderr.contains(needle), "{needle:?} not in {line:?}");
        }
    };

    // An output that cannot be written: under a regular file, or a directory.
    let not_a_dir = dir.path().join("file");
    std::fs::write(&not_a_dir, "x").unwrap();
    let blocked = not_a_dir.join("x.rrd");
    let out = cell(&[
        "bag",
        "to-rerun",
        bag.to_str().unwrap(),
        "--out",
        blocked.to_str().unwrap(),
    ]);
    assert_error(&out, 64, &["--out", blocked.to_str().unwrap()]);
    let out = cell(&[
        "bag",
        "to-rerun",
        bag.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_error(&out, 64, &["is a directory"]);

    // No such bag.
    let out = cell(&[
        "bag",
        "to-rerun",
        "/no/such/bag",
        "--out",
        rrd.to_str().unwrap(),
    ]);
    assert_error(&out, 64, &["/no/such/bag"]);

    // Cut as a killed recorder leaves it: no summary, a torn last record.
    let mcap = std::fs::read_dir(&bag)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "mcap"))
        .unwrap();
    let bytes = std::fs::read(&mcap).unwrap();
    std::fs::write(&mcap, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let out = cell(&[
        "bag",
        "to-rerun",
        bag.to_str().unwrap(),
        "--out",
        rrd.to_str().unwrap(),
    ]);
    assert_error(
        &out,
        65,
        &[
            mcap.file_name().unwrap().to_str().unwrap(),
            &format!("cell bag repair {}", bag.display()),
        ],
    );
    assert!(
        !rrd.exists(),
        "nothing written from a bag that cannot be read"
    );
    assert!(!dir.path().join("cut.rrd.tmp").exists());

    // After `cell bag repair`, the complete chunks convert.
    let out = cell(&["bag", "repair", bag.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = cell(&[
        "bag",
        "to-rerun",
        bag.to_str().unwrap(),
        "--out",
        rrd.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(common::rrd_dump(&rrd).contains("/machine/grbl-sim/position"));
}
