//! Type hashes against stock rosidl's: the `type_hashes` that `rosidl_generator_type_description`
//! wrote into the ROS 2 Jazzy packages (`share/<pkg>/{msg,srv}/<T>.json` of the PyPI wheels
//! `ros-builtin-interfaces` 2.0.3, `ros-std-msgs`/`ros-geometry-msgs`/`ros-std-srvs`/
//! `ros-sensor-msgs`/`ros-nav-msgs`/`ros-visualization-msgs`/`ros-diagnostic-msgs` 5.3.6,
//! `ros-action-msgs`/`ros-service-msgs`/`ros-rcl-interfaces`/`ros-rosgraph-msgs` 2.0.3,
//! `ros-unique-identifier-msgs` 2.5.0, as `ros-jazzy-*` pull them in).

use cell_msgs::registry::RegistryError;
use cell_msgs::type_description::type_description;
use cell_msgs::{type_hash, TypeHash};

/// (type, hash stock rosidl computed), copied from those JSON files.
const STOCK_JAZZY: &[(&str, &str)] = &[
    (
        "action_msgs/msg/GoalInfo",
        "RIHS01_6398fe763154554353930716b225947f93b672f0fb2e49fdd01bb7a7e37933e9",
    ),
    (
        "action_msgs/msg/GoalStatus",
        "RIHS01_32f4cfd717735d17657e1178f24431c1ce996c878c515230f6c5b3476819dbb9",
    ),
    (
        "action_msgs/msg/GoalStatusArray",
        "RIHS01_6c1684b00f177d37438febe6e709fc4e2b0d4248dca4854946f9ed8b30cda83e",
    ),
    (
        "action_msgs/srv/CancelGoal",
        "RIHS01_573d8b0a534451d7bc2ac8c5ffde8ac14b8593b7001175d0cd6516dcbeb8689a",
    ),
    (
        "action_msgs/srv/CancelGoal_Request",
        "RIHS01_3d3c84653c1f96918086887e1dcb236faec88b81a5b14fd4cf4840065bcdf8af",
    ),
    (
        "action_msgs/srv/CancelGoal_Response",
        "RIHS01_35e682cf3f510e83c70a82a4aac888496dedee56773bf9d8e5e0aa81f9e1c960",
    ),
    (
        "action_msgs/srv/CancelGoal_Event",
        "RIHS01_178f81615ce6be41ad328211d7a56b08b00e73f41f0b8aec256b2f3ff97a5e7e",
    ),
    (
        "builtin_interfaces/msg/Duration",
        "RIHS01_e8d009f659816f758b75334ee1a9ca5b5c0b859843261f14c7f937349599d93b",
    ),
    (
        "builtin_interfaces/msg/Time",
        "RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197",
    ),
    (
        "diagnostic_msgs/msg/DiagnosticArray",
        "RIHS01_5a8a36efb05fb25070fa0fb3810290c0e6cd4862b54a8fb975a1ee8dc55a333e",
    ),
    (
        "diagnostic_msgs/msg/DiagnosticStatus",
        "RIHS01_b0e3e692ea2d54a8af2f4ef1930e81556a2db55216b771f8a7d2724ed47bf0e4",
    ),
    (
        "diagnostic_msgs/msg/KeyValue",
        "RIHS01_d68081eaa540288c5440753baecef0c4e16e81a5f78ad68902ded5100413bb42",
    ),
    (
        "geometry_msgs/msg/Point",
        "RIHS01_6963084842a9b04494d6b2941d11444708d892da2f4b09843b9c43f42a7f6881",
    ),
    (
        "geometry_msgs/msg/Pose",
        "RIHS01_d501954e9476cea2996984e812054b68026ae0bfae789d9a10b23daf35cc90fa",
    ),
    (
        "geometry_msgs/msg/PoseStamped",
        "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8",
    ),
    (
        "geometry_msgs/msg/Quaternion",
        "RIHS01_8a765f66778c8ff7c8ab94afcc590a2ed5325a1d9a076ffff38fbce36f458684",
    ),
    (
        "geometry_msgs/msg/Transform",
        "RIHS01_beb83fbe698636351461f6f35d1abb20010c43d55374d81bd041f1ba2581fddc",
    ),
    (
        "geometry_msgs/msg/TransformStamped",
        "RIHS01_0a241f87d04668d94099cbb5ba11691d5ad32c2f29682e4eb5653424bd275206",
    ),
    (
        "geometry_msgs/msg/Vector3",
        "RIHS01_cc12fe83e4c02719f1ce8070bfd14aecd40f75a96696a67a2a1f37f7dbb0765d",
    ),
    (
        "nav_msgs/msg/Path",
        "RIHS01_1957a5bb3cee5da65c4e52e52b65a93df227efce4c20f8458b36e73066ca334b",
    ),
    (
        "rcl_interfaces/msg/Log",
        "RIHS01_e28ce254ca8abc06abf92773b74602cdbf116ed34fbaf294fb9f81da9f318eac",
    ),
    (
        "rosgraph_msgs/msg/Clock",
        "RIHS01_692f7a66e93a3c83e71765d033b60349ba68023a8c689a79e48078bcb5c58564",
    ),
    (
        "sensor_msgs/msg/CompressedImage",
        "RIHS01_15640771531571185e2efc8a100baf923961a4d15d5569652e6cb6691e8e371a",
    ),
    (
        "sensor_msgs/msg/Image",
        "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47",
    ),
    (
        "sensor_msgs/msg/JointState",
        "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e",
    ),
    (
        "sensor_msgs/msg/Temperature",
        "RIHS01_72514a14126ab9f8a9abec974c78e5610a367b59db5da355ff1fb982d5bad4b8",
    ),
    (
        "service_msgs/msg/ServiceEventInfo",
        "RIHS01_41bcbbe07a75c9b52bc96bfd5c24d7f0fc0a08c0cb7921b3373c5732345a6f45",
    ),
    (
        "std_msgs/msg/ColorRGBA",
        "RIHS01_77a7a5b9ae477306097665106e0413ba74440245b1f3d0c6d6405fe5c7813fe8",
    ),
    (
        "std_msgs/msg/Header",
        "RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01",
    ),
    (
        "std_msgs/msg/String",
        "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
    ),
    (
        "std_srvs/srv/SetBool",
        "RIHS01_abe9e4bb6b41b40e6789712c00ec8871923e089af3f667a79992a428cff2da0a",
    ),
    (
        "std_srvs/srv/SetBool_Request",
        "RIHS01_c62fbb99d94e1b25e8ef9e109f9581956bb1b3361a45a4e5810c36a90d29932e",
    ),
    (
        "std_srvs/srv/SetBool_Response",
        "RIHS01_d0814e7f7b4880ab77e9c57426c7aa1562ab69f11eef8e2e968812f9cbd0b059",
    ),
    (
        "std_srvs/srv/SetBool_Event",
        "RIHS01_3c4c20015afb4303eafd347b1d6a786f171a89c814726961a9593ef10df878cf",
    ),
    (
        "unique_identifier_msgs/msg/UUID",
        "RIHS01_1b8e8aca958cbea28fe6ef60bf6c19b683c97a9ef60bb34752067d0f2f7ab437",
    ),
    (
        "visualization_msgs/msg/Marker",
        "RIHS01_45b13ccf791f225962bf74e746f9644518855d783a6f42ba0cc14fde2b4f3ce0",
    ),
    (
        "visualization_msgs/msg/MarkerArray",
        "RIHS01_86cb8800b6fb05b5eff1abd7a56f62a5641d3ae9a1c29e78e67e704f1d067dcf",
    ),
    (
        "visualization_msgs/msg/MeshFile",
        "RIHS01_7710ece15a148fb7c9b546364cfb215bb06098087bd6394fe5b73a493508f8c4",
    ),
    (
        "visualization_msgs/msg/UVCoordinate",
        "RIHS01_f27f7ed21fe360c6066944f856b801a0c0d1e94e815b6886444b42d90b196a26",
    ),
];

