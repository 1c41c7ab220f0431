//! Files named in goals and requests: only regular files under the node's data directories,
//! size-capped, read without blocking, and errors that never quote the file (issue 23, item 3).
//!
//! A goal's `machine_profile`, `root_airfoil`, `layout_file`, `stl_file`, `wing_spec_file` or
//! `process_file` may be a path. A remote caller must not make the node read `/etc/passwd`
//! (and answer with its lines), `/dev/zero` (and run out of memory) or a FIFO (and hang), so
//! every node that opens such a path goes through [`DataDirs`]:
//!
//! 1. A relative path is looked up as given (against the working directory, as before) and
//!    then under each data directory, in order; the first that exists is the file.
//! 2. It is canonicalised (symlinks followed, `..` gone) and must lie under a canonicalised
//!    data directory; a path that does not exist and is not under one reads "outside" too, so
//!    the answer tells nothing about files elsewhere.
//! 3. Its metadata, before opening, must say regular file, at most `max_bytes` long.
//! 4. It is opened with `O_NONBLOCK | O_NOFOLLOW` (a FIFO swapped in meanwhile cannot hang the
//!    open), checked again on the open handle, and read through `take(max_bytes + 1)`, so a
//!    file that grows after the check cannot exhaust memory.
//!
//! Errors ([`DataFileError`]) name the path as the caller gave it and the reason; parse errors
//! of what was read go through [`cell_config::without_content`] before they reach a remote
//! caller ([`DataDirs::machine_profile`] does this for profiles).
//!
//! The directories come from the node's `data_dirs` parameter (default [`DEFAULT_DATA_DIRS`]:
//! `config`, relative to the working directory, where the shipped profiles, airfoils,
//! sheets and wings live) and the cap from `max_file_mib` (default [`DEFAULT_MAX_FILE_MIB`]).
//! Names of embedded items (`grbl-xy`, `s1223`) read no file and are not affected.

use std::{
    fmt,
    fs::{Metadata, OpenOptions},
    io::Read,
    os::unix::fs::{FileTypeExt, OpenOptionsExt},
    path::{Component, Path, PathBuf},
};

use cell_profiles::MachineProfile;

/// Blanks the quoted values of a reader's error message (re-exported for nodes).
pub use cell_config::without_content;

/// The data directories when a node's `data_dirs` parameter is not set.
pub const DEFAULT_DATA_DIRS: &[&str] = &["config"];

/// The size cap when a node's `max_file_mib` parameter is not set (STL parts can be large).
pub const DEFAULT_MAX_FILE_MIB: u64 = 64;

/// The default `data_dirs` parameter value.
pub fn default_data_dirs() -> Vec<String> {
    DEFAULT_DATA_DIRS.iter().map(|d| (*d).to_owned()).collect()
}

/// Where a node may read files named by remote callers, and how much (module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DataDirs {
    dirs: Vec<PathBuf>,
    max_bytes: u64,
}

/// Why a named file is not read. Written as `PATH: reason`; never holds the file's contents.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DataFileError {
    /// Not under any data directory (after following symlinks), or absent and not under one.
    #[error("{path}: outside the node's data directories ({dirs}; parameter `data_dirs`)")]
    Outside {
        /// The path as given.
        path: String,
        /// The data directories, comma-separated.
        dirs: String,
    },
    /// Under a data directory, but no such file.
    #[error("{path}: no such file in the node's data directories ({dirs})")]
    NotFound {
        /// The path as given.
        path: String,
        /// The data directories, comma-separated.
        dirs: String,
    },
    /// A directory, FIFO, socket or device.
    #[error("{path}: not a regular file (a {kind})")]
    NotRegular {
        /// The path as given.
        path: String,
        /// What it is instead.
        kind: &'static str,
    },
    /// Longer than the cap.
    #[error("{path}: larger than the node's {max_bytes}-byte limit (parameter `max_file_mib`)")]
    TooLarge {
        /// The path as given.
        path: String,
        /// The cap.
        max_bytes: u64,
    },
    /// Opening or reading failed (the kind of error only).
    #[error("{path}: cannot read ({kind})")]
    Unreadable {
        /// The path as given.
        path: String,
        /// The I/O error's kind.
        kind: String,
    },
    /// Not UTF-8 text where text was expected.
    #[error("{path}: not UTF-8 text")]
    NotText {
        /// The path as given.
        path: String,
    },
}

