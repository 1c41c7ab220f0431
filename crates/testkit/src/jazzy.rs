//! A stock ROS 2 Jazzy from PyPI (the `ros-jazzy-*` wheels: rclpy on Fast DDS) with `cell_msgs`
//! built from `msgs/` by stock rosidl: the peer an integrator's own code would be.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;

use crate::require_tool;

/// What runs an rclpy script against the cell nodes: the venv's Python and the environment of
/// the built `cell_msgs` (`PYTHONPATH`, `LD_LIBRARY_PATH`, `AMENT_PREFIX_PATH`,
/// `RMW_IMPLEMENTATION=rmw_fastrtps_cpp`).
#[derive(Debug, Clone)]
pub struct JazzyEnv {
    /// The venv's Python, with rclpy.
    pub python: PathBuf,
    /// `cell_msgs`' install prefix (`share/cell_msgs/msg/<T>.json` carry the type hashes).
    pub install: PathBuf,
    /// Variables to set for the script, as `tests/ros2/build_msgs.sh` wrote them.
    pub vars: Vec<(String, String)>,
}

/// The Jazzy venv `tmp_dir/jazzy-venv` and `cell_msgs` built and installed under
/// `tmp_dir/jazzy-msgs` (pass the test's `CARGO_TARGET_TMPDIR`) by `tests/ros2/build_msgs.sh`,
/// which fills the venv from PyPI and rebuilds only when `msgs/` or the tooling changed. Made
/// once per test binary; `None` when it cannot be made, after [`require_tool`] said so (or failed
/// the test under CI).
pub fn jazzy_workspace(tmp_dir: &Path) -> Option<JazzyEnv> {
    static MADE: OnceLock<Result<JazzyEnv, String>> = OnceLock::new();
    let made = MADE.get_or_init(|| build(tmp_dir)).clone();
    let how = "Python 3 with venv, a C/C++ compiler and PyPI access (`scripts/test` installs the \
               first two); by hand: tests/ros2/build_msgs.sh VENV BUILD_DIR";
    match made {
        Ok(env) => Some(env),
        Err(why) => {
            require_tool(
                "a stock ROS 2 Jazzy (PyPI ros-jazzy-* wheels) with cell_msgs built",
                Err(why),
                how,
            );
            None
        }
    }
}

/// Runs `build_msgs.sh` (its progress and, on failure, its log tail go to stderr) and reads the
/// environment it wrote.
fn build(tmp_dir: &Path) -> Result<JazzyEnv, String> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/ros2/build_msgs.sh");
    let (venv, build) = (tmp_dir.join("jazzy-venv"), tmp_dir.join("jazzy-msgs"));
    let status = Command::new("bash")
        .arg(&script)
        .args([&venv, &build])
        .stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .status()
        .map_err(|e| format!("bash {}: {e}", script.display()))?;
    if !status.success() {
        return Err(format!(
            "{} {} {} failed ({status}; its log tail is above)",
            script.display(),
            venv.display(),
            build.display()
        ));
    }
    let env_file = build.join("jazzy.env");
    let text =
        std::fs::read_to_string(&env_file).map_err(|e| format!("{}: {e}", env_file.display()))?;
    let vars: Vec<(String, String)> = text
        .lines()
        .filter_map(|line| line.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let python = vars
        .iter()
        .find(|(k, _)| k == "PYTHON")
        .map(|(_, v)| PathBuf::from(v))
        .ok_or_else(|| format!("{}: no PYTHON line", env_file.display()))?;
    Ok(JazzyEnv {
        python,
        install: build.join("install"),
        vars,
    })
}
