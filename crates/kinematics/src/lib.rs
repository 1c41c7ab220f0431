//! Robot kinematics for the RAPID emitter: where a six-axis arm's joints must be for its tool
//! to reach a target, and which ABB configuration (`confdata`) that is.
//!
//! - [`frame`]: rigid frames (mm, quaternion `[w, x, y, z]` as in RAPID) and their algebra;
//! - [`model`]: the arm ([`OpwGeometry`], joint ranges, base frame in the world) with forward
//!   and inverse kinematics over `rs-opw-kinematics` (analytic OPW solutions), and the
//!   published parameters of the ABB IRB 2600 (1.65 m) and IRB 1600 (1.45 m);
//! - [`confdata`]: ABB's `[cf1, cf4, cf6, cfx]` of a joint solution;
//! - [`path`]: solutions along a path of linear moves in one arm configuration, or an error
//!   naming the target that cannot be reached that way.
//!
//! A target `T` (TCP in the world) is reached at joints `q` when
//! `base · tool0(q) · tool = T`, with `base` the robot base in the world and `tool` the TCP
//! in the flange frame (RAPID `tooldata.tframe`).
//!
//! ```
//! use cell_kinematics::{Frame, OpwGeometry, Robot, IRB2600_LIMITS_DEG};
//! let robot = Robot::new(OpwGeometry::abb_irb2600_165(), IRB2600_LIMITS_DEG, Frame::IDENTITY)
//!     .unwrap();
//! let torch = Frame::new([0.0, 0.0, 400.0], [1.0, 0.0, 0.0, 0.0]);
//! // The torch pointing straight down (tool z = −Z) 1 m in front of the robot, 300 mm up.
//! let target = Frame::new([1000.0, 0.0, 300.0], [0.0, 1.0, 0.0, 0.0]);
//! let path = robot.solve_path(&[target], &torch).unwrap();
//! let reached = robot.forward(&path[0].joints, &torch).unwrap();
//! assert!(reached.distance_mm(&target) < 1e-6);
//! assert_eq!(path[0].confdata[3], 0); // cfx 0: the usual arm configuration
//! ```

pub mod confdata;
pub mod frame;
pub mod model;
pub mod path;

pub use frame::Frame;
pub use model::{
    JointLimitsDeg, Joints, ModelError, OpwGeometry, Robot, IRB1600_LIMITS_DEG, IRB2600_LIMITS_DEG,
};
pub use path::{PathError, PathSolution, ReachProblem};

#[cfg(test)]
mod tests;
