//! `cell_testkit`: what the workspace's tests share when they need something from outside the
//! workspace (LinuxCNC's interpreter, a Python peer from PyPI, a stock ROS 2 Jazzy with `cell_msgs`
//! built, root for network namespaces).
//!
//! One rule for all of them ([`require_tool`]): a test whose tool is here runs; one whose tool
//! is missing fails under CI and, elsewhere, prints one `skipped:` line naming the tool and how
//! to install it and returns early. `scripts/test` installs the tools, so a fresh machine runs
//! everything. Only ever a dev-dependency.

mod interpreter;
mod jazzy;
mod tool;
mod venv;

pub use interpreter::{linuxcnc_interpreter, linuxcnc_interpreter_here};
pub use jazzy::{jazzy_workspace, JazzyEnv};
pub use tool::{require_command, require_tool, under_ci};
pub use venv::{venv_python, venv_python_with};
