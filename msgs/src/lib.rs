//! cellsuite message, service and action types.
//!
//! The `.msg`/`.srv`/`.action` files under `msgs/` are the single source of truth. This crate embeds
//! them ([`registry`]), parses them ([`idl`]), provides matching serde types (this module and
//! [`builtin_interfaces`], [`std_msgs`], [`std_srvs`], [`geometry_msgs`], and the standard types
//! of the RViz/Foxglove views in [`nav_msgs`], [`visualization_msgs`], [`sensor_msgs`],
//! [`tf2_msgs`], [`diagnostic_msgs`]), writes and reads ROS 2 CDR ([`to_cdr`], [`from_cdr`]) and
//! decodes CDR from the definitions alone ([`dynamic`]). The drift test (`tests/drift.rs`) checks
//! every Rust type against its definition. [`type_hash()`] gives the REP-2011 `RIHS01_` hash of
//! every interface (messages, services, actions and the types rosidl derives from them), equal to
//! stock rosidl's ([`type_description`] builds what is hashed).
//!
//! Service and action parts are plain messages named like rosidl does:
//! `cell_msgs/srv/EmitProgram_Request` is [`EmitProgramRequest`] and
//! `cell_msgs/action/PlanHotwire_Goal` is [`PlanHotwireGoal`].

pub mod builtin_interfaces;
pub mod cdr;
pub mod diagnostic_msgs;
pub mod dynamic;
pub mod geometry_msgs;
pub mod idl;
pub mod json;
pub mod nav_msgs;
pub mod registry;
pub mod rosgraph_msgs;
pub mod sensor_msgs;
pub mod std_msgs;
pub mod std_srvs;
pub mod tf2_msgs;
pub mod type_description;
pub mod type_hash;
pub mod visualization_msgs;

mod action;
mod msg;
mod srv;

pub use action::{
    ExecuteProgramFeedback, ExecuteProgramGoal, ExecuteProgramResult, PlanHotwireFeedback,
    PlanHotwireGoal, PlanHotwireResult, SequenceSheetFeedback, SequenceSheetGoal,
    SequenceSheetResult, SliceFeedback, SliceGoal, SliceResult,
};
pub use cdr::{from_cdr, to_cdr, CdrError};
pub use msg::{
    CutPlan, HeatMap, HeatMapSizeError, LayerStack, MachineCommand, MachineProgram, MachineStatus,
    Polygon2, ProgramFile, SliceLayer, Toolpath, ToolpathSegment,
};
pub use srv::{
    EmitProgramRequest, EmitProgramResponse, SendMachineCommandRequest, SendMachineCommandResponse,
};
pub use type_hash::{type_hash, TypeHash};

/// A Rust type that mirrors a registered ROS 2 message definition.
pub trait RosMessage:
    serde::Serialize + serde::de::DeserializeOwned + Clone + std::fmt::Debug + Send + Sync + 'static
{
    /// ROS 2 name, e.g. `cell_msgs/msg/Toolpath`, `cell_msgs/srv/EmitProgram_Request` or
    /// `cell_msgs/action/PlanHotwire_Goal`.
    const ROS_NAME: &'static str;

    /// Package, e.g. `cell_msgs`.
    fn package() -> &'static str {
        name_parts(Self::ROS_NAME).0
    }

    /// Interface kind: `msg`, `srv` or `action`.
    fn interface_kind() -> &'static str {
        name_parts(Self::ROS_NAME).1
    }

    /// Type name within the package, e.g. `Toolpath` or `PlanHotwire_Goal`.
    fn type_name() -> &'static str {
        name_parts(Self::ROS_NAME).2
    }

    /// DDS type name as rosidl generates it, e.g. `cell_msgs::msg::dds_::Toolpath_`.
    fn dds_type_name() -> String {
        let (package, kind, name) = name_parts(Self::ROS_NAME);
        format!("{package}::{kind}::dds_::{name}_")
    }

    /// Serializes the message as ROS 2 does (see [`to_cdr`]). Messages dominated by one large
    /// numeric array ([`HeatMap`]) write it as one block instead of value by value, which is
    /// byte-identical and far faster (a 1024×1024 heat map: milliseconds less per frame).
    fn encode(&self) -> Result<Vec<u8>, CdrError> {
        match (self as &dyn std::any::Any).downcast_ref::<HeatMap>() {
            Some(heat_map) => heat_map.to_cdr_bulk(),
            None => to_cdr(self),
        }
    }

    /// Reads a ROS 2 serialized message (see [`from_cdr`]); the inverse of [`Self::encode`].
    fn decode(bytes: &[u8]) -> Result<Self, CdrError> {
        if std::any::TypeId::of::<Self>() == std::any::TypeId::of::<HeatMap>() {
            let heat_map: Box<dyn std::any::Any> = Box::new(HeatMap::from_cdr_bulk(bytes)?);
            if let Ok(this) = heat_map.downcast::<Self>() {
                return Ok(*this);
            }
        }
        from_cdr(bytes)
    }

    /// The rosbag2 `ros2msg` complete definition, see [`registry::full_definition`].
    ///
    /// # Panics
    /// If `ROS_NAME` is not registered or its files do not parse. Never for this crate's types:
    /// the definitions are embedded and the drift test resolves every one.
    fn full_definition() -> String {
        match registry::full_definition(Self::ROS_NAME) {
            Ok(text) => text,
            Err(e) => panic!("embedded definition of {}: {e}", Self::ROS_NAME),
        }
    }
}

