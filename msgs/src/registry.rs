//! Every interface file of the crate, embedded at build time and keyed by ROS 2 name.
//!
//! Messages are registered as `pkg/msg/Type`; each service `pkg/srv/Name` contributes
//! `Name_Request` and `Name_Response`, and each action `pkg/action/Name` contributes
//! `Name_Goal`, `Name_Result` and `Name_Feedback`.
//!
//! A few standard types are known by their definition alone (no Rust type, not in [`list`]):
//! those the type hashes of services and actions reference, see `DEFINITION_ONLY_FILES`.

use crate::idl::{self, MessageSpec, ParseError};

/// Why a definition could not be produced.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RegistryError {
    /// No registered interface has this name.
    #[error("unknown interface type `{0}`")]
    Unknown(String),
    /// A registered file does not parse (a bug in the crate: the tests parse them all).
    #[error(transparent)]
    Parse(#[from] ParseError),
}

/// Kind of an interface file.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Msg,
    Srv,
    Action,
}

impl Kind {
    /// Names of the messages each `---`-separated section of the file defines.
    fn parts(self) -> &'static [&'static str] {
        match self {
            Kind::Msg => &[""],
            Kind::Srv => &["_Request", "_Response"],
            Kind::Action => &["_Goal", "_Result", "_Feedback"],
        }
    }
}

