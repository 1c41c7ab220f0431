//! Fuzz targets for every parser in cellsuite that reads outside input, and a mutational driver
//! that runs them on stable Rust.
//!
//! A target is a plain `fn(&[u8])` that hands the bytes to the real public entry points of one
//! family (the GRBL response parser, the link task, the G-code program parser, the simulator's
//! interpreter, DXF and JSON layouts, STL, airfoil `.dat`, bags, the dynamic CDR decoder and the
//! `.msg` parser, each YAML config type, the RWS answers) and uses what comes back. A target
//! must return normally for every input: an error is the right answer to bad input, a panic, a
//! hang or a huge allocation is a finding ([`run`]).
//!
//! Each target has seed inputs from the repository's real files (`config/`, `tests/data/`,
//! `msgs/`) or built by the library itself (bags, CDR), and a dictionary of tokens its format
//! uses. Found cases live in `crates/fuzz/corpus/<target>/<sha256>`; the tests replay them.
//!
//! The targets are plain functions so that libFuzzer (`cargo fuzz`, nightly only) could drive
//! them too; the driver here needs no nightly toolchain.

pub mod mutate;
pub mod run;
pub mod targets;

use std::path::{Path, PathBuf};

/// One fuzz target.
#[derive(Clone, Copy)]
pub struct Target {
    /// Name on the command line and the corpus folder (`grbl_response`).
    pub name: &'static str,
    /// What it feeds, in a few words.
    pub about: &'static str,
    /// Runs one input; returns normally for every input unless the code under test is wrong.
    pub run: fn(&[u8]),
    /// Seed inputs (real files of the repository, or built by the library under test).
    pub seeds: fn() -> Vec<Vec<u8>>,
    /// Tokens of the input format the mutator splices in.
    pub tokens: &'static [&'static str],
    /// Longest input the mutator makes, bytes.
    pub max_len: usize,
}

/// Every target, in a stable order.
pub fn targets() -> Vec<Target> {
    let mut all = Vec::new();
    all.extend(targets::grbl::targets());
    all.extend(targets::marlin::targets());
    all.extend(targets::layout::targets());
    all.extend(targets::mesh::targets());
    all.extend(targets::airfoil::targets());
    all.extend(targets::bag::targets());
    all.extend(targets::msgs::targets());
    all.extend(targets::config::targets());
    all.extend(targets::rws::targets());
    all
}

/// The target called `name`.
pub fn target(name: &str) -> Option<Target> {
    targets().into_iter().find(|t| t.name == name)
}

/// The repository's root (seed files are read from it).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Where the found cases of `target` are kept.
pub fn corpus_dir(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("corpus")
        .join(target)
}

/// The files under `dir` (relative to the repository root) whose names end in one of
/// `suffixes` (case-insensitive), at most `max_len` bytes each, sorted by name.
pub fn seed_files(dir: &str, suffixes: &[&str], max_len: usize) -> Vec<Vec<u8>> {
    let Ok(entries) = std::fs::read_dir(repo_root().join(dir)) else {
        return Vec::new();
    };
    let mut paths: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let name = p
                .file_name()
                .map(|n| n.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default();
            suffixes.iter().any(|s| name.ends_with(s))
        })
        .collect();
    paths.sort();
    paths
        .iter()
        .filter_map(|p| std::fs::read(p).ok())
        .filter(|b| b.len() <= max_len)
        .collect()
}

/// The input as text, invalid UTF-8 replaced (every input reaches the text parsers).
pub fn text(data: &[u8]) -> String {
    String::from_utf8_lossy(data).into_owned()
}

/// Removes this thread's scratch directories ([`scratch_dir`]).
pub fn remove_scratch() {
    let prefix = format!("cell_fuzz-{}-{}-", std::process::id(), thread_digits());
    for base in [Path::new("/dev/shm").to_path_buf(), std::env::temp_dir()] {
        let Ok(entries) = std::fs::read_dir(&base) else {
            continue;
        };
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with(&prefix) {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    }
}

/// A scratch directory on tmpfs (`/dev/shm` when there is one) for targets whose entry point
/// takes a path; one per process and thread, removed when the thread's run ends.
pub fn scratch_dir(what: &str) -> PathBuf {
    let base = if Path::new("/dev/shm").is_dir() {
        PathBuf::from("/dev/shm")
    } else {
        std::env::temp_dir()
    };
    let dir = base.join(format!(
        "cell_fuzz-{}-{}-{what}",
        std::process::id(),
        thread_digits()
    ));
    let _ = std::fs::create_dir_all(&dir);
    dir
}

/// This thread's id as digits (scratch directories are per thread).
fn thread_digits() -> String {
    format!("{:?}", std::thread::current().id())
        .chars()
        .filter(char::is_ascii_digit)
        .collect()
}
