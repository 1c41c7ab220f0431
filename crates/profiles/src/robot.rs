//! The robot arm of a RAPID profile (the `robot:` section of `config/machines/*.yaml`): its
//! kinematic model as OPW parameters, its joint ranges and where its base stands in the
//! world. With it the emitter solves every robtarget's joints and writes its configuration
//! (`robconf`) under `ConfL \On` (`cell_emitter::rapid`, `cell_kinematics`); without it the
//! emitter writes `rapid.robconf` and, by default, `ConfL \Off`.
//!
//! ```yaml
//! robot:
//!   model: ABB IRB 2600-20/1.65        # a label for people
//!   opw: {a1_mm: 150, a2_mm: -115, b_mm: 0, c1_mm: 445, c2_mm: 700, c3_mm: 795, c4_mm: 85}
//!   joint_limits_deg: [[-180, 180], [-95, 95], [-155, 75], [-400, 400], [-120, 120], [-400, 400]]
//!   base: {trans_mm: [0, 0, 0], quat: [1, 0, 0, 0]}   # world -> robot base
//! ```
//!
//! The tool (`rapid.tool.value`: TCP and its orientation in the flange frame) and the work
//! object (`rapid.wobj.value`: user and object frames in the world) come from the `rapid`
//! section; a profile with a robot declares both values (predefined `tool0`/`wobj0` are the
//! flange and the world).

use cell_config::FieldError;

/// OPW parameters (Brandstötter et al. 2014), mm and degrees.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct OpwParameters {
    /// Shoulder offset along x, mm.
    pub a1_mm: f64,
    /// Elbow offset (negative for ABB arms whose forearm sits above the elbow axis), mm.
    pub a2_mm: f64,
    /// Lateral offset, mm.
    #[serde(default)]
    pub b_mm: f64,
    /// Base to shoulder height, mm.
    pub c1_mm: f64,
    /// Lower arm, mm.
    pub c2_mm: f64,
    /// Upper arm to the wrist centre, mm.
    pub c3_mm: f64,
    /// Wrist centre to flange, mm.
    pub c4_mm: f64,
    /// Joint zero offsets between controller and model, degrees. Default ABB's
    /// [0, 0, −90, 0, 0, 0].
    #[serde(default = "abb_offsets")]
    pub offsets_deg: [f64; 6],
    /// Joint directions relative to the model, +1 or −1. Default all +1.
    #[serde(default = "plus_ones")]
    pub signs: [i8; 6],
}

fn abb_offsets() -> [f64; 6] {
    [0.0, 0.0, -90.0, 0.0, 0.0, 0.0]
}

fn plus_ones() -> [i8; 6] {
    [1; 6]
}

/// A frame in its parent: translation (mm) and quaternion [w, x, y, z].
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct FrameValue {
    /// Translation, mm.
    #[serde(default)]
    pub trans_mm: [f64; 3],
    /// Orientation [w, x, y, z] (normalised when used).
    #[serde(default = "identity_quat")]
    pub quat: [f64; 4],
}

fn identity_quat() -> [f64; 4] {
    [1.0, 0.0, 0.0, 0.0]
}

impl Default for FrameValue {
    fn default() -> Self {
        Self {
            trans_mm: [0.0; 3],
            quat: identity_quat(),
        }
    }
}

/// The `robot:` section (module docs).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSection {
    /// The arm, for people (e.g. `ABB IRB 2600-20/1.65`).
    #[serde(default)]
    pub model: String,
    /// Kinematic model.
    pub opw: OpwParameters,
    /// Axis ranges [min, max], degrees, axes 1–6.
    pub joint_limits_deg: [[f64; 2]; 6],
    /// The robot base in the world frame (RAPID's world → base). Default: the same frame.
    #[serde(default)]
    pub base: FrameValue,
}

