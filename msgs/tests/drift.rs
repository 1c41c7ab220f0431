//! The drift test: every Rust message type must serialize to exactly the CDR layout its
//! `.msg` definition describes, with the same field names, order, widths and defaults.
//!
//! For each type in [`cell_msgs::for_each_message`], a JSON sample is generated from the
//! definition with a distinct non-default value in every field and two elements in every
//! sequence (nested too). It is deserialized into the Rust type (fails on missing or renamed
//! fields and on values that do not fit a narrower Rust type), serialized with `to_cdr`,
//! decoded with `dynamic::decode` from the definition alone, and compared with both the
//! generated sample and `serde_json::to_value` of the Rust value.

use cell_msgs::dynamic::{self, Schema};
use cell_msgs::geometry_msgs::Point;
use cell_msgs::idl::{Array, BaseType, FieldType, Primitive};
use cell_msgs::{for_each_message, from_cdr, registry, to_cdr, RosMessage};
use serde::{Deserialize, Serialize};
use serde_json::{json, Map, Value};

/// Generates sample values from definitions; a counter makes every scalar distinct.
#[derive(Default)]
struct Gen {
    n: u64,
}

impl Gen {
    fn message(&mut self, name: &str) -> Value {
        let spec = registry::spec(name).unwrap_or_else(|e| panic!("{e}"));
        let fields = spec
            .fields
            .iter()
            .map(|f| (f.name.clone(), self.field(&f.ty)));
        Value::Object(fields.collect::<Map<_, _>>())
    }

    fn field(&mut self, ty: &FieldType) -> Value {
        let len = match ty.array {
            None => return self.single(&ty.base),
            Some(Array::Fixed(n)) => n,
            Some(Array::Bounded(n)) => n.min(2),
            Some(Array::Unbounded) => 2,
        };
        Value::Array((0..len).map(|_| self.single(&ty.base)).collect())
    }

    /// Values are chosen to overflow the next narrower Rust type, so a too-narrow field fails.
    fn single(&mut self, base: &BaseType) -> Value {
        use Primitive::*;
        let prim = match base {
            BaseType::Message(name) => return self.message(name),
            BaseType::Primitive(p) => *p,
        };
        self.n += 1;
        let n = self.n;
        let (i, f) = (n as i64, n as f64);
        match prim {
            Bool => json!(true),
            Byte | Char | Uint8 => json!(n % 250 + 1),
            Int8 => json!(-(i % 120) - 1),
            Uint16 => json!(1_000 + n),
            Int16 => json!(-1_000 - i),
            Uint32 => json!(70_000 + n),
            Int32 => json!(-70_000 - i),
            Uint64 => json!(5_000_000_000 + n),
            Int64 => json!(-5_000_000_000 - i),
            Float32 => json!((f as f32 + 0.5) as f64),
            // Not representable as f32, so an f32 Rust field cannot reproduce it.
            Float64 => json!(f + 0.1),
            String { max_len } | WString { max_len } => {
                let s = format!("s{n}");
                json!(s[..s.len().min(max_len.unwrap_or(usize::MAX))])
            }
        }
    }
}

/// What `Default::default()` must serialize to: `.msg` defaults, else zeros and empties.
fn default_json(name: &str) -> Value {
    let spec = registry::spec(name).unwrap_or_else(|e| panic!("{e}"));
    let zero = |base: &BaseType| match base {
        BaseType::Message(m) => default_json(m),
        BaseType::Primitive(Primitive::Bool) => json!(false),
        BaseType::Primitive(Primitive::Float32 | Primitive::Float64) => json!(0.0),
        BaseType::Primitive(Primitive::String { .. } | Primitive::WString { .. }) => json!(""),
        BaseType::Primitive(_) => json!(0),
    };
    let fields = spec.fields.iter().map(|f| {
        let value = match (&f.default, f.ty.array) {
            (Some(d), _) => d.clone(),
            (None, None) => zero(&f.ty.base),
            (None, Some(Array::Fixed(n))) => {
                Value::Array((0..n).map(|_| zero(&f.ty.base)).collect())
            }
            (None, Some(_)) => json!([]),
        };
        (f.name.clone(), value)
    });
    Value::Object(fields.collect())
}

