//! The targets, one file per family.

pub mod airfoil;
pub mod bag;
pub mod config;
pub mod grbl;
pub mod layout;
pub mod marlin;
pub mod mesh;
pub mod msgs;
pub mod rws;
mod serial;
