//! Topic names of the views, derived from the topic of the message they show.
//!
//! A view sits below its source's resolved topic, so remapping the source (the demo puts the
//! sequencer's toolpath on `/cell/sheet_toolpath`) moves its views with it:
//! `/cell/sheet_toolpath/path`, `/cell/sheet_toolpath/markers`, `/cell/sheet_heat/image`.
//! The machine views use the names stock tools look for: `joint_states` (relative, so in the
//! node's namespace), and the global `/tf`, `/tf_static` and `/diagnostics`. A printer's
//! heaters are per machine, relative too: `<machine>/temperature/<heater>` ([`temperature`]).

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

/// `sensor_msgs/Temperature` of one heater of one machine (relative: in the node's namespace):
/// `<machine>/temperature/<heater>`, e.g. `marlin_sim/temperature/hotend`, each part made a
/// valid ROS 2 name token by [`name_token`].
pub fn temperature(machine_id: &str, heater: &str) -> String {
    format!(
        "{}/temperature/{}",
        name_token(machine_id),
        name_token(heater)
    )
}

/// `text` as one token of a ROS 2 topic name (rcl's `rmw_validate_full_topic_name`: ASCII
/// letters, digits and `_`, no `__`, not starting with a digit): every other character (the
/// `-` of `marlin-sim`) and every run of them becomes one `_`, a leading digit gets a `_` in
/// front, and an empty text is `_`. Distinct ids can share a token (`a-b`, `a_b`); their
/// messages keep them apart by frame id.
pub fn name_token(text: &str) -> String {
    let mut token = String::with_capacity(text.len() + 1);
    if text.starts_with(|c: char| c.is_ascii_digit()) {
        token.push('_');
    }
    for c in text.chars() {
        let c = if c.is_ascii_alphanumeric() { c } else { '_' };
        if !(c == '_' && token.ends_with('_')) {
            token.push(c);
        }
    }
    if token.is_empty() {
        token.push('_');
    }
    token
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_sit_below_their_source() {
        assert_eq!(path("/cell/sheet_toolpath"), "/cell/sheet_toolpath/path");
        assert_eq!(markers("toolpath"), "toolpath/markers");
        assert_eq!(image("/cell/exposure/"), "/cell/exposure/image");
    }

    #[test]
    fn temperature_topics_are_valid_names_per_machine_and_heater() {
        assert_eq!(
            temperature("marlin-sim", "hotend"),
            "marlin_sim/temperature/hotend"
        );
        assert_eq!(temperature("printer", "bed"), "printer/temperature/bed");
        for (text, token) in [
            ("marlin-sim", "marlin_sim"),
            ("3d--printer", "_3d_printer"),
            ("a__b", "a_b"),
            ("/x.y/", "_x_y_"),
            ("drücker", "dr_cker"),
            ("", "_"),
        ] {
            assert_eq!(name_token(text), token, "{text:?}");
        }
    }
}
