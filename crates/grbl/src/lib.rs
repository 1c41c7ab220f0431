//! GRBL 1.1 for cellsuite's machine bridge, with no ROS in it: a streaming client that behaves
//! like the best senders (character counting or send-response, status polling, real-time
//! commands, safe stop, resume after a link drop) and a GRBL 1.1 protocol simulator.
//!
//! - [`firmware`]: which firmware answers (GRBL, grblHAL, FluidNC banners), `$I` buffer sizes,
//!   the spindle word of `$G`.
//! - [`protocol`]: real-time bytes, response and status-report parsing, error/alarm tables.
//! - [`program`]: a program cleaned for streaming, with original line numbers kept.
//! - [`resume`]: the machine state a program had at a line, and the lines that restore it
//!   before a resume from there ([`words`] splits the lines into words).
//! - [`resume_point`]: the line to resume from after a safe stop flushed the planner.
//! - [`transport`]: TCP, serial, pty behind one trait.
//! - [`stream`]: the streaming client ([`stream::GrblClient`]).
//! - [`cycle_start`]: resume from a feed hold: wait for `Hold:0`, send `~`, confirm it was
//!   taken.
//! - [`sim`]: the simulator.

#![warn(missing_docs)]

pub mod cycle_start;
pub mod firmware;
pub mod program;
pub mod protocol;
pub mod resume;
pub mod resume_point;
pub mod sim;
pub mod stream;
pub mod transport;
pub mod words;
