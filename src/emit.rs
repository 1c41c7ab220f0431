//! `cell emit`: turn a toolpath file into a machine program on the spot, without DDS.
//!
//! Reads a `Toolpath` from JSON (as `cell hotwire` writes `toolpath.json`; `null` in a float
//! field reads as NaN, see [`cell_msgs::json`]), emits it with [`cell_emitter::emit_program`]
//! for `--profile`, and writes the program atomically:
//!
//! - `--out FILE`: the program's first file (the G-code file, or the RAPID main module) at
//!   FILE; any other files of the program (RAPID part modules and the `.pgf`) beside it, in
//!   FILE's directory, under their own names. Those files refer to each other by name (the
//!   `.pgf` lists the modules), so for a multi-file program FILE must carry the main file's
//!   own name (e.g. `out/WAAM_job42.mod`); another name is a usage error and nothing is
//!   written. Missing directories are created.
//! - `--out DIR/` (an existing directory, or a path ending in `/`): every file in DIR under
//!   its own name (`<job>.ngc` for G-code).
//!
//! Prints one line: job, profile, dialect, line count, SHA-256 and the files written.
//!
//! Exit status: 0 written; 64 a bad command line (including an unknown `--profile`, one that
//! takes no programs, or a `--toolpath` that cannot be read); 65 a toolpath file that is not a
//! toolpath or that the emitter refuses (NaN, feed ≤ 0, outside the machine's travel, …): the
//! message names the segment and point, and no file is created or changed; 1 the output could
//! not be written.

use std::{
    path::{Path, PathBuf},
    process::ExitCode,
};

use cell_msgs::Toolpath;
use cell_profiles::MachineProfile;
use clap::Args;

use crate::exit::{bad_data, usage};

/// `cell emit` options.
#[derive(Args, Debug)]
pub struct EmitArgs {
    /// Toolpath JSON file (e.g. the toolpath.json `cell hotwire` writes).
    #[arg(long, value_name = "FILE")]
    pub toolpath: PathBuf,
    /// Machine profile: a name under config/machines (linuxcnc-xyuv, grbl-xy, …) or a YAML
    /// file; it must have a gcode or a rapid section.
    #[arg(long, value_name = "NAME|FILE")]
    pub profile: String,
    /// Where the program goes: FILE for its first (main) file, any others beside it under
    /// their own names (a multi-file RAPID program's FILE must then carry the main module's
    /// own name, which its .pgf lists); or DIR/ (existing, or ending in /) for every file
    /// under its own name.
    #[arg(long, value_name = "FILE|DIR/")]
    pub out: PathBuf,
    /// Job id for the program's header and file names (default: the toolpath's job_id, else
    /// the --out file's stem).
    #[arg(long, value_name = "ID")]
    pub job_id: Option<String>,
}

/// A machine profile for `flag`, checked to take programs.
///
/// # Errors
/// One line naming `flag` and the profile: unknown, unreadable, invalid, or without a `gcode`
/// or `rapid` section.
pub fn program_profile(flag: &str, name: &str) -> Result<MachineProfile, String> {
    let profile = MachineProfile::resolve(name).map_err(|e| format!("{flag}: {e}"))?;
    if profile.gcode.is_none() && profile.rapid.is_none() {
        return Err(format!(
            "{flag}: machine profile {name:?} has no gcode or rapid section, so no program can be written for it"
        ));
    }
    Ok(profile)
}

/// Where `--out` puts the program: (directory for the files, path of the first file if it is
/// not `dir/<its name>`).
fn destination(out: &Path) -> (PathBuf, Option<PathBuf>) {
    let text = out.as_os_str().to_string_lossy();
    if out.is_dir() || text.ends_with('/') || text.ends_with(std::path::MAIN_SEPARATOR) {
        return (out.to_path_buf(), None);
    }
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    (dir.to_path_buf(), Some(out.to_path_buf()))
}

/// Runs `cell emit`.
pub fn run(a: EmitArgs) -> ExitCode {
    let profile = match program_profile("--profile", &a.profile) {
        Ok(p) => p,
        Err(e) => return usage(e),
    };
    let text = match std::fs::read_to_string(&a.toolpath) {
        Ok(t) => t,
        Err(e) => return usage(format!("--toolpath {}: {e}", a.toolpath.display())),
    };
    let toolpath: Toolpath = match cell_msgs::json::from_str(&text) {
        Ok(t) => t,
        Err(e) => {
            return bad_data(format!(
                "{}: {e} (expected a Toolpath as JSON)",
                a.toolpath.display()
            ))
        }
    };
    let (dir, main) = destination(&a.out);
    let job_id = a
        .job_id
        .clone()
        .filter(|j| !j.is_empty())
        .or_else(|| (!toolpath.job_id.is_empty()).then(|| toolpath.job_id.clone()))
        .or_else(|| {
            main.as_deref()
                .and_then(Path::file_stem)
                .map(|s| s.to_string_lossy().into_owned())
        })
        .unwrap_or_else(|| "program".into());
    let program = match cell_emitter::emit_program(&toolpath, &profile, &job_id) {
        Ok(p) => p,
        Err(e) => return bad_data(format!("{}: {e}", a.toolpath.display())),
    };
    if let (Some(path), [first, _, ..]) = (&main, program.files.as_slice()) {
        if path.file_name() != Some(std::ffi::OsStr::new(&first.name)) {
            return usage(format!(
                "--out {}: the program has {} files that refer to each other by name (main file \
                 {}); give a directory (--out DIR/) or --out DIR/{}",
                path.display(),
                program.files.len(),
                first.name,
                first.name
            ));
        }
    }
    if let Err(e) = std::fs::create_dir_all(&dir) {
        eprintln!("error: --out: cannot create {}: {e}", dir.display());
        return ExitCode::FAILURE;
    }
    let written = match cell_emitter::program::write_files(&program, &dir, main.as_deref()) {
        Ok(paths) => paths,
        Err(e) => {
            eprintln!("error: --out: {e}");
            return ExitCode::FAILURE;
        }
    };
    let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    println!(
        "cell emit: {}; wrote {}",
        cell_emitter::program::summary(&program),
        names.join(", ")
    );
    ExitCode::SUCCESS
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_is_a_file_or_a_directory() {
        assert_eq!(
            destination(Path::new("out/job.ngc")),
            (PathBuf::from("out"), Some(PathBuf::from("out/job.ngc")))
        );
        assert_eq!(
            destination(Path::new("job.ngc")),
            (PathBuf::from("."), Some(PathBuf::from("job.ngc")))
        );
        assert_eq!(
            destination(Path::new("out/")),
            (PathBuf::from("out/"), None)
        );
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(destination(dir.path()), (dir.path().to_path_buf(), None));
    }

    #[test]
    fn profiles_must_take_programs() {
        assert!(program_profile("--profile", "grbl-xy").is_ok());
        let e = program_profile("--profile", "mill_9000").unwrap_err();
        assert!(
            e.starts_with("--profile: ") && e.contains("mill_9000"),
            "{e}"
        );
    }
}