/// (ROS 2 file name, kind, text) of every embedded interface file.
const FILES: &[(&str, Kind, &str)] = &[
    (
        "builtin_interfaces/msg/Time",
        Kind::Msg,
        include_str!("../std/builtin_interfaces/msg/Time.msg"),
    ),
    (
        "std_msgs/msg/Header",
        Kind::Msg,
        include_str!("../std/std_msgs/msg/Header.msg"),
    ),
    (
        "std_msgs/msg/String",
        Kind::Msg,
        include_str!("../std/std_msgs/msg/String.msg"),
    ),
    (
        "geometry_msgs/msg/Point",
        Kind::Msg,
        include_str!("../std/geometry_msgs/msg/Point.msg"),
    ),
    (
        "geometry_msgs/msg/Vector3",
        Kind::Msg,
        include_str!("../std/geometry_msgs/msg/Vector3.msg"),
    ),
    (
        "geometry_msgs/msg/Quaternion",
        Kind::Msg,
        include_str!("../std/geometry_msgs/msg/Quaternion.msg"),
    ),
    (
        "geometry_msgs/msg/Pose",
        Kind::Msg,
        include_str!("../std/geometry_msgs/msg/Pose.msg"),
    ),
    (
        "rosgraph_msgs/msg/Clock",
        Kind::Msg,
        include_str!("../std/rosgraph_msgs/msg/Clock.msg"),
    ),
    (
        "std_srvs/srv/SetBool",
        Kind::Srv,
        include_str!("../std/std_srvs/srv/SetBool.srv"),
    ),
    // Standard types of the RViz/Foxglove views (cell_views), copied from the Jazzy packages.
    (
        "builtin_interfaces/msg/Duration",
        Kind::Msg,
        include_str!("../std/builtin_interfaces/msg/Duration.msg"),
    ),
    (
        "std_msgs/msg/ColorRGBA",
        Kind::Msg,
        include_str!("../std/std_msgs/msg/ColorRGBA.msg"),
    ),
    (
        "geometry_msgs/msg/PoseStamped",
        Kind::Msg,
        include_str!("../std/geometry_msgs/msg/PoseStamped.msg"),
    ),
    (
        "geometry_msgs/msg/Transform",
        Kind::Msg,
        include_str!("../std/geometry_msgs/msg/Transform.msg"),
    ),
    (
        "geometry_msgs/msg/TransformStamped",
        Kind::Msg,
        include_str!("../std/geometry_msgs/msg/TransformStamped.msg"),
    ),
    (
        "nav_msgs/msg/Path",
        Kind::Msg,
        include_str!("../std/nav_msgs/msg/Path.msg"),
    ),
    (
        "visualization_msgs/msg/Marker",
        Kind::Msg,
        include_str!("../std/visualization_msgs/msg/Marker.msg"),
    ),
    (
        "visualization_msgs/msg/MarkerArray",
        Kind::Msg,
        include_str!("../std/visualization_msgs/msg/MarkerArray.msg"),
    ),
    (
        "visualization_msgs/msg/UVCoordinate",
        Kind::Msg,
        include_str!("../std/visualization_msgs/msg/UVCoordinate.msg"),
    ),
    (
        "visualization_msgs/msg/MeshFile",
        Kind::Msg,
        include_str!("../std/visualization_msgs/msg/MeshFile.msg"),
    ),
    (
        "sensor_msgs/msg/Image",
        Kind::Msg,
        include_str!("../std/sensor_msgs/msg/Image.msg"),
    ),
    (
        "sensor_msgs/msg/CompressedImage",
        Kind::Msg,
        include_str!("../std/sensor_msgs/msg/CompressedImage.msg"),
    ),
    (
        "sensor_msgs/msg/JointState",
        Kind::Msg,
        include_str!("../std/sensor_msgs/msg/JointState.msg"),
    ),
    (
        "sensor_msgs/msg/Temperature",
        Kind::Msg,
        include_str!("../std/sensor_msgs/msg/Temperature.msg"),
    ),
    (
        "tf2_msgs/msg/TFMessage",
        Kind::Msg,
        include_str!("../std/tf2_msgs/msg/TFMessage.msg"),
    ),
    (
        "diagnostic_msgs/msg/DiagnosticArray",
        Kind::Msg,
        include_str!("../std/diagnostic_msgs/msg/DiagnosticArray.msg"),
    ),
    (
        "diagnostic_msgs/msg/DiagnosticStatus",
        Kind::Msg,
        include_str!("../std/diagnostic_msgs/msg/DiagnosticStatus.msg"),
    ),
    (
        "diagnostic_msgs/msg/KeyValue",
        Kind::Msg,
        include_str!("../std/diagnostic_msgs/msg/KeyValue.msg"),
    ),
    (
        "cell_msgs/msg/Toolpath",
        Kind::Msg,
        include_str!("../msg/Toolpath.msg"),
    ),
    (
        "cell_msgs/msg/ToolpathSegment",
        Kind::Msg,
        include_str!("../msg/ToolpathSegment.msg"),
    ),
    (
        "cell_msgs/msg/HeatMap",
        Kind::Msg,
        include_str!("../msg/HeatMap.msg"),
    ),
    (
        "cell_msgs/msg/ProgramFile",
        Kind::Msg,
        include_str!("../msg/ProgramFile.msg"),
    ),
    (
        "cell_msgs/msg/MachineProgram",
        Kind::Msg,
        include_str!("../msg/MachineProgram.msg"),
    ),
    (
        "cell_msgs/msg/MachineStatus",
        Kind::Msg,
        include_str!("../msg/MachineStatus.msg"),
    ),
    (
        "cell_msgs/msg/MachineCommand",
        Kind::Msg,
        include_str!("../msg/MachineCommand.msg"),
    ),
    (
        "cell_msgs/msg/CutPlan",
        Kind::Msg,
        include_str!("../msg/CutPlan.msg"),
    ),
    (
        "cell_msgs/msg/Polygon2",
        Kind::Msg,
        include_str!("../msg/Polygon2.msg"),
    ),
    (
        "cell_msgs/msg/SliceLayer",
        Kind::Msg,
        include_str!("../msg/SliceLayer.msg"),
    ),
    (
        "cell_msgs/msg/LayerStack",
        Kind::Msg,
        include_str!("../msg/LayerStack.msg"),
    ),
    (
        "cell_msgs/srv/EmitProgram",
        Kind::Srv,
        include_str!("../srv/EmitProgram.srv"),
    ),
    (
        "cell_msgs/srv/SendMachineCommand",
        Kind::Srv,
        include_str!("../srv/SendMachineCommand.srv"),
    ),
    (
        "cell_msgs/action/PlanHotwire",
        Kind::Action,
        include_str!("../action/PlanHotwire.action"),
    ),
    (
        "cell_msgs/action/ExecuteProgram",
        Kind::Action,
        include_str!("../action/ExecuteProgram.action"),
    ),
    (
        "cell_msgs/action/SequenceSheet",
        Kind::Action,
        include_str!("../action/SequenceSheet.action"),
    ),
    (
        "cell_msgs/action/Slice",
        Kind::Action,
        include_str!("../action/Slice.action"),
    ),
];

