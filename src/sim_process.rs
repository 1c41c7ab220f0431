//! What the simulator binaries (`grbl_sim`, `marlin_sim`) share as processes: a stable name for
//! their pty, and the executed-line log and link cleanup when Ctrl-C ends them.

use std::path::Path;

/// Points the symlink `link` at the simulator's `pty` (replacing an old link, never another
/// file), so a sender can be given a fixed path; `program` prefixes the line it prints.
pub fn link_pty(program: &str, pty: &Path, link: &Path) -> Result<(), String> {
    if std::fs::symlink_metadata(link).is_ok_and(|m| m.file_type().is_symlink()) {
        std::fs::remove_file(link).map_err(|e| format!("{}: {e}", link.display()))?;
    }
    std::os::unix::fs::symlink(pty, link)
        .map_err(|e| format!("cannot link {}: {e}", link.display()))?;
    println!("{program}: linked {} -> {}", link.display(), pty.display());
    Ok(())
}

/// At exit: writes the executed lines to `log` (one per line) and removes the pty `link`.
pub fn finish(executed: &[String], log: Option<&Path>, link: Option<&Path>) -> Result<(), String> {
    if let Some(path) = log {
        let mut text = executed.join("\n");
        text.push('\n');
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if let Some(link) = link {
        let _ = std::fs::remove_file(link);
    }
    Ok(())
}
