//! Shared by the bag tests: sample messages of every cell_msgs type, the Python venv and the
//! rule for a missing outside tool.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use cell_msgs::geometry_msgs::Point;
use cell_msgs::idl::{Array, BaseType, FieldType, Primitive};
use cell_msgs::registry;
use serde_json::{json, Map, Value};

/// A JSON sample of a registered type with a distinct value in every field and two elements in
/// every sequence (as `msgs/tests/drift.rs` builds them); `seed` varies the values.
pub fn sample(name: &str, seed: u64) -> Value {
    let mut n = seed * 10;
    message(name, &mut n)
}

fn message(name: &str, n: &mut u64) -> Value {
    let spec = registry::spec(name).unwrap_or_else(|e| panic!("{e}"));
    let fields = spec
        .fields
        .iter()
        .map(|f| (f.name.clone(), field(&f.ty, n)));
    Value::Object(fields.collect::<Map<_, _>>())
}

fn field(ty: &FieldType, n: &mut u64) -> Value {
    let len = match ty.array {
        None => return single(&ty.base, n),
        Some(Array::Fixed(k)) => k,
        Some(Array::Bounded(k)) => k.min(2),
        Some(Array::Unbounded) => 2,
    };
    Value::Array((0..len).map(|_| single(&ty.base, n)).collect())
}

fn single(base: &BaseType, n: &mut u64) -> Value {
    use Primitive::*;
    let prim = match base {
        BaseType::Message(name) => return message(name, n),
        BaseType::Primitive(p) => *p,
    };
    *n += 1;
    let (i, f) = (*n as i64, *n as f64);
    match prim {
        Bool => json!(n.is_multiple_of(2)),
        // rosbags 0.11 reads `byte` as int8 (ROS 1's meaning); ROS 2's is an octet. Values
        // below 128 read the same either way.
        Byte => json!(*n % 127 + 1),
        Char | Uint8 => json!(*n % 250 + 1),
        Int8 => json!(-(i % 120) - 1),
        Uint16 => json!(1_000 + *n),
        Int16 => json!(-1_000 - i),
        Uint32 => json!(70_000 + *n),
        Int32 => json!(-70_000 - i),
        Uint64 => json!(5_000_000_000 + *n),
        Int64 => json!(-5_000_000_000 - i),
        Float32 => json!((f as f32 + 0.5) as f64),
        Float64 => json!(f + 0.1),
        String { max_len } | WString { max_len } => {
            let s = format!("s{n}");
            json!(s[..s.len().min(max_len.unwrap_or(usize::MAX))])
        }
    }
}

/// A toolpath with known values the tests check field by field.
pub fn toolpath(job: &str) -> cell_msgs::Toolpath {
    let mut tp: cell_msgs::Toolpath = serde_json::from_value(sample(
        <cell_msgs::Toolpath as cell_msgs::RosMessage>::ROS_NAME,
        7,
    ))
    .unwrap();
    tp.job_id = job.into();
    tp.segments[0].points = vec![
        Point {
            x: 1.5,
            y: -2.25,
            z: 0.0,
        },
        Point {
            x: 100.0,
            y: 42.125,
            z: 3.0,
        },
    ];
    tp
}

/// Which Python runs the checker: `CELL_TEST_PYTHON` if set, else the venv
/// `CARGO_TARGET_TMPDIR/bag-venv` filled from `tests/py/requirements.txt` on first use
/// ([`cell_testkit::venv_python`]). `None` (the check is skipped, or fails under CI) when it
/// cannot be made.
pub fn python() -> Option<String> {
    cell_testkit::venv_python(
        Path::new(env!("CARGO_TARGET_TMPDIR")),
        "bag-venv",
        &py_dir().join("requirements.txt"),
        "mcap_ros2.decoder, rosbags.highlevel",
    )
    .map(|p| p.display().to_string())
}

pub fn py_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/py")
}

/// Runs the checker on a bag; one JSON value per output line. `None` (the test skips the
/// check) when the readers cannot be installed, see [`python`].
pub fn third_party_read(bag: &Path) -> Option<Vec<Value>> {
    let out = std::process::Command::new(python()?)
        .arg(py_dir().join("check_bag.py"))
        .arg(bag)
        .output()
        .expect("run check_bag.py");
    assert!(
        out.status.success(),
        "check_bag.py {} failed:\n{}",
        bag.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let lines = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    Some(lines)
}