/// Checks one Rust type against its definition; `Err` describes the drift.
fn check<T: RosMessage + Default>() -> Result<(), String> {
    let name = T::ROS_NAME;
    let expected = Gen::default().message(name);
    let sample: T = serde_json::from_value(expected.clone())
        .map_err(|e| format!("sample does not fit: {e}"))?;
    let as_json = serde_json::to_value(&sample).map_err(|e| e.to_string())?;
    if as_json != expected {
        return Err(format!(
            "Rust value differs from the sample:\n{as_json}\nvs\n{expected}"
        ));
    }
    let bytes = to_cdr(&sample).map_err(|e| e.to_string())?;
    let decoded = dynamic::decode(name, &bytes)
        .map_err(|e| format!("CDR does not decode by the .msg: {e}"))?;
    if decoded != as_json {
        return Err(format!(
            "CDR decoded by the .msg differs:\n{decoded}\nvs\n{as_json}"
        ));
    }
    // The complete definition (as stored in bags) must describe the same layout.
    let schema =
        Schema::from_full_definition(name, &T::full_definition()).map_err(|e| e.to_string())?;
    if schema.decode(&bytes).map_err(|e| e.to_string())? != decoded {
        return Err("decoding via full_definition differs".into());
    }
    let back: T = from_cdr(&bytes).map_err(|e| e.to_string())?;
    if serde_json::to_value(&back).map_err(|e| e.to_string())? != as_json {
        return Err("from_cdr(to_cdr(x)) != x".into());
    }
    let default = serde_json::to_value(T::default()).map_err(|e| e.to_string())?;
    if default != default_json(name) {
        return Err(format!(
            "Default differs from the .msg defaults:\n{default}\nvs\n{}",
            default_json(name)
        ));
    }
    Ok(())
}

