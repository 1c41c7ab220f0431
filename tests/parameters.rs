//! A node's effective parameters (file, `-p` and defaults) are visible on the ROS graph through
//! the standard `rcl_interfaces` services, as `ros2 param list/get` would query them.

mod common;

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
    setup.args =
        NodeArgs::parse(["--ros-args", "-r", "__ns:=/cell", "-p", "timeout_s:=12.5"]).unwrap();
    let (_node, params) = CellNode::with_params::<MonitorParams>(setup).unwrap();
    assert_eq!(params.timeout_s, 12.5);

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
    for name in ["expect_toolpaths", "expect_heat_maps", "timeout_s"] {
        assert!(
            listed.result.names.iter().any(|n| n == name),
            "{name} not in {:?}",
            listed.result.names
        );
    }
    let values = tokio::time::timeout(
        DELIVERY_TIMEOUT,
        get.async_call_service(GetParametersRequest {
            names: vec!["timeout_s".into(), "expect_toolpaths".into()],
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
            ros2_client::ParameterValue::Integer(0)
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
}
