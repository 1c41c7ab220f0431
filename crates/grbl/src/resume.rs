//! Resuming a program from a line after the controller was reset: the machine state the program
//! had there, rebuilt from the lines before it, and the lines that restore it (the *preamble*).
//!
//! After a safe stop (feed hold, soft reset, `M5`) GRBL is in its reset state: `G0 G54 G17 G21
//! G90 G94 M5 M9`, F0, S0. Resumed from line N in that state, a G93 hot-wire program would go on
//! in G94 with the wire cold, a laser program with the beam off. [`preamble`] rebuilds, from the
//! lines before N, the state GRBL would hold at N, and writes the lines that put a controller
//! there; the caller sends them, each acknowledged, before line N. They are not program lines:
//! they take no part in the line accounting.
//!
//! The preamble, in order (it repeats what the emitter writes to start a cut, `cell_emitter`'s
//! `power_on`: `G0 Z{pierce}`, `M3 S…`, `G4 P…`, `G1 Z{cut} F…`):
//! 1. `M5 M9`: heat and coolant off while the tool moves into place, also on a controller that
//!    was not reset.
//! 2. The frame: plane, units, `G90` and work coordinate system (`G17 G21 G90 G54`), with
//!    `G92.1` when the program used G92.
//! 3. Into place with the heat off, in rapids: Z up to the travel height when the program
//!    moves Z (the Z of its last rapid that moved other axes); the other axes to where the
//!    program was before line N, which is where line N starts; Z down to the pierce height
//!    (the Z at which the program switched the heat on for the cut in progress) when the heat
//!    is on at N, else to the Z line N starts at.
//! 4. The heat, as the program switched it on for that cut: coolant (`M7`, `M8`), `M3`/`M4`
//!    with the S it used then, the dwell that followed (`G4 P`: pierce time, or a hot wire's
//!    pre-heat), and, when the pierce height is not the height at N, the feed move down to it
//!    at the feed of the program's own plunge (the first Z-only feed move after the heat-on).
//! 5. The modal words line N relies on: motion mode (unless line N names one), distance mode,
//!    feed mode with the last F (G94; under G93 every feed line carries its own F, so the F
//!    written there only makes a bare `G1` legal), the S in effect at N (a program may change
//!    S during a cut) and the tool number.
//!
//! The way into place is a straight rapid from where the machine stopped. A feed hold stops
//! the machine on the path of the line it was running, so resuming from that line (the first
//! one not executed) runs back along its own kerf; a hot wire goes back cold and heats up where
//! it cuts on, as at the start of the program.
//!
//! Groups the program never sets get GRBL's reset values, the state the program started from
//! when it started after a reset. An axis whose place the text does not tell (never moved, or
//! moved by `G28`/`G30`, a `G53` move, `$H` or `$J=`, a change of coordinate system, an
//! incremental move from an unknown place) is left where the machine has it, which is where
//! the program left it; that is refused, naming the line that lost it, only when line N moves
//! that axis and where it starts matters (an incremental move, an arc, or a cut with the heat
//! on; an absolute straight move with the heat off ends at the same place from anywhere).
//! The preamble is also refused, naming the line, for commands outside GRBL's modal set
//! (`G41`/`G42` cutter compensation, `G43.1` tool length offsets, `G38` probing, `M6`, unknown
//! words), a G92 offset still in effect at N, and an arc mode that line N or a line after it
//! moves in without naming `G2`/`G3` (no arc mode can be set without moving). Other controller
//! commands the controller file allows (`$` lines) leave the modal state as it is.

mod preamble;
mod state;

use crate::program::Program;

use state::ModalState;

/// Why a program cannot be resumed from a line: the line whose state the preamble cannot
/// restore, and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line} (`{text}`): {reason}")]
pub struct ResumeError {
    /// Original line number.
    pub line: usize,
    /// The line as sent.
    pub text: String,
    /// Why.
    pub reason: String,
}

/// The lines that put a controller fresh from a reset into the state `program` had before its
/// line `from_line` (module documentation), to send before streaming from `from_line`. Empty
/// when `from_line` is the program's first line (or before it, or past its end).
///
/// # Errors
/// A line before `from_line` (or `from_line` itself) that leaves a state the preamble cannot
/// restore, named with its reason.
pub fn preamble(program: &Program, from_line: usize) -> Result<Vec<String>, ResumeError> {
    let lines = program.lines();
    let Some(at) = program.index_of_line(from_line).filter(|&i| i > 0) else {
        return Ok(Vec::new());
    };
    let error = |line: usize, reason: String| ResumeError {
        line,
        text: lines
            .iter()
            .find(|l| l.number == line)
            .map(|l| l.text.clone())
            .unwrap_or_default(),
        reason,
    };
    let mut state = ModalState::new();
    for l in &lines[..at] {
        state
            .apply(l.number, &l.text)
            .map_err(|r| error(l.number, r))?;
    }
    preamble::lines(&state, &lines[at..]).map_err(|(line, r)| error(line, r))
}

#[cfg(test)]
mod tests;
