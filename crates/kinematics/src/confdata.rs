//! ABB's robot configuration `confdata` `[cf1, cf4, cf6, cfx]` of a joint solution.
//!
//! ABB, *Technical reference manual – RAPID Instructions, Functions and Data types*, data
//! type `confdata` (serial six-axis robots such as the IRB 1600 and 2600):
//!
//! - **cf1, cf4, cf6**: the quadrant of axis 1, 4 and 6, a signed integer: quadrant 0 holds
//!   0°..90°, 1 holds 90°..180°, −1 holds −90°..0°, −2 holds −180°..−90°, and so on over
//!   the multi-turn range of axes 4 and 6 (±400° gives −5..4). So cfN = ⌊θN / 90°⌋; an angle
//!   exactly on a border belongs to the quadrant above it (0° is quadrant 0, 90° is 1,
//!   −90° is −1). A round-off slack of 1e-9 rad decides a value within it of a border.
//! - **cfx**: the arm configuration 0–7 from three bits: the wrist centre behind axis 1 (+4),
//!   the wrist centre behind the lower arm (+2), axis 5 negative (+1):
//!
//!   | cfx | wrist centre vs axis 1 | wrist centre vs lower arm | axis 5 |
//!   |-----|------------------------|---------------------------|--------|
//!   | 0   | in front               | in front                  | ≥ 0    |
//!   | 1   | in front               | in front                  | < 0    |
//!   | 2   | in front               | behind                    | ≥ 0    |
//!   | 3   | in front               | behind                    | < 0    |
//!   | 4   | behind                 | in front                  | ≥ 0    |
//!   | 5   | behind                 | in front                  | < 0    |
//!   | 6   | behind                 | behind                    | ≥ 0    |
//!   | 7   | behind                 | behind                    | < 0    |
//!
//!   "In front of axis 1": the wrist centre's coordinate along the arm's forward direction
//!   (the base x axis turned by axis 1) is ≥ 0. "In front of the lower arm": the wrist centre
//!   lies on the forward side of the line through axes 2 and 3 (the lower arm), in the arm's
//!   plane. At the calibration position (all axes 0) the IRB 2600 has cfx 0.

use crate::model::{Joints, Robot};

/// Round-off slack at quadrant borders, radians.
const BORDER_SLACK_RAD: f64 = 1e-9;

/// The quadrant of an axis angle (module docs).
pub fn quadrant(angle_rad: f64) -> i32 {
    ((angle_rad + BORDER_SLACK_RAD) / std::f64::consts::FRAC_PI_2).floor() as i32
}

impl Robot {
    /// ABB `confdata` `[cf1, cf4, cf6, cfx]` of `joints` (module docs); `None` for
    /// non-finite joints.
    pub fn confdata(&self, joints: &Joints) -> Option<[i32; 4]> {
        Some([
            quadrant(joints[0]),
            quadrant(joints[3]),
            quadrant(joints[5]),
            self.cfx(joints)?,
        ])
    }

    /// The in-range solutions for `tcp_world` whose configuration is `confdata`: what a
    /// controller moving to a robtarget with that `robconf` arrives at (one, away from the
    /// wrist singularity).
    pub fn solutions_with_confdata(
        &self,
        tcp_world: &crate::Frame,
        tool: &crate::Frame,
        confdata: [i32; 4],
    ) -> Vec<Joints> {
        self.inverse_within_limits(tcp_world, tool)
            .into_iter()
            .filter(|q| self.confdata(q) == Some(confdata))
            .collect()
    }

    /// The arm configuration bits (module docs).
    pub fn cfx(&self, joints: &Joints) -> Option<i32> {
        let g = *self.geometry();
        let [wx, wy, wz] = self.wrist_centre_in_base(joints)?;
        let q1 = self.model_angle(0, joints[0]);
        let q2 = self.model_angle(1, joints[1]);
        // In the arm plane (base turned by axis 1): forward coordinate and height.
        let forward = q1.cos() * wx + q1.sin() * wy;
        let behind_axis1 = forward < 0.0;
        // Relative to the shoulder (axis 2); the lower arm points along (sin q2, cos q2).
        let (dx, dz) = (forward - g.a1_mm, wz - g.c1_mm);
        let behind_lower_arm = dx * q2.cos() - dz * q2.sin() < 0.0;
        let axis5_negative = joints[4] < 0.0;
        Some(
            4 * i32::from(behind_axis1)
                + 2 * i32::from(behind_lower_arm)
                + i32::from(axis5_negative),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Frame, OpwGeometry, IRB2600_LIMITS_DEG};

    #[test]
    fn quadrants_follow_abb() {
        let d = f64::to_radians;
        assert_eq!(quadrant(d(0.0)), 0);
        assert_eq!(quadrant(d(45.0)), 0);
        assert_eq!(quadrant(d(90.0)), 1);
        assert_eq!(quadrant(d(179.0)), 1);
        assert_eq!(quadrant(d(-1.0)), -1);
        assert_eq!(quadrant(d(-90.0)), -1);
        assert_eq!(quadrant(d(-91.0)), -2);
        assert_eq!(quadrant(d(-180.0)), -2);
        assert_eq!(quadrant(d(390.0)), 4);
        assert_eq!(quadrant(d(-400.0)), -5);
    }

    #[test]
    fn arm_configuration_bits() {
        let robot = Robot::new(
            OpwGeometry::abb_irb2600_165(),
            IRB2600_LIMITS_DEG,
            Frame::IDENTITY,
        )
        .unwrap();
        let d = f64::to_radians;
        // Calibration position: in front of everything, axis 5 = 0.
        assert_eq!(robot.confdata(&[0.0; 6]), Some([0, 0, 0, 0]));
        // Axis 5 negative sets bit 0.
        assert_eq!(robot.cfx(&[0.0, 0.0, 0.0, 0.0, d(-30.0), 0.0]), Some(1));
        // Lower arm leaning far forward, upper arm folded back: the wrist centre ends up
        // behind the lower arm (bit 1).
        assert_eq!(
            robot.cfx(&[0.0, d(60.0), d(-150.0), 0.0, d(10.0), 0.0]),
            Some(2)
        );
        // Lower arm leaning back, upper arm up: the wrist centre behind axis 1 but on the
        // front side of the lower arm (bit 2 only).
        assert_eq!(
            robot.cfx(&[0.0, d(-80.0), d(-10.0), 0.0, d(10.0), 0.0]),
            Some(4)
        );
        // Reaching over the top to the back: behind axis 1 and behind the lower arm.
        assert_eq!(
            robot.cfx(&[0.0, d(-60.0), d(-140.0), 0.0, d(-10.0), 0.0]),
            Some(7)
        );
        // Turning axis 1 does not change the arm configuration; it changes cf1.
        assert_eq!(
            robot.confdata(&[d(100.0), 0.0, 0.0, d(-200.0), d(20.0), d(370.0)]),
            Some([1, -3, 4, 0])
        );
    }
}
