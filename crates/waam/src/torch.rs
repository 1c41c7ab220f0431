//! The torch pose along a bead: lead (push/drag) and work angles, and the height of the tool
//! point above the layer (`torch:` in `config/processes/waam.yaml`).
//!
//! Angles follow the welding convention (AWS A3.0, "travel angle" and "work angle"): with
//! `n` the surface normal (+Z on a horizontal layer), `t` the unit travel direction along the
//! bead (horizontal) and `l = n × t` the side to the left of travel,
//!
//! - the **lead angle** `α` is the tilt of the torch axis from `n` in the plane of `n` and
//!   `t`: positive = push (the torch leans back and points ahead, along `t`), negative =
//!   drag (it points back at the deposited bead);
//! - the **work angle** `β` is the tilt from `n` in the plane of `n` and `l`: positive = the
//!   torch leans to the left of travel and points to the right.
//!
//! The torch axis, pointing from the work up the torch (what the toolpath carries as its
//! normal; the emitter points the tool z-axis against it), is
//! `a = (n − tan α · t + tan β · l) / ‖…‖`: its projections on the two planes make exactly
//! `α` and `β` with `n`. Both angles lie in [−45°, 45°].
//!
//! The tool point (the wire tip, the TCP of the robot's tool) is at the top of the bead being
//! laid, the layer's top, `z_slice + layer_height / 2` (the slicer cuts mid-layer), plus
//! `ctwd_mm` when the process gives a contact-tip-to-work distance for a TCP at the contact
//! tip.

use serde::{Deserialize, Serialize};

/// Largest lead or work angle, degrees.
pub const MAX_ANGLE_DEG: f64 = 45.0;

/// Torch angles and tool point height (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TorchPose {
    /// Lead angle α, degrees: push > 0, drag < 0. Default 0 (torch along the normal).
    pub lead_angle_deg: f64,
    /// Work angle β, degrees: > 0 leans left of travel. Default 0.
    pub work_angle_deg: f64,
    /// Contact-tip-to-work distance (mm, ≥ 0) when the tool's TCP is the contact tip; `None`
    /// (default): the TCP is the wire tip, at the top of the bead.
    pub ctwd_mm: Option<f64>,
}

impl Default for TorchPose {
    fn default() -> Self {
        Self {
            lead_angle_deg: 0.0,
            work_angle_deg: 0.0,
            ctwd_mm: None,
        }
    }
}

impl TorchPose {
    /// The torch axis for travel direction `travel` on a horizontal layer (module docs);
    /// +Z when `travel` has no horizontal length.
    pub fn axis(&self, travel: [f64; 3]) -> [f64; 3] {
        let len = travel[0].hypot(travel[1]);
        if len.is_nan() || len <= 1e-12 {
            return [0.0, 0.0, 1.0];
        }
        let t = [travel[0] / len, travel[1] / len];
        // l = Z × t.
        let l = [-t[1], t[0]];
        let (ta, tb) = (
            self.lead_angle_deg.to_radians().tan(),
            self.work_angle_deg.to_radians().tan(),
        );
        let a = [-ta * t[0] + tb * l[0], -ta * t[1] + tb * l[1], 1.0];
        let n = (a[0] * a[0] + a[1] * a[1] + 1.0).sqrt();
        a.map(|v| v / n)
    }

    /// True when the torch stands along the normal (both angles 0).
    pub fn is_upright(&self) -> bool {
        self.lead_angle_deg == 0.0 && self.work_angle_deg == 0.0
    }

    /// Height of the tool point above the slicing plane (mm): half a layer up to the layer's
    /// top, plus the contact-tip-to-work distance if given.
    pub fn height_above_slice_mm(&self, layer_height_mm: f64) -> f64 {
        layer_height_mm / 2.0 + self.ctwd_mm.unwrap_or(0.0)
    }

    /// The first invalid field and why: angles within ±[`MAX_ANGLE_DEG`], CTWD finite ≥ 0.
    pub fn problem(&self) -> Option<(&'static str, String)> {
        for (field, v) in [
            ("torch.lead_angle_deg", self.lead_angle_deg),
            ("torch.work_angle_deg", self.work_angle_deg),
        ] {
            if !(v.is_finite() && v.abs() <= MAX_ANGLE_DEG) {
                return Some((
                    field,
                    format!("{v} deg must lie in [-{MAX_ANGLE_DEG}, {MAX_ANGLE_DEG}]"),
                ));
            }
        }
        if let Some(c) = self.ctwd_mm {
            if !(c.is_finite() && c >= 0.0) {
                return Some(("torch.ctwd_mm", format!("{c} mm must be finite and >= 0")));
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lead_and_work_angles_tilt_the_axis_as_measured() {
        let torch = TorchPose {
            lead_angle_deg: 15.0,
            work_angle_deg: -10.0,
            ctwd_mm: None,
        };
        // Travelling along +Y: t = +Y, l = −X.
        let a = torch.axis([0.0, 3.0, 0.0]);
        let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        assert!((norm - 1.0).abs() < 1e-12);
        // Lead: angle from Z in the (Z, t) plane; push leans back (−t).
        let lead = (-a[1]).atan2(a[2]).to_degrees();
        assert!((lead - 15.0).abs() < 1e-9, "{lead}");
        // Work: angle from Z in the (Z, l) plane, l = −X.
        let work = (-a[0]).atan2(a[2]).to_degrees();
        assert!((work + 10.0).abs() < 1e-9, "{work}");
        assert_eq!(TorchPose::default().axis([1.0, 0.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(torch.axis([0.0, 0.0, 5.0]), [0.0, 0.0, 1.0]);
    }

    #[test]
    fn the_tool_point_sits_on_the_layer_top() {
        assert_eq!(TorchPose::default().height_above_slice_mm(1.6), 0.8);
        let t = TorchPose {
            ctwd_mm: Some(15.0),
            ..TorchPose::default()
        };
        assert_eq!(t.height_above_slice_mm(1.6), 15.8);
        let bad = TorchPose {
            lead_angle_deg: 60.0,
            ..TorchPose::default()
        };
        assert_eq!(bad.problem().unwrap().0, "torch.lead_angle_deg");
    }
}
