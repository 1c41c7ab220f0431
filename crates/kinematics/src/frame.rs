//! A rigid frame in millimetres with an ABB-order quaternion, and its conversion to the
//! solver's pose (metres).
//!
//! Frames compose as homogeneous transforms: `a.then(b)` is `a · b`, the frame `b` expressed
//! in `a`'s parent. A robtarget in a work object is reached when
//! `world_T_base · base_T_tool0(q) · tool0_T_tcp = world_T_uframe · uframe_T_oframe · target`.

use rs_opw_kinematics::glam::{DQuat, DVec3};
use rs_opw_kinematics::pose::Pose;

/// A rigid transform: translation (mm) and rotation as a unit quaternion in ABB's order
/// `[q1, q2, q3, q4] = [w, x, y, z]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Translation, mm.
    pub trans_mm: [f64; 3],
    /// Rotation `[w, x, y, z]`; normalised when used.
    pub quat: [f64; 4],
}

impl Frame {
    /// The identity.
    pub const IDENTITY: Frame = Frame {
        trans_mm: [0.0; 3],
        quat: [1.0, 0.0, 0.0, 0.0],
    };

    /// A frame from its parts.
    pub fn new(trans_mm: [f64; 3], quat: [f64; 4]) -> Self {
        Self { trans_mm, quat }
    }

    /// True when every component is finite and the quaternion is not zero.
    pub fn is_valid(&self) -> bool {
        let norm = self.quat.iter().map(|v| v * v).sum::<f64>().sqrt();
        self.trans_mm.iter().all(|v| v.is_finite()) && norm.is_finite() && norm > 1e-12
    }

    fn parts(&self) -> (DVec3, DQuat) {
        let [w, x, y, z] = self.quat;
        (
            DVec3::from_array(self.trans_mm),
            DQuat::from_xyzw(x, y, z, w).normalize(),
        )
    }

    fn from_parts(t: DVec3, q: DQuat) -> Self {
        Self {
            trans_mm: t.to_array(),
            quat: [q.w, q.x, q.y, q.z],
        }
    }

    /// `self · other`.
    pub fn then(&self, other: &Frame) -> Frame {
        let (ta, qa) = self.parts();
        let (tb, qb) = other.parts();
        Self::from_parts(ta + qa * tb, (qa * qb).normalize())
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Frame {
        let (t, q) = self.parts();
        let qi = q.inverse();
        Self::from_parts(qi * -t, qi)
    }

    /// Maps a point (mm) from this frame to its parent.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let (t, q) = self.parts();
        (t + q * DVec3::from_array(p)).to_array()
    }

    /// Rotates a direction from this frame to its parent.
    pub fn rotate(&self, v: [f64; 3]) -> [f64; 3] {
        let (_, q) = self.parts();
        (q * DVec3::from_array(v)).to_array()
    }

    /// Distance between the origins, mm.
    pub fn distance_mm(&self, other: &Frame) -> f64 {
        let (ta, _) = self.parts();
        let (tb, _) = other.parts();
        (ta - tb).length()
    }

    /// Angle of the rotation between the two orientations, radians (q and −q are the same).
    pub fn angle_to(&self, other: &Frame) -> f64 {
        let (_, qa) = self.parts();
        let (_, qb) = other.parts();
        2.0 * qa.dot(qb).abs().min(1.0).acos()
    }

    /// The frame a fraction `t` (0..1) of the way from `self` to `other`: position linear,
    /// orientation by spherical linear interpolation (what a linear move does).
    pub fn interpolate(&self, other: &Frame, t: f64) -> Frame {
        let (ta, qa) = self.parts();
        let (tb, qb) = other.parts();
        Self::from_parts(ta.lerp(tb, t), qa.slerp(qb, t).normalize())
    }

    /// The solver's pose (metres); `None` for a non-finite frame.
    pub(crate) fn to_pose(self) -> Option<Pose> {
        if !self.is_valid() {
            return None;
        }
        let (t, q) = self.parts();
        Pose::try_from_parts(t / 1000.0, q).ok()
    }

    /// A solver pose (metres) as a frame in mm.
    pub(crate) fn from_pose(pose: &Pose) -> Frame {
        Self::from_parts(pose.translation * 1000.0, pose.rotation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn composition_and_inverse_cancel() {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let a = Frame::new([100.0, -20.0, 5.0], [s, 0.0, s, 0.0]);
        let b = Frame::new([1.0, 2.0, 3.0], [0.5, 0.5, 0.5, 0.5]);
        let c = a.then(&b).then(&b.inverse());
        assert!(c.distance_mm(&a) < 1e-9);
        assert!(c.angle_to(&a) < 1e-9);
        // A quarter turn about Y takes +X to −Z.
        let p = a.rotate([1.0, 0.0, 0.0]);
        assert!((p[2] + 1.0).abs() < 1e-12, "{p:?}");
    }

    #[test]
    fn invalid_frames_have_no_pose() {
        assert!(Frame::new([f64::NAN, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0])
            .to_pose()
            .is_none());
        assert!(Frame::new([0.0; 3], [0.0; 4]).to_pose().is_none());
    }
}
