//! Shared helpers for the in-process integration tests: fresh domains, loopback nodes.
#![allow(dead_code)] // each test binary uses a different subset

use std::{
    sync::atomic::{AtomicU16, Ordering},
    time::Duration,
};

use cell_runtime::{CellNode, FastPathMode, NodeSetup};

static NEXT: AtomicU16 = AtomicU16::new(0);

/// A DDS domain no other running test uses: test binaries run one at a time, tests inside one
/// binary get consecutive ids from a per-process base.
pub fn fresh_domain() -> u16 {
    let base = 100 + (std::process::id() % 8) as u16 * 16;
    base + NEXT.fetch_add(1, Ordering::Relaxed) % 16
}

/// A node on `domain`, DDS on loopback only, with or without the shared-memory fast path.
pub fn node(name: &str, domain: u16, fast_path: bool) -> CellNode {
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = if fast_path {
        FastPathMode::Auto
    } else {
        FastPathMode::Off
    };
    CellNode::new(setup).expect("node comes up")
}

/// Generous bound for discovery and delivery on a loaded 2-core machine.
pub const DELIVERY_TIMEOUT: Duration = Duration::from_secs(30);

/// Awaits `f`, failing the test if it takes longer than [`DELIVERY_TIMEOUT`].
pub async fn within<F: std::future::Future>(f: F) -> F::Output {
    tokio::time::timeout(DELIVERY_TIMEOUT, f)
        .await
        .expect("in time")
}

/// Waits until `client` has discovered the action server `name`, failing the test if that takes
/// longer than [`DELIVERY_TIMEOUT`]. Send goals only after this (goals sent earlier are lost).
pub async fn discover_action_server(client: &CellNode, name: &str) {
    assert!(
        client.wait_for_action_server(name, DELIVERY_TIMEOUT).await,
        "action server {name} never discovered"
    );
}

/// What an action client saw of one accepted goal.
pub struct FollowedGoal<F, R> {
    /// The first feedback message.
    pub first_feedback: F,
    /// The goal's final status.
    pub status: cell_runtime::action::GoalStatusEnum,
    /// The goal's result.
    pub result: R,
}

/// Sends `goal`; if the server accepts it, waits for its first feedback and then its result.
/// `None` when the server rejects the goal.
pub async fn follow_goal<G, R, F>(
    client: &cell_runtime::action::ActionClient<G, R, F>,
    goal: G,
) -> Option<FollowedGoal<F, R>>
where
    G: ros2_client::Message + Clone + 'static,
    R: ros2_client::Message + Clone + 'static,
    F: ros2_client::Message + 'static,
{
    use futures::StreamExt;
    let (goal_id, response) = within(client.async_send_goal(goal)).await.expect("sent");
    if !response.accepted {
        return None;
    }
    let feedback = client.feedback_stream(goal_id);
    let mut feedback = std::pin::pin!(feedback);
    let first_feedback = within(feedback.next())
        .await
        .expect("stream")
        .expect("feedback");
    // One request held open for the whole goal: the server answers only the first request it
    // reads once the goal has ended, so a retry while the goal runs loses the answer (see
    // `request_result`). Goals in these tests run for seconds, on a loaded machine tens.
    let (status, result) = cell_runtime::action::request_result(
        client,
        goal_id,
        3 * DELIVERY_TIMEOUT,
        3 * DELIVERY_TIMEOUT,
    )
    .await
    .expect("result");
    Some(FollowedGoal {
        first_feedback,
        status,
        result,
    })
}

/// Whether a test may run, given whether the outside tool it needs is here (`found`). When it
/// is not: under CI (`CI` set, not empty, `0` or `false`) the test fails; elsewhere this prints
/// one `skipped:` line naming the test, the tool and how to install it (straight to stderr, past
/// the test harness's capture; `scripts/test` repeats these lines before its totals) and returns
/// `false`, and the caller returns early. The one rule for every test that needs a tool from
/// outside the workspace.
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

/// LinuxCNC's RS274NGC interpreter as `tests/interp/canon.py` runs it: `/usr/bin/rs274` and the
/// `gcode` module of Debian's `/usr/bin/python3` (what `tests/interp/install.sh` checks).
pub fn linuxcnc_interpreter() -> Result<(), String> {
    if !std::path::Path::new("/usr/bin/rs274").is_file() {
        return Err("no /usr/bin/rs274".into());
    }
    let import = std::process::Command::new("/usr/bin/python3")
        .args(["-c", "import gcode"])
        .output()
        .map_err(|e| format!("/usr/bin/python3: {e}"))?;
    if !import.status.success() {
        return Err("/usr/bin/python3 cannot import gcode".into());
    }
    Ok(())
}

