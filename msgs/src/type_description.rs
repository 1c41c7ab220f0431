//! REP-2011 type descriptions (`type_description_interfaces/msg/TypeDescription`) of the
//! registered interfaces, built as stock rosidl does (`rosidl_generator_type_description`,
//! ROS 2 Jazzy), from which [`crate::type_hash()`] computes the `RIHS01_` hash.
//!
//! A description is the type's own fields plus every type it references, directly or not,
//! sorted by name. Besides the registered messages it covers what rosidl derives from `.srv`
//! and `.action` files (`rosidl_parser.definition.Service` and `Action`):
//! - a service `pkg/srv/S`: fields `request_message`, `response_message`, `event_message`;
//!   `S_Event` is `service_msgs/msg/ServiceEventInfo info`, `S_Request[<=1] request`,
//!   `S_Response[<=1] response`;
//! - an action `pkg/action/A`: fields `goal`, `result`, `feedback`, `send_goal_service`,
//!   `get_result_service`, `feedback_message`; the services `A_SendGoal` (request: UUID
//!   `goal_id`, `A_Goal goal`; response: `bool accepted`, `builtin_interfaces/msg/Time stamp`)
//!   and `A_GetResult` (request: `goal_id`; response: `int8 status`, `A_Result result`), and
//!   the message `A_FeedbackMessage` (`goal_id`, `A_Feedback feedback`), where `goal_id` is a
//!   `unique_identifier_msgs/msg/UUID`.
//!
//! Constants are not part of a description; a message without fields gets rosidl's
//! `uint8 structure_needs_at_least_one_member`. Field defaults are left out: rosidl drops them
//! before hashing, so they never change a hash.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::idl::{Array, BaseType, MessageSpec, Primitive};
use crate::registry::{self, RegistryError};

/// The member rosidl adds to an empty structure (`rosidl_parser.definition`).
const EMPTY_STRUCTURE_MEMBER: &str = "structure_needs_at_least_one_member";

/// A field's type (`type_description_interfaces/msg/FieldType`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct FieldType {
    /// `FieldType.FIELD_TYPE_*`: the element type's id, plus 48 for a fixed array, 96 for a
    /// bounded sequence, 144 for an unbounded sequence.
    pub type_id: u8,
    /// Length of a fixed array or bound of a bounded sequence, else 0.
    pub capacity: u64,
    /// Bound of a bounded string (element), else 0.
    pub string_capacity: u64,
    /// `pkg/kind/Type` of a nested type (element), else empty.
    pub nested_type_name: String,
}

/// A field (`type_description_interfaces/msg/Field`, without `default_value`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Field {
    /// Field name.
    pub name: String,
    /// Field type.
    #[serde(rename = "type")]
    pub ty: FieldType,
}

/// One type's own description (`IndividualTypeDescription`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct IndividualTypeDescription {
    /// `pkg/kind/Type`, e.g. `cell_msgs/action/PlanHotwire_SendGoal_Request`.
    pub type_name: String,
    /// Fields in definition order.
    pub fields: Vec<Field>,
}

/// A type and everything it references (`TypeDescription`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct TypeDescription {
    /// The type itself.
    pub type_description: IndividualTypeDescription,
    /// Every type it references, directly or not, each once, sorted by name.
    pub referenced_type_descriptions: Vec<IndividualTypeDescription>,
}

/// The full type description of `ros_name`: a registered message (`cell_msgs/msg/Toolpath`,
/// `cell_msgs/srv/EmitProgram_Request`), a service or action (`cell_msgs/srv/EmitProgram`,
/// `cell_msgs/action/PlanHotwire`) or a type rosidl derives from one (`…/EmitProgram_Event`,
/// `…/PlanHotwire_SendGoal`, `…/PlanHotwire_SendGoal_Request`, `…/PlanHotwire_FeedbackMessage`).
pub fn type_description(ros_name: &str) -> Result<TypeDescription, RegistryError> {
    let top = individual(ros_name)?;
    let mut referenced = BTreeMap::new();
    let mut pending: Vec<String> = nested_names(&top);
    while let Some(name) = pending.pop() {
        if referenced.contains_key(&name) {
            continue;
        }
        let description = individual(&name)?;
        pending.extend(nested_names(&description));
        referenced.insert(name, description);
    }
    Ok(TypeDescription {
        type_description: top,
        referenced_type_descriptions: referenced.into_values().collect(),
    })
}

