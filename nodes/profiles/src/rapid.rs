//! ABB RAPID output settings (the emitter's part of a robot profile). Placeholder until the
//! RAPID writer lands: no keys are accepted yet.

/// How the emitter writes RAPID for one robot (module docs).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RapidSettings {}

impl RapidSettings {
    /// Checks the values; `Err((field, reason))` with the field relative to `rapid.`.
    pub(crate) fn validate(
        &self,
        _profile: &crate::MachineProfile,
    ) -> Result<(), (String, String)> {
        Ok(())
    }
}