type Check = (&'static str, fn() -> Result<(), String>);

macro_rules! checks {
    ($($ty:ty => $name:literal),* $(,)?) => {
        vec![$((<$ty as RosMessage>::ROS_NAME, check::<$ty> as fn() -> Result<(), String>)),*]
    };
}

fn all_checks() -> Vec<Check> {
    for_each_message!(checks)
}

#[test]
fn every_rust_type_matches_its_definition() {
    let failures: Vec<String> = all_checks()
        .into_iter()
        .filter_map(|(name, check)| check().err().map(|e| format!("{name}: {e}")))
        .collect();
    assert!(failures.is_empty(), "drift:\n{}", failures.join("\n\n"));
}

#[test]
fn every_registered_message_has_a_rust_type() {
    let mut covered: Vec<&str> = all_checks().iter().map(|(name, _)| *name).collect();
    covered.sort_unstable();
    let mut registered = registry::list();
    registered.sort_unstable();
    assert_eq!(covered, registered);
}

#[test]
fn constants_match_their_definitions() {
    use cell_msgs::diagnostic_msgs::DiagnosticStatus as D;
    use cell_msgs::visualization_msgs::Marker as M;
    use cell_msgs::{
        ExecuteProgramResult as R, MachineCommand as C, MachineStatus as S, Toolpath as T,
        ToolpathSegment as G,
    };
    let rust: Vec<(&str, Vec<(&str, i64)>)> = vec![
        (
            T::ROS_NAME,
            vec![
                ("PROCESS_HOTWIRE", T::PROCESS_HOTWIRE.into()),
                ("PROCESS_SHEET_CUT", T::PROCESS_SHEET_CUT.into()),
                ("PROCESS_WAAM", T::PROCESS_WAAM.into()),
                ("PROCESS_EXTRUSION", T::PROCESS_EXTRUSION.into()),
                ("POWER_NONE", T::POWER_NONE.into()),
                ("POWER_WIRE_CURRENT_A", T::POWER_WIRE_CURRENT_A.into()),
                ("POWER_LASER_PERCENT", T::POWER_LASER_PERCENT.into()),
                ("POWER_ARC_ON", T::POWER_ARC_ON.into()),
                ("POWER_EXTRUSION_MM3_S", T::POWER_EXTRUSION_MM3_S.into()),
                ("POWER_WIRE_FEED_M_MIN", T::POWER_WIRE_FEED_M_MIN.into()),
            ],
        ),
        (
            G::ROS_NAME,
            vec![
                ("KIND_CUT", G::KIND_CUT.into()),
                ("KIND_TRAVEL", G::KIND_TRAVEL.into()),
                ("KIND_DEPOSIT", G::KIND_DEPOSIT.into()),
                ("KIND_LEAD", G::KIND_LEAD.into()),
            ],
        ),
        (
            S::ROS_NAME,
            vec![
                ("STATE_UNKNOWN", S::STATE_UNKNOWN.into()),
                ("STATE_DISCONNECTED", S::STATE_DISCONNECTED.into()),
                ("STATE_IDLE", S::STATE_IDLE.into()),
                ("STATE_RUNNING", S::STATE_RUNNING.into()),
                ("STATE_HOLD", S::STATE_HOLD.into()),
                ("STATE_ALARM", S::STATE_ALARM.into()),
                ("STATE_DONE", S::STATE_DONE.into()),
            ],
        ),
        (
            C::ROS_NAME,
            vec![
                ("COMMAND_HOLD", C::COMMAND_HOLD.into()),
                ("COMMAND_RESUME", C::COMMAND_RESUME.into()),
                ("COMMAND_ABORT", C::COMMAND_ABORT.into()),
                ("COMMAND_FEED_OVERRIDE", C::COMMAND_FEED_OVERRIDE.into()),
                (
                    "COMMAND_SPINDLE_OVERRIDE",
                    C::COMMAND_SPINDLE_OVERRIDE.into(),
                ),
            ],
        ),
        (
            M::ROS_NAME,
            vec![
                ("ARROW", M::ARROW.into()),
                ("CUBE", M::CUBE.into()),
                ("SPHERE", M::SPHERE.into()),
                ("CYLINDER", M::CYLINDER.into()),
                ("LINE_STRIP", M::LINE_STRIP.into()),
                ("LINE_LIST", M::LINE_LIST.into()),
                ("CUBE_LIST", M::CUBE_LIST.into()),
                ("SPHERE_LIST", M::SPHERE_LIST.into()),
                ("POINTS", M::POINTS.into()),
                ("TEXT_VIEW_FACING", M::TEXT_VIEW_FACING.into()),
                ("MESH_RESOURCE", M::MESH_RESOURCE.into()),
                ("TRIANGLE_LIST", M::TRIANGLE_LIST.into()),
                ("ARROW_STRIP", M::ARROW_STRIP.into()),
                ("ADD", M::ADD.into()),
                ("MODIFY", M::MODIFY.into()),
                ("DELETE", M::DELETE.into()),
                ("DELETEALL", M::DELETEALL.into()),
            ],
        ),
        (
            D::ROS_NAME,
            vec![
                ("OK", D::OK.into()),
                ("WARN", D::WARN.into()),
                ("ERROR", D::ERROR.into()),
                ("STALE", D::STALE.into()),
            ],
        ),
        (
            R::ROS_NAME,
            vec![
                ("OUTCOME_FINISHED", R::OUTCOME_FINISHED.into()),
                ("OUTCOME_ABORTED", R::OUTCOME_ABORTED.into()),
                ("OUTCOME_ALARM", R::OUTCOME_ALARM.into()),
                ("OUTCOME_REJECTED_LINE", R::OUTCOME_REJECTED_LINE.into()),
                ("OUTCOME_LINK_LOST", R::OUTCOME_LINK_LOST.into()),
                ("OUTCOME_REFUSED", R::OUTCOME_REFUSED.into()),
            ],
        ),
    ];
    for name in registry::list() {
        let spec = registry::spec(&name).unwrap_or_else(|e| panic!("{e}"));
        let from_msg: Vec<(String, Value)> = spec
            .constants
            .iter()
            .map(|c| (c.name.clone(), c.value.clone()))
            .collect();
        let from_rust: Vec<(String, Value)> = rust
            .iter()
            .filter(|(n, _)| *n == name)
            .flat_map(|(_, cs)| cs.iter().map(|(c, v)| (c.to_string(), json!(v))))
            .collect();
        assert_eq!(from_msg, from_rust, "constants of {name}");
    }
}

/// A Toolpath sample and its CDR, for the negative tests.
fn toolpath_sample() -> (Value, Vec<u8>) {
    let expected = Gen::default().message(cell_msgs::Toolpath::ROS_NAME);
    let sample: cell_msgs::Toolpath = serde_json::from_value(expected.clone()).expect("fits");
    (expected, to_cdr(&sample).expect("serializes"))
}

#[test]
fn altered_definitions_are_detected() {
    let (expected, bytes) = toolpath_sample();
    let full = cell_msgs::Toolpath::full_definition();
    let decode = |text: &str| {
        Schema::from_full_definition("cell_msgs/msg/Toolpath", text)
            .expect("parses")
            .decode(&bytes)
    };
    assert_eq!(decode(&full).expect("unaltered decodes"), expected);

    let widened = full.replace("uint32 layer", "uint64 layer");
    assert_ne!(widened, full);
    assert!(
        !matches!(decode(&widened), Ok(v) if v == expected),
        "widened field not detected"
    );

    let swapped = full
        .replace("float32[] bead_width_mm", "float32[] TMP")
        .replace("float32[] bead_height_mm", "float32[] bead_width_mm")
        .replace("float32[] TMP", "float32[] bead_height_mm");
    assert_ne!(swapped, full);
    assert!(
        !matches!(decode(&swapped), Ok(v) if v == expected),
        "swapped fields not detected"
    );

    let dropped = full.replace("float64 plane_separation_mm", "");
    assert!(
        decode(&dropped).is_err(),
        "a dropped field leaves trailing bytes"
    );
}

/// `geometry_msgs/msg/Point` with two fields swapped.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
struct SwappedPoint {
    x: f64,
    z: f64,
    y: f64,
}

impl RosMessage for SwappedPoint {
    const ROS_NAME: &'static str = "geometry_msgs/msg/Point";
}

/// `builtin_interfaces/msg/Time` with `nanosec` too narrow.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
struct NarrowTime {
    sec: i32,
    nanosec: u16,
}

impl RosMessage for NarrowTime {
    const ROS_NAME: &'static str = "builtin_interfaces/msg/Time";
}

/// `builtin_interfaces/msg/Time` with `nanosec` too wide (u64 still holds the sample).
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
struct WideTime {
    sec: i32,
    nanosec: u64,
}

impl RosMessage for WideTime {
    const ROS_NAME: &'static str = "builtin_interfaces/msg/Time";
}

/// `cell_msgs/msg/ProgramFile` missing its last field.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
struct ShortProgramFile {
    name: String,
}

impl RosMessage for ShortProgramFile {
    const ROS_NAME: &'static str = "cell_msgs/msg/ProgramFile";
}

/// `geometry_msgs/msg/Quaternion` whose Default ignores the `.msg` default `w = 1`.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
struct ZeroQuaternion {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

impl RosMessage for ZeroQuaternion {
    const ROS_NAME: &'static str = "geometry_msgs/msg/Quaternion";
}

#[test]
fn drifted_rust_types_fail_the_check() {
    let results = [
        ("swapped fields", check::<SwappedPoint>()),
        ("narrow field", check::<NarrowTime>()),
        ("wide field", check::<WideTime>()),
        ("missing field", check::<ShortProgramFile>()),
        ("wrong default", check::<ZeroQuaternion>()),
    ];
    for (what, result) in results {
        assert!(result.is_err(), "{what} not detected");
    }
    assert!(check::<Point>().is_ok());
}
