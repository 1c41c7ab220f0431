//! Interoperability with an independent DDS implementation: Eclipse Cyclone DDS (PyPI
//! `cyclonedds`, driven by `tests/interop/ros_peer.py`) sees our topics under ROS 2 naming
//! (`rt/…`, `…::msg::dds_::…_`), decodes a `std_msgs/String` and a `cell_msgs/Toolpath` from our
//! node, and publishes a `std_msgs/String` that our node receives. Both sides stay on loopback
//! (`tests/interop/cyclonedds.xml`).

mod common;

use std::{path::PathBuf, process::Stdio, time::Duration};

use cell_msgs::{std_msgs::StringMsg, Toolpath};
use cell_runtime::QosPreset;
use common::{fresh_domain, node, DELIVERY_TIMEOUT};
use probe::{test_block, ProbeParams};
use tokio::io::{AsyncBufReadExt, BufReader};

fn peer_script() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/interop/ros_peer.py")
}

/// The Python that runs the Cyclone peer (see [`common::venv_python`]); `None`: skip.
fn python() -> Option<String> {
    common::venv_python(
        "interop-venv",
        "tests/interop/requirements.txt",
        "cyclonedds",
    )
    .map(|python| python.display().to_string())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cyclone_dds_decodes_our_topics_and_we_decode_theirs() {
    let Some(python) = python() else { return };
    let domain = fresh_domain();
    let ours = node("interop", domain, false);

    // Our side publishes; Cyclone listens.
    let chatter = ours
        .publisher::<StringMsg>("/chatter", QosPreset::Plan)
        .unwrap();
    let toolpaths = ours
        .publisher::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let block = test_block(&ProbeParams {
        job_id: "interop-1".into(),
        ..Default::default()
    });
    chatter
        .publish(StringMsg {
            data: "hello from cellsuite".into(),
        })
        .await
        .unwrap();
    toolpaths.publish(block.clone()).await.unwrap();

    let mut listen = tokio::process::Command::new(&python)
        .arg(peer_script())
        .args(["listen", "--domain", &domain.to_string(), "--timeout", "60"])
        .args([
            "--topic",
            "chatter:std_msgs/String",
            "--topic",
            "toolpath:cell_msgs/Toolpath",
        ])
        .stdout(Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .expect("start the Cyclone peer");
    let mut lines = BufReader::new(listen.stdout.take().unwrap()).lines();
    let mut samples = Vec::new();
    while let Some(line) = lines.next_line().await.unwrap() {
        samples.push(serde_json::from_str::<serde_json::Value>(&line).expect("peer prints JSON"));
    }
    let status = listen.wait().await.unwrap();
    assert!(status.success(), "Cyclone peer: {status}; got {samples:?}");

    let string = samples
        .iter()
        .find(|s| s["topic"] == "rt/chatter")
        .expect("String sample");
    assert_eq!(string["type"], "std_msgs::msg::dds_::String_");
    assert_eq!(string["value"]["data"], "hello from cellsuite");

    let tp = samples
        .iter()
        .find(|s| s["topic"] == "rt/toolpath")
        .expect("Toolpath sample");
    assert_eq!(tp["type"], "cell_msgs::msg::dds_::Toolpath_");
    let value = &tp["value"];
    assert_eq!(value["job_id"], "interop-1");
    assert_eq!(value["header"]["frame_id"], block.header.frame_id.as_str());
    assert_eq!(value["plane_separation_mm"], block.plane_separation_mm);
    let segments = value["segments"].as_array().unwrap();
    assert_eq!(segments.len(), block.segments.len());
    for (theirs, ours) in segments.iter().zip(&block.segments) {
        assert_eq!(theirs["kind"], ours.kind);
        let points = theirs["points"].as_array().unwrap();
        assert_eq!(points.len(), ours.points.len());
        for (p, q) in points.iter().zip(&ours.points) {
            assert_eq!(
                (p["x"].as_f64(), p["y"].as_f64(), p["z"].as_f64()),
                (Some(q.x), Some(q.y), Some(q.z))
            );
        }
        let tip = theirs["secondary_points"].as_array().unwrap();
        assert_eq!(tip.len(), ours.secondary_points.len());
        let feeds: Vec<f32> = theirs["feed_mm_s"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        assert_eq!(feeds, ours.feed_mm_s);
    }

    // Cyclone publishes; our side listens.
    let mut inbox = ours
        .subscriber::<StringMsg>("/from_cyclone", QosPreset::Plan)
        .unwrap();
    let mut talk = tokio::process::Command::new(&python)
        .arg(peer_script())
        .args([
            "talk",
            "--domain",
            &domain.to_string(),
            "--topic",
            "from_cyclone",
        ])
        .args([
            "--data",
            "hello from cyclone",
            "--count",
            "60",
            "--period",
            "0.25",
        ])
        .kill_on_drop(true)
        .spawn()
        .expect("start the Cyclone talker");
    let got = tokio::time::timeout(DELIVERY_TIMEOUT, inbox.recv())
        .await
        .expect("Cyclone's String arrived before the timeout")
        .unwrap();
    assert_eq!(got.message.data, "hello from cyclone");
    let _ = talk.start_kill();
    let _ = tokio::time::timeout(Duration::from_secs(5), talk.wait()).await;
}
