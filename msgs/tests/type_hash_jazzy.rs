//! Every type hash in the `cell_msgs` package that stock rosidl built from `msgs/` (ROS 2 Jazzy
//! from the PyPI wheels, `cell_testkit::jazzy_workspace`) equals [`cell_msgs::type_hash`]: each
//! `share/cell_msgs/{msg,srv,action}/<T>.json` lists the hashes of its type and of every type it
//! references (services' `_Event`, actions' `_SendGoal`, `_GetResult`, `_FeedbackMessage`, and
//! the standard types they use).

use std::collections::BTreeMap;
use std::path::Path;

#[test]
fn every_hash_of_the_built_package_matches() {
    let Some(jazzy) = cell_testkit::jazzy_workspace(Path::new(env!("CARGO_TARGET_TMPDIR"))) else {
        return;
    };
    let share = jazzy.install.join("share/cell_msgs");
    let mut stock: BTreeMap<String, String> = BTreeMap::new();
    for kind in ["msg", "srv", "action"] {
        let dir = share.join(kind);
        let entries = std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        for path in entries.map(|e| e.expect("dir entry").path()) {
            if path.extension().is_none_or(|x| x != "json") {
                continue;
            }
            let text = std::fs::read_to_string(&path).expect("readable");
            let json: serde_json::Value =
                serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            for entry in json["type_hashes"].as_array().expect("type_hashes") {
                let name = entry["type_name"].as_str().expect("type_name");
                let hash = entry["hash_string"].as_str().expect("hash_string");
                stock.insert(name.to_owned(), hash.to_owned());
            }
        }
    }
    let mismatches: Vec<String> = stock
        .iter()
        .filter_map(|(name, hash)| match cell_msgs::type_hash(name) {
            Ok(ours) if ours.to_string() == *hash => None,
            Ok(ours) => Some(format!("{name}: ours {ours}, rosidl {hash}")),
            Err(e) => Some(format!("{name}: {e} (rosidl {hash})")),
        })
        .collect();
    assert!(mismatches.is_empty(), "{}", mismatches.join("\n"));
    // 11 messages, 2 services (4 types each), 4 actions (3 parts + 10 derived types each).
    let cell = stock.keys().filter(|n| n.starts_with("cell_msgs/")).count();
    assert_eq!(cell, 11 + 2 * 4 + 4 * 13, "{:?}", stock.keys());
}

/// The parameter services and events every node serves and the graph information it publishes
/// (endpoints ros2-client creates) hash as stock `rcl_interfaces` and `rmw_dds_common` in the
/// Jazzy venv say.
#[test]
fn the_parameter_interfaces_match_stock_rcl_interfaces() {
    let Some(jazzy) = cell_testkit::jazzy_workspace(Path::new(env!("CARGO_TARGET_TMPDIR"))) else {
        return;
    };
    // The venv is the install's sibling prefix: bin/python's parent's parent.
    let venv = jazzy.python.parent().and_then(Path::parent).expect("venv");
    let share = venv.join("share/rcl_interfaces");
    let mut checked = 0;
    for (kind, names) in [
        (
            "msg",
            &[
                "ParameterEvent",
                "Parameter",
                "ParameterValue",
                "ParameterDescriptor",
            ][..],
        ),
        (
            "srv",
            &[
                "DescribeParameters",
                "GetParameterTypes",
                "GetParameters",
                "ListParameters",
                "SetParameters",
                "SetParametersAtomically",
            ][..],
        ),
    ] {
        for name in names {
            let path = share.join(kind).join(format!("{name}.json"));
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let json: serde_json::Value = serde_json::from_str(&text).expect("json");
            for entry in json["type_hashes"].as_array().expect("type_hashes") {
                let type_name = entry["type_name"].as_str().expect("type_name");
                let hash = entry["hash_string"].as_str().expect("hash_string");
                let ours =
                    cell_msgs::type_hash(type_name).unwrap_or_else(|e| panic!("{type_name}: {e}"));
                assert_eq!(ours.to_string(), hash, "{type_name}");
                checked += 1;
            }
        }
    }
    let path = venv.join("share/rmw_dds_common/msg/ParticipantEntitiesInfo.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("stock rmw_dds_common"))
            .expect("json");
    for entry in json["type_hashes"].as_array().expect("type_hashes") {
        let type_name = entry["type_name"].as_str().expect("type_name");
        let ours = cell_msgs::type_hash(type_name).unwrap_or_else(|e| panic!("{type_name}: {e}"));
        assert_eq!(
            ours.to_string(),
            entry["hash_string"].as_str().unwrap(),
            "{type_name}"
        );
        checked += 1;
    }
    assert!(checked >= 43, "{checked} hashes checked");
}
