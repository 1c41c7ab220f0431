//! Topic names of the views, derived from the topic of the message they show.
//!
//! A view sits below its source's resolved topic, so remapping the source (the demo puts the
//! sequencer's toolpath on `/cell/sheet_toolpath`) moves its views with it:
//! `/cell/sheet_toolpath/path`, `/cell/sheet_toolpath/markers`, `/cell/sheet_heat/image`.
//! The machine views use the names stock tools look for: `joint_states` (relative, so in the
//! node's namespace), and the global `/tf`, `/tf_static` and `/diagnostics`.

/// `nav_msgs/Path` of a toolpath topic.
pub fn path(toolpath_topic: &str) -> String {
    format!("{}/path", toolpath_topic.trim_end_matches('/'))
}

/// `visualization_msgs/MarkerArray` of a toolpath topic.
pub fn markers(toolpath_topic: &str) -> String {
    format!("{}/markers", toolpath_topic.trim_end_matches('/'))
}

/// `sensor_msgs/Image` of a heat-map topic.
pub fn image(heat_map_topic: &str) -> String {
    format!("{}/image", heat_map_topic.trim_end_matches('/'))
}

/// `sensor_msgs/JointState` of the machine bridge (relative: in the node's namespace).
pub const JOINT_STATES: &str = "joint_states";

/// tf2's dynamic transforms.
pub const TF: &str = "/tf";

/// tf2's static transforms (latched: reliable, transient-local).
pub const TF_STATIC: &str = "/tf_static";

/// `diagnostic_msgs/DiagnosticArray`, read by `rqt_robot_monitor` and Foxglove's diagnostics panels.
pub const DIAGNOSTICS: &str = "/diagnostics";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_sit_below_their_source() {
        assert_eq!(path("/cell/sheet_toolpath"), "/cell/sheet_toolpath/path");
        assert_eq!(markers("toolpath"), "toolpath/markers");
        assert_eq!(image("/cell/exposure/"), "/cell/exposure/image");
    }
}
