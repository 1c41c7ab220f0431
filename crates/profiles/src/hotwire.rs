//! Hot-wire cutters: the two towers (carriages) and where the foam block sits between them.

use cell_config::{Allowed, FieldError};

use crate::MachineProfile;

/// Hot-wire cutter geometry: two carriages (XY and, on a 4-axis machine, UV) hold the wire
/// ends in two parallel planes; the foam block sits between them.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct HotwireGeometry {
    /// Distance between the XY and UV carriage planes along the wire, mm.
    pub tower_separation_mm: f64,
    /// Distance from the XY plane to the block's root face, mm (the tip face is a panel span
    /// further).
    pub root_plane_mm: f64,
    /// Where the root section's leading edge sits in XY machine coordinates, mm.
    pub part_origin_mm: [f64; 2],
    /// Wire id in the material library (`config/materials/wires.yaml`).
    pub wire: String,
    /// The wire supply's current range [min, max], A.
    pub supply_a: [f64; 2],
    /// Axis letters of the second (UV) carriage: `[U, V]` (the default), or e.g. `[A, B]` on a
    /// Mach3 or GRBL board that drives the far tower on A and B. A machine without these axes
    /// is a 2-axis cutter.
    #[serde(default = "default_uv_axes")]
    pub uv_axes: [char; 2],
}

fn default_uv_axes() -> [char; 2] {
    ['U', 'V']
}

impl MachineProfile {
    /// The hot-wire towers: axes X and Y, both or neither of the second carriage's axes (and
    /// G-code axis words `u`, `v` on them), a positive tower separation, the root face between
    /// the towers, a finite part origin and a supply range 0 ≤ min ≤ max, max > 0. Fields are
    /// named from the profile's root (`axes`, `gcode.axis_words`, `hotwire.…`).
    pub(crate) fn validate_hotwire(&self, h: &HotwireGeometry) -> Result<(), FieldError> {
        for axis in ['X', 'Y'] {
            if !self.axes.contains_key(&axis) {
                return Err(FieldError::new(
                    "axes",
                    format!("a hot-wire machine needs axis {axis}"),
                ));
            }
        }
        let [u, v] = h.uv_axes;
        if self.axes.contains_key(&u) != self.axes.contains_key(&v) {
            return Err(FieldError::new(
                "axes",
                format!("a 4-axis hot-wire machine needs both {u} and {v} (hotwire.uv_axes)"),
            ));
        }
        if let Some(g) = &self.gcode {
            let words = (g.axis_words.u, g.axis_words.v);
            if self.axes.contains_key(&u) && words != (Some(u), Some(v)) {
                return Err(FieldError::new(
                    "gcode.axis_words",
                    format!("the second carriage is on {u} {v} (hotwire.uv_axes): u: {u}, v: {v}"),
                ));
            }
        }
        Allowed::POSITIVE.check_field(
            "hotwire.tower_separation_mm",
            h.tower_separation_mm,
            "mm",
        )?;
        Allowed::half_open(0.0, h.tower_separation_mm)
            .check(h.root_plane_mm, "mm")
            .map_err(|e| {
                e.because("the root face lies between the towers, tower_separation_mm apart")
                    .at("hotwire.root_plane_mm")
            })?;
        if !h.part_origin_mm.iter().all(|v| v.is_finite()) {
            return Err(FieldError::new(
                "hotwire.part_origin_mm",
                format!("{:?} must be finite", h.part_origin_mm),
            ));
        }
        let [lo, hi] = h.supply_a;
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi && hi > 0.0) {
            return Err(FieldError::new(
                "hotwire.supply_a",
                format!("[{lo}, {hi}] must satisfy 0 <= min <= max, max > 0"),
            ));
        }
        Ok(())
    }
}
