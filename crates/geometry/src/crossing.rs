//! Whether a straight travel move crosses printed walls: the extrusion Z-hop rule the wing
//! toolpaths (`cell_wing::layers::moves`) and the G-code emitter share, so the planned moves
//! and the program as written lift the nozzle on the same travels.

use crate::distance::segment_distance;
use crate::point::{AsPoint2, Norm};

/// How far from each end of a travel a wall may touch it without counting as crossed \[mm\]:
/// a travel starts on the end of the stroke it leaves and may end on a wall it starts from,
/// so contacts within a micron of its ends (far below any bead width) are that, not a crossing.
pub const TRAVEL_END_CLEARANCE_MM: f64 = 1e-3;

/// True when the straight move a → b meets any edge of any of the open `polylines` other than
/// within [`TRAVEL_END_CLEARANCE_MM`] of a or b (the move is shortened by that much at both
/// ends, then tested by [`segment_distance`] = 0, which counts touching as meeting). A move no
/// longer than twice the clearance (or of NaN length) crosses nothing. Polylines of one point
/// have no edges.
///
/// This is the rule of Cura's "Z Hop Only Over Printed Parts" on bead centre lines: lift the
/// nozzle only where the travel passes over a wall already laid in this layer.
pub fn travel_crosses_polylines<P: AsPoint2, L: AsRef<[P]>>(
    a: impl AsPoint2,
    b: impl AsPoint2,
    polylines: impl IntoIterator<Item = L>,
) -> bool {
    let (a, b) = (a.point2(), b.point2());
    let length = Norm::Sqrt.distance(a, b);
    if length.is_nan() || length <= 2.0 * TRAVEL_END_CLEARANCE_MM {
        return false;
    }
    let step = (b - a) * (TRAVEL_END_CLEARANCE_MM / length);
    let (a, b) = (a + step, b - step);
    polylines.into_iter().any(|line| {
        line.as_ref()
            .windows(2)
            .any(|e| segment_distance(a, b, e[0], e[1], Norm::Sqrt) == 0.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossings_count_but_contacts_at_the_ends_do_not() {
        let wall = [[0.0, -1.0], [0.0, 1.0]];
        assert!(travel_crosses_polylines(
            [-1.0, 0.0],
            [1.0, 0.0],
            [&wall[..]]
        ));
        // Leaving the wall's end, or arriving on it: no crossing.
        assert!(!travel_crosses_polylines(
            [0.0, 1.0],
            [1.0, 1.0],
            [&wall[..]]
        ));
        assert!(!travel_crosses_polylines(
            [-1.0, 0.5],
            [0.0, 0.5],
            [&wall[..]]
        ));
        // Passing beside it, or stopping short of it.
        assert!(!travel_crosses_polylines(
            [0.1, -2.0],
            [0.1, 2.0],
            [&wall[..]]
        ));
        assert!(!travel_crosses_polylines(
            [-1.0, 0.0],
            [-0.01, 0.0],
            [&wall[..]]
        ));
        // Running along it counts (collinear overlap), a zero-length move never does.
        assert!(travel_crosses_polylines(
            [0.0, -2.0],
            [0.0, 2.0],
            [&wall[..]]
        ));
        assert!(!travel_crosses_polylines(
            [0.0, 0.0],
            [0.0, 0.0],
            [&wall[..]]
        ));
        // Any of several polylines, and a closed ring's far side.
        let ring = [
            [2.0, -1.0],
            [4.0, -1.0],
            [4.0, 1.0],
            [2.0, 1.0],
            [2.0, -1.0],
        ];
        assert!(travel_crosses_polylines(
            [3.0, 0.0],
            [5.0, 0.0],
            [&wall[..], &ring[..]]
        ));
        assert!(!travel_crosses_polylines(
            [3.0, 0.0],
            [2.5, 0.5],
            [&wall[..], &ring[..]]
        ));
        assert!(!travel_crosses_polylines(
            [3.0, 0.0],
            [5.0, 0.0],
            Vec::<&[[f64; 2]]>::new()
        ));
    }
}
