//! The rule for a test that needs a tool from outside the workspace.

use std::io::Write;

/// Whether the tests run under CI: `CI` set and not empty, `0` or `false`.
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !matches!(v.as_str(), "" | "0" | "false"))
}

/// Whether a test may run, given whether the outside tool it needs is here (`found`). When it
/// is not: under CI ([`under_ci`]) the test fails; elsewhere this prints one `skipped:` line
/// naming the test, the tool and how to install it (straight to stderr, past the test
/// harness's capture; `scripts/test` repeats these lines before its totals) and returns
/// `false`, and the caller returns early.
pub fn require_tool(tool: &str, found: Result<(), String>, how_to_install: &str) -> bool {
    let Err(why) = found else { return true };
    assert!(
        !under_ci(),
        "needs {tool}: {why}; CI must have it: {how_to_install}"
    );
    let thread = std::thread::current();
    let test = thread.name().filter(|n| *n != "main").unwrap_or("a test");
    // One write, so the line stays whole among the harness's own output.
    let line = format!("skipped: {test}: needs {tool}: {why}; install: {how_to_install}\n");
    let _ = std::io::stderr().write_all(line.as_bytes());
    false
}

/// [`require_tool`] for a command on the PATH: found when `command version_arg` runs and
/// exits 0 (e.g. `openssl version`, `openscad --version`).
pub fn require_command(command: &str, version_arg: &str, how_to_install: &str) -> bool {
    let found = std::process::Command::new(command)
        .arg(version_arg)
        .output()
        .map_err(|e| e.to_string())
        .and_then(|o| {
            o.status
                .success()
                .then_some(())
                .ok_or_else(|| format!("`{command} {version_arg}` failed"))
        });
    require_tool(command, found, how_to_install)
}