/// Standard interfaces known by their definition alone (no Rust type, so not in [`list`] nor
/// under the drift test): the types that REP-2011 type descriptions of services and actions
/// reference (`crate::type_hash`), the action cancel/status types and `/rosout`'s `Log`.
/// Copied unchanged from the ROS 2 Jazzy packages.
const DEFINITION_ONLY_FILES: &[(&str, Kind, &str)] = &[
    (
        "unique_identifier_msgs/msg/UUID",
        Kind::Msg,
        include_str!("../std/unique_identifier_msgs/msg/UUID.msg"),
    ),
    (
        "service_msgs/msg/ServiceEventInfo",
        Kind::Msg,
        include_str!("../std/service_msgs/msg/ServiceEventInfo.msg"),
    ),
    (
        "action_msgs/msg/GoalInfo",
        Kind::Msg,
        include_str!("../std/action_msgs/msg/GoalInfo.msg"),
    ),
    (
        "action_msgs/msg/GoalStatus",
        Kind::Msg,
        include_str!("../std/action_msgs/msg/GoalStatus.msg"),
    ),
    (
        "action_msgs/msg/GoalStatusArray",
        Kind::Msg,
        include_str!("../std/action_msgs/msg/GoalStatusArray.msg"),
    ),
    (
        "action_msgs/srv/CancelGoal",
        Kind::Srv,
        include_str!("../std/action_msgs/srv/CancelGoal.srv"),
    ),
    (
        "rcl_interfaces/msg/Log",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/Log.msg"),
    ),
    // The parameter services and events ros2-client serves on every node (their endpoints
    // announce these hashes too).
    (
        "rcl_interfaces/msg/FloatingPointRange",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/FloatingPointRange.msg"),
    ),
    (
        "rcl_interfaces/msg/IntegerRange",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/IntegerRange.msg"),
    ),
    (
        "rcl_interfaces/msg/ListParametersResult",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/ListParametersResult.msg"),
    ),
    (
        "rcl_interfaces/msg/Parameter",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/Parameter.msg"),
    ),
    (
        "rcl_interfaces/msg/ParameterDescriptor",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/ParameterDescriptor.msg"),
    ),
    (
        "rcl_interfaces/msg/ParameterEvent",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/ParameterEvent.msg"),
    ),
    (
        "rcl_interfaces/msg/ParameterType",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/ParameterType.msg"),
    ),
    (
        "rcl_interfaces/msg/ParameterValue",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/ParameterValue.msg"),
    ),
    (
        "rcl_interfaces/msg/SetParametersResult",
        Kind::Msg,
        include_str!("../std/rcl_interfaces/msg/SetParametersResult.msg"),
    ),
    (
        "rcl_interfaces/srv/DescribeParameters",
        Kind::Srv,
        include_str!("../std/rcl_interfaces/srv/DescribeParameters.srv"),
    ),
    (
        "rcl_interfaces/srv/GetParameterTypes",
        Kind::Srv,
        include_str!("../std/rcl_interfaces/srv/GetParameterTypes.srv"),
    ),
    (
        "rcl_interfaces/srv/GetParameters",
        Kind::Srv,
        include_str!("../std/rcl_interfaces/srv/GetParameters.srv"),
    ),
    (
        "rcl_interfaces/srv/ListParameters",
        Kind::Srv,
        include_str!("../std/rcl_interfaces/srv/ListParameters.srv"),
    ),
    (
        "rcl_interfaces/srv/SetParameters",
        Kind::Srv,
        include_str!("../std/rcl_interfaces/srv/SetParameters.srv"),
    ),
    (
        "rcl_interfaces/srv/SetParametersAtomically",
        Kind::Srv,
        include_str!("../std/rcl_interfaces/srv/SetParametersAtomically.srv"),
    ),
    // The graph-information topic every ROS 2 participant publishes (`ros_discovery_info`).
    (
        "rmw_dds_common/msg/Gid",
        Kind::Msg,
        include_str!("../std/rmw_dds_common/msg/Gid.msg"),
    ),
    (
        "rmw_dds_common/msg/NodeEntitiesInfo",
        Kind::Msg,
        include_str!("../std/rmw_dds_common/msg/NodeEntitiesInfo.msg"),
    ),
    (
        "rmw_dds_common/msg/ParticipantEntitiesInfo",
        Kind::Msg,
        include_str!("../std/rmw_dds_common/msg/ParticipantEntitiesInfo.msg"),
    ),
];

