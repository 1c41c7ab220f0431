//! Where a machine's tool is, as a tf2 transform.

use cell_msgs::geometry_msgs::{Transform, TransformStamped, Vector3};
use cell_msgs::std_msgs::Header;
use cell_msgs::MachineStatus;

use crate::{frames, units};

/// The transform from the machine's frame ([`frames::machine`]) to its tool frame
/// ([`frames::tool`]): translation the X, Y and Z axis positions in metres (an axis the machine
/// lacks counts 0), rotation the identity. `None` when the status reports none of X, Y, Z (a
/// disconnected controller, a robot that reports no position). Stamp as the status.
pub fn tool_transform(status: &MachineStatus) -> Option<TransformStamped> {
    let axis = |name: &str| {
        status
            .axis_names
            .iter()
            .zip(&status.axis_positions)
            .find(|(a, _)| a.eq_ignore_ascii_case(name))
            .map(|(_, &mm)| units::mm_to_m(mm))
    };
    let (x, y, z) = (axis("X"), axis("Y"), axis("Z"));
    if x.is_none() && y.is_none() && z.is_none() {
        return None;
    }
    Some(TransformStamped {
        header: Header {
            stamp: status.header.stamp,
            frame_id: frames::machine(&status.machine_id),
        },
        child_frame_id: frames::tool(&status.machine_id),
        transform: Transform {
            translation: Vector3 {
                x: x.unwrap_or(0.0),
                y: y.unwrap_or(0.0),
                z: z.unwrap_or(0.0),
            },
            ..Default::default()
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tool_sits_at_the_xyz_axes_in_metres() {
        let mut status = MachineStatus {
            machine_id: "grbl-sim".into(),
            axis_names: vec!["X".into(), "Y".into(), "U".into(), "V".into()],
            axis_positions: vec![250.0, 40.0, 251.0, 41.0],
            ..Default::default()
        };
        let t = tool_transform(&status).expect("has X and Y");
        assert_eq!(t.header.frame_id, "grbl-sim");
        assert_eq!(t.child_frame_id, "grbl-sim/tool");
        let v = t.transform.translation;
        assert_eq!((v.x, v.y, v.z), (0.25, 0.04, 0.0));
        assert_eq!(t.transform.rotation.w, 1.0);
        status.axis_positions.clear();
        assert!(tool_transform(&status).is_none());
    }
}
