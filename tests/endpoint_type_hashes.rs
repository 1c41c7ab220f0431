//! Every endpoint a cell node creates announces its type's REP-2011 hash in its DDS USER_DATA,
//! `typehash=RIHS01_<64 hex>;`, as ROS 2 Jazzy does (rmw_dds_common
//! `encode_type_hash_for_user_data_qos`). A plain rustdds participant reads it from discovery
//! (SEDP), for topics, services and actions, on both the serving and the calling side.

mod common;

use std::{
    net::{IpAddr, Ipv4Addr},
    time::Instant,
};

use cell_msgs::{
    EmitProgramRequest, EmitProgramResponse, MachineProgram, PlanHotwireFeedback, PlanHotwireGoal,
    PlanHotwireResult, Toolpath,
};
use cell_runtime::{graph::ros_type_name, QosPreset};
use common::{fresh_domain, node, DELIVERY_TIMEOUT};
use ros2_client::dds::rustdds::DomainParticipantBuilder;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    Writer,
    Reader,
}
use Side::{Reader, Writer};

const NODE: &str = "hash_announcer";

/// (DDS topic, side, the ROS 2 type whose hash the endpoint announces). Request endpoints carry
/// `_Request`'s hash and reply endpoints `_Response`'s, as rmw_fastrtps_cpp (Jazzy) does.
const EXPECTED: &[(&str, Side, &str)] = &[
    ("rt/toolpath", Writer, "cell_msgs/msg/Toolpath"),
    ("rt/machine_program", Reader, "cell_msgs/msg/MachineProgram"),
    // emit_program: the server's and the client's endpoints.
    (
        "rq/emit_programRequest",
        Reader,
        "cell_msgs/srv/EmitProgram_Request",
    ),
    (
        "rr/emit_programReply",
        Writer,
        "cell_msgs/srv/EmitProgram_Response",
    ),
    (
        "rq/emit_programRequest",
        Writer,
        "cell_msgs/srv/EmitProgram_Request",
    ),
    (
        "rr/emit_programReply",
        Reader,
        "cell_msgs/srv/EmitProgram_Response",
    ),
    // plan_hotwire: the action server's endpoints and the client's feedback reader.
    (
        "rq/plan_hotwire/_action/send_goalRequest",
        Reader,
        "cell_msgs/action/PlanHotwire_SendGoal_Request",
    ),
    (
        "rr/plan_hotwire/_action/send_goalReply",
        Writer,
        "cell_msgs/action/PlanHotwire_SendGoal_Response",
    ),
    (
        "rq/plan_hotwire/_action/get_resultRequest",
        Reader,
        "cell_msgs/action/PlanHotwire_GetResult_Request",
    ),
    (
        "rr/plan_hotwire/_action/get_resultReply",
        Writer,
        "cell_msgs/action/PlanHotwire_GetResult_Response",
    ),
    (
        "rq/plan_hotwire/_action/cancel_goalRequest",
        Reader,
        "action_msgs/srv/CancelGoal_Request",
    ),
    (
        "rr/plan_hotwire/_action/cancel_goalReply",
        Writer,
        "action_msgs/srv/CancelGoal_Response",
    ),
    (
        "rt/plan_hotwire/_action/feedback",
        Writer,
        "cell_msgs/action/PlanHotwire_FeedbackMessage",
    ),
    (
        "rt/plan_hotwire/_action/status",
        Writer,
        "action_msgs/msg/GoalStatusArray",
    ),
    (
        "rt/plan_hotwire/_action/feedback",
        Reader,
        "cell_msgs/action/PlanHotwire_FeedbackMessage",
    ),
];

/// One remote endpoint as discovery reports it.
#[derive(Debug)]
struct Seen {
    topic: String,
    side: Side,
    type_name: String,
    user_data: Vec<u8>,
}