/// Splits `pkg/kind/Type` into its three parts (a malformed name yields empty leading parts).
fn name_parts(ros_name: &'static str) -> (&'static str, &'static str, &'static str) {
    let mut parts = ros_name.rsplitn(3, '/');
    let name = parts.next().unwrap_or_default();
    let kind = parts.next().unwrap_or_default();
    (parts.next().unwrap_or_default(), kind, name)
}

/// Calls `$callback!(Type => "ros/name", ...)` with every Rust message type of this crate.
/// This is the one list to extend when adding a type: it implements [`RosMessage`] and puts the
/// type under the drift test.
#[macro_export]
macro_rules! for_each_message {
    ($callback:ident) => {
        $callback! {
            $crate::builtin_interfaces::Time => "builtin_interfaces/msg/Time",
            $crate::std_msgs::Header => "std_msgs/msg/Header",
            $crate::std_msgs::StringMsg => "std_msgs/msg/String",
            $crate::geometry_msgs::Point => "geometry_msgs/msg/Point",
            $crate::geometry_msgs::Vector3 => "geometry_msgs/msg/Vector3",
            $crate::geometry_msgs::Quaternion => "geometry_msgs/msg/Quaternion",
            $crate::geometry_msgs::Pose => "geometry_msgs/msg/Pose",
            $crate::rosgraph_msgs::Clock => "rosgraph_msgs/msg/Clock",
            $crate::builtin_interfaces::Duration => "builtin_interfaces/msg/Duration",
            $crate::std_msgs::ColorRGBA => "std_msgs/msg/ColorRGBA",
            $crate::geometry_msgs::PoseStamped => "geometry_msgs/msg/PoseStamped",
            $crate::geometry_msgs::Transform => "geometry_msgs/msg/Transform",
            $crate::geometry_msgs::TransformStamped => "geometry_msgs/msg/TransformStamped",
            $crate::nav_msgs::Path => "nav_msgs/msg/Path",
            $crate::visualization_msgs::Marker => "visualization_msgs/msg/Marker",
            $crate::visualization_msgs::MarkerArray => "visualization_msgs/msg/MarkerArray",
            $crate::visualization_msgs::UVCoordinate => "visualization_msgs/msg/UVCoordinate",
            $crate::visualization_msgs::MeshFile => "visualization_msgs/msg/MeshFile",
            $crate::sensor_msgs::Image => "sensor_msgs/msg/Image",
            $crate::sensor_msgs::CompressedImage => "sensor_msgs/msg/CompressedImage",
            $crate::sensor_msgs::JointState => "sensor_msgs/msg/JointState",
            $crate::sensor_msgs::Temperature => "sensor_msgs/msg/Temperature",
            $crate::tf2_msgs::TFMessage => "tf2_msgs/msg/TFMessage",
            $crate::diagnostic_msgs::DiagnosticArray => "diagnostic_msgs/msg/DiagnosticArray",
            $crate::diagnostic_msgs::DiagnosticStatus => "diagnostic_msgs/msg/DiagnosticStatus",
            $crate::diagnostic_msgs::KeyValue => "diagnostic_msgs/msg/KeyValue",
            $crate::std_srvs::SetBoolRequest => "std_srvs/srv/SetBool_Request",
            $crate::std_srvs::SetBoolResponse => "std_srvs/srv/SetBool_Response",
            $crate::Toolpath => "cell_msgs/msg/Toolpath",
            $crate::ToolpathSegment => "cell_msgs/msg/ToolpathSegment",
            $crate::HeatMap => "cell_msgs/msg/HeatMap",
            $crate::ProgramFile => "cell_msgs/msg/ProgramFile",
            $crate::MachineProgram => "cell_msgs/msg/MachineProgram",
            $crate::MachineStatus => "cell_msgs/msg/MachineStatus",
            $crate::MachineCommand => "cell_msgs/msg/MachineCommand",
            $crate::CutPlan => "cell_msgs/msg/CutPlan",
            $crate::Polygon2 => "cell_msgs/msg/Polygon2",
            $crate::SliceLayer => "cell_msgs/msg/SliceLayer",
            $crate::LayerStack => "cell_msgs/msg/LayerStack",
            $crate::EmitProgramRequest => "cell_msgs/srv/EmitProgram_Request",
            $crate::EmitProgramResponse => "cell_msgs/srv/EmitProgram_Response",
            $crate::SendMachineCommandRequest => "cell_msgs/srv/SendMachineCommand_Request",
            $crate::SendMachineCommandResponse => "cell_msgs/srv/SendMachineCommand_Response",
            $crate::PlanHotwireGoal => "cell_msgs/action/PlanHotwire_Goal",
            $crate::PlanHotwireResult => "cell_msgs/action/PlanHotwire_Result",
            $crate::PlanHotwireFeedback => "cell_msgs/action/PlanHotwire_Feedback",
            $crate::ExecuteProgramGoal => "cell_msgs/action/ExecuteProgram_Goal",
            $crate::ExecuteProgramResult => "cell_msgs/action/ExecuteProgram_Result",
            $crate::ExecuteProgramFeedback => "cell_msgs/action/ExecuteProgram_Feedback",
            $crate::SequenceSheetGoal => "cell_msgs/action/SequenceSheet_Goal",
            $crate::SequenceSheetResult => "cell_msgs/action/SequenceSheet_Result",
            $crate::SequenceSheetFeedback => "cell_msgs/action/SequenceSheet_Feedback",
            $crate::SliceGoal => "cell_msgs/action/Slice_Goal",
            $crate::SliceResult => "cell_msgs/action/Slice_Result",
            $crate::SliceFeedback => "cell_msgs/action/Slice_Feedback",
        }
    };
}

