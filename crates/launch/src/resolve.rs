//! Finding the program for each node and planning the processes to start.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use crate::file::LaunchFile;
use crate::LaunchError;

/// What a resolver returns for a node: the program to run and the arguments
/// that go before the node's own (e.g. `cell` + `["node", "monitor"]`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Program {
    /// The program to execute.
    pub program: PathBuf,
    /// Arguments placed before the node's command-line arguments.
    pub leading_args: Vec<String>,
}

impl Program {
    /// A program with no leading arguments.
    pub fn new(program: impl Into<PathBuf>) -> Self {
        Self {
            program: program.into(),
            leading_args: Vec::new(),
        }
    }
}

/// The default executable resolver: `exec` itself if it contains a `/`,
/// else a file named `exec` next to the current executable, else the first
/// one on `$PATH`. `pkg` is not used. Only executable regular files count.
pub fn default_resolver(_pkg: &str, exec: &str) -> Option<Program> {
    if exec.contains('/') {
        let path = Path::new(exec);
        return is_executable(path).then(|| Program::new(path));
    }
    let beside_us = std::env::current_exe()
        .ok()
        .and_then(|me| me.parent().map(|dir| dir.join(exec)));
    let on_path = std::env::var_os("PATH")
        .into_iter()
        .flat_map(|paths| std::env::split_paths(&paths).collect::<Vec<_>>())
        .filter(|dir| !dir.as_os_str().is_empty())
        .map(|dir| dir.join(exec));
    beside_us
        .into_iter()
        .chain(on_path)
        .find(|p| is_executable(p))
        .map(Program::new)
}

fn is_executable(path: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    std::fs::metadata(path).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

/// A process ready to be started by [`supervise`](crate::supervise).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlannedNode {
    /// Unique label: the node name, else its exec; `-2`, `-3`, ... is added
    /// to repeated labels. Output lines are prefixed with `[LABEL] `.
    pub label: String,
    /// What the launch file asked for (its `exec`), for messages.
    pub exec: String,
    /// The program to execute.
    pub program: PathBuf,
    /// All its arguments: the resolver's leading ones, then the node's.
    pub args: Vec<String>,
    /// Environment variables set on top of ours.
    pub env: Vec<(String, String)>,
}

impl PlannedNode {
    /// A node running `program` with `args`, labelled `label`, with no
    /// extra environment.
    pub fn new(label: impl Into<String>, program: impl Into<PathBuf>, args: &[&str]) -> Self {
        let program = program.into();
        Self {
            label: label.into(),
            exec: program.display().to_string(),
            program,
            args: args.iter().map(|a| a.to_string()).collect(),
            env: Vec::new(),
        }
    }

    /// The command line as a shell would need it, for messages.
    pub fn command_line(&self) -> String {
        let program = self.program.display().to_string();
        shell_words::join(
            std::iter::once(program.as_str()).chain(self.args.iter().map(String::as_str)),
        )
    }
}

impl LaunchFile {
    /// Resolves every node's executable with `resolve(pkg, exec)` and builds
    /// its command line. Fails on the first node that `resolve` cannot find,
    /// before anything is started.
    pub fn plan(
        &self,
        resolve: impl Fn(&str, &str) -> Option<Program>,
    ) -> Result<Vec<PlannedNode>, LaunchError> {
        let mut used = HashSet::new();
        let mut planned = Vec::with_capacity(self.nodes.len());
        for node in &self.nodes {
            let base = node.label();
            let mut label = base.to_string();
            let mut n = 1;
            while !used.insert(label.clone()) {
                n += 1;
                label = format!("{base}-{n}");
            }
            let Some(program) = resolve(&node.pkg, &node.exec) else {
                return Err(LaunchError::Unresolved {
                    file: self.path.clone(),
                    at: node.at.clone(),
                    node: label,
                    pkg: node.pkg.clone(),
                    exec: node.exec.clone(),
                });
            };
            let mut args = program.leading_args;
            args.extend(node.command_args());
            planned.push(PlannedNode {
                label,
                exec: node.exec.clone(),
                program: program.program,
                args,
                env: node.env.clone(),
            });
        }
        Ok(planned)
    }
}
