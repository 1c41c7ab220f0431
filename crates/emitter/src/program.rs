//! The `MachineProgram` message and program files on disk.

use std::path::{Path, PathBuf};

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

/// One line about a program: job, profile, dialect, line count and SHA-256, e.g. `job wing-1:
/// profile grbl-xy, dialect grbl, 214 lines, sha256 3f2a…` (the whole hash).
pub fn summary(program: &MachineProgram) -> String {
    format!(
        "job {}: profile {}, dialect {}, {} lines, sha256 {}",
        program.job_id,
        program.machine_profile,
        program.dialect,
        program.line_count,
        program.sha256
    )
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

/// Writes every file of `program` atomically (see [`write_atomically`]): the first (the entry
/// point) at `main` when given, every other file, and the first when `main` is `None`, as
/// `dir/<its name>`. Returns the paths written, in file order.
///
/// Every name is checked before anything is written: a name that is not a plain file name
/// (empty, `.`, `..`, or with a path separator) writes nothing. Each file is replaced
/// atomically; if writing a later file fails, the earlier ones stay written.
///
/// # Errors
/// [`EmitError::Io`] naming the file.
pub fn write_files(
    program: &MachineProgram,
    dir: &Path,
    main: Option<&Path>,
) -> Result<Vec<PathBuf>, EmitError> {
    let mut paths = Vec::with_capacity(program.files.len());
    for (i, file) in program.files.iter().enumerate() {
        let plain = !file.name.is_empty()
            && file.name != "."
            && file.name != ".."
            && !file.name.contains(['/', '\\', '\0']);
        if !plain {
            return Err(EmitError::Io {
                path: file.name.clone(),
                message: "program file name is not a plain file name".into(),
            });
        }
        paths.push(match (i, main) {
            (0, Some(main)) => main.to_path_buf(),
            _ => dir.join(&file.name),
        });
    }
    for (path, file) in paths.iter().zip(&program.files) {
        write_atomically(path, &file.text)?;
    }
    Ok(paths)
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

    #[test]
    fn program_files_go_to_main_and_beside_it() {
        let dir = tempfile::tempdir().unwrap();
        let file = |name: &str, text: &str| ProgramFile {
            name: name.into(),
            text: text.into(),
        };
        let p = machine_program(
            "j",
            "rapid",
            "robot",
            vec![
                file("Main.mod", "MODULE Main\n"),
                file("j.pgf", "<Program/>\n"),
            ],
        );
        let main = dir.path().join("wall.mod");
        let written = write_files(&p, dir.path(), Some(&main)).unwrap();
        assert_eq!(written, [main.clone(), dir.path().join("j.pgf")]);
        assert_eq!(std::fs::read_to_string(&main).unwrap(), "MODULE Main\n");
        let written = write_files(&p, dir.path(), None).unwrap();
        assert_eq!(written[0], dir.path().join("Main.mod"));

        for bad in ["", "..", "../x.ngc", "a/b.ngc"] {
            let q = machine_program(
                "j",
                "grbl",
                "m",
                vec![file("ok.ngc", "M2\n"), file(bad, "x")],
            );
            let e = write_files(&q, dir.path(), Some(&dir.path().join("new.ngc"))).unwrap_err();
            assert!(e.to_string().contains("not a plain file name"), "{e}");
            assert!(
                !dir.path().join("new.ngc").exists(),
                "nothing written for {bad:?}"
            );
        }
    }
}
