//! Frame ids of the views (REP-103 conventions: right-handed, x forward, z up, metres).
//!
//! - [`CELL`] is the fixed frame (RViz's "Fixed Frame", Foxglove's display frame).
//! - Each message keeps its own `header.frame_id` (`hotwire_machine`, `sheet`, the slicer's work
//!   object, …); the node publishing its view attaches that frame to [`CELL`] on `/tf_static`
//!   with the identity ([`attach_to_cell`]), so every view shows without further set-up. A cell
//!   with a real layout replaces those identities by publishing its own transforms.
//! - A machine's frame is its `machine_id` ([`machine`]); its tool frame is
//!   `<machine_id>/tool` ([`tool`]), moved by the machine's X, Y, Z axes.

use cell_msgs::builtin_interfaces::Time;
use cell_msgs::geometry_msgs::{Transform, TransformStamped};
use cell_msgs::std_msgs::Header;

/// The fixed frame every view hangs from.
pub const CELL: &str = "cell";

/// A message's frame id for its view: its own, without a leading `/` (tf2 refuses those), or
/// [`CELL`] when it has none.
pub fn of_header(header: &Header) -> String {
    let id = header.frame_id.trim_start_matches('/');
    if id.is_empty() {
        CELL.to_owned()
    } else {
        id.to_owned()
    }
}

/// A machine's frame: its `machine_id` without a leading `/`, or `machine` when empty.
pub fn machine(machine_id: &str) -> String {
    let id = machine_id.trim_start_matches('/');
    if id.is_empty() {
        "machine".to_owned()
    } else {
        id.to_owned()
    }
}

/// A machine's tool frame: `<machine frame>/tool`.
pub fn tool(machine_id: &str) -> String {
    format!("{}/tool", machine(machine_id))
}

/// A machine's heater's frame (`sensor_msgs/Temperature`'s frame id): `<machine frame>/<heater>`,
/// e.g. `marlin-sim/hotend`.
pub fn heater(machine_id: &str, heater: &str) -> String {
    format!("{}/{heater}", machine(machine_id))
}

/// The identity transform that puts `frame` at [`CELL`]'s origin (for `/tf_static`), or `None`
/// when `frame` is [`CELL`] itself.
pub fn attach_to_cell(frame: &str, stamp: Time) -> Option<TransformStamped> {
    (frame != CELL).then(|| TransformStamped {
        header: Header {
            stamp,
            frame_id: CELL.to_owned(),
        },
        child_frame_id: frame.to_owned(),
        transform: Transform::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_named_and_attached() {
        let h = |id: &str| Header {
            frame_id: id.into(),
            ..Default::default()
        };
        assert_eq!(of_header(&h("/sheet")), "sheet");
        assert_eq!(of_header(&h("")), CELL);
        assert_eq!(tool("grbl-sim"), "grbl-sim/tool");
        assert_eq!(machine(""), "machine");
        let t = attach_to_cell("sheet", Time::default()).expect("not the cell");
        assert_eq!(
            (t.header.frame_id.as_str(), t.child_frame_id.as_str()),
            ("cell", "sheet")
        );
        assert_eq!(t.transform.rotation.w, 1.0);
        assert!(attach_to_cell(CELL, Time::default()).is_none());
    }
}
