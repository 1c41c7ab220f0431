//! [`winding_number`] against `cavalier_contours`' `winding_number` on polylines without arcs,
//! which the sequencer used before: the same integer for every ring and point, including points
//! on vertices and edges (the boundary rule must match too, not just the interior).

use cavalier_contours::core::math::Vector2;
use cavalier_contours::polyline::{PlineCreation, PlineSource, PlineSourceMut, Polyline};
use cell_geometry::{point_in_ring_nonzero, winding_number};
use proptest::prelude::*;

fn cavalier(ring: &[[f64; 2]], p: [f64; 2]) -> i32 {
    let mut pl = Polyline::with_capacity(ring.len(), true);
    for q in ring {
        pl.add(q[0], q[1], 0.0);
    }
    pl.winding_number(Vector2::new(p[0], p[1]))
}

/// Coordinates on a coarse grid, so vertices, edges and probes often coincide exactly.
fn coord() -> impl Strategy<Value = f64> {
    (-4i32..=4).prop_map(|k| f64::from(k) * 0.5)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn same_winding_number_as_cavalier_contours(
        ring in prop::collection::vec([coord(), coord()], 0..8),
        probe in [coord(), coord()],
        vertex in any::<prop::sample::Index>(),
    ) {
        prop_assert_eq!(winding_number(probe, &ring), cavalier(&ring, probe));
        if !ring.is_empty() {
            // On a vertex, and on the midpoint of the edge leaving it.
            let i = vertex.index(ring.len());
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            prop_assert_eq!(winding_number(a, &ring), cavalier(&ring, a));
            prop_assert_eq!(winding_number(mid, &ring), cavalier(&ring, mid));
            prop_assert_eq!(point_in_ring_nonzero(mid, &ring), cavalier(&ring, mid) != 0);
        }
    }

    #[test]
    fn same_winding_number_off_the_grid(
        ring in prop::collection::vec([-10.0..10.0f64, -10.0..10.0f64], 3..12),
        probe in [-10.0..10.0f64, -10.0..10.0f64],
    ) {
        prop_assert_eq!(winding_number(probe, &ring), cavalier(&ring, probe));
    }
}
