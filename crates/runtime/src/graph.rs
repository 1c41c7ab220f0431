//! What other nodes publish: the ROS topics in the DDS graph, with their types and the QoS
//! preset that matches their writers (for a recorder that subscribes to whatever it finds).

use rustdds::policy::{Durability, Reliability};

use crate::{CellNode, QosPreset};

/// A topic some writer in the graph publishes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PublishedTopic {
    /// ROS topic name, e.g. `/cell/toolpath`.
    pub topic: String,
    /// ROS type name, e.g. `cell_msgs/msg/Toolpath`.
    pub ros_type: String,
    /// The preset a subscriber needs to match the writer: transient-local writers are `Plan`,
    /// best-effort ones `Stream`, other reliable ones `Status`.
    pub qos: QosPreset,
}

/// `rt/cell/toolpath` → `/cell/toolpath`; `None` for services, actions' internal topics and
/// DDS-only topics.
pub fn ros_topic_name(dds: &str) -> Option<String> {
    let rest = dds.strip_prefix("rt/")?;
    (!rest.contains("/_action/")).then(|| format!("/{rest}"))
}

/// The ROS 2 name of a DDS type name, the inverse of rosidl's DDS naming:
/// `cell_msgs::msg::dds_::Toolpath_` → `cell_msgs/msg/Toolpath`. `None` for a name not of that
/// form (a kind other than msg/srv/action, an empty package or type).
pub fn ros_type_name(dds: &str) -> Option<String> {
    let mut parts = dds.split("::");
    let (package, kind, dds_, name) = (parts.next()?, parts.next()?, parts.next()?, parts.next()?);
    let name = name.strip_suffix('_')?;
    let well_formed = parts.next().is_none()
        && dds_ == "dds_"
        && matches!(kind, "msg" | "srv" | "action")
        && !package.is_empty()
        && !name.is_empty();
    well_formed.then(|| format!("{package}/{kind}/{name}"))
}

impl CellNode {
    /// Topics the writers discovered so far publish (one entry per topic, sorted; our own
    /// writers included).
    pub fn published_topics(&self) -> Vec<PublishedTopic> {
        let mut found: Vec<PublishedTopic> = self
            .domain_participant()
            .discovered_writers()
            .into_iter()
            .filter_map(|w| {
                let data = &w.publication_topic_data;
                let topic = ros_topic_name(&data.topic_name)?;
                let ros_type = ros_type_name(&data.type_name)?;
                let qos = if matches!(data.durability, Some(Durability::TransientLocal)) {
                    QosPreset::Plan
                } else if matches!(data.reliability, Some(Reliability::BestEffort)) {
                    QosPreset::Stream
                } else {
                    QosPreset::Status
                };
                Some(PublishedTopic {
                    topic,
                    ros_type,
                    qos,
                })
            })
            .collect();
        found.sort_by(|a, b| a.topic.cmp(&b.topic));
        found.dedup_by(|a, b| a.topic == b.topic);
        found
    }

    /// Readers discovered so far (our own included), with their DDS topic and ROS type names
    /// (`rt/machine_program`, `cell_msgs/msg/MachineProgram`; a service server's request reader
    /// is `rq/machine_commandRequest`, `cell_msgs/srv/SendMachineCommand_Request`), sorted,
    /// one entry per pair. Readers of types not named as rosidl names them are left out.
    pub fn discovered_readers(&self) -> Vec<DiscoveredReader> {
        let mut found: Vec<DiscoveredReader> = self
            .domain_participant()
            .discovered_readers()
            .into_iter()
            .filter_map(|r| {
                let data = &r.subscription_topic_data;
                Some(DiscoveredReader {
                    dds_topic: data.topic_name().to_string(),
                    ros_type: ros_type_name(data.type_name())?,
                })
            })
            .collect();
        found.sort();
        found.dedup();
        found
    }
}

/// A reader in the graph: see [`CellNode::discovered_readers`].
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct DiscoveredReader {
    /// DDS topic name (`rt/…` for topics, `rq/…Request` for service servers).
    pub dds_topic: String,
    /// ROS type name, e.g. `cell_msgs/msg/MachineProgram`.
    pub ros_type: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dds_names_map_to_ros_names() {
        assert_eq!(
            ros_topic_name("rt/cell/toolpath").as_deref(),
            Some("/cell/toolpath")
        );
        assert_eq!(ros_topic_name("rq/cell/emit_programRequest"), None);
        assert_eq!(ros_topic_name("rt/plan_hotwire/_action/feedback"), None);
        assert_eq!(ros_topic_name("ros_discovery_info"), None);
        assert_eq!(
            ros_type_name("cell_msgs::msg::dds_::Toolpath_").as_deref(),
            Some("cell_msgs/msg/Toolpath")
        );
        assert_eq!(
            ros_type_name("std_msgs::msg::dds_::String_").as_deref(),
            Some("std_msgs/msg/String")
        );
        assert_eq!(
            ros_type_name("rmw_dds_common::msg::ParticipantEntitiesInfo"),
            None
        );
    }

    #[test]
    fn dds_type_names_map_back_to_ros_names() {
        let cases = [
            ("cell_msgs::msg::dds_::Toolpath_", "cell_msgs/msg/Toolpath"),
            (
                "cell_msgs::srv::dds_::EmitProgram_Request_",
                "cell_msgs/srv/EmitProgram_Request",
            ),
            (
                "cell_msgs::action::dds_::PlanHotwire_SendGoal_Response_",
                "cell_msgs/action/PlanHotwire_SendGoal_Response",
            ),
            (
                "cell_msgs::action::dds_::PlanHotwire_FeedbackMessage_",
                "cell_msgs/action/PlanHotwire_FeedbackMessage",
            ),
        ];
        for (dds, ros) in cases {
            assert_eq!(ros_type_name(dds).as_deref(), Some(ros), "{dds}");
        }
    }

    #[test]
    fn names_that_are_not_rosidl_dds_names_map_to_none() {
        for name in [
            "",
            "Toolpath",
            "cell_msgs::msg::Toolpath_",
            "cell_msgs::msg::dds_::Toolpath",
            "cell_msgs::idl::dds_::Toolpath_",
            "cell_msgs::msg::dds_::_",
            "a::msg::dds_::B_::C_",
            "DiscoveredWriterData",
        ] {
            assert_eq!(ros_type_name(name), None, "{name:?}");
        }
    }
}
