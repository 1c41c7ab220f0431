//! `/rosout` (issue 22, item 5): a cell node's log events above its level reach `/rosout` as
//! `rcl_interfaces/msg/Log` under the node's name, as `rqt_console` would read them; events
//! below the level do not.

mod common;

use std::time::Duration;

use cell_runtime::{args::NodeArgs, CellNode, NodeSetup};
use common::{fresh_domain, DELIVERY_TIMEOUT};
use ros2_client::{dds::rustdds::DomainParticipantBuilder, Context, NodeName, NodeOptions};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn log_events_reach_rosout_with_the_nodes_name_and_level() {
    cell_runtime::logging::init(Some("info"));
    let domain = fresh_domain();

    // An independent reader of /rosout, as rqt_console would be.
    let participant = DomainParticipantBuilder::new(domain)
        .with_only_networks([std::net::IpAddr::from([127, 0, 0, 1])])
        .build()
        .unwrap();
    let context = Context::from_domain_participant(participant).unwrap();
    let mut reader = context
        .new_node(
            NodeName::new("/", "console").unwrap(),
            NodeOptions::new().read_rosout(true),
        )
        .unwrap();
    let spinner = reader.spinner().unwrap();
    tokio::spawn(spinner.spin());

    let mut setup = NodeSetup::local("monitor", domain);
    setup.args =
        NodeArgs::parse(["--ros-args", "-r", "__ns:=/cell", "-r", "__node:=talker"]).unwrap();
    let _node = CellNode::new(setup).unwrap();

    let marker = format!("rosout check {}", std::process::id());
    let rosout = reader.rosout_subscription().expect("rosout reading on");
    let found = tokio::time::timeout(DELIVERY_TIMEOUT, async {
        loop {
            // Until discovery matches, events are lost: log again until one arrives.
            tracing::debug!("{marker} below the level");
            // rustdds logs through the `log` crate: such lines stay off /rosout.
            log::error!(target: "rustdds::discovery", "{marker} from the DDS stack");
            tracing::warn!(tool = "cutter", "{marker}");
            tokio::time::sleep(Duration::from_millis(200)).await;
            while let Ok(Some((log, _))) = rosout.take() {
                if log.msg.contains(&marker) {
                    return log;
                }
            }
        }
    })
    .await
    .expect("a log line on /rosout in time");
    assert_eq!(
        found.name, "cell.talker",
        "rcl's logger name of /cell/talker"
    );
    assert_eq!(found.level, ros2_client::log::Log::WARN);
    assert!(found.msg.starts_with(&marker), "{}", found.msg);
    assert!(found.msg.contains("tool=cutter"), "{}", found.msg);
    assert!(found.file.ends_with("rosout.rs"), "{}", found.file);
    // The debug line never went out (info level).
    tokio::time::sleep(Duration::from_millis(300)).await;
    while let Ok(Some((log, _))) = rosout.take() {
        assert!(!log.msg.contains("below the level"), "{}", log.msg);
        assert!(!log.msg.contains("from the DDS stack"), "{}", log.msg);
    }
}
