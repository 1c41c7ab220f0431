//! `cell_mesh`: STL input and planar Z-slicing for the WAAM slicer (seed 004, issue 8).
//!
//! Pure library: no ROS. The pipeline is
//! 1. [`Mesh::load_stl`] — ASCII or binary STL via `stl_io`, corners welded within a tolerance
//!    ([`WeldTolerance`], default 1e-6 × bounding-box diagonal), an edge table, and a
//!    [`MeshReport`] of holes, non-manifold edges, flipped windings and degenerate triangles.
//!    Bad files give a [`MeshError`] naming the file (and triangle); nothing panics.
//! 2. [`slice()`] — planes at `z_k = first_z + k·h` (default `first_z = z_min + h/2`, mid-layer),
//!    a sweep over triangles sorted by lowest z with an active set, so each triangle is touched
//!    only for the layers it spans; the triangle–plane intersection of seed 004 eqs. 8–11 with a
//!    half-open rule (a corner with `z == plane` counts as above) so planes through vertices or
//!    faces lose and double nothing.
//! 3. Chaining: segments are linked through the mesh edge they cross (exact, no tolerance), then
//!    leftover open chains are joined end to end within a tolerance (triangle soup); what still
//!    stays open is reported per layer in [`Layer::open_chains`].
//! 4. Orientation by nesting depth: outer contours counter-clockwise, holes clockwise.
//!
//! The contract for the toolpath crate: a [`Contour`] is a closed polygon `Vec<[f64; 2]>` (mm)
//! without a repeated last point.

pub mod error;
pub mod mesh;
pub mod slice;

pub use error::{MeshError, SliceError};
pub use mesh::{Mesh, MeshOptions, MeshReport, StlFormat, WeldTolerance};
pub use slice::{
    slice, Contour, Layer, LayerStack, LayerStackResult, OpenChain, SliceParams, MAX_LAYERS,
};
