//! The parser's modal state as a host can compare it: what `$G` reports, group by group, and
//! where the parser is. Recorded after every executed line ([`ExecutedLine::parser`]) and kept
//! current for [`SimHandle::parser_state`], so a test can tell whether a resumed program runs
//! a line in the same state as an uninterrupted one.
//!
//! [`ExecutedLine::parser`]: super::ExecutedLine::parser
//! [`SimHandle::parser_state`]: super::SimHandle::parser_state

use super::gcode::Modal;

/// The parser's modal state, as `$G` reports it, and its position.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParserState {
    /// Motion mode: `G0`, `G1`, `G2`, `G3` or `G80`.
    pub motion: String,
    /// Work coordinate system: `G54` … `G59`.
    pub coordinate_system: String,
    /// Plane: `G17`, `G18` or `G19`.
    pub plane: String,
    /// Units: `G20` or `G21`.
    pub units: String,
    /// Distance mode: `G90` or `G91`.
    pub distance: String,
    /// Feed mode: `G93` or `G94`.
    pub feed_mode: String,
    /// Spindle (the heat): `M3`, `M4` or `M5`.
    pub spindle: String,
    /// Coolant: `M9`, `M7`, `M8` or `M7 M8`.
    pub coolant: String,
    /// Tool number.
    pub tool: String,
    /// F as `$G` prints it (units per minute, or the inverse-time F under G93).
    pub feed: String,
    /// S as `$G` prints it.
    pub spindle_speed: String,
    /// Where the parser is (the end of the last move it took), work coordinates (mm).
    pub work_position: Vec<f64>,
}

impl ParserState {
    /// The state of `modal`, read from its `$G` report.
    pub(super) fn of(modal: &Modal) -> ParserState {
        let report = modal.gc_report();
        let words: Vec<&str> = report.split(' ').collect();
        let group = |k: usize| words.get(k).copied().unwrap_or_default().to_string();
        let with = |prefix: char| {
            words
                .iter()
                .skip(7)
                .filter(|w| w.starts_with(prefix))
                .copied()
                .collect::<Vec<_>>()
                .join(" ")
        };
        ParserState {
            motion: group(0),
            coordinate_system: group(1),
            plane: group(2),
            units: group(3),
            distance: group(4),
            feed_mode: group(5),
            spindle: group(6),
            coolant: with('M'),
            tool: with('T'),
            feed: with('F'),
            spindle_speed: with('S'),
            work_position: modal
                .position
                .iter()
                .zip(modal.wco())
                .map(|(p, o)| p - o)
                .collect(),
        }
    }
}

impl std::fmt::Display for ParserState {
    /// The `$G` body, then the work position.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {} {} {} {} {} {} {} {} {} {} at {:?}",
            self.motion,
            self.coordinate_system,
            self.plane,
            self.units,
            self.distance,
            self.feed_mode,
            self.spindle,
            self.coolant,
            self.tool,
            self.feed,
            self.spindle_speed,
            self.work_position
        )
    }
}