/// The line that precedes each dependency in a `ros2msg` complete definition.
pub const DELIMITER: &str =
    "================================================================================";

/// All registered message names, e.g. `cell_msgs/msg/Toolpath`, `cell_msgs/action/PlanHotwire_Goal`.
pub fn list() -> Vec<String> {
    FILES
        .iter()
        .flat_map(|(file, kind, _)| {
            kind.parts()
                .iter()
                .map(move |suffix| format!("{file}{suffix}"))
        })
        .collect()
}

/// Finds the file and section index that define `ros_name`.
fn locate(ros_name: &str) -> Option<(&'static str, Kind, &'static str, usize)> {
    FILES
        .iter()
        .chain(DEFINITION_ONLY_FILES)
        .find_map(|&(file, kind, text)| {
            let suffix = ros_name.strip_prefix(file)?;
            let index = kind.parts().iter().position(|p| *p == suffix)?;
            Some((file, kind, text, index))
        })
}

/// The `.msg` text of one registered message, as in the file; for a service or action part,
/// that section of the file (without the `---` lines).
pub fn definition(ros_name: &str) -> Option<&'static str> {
    let (_, kind, text, index) = locate(ros_name)?;
    if kind == Kind::Msg {
        return Some(text);
    }
    idl::sections(text).get(index).map(|s| s.text)
}

/// The parsed definition of one registered message. Errors in service or action parts carry
/// the line number within the whole file.
pub fn spec(ros_name: &str) -> Result<MessageSpec, RegistryError> {
    let unknown = || RegistryError::Unknown(ros_name.to_owned());
    let (file, kind, text, index) = locate(ros_name).ok_or_else(unknown)?;
    if kind == Kind::Msg {
        return Ok(idl::parse_message(ros_name, text)?);
    }
    let section = idl::sections(text)
        .get(index)
        .copied()
        .ok_or_else(unknown)?;
    Ok(idl::parse_section(
        ros_name,
        file,
        section.first_line,
        section.text,
    )?)
}

/// The rosbag2 `ros2msg` complete definition of a registered message: its own text, then each
/// message it uses (recursively, each once, depth-first in order of first use), each preceded
/// by [`DELIMITER`] and `MSG: pkg/msg/Type`. Parts are joined with `\n`; trailing newlines of the
/// files are dropped so no blank lines appear around delimiters.
pub fn full_definition(ros_name: &str) -> Result<String, RegistryError> {
    let text = definition(ros_name).ok_or_else(|| RegistryError::Unknown(ros_name.to_owned()))?;
    let mut parts = vec![text.trim_end_matches(['\n', '\r']).to_owned()];
    let mut seen = vec![ros_name.to_owned()];
    append_dependencies(ros_name, &mut seen, &mut parts)?;
    Ok(parts.join("\n"))
}

