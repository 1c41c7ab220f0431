//! The recorder node over real DDS (and the iceoryx2 fast path for heat maps): it finds the
//! topics by discovery, records them to a rosbag2 MCAP bag, and the bag reads back equal to
//! what was published, with our reader and with the PyPI `mcap` and `rosbags` readers.

mod common;

use std::time::Duration;

use cell_bag::BagReader;
use cell_msgs::{HeatMap, MachineStatus, Toolpath};
use cell_runtime::{CellNode, NodeSetup, QosPreset};
use common::{fresh_domain, node, within, DELIVERY_TIMEOUT};
use probe::{test_block, ProbeParams};
use recorder::{run, RecorderParams};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_recorder_writes_what_was_published_and_third_party_readers_agree() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("run1");
    let domain = fresh_domain();
    let setup = NodeSetup::local("recorder", domain);
    let shutdown = setup.shutdown.clone();
    let recorder = tokio::spawn(run(
        CellNode::new(setup).unwrap(),
        RecorderParams {
            output: bag.display().to_string(),
            topics: vec!["/cell/.*".into()],
            discover_every_s: 0.2,
            ..RecorderParams::default()
        },
    ));
    let publisher = node("publisher", domain, true);
    let toolpaths = publisher
        .publisher::<Toolpath>("/cell/toolpath", QosPreset::Plan)
        .unwrap();
    let statuses = publisher
        .publisher::<MachineStatus>("/cell/machine_status", QosPreset::Status)
        .unwrap();
    let heat = publisher
        .publisher::<HeatMap>("/cell/heat", QosPreset::Stream)
        .unwrap();
    let ignored = publisher
        .publisher::<MachineStatus>("/other/machine_status", QosPreset::Status)
        .unwrap();
    for (name, matched) in [
        (
            "toolpath",
            toolpaths.wait_for_subscribers(1, DELIVERY_TIMEOUT).await,
        ),
        (
            "machine_status",
            statuses.wait_for_subscribers(1, DELIVERY_TIMEOUT).await,
        ),
        ("heat", heat.wait_for_subscribers(1, DELIVERY_TIMEOUT).await),
    ] {
        assert!(matched, "the recorder never subscribed to /cell/{name}");
    }
    // The recorder's readers are matched; give reliable ones a moment to see our writers too.
    tokio::time::sleep(Duration::from_millis(500)).await;

    let block = test_block(&ProbeParams::default());
    toolpaths.publish(block.clone()).await.unwrap();
    let sent: Vec<MachineStatus> = (0..50u32)
        .map(|i| MachineStatus {
            machine_id: "grbl-sim".into(),
            state: MachineStatus::STATE_RUNNING,
            acked_line: i,
            axis_names: vec!["X".into(), "Y".into()],
            axis_positions: vec![f64::from(i), 0.5 * f64::from(i)],
            ..MachineStatus::default()
        })
        .collect();
    for s in &sent {
        statuses.publish(s.clone()).await.unwrap();
        ignored.publish(s.clone()).await.unwrap();
    }
    let maps: Vec<HeatMap> = (0..3)
        .map(|k| {
            let data = (0..64 * 48).map(|i| (i + k * 7) as f32 * 0.25).collect();
            HeatMap::new("sheet_temperature", "K", 64, 48, data).unwrap()
        })
        .collect();
    for m in &maps {
        heat.publish(m.clone()).await.unwrap();
        // Keep-last-1 best effort: one frame in flight at a time.
        tokio::time::sleep(Duration::from_millis(300)).await;
    }
    tokio::time::sleep(Duration::from_secs(1)).await;
    shutdown.trigger();
    within(recorder).await.unwrap().unwrap();

    let mut reader = BagReader::open(&bag).unwrap();
    let info = reader.info().clone();
    let topics: Vec<&str> = info.topics.iter().map(|t| t.name.as_str()).collect();
    assert!(!topics.contains(&"/other/machine_status"), "{topics:?}");
    let mut got_toolpaths = Vec::new();
    let mut got_statuses = Vec::new();
    let mut got_maps = Vec::new();
    for m in reader.messages() {
        let m = m.unwrap();
        match &*m.topic {
            "/cell/toolpath" => got_toolpaths.push(m.decode::<Toolpath>().unwrap()),
            "/cell/machine_status" => got_statuses.push(m.decode::<MachineStatus>().unwrap()),
            "/cell/heat" => got_maps.push(m.decode::<HeatMap>().unwrap()),
            other => panic!("unexpected topic {other}"),
        }
    }
    assert_eq!(got_toolpaths, vec![block], "the toolpath, bit for bit");
    assert_eq!(got_statuses, sent, "every status, in order (reliable)");
    assert!(!got_maps.is_empty(), "heat maps recorded");
    // (A HeatMap without a threshold holds NaN there, which `==` never equals.)
    let key = |m: &HeatMap| (m.quantity.clone(), m.width, m.height, m.data.clone());
    for m in &got_maps {
        assert!(m.threshold.is_nan());
        assert!(
            maps.iter().any(|p| key(p) == key(m)),
            "a recorded heat map equals a published one"
        );
    }

    // Independent readers decode the whole bag.
    let Some(python) = common::venv_python(
        "bag-venv",
        "crates/bag/tests/py/requirements.txt",
        "rosbags",
    ) else {
        return;
    };
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/crates/bag/tests/py/check_bag.py"
    );
    let out = std::process::Command::new(&python)
        .arg(script)
        .arg(&bag)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "check_bag.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    for topic in ["/cell/toolpath", "/cell/machine_status", "/cell/heat"] {
        assert!(
            stdout.contains(topic),
            "{topic} not decoded by the Python readers"
        );
    }
}
