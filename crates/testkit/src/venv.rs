//! Python virtualenvs holding the PyPI peers the tests compare against (Cyclone DDS, the MCAP
//! and rosbag2 readers, Rerun's `rrd verify`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

use crate::require_tool;

/// A Python with `requirements` installed: `CELL_TEST_PYTHON` if set, else the virtualenv
/// `tmp_dir/<name>` (pass the test's `CARGO_TARGET_TMPDIR`), created and filled from PyPI on
/// first use and again whenever `requirements` changed or `import` fails in it, so
/// `cargo test` needs no manual set-up. `None` when the venv cannot be made (no Python 3 with
/// venv, no PyPI), after [`require_tool`] said so (or failed the test under CI). Made once per
/// test binary and name: later calls get the first one's outcome.
pub fn venv_python(
    tmp_dir: &Path,
    name: &str,
    requirements: &Path,
    import: &str,
) -> Option<PathBuf> {
    venv_python_with(tmp_dir, name, requirements, import, &[])
}

/// As [`venv_python`], with more `pip install` options, e.g. `--no-deps` for a package whose
/// declared dependencies (a GUI toolkit) the test does not need and cannot build.
pub fn venv_python_with(
    tmp_dir: &Path,
    name: &str,
    requirements: &Path,
    import: &str,
    pip_options: &[&str],
) -> Option<PathBuf> {
    static MADE: Mutex<Option<HashMap<PathBuf, Result<(), String>>>> = Mutex::new(None);
    if let Ok(python) = std::env::var("CELL_TEST_PYTHON") {
        return Some(PathBuf::from(python));
    }
    let venv = tmp_dir.join(name);
    let made = MADE
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .get_or_insert_with(HashMap::new)
        .entry(venv.clone())
        .or_insert_with(|| make_venv(&venv, requirements, import, pip_options))
        .clone();
    require_tool(
        &format!("the PyPI packages of {}", requirements.display()),
        made,
        "Python 3 with venv (`scripts/test` installs python3-venv) and access to PyPI",
    )
    .then(|| venv.join("bin/python"))
}

/// Creates (or completes) the venv of [`venv_python`]: `Err` when Python, venv or pip fails.
fn make_venv(
    venv: &Path,
    requirements: &Path,
    import: &str,
    pip_options: &[&str],
) -> Result<(), String> {
    let python = venv.join("bin/python");
    let stamp = venv.join("requirements.installed");
    let wanted = std::fs::read_to_string(requirements)
        .map_err(|e| format!("{}: {e}", requirements.display()))?;
    let ready = || {
        std::fs::read_to_string(&stamp).is_ok_and(|s| s == wanted)
            && Command::new(&python)
                .args(["-c", &format!("import {import}")])
                .status()
                .is_ok_and(|s| s.success())
    };
    if ready() {
        return Ok(());
    }
    run(Command::new("python3").args(["-m", "venv"]).arg(venv))?;
    run(Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
        ])
        .args(pip_options)
        .arg("-r")
        .arg(requirements))?;
    std::fs::write(&stamp, &wanted).map_err(|e| format!("{}: {e}", stamp.display()))?;
    assert!(
        ready(),
        "{} cannot import {import} after installing {}",
        python.display(),
        requirements.display()
    );
    Ok(())
}

/// Runs a set-up command: `Err` with the command and the last line it printed on failure.
fn run(cmd: &mut Command) -> Result<(), String> {
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
}
