//! The one error type of this crate.

use std::path::PathBuf;

/// Everything that can go wrong while reading a launch file, planning its
/// nodes or starting them.
///
/// Errors about the file name the file as the caller gave it and the place in
/// it, e.g. `demo.launch.yaml: launch[2].node: unknown key "remaps"`.
/// A node that dies while running is not an error: it is reported in the
/// [`Summary`](crate::Summary) returned by [`supervise`](crate::supervise).
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    /// The launch file could not be read.
    #[error("{}: cannot read launch file: {source}", file.display())]
    Read {
        /// The launch file.
        file: PathBuf,
        /// Why reading failed.
        source: std::io::Error,
    },

    /// The launch file is not valid YAML.
    #[error("{}: not valid YAML: {source}", file.display())]
    Yaml {
        /// The launch file.
        file: PathBuf,
        /// The parser's message, with line and column.
        source: serde_norway::Error,
    },

    /// The launch file is valid YAML but not a valid launch description:
    /// an unknown key, a missing key, a wrong type, a bad substitution, ...
    #[error("{}: {at}: {message}", file.display())]
    Invalid {
        /// The launch file.
        file: PathBuf,
        /// Where in the file, e.g. `launch[2].node.param[0].value`.
        at: String,
        /// What is wrong there.
        message: String,
    },

    /// A launch argument given by the caller (`NAME:=VALUE`) is malformed or
    /// not declared by the launch file.
    #[error("launch argument {arg:?}: {message}")]
    Argument {
        /// The argument as the caller gave it.
        arg: String,
        /// What is wrong with it.
        message: String,
    },

    /// No program was found for a node's `exec`.
    #[error(
        "{}: {at}: node {node:?}: no executable found for exec {exec:?} of package {pkg:?}",
        file.display()
    )]
    Unresolved {
        /// The launch file.
        file: PathBuf,
        /// Where the node is declared, e.g. `launch[3].node`.
        at: String,
        /// The node's label (its name, or its exec).
        node: String,
        /// The node's `pkg`.
        pkg: String,
        /// The node's `exec`.
        exec: String,
    },

    /// The supervisor was configured wrongly (e.g. `stop_others_when` names
    /// a node that is not launched).
    #[error("launch options: {0}")]
    Options(String),

    /// A node's process could not be started. Nodes started before it have
    /// been stopped again.
    #[error("node {node}: cannot start {program:?}: {source}")]
    Spawn {
        /// The node's label.
        node: String,
        /// The program that failed to start.
        program: PathBuf,
        /// Why starting failed.
        source: std::io::Error,
    },

    /// Installing the Ctrl-C / SIGTERM handler failed.
    #[error("cannot install the signal handler for {signal}: {source}")]
    Signal {
        /// The signal's name.
        signal: &'static str,
        /// Why it failed.
        source: std::io::Error,
    },
}