impl RobotSection {
    /// Finite lengths, offsets within ±360°, signs ±1, ranges with min < max, a finite base
    /// with a non-zero quaternion; and, on `rapid`, declared tool and work object values
    /// (the kinematics needs the numbers).
    ///
    /// # Errors
    /// The first bad field, relative to `robot`.
    pub fn validate(&self, rapid: Option<&crate::RapidSettings>) -> Result<(), FieldError> {
        let o = &self.opw;
        for (field, v) in [
            ("opw.a1_mm", o.a1_mm),
            ("opw.a2_mm", o.a2_mm),
            ("opw.b_mm", o.b_mm),
            ("opw.c1_mm", o.c1_mm),
            ("opw.c2_mm", o.c2_mm),
            ("opw.c3_mm", o.c3_mm),
            ("opw.c4_mm", o.c4_mm),
        ] {
            if !v.is_finite() {
                return Err(FieldError::new(field, format!("{v} is not finite")));
            }
        }
        for (field, v) in [("opw.c2_mm", o.c2_mm), ("opw.c3_mm", o.c3_mm)] {
            if v <= 0.0 {
                return Err(FieldError::new(
                    field,
                    format!("{v} mm: an arm length must be > 0"),
                ));
            }
        }
        for (i, v) in o.offsets_deg.iter().enumerate() {
            if !(v.is_finite() && v.abs() <= 360.0) {
                return Err(FieldError::new(
                    format!("opw.offsets_deg[{i}]"),
                    format!("{v} must lie in [-360, 360]"),
                ));
            }
        }
        for (i, s) in o.signs.iter().enumerate() {
            if s.abs() != 1 {
                return Err(FieldError::new(
                    format!("opw.signs[{i}]"),
                    format!("{s} must be 1 or -1"),
                ));
            }
        }
        for (i, [lo, hi]) in self.joint_limits_deg.iter().enumerate() {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(FieldError::new(
                    format!("joint_limits_deg[{i}]"),
                    format!(
                        "[{lo}, {hi}] must be finite with min < max (axis {})",
                        i + 1
                    ),
                ));
            }
        }
        check_frame(&self.base).map_err(|r| FieldError::new("base", r))?;
        let Some(r) = rapid else {
            return Err(FieldError::new(
                "",
                "a robot section needs a rapid section (its tool and work object)",
            ));
        };
        if r.tool.value.is_none() {
            return Err(FieldError::new(
                "",
                format!(
                    "the kinematics needs the tool's TCP: declare rapid.tool.value for {:?}",
                    r.tool.name
                ),
            ));
        }
        if r.wobj.value.is_none() && !r.wobj.name.eq_ignore_ascii_case("wobj0") {
            return Err(FieldError::new(
                "",
                format!(
                    "the kinematics needs the work object's frames: declare rapid.wobj.value for {:?}",
                    r.wobj.name
                ),
            ));
        }
        Ok(())
    }
}

fn check_frame(f: &FrameValue) -> Result<(), String> {
    if !f.trans_mm.iter().all(|v| v.is_finite()) {
        return Err(format!("trans_mm {:?} is not finite", f.trans_mm));
    }
    let norm = f.quat.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 1e-9) {
        return Err(format!(
            "quat {:?} is not a finite non-zero quaternion",
            f.quat
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::MachineProfile;

    fn yaml(name: &str) -> String {
        std::fs::read_to_string(format!(
            "{}/../../config/machines/{name}.yaml",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap()
    }

    #[test]
    fn the_abb_profiles_carry_their_arms() {
        let p = MachineProfile::resolve("abb-irb2600-waam").unwrap();
        let r = p.robot.unwrap();
        assert_eq!(
            (r.opw.a2_mm, r.opw.c3_mm, r.opw.c4_mm),
            (-115.0, 795.0, 85.0)
        );
        assert_eq!(r.joint_limits_deg[5], [-400.0, 400.0]);
        let p = MachineProfile::resolve("abb-irb1600-rw7-do").unwrap();
        let r = p.robot.unwrap();
        assert_eq!(
            (r.opw.c1_mm, r.opw.c2_mm, r.opw.c3_mm),
            (486.5, 700.0, 600.0)
        );
    }

    #[test]
    fn bad_robot_values_name_the_field() {
        let base = yaml("abb-irb2600-waam");
        for (from, to, field) in [
            ("c2_mm: 700.0", "c2_mm: -700.0", "robot.opw.c2_mm"),
            (
                "[-120.0, 120.0]",
                "[120.0, -120.0]",
                "robot.joint_limits_deg[4]",
            ),
            (
                "signs: [1, 1, 1, 1, 1, 1]",
                "signs: [1, 1, 2, 1, 1, 1]",
                "robot.opw.signs[2]",
            ),
            (
                "\n    quat: [1.0, 0.0, 0.0, 0.0]",
                "\n    quat: [0.0, 0.0, 0.0, 0.0]",
                "robot.base",
            ),
        ] {
            assert!(base.contains(from), "{from}");
            let text = base.replacen(from, to, 1);
            let e = MachineProfile::from_yaml_str(&text, "t.yaml").unwrap_err();
            assert!(e.to_string().contains(&format!("field `{field}`")), "{e}");
        }
        // The tool's TCP is needed.
        let text = base.replace(
            "  tool:\n    name: tWAAM\n    value:\n      robhold: true\n      tcp_mm: [0.0, 0.0, 400.0]\n      tcp_quat: [1.0, 0.0, 0.0, 0.0]\n      mass_kg: 4.5\n      cog_mm: [0.0, 0.0, 150.0]\n",
            "  tool:\n    name: tWAAM\n",
        );
        assert_ne!(text, base);
        let e = MachineProfile::from_yaml_str(&text, "t.yaml").unwrap_err();
        assert!(e.to_string().contains("rapid.tool.value"), "{e}");
    }
}