/// `typehash=RIHS01_` and 64 lower-case hex digits, then `;` (rosidl_stringify_type_hash).
fn is_rihs01_user_data(text: &str) -> bool {
    text.strip_prefix("typehash=RIHS01_")
        .and_then(|rest| rest.strip_suffix(';'))
        .is_some_and(|hex| {
            hex.len() == 64
                && hex
                    .bytes()
                    .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
        })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_endpoint_announces_its_type_hash_in_user_data() {
    let domain = fresh_domain();
    let cell = node(NODE, domain, false);
    let _publisher = cell
        .publisher::<Toolpath>("toolpath", QosPreset::Plan)
        .unwrap();
    let _subscriber = cell
        .subscriber::<MachineProgram>("machine_program", QosPreset::Plan)
        .unwrap();
    let _server = cell
        .service_server::<EmitProgramRequest, EmitProgramResponse>("emit_program")
        .unwrap();
    let _client = cell
        .service_client::<EmitProgramRequest, EmitProgramResponse>("emit_program")
        .unwrap();
    let _action_server = cell
        .action_server::<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>("plan_hotwire")
        .unwrap();
    let _action_client = cell
        .action_client::<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>("plan_hotwire")
        .unwrap();

    let observer = DomainParticipantBuilder::new(domain)
        .with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)])
        .build()
        .expect("observer participant");
    let find = |seen: &[Seen], topic: &str, side: Side| -> Option<usize> {
        seen.iter().position(|s| s.topic == topic && s.side == side)
    };
    let started = Instant::now();
    let seen = loop {
        let writers = observer.discovered_writers().into_iter().map(|w| Seen {
            topic: w.publication_topic_data.topic_name.clone(),
            side: Writer,
            type_name: w.publication_topic_data.type_name.clone(),
            user_data: w.user_data,
        });
        let readers = observer.discovered_readers().into_iter().map(|r| Seen {
            topic: r.subscription_topic_data.topic_name().clone(),
            side: Reader,
            type_name: r.subscription_topic_data.type_name().clone(),
            user_data: r.user_data,
        });
        let seen: Vec<Seen> = writers.chain(readers).collect();
        let missing: Vec<_> = EXPECTED
            .iter()
            .filter(|(topic, side, _)| find(&seen, topic, *side).is_none())
            .collect();
        if missing.is_empty() {
            break seen;
        }
        assert!(
            started.elapsed() < DELIVERY_TIMEOUT,
            "not discovered in {DELIVERY_TIMEOUT:?}: {missing:?}"
        );
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    };

    for (topic, side, ros_name) in EXPECTED {
        let endpoint = &seen[find(&seen, topic, *side).unwrap()];
        assert_eq!(
            ros_type_name(&endpoint.type_name).as_deref(),
            Some(*ros_name),
            "{side:?} on {topic}: DDS type {}",
            endpoint.type_name
        );
        let hash = cell_msgs::type_hash(ros_name)
            .unwrap_or_else(|e| panic!("{ros_name} has no type hash: {e}"));
        let announced = String::from_utf8_lossy(&endpoint.user_data);
        assert_eq!(
            announced,
            format!("typehash={hash};"),
            "{side:?} on {topic} ({ros_name})"
        );
        assert!(
            is_rihs01_user_data(&announced),
            "{side:?} on {topic}: {announced:?} is not typehash=RIHS01_<64 hex>;"
        );
    }

    // ros2-client's own parameter services go through the same hook: a type the registry does
    // not know announces nothing, and the node still came up.
    let topic = format!("rq/{NODE}/get_parametersRequest");
    let parameters = seen
        .iter()
        .find(|s| s.topic == topic && s.side == Reader)
        .unwrap_or_else(|| panic!("no reader on {topic}"));
    let ros_name = ros_type_name(&parameters.type_name).expect("a rosidl DDS type name");
    let expected = cell_msgs::type_hash(&ros_name)
        .map(|hash| format!("typehash={hash};"))
        .unwrap_or_default();
    assert_eq!(
        String::from_utf8_lossy(&parameters.user_data),
        expected,
        "{topic} ({ros_name})"
    );
}