/// A file read through [`DataDirs::read`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DataFile {
    /// The path as the caller gave it (what errors name).
    pub name: String,
    /// The canonical path that was read.
    pub path: PathBuf,
    /// Its contents (at most the cap).
    pub bytes: Vec<u8>,
}

impl DataFile {
    /// The contents as text.
    ///
    /// # Errors
    /// [`DataFileError::NotText`] (without the bytes).
    pub fn text(&self) -> Result<&str, DataFileError> {
        std::str::from_utf8(&self.bytes).map_err(|_| DataFileError::NotText {
            path: self.name.clone(),
        })
    }
}

impl DataDirs {
    /// `dirs` (relative ones against the working directory at each look-up) and a cap of
    /// `max_bytes`.
    pub fn new<D: Into<PathBuf>>(dirs: impl IntoIterator<Item = D>, max_bytes: u64) -> Self {
        Self {
            dirs: dirs.into_iter().map(Into::into).collect(),
            max_bytes,
        }
    }

    /// From a node's `data_dirs` and `max_file_mib` parameters.
    pub fn from_params(dirs: &[String], max_file_mib: u64) -> Self {
        Self::new(dirs, max_file_mib.saturating_mul(1024 * 1024))
    }

    /// The cap, bytes.
    pub fn max_bytes(&self) -> u64 {
        self.max_bytes
    }

    /// The canonical path of `name`, a regular file under a data directory within the cap,
    /// for a library that opens it itself (it should open it at once).
    ///
    /// # Errors
    /// [`DataFileError`]: outside, not found, not a regular file, too large, unreadable.
    pub fn check(&self, name: &str) -> Result<PathBuf, DataFileError> {
        let path = self.locate(name)?;
        let meta = std::fs::metadata(&path).map_err(|e| self.io_error(name, &e))?;
        self.check_metadata(name, &meta)?;
        Ok(path)
    }

