//! LinuxCNC's RS274NGC interpreter, the independent reader of the emitted G-code.

use crate::require_tool;

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
