//! Bags we write are read back by us and, field for field, by two third-party decoders: the
//! PyPI `mcap` reader with `mcap-ros2-support`, and `rosbags`' AnyReader (metadata.yaml + MCAP,
//! types registered from the bag's schemas). See `tests/py/check_bag.py`.

mod common;

use std::time::Duration;

use cell_bag::{BagInfo, BagReader, BagWriter, BagWriterOptions, QosProfile};
use cell_msgs::{for_each_message, HeatMap, MachineStatus, RosMessage, Toolpath};
use common::{sample, third_party_read, toolpath};
use serde_json::{json, Value};

const T0: u64 = 1_795_000_000_000_000_000;

type Writer = fn(&mut BagWriter, u64) -> (String, &'static str, Value);

macro_rules! writers {
    ($($ty:ty => $name:literal),* $(,)?) => {
        vec![$(
            (|w: &mut BagWriter, t: u64| {
                let value: $ty = serde_json::from_value(sample($name, t % 97)).unwrap();
                let topic = format!("/samples/{}", $name.replace('/', "_"));
                w.write(&topic, &value, t).unwrap();
                (topic, $name, serde_json::to_value(&value).unwrap())
            }) as Writer
        ),*]
    };
}

/// (topic, type, log time, value as JSON) of everything written, in write order.
type Expected = Vec<(String, String, u64, Value)>;

fn write_cell_bag(dir: &std::path::Path, options: BagWriterOptions) -> Expected {
    let mut w = BagWriter::create(dir, options).unwrap();
    let mut expected = Expected::new();
    w.add_topic(
        "/cell/toolpath",
        Toolpath::ROS_NAME,
        &[QosProfile::reliable_transient_local(16)],
    )
    .unwrap();
    w.add_topic(
        "/cell/heat_map",
        HeatMap::ROS_NAME,
        &[QosProfile::best_effort(1)],
    )
    .unwrap();
    w.add_topic(
        "/machine_status",
        MachineStatus::ROS_NAME,
        &[QosProfile::reliable_volatile(32)],
    )
    .unwrap();
    let tp = toolpath("job-42");
    w.write("/cell/toolpath", &tp, T0).unwrap();
    expected.push((
        "/cell/toolpath".into(),
        Toolpath::ROS_NAME.into(),
        T0,
        serde_json::to_value(&tp).unwrap(),
    ));
    for i in 0..30u64 {
        let t = T0 + (i + 1) * 100_000_000;
        let status = MachineStatus {
            machine_id: "grbl-sim".into(),
            state: MachineStatus::STATE_RUNNING,
            acked_line: i as u32,
            axis_names: vec!["X".into(), "Y".into(), "U".into(), "V".into()],
            axis_positions: vec![i as f64 * 0.5, -1.25, 3.0, i as f64],
            ..Default::default()
        };
        w.write("/machine_status", &status, t).unwrap();
        expected.push((
            "/machine_status".into(),
            MachineStatus::ROS_NAME.into(),
            t,
            serde_json::to_value(&status).unwrap(),
        ));
        if i % 10 == 5 {
            let map = HeatMap {
                width: 64,
                height: 48,
                quantity: "sheet_temperature".into(),
                unit: "K".into(),
                threshold: 900.5,
                data: (0..64 * 48).map(|k| 290.0 + k as f32 * 0.25).collect(),
                ..Default::default()
            };
            w.write("/cell/heat_map", &map, t + 1).unwrap();
            expected.push((
                "/cell/heat_map".into(),
                HeatMap::ROS_NAME.into(),
                t + 1,
                serde_json::to_value(&map).unwrap(),
            ));
        }
    }
    for (k, write) in for_each_message!(writers).into_iter().enumerate() {
        let t = T0 + 3_500_000_000 + k as u64 * 1000;
        let (topic, ty, value) = write(&mut w, t);
        expected.push((topic, ty.into(), t, value));
    }
    w.finish().unwrap();
    expected
}

/// Our reader returns everything, in log-time order, decoding to the values written.
fn check_ours(bag: &std::path::Path, expected: &Expected) {
    let mut reader = BagReader::open(bag).unwrap();
    assert_eq!(reader.info().message_count, expected.len() as u64);
    let got: Vec<_> = reader.messages().map(|m| m.unwrap()).collect();
    let mut want = expected.clone();
    want.sort_by_key(|e| e.2);
    assert_eq!(got.len(), want.len());
    for (m, (topic, ty, t, value)) in got.iter().zip(&want) {
        assert_eq!(
            (&*m.topic, &*m.type_name, m.log_time_ns),
            (topic.as_str(), ty.as_str(), *t)
        );
        let decoded = cell_msgs::dynamic::decode(ty, &m.data).unwrap();
        assert_eq!(&decoded, value, "{topic}");
    }
    let tp: Toolpath = got[0].decode().unwrap();
    assert_eq!(tp.job_id, "job-42");
}

/// Both third-party readers decode every message to the values written; their lines, or
/// `None` when the readers cannot be installed (the caller skips the rest).
fn check_third_party(bag: &std::path::Path, expected: &Expected) -> Option<Vec<Value>> {
    let lines = third_party_read(bag)?;
    for reader in ["mcap", "rosbags"] {
        let got: Vec<&Value> = lines.iter().filter(|l| l["reader"] == reader).collect();
        assert_eq!(got.len(), expected.len(), "{reader} message count");
        for (topic, ty, t, value) in expected {
            let m = got
                .iter()
                .find(|l| l["topic"] == topic.as_str() && l["log_time"] == *t)
                .unwrap_or_else(|| panic!("{reader}: no {topic} at {t}"));
            assert_eq!(m["type"], ty.as_str());
            assert_eq!(&m["value"], value, "{reader}: {topic} at {t}");
        }
    }
    // AnyReader misfiles service parts (`pkg/srv/msg/Name_Request`); only those need the
    // checker's own typestore.
    let own_only = lines
        .iter()
        .find(|l| l["reader"] == "rosbags-own-store-only")
        .unwrap();
    for ty in own_only["types"].as_array().unwrap() {
        assert!(ty.as_str().unwrap().contains("/srv/"), "{ty}");
    }
    Some(lines)
}

#[test]
fn third_party_readers_decode_every_field() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("cell_run");
    let expected = write_cell_bag(&bag, BagWriterOptions::default());
    check_ours(&bag, &expected);
    let Some(lines) = check_third_party(&bag, &expected) else {
        return;
    };

    // Spot checks in the readers' own terms, beyond the whole-value comparison.
    let by = |reader: &str, topic: &str| -> Vec<Value> {
        lines
            .iter()
            .filter(|l| l["reader"] == reader && l["topic"] == topic)
            .map(|l| l["value"].clone())
            .collect()
    };
    for reader in ["mcap", "rosbags"] {
        let tp = &by(reader, "/cell/toolpath")[0];
        assert_eq!(tp["job_id"], "job-42");
        assert_eq!(
            tp["segments"][0]["points"][1],
            json!({"x": 100.0, "y": 42.125, "z": 3.0})
        );
        let hm = &by(reader, "/cell/heat_map")[0];
        assert_eq!(
            (hm["width"].as_u64(), hm["height"].as_u64()),
            (Some(64), Some(48))
        );
        assert_eq!(hm["data"].as_array().unwrap().len(), 64 * 48);
        let st = by(reader, "/machine_status");
        assert_eq!(st.len(), 30);
        assert_eq!(st[29]["state"], MachineStatus::STATE_RUNNING);
        assert_eq!(st[29]["axis_positions"], json!([14.5, -1.25, 3.0, 29.0]));
    }
    let file = lines.iter().find(|l| l["reader"] == "mcap-file").unwrap();
    assert_eq!(file["profile"], "ros2");
    assert!(file["library"].as_str().unwrap().contains("cellsuite"));
    assert_eq!(file["compression"], json!(["zstd"]));
    assert_eq!(file["message_indexes"], true);
    let channels = file["channels"].as_array().unwrap();
    let tp = channels
        .iter()
        .find(|c| c["topic"] == "/cell/toolpath")
        .unwrap();
    assert_eq!(
        (
            tp["encoding"].as_str(),
            tp["schema"].as_str(),
            tp["schema_encoding"].as_str()
        ),
        (Some("cdr"), Some("cell_msgs/msg/Toolpath"), Some("ros2msg"))
    );
    // The REP-2011 hash in the channel metadata (as rosbag2 Jazzy's MCAP storage puts it) and
    // in metadata.yaml (rosbags reads it from there), for every topic.
    let bag_info = lines.iter().find(|l| l["reader"] == "rosbags-bag").unwrap();
    let topics = bag_info["topics"].as_array().unwrap();
    for c in channels {
        let ros_type = c["schema"].as_str().unwrap();
        let hash = cell_msgs::type_hash(ros_type).unwrap().to_string();
        assert_eq!(c["type_hash"], hash, "mcap channel {}", c["topic"]);
        let t = topics.iter().find(|t| t["topic"] == c["topic"]).unwrap();
        assert_eq!(t["type_hash"], hash, "rosbags {}", c["topic"]);
    }
    assert_eq!(bag_info["message_count"], expected.len());
    let qos = |topic: &str| {
        bag_info["topics"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["topic"] == topic)
            .unwrap()["qos"][0]
            .clone()
    };
    assert_eq!(
        qos("/cell/toolpath"),
        json!({"reliability": "RELIABLE", "durability": "TRANSIENT_LOCAL", "history": "KEEP_LAST", "depth": 16})
    );
    assert_eq!(
        qos("/cell/heat_map"),
        json!({"reliability": "BEST_EFFORT", "durability": "VOLATILE", "history": "KEEP_LAST", "depth": 1})
    );
    assert_eq!(
        qos("/machine_status"),
        json!({"reliability": "RELIABLE", "durability": "VOLATILE", "history": "KEEP_LAST", "depth": 32})
    );
}

