//! The simulator's G-code parser: GRBL 1.1's `gc_execute_line` checks for a useful subset of
//! RS274/NGC, returning the same `error:N` codes, and the motion a line commands.
//!
//! Input is a line as GRBL stores it: spaces and comments already removed, upper case.
//! Positions are in millimetres, machine coordinates.
//!
//! A line goes through three steps, each stopping at the first error as GRBL does:
//! 1. `lex`: split into words (`error:1`, `2`, `20`, `23`, `25`);
//! 2. `groups`: G and M commands checked one per modal group and applied to a copy of the
//!    modal state (`error:20`, `21`, `29`, and `16` for a bad jog);
//! 3. `apply`: value words, the non-modal command and the motion (with `arc` for G2/G3), then
//!    the check for unused words (`error:36`).

mod action;
mod apply;
mod arc;
mod code;
mod groups;
mod lex;
mod modal;

pub(crate) use action::{Action, Move, Speed};
pub(crate) use modal::{Modal, MotionMode, Spindle};

/// Parses and checks one stored line against `modal`; on success returns the new modal state
/// and what the line does. `axes` are the configured axis letters. `jog` applies `$J=` rules
/// (G91/G90/G20/G21/G53/F/axes only, feed required, modal state left untouched except the
/// parser position).
pub(crate) fn execute(
    modal: &Modal,
    line: &str,
    axes: &[char],
    jog: bool,
) -> Result<(Modal, Action), u8> {
    let words = lex::lex(line, axes)?;
    let groups = groups::check(modal, &words, jog)?;
    apply::apply(modal, &words, groups, axes, jog)
}

#[cfg(test)]
mod tests;
