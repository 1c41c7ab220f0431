//! What a line commands besides its modal state: the moves for the planner and the
//! synchronisation it needs.

/// How fast a move goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Speed {
    /// At the rapid rate (times the rapid override).
    Rapid,
    /// At a feed (mm/s, before the feed override).
    Feed(f64),
}

/// A move the line commands.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Move {
    pub target: Vec<f64>,
    pub length_mm: f64,
    pub speed: Speed,
}

/// What executing a line does, besides the modal state it leaves.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Action {
    /// Moves for the planner, in order (empty moves already dropped).
    pub moves: Vec<Move>,
    /// G4 dwell (s).
    pub dwell_s: Option<f64>,
    /// The line must wait for the planner to empty (spindle/coolant changes, M0/M1/M2/M30,
    /// dwell, G10, G28/G30, G92).
    pub sync: bool,
    /// M2/M30.
    pub program_end: bool,
    /// M0/M1 (feed hold after the planner empties).
    pub pause: bool,
}

impl Action {
    /// Adds a straight move from `from` to `to` (dropped if shorter than 1 nm).
    pub(super) fn push_line(&mut self, from: &[f64], to: &[f64], speed: Speed) {
        let length = from
            .iter()
            .zip(to)
            .map(|(a, b)| (b - a).powi(2))
            .sum::<f64>()
            .sqrt();
        self.push_move(to.to_vec(), length, speed);
    }

    /// Adds a move of `length_mm` ending at `target` (dropped if shorter than 1 nm).
    pub(super) fn push_move(&mut self, target: Vec<f64>, length_mm: f64, speed: Speed) {
        if length_mm > 1e-9 {
            self.moves.push(Move {
                target,
                length_mm,
                speed,
            });
        }
    }
}
