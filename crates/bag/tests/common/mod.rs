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
        Byte | Char | Uint8 => json!(*n % 250 + 1),
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

/// Whether a test may run, given whether the outside tool it needs is here (`found`). When it
/// is not: under CI (`CI` set, not empty, `0` or `false`) the test fails; elsewhere this prints
/// one `skipped:` line naming the test, the tool and how to install it (straight to stderr, past
/// the test harness's capture; `scripts/test` repeats these lines before its totals) and returns
/// `false`, and the caller returns early. The same rule as the workspace's `tests/common`.
pub fn require_tool(tool: &str, found: Result<(), String>, how_to_install: &str) -> bool {
    use std::io::Write;
    let Err(why) = found else { return true };
    let ci = std::env::var("CI").is_ok_and(|v| !matches!(v.as_str(), "" | "0" | "false"));
    assert!(
        !ci,
        "needs {tool}: {why}; CI must have it: {how_to_install}"
    );
    let thread = std::thread::current();
    let test = thread.name().filter(|n| *n != "main").unwrap_or("a test");
    // One write, so the line stays whole among the harness's own output.
    let line = format!("skipped: {test}: needs {tool}: {why}; install: {how_to_install}\n");
    let _ = std::io::stderr().write_all(line.as_bytes());
    false
}

/// Which Python runs the checker: `CELL_TEST_PYTHON` if set, else a venv under the target
/// directory filled from `tests/py/requirements.txt` on first use. `None` when the venv cannot
/// be made (no Python 3 with venv, no PyPI), after [`require_tool`] said so (or failed the test
/// under CI). Made once per test binary: later calls get the first one's outcome.
pub fn python() -> Option<String> {
    use std::sync::Mutex;
    static MADE: Mutex<Option<Result<(), String>>> = Mutex::new(None);
    if let Ok(python) = std::env::var("CELL_TEST_PYTHON") {
        return Some(python);
    }
    let made = MADE
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .get_or_insert_with(make_venv)
        .clone();
    require_tool(
        "the PyPI packages of crates/bag/tests/py/requirements.txt",
        made,
        "Python 3 with venv (`scripts/test` installs python3-venv) and access to PyPI",
    )
    .then(|| venv_dir().join("bin/python").display().to_string())
}

fn venv_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bag-venv")
}

/// Creates (or completes) the venv of [`python`]: `Err` when Python, venv or pip fails.
fn make_venv() -> Result<(), String> {
    let venv = venv_dir();
    let python = venv.join("bin/python");
    let requirements = py_dir().join("requirements.txt");
    let stamp = venv.join("requirements.installed");
    let wanted = std::fs::read_to_string(&requirements).expect("requirements.txt");
    let ready = |python: &Path| {
        std::fs::read_to_string(&stamp).is_ok_and(|s| s == wanted)
            && std::process::Command::new(python)
                .args(["-c", "import mcap_ros2.decoder, rosbags.highlevel"])
                .status()
                .is_ok_and(|s| s.success())
    };
    if ready(&python) {
        return Ok(());
    }
    let run = |cmd: &mut std::process::Command| {
        let program = cmd.get_program().to_string_lossy().into_owned();
        let out = cmd.output().map_err(|e| format!("{program}: {e}"))?;
        if out.status.success() {
            return Ok(());
        }
        let stderr = String::from_utf8_lossy(&out.stderr);
        let last = stderr.lines().rfind(|l| !l.trim().is_empty()).unwrap_or("");
        let args: Vec<_> = cmd
            .get_args()
            .take(3)
            .map(|a| a.to_string_lossy())
            .collect();
        Err(format!(
            "`{program} {}` failed: {}",
            args.join(" "),
            last.trim()
        ))
    };
    run(std::process::Command::new("python3")
        .args(["-m", "venv"])
        .arg(&venv))?;
    run(std::process::Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "-r",
        ])
        .arg(&requirements))?;
    std::fs::write(&stamp, &wanted).expect("stamp");
    assert!(
        ready(&python),
        "{} cannot import the bag readers",
        python.display()
    );
    Ok(())
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
