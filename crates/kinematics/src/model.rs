//! The robot: OPW geometry, joint limits and where its base stands in the world; forward and
//! inverse kinematics of the tool centre point through `rs-opw-kinematics`.
//!
//! OPW (ortho-parallel basis, spherical wrist: Brandstötter, Angerer and Hofbaur, "An
//! analytical solution of the inverse kinematics problem of industrial serial manipulators
//! with an ortho-parallel basis and a spherical wrist", Austrian Robotics Workshop 2014) gives
//! up to eight closed-form solutions for a six-axis arm from seven lengths: a1 (shoulder
//! offset along x), a2 (elbow-to-forearm offset), b (lateral offset), c1 (base to shoulder
//! height), c2 (lower arm), c3 (upper arm to the wrist centre), c4 (wrist centre to flange).
//! Joint values are the controller's (ABB's axis angles, degrees in the profile, radians
//! here); the solver's flange frame at all joints zero is ABB's `tool0`: z along the base x
//! axis, x pointing down, quaternion `[0.7071, 0, 0.7071, 0]`.

use std::f64::consts::TAU;

use rs_opw_kinematics::kinematic_traits::Kinematics;
use rs_opw_kinematics::kinematics_impl::OPWKinematics;
use rs_opw_kinematics::parameters::opw_kinematics::Parameters;
use thiserror::Error;

use crate::frame::Frame;

/// Six joint values, radians (controller convention).
pub type Joints = [f64; 6];

/// OPW parameters in millimetres and degrees (see the module docs for the lengths).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpwGeometry {
    /// Shoulder offset along x, mm.
    pub a1_mm: f64,
    /// Elbow offset (forearm height above the elbow axis, negative for ABB arms), mm.
    pub a2_mm: f64,
    /// Lateral offset, mm.
    pub b_mm: f64,
    /// Base to shoulder height, mm.
    pub c1_mm: f64,
    /// Lower arm length, mm.
    pub c2_mm: f64,
    /// Upper arm length (elbow to wrist centre), mm.
    pub c3_mm: f64,
    /// Wrist centre to flange, mm.
    pub c4_mm: f64,
    /// Zero offsets between the controller's joint values and the OPW model's, degrees (ABB
    /// arms: −90 on axis 3).
    pub offsets_deg: [f64; 6],
    /// Direction of each joint relative to the model: +1 or −1.
    pub signs: [i8; 6],
}

impl OpwGeometry {
    /// ABB IRB 2600-12/1.65 and -20/1.65 (one arm geometry for both payloads). Source: the
    /// ROS-Industrial support package `abb_irb2600_support`, `urdf/irb2600_12_165_macro.xacro`
    /// (joint origins: shoulder 150 mm out and 445 mm up, lower arm 700 mm, forearm 115 mm
    /// above the elbow, upper arm 795 mm, flange 85 mm), which is also
    /// `rs_opw_kinematics::Parameters::irb2600_12_165`.
    pub fn abb_irb2600_165() -> Self {
        Self {
            a1_mm: 150.0,
            a2_mm: -115.0,
            b_mm: 0.0,
            c1_mm: 445.0,
            c2_mm: 700.0,
            c3_mm: 795.0,
            c4_mm: 85.0,
            offsets_deg: [0.0, 0.0, -90.0, 0.0, 0.0, 0.0],
            signs: [1; 6],
        }
    }

    /// ABB IRB 1600-6/1.45, -8/1.45 and -10/1.45 (one arm geometry). Source: ROS-Industrial
    /// `abb_irb1600_support/config/opw_parameters_irb1600_8_145.yaml` (a1 150, c1 486.5, c2
    /// 700, c3 600, c4 65 mm; axis 3 offset −90°).
    pub fn abb_irb1600_145() -> Self {
        Self {
            a1_mm: 150.0,
            a2_mm: 0.0,
            b_mm: 0.0,
            c1_mm: 486.5,
            c2_mm: 700.0,
            c3_mm: 600.0,
            c4_mm: 65.0,
            offsets_deg: [0.0, 0.0, -90.0, 0.0, 0.0, 0.0],
            signs: [1; 6],
        }
    }

