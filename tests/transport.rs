//! Nodes on tokio tasks, each with its own DDS participant on loopback and a fresh domain,
//! exchange a Toolpath and a 1024×1024 f32 HeatMap, over DDS and over iceoryx2; what arrives
//! must be byte-identical to what was sent.

mod common;

use std::time::Duration;

use cell_msgs::{to_cdr, HeatMap, Toolpath};
use cell_runtime::{QosPreset, Received, Subscriber, Via};
use common::{fresh_domain, node, DELIVERY_TIMEOUT};
use probe::{hot_spot, test_block, ProbeParams};

/// Publishes `make()` every 100 ms until the subscriber has one, then returns it.
async fn deliver<T: cell_msgs::RosMessage>(
    publisher: cell_runtime::Publisher<T>,
    subscriber: &mut Subscriber<T>,
    make: impl Fn() -> T + Send + 'static,
) -> Received<T> {
    let pump = tokio::spawn(async move {
        loop {
            publisher.publish(make()).await.expect("publish");
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    });
    let got = tokio::time::timeout(DELIVERY_TIMEOUT, subscriber.recv())
        .await
        .expect("delivered before the timeout")
        .expect("subscriber alive");
    pump.abort();
    got
}

async fn exchange(fast_path: bool) {
    let domain = fresh_domain();
    let talker = node("talker", domain, fast_path);
    let listener = node("listener", domain, fast_path);
    assert_eq!(talker.has_fast_path(), fast_path);

    let mut paths = listener
        .subscriber::<Toolpath>("toolpath", QosPreset::Plan)
        .unwrap();
    let mut heat = listener
        .subscriber::<HeatMap>("heat_map", QosPreset::Stream)
        .unwrap();

    let block = test_block(&ProbeParams::default());
    let sent = block.clone();
    let publisher = talker
        .publisher::<Toolpath>("toolpath", QosPreset::Plan)
        .unwrap();
    let got = deliver(publisher, &mut paths, move || sent.clone()).await;
    assert_eq!(got.via, Via::Dds, "plans always travel over DDS");
    assert_eq!(to_cdr(&got.message).unwrap(), to_cdr(&block).unwrap());

    let frame = hot_spot(1024, 1024, 7);
    assert_eq!(frame.data.len(), 1024 * 1024);
    let sent = frame.clone();
    let publisher = talker
        .publisher::<HeatMap>("heat_map", QosPreset::Stream)
        .unwrap();
    let got = deliver(publisher, &mut heat, move || sent.clone()).await;
    let expected_via = if fast_path {
        Via::SharedMemory
    } else {
        Via::Dds
    };
    assert_eq!(got.via, expected_via);
    let (sent_bytes, got_bytes) = (to_cdr(&frame).unwrap(), to_cdr(&got.message).unwrap());
    assert!(sent_bytes.len() > 4 * 1024 * 1024);
    assert!(sent_bytes == got_bytes, "heat map differs after transport");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn toolpath_and_megapixel_heat_map_over_dds() {
    exchange(false).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn toolpath_and_megapixel_heat_map_over_iceoryx2() {
    exchange(true).await;
}

/// A local fast-path subscriber gets each frame once, even when a DDS-only reader forces the
/// publisher to send over DDS as well.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn shared_memory_and_dds_readers_each_get_every_frame_once() {
    let domain = fresh_domain();
    let talker = node("talker", domain, true);
    let local = node("local", domain, true);
    let dds_only = node("dds_only", domain, false);
    let fast_sub = local
        .subscriber::<HeatMap>("heat_map", QosPreset::Stream)
        .unwrap();
    let dds_sub = dds_only
        .subscriber::<HeatMap>("heat_map", QosPreset::Stream)
        .unwrap();
    let publisher = talker
        .publisher::<HeatMap>("heat_map", QosPreset::Stream)
        .unwrap();
    assert!(publisher.wait_for_subscribers(2, DELIVERY_TIMEOUT).await);
    // Wait until DDS has matched both readers and the local one is attached to shared memory,
    // so every frame goes both ways. (DDS discovery alone can finish first; a frame sent then
    // goes over DDS only, which is correct delivery but not what this test measures.)
    let deadline = tokio::time::Instant::now() + DELIVERY_TIMEOUT;
    while publisher.dds_subscription_count() < 2 || publisher.shared_memory_subscriber_count() < 1 {
        assert!(
            tokio::time::Instant::now() < deadline,
            "DDS readers never matched or the local reader never attached to shared memory"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let frames = 20u32;
    // Readers collect concurrently: stream queues are short and drop when full.
    let local_task = tokio::spawn(collect(fast_sub));
    let dds_task = tokio::spawn(collect(dds_sub));
    for i in 0..frames {
        publisher.publish(hot_spot(32, 32, i)).await.unwrap();
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let local_seen = local_task.await.unwrap();
    let dds_seen = dds_task.await.unwrap();
    assert!(
        local_seen.iter().all(|(via, _)| *via == Via::SharedMemory),
        "local reader took a DDS copy"
    );
    let mut distinct: Vec<_> = local_seen.iter().map(|(_, d)| d.clone()).collect();
    distinct.dedup();
    assert_eq!(
        distinct.len(),
        local_seen.len(),
        "a frame arrived twice at the local reader"
    );
    assert!(
        local_seen.len() >= frames as usize / 2,
        "local reader got {} of {frames}",
        local_seen.len()
    );
    assert!(
        !dds_seen.is_empty(),
        "the DDS-only reader got nothing: the publisher skipped DDS"
    );
    assert!(dds_seen.iter().all(|(via, _)| *via == Via::Dds));
}

/// Everything a subscriber receives until it has been quiet for a second.
async fn collect(mut sub: Subscriber<HeatMap>) -> Vec<(Via, Vec<f32>)> {
    let mut seen = Vec::new();
    while let Ok(Some(r)) = tokio::time::timeout(Duration::from_secs(1), sub.recv()).await {
        seen.push((r.via, r.message.data));
    }
    seen
}

/// Undecodable samples, over DDS and over shared memory, are logged and skipped; the subscriber
/// keeps delivering the valid messages that follow.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn undecodable_messages_are_skipped_and_the_node_stays_up() {
    use ros2_client::dds::rustdds::DomainParticipantBuilder;
    use ros2_client::{Context, MessageTypeName, Name, NodeName, NodeOptions};

    let domain = fresh_domain();
    let listener = node("listener", domain, true);
    let mut paths = listener
        .subscriber::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let mut heat = listener
        .subscriber::<HeatMap>("/heat_map", QosPreset::Stream)
        .unwrap();

    // A raw participant that claims to publish Toolpaths but sends a single byte.
    let participant = DomainParticipantBuilder::new(domain)
        .with_only_networks([std::net::IpAddr::from([127, 0, 0, 1])])
        .build()
        .unwrap();
    let context = Context::from_domain_participant(participant).unwrap();
    let mut rogue = context
        .new_node(NodeName::new("/", "rogue").unwrap(), NodeOptions::new())
        .unwrap();
    let qos = QosPreset::Plan.profile();
    let topic = rogue
        .create_topic(
            &Name::parse("/toolpath").unwrap(),
            MessageTypeName::new("cell_msgs", "Toolpath"),
            &qos,
        )
        .unwrap();
    let garbage = rogue.create_publisher::<u8>(&topic, Some(qos)).unwrap();
    for _ in 0..3 {
        garbage.publish(0xAB).unwrap();
    }
    // And a shared-memory frame that is not a HeatMap.
    let fast = cell_runtime::fastpath::FastPath::open(domain).unwrap();
    let junk = fast
        .publisher(
            "/heat_map",
            <HeatMap as cell_msgs::RosMessage>::ROS_NAME,
            [7; 16],
        )
        .unwrap();
    junk.send_copy(&[0, 1, 0, 0, 0xFF, 0xFF]).unwrap();

    let talker = node("talker", domain, true);
    let block = test_block(&ProbeParams::default());
    let sent = block.clone();
    let got = deliver(
        talker.publisher("/toolpath", QosPreset::Plan).unwrap(),
        &mut paths,
        move || sent.clone(),
    )
    .await;
    assert_eq!(
        got.message, block,
        "a valid Toolpath still arrives after the garbage"
    );
    let frame = hot_spot(16, 16, 3);
    let sent = frame.clone();
    let got = deliver(
        talker.publisher("/heat_map", QosPreset::Stream).unwrap(),
        &mut heat,
        move || sent.clone(),
    )
    .await;
    assert_eq!(
        got.message.data, frame.data,
        "a valid HeatMap still arrives after the junk frame"
    );
}

/// `-r __ns:=` and `-r from:=to` from the command line decide which topic a node really uses.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn remapped_topics_meet() {
    use cell_runtime::{args::NodeArgs, CellNode, NodeSetup};
    let domain = fresh_domain();
    let with_args = |name: &str, args: &[&str]| {
        let mut setup = NodeSetup::local(name, domain);
        setup.args = NodeArgs::parse(args.iter().copied()).unwrap();
        CellNode::new(setup).unwrap()
    };
    // The talker publishes "toolpath" in /cell, remapped to /plan/toolpath; the listener
    // subscribes to "plans" in the root namespace, remapped to the same.
    let talker = with_args(
        "talker",
        &[
            "--ros-args",
            "-r",
            "__ns:=/cell",
            "-r",
            "toolpath:=/plan/toolpath",
        ],
    );
    let listener = with_args("listener", &["--ros-args", "-r", "plans:=/plan/toolpath"]);
    let bystander = node("bystander", domain, false);
    let mut unremapped = bystander
        .subscriber::<Toolpath>("/cell/toolpath", QosPreset::Plan)
        .unwrap();
    let mut sub = listener
        .subscriber::<Toolpath>("plans", QosPreset::Plan)
        .unwrap();
    assert_eq!(sub.topic(), "/plan/toolpath");
    let publisher = talker
        .publisher::<Toolpath>("toolpath", QosPreset::Plan)
        .unwrap();
    assert_eq!(publisher.topic(), "/plan/toolpath");
    let block = test_block(&ProbeParams::default());
    let sent = block.clone();
    let got = deliver(publisher, &mut sub, move || sent.clone()).await;
    assert_eq!(got.message, block);
    let stray = tokio::time::timeout(Duration::from_millis(500), unremapped.recv()).await;
    assert!(stray.is_err(), "the un-remapped name must stay silent");
}
