//! Reachability and robot configuration of the robtargets, for a profile with a `robot`
//! section (`cell_profiles::RobotSection`).
//!
//! Each robtarget, as written (positions to 1 µm, quaternions to 6 places), is taken to the
//! world through the work object (`uframe · oframe · target`) and solved for the flange with
//! the tool's TCP (`cell_kinematics`, OPW inverse kinematics): the whole program is one path
//! of linear moves in one arm configuration (`cfx`), joints continuous and inside their
//! ranges ([`cell_kinematics::Robot::solve_path`]). Every robtarget then carries its computed
//! `[cf1, cf4, cf6, cfx]` and `main` starts with `ConfL \On`, so the controller stops rather
//! than reach a point in another configuration. A point that cannot be reached that way is
//! [`EmitError::Reach`], naming its layer, segment and point.
//!
//! Without a `robot` section nothing is solved: every robtarget carries the profile's fixed
//! `rapid.robconf` and `ConfL \Off` (when `rapid.confl_off`) lets the controller pick the
//! configuration nearest it.

use cell_kinematics::{Frame, OpwGeometry, PathSolution, Robot};
use cell_msgs::Toolpath;
use cell_profiles::{MachineProfile, RapidSettings};

use super::{Move, POSITION_DECIMALS, QUATERNION_DECIMALS};
use crate::EmitError;

/// A profile's robot with its tool and work object.
#[derive(Debug, Clone)]
pub struct RobotCell {
    /// The arm standing in the world.
    pub robot: Robot,
    /// The TCP in the flange frame (`tooldata.tframe`).
    pub tool: Frame,
    /// The work object in the world (`uframe · oframe`).
    pub wobj: Frame,
}

impl RobotCell {
    /// The robot, tool and work object of `profile`; `None` without a `robot` section.
    ///
    /// # Errors
    /// [`EmitError::MissingSection`] without a `rapid` section; a robot model the solver
    /// rejects (a profile that passed validation has none).
    pub fn of(profile: &MachineProfile) -> Result<Option<Self>, EmitError> {
        let Some(section) = &profile.robot else {
            return Ok(None);
        };
        let r = super::rapid_section(profile)?;
        let o = &section.opw;
        let geometry = OpwGeometry {
            a1_mm: o.a1_mm,
            a2_mm: o.a2_mm,
            b_mm: o.b_mm,
            c1_mm: o.c1_mm,
            c2_mm: o.c2_mm,
            c3_mm: o.c3_mm,
            c4_mm: o.c4_mm,
            offsets_deg: o.offsets_deg,
            signs: o.signs,
        };
        let base = Frame::new(section.base.trans_mm, section.base.quat);
        // The profile's validation checks what the model checks; a profile built in code
        // past it gets this error.
        let robot = Robot::new(geometry, section.joint_limits_deg, base).map_err(|_| {
            EmitError::NoAxis {
                profile: profile.name.clone(),
                what: "a valid robot model (check the robot section)",
            }
        })?;
        Ok(Some(Self {
            robot,
            tool: tool_frame(r),
            wobj: wobj_frame(r),
        }))
    }

    /// The world frame of a robtarget `[position, quaternion]` in the work object.
    pub fn target_in_world(&self, position: [f64; 3], quat: [f64; 4]) -> Frame {
        self.wobj.then(&Frame::new(position, quat))
    }
}

/// The tool's TCP in the flange frame; `tool0` (no value) is the flange itself.
fn tool_frame(r: &RapidSettings) -> Frame {
    r.tool
        .value
        .as_ref()
        .map_or(Frame::IDENTITY, |t| Frame::new(t.tcp_mm, t.tcp_quat))
}

/// The work object in the world, `uframe · oframe`; `wobj0` (no value) is the world.
fn wobj_frame(r: &RapidSettings) -> Frame {
    r.wobj.value.as_ref().map_or(Frame::IDENTITY, |w| {
        Frame::new(w.uframe_mm, w.uframe_quat).then(&Frame::new(w.oframe_mm, w.oframe_quat))
    })
}

/// `v` rounded to `decimals` places, as the module writes it.
fn as_written(v: f64, decimals: usize) -> f64 {
    let scale = 10f64.powi(decimals as i32);
    (v * scale).round() / scale
}

/// Solves every move (module docs) and sets its `robconf`; nothing without a robot section.
/// `at` gives each move's (segment, point) for errors.
pub(super) fn assign_robconf(
    moves: &mut [Move],
    at: &[(usize, usize)],
    toolpath: &Toolpath,
    profile: &MachineProfile,
) -> Result<(), EmitError> {
    let Some(cell) = RobotCell::of(profile)? else {
        return Ok(());
    };
    let targets: Vec<Frame> = moves
        .iter()
        .map(|m| {
            cell.target_in_world(
                m.position.map(|v| as_written(v, POSITION_DECIMALS)),
                m.quat.map(|v| as_written(v, QUATERNION_DECIMALS)),
            )
        })
        .collect();
    let path: Vec<PathSolution> = cell.robot.solve_path(&targets, &cell.tool).map_err(|e| {
        let (segment, point) = at.get(e.index).copied().unwrap_or((0, e.index));
        let [x, y, z] = moves[e.index].position;
        EmitError::Reach {
            layer: toolpath.segments.get(segment).map_or(0, |s| s.layer),
            segment,
            point,
            x,
            y,
            z,
            problem: e.problem,
        }
    })?;
    for (m, s) in moves.iter_mut().zip(&path) {
        m.robconf = Some(s.confdata);
    }
    Ok(())
}
