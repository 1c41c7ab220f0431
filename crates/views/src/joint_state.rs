//! A `MachineStatus`'s axis positions as a `sensor_msgs/JointState`.

use cell_msgs::sensor_msgs::JointState;
use cell_msgs::std_msgs::Header;
use cell_msgs::MachineStatus;

use crate::{frames, units};

/// Whether an axis is rotary: the G-code rotary axes A, B and C (degrees); every other axis
/// (X, Y, Z, U, V, W, …) is linear (millimetres).
pub fn is_rotary(axis: &str) -> bool {
    matches!(axis, "A" | "B" | "C" | "a" | "b" | "c")
}

/// The machine's axes as joints: names `<machine frame>/<axis>` (e.g. `grbl-sim/X`, unique
/// across machines), positions in SI (linear axes mm → m, rotary axes deg → rad,
/// [`is_rotary`]), no velocities or efforts. Stamp as the status; frame the machine's
/// ([`frames::machine`]). Axis names without a position are left out.
pub fn joint_state(status: &MachineStatus) -> JointState {
    let machine = frames::machine(&status.machine_id);
    let (name, position) = status
        .axis_names
        .iter()
        .zip(&status.axis_positions)
        .map(|(axis, &value)| {
            let si = if is_rotary(axis) {
                units::deg_to_rad(value)
            } else {
                units::mm_to_m(value)
            };
            (format!("{machine}/{axis}"), si)
        })
        .unzip();
    JointState {
        header: Header {
            stamp: status.header.stamp,
            frame_id: machine,
        },
        name,
        position,
        velocity: Vec::new(),
        effort: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_become_joints_in_si_units() {
        let status = MachineStatus {
            machine_id: "grbl-sim".into(),
            axis_names: vec!["X".into(), "Y".into(), "U".into(), "A".into(), "V".into()],
            axis_positions: vec![120.0, -35.5, 0.0, 90.0],
            ..Default::default()
        };
        let js = joint_state(&status);
        assert_eq!(
            js.name,
            ["grbl-sim/X", "grbl-sim/Y", "grbl-sim/U", "grbl-sim/A"]
        );
        assert_eq!(js.position[..3], [0.12, -0.0355, 0.0]);
        assert!((js.position[3] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!(js.velocity.is_empty() && js.effort.is_empty());
        assert_eq!(js.header.frame_id, "grbl-sim");
    }
}
