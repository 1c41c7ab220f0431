//! `cell_geometry`: the plane geometry the algorithm crates share, each routine written once:
//! ring area and orientation ([`signed_area`], [`orientation`]), point-in-ring by crossing
//! number and by winding number ([`point_in_ring_even_odd`], [`winding_number`]), point and
//! segment distances ([`point_segment_distance`], [`segment_distance`]), polyline length and
//! resampling ([`polyline_length`], [`resample_max_step`], [`sample_at_arc_fractions`],
//! [`point_at_arc_length`]), bounding boxes ([`bounding_box`]), whether a travel crosses printed
//! walls ([`travel_crosses_polylines`]).
//!
//! **One point type.** [`Point2`] and [`Point3`] are nalgebra's `Point2<f64>` and
//! `Point3<f64>`, which the airfoil, planner, wing and emitter crates already use. The mesh,
//! WAAM and sequencer crates keep their points as `[f64; 2]`: there the array is the data
//! format (serialised layouts, slicer contours, the message views) and is indexed in hundreds
//! of lines, so rewriting it would be a large change for no gain. Instead every routine here
//! takes any [`AsPoint2`] (`Point2`, `[f64; 2]`, or a reference to either) and converts it to
//! a [`Point2`] (a copy of two floats), and the routines that build points return the caller's
//! own type (`P: From<Point2>`, which both types are). So the helpers exist once and no caller
//! copies its rings to use them.
//!
//! **Rings.** A ring is a closed polygon given by its vertices, the closing edge (last → first)
//! implied. A repeated closing point is allowed: it adds a zero-length edge, which changes no
//! area, crossing count or winding number. Nothing here checks simplicity; on a
//! self-intersecting ring the area is the winding-weighted area and the two point-in-ring
//! rules disagree where the winding number is even and non-zero.
//!
//! **Bit-identical results.** The routines replaced copies whose results are pinned by tests
//! and fixtures, so each keeps the floating-point operation order of the copy it replaced; where
//! the copies differed, both variants are here and named:
//! - the length of a vector is rounded one of two ways ([`Norm`]): `√(dx² + dy²)` as nalgebra's
//!   `norm()` (planner, airfoil, the sequencer's improvement moves) or `dx.hypot(dy)` (WAAM
//!   toolpaths, the sequencer's layouts, costs and cut paths, the probe's test block);
//! - the shoelace area sums `xᵢyᵢ₊₁ − xᵢ₊₁yᵢ` ([`signed_area`]: airfoil, WAAM, sequencer,
//!   slicer) or a fan of triangles about the first vertex ([`signed_area_from_first_vertex`]:
//!   mesh slicer, smaller cancellation far from the origin);
//! - the crossing-number test takes the ring as an iterator, so a caller that walked the edges
//!   backwards (the mesh slicer) passes `ring.iter().rev()` and keeps its crossing abscissae.

#![warn(missing_docs)]

mod area;
mod bounds;
mod crossing;
mod distance;
mod inside;
mod point;
mod polyline;

pub use area::{orientation, signed_area, signed_area_from_first_vertex, Orientation};
pub use bounds::bounding_box;
pub use crossing::{travel_crosses_polylines, TRAVEL_END_CLEARANCE_MM};
pub use distance::{
    closest_point_on_segment, distance_to_rings, point_segment_distance, segment_distance,
};
pub use inside::{
    point_in_ring_even_odd, point_in_ring_nonzero, point_in_rings_even_odd, point_in_rings_or_near,
    winding_number,
};
pub use point::{AsPoint2, Norm, Point2, Point3};
pub use polyline::{
    closed_from_arc_length, cumulative_lengths, distance3, point_at_arc_length, polyline_length,
    polyline_length3, resample_max_step, ring_perimeter, sample_at_arc_fractions,
};
