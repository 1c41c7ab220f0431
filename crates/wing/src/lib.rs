//! `cell_wing`: G-Wing (seed 002, Valenti, Bartolai, Yukish, "G-Wing: toolpath-centric design
//! of wings for material extrusion"), pure library. "The notes" in its comments are the
//! implementer's notes, `docs/notes/seed-notes-hotwire-gwing.md` (part SEED 002).
//!
//! - [`llt`]: matrix lifting-line theory and the six design cases of Table 1.
//! - [`structure`]: spar locations X_sp (Algorithm 1).
//! - [`section`]: the wing split into printable sections (eq. 1, per semispan).
//! - [`layers`]: per-layer toolpaths: perimeter, spars, first-layer rib, with E, Z-hop and
//!   retract (Algorithm 2).
//! - [`estimate`]: mass and build time.
//! - [`spec`]: the wing spec (YAML) and the whole pipeline.
//! - [`msg`]: the layers as a `cell_msgs::Toolpath` for the emitter.

#![warn(missing_docs)]

pub mod estimate;
pub mod layers;
pub mod llt;
pub mod msg;
pub mod section;
pub mod spec;
pub mod structure;
