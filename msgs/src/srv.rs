//! Parts of the `cell_msgs/srv/*` services (request, response), mirroring `msgs/srv/*.srv`
//! section by section.

use serde::{Deserialize, Serialize};

use crate::{MachineCommand, MachineProgram, Toolpath};

/// Request of `EmitProgram`: turn a toolpath into a machine program for one machine profile.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct EmitProgramRequest {
    /// The toolpath to emit.
    pub toolpath: Toolpath,
    /// Machine profile: a name under config/machines (e.g. "grbl-xy") or a path to a profile
    /// YAML on the emitter's host; empty = the node's `machine_profile` parameter.
    pub machine_profile: String,
    /// Job id: names the program files and goes into their header comment; empty = the
    /// toolpath's `job_id`.
    pub job_id: String,
    /// Also publish the program on the node's output topic (and write it to its `output_dir`,
    /// if set), as for a Toolpath received on its input topic.
    pub publish: bool,
}

/// Response of `EmitProgram`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct EmitProgramResponse {
    /// Whether a program was emitted.
    pub success: bool,
    /// Why not, in one line (naming the segment and point where it applies), or a one-line
    /// summary on success (dialect, lines, SHA-256).
    pub message: String,
    /// The program; empty unless `success`.
    pub program: MachineProgram,
}

/// Request of `SendMachineCommand`: act on a controller now.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct SendMachineCommandRequest {
    /// The command.
    pub command: MachineCommand,
}

/// Response of `SendMachineCommand`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct SendMachineCommandResponse {
    /// Whether every addressed controller took the command.
    pub success: bool,
    /// What was done, or why not, per controller.
    pub message: String,
}
