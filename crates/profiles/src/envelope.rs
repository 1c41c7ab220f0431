//! The travel envelope: is a commanded position inside every axis's travel?

use crate::MachineProfile;

/// A position outside a machine's travel.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{axis} = {value:.3} mm is outside the travel {min}..{max} mm of machine {machine:?}")]
pub struct EnvelopeViolation {
    /// The machine.
    pub machine: String,
    /// The axis letter.
    pub axis: char,
    /// The commanded value.
    pub value: f64,
    /// Travel minimum.
    pub min: f64,
    /// Travel maximum.
    pub max: f64,
}

impl MachineProfile {
    /// Checks one position given as (axis, value) pairs against the travel. Axes the machine
    /// does not have are an error too (reported with an empty travel 0..0).
    ///
    /// # Errors
    /// The first axis out of travel.
    pub fn check_position(&self, position: &[(char, f64)]) -> Result<(), EnvelopeViolation> {
        for &(axis, value) in position {
            let travel = self.axes.get(&axis).copied();
            let [min, max] = travel.unwrap_or([0.0, 0.0]);
            // A thousandth of a millimetre of slack: values that round onto the limit pass.
            let slack = 1e-3;
            if !(travel.is_some() && value >= min - slack && value <= max + slack) {
                return Err(EnvelopeViolation {
                    machine: self.name.clone(),
                    axis,
                    value,
                    min,
                    max,
                });
            }
        }
        Ok(())
    }
}
