//! ABB RAPID from a `Toolpath` (seed 004 §4.7). Placeholder until the RAPID writer lands.

use cell_msgs::{ProgramFile, Toolpath};
use cell_profiles::MachineProfile;

use crate::EmitError;

/// The RAPID files for `toolpath` on `profile` (the first is the main module).
///
/// # Errors
/// Not written yet: always [`EmitError::MissingSection`].
pub fn emit(
    _toolpath: &Toolpath,
    profile: &MachineProfile,
    _job_id: &str,
) -> Result<Vec<ProgramFile>, EmitError> {
    Err(EmitError::MissingSection {
        profile: profile.name.clone(),
        section: "rapid",
    })
}
