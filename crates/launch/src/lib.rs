//! `cell launch`: start the nodes of a ROS 2 YAML launch file and supervise
//! them.
//!
//! Three steps, each usable on its own:
//!
//! 1. [`LaunchFile::load`] reads a launch file in ROS 2's YAML syntax (see
//!    [`mod@file`] for what is supported), applying the caller's launch
//!    arguments and every substitution.
//! 2. [`LaunchFile::plan`] finds each node's program with a resolver (such
//!    as [`default_resolver`]) and builds its ROS 2 command line
//!    ([`NodeSpec::command_args`]), failing before anything is started.
//! 3. [`supervise`] starts the processes, forwards their output with a
//!    `[NAME] ` prefix, stops everything if a node dies at start or fails,
//!    forwards Ctrl-C, and returns a [`Summary`] whose
//!    [`exit_code`](Summary::exit_code) the command should exit with.
//!
//! ```no_run
//! # async fn run() -> Result<i32, cell_launch::LaunchError> {
//! use cell_launch::{default_resolver, supervise, LaunchFile, SupervisorOptions};
//! let file = LaunchFile::load("demo.launch.yaml", &[("domain".into(), "3".into())])?;
//! let summary = supervise(file.plan(default_resolver)?, SupervisorOptions::default()).await?;
//! Ok(summary.exit_code())
//! # }
//! ```
//!
//! # Substitutions
//!
//! Any string value may contain `$(var NAME)` (an `arg` or `let` declared
//! above), `$(env NAME)` (an error if unset), `$(env NAME DEFAULT)`,
//! `$(optenv NAME [DEFAULT])` (empty if unset) and `$(dirname)` (the launch
//! file's directory). Arguments inside `$(...)` may be quoted. Anything else
//! is an error naming the file and the key.
//!
//! A parameter `value` that is a literal string stays a string; one that
//! contains a substitution is read as YAML after substitution, as in ROS 2,
//! so `value: $(var rate)` with `rate` = `2.5` is the float 2.5.

#![warn(missing_docs)]

mod cmdline;
mod error;
pub mod file;
mod param;
mod resolve;
mod subst;
mod supervise;

pub use error::LaunchError;
pub use file::{parse_launch_arg, ArgDecl, LaunchFile, NodeSpec, Param, Remap};
pub use param::ParamValue;
pub use resolve::{default_resolver, PlannedNode, Program};
pub use supervise::{
    supervise, NodeReport, Outcome, OutputLine, StopOthersWhen, Stream, Summary, SupervisorOptions,
};
pub use tokio_util::sync::CancellationToken;
