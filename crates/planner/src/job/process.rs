//! The kerf-model side of a job (seed 001): the wire-centre offset and the inputs of the
//! constant-kerf current schedule, with the fallbacks taken when the material library does not
//! know the foam or the wire.

use cell_profiles::HotwireGeometry;

use crate::kerf::{self, CurrentLimits, MaterialLibrary};

use super::{HotwireJob, JobError, JobParameter};

/// Wire offset used when the material library cannot give one (mm).
pub const FALLBACK_OFFSET_MM: f64 = 0.5;

/// The kerf-model side of a job: offset and current schedule inputs.
pub(super) struct Process {
    pub(super) offset_mm: f64,
    /// (Q_eff in J/m², R' in Ω/m) when the library has the material and wire.
    pub(super) schedule: Option<(f64, f64)>,
    pub(super) supply: CurrentLimits,
    pub(super) notes: Vec<String>,
}

pub(super) fn process(job: &HotwireJob, hw: &HotwireGeometry) -> Result<Process, JobError> {
    let lib = MaterialLibrary::builtin();
    let mut notes = Vec::new();
    let (foam, wire) = (lib.find_foam(&job.material), lib.find_wire(&hw.wire));
    let model = match (foam, wire) {
        (Some(foam), Some(wire)) => {
            let inputs = kerf::KerfInputs::for_cut(job.current_a, job.feed_mm_s * 1e-3, wire, foam);
            kerf::predict_kerf_m(&inputs)
                .and_then(|k| kerf::clamp_kerf_to_wire(k, wire.diameter_m))
                .ok()
                .map(|k| (k.kerf_m, foam, wire))
        }
        _ => None,
    };
    let offset_mm = match (job.offset_mm, &model) {
        (Some(o), _) => o,
        (None, Some((kerf_m, ..))) => kerf_m / 2.0 * 1e3,
        (None, None) => FALLBACK_OFFSET_MM,
    };
    if !(offset_mm.is_finite() && offset_mm > 0.0) {
        return Err(JobError::InvalidParameter {
            parameter: JobParameter::OffsetMm,
            value: offset_mm,
            requirement: "finite and > 0",
        });
    }
    let schedule = match &model {
        // The area energy that cuts a kerf of 2 × offset: Q_eff = λ · ρ_f · ^mass Q_eff (seed 001
        // eq. 4–6).
        Some((_, foam, wire)) => Some((
            2.0 * offset_mm * 1e-3 * foam.density_kg_m3 * foam.mass_energy_j_kg(),
            wire.resistance_ohm_per_m,
        )),
        None => {
            let what = match (foam, wire) {
                (None, _) => format!(
                    "material {:?} is not in the material library (known: {})",
                    job.material,
                    lib.foam_names().join(", ")
                ),
                (_, None) => format!("wire {:?} is not in the material library", hw.wire),
                _ => "the kerf model rejected the current/feed".to_string(),
            };
            notes.push(format!(
                "{what}: constant current {} A{}",
                job.current_a,
                if job.offset_mm.is_none() {
                    format!(", offset {FALLBACK_OFFSET_MM} mm")
                } else {
                    String::new()
                }
            ));
            None
        }
    };
    Ok(Process {
        offset_mm,
        schedule,
        supply: CurrentLimits {
            min_a: hw.supply_a[0],
            max_a: hw.supply_a[1],
        },
        notes,
    })
}
