//! The `MachineProgram` message and program files on disk.

use std::path::Path;

use cell_msgs::{builtin_interfaces::Time, std_msgs::Header, MachineProgram, ProgramFile};
use sha2::{Digest, Sha256};

use crate::EmitError;

/// A `MachineProgram` of `files` (the first is the entry point): line count over all files and
/// the lower-case hex SHA-256 of their texts concatenated in order.
pub fn machine_program(
    job_id: &str,
    dialect: &str,
    machine_profile: &str,
    files: Vec<ProgramFile>,
) -> MachineProgram {
    let mut hash = Sha256::new();
    let mut lines = 0usize;
    for f in &files {
        hash.update(f.text.as_bytes());
        lines += f.text.lines().count();
    }
    let sha256 = hash.finalize().iter().map(|b| format!("{b:02x}")).collect();
    MachineProgram {
        header: Header {
            stamp: Time::now(),
            frame_id: String::new(),
        },
        job_id: job_id.into(),
        dialect: dialect.into(),
        machine_profile: machine_profile.into(),
        files,
        line_count: u32::try_from(lines).unwrap_or(u32::MAX),
        sha256,
    }
}

/// Writes `text` to `path` atomically: a temporary file in the same directory, synced, then
/// renamed over `path`, so a reader never sees half a program.
///
/// # Errors
/// [`EmitError::Io`] naming the path.
pub fn write_atomically(path: &Path, text: &str) -> Result<(), EmitError> {
    use std::io::Write as _;
    let io = |e: std::io::Error| EmitError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map_or("program".into(), |n| n.to_string_lossy().into_owned());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(text.as_bytes())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksum_and_line_count_cover_every_file() {
        let file = |name: &str, text: &str| ProgramFile {
            name: name.into(),
            text: text.into(),
        };
        let p = machine_program(
            "j",
            "linuxcnc",
            "linuxcnc-xyuv",
            vec![file("a.ngc", "G0 X1\nM2\n"), file("b.ngc", "M2\n")],
        );
        assert_eq!(p.line_count, 3);
        // printf 'G0 X1\nM2\nM2\n' | sha256sum
        assert_eq!(
            p.sha256,
            "539d849c4951e5fb32a455510258bd49b216767cf1b06a76f3b0013eddb874da"
        );
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("job.ngc");
        write_atomically(&path, "old\n").unwrap();
        write_atomically(&path, "new\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new\n");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let e = write_atomically(&dir.path().join("missing/job.ngc"), "x").unwrap_err();
        assert!(e.to_string().contains("missing/job.ngc"), "{e}");
    }
}
