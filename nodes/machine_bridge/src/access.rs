//! Who may do what to the machines: every goal, command and topic program is checked here before
//! it reaches a controller.
//!
//! 1. The sender must be an allowed peer (`allowed_peers`; [`cell_runtime::peers`]): the
//!    request's writer GUID names its participant, discovery its addresses. A participant not
//!    (yet) discovered is refused.
//! 2. Starting motion (a run, resume, an override) needs the bridge armed
//!    ([`cell_bridge::arming`]); hold and abort never do, so a stop from an allowed peer always
//!    goes through.
//! 3. An empty `machine_id` addresses every machine only for hold and abort; anything else must
//!    name its machine.
//! 4. A program must be for the controller's machine profile ([`profile_refusal`]).
//!
//! A refusal is one line naming the peer and why; the caller logs it at WARN and answers with it.

use std::sync::Arc;

use cell_bridge::arming::{Arming, MachineAct};
use cell_bridge::controller::Controller;
use cell_bridge::program_fit::UnnamedProfile;
use cell_msgs::{MachineCommand, MachineProgram};
use cell_runtime::peers::AllowedPeers;
use cell_runtime::CellNode;

/// The bridge's access rules (module docs).
pub struct Access {
    node: CellNode,
    allowed: AllowedPeers,
    /// The armed state, shared with the arm service.
    pub arming: Arc<Arming>,
}

impl Access {
    /// Rules over `allowed` and `arming`.
    pub fn new(node: CellNode, allowed: AllowedPeers, arming: Arc<Arming>) -> Self {
        Access {
            node,
            allowed,
            arming,
        }
    }

    /// Whether the writer `from` may do `act` (rules 1 and 2); an allowed act counts as machine
    /// activity for the arming.
    ///
    /// # Errors
    /// Why not, naming the peer.
    pub fn check(&self, from: &[u8; 16], act: MachineAct) -> Result<(), String> {
        let peer = self
            .node
            .peer(from)
            .map_err(|why| format!("{} refused: {why}", act.name()))?;
        self.allowed
            .admit(&peer)
            .map_err(|why| format!("{} refused: {why}", act.name()))?;
        if act.needs_arming() && !self.arming.is_armed() {
            return Err(format!(
                "{} refused from {peer}: the bridge is not armed (arm it at the machine: `cell \
                 machine arm`)",
                act.name()
            ));
        }
        self.arming.touch();
        Ok(())
    }

    /// [`Access::check`] for a command, and rule 3.
    ///
    /// # Errors
    /// Why not, naming the peer.
    pub fn check_command(&self, from: &[u8; 16], command: &MachineCommand) -> Result<(), String> {
        let act = MachineAct::Command(command.command);
        if command.machine_id.is_empty() && !act.may_address_all() {
            return Err(format!(
                "{} refused: machine_id is empty; only hold and abort may address every machine",
                act.name()
            ));
        }
        self.check(from, act)
    }
}

/// Rule 4: a controller configured for a machine profile runs only programs emitted for it (a
/// program naming no profile could be for any machine). `None`: it may run it.
pub fn profile_refusal(controller: &Controller, program: &MachineProgram) -> Option<String> {
    cell_bridge::program_fit::profile_refusal(
        controller.id(),
        controller.machine_profile(),
        program,
        UnnamedProfile::Refuse,
    )
}
