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

/// The ROS 2 name (`pkg/msg/Type`) of a DDS type name (`pkg::msg::dds_::Type_`): the inverse of
/// rosidl's DDS naming. `None` for a name not of that form.
pub fn ros_type_name(dds_type_name: &str) -> Option<String> {
    let mut parts = dds_type_name.split("::");
    let (package, kind, dds, type_name) =
        (parts.next()?, parts.next()?, parts.next()?, parts.next()?);
    let type_name = type_name.strip_suffix('_')?;
    let well_formed = parts.next().is_none()
        && dds == "dds_"
        && matches!(kind, "msg" | "srv" | "action")
        && !package.is_empty()
        && !type_name.is_empty();
    well_formed.then(|| format!("{package}/{kind}/{type_name}"))
}

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