    fn parameters(&self) -> Parameters {
        Parameters {
            a1: self.a1_mm / 1000.0,
            a2: self.a2_mm / 1000.0,
            b: self.b_mm / 1000.0,
            c1: self.c1_mm / 1000.0,
            c2: self.c2_mm / 1000.0,
            c3: self.c3_mm / 1000.0,
            c4: self.c4_mm / 1000.0,
            offsets: self.offsets_deg.map(f64::to_radians),
            sign_corrections: self.signs,
            dof: 6,
        }
    }
}

/// Joint ranges `[min, max]` in degrees, axes 1–6.
pub type JointLimitsDeg = [[f64; 2]; 6];

/// IRB 2600 axis ranges, degrees: axis 1 ±180, 2 −95..+95, 3 −155..+75, 4 ±400, 5 ±120,
/// 6 ±400. Where ABB's *Product specification IRB 2600* ("Working range": axis 2 +155/−95,
/// axis 3 +75/−180) and the ROS-Industrial `irb2600_12_165_macro.xacro` (joint 2
/// −155..+95, joint 3 −155..+75) disagree, the intersection: a solution inside it is inside
/// both. Axes 4 and 6 at their default ±400° software range.
pub const IRB2600_LIMITS_DEG: JointLimitsDeg = [
    [-180.0, 180.0],
    [-95.0, 95.0],
    [-155.0, 75.0],
    [-400.0, 400.0],
    [-120.0, 120.0],
    [-400.0, 400.0],
];

/// IRB 1600 (1.45 m arm) axis ranges, degrees, from ROS-Industrial
/// `abb_irb1600_support/urdf/irb1600_8_145_macro.xacro`: axis 1 ±180, 2 −90..+120,
/// 3 −245..+65, 4 ±200, 5 ±115, 6 ±400.
pub const IRB1600_LIMITS_DEG: JointLimitsDeg = [
    [-180.0, 180.0],
    [-90.0, 120.0],
    [-245.0, 65.0],
    [-200.0, 200.0],
    [-115.0, 115.0],
    [-400.0, 400.0],
];

/// A bad robot model.
#[derive(Debug, Error, PartialEq)]
pub enum ModelError {
    /// A length, offset or limit that is not finite, an offset beyond ±360°, a sign that is
    /// not ±1, or a range with min ≥ max.
    #[error("{field}: {reason}")]
    Invalid {
        /// The field, e.g. `joint_limits_deg[3]`.
        field: String,
        /// What is wrong.
        reason: String,
    },
}

/// A robot standing in the world: geometry, joint ranges and base frame.
#[derive(Debug, Clone)]
pub struct Robot {
    geometry: OpwGeometry,
    solver: OPWKinematics,
    limits_rad: [[f64; 2]; 6],
    /// World → robot base.
    base: Frame,
}

/// Slack on joint limits and quadrant borders for round-off, radians (≈ 6e-8°).
const LIMIT_SLACK_RAD: f64 = 1e-9;

