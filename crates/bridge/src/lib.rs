//! `cell_bridge`: where cellsuite meets the machines, the controller layer of the
//! `machine_bridge` node (`nodes/machine_bridge`). It streams `MachineProgram`s to
//! GRBL-class controllers ([`cell_grbl`]) and ABB robots ([`cell_rws`]), follows them to the
//! end, publishes each controller's `MachineStatus` and acts on hold, resume and abort at once.
//!
//! - [`config`]: controller files (`config/controllers/*.yaml`), one per controller.
//! - [`grbl`]: a GRBL controller: link keeping, streaming, resume after link drops, status.
//! - [`rws`]: an ABB controller: upload, load, start, follow, stop with heat off.
//! - [`marlin`]: a Marlin printer: ping-pong streaming with line numbers and checksums, the
//!   heat off and read back after every stop.
//! - [`controller`]: one face for both, and which controller a goal goes to.
//! - [`arming`]: what needs the bridge armed, the armed state and its local-only arm service.
//!
//! Free of ROS: the node (action `execute_program`, `machine_status`, `machine_command`) is the
//! ROS adapter over [`controller::Controller`].

#![warn(missing_docs)]

pub mod arming;
pub mod config;
pub mod controller;
pub mod grbl;
pub mod marlin;
pub mod program_fit;
pub mod rws;
