//! A node's effective parameters (file, `-p` and defaults) are visible on the ROS graph through
//! the standard `rcl_interfaces` services, as `ros2 param list/get` would query them.

mod common;

use cell_msgs::{builtin_interfaces::Time, rosgraph_msgs::Clock};
use cell_runtime::{args::NodeArgs, CellNode, NodeSetup};
use common::{fresh_domain, DELIVERY_TIMEOUT};
use monitor::MonitorParams;
use ros2_client::{
    dds::rustdds::DomainParticipantBuilder,
    rcl_interfaces::{
        GetParametersRequest, GetParametersResponse, ListParametersRequest, ListParametersResponse,
        SetParametersRequest, SetParametersResponse,
    },
    Context, Name, NodeName, NodeOptions, QosProfile, ServiceMapping, ServiceTypeName,
};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn effective_parameters_are_listed_and_readable_remotely() {
    let domain = fresh_domain();
    let mut setup = NodeSetup::local("monitor", domain);
    // A bringup's shared file: the ROS-standard keys every ROS 2 node accepts (issue 22).
    let shared = std::env::temp_dir().join(format!("cell-shared-{}.yaml", std::process::id()));
    std::fs::write(
        &shared,
        "/**:\n  ros__parameters:\n    use_sim_time: false\n    \
         start_type_description_service: true\n    qos_overrides:\n      \
         /cell/toolpath:\n        subscription:\n          depth: 5\n",
    )
    .unwrap();
    setup.args = NodeArgs::parse([
        "--ros-args",
        "-r",
        "__ns:=/cell",
        "--params-file",
        shared.to_str().unwrap(),
        "-p",
        "timeout_s:=12.5",
    ])
    .unwrap();
    let (node, params) = CellNode::with_params::<MonitorParams>(setup).unwrap();
    let _ = std::fs::remove_file(&shared);
    assert_eq!(params.timeout_s, 12.5);
    assert!(!node.standard_params().use_sim_time);
    let depth = |endpoint| {
        node.qos(
            "/cell/toolpath",
            endpoint,
            ros2_client::QosProfile::publisher_default(),
        )
        .history
    };
    use cell_runtime::standard_params::Endpoint;
    assert_eq!(
        depth(Endpoint::Subscription),
        ros2_client::qos::History::KeepLast { depth: 5 }
    );
    assert_ne!(
        depth(Endpoint::Publisher),
        ros2_client::qos::History::KeepLast { depth: 5 }
    );

    // An independent ros2-client node, as `ros2 param` would be.
    let participant = DomainParticipantBuilder::new(domain)
        .with_only_networks([std::net::IpAddr::from([127, 0, 0, 1])])
        .build()
        .unwrap();
    let context = Context::from_domain_participant(participant).unwrap();
    let mut asker = context
        .new_node(NodeName::new("/", "asker").unwrap(), NodeOptions::new())
        .unwrap();
    let spinner = asker.spinner().unwrap();
    tokio::spawn(spinner.spin());
    let qos = QosProfile::publisher_default();
    let list = asker
        .create_client::<ListParametersRequest, ListParametersResponse>(
            ServiceMapping::Enhanced,
            &Name::new("/cell/monitor", "list_parameters").unwrap(),
            &ServiceTypeName::new("rcl_interfaces", "ListParameters"),
            qos.clone(),
            qos.clone(),
        )
        .unwrap();
    let get = asker
        .create_client::<GetParametersRequest, GetParametersResponse>(
            ServiceMapping::Enhanced,
            &Name::new("/cell/monitor", "get_parameters").unwrap(),
            &ServiceTypeName::new("rcl_interfaces", "GetParameters"),
            qos.clone(),
            qos.clone(),
        )
        .unwrap();
    let set = asker
        .create_client::<SetParametersRequest, SetParametersResponse>(
            ServiceMapping::Enhanced,
            &Name::new("/cell/monitor", "set_parameters").unwrap(),
            &ServiceTypeName::new("rcl_interfaces", "SetParameters"),
            qos.clone(),
            qos,
        )
        .unwrap();
    tokio::time::timeout(DELIVERY_TIMEOUT, async {
        list.wait_for_service(&asker).await;
        get.wait_for_service(&asker).await;
        set.wait_for_service(&asker).await;
    })
    .await
    .expect("parameter services discovered");

    let listed = tokio::time::timeout(
        DELIVERY_TIMEOUT,
        list.async_call_service(ListParametersRequest {
            prefixes: vec![],
            depth: 0,
        }),
    )
    .await
    .expect("in time")
    .expect("list_parameters");
    for name in [
        "expect_toolpaths",
        "expect_heat_maps",
        "timeout_s",
        "use_sim_time",
    ] {
        assert!(
            listed.result.names.iter().any(|n| n == name),
            "{name} not in {:?}",
            listed.result.names
        );
    }
    let values = tokio::time::timeout(
        DELIVERY_TIMEOUT,
        get.async_call_service(GetParametersRequest {
            names: vec![
                "timeout_s".into(),
                "expect_toolpaths".into(),
                "use_sim_time".into(),
            ],
        }),
    )
    .await
    .expect("in time")
    .expect("get_parameters");
    let values: Vec<ros2_client::ParameterValue> =
        values.values.into_iter().map(Into::into).collect();
    assert_eq!(
        values,
        [
            ros2_client::ParameterValue::Double(12.5),
            ros2_client::ParameterValue::Integer(0),
            ros2_client::ParameterValue::Boolean(false)
        ]
    );

    // Parameters are read at start-up; a remote change is refused with the reason.
    let change = ros2_client::Parameter {
        name: "timeout_s".into(),
        value: ros2_client::ParameterValue::Double(1.0),
    };
    let answer = tokio::time::timeout(
        DELIVERY_TIMEOUT,
        set.async_call_service(SetParametersRequest {
            parameter: vec![change.into()],
        }),
    )
    .await
    .expect("in time")
    .expect("set_parameters");
    assert_eq!(answer.results.len(), 1);
    assert!(!answer.results[0].successful);
    assert!(
        answer.results[0].reason.contains("read at start-up"),
        "{}",
        answer.results[0].reason
    );

    // use_sim_time may be switched at run time, as in rclcpp: the node then follows /clock.
    let before = node.now();
    assert!(before.sec > 1_700_000_000, "the wall clock: {before:?}");
    let switch = ros2_client::Parameter {
        name: "use_sim_time".into(),
        value: ros2_client::ParameterValue::Boolean(true),
    };
    let answer = tokio::time::timeout(
        DELIVERY_TIMEOUT,
        set.async_call_service(SetParametersRequest {
            parameter: vec![switch.into()],
        }),
    )
    .await
    .expect("in time")
    .expect("set_parameters");
    assert!(answer.results[0].successful, "{}", answer.results[0].reason);
    assert_eq!(node.now(), Time::default(), "zero before the first /clock");
    let mut source = NodeSetup::local("time_source", domain);
    source.fast_path = cell_runtime::FastPathMode::Off;
    let source = CellNode::new(source).unwrap();
    let clock = source
        .publisher::<Clock>("/clock", cell_runtime::QosPreset::Clock)
        .unwrap();
    let tick = Time {
        sec: 1_000,
        nanosec: 500,
    };
    tokio::time::timeout(DELIVERY_TIMEOUT, async {
        while node.now() != tick {
            clock.publish(Clock { clock: tick }).await.unwrap();
            tokio::time::sleep(std::time::Duration::from_millis(50)).await;
        }
    })
    .await
    .expect("the node follows /clock after use_sim_time was set");
}