#[test]
fn standard_types_hash_as_stock_rosidl() {
    let mismatches: Vec<String> = STOCK_JAZZY
        .iter()
        .filter_map(|&(name, stock)| match type_hash(name) {
            Ok(hash) if hash.to_string() == stock => None,
            Ok(hash) => Some(format!("{name}: {hash}, stock rosidl {stock}")),
            Err(e) => Some(format!("{name}: {e}")),
        })
        .collect();
    assert!(mismatches.is_empty(), "{}", mismatches.join("\n"));
}

#[test]
fn every_cell_interface_and_its_derived_types_hash() {
    let mut names = Vec::new();
    for name in cell_msgs::registry::list() {
        let file = ["_Request", "_Response", "_Goal", "_Result", "_Feedback"]
            .iter()
            .find_map(|suffix| name.strip_suffix(suffix));
        match file {
            Some(service) if name.contains("/srv/") => {
                names.extend([service.to_owned(), format!("{service}_Event")])
            }
            Some(action) if name.contains("/action/") => names.extend(
                [
                    "",
                    "_SendGoal",
                    "_SendGoal_Request",
                    "_SendGoal_Response",
                    "_SendGoal_Event",
                    "_GetResult",
                    "_GetResult_Request",
                    "_GetResult_Response",
                    "_GetResult_Event",
                    "_FeedbackMessage",
                ]
                .map(|suffix| format!("{action}{suffix}")),
            ),
            _ => {}
        }
        names.push(name);
    }
    names.sort();
    names.dedup();
    let mut seen: Vec<TypeHash> = Vec::new();
    for name in &names {
        let hash = type_hash(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!seen.contains(&hash), "{name} hashes like another type");
        seen.push(hash);
    }
    // cell_msgs: 11 messages, 2 services (4 types each), 4 actions (3 parts + 10 derived each).
    let cell = names.iter().filter(|n| n.starts_with("cell_msgs/")).count();
    assert_eq!(cell, 11 + 2 * 4 + 4 * 13, "{names:?}");
}

#[test]
fn descriptions_list_references_once_sorted() {
    let description = type_description("cell_msgs/action/PlanHotwire").expect("known");
    let referenced: Vec<&str> = description
        .referenced_type_descriptions
        .iter()
        .map(|d| d.type_name.as_str())
        .collect();
    let mut sorted = referenced.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(referenced, sorted);
    for needed in [
        "builtin_interfaces/msg/Time",
        "service_msgs/msg/ServiceEventInfo",
        "unique_identifier_msgs/msg/UUID",
        "cell_msgs/action/PlanHotwire_SendGoal_Event",
        "cell_msgs/action/PlanHotwire_FeedbackMessage",
        "cell_msgs/msg/Toolpath",
    ] {
        assert!(referenced.contains(&needed), "{needed} in {referenced:?}");
    }
}

#[test]
fn unknown_names_are_one_error() {
    for name in [
        "cell_msgs/msg/Nope",
        "cell_msgs/action/PlanHotwire_Cancel",
        "",
    ] {
        assert_eq!(type_hash(name), Err(RegistryError::Unknown(name.into())));
    }
}