fn nested_names(description: &IndividualTypeDescription) -> Vec<String> {
    description
        .fields
        .iter()
        .map(|f| f.ty.nested_type_name.clone())
        .filter(|name| !name.is_empty())
        .collect()
}

/// One type's own description: from the registry, or derived from a service or action.
fn individual(ros_name: &str) -> Result<IndividualTypeDescription, RegistryError> {
    let fields = match registry::spec(ros_name) {
        Ok(spec) => message_fields(&spec),
        Err(RegistryError::Unknown(_)) => {
            derived_fields(ros_name).ok_or_else(|| RegistryError::Unknown(ros_name.to_owned()))?
        }
        Err(e) => return Err(e),
    };
    Ok(IndividualTypeDescription {
        type_name: ros_name.to_owned(),
        fields,
    })
}

fn message_fields(spec: &MessageSpec) -> Vec<Field> {
    if spec.fields.is_empty() {
        return vec![field(
            EMPTY_STRUCTURE_MEMBER,
            &BaseType::Primitive(Primitive::Uint8),
            None,
        )];
    }
    spec.fields
        .iter()
        .map(|f| field(&f.name, &f.ty.base, f.ty.array))
        .collect()
}

/// Fields of the types rosidl derives from services and actions (see the module docs);
/// `None` when `ros_name` is none of them.
fn derived_fields(ros_name: &str) -> Option<Vec<Field>> {
    let nested = |name: &str, ty: String| field(name, &BaseType::Message(ty), None);
    let uuid = || nested("goal_id", "unique_identifier_msgs/msg/UUID".into());
    if is_service(ros_name) {
        return Some(vec![
            nested("request_message", format!("{ros_name}_Request")),
            nested("response_message", format!("{ros_name}_Response")),
            nested("event_message", format!("{ros_name}_Event")),
        ]);
    }
    if is_action(ros_name) {
        return Some(vec![
            nested("goal", format!("{ros_name}_Goal")),
            nested("result", format!("{ros_name}_Result")),
            nested("feedback", format!("{ros_name}_Feedback")),
            nested("send_goal_service", format!("{ros_name}_SendGoal")),
            nested("get_result_service", format!("{ros_name}_GetResult")),
            nested("feedback_message", format!("{ros_name}_FeedbackMessage")),
        ]);
    }
    if let Some(service) = ros_name.strip_suffix("_Event").filter(|s| is_service(s)) {
        let at_most_one =
            |name: &str, ty: String| field(name, &BaseType::Message(ty), Some(Array::Bounded(1)));
        return Some(vec![
            nested("info", "service_msgs/msg/ServiceEventInfo".into()),
            at_most_one("request", format!("{service}_Request")),
            at_most_one("response", format!("{service}_Response")),
        ]);
    }
    let action_part = |suffix: &str| ros_name.strip_suffix(suffix).filter(|a| is_action(a));
    if let Some(action) = action_part("_SendGoal_Request") {
        return Some(vec![uuid(), nested("goal", format!("{action}_Goal"))]);
    }
    if action_part("_SendGoal_Response").is_some() {
        return Some(vec![
            field("accepted", &BaseType::Primitive(Primitive::Bool), None),
            nested("stamp", "builtin_interfaces/msg/Time".into()),
        ]);
    }
    if action_part("_GetResult_Request").is_some() {
        return Some(vec![uuid()]);
    }
    if let Some(action) = action_part("_GetResult_Response") {
        return Some(vec![
            field("status", &BaseType::Primitive(Primitive::Int8), None),
            nested("result", format!("{action}_Result")),
        ]);
    }
    if let Some(action) = action_part("_FeedbackMessage") {
        return Some(vec![
            uuid(),
            nested("feedback", format!("{action}_Feedback")),
        ]);
    }
    None
}

/// The middle part of `pkg/kind/Type`.
fn kind(ros_name: &str) -> Option<&str> {
    let mut parts = ros_name.split('/');
    let (_, kind, _) = (parts.next()?, parts.next()?, parts.next()?);
    parts.next().is_none().then_some(kind)
}