/// Whether LinuxCNC's interpreter is here, by [`require_tool`]'s rule.
pub fn linuxcnc_interpreter_here() -> bool {
    require_tool(
        "LinuxCNC's RS274NGC interpreter",
        linuxcnc_interpreter(),
        "`scripts/test` (or, as root, `bash tests/interp/install.sh`: Debian's linuxcnc-uspace)",
    )
}

/// A Python with `requirements` installed: `CELL_TEST_PYTHON` if set, else a virtualenv
/// `CARGO_TARGET_TMPDIR/<name>` created and filled from PyPI on first use (when `import` fails
/// in it), so `cargo test` needs no manual set-up. `None` when the venv cannot be made (no
/// Python 3 with venv, no PyPI), after [`require_tool`] said so (or failed the test under CI).
/// Made once per test binary: later calls get the first one's outcome.
pub fn venv_python(name: &str, requirements: &str, import: &str) -> Option<std::path::PathBuf> {
    use std::collections::HashMap;
    use std::path::PathBuf;
    use std::sync::Mutex;
    static MADE: Mutex<Option<HashMap<String, Result<(), String>>>> = Mutex::new(None);
    if let Ok(python) = std::env::var("CELL_TEST_PYTHON") {
        return Some(PathBuf::from(python));
    }
    let made = MADE
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .get_or_insert_with(HashMap::new)
        .entry(name.to_string())
        .or_insert_with(|| make_venv(name, requirements, import))
        .clone();
    require_tool(
        &format!("the PyPI packages of {requirements}"),
        made,
        "Python 3 with venv (`scripts/test` installs python3-venv) and access to PyPI",
    )
    .then(|| {
        PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
            .join(name)
            .join("bin/python")
    })
}

/// Creates (or completes) the venv of [`venv_python`]: `Err` when Python, venv or pip fails.
fn make_venv(name: &str, requirements: &str, import: &str) -> Result<(), String> {
    use std::path::PathBuf;
    use std::process::Command;
    let venv = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let python = venv.join("bin/python");
    let ready = |python: &std::path::Path| {
        Command::new(python)
            .args(["-c", &format!("import {import}")])
            .status()
            .is_ok_and(|s| s.success())
    };
    if ready(&python) {
        return Ok(());
    }
    let requirements = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(requirements);
    let run = |cmd: &mut Command| {
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
    run(Command::new("python3").args(["-m", "venv"]).arg(&venv))?;
    run(Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "-r",
        ])
        .arg(&requirements))?;
    assert!(
        ready(&python),
        "{} cannot import {import} after installing {}",
        python.display(),
        requirements.display()
    );
    Ok(())
}

/// Every message of an `.rrd` file, decoded by Rerun's own decoder, as one debug string to
/// search for entity paths; fails the test if the file is not a valid recording.
pub fn rrd_dump(path: &std::path::Path) -> String {
    let reader = std::io::BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    );
    let messages: Vec<_> = re_log_encoding::DecoderApp::decode_eager(reader)
        .unwrap_or_else(|e| panic!("{} is not a valid .rrd: {e}", path.display()))
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    format!("{messages:?}")
}

/// Checks an `.rrd` file with Rerun's own tool, `rerun rrd verify` from the PyPI rerun-sdk of
/// the crate's version (a venv made on first use); panics with its complaint. Skips the check
/// (see [`venv_python`]) when the venv cannot be made.
pub fn rrd_verify(path: &std::path::Path) {
    let Some(python) = venv_python("rerun-venv", "tests/rerun/requirements.txt", "rerun") else {
        return;
    };
    let verify = std::process::Command::new(&python)
        .args(["-m", "rerun", "rrd", "verify"])
        .arg(path)
        .env("RERUN_ANALYTICS", "false")
        .output()
        .expect("run rerun");
    assert!(
        verify.status.success(),
        "rerun rrd verify {}: {}",
        path.display(),
        String::from_utf8_lossy(&verify.stderr)
    );
}
