//! The rule for a test that needs a tool from outside the workspace (here LinuxCNC's
//! interpreter): it runs when the tool is here; when it is not, it fails under CI and says so and
//! skips elsewhere. The same rule as the workspace's `tests/common/mod.rs`.

/// Whether a test may run, given whether the outside tool it needs is here (`found`). When it
/// is not: under CI (`CI` set, not empty, `0` or `false`) the test fails; elsewhere this prints
/// one `skipped:` line naming the test, the tool and how to install it (straight to stderr, past
/// the test harness's capture; `scripts/test` repeats these lines before its totals) and returns
/// `false`, and the caller returns early.
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