fn append_dependencies(
    ros_name: &str,
    seen: &mut Vec<String>,
    parts: &mut Vec<String>,
) -> Result<(), RegistryError> {
    for dep in spec(ros_name)?.dependencies() {
        if seen.iter().any(|s| s == dep) {
            continue;
        }
        seen.push(dep.to_owned());
        let text = definition(dep).ok_or_else(|| RegistryError::Unknown(dep.to_owned()))?;
        parts.push(DELIMITER.to_owned());
        parts.push(format!("MSG: {dep}"));
        parts.push(text.trim_end_matches(['\n', '\r']).to_owned());
        append_dependencies(dep, seen, parts)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_definition_parses_and_resolves() {
        let names = list();
        // Messages: cell 11, std 7, rosgraph_msgs 1, the views' standard types 18.
        assert_eq!(names.len(), 11 + 7 + 1 + 18 + 3 * 2 + 4 * 3);
        for name in &names {
            assert!(definition(name).is_some(), "{name}");
            let spec = spec(name).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(&spec.name, name);
            full_definition(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
        assert!(definition("cell_msgs/msg/Nope").is_none());
        assert!(definition("cell_msgs/action/PlanHotwire").is_none());
        assert_eq!(
            spec("nope/msg/X"),
            Err(RegistryError::Unknown("nope/msg/X".into()))
        );
    }

    #[test]
    fn action_parts_are_their_sections() {
        let goal = definition("cell_msgs/action/PlanHotwire_Goal").expect("goal");
        assert!(
            goal.starts_with("# Plan a hot-wire cut") && goal.ends_with("uint64 seed"),
            "{goal}"
        );
        let result = definition("cell_msgs/action/PlanHotwire_Result").expect("result");
        assert!(result.starts_with("bool success") && result.ends_with("float64 baseline_loss"));
        let feedback = definition("cell_msgs/action/ExecuteProgram_Feedback").expect("feedback");
        assert!(feedback.starts_with("uint32 acked_line"));
    }

    #[test]
    fn service_parts_are_their_sections() {
        let request = definition("cell_msgs/srv/EmitProgram_Request").expect("request");
        assert!(
            request.starts_with("# Turn a Toolpath") && request.ends_with("bool publish"),
            "{request}"
        );
        let response = definition("cell_msgs/srv/EmitProgram_Response").expect("response");
        assert!(
            response.starts_with("# Whether a program was emitted")
                && response
                    .trim_end()
                    .ends_with("cell_msgs/MachineProgram program"),
            "{response}"
        );
        assert!(definition("cell_msgs/srv/EmitProgram").is_none());
        let full = full_definition("cell_msgs/srv/EmitProgram_Response").expect("resolves");
        for dep in ["cell_msgs/msg/MachineProgram", "cell_msgs/msg/ProgramFile"] {
            assert_eq!(full.matches(&format!("MSG: {dep}\n")).count(), 1, "{dep}");
        }
    }

    #[test]
    fn toolpath_full_definition_golden() {
        let full = full_definition("cell_msgs/msg/Toolpath").expect("resolves");
        let toolpath = include_str!("../msg/Toolpath.msg");
        assert!(
            full.starts_with(toolpath.trim_end()),
            "top-level text comes first, undelimited"
        );
        assert_eq!(DELIMITER.len(), 80);
        assert!(DELIMITER.chars().all(|c| c == '='));
        let headers: Vec<&str> = full.lines().filter(|l| l.starts_with("MSG: ")).collect();
        assert_eq!(
            headers,
            [
                "MSG: std_msgs/msg/Header",
                "MSG: builtin_interfaces/msg/Time",
                "MSG: cell_msgs/msg/ToolpathSegment",
                "MSG: geometry_msgs/msg/Point",
                "MSG: geometry_msgs/msg/Vector3",
            ]
        );
        // Every MSG line is directly preceded by the delimiter, and delimiters appear nowhere else.
        let lines: Vec<&str> = full.lines().collect();
        let delimiters: Vec<usize> = (0..lines.len())
            .filter(|&i| lines[i] == DELIMITER)
            .collect();
        assert_eq!(delimiters.len(), headers.len());
        assert!(delimiters
            .iter()
            .all(|&i| lines[i + 1].starts_with("MSG: ")));
        assert!(full.contains(&format!(
            "{DELIMITER}\nMSG: geometry_msgs/msg/Point\n# This contains the position"
        )));
        assert!(!full.ends_with('\n'));
    }

    #[test]
    fn action_full_definition_includes_nested_dependencies() {
        let full = full_definition("cell_msgs/action/ExecuteProgram_Goal").expect("resolves");
        assert!(full.starts_with("# Stream a machine program"));
        for dep in [
            "cell_msgs/msg/MachineProgram",
            "std_msgs/msg/Header",
            "cell_msgs/msg/ProgramFile",
        ] {
            assert_eq!(full.matches(&format!("MSG: {dep}\n")).count(), 1, "{dep}");
        }
    }
}