#[test]
fn split_bags_are_read_across_files() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("split_run");
    let options = BagWriterOptions {
        max_file_duration: Some(Duration::from_secs(1)),
        chunk_size: 4096,
        ..Default::default()
    };
    let expected = write_cell_bag(&bag, options);
    let info = BagInfo::open(&bag).unwrap();
    let names: Vec<String> = info
        .files
        .iter()
        .map(|f| f.path.file_name().unwrap().to_string_lossy().into())
        .collect();
    assert_eq!(
        names,
        [
            "split_run_0.mcap",
            "split_run_1.mcap",
            "split_run_2.mcap",
            "split_run_3.mcap"
        ]
    );
    assert_eq!(
        info.files.iter().map(|f| f.message_count).sum::<u64>(),
        expected.len() as u64
    );
    check_ours(&bag, &expected);
    let Some(lines) = check_third_party(&bag, &expected) else {
        return;
    };
    assert_eq!(
        lines.iter().filter(|l| l["reader"] == "mcap-file").count(),
        4
    );
}

#[test]
fn metadata_yaml_and_info_display() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("meta_run");
    let expected = write_cell_bag(&bag, BagWriterOptions::default());
    let text = std::fs::read_to_string(bag.join("metadata.yaml")).unwrap();
    assert!(
        text.starts_with(
            "rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: mcap\n"
        ),
        "{text}"
    );
    let meta = cell_bag::MetadataFile::read(&bag)
        .unwrap()
        .rosbag2_bagfile_information;
    let last = expected.iter().map(|e| e.2).max().unwrap();
    assert_eq!(meta.message_count, expected.len() as u64);
    assert_eq!(meta.starting_time.nanoseconds_since_epoch, T0);
    assert_eq!(meta.duration.nanoseconds, last - T0);
    assert_eq!(meta.relative_file_paths, ["meta_run_0.mcap"]);
    assert_eq!(meta.files[0].path, "meta_run_0.mcap");
    assert_eq!(meta.files[0].message_count, expected.len() as u64);
    assert_eq!(
        (
            meta.compression_format.as_str(),
            meta.compression_mode.as_str()
        ),
        ("", "")
    );
    let tp = &meta.topics_with_message_count[0];
    assert_eq!(
        (
            tp.topic_metadata.name.as_str(),
            tp.topic_metadata.type_name.as_str()
        ),
        ("/cell/toolpath", "cell_msgs/msg/Toolpath")
    );
    assert_eq!(tp.topic_metadata.serialization_format, "cdr");
    assert_eq!(tp.message_count, 1);
    // rosbag2 version 7's hash and version 8's distro; our reader sees the channel's hash.
    let toolpath_hash = cell_msgs::type_hash(Toolpath::ROS_NAME)
        .unwrap()
        .to_string();
    assert_eq!(tp.topic_metadata.type_description_hash, toolpath_hash);
    assert!(
        text.contains(&format!("      type_description_hash: {toolpath_hash}\n")),
        "{text}"
    );
    assert_eq!(meta.ros_distro, "jazzy");
    assert!(
        text.contains("\n  custom_data: {}\n  ros_distro: jazzy\n"),
        "{text}"
    );
    let ours = BagInfo::open(&bag).unwrap();
    for t in &ours.topics {
        let hash = cell_msgs::type_hash(&t.type_name).unwrap().to_string();
        assert_eq!(t.type_hash, hash, "{}", t.name);
    }
    assert_eq!(
        cell_bag::qos::from_yaml(&tp.topic_metadata.offered_qos_profiles).unwrap(),
        [Some(QosProfile::reliable_transient_local(16))]
    );

    let info = BagInfo::open(&bag).unwrap().to_string();
    assert!(
        info.starts_with("Files:             meta_run_0.mcap\nBag size:          "),
        "{info}"
    );
    assert!(info.contains("Storage id:        mcap\n"), "{info}");
    assert!(
        info.contains(&format!("Messages:          {}\n", expected.len())),
        "{info}"
    );
    assert!(info.contains("Topic information: Topic: /cell/toolpath | Type: cell_msgs/msg/Toolpath | Count: 1 | Serialization Format: cdr\n"), "{info}");
}