/// A `.srv` file's service, or an action's `_SendGoal` or `_GetResult` service.
fn is_service(ros_name: &str) -> bool {
    match kind(ros_name) {
        Some("srv") => registry::definition(&format!("{ros_name}_Request")).is_some(),
        Some("action") => ros_name
            .strip_suffix("_SendGoal")
            .or_else(|| ros_name.strip_suffix("_GetResult"))
            .is_some_and(is_action),
        _ => false,
    }
}

/// An `.action` file's action.
fn is_action(ros_name: &str) -> bool {
    kind(ros_name) == Some("action") && registry::definition(&format!("{ros_name}_Goal")).is_some()
}

fn field(name: &str, base: &BaseType, array: Option<Array>) -> Field {
    let (element_id, string_capacity, nested_type_name) = match base {
        BaseType::Message(name) => (1, 0, name.clone()),
        BaseType::Primitive(p) => {
            let (id, bound) = primitive_id(*p);
            (id, bound.unwrap_or(0) as u64, String::new())
        }
    };
    let (offset, capacity) = match array {
        None => (0, 0),
        Some(Array::Fixed(n)) => (48, n as u64),
        Some(Array::Bounded(n)) => (96, n as u64),
        Some(Array::Unbounded) => (144, 0),
    };
    Field {
        name: name.to_owned(),
        ty: FieldType {
            type_id: element_id + offset,
            capacity,
            string_capacity,
            nested_type_name,
        },
    }
}

/// `FieldType.FIELD_TYPE_*` of a primitive (type_description_interfaces, Jazzy) and a string's
/// bound. `.msg` `char` is IDL `uint8` and `byte` is `octet` (rosidl_adapter `MSG_TYPE_TO_IDL`).
fn primitive_id(primitive: Primitive) -> (u8, Option<usize>) {
    use Primitive::*;
    match primitive {
        Int8 => (2, None),
        Uint8 | Char => (3, None),
        Int16 => (4, None),
        Uint16 => (5, None),
        Int32 => (6, None),
        Uint32 => (7, None),
        Int64 => (8, None),
        Uint64 => (9, None),
        Float32 => (10, None),
        Float64 => (11, None),
        Bool => (15, None),
        Byte => (16, None),
        String { max_len: None } => (17, None),
        WString { max_len: None } => (18, None),
        String { max_len } => (21, max_len),
        WString { max_len } => (22, max_len),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_types_follow_rosidl_ids() {
        let text = "char c\nbyte[4] b\nstring<=8[<=3] names\nwstring w\nToolpath[] paths\n";
        let spec = crate::idl::parse_message("cell_msgs/msg/T", text).expect("parses");
        let fields = message_fields(&spec);
        let ids: Vec<(u8, u64, u64, &str)> = fields
            .iter()
            .map(|f| {
                let t = &f.ty;
                (
                    t.type_id,
                    t.capacity,
                    t.string_capacity,
                    t.nested_type_name.as_str(),
                )
            })
            .collect();
        assert_eq!(
            ids,
            [
                (3, 0, 0, ""),
                (16 + 48, 4, 0, ""),
                (21 + 96, 3, 8, ""),
                (18, 0, 0, ""),
                (1 + 144, 0, 0, "cell_msgs/msg/Toolpath"),
            ]
        );
    }

    #[test]
    fn derived_types_and_unknown_names() {
        let send_goal = individual("cell_msgs/action/PlanHotwire_SendGoal_Request").expect("known");
        let names: Vec<&str> = send_goal.fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["goal_id", "goal"]);
        let event = individual("cell_msgs/srv/EmitProgram_Event").expect("known");
        assert_eq!(event.fields[1].ty.type_id, 97);
        for unknown in [
            "cell_msgs/msg/Nope",
            "cell_msgs/srv/Toolpath_Event",
            "cell_msgs/msg/PlanHotwire_SendGoal",
            "cell_msgs/action/Nope_FeedbackMessage",
            "not a name",
        ] {
            assert_eq!(
                type_description(unknown),
                Err(RegistryError::Unknown(unknown.into())),
                "{unknown}"
            );
        }
    }
}
