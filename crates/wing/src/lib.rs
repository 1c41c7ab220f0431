//! `cell_wing`: G-Wing (seed 002, Valenti, Bartolai, Yukish, "G-Wing: toolpath-centric design
//! of wings for material extrusion"), pure library. "The notes" in its comments are the
//! implementer's notes, `docs/notes/seed-notes-hotwire-gwing.md` (part SEED 002).
//!
//! - [`llt`]: matrix lifting-line theory and the six design cases of Table 1.
//! - [`avl`]: the AVL geometry file (vortex-lattice input) of a designed wing.
//! - [`crosscheck`]: the lifting line beside a vortex-lattice solution of the same wing.
//! - [`structure`]: spar locations X_sp (Algorithm 1).
//! - [`spacing`]: the AM spar spacing rule (Algorithm 1 step 5, ref. \[8\]).
//! - [`section`]: the wing split into printable sections (eq. 1, per semispan).
//! - [`layers`]: per-layer toolpaths: perimeter, spars, first-layer rib, with E, Z-hop and
//!   retract (Algorithm 2).
//! - [`estimate`]: mass and build time.
//! - [`marlin`]: print time as Marlin 2's planner spends it, and Pronterface's estimate.
//! - [`design`]: the spec's design case (`aero.design`): the six cases' inputs, checks and solve.
//! - [`spec`]: the wing spec (YAML) and the whole pipeline.
//! - [`scad`]: the OpenSCAD model (OML and spar walls) from the design, not the G-code.
//! - [`picture`]: the planform picture (seed 002 Fig. 7): edges, hinge, spars, section
//!   breaks, and c, α, ℓ against y.
//! - [`msg`]: the layers as a `cell_msgs::Toolpath` for the emitter.

#![warn(missing_docs)]

pub mod avl;
pub mod crosscheck;
pub mod design;
pub mod estimate;
pub mod layers;
pub mod llt;
pub mod marlin;
pub mod msg;
pub mod picture;
pub mod scad;
pub mod section;
pub mod spacing;
pub mod spec;
pub mod structure;