    /// Reads `name` (see the module docs for every check).
    ///
    /// # Errors
    /// As [`DataDirs::check`].
    pub fn read(&self, name: &str) -> Result<DataFile, DataFileError> {
        let path = self.check(name)?;
        let file = OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NONBLOCK | libc::O_NOFOLLOW)
            .open(&path)
            .map_err(|e| self.io_error(name, &e))?;
        let meta = file.metadata().map_err(|e| self.io_error(name, &e))?;
        self.check_metadata(name, &meta)?;
        let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
        file.take(self.max_bytes.saturating_add(1))
            .read_to_end(&mut bytes)
            .map_err(|e| self.io_error(name, &e))?;
        if bytes.len() as u64 > self.max_bytes {
            return Err(self.too_large(name));
        }
        Ok(DataFile {
            name: name.to_owned(),
            path,
            bytes,
        })
    }

    /// A machine profile named by a goal or request (`field` names it in errors): an embedded
    /// name as [`MachineProfile::resolve`], a path read with [`DataDirs::read`]. Errors are one
    /// line, `FIELD: …`, without the file's contents.
    ///
    /// # Errors
    /// An unknown name, a refused path, a profile that does not parse or validate.
    pub fn machine_profile(&self, field: &str, name: &str) -> Result<MachineProfile, String> {
        if !MachineProfile::names_a_file(name) {
            return MachineProfile::resolve(name).map_err(|e| format!("{field}: {e}"));
        }
        let file = self.read(name).map_err(|e| format!("{field}: {e}"))?;
        let text = file.text().map_err(|e| format!("{field}: {e}"))?;
        MachineProfile::from_yaml_str(text, name).map_err(|e| {
            let message = match e {
                cell_profiles::ProfileError::Parse(p) => p.without_content().to_string(),
                other => cell_config::without_content(&other.to_string()),
            };
            format!("{field}: {message}")
        })
    }

    /// The existing canonical path `name` means, under a data directory.
    fn locate(&self, name: &str) -> Result<PathBuf, DataFileError> {
        let given = Path::new(name);
        let cwd = std::env::current_dir().unwrap_or_default();
        let mut candidates = vec![cwd.join(given)];
        if given.is_relative() {
            candidates.extend(self.dirs.iter().map(|d| cwd.join(d).join(given)));
        }
        let roots = self.roots(&cwd);
        let mut exists = false;
        for candidate in &candidates {
            if std::fs::symlink_metadata(candidate).is_err() {
                continue;
            }
            exists = true;
            // A dangling link, or a path that leads out, does not count.
            if let Ok(real) = std::fs::canonicalize(candidate) {
                if roots.iter().any(|r| real.starts_with(r)) {
                    return Ok(real);
                }
            }
        }
        // Absent: "not found" only where the caller may look.
        let inside = !exists
            && candidates
                .iter()
                .any(|c| roots.iter().any(|r| lexical(c).starts_with(r)));
        Err(if inside {
            DataFileError::NotFound {
                path: name.into(),
                dirs: self.dirs_text(),
            }
        } else {
            self.outside(name)
        })
    }

    /// The data directories that exist, canonical (and, for the absent-file check, lexical).
    fn roots(&self, cwd: &Path) -> Vec<PathBuf> {
        self.dirs
            .iter()
            .filter_map(|d| std::fs::canonicalize(cwd.join(d)).ok())
            .filter(|d| d.is_dir())
            .collect()
    }

    fn check_metadata(&self, name: &str, meta: &Metadata) -> Result<(), DataFileError> {
        if !meta.is_file() {
            return Err(DataFileError::NotRegular {
                path: name.into(),
                kind: kind_of(meta),
            });
        }
        if meta.len() > self.max_bytes {
            return Err(self.too_large(name));
        }
        Ok(())
    }

    fn too_large(&self, name: &str) -> DataFileError {
        DataFileError::TooLarge {
            path: name.into(),
            max_bytes: self.max_bytes,
        }
    }

    fn outside(&self, name: &str) -> DataFileError {
        DataFileError::Outside {
            path: name.into(),
            dirs: self.dirs_text(),
        }
    }

    fn io_error(&self, name: &str, e: &std::io::Error) -> DataFileError {
        DataFileError::Unreadable {
            path: name.into(),
            kind: e.kind().to_string(),
        }
    }

    fn dirs_text(&self) -> String {
        if self.dirs.is_empty() {
            return "none".into();
        }
        self.dirs
            .iter()
            .map(|d| d.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl fmt::Display for DataDirs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} (≤ {} bytes a file)",
            self.dirs_text(),
            self.max_bytes
        )
    }
}