impl Robot {
    /// A robot of `geometry` with `limits_deg`, its base at `base` in the world.
    ///
    /// # Errors
    /// [`ModelError::Invalid`] naming the first bad value.
    pub fn new(
        geometry: OpwGeometry,
        limits_deg: JointLimitsDeg,
        base: Frame,
    ) -> Result<Self, ModelError> {
        let bad = |field: String, reason: String| Err(ModelError::Invalid { field, reason });
        let g = &geometry;
        for (field, v) in [
            ("a1_mm", g.a1_mm),
            ("a2_mm", g.a2_mm),
            ("b_mm", g.b_mm),
            ("c1_mm", g.c1_mm),
            ("c2_mm", g.c2_mm),
            ("c3_mm", g.c3_mm),
            ("c4_mm", g.c4_mm),
        ] {
            if !v.is_finite() {
                return bad(field.into(), format!("{v} is not finite"));
            }
        }
        for (i, o) in g.offsets_deg.iter().enumerate() {
            if !(o.is_finite() && o.abs() <= 360.0) {
                return bad(
                    format!("offsets_deg[{i}]"),
                    format!("{o} is not in [-360, 360]"),
                );
            }
        }
        for (i, s) in g.signs.iter().enumerate() {
            if s.abs() != 1 {
                return bad(format!("signs[{i}]"), format!("{s} is not 1 or -1"));
            }
        }
        for (i, [lo, hi]) in limits_deg.iter().enumerate() {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return bad(
                    format!("joint_limits_deg[{i}]"),
                    format!("[{lo}, {hi}] must be finite with min < max"),
                );
            }
        }
        if !base.is_valid() {
            return bad("base".into(), "not finite or a zero quaternion".into());
        }
        Ok(Self {
            geometry,
            solver: OPWKinematics::new(geometry.parameters()),
            limits_rad: limits_deg.map(|r| r.map(f64::to_radians)),
            base,
        })
    }

    /// The geometry.
    pub fn geometry(&self) -> &OpwGeometry {
        &self.geometry
    }

    /// Joint ranges, radians.
    pub fn limits_rad(&self) -> &[[f64; 2]; 6] {
        &self.limits_rad
    }

    /// The flange (`tool0`) in the base frame at `joints`; `None` for non-finite joints.
    pub fn flange_in_base(&self, joints: &Joints) -> Option<Frame> {
        self.solver
            .try_forward(joints)
            .ok()
            .map(|p| Frame::from_pose(&p))
    }

    /// Forward kinematics: the TCP of `tool` (tool0 → TCP) in the world at `joints`.
    pub fn forward(&self, joints: &Joints, tool: &Frame) -> Option<Frame> {
        let flange = self.flange_in_base(joints)?;
        Some(self.base.then(&flange).then(tool))
    }

    /// Inverse kinematics: every joint solution placing the TCP of `tool` at `tcp_world`,
    /// each joint in (−180°, 180°], joint limits not applied (see [`Robot::within_limits`]
    /// and [`Robot::turn_variants`]). Empty when the pose is out of reach or not finite.
    pub fn inverse(&self, tcp_world: &Frame, tool: &Frame) -> Vec<Joints> {
        let flange = self.base.inverse().then(tcp_world).then(&tool.inverse());
        match flange.to_pose() {
            Some(pose) => self.solver.inverse(&pose),
            None => Vec::new(),
        }
    }

    /// True when every joint lies in its range.
    pub fn within_limits(&self, joints: &Joints) -> bool {
        self.first_violation(joints).is_none()
    }

    /// The first joint outside its range: (axis index 0–5, value rad).
    pub fn first_violation(&self, joints: &Joints) -> Option<(usize, f64)> {
        joints.iter().enumerate().find_map(|(i, &q)| {
            let [lo, hi] = self.limits_rad[i];
            (!(lo - LIMIT_SLACK_RAD..=hi + LIMIT_SLACK_RAD).contains(&q)).then_some((i, q))
        })
    }

    /// The values `q + k·360°` of axis `axis` that lie in its range (a revolute joint reaches
    /// the same pose a whole turn further: axes 4 and 6 of ±400° have two or three).
    pub fn turn_variants(&self, axis: usize, q: f64) -> Vec<f64> {
        let [lo, hi] = self.limits_rad[axis];
        let k_min = ((lo - LIMIT_SLACK_RAD - q) / TAU).ceil() as i64;
        let k_max = ((hi + LIMIT_SLACK_RAD - q) / TAU).floor() as i64;
        (k_min..=k_max.min(k_min + 8))
            .map(|k| q + k as f64 * TAU)
            .collect()
    }

    /// Every in-range solution for `tcp_world`, whole-turn variants included.
    pub fn inverse_within_limits(&self, tcp_world: &Frame, tool: &Frame) -> Vec<Joints> {
        let mut out = Vec::new();
        for q in self.inverse(tcp_world, tool) {
            let mut partial: Vec<Joints> = vec![q];
            for axis in 0..6 {
                let mut next = Vec::new();
                for p in &partial {
                    for v in self.turn_variants(axis, p[axis]) {
                        let mut j = *p;
                        j[axis] = v;
                        next.push(j);
                    }
                }
                partial = next;
            }
            out.extend(partial);
        }
        out
    }

    /// The wrist centre in the base frame at `joints`, mm.
    pub(crate) fn wrist_centre_in_base(&self, joints: &Joints) -> Option<[f64; 3]> {
        let flange = self.flange_in_base(joints)?;
        let z = flange.rotate([0.0, 0.0, 1.0]);
        let c4 = self.geometry.c4_mm;
        let t = flange.trans_mm;
        Some([t[0] - c4 * z[0], t[1] - c4 * z[1], t[2] - c4 * z[2]])
    }

    /// The model angle of `axis` (the controller's value through sign and offset).
    pub(crate) fn model_angle(&self, axis: usize, q: f64) -> f64 {
        let g = &self.geometry;
        q * f64::from(g.signs[axis]) - g.offsets_deg[axis].to_radians()
    }
}
