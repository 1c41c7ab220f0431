//! REP-2011 type hashes, version 1 (`RIHS01_…`), of the registered interfaces, equal to what
//! stock rosidl computes (`rosidl_generator_type_description.calculate_type_hash`, ROS 2 Jazzy)
//! and what Jazzy endpoints announce in their USER_DATA (`typehash=RIHS01_…;`).
//!
//! The hash is the SHA-256 of the [`TypeDescription`]'s JSON exactly as rosidl writes it for
//! hashing: keys in the message's field order, no default values, `", "` between items and
//! `": "` after keys (Python `json.dumps(separators=(', ', ': '))`), no other whitespace.
//! rosidl also escapes non-ASCII (`ensure_ascii`); names are ASCII here, as the parser checks.

use std::io;

use sha2::{Digest, Sha256};

use crate::registry::RegistryError;
use crate::type_description::{type_description, TypeDescription};

/// A REP-2011 type hash, version 1: the SHA-256 of a type description's canonical JSON.
/// Displays as `RIHS01_<64 lowercase hex>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TypeHash(pub [u8; 32]);

impl std::fmt::Display for TypeHash {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("RIHS01_")?;
        self.0.iter().try_for_each(|b| write!(f, "{b:02x}"))
    }
}

/// The type hash of `ros_name`: any name [`type_description`] knows, e.g.
/// `cell_msgs/msg/Toolpath`, `cell_msgs/srv/EmitProgram`, `cell_msgs/srv/EmitProgram_Request`,
/// `cell_msgs/action/PlanHotwire`, `cell_msgs/action/PlanHotwire_SendGoal_Request`,
/// `action_msgs/srv/CancelGoal_Request`.
pub fn type_hash(ros_name: &str) -> Result<TypeHash, RegistryError> {
    Ok(hash_of(&type_description(ros_name)?))
}

/// The hash of a type description.
pub fn hash_of(description: &TypeDescription) -> TypeHash {
    TypeHash(Sha256::digest(hashed_json(description)).into())
}

/// The JSON text rosidl hashes for a type description.
pub fn hashed_json(description: &TypeDescription) -> String {
    let mut out = Vec::new();
    let mut serializer = serde_json::Serializer::with_formatter(&mut out, PythonJsonFormatter);
    // Only strings and integers in plain structs: serializing cannot fail.
    if let Err(e) = serde::Serialize::serialize(description, &mut serializer) {
        unreachable!("a type description always serializes: {e}");
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Python `json.dumps(separators=(', ', ': '))` layout.
struct PythonJsonFormatter;

impl serde_json::ser::Formatter for PythonJsonFormatter {
    fn begin_array_value<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> io::Result<()> {
        if first {
            Ok(())
        } else {
            w.write_all(b", ")
        }
    }

    fn begin_object_key<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> io::Result<()> {
        if first {
            Ok(())
        } else {
            w.write_all(b", ")
        }
    }

    fn begin_object_value<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        w.write_all(b": ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_layout_is_pythons() {
        let description = type_description("builtin_interfaces/msg/Time").expect("registered");
        assert_eq!(
            hashed_json(&description),
            r#"{"type_description": {"type_name": "builtin_interfaces/msg/Time", "fields": [{"name": "sec", "type": {"type_id": 6, "capacity": 0, "string_capacity": 0, "nested_type_name": ""}}, {"name": "nanosec", "type": {"type_id": 7, "capacity": 0, "string_capacity": 0, "nested_type_name": ""}}]}, "referenced_type_descriptions": []}"#
        );
    }

    #[test]
    fn displays_as_rihs01() {
        let mut bytes = [0u8; 32];
        bytes[0] = 0xab;
        bytes[31] = 0x01;
        let text = TypeHash(bytes).to_string();
        assert_eq!(text.len(), 7 + 64);
        assert!(
            text.starts_with("RIHS01_ab00") && text.ends_with("0001"),
            "{text}"
        );
    }
}