macro_rules! impl_ros_message {
    ($($ty:ty => $name:literal),* $(,)?) => {
        $(impl RosMessage for $ty {
            const ROS_NAME: &'static str = $name;
        })*
    };
}
for_each_message!(impl_ros_message);

/// ros2-client's services and actions take types marked with its `Message` trait; the orphan
/// rule means the mark can only be made here.
#[cfg(feature = "ros2")]
macro_rules! impl_ros2_client_message {
    ($($ty:ty => $name:literal),* $(,)?) => {
        $(impl ros2_client::Message for $ty {})*
    };
}
#[cfg(feature = "ros2")]
for_each_message!(impl_ros2_client_message);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_derived_from_ros_name() {
        assert_eq!(Toolpath::dds_type_name(), "cell_msgs::msg::dds_::Toolpath_");
        assert_eq!(
            PlanHotwireGoal::dds_type_name(),
            "cell_msgs::action::dds_::PlanHotwire_Goal_"
        );
        assert_eq!(
            std_msgs::Header::dds_type_name(),
            "std_msgs::msg::dds_::Header_"
        );
        assert_eq!(
            (
                ExecuteProgramFeedback::package(),
                ExecuteProgramFeedback::interface_kind()
            ),
            ("cell_msgs", "action")
        );
        assert_eq!(
            ExecuteProgramFeedback::type_name(),
            "ExecuteProgram_Feedback"
        );
        assert_eq!(
            EmitProgramRequest::dds_type_name(),
            "cell_msgs::srv::dds_::EmitProgram_Request_"
        );
        assert_eq!(
            (
                EmitProgramResponse::interface_kind(),
                EmitProgramResponse::type_name()
            ),
            ("srv", "EmitProgram_Response")
        );
        assert_eq!(name_parts("bad"), ("", "", "bad"));
    }
}