/// `path` with `.` and `..` resolved by name (no file system access).
fn lexical(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// What a non-regular file is, for the error.
fn kind_of(meta: &Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        "directory"
    } else if t.is_fifo() {
        "FIFO"
    } else if t.is_socket() {
        "socket"
    } else if t.is_char_device() {
        "character device"
    } else if t.is_block_device() {
        "block device"
    } else {
        "special file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dirs(root: &Path, max_bytes: u64) -> DataDirs {
        DataDirs::new([root.join("data")], max_bytes)
    }

    fn setup() -> tempfile::TempDir {
        let t = tempfile::tempdir().unwrap();
        std::fs::create_dir(t.path().join("data")).unwrap();
        std::fs::write(t.path().join("data/ok.yaml"), "name: x\n").unwrap();
        std::fs::write(t.path().join("secret.txt"), "root:x:0:0:root\n").unwrap();
        t
    }

    #[test]
    fn a_regular_file_inside_is_read_by_absolute_and_relative_name() {
        let t = setup();
        let d = dirs(t.path(), 1024);
        let abs = t.path().join("data/ok.yaml");
        let f = d.read(abs.to_str().unwrap()).unwrap();
        assert_eq!(f.text().unwrap(), "name: x\n");
        assert_eq!(f.path, std::fs::canonicalize(&abs).unwrap());
        // Relative: looked up under the data directory.
        assert_eq!(d.read("ok.yaml").unwrap().bytes, b"name: x\n");
        assert_eq!(d.check("ok.yaml").unwrap(), f.path);
    }

    #[test]
    fn paths_outside_are_refused_whether_or_not_they_exist() {
        let t = setup();
        let d = dirs(t.path(), 1024);
        for name in [
            "/etc/passwd".to_string(),
            t.path().join("secret.txt").display().to_string(),
            t.path().join("data/../secret.txt").display().to_string(),
            "../secret.txt".into(),
            "/nonexistent/x.yaml".into(),
        ] {
            let e = d.read(&name).unwrap_err();
            assert!(matches!(e, DataFileError::Outside { .. }), "{name}: {e}");
            assert!(
                e.to_string().starts_with(&format!("{name}: outside")),
                "{e}"
            );
        }
        let e = d.read("missing.yaml").unwrap_err();
        assert!(matches!(e, DataFileError::NotFound { .. }), "{e}");
    }

    #[test]
    fn a_symlink_leading_out_is_outside_one_staying_in_is_followed() {
        let t = setup();
        let d = dirs(t.path(), 1024);
        std::os::unix::fs::symlink(t.path().join("secret.txt"), t.path().join("data/out.yaml"))
            .unwrap();
        std::os::unix::fs::symlink("/etc/passwd", t.path().join("data/passwd")).unwrap();
        std::os::unix::fs::symlink("ok.yaml", t.path().join("data/in.yaml")).unwrap();
        for name in ["out.yaml", "passwd"] {
            let e = d.read(name).unwrap_err();
            assert!(matches!(e, DataFileError::Outside { .. }), "{e}");
        }
        assert_eq!(d.read("in.yaml").unwrap().bytes, b"name: x\n");
    }

    #[test]
    fn devices_fifos_and_directories_are_not_opened() {
        let t = setup();
        let fifo = t.path().join("data/pipe.yaml");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo only creates a file.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let d = dirs(t.path(), 1024);
        let started = std::time::Instant::now();
        let e = d.read("pipe.yaml").unwrap_err();
        assert_eq!(
            e,
            DataFileError::NotRegular {
                path: "pipe.yaml".into(),
                kind: "FIFO"
            }
        );
        assert!(started.elapsed() < std::time::Duration::from_secs(1));
        std::fs::create_dir(t.path().join("data/sub")).unwrap();
        let e = d.read("sub").unwrap_err();
        assert!(
            e.to_string().ends_with("not a regular file (a directory)"),
            "{e}"
        );
        // /dev/zero is a device, and outside the data directories either way.
        let dev = DataDirs::new(["/dev"], 1024);
        let e = dev.read("/dev/zero").unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
    }

    #[test]
    fn files_over_the_cap_are_refused() {
        let t = setup();
        std::fs::write(t.path().join("data/big.stl"), vec![b'x'; 2048]).unwrap();
        let d = dirs(t.path(), 1024);
        let e = d.read("big.stl").unwrap_err();
        assert_eq!(
            e.to_string(),
            "big.stl: larger than the node's 1024-byte limit (parameter `max_file_mib`)"
        );
        assert!(d.check("big.stl").is_err());
        assert_eq!(DataDirs::from_params(&[], 2).max_bytes(), 2 * 1024 * 1024);
    }

    #[test]
    fn profiles_by_name_need_no_file_and_bad_files_are_not_quoted() {
        let t = setup();
        let d = dirs(t.path(), 1 << 20);
        assert_eq!(
            d.machine_profile("machine_profile", "grbl-xy")
                .unwrap()
                .name,
            "grbl-xy"
        );
        std::fs::write(
            t.path().join("data/passwd.yaml"),
            "root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin\n",
        )
        .unwrap();
        let e = d
            .machine_profile("machine_profile", "passwd.yaml")
            .unwrap_err();
        assert!(e.starts_with("machine_profile: passwd.yaml:1: "), "{e}");
        assert!(!e.contains("root") && !e.contains("daemon"), "{e}");
        std::fs::write(t.path().join("data/keys.yaml"), "root: 1\n").unwrap();
        let e = d
            .machine_profile("machine_profile", "keys.yaml")
            .unwrap_err();
        assert!(!e.contains("root"), "{e}");
        let e = d
            .machine_profile("machine_profile", "/etc/passwd")
            .unwrap_err();
        assert!(e.contains("outside") && !e.contains("root:"), "{e}");
    }
}
