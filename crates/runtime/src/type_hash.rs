//! The REP-2011 type hash each DDS endpoint announces in its USER_DATA, as ROS 2 Jazzy does.
//!
//! The text is `typehash=RIHS01_<64 hex>;` (rmw_dds_common `encode_type_hash_for_user_data_qos`);
//! a Jazzy peer reads it back with `parse_type_hash_from_user_data` into the `topic_type_hash` of
//! its graph queries, and warns about every endpoint that announces none.
//!
//! The endpoint's DDS type name picks the hash. A topic of `pkg::msg::dds_::Type_` announces
//! `pkg/msg/Type`'s. Services and actions announce their messages' hashes, not the service's:
//! rmw_fastrtps_cpp (Jazzy, `rmw_service.cpp`, `rmw_client.cpp`) gives request endpoints
//! `request_typesupport`'s hash (`pkg/srv/Name_Request`) and reply endpoints
//! `response_typesupport`'s (`pkg/srv/Name_Response`). An action's endpoints follow from its
//! services and topics: `pkg/action/Name_SendGoal_Request`, `Name_GetResult_Response`,
//! `Name_FeedbackMessage`, `action_msgs/srv/CancelGoal_Request`, `action_msgs/msg/GoalStatusArray`.

use crate::graph::ros_type_name;

/// The USER_DATA announcing the type hash of an endpoint of `dds_type_name`:
/// `typehash=RIHS01_…;`. Empty (nothing announced, as Jazzy does for a type without a hash) when
/// the type is not one `cell_msgs` knows, with a debug line: a missing hash only costs the peer
/// a warning, so it never stops the node.
pub fn user_data(dds_type_name: &str) -> Vec<u8> {
    let Some(ros_name) = ros_type_name(dds_type_name) else {
        tracing::debug!("DDS type {dds_type_name} is not a ROS 2 type: no type hash announced");
        return Vec::new();
    };
    match cell_msgs::type_hash(&ros_name) {
        Ok(hash) => format!("typehash={hash};").into_bytes(),
        Err(e) => {
            tracing::debug!("{ros_name}: no type hash announced ({e})");
            Vec::new()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_types_announce_nothing() {
        assert!(user_data("nobody_msgs::msg::dds_::Nothing_").is_empty());
        assert!(user_data("not a type").is_empty());
    }

    #[test]
    fn known_types_announce_typehash_and_their_rihs01_hash() {
        let hash = cell_msgs::type_hash("cell_msgs/msg/Toolpath").expect("Toolpath has a hash");
        let announced = String::from_utf8(user_data("cell_msgs::msg::dds_::Toolpath_")).unwrap();
        assert_eq!(announced, format!("typehash={hash};"));
        // rosidl_stringify_type_hash: `RIHS01_` and 32 bytes in lower-case hex.
        let hex = announced
            .strip_prefix("typehash=RIHS01_")
            .and_then(|rest| rest.strip_suffix(';'))
            .unwrap_or_else(|| panic!("{announced:?}"));
        assert_eq!(hex.len(), 64, "{announced:?}");
        assert!(
            hex.bytes()
                .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)),
            "{announced:?}"
        );
    }
}
