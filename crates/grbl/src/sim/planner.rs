//! The planner: GRBL's 15-block motion queue, with the non-motion lines between its blocks kept
//! in program order so that each line is logged when it takes effect.

use super::gcode::{Move, Speed};
use super::machine::Machine;
use super::{ExecutedLine, ParserState};

/// An entry in the execution queue (the planner plus the non-motion lines between its blocks).
#[derive(Debug)]
pub(super) enum Entry {
    Motion(Block),
    Marker(LogLine),
}

/// A line for the executed-line log.
#[derive(Debug, Clone)]
pub(super) struct LogLine {
    pub(super) text: String,
    pub(super) seq: u64,
    pub(super) connection: u64,
    /// The parser's state right after the line.
    pub(super) parser: ParserState,
}

/// One planner block: a straight move or a whole arc.
#[derive(Debug)]
pub(super) struct Block {
    /// Where the move starts and ends (mm, machine coordinates).
    pub(super) start: Vec<f64>,
    pub(super) target: Vec<f64>,
    /// Path length (mm; an arc's true length) and how much of it is left.
    pub(super) length_mm: f64,
    pub(super) remaining_mm: f64,
    pub(super) speed: Speed,
    /// A `$J=` jog move (no feed override).
    pub(super) jog: bool,
    /// The move has begun (the state went to Run or Jog).
    pub(super) started: bool,
    /// The last move of a line carries the line for the log.
    pub(super) log: Option<LogLine>,
}

impl Machine {
    /// True if `blocks` more moves fit in the planner.
    pub(super) fn planner_has_room(&self, blocks: usize) -> bool {
        self.planner_used + blocks <= self.cfg.planner_blocks
    }

    /// Queues `moves` from `start`, the last one carrying `log`.
    pub(super) fn enqueue_moves(
        &mut self,
        start: Vec<f64>,
        moves: Vec<Move>,
        jog: bool,
        log: Option<LogLine>,
    ) {
        let n = moves.len();
        let mut start = start;
        for (i, m) in moves.into_iter().enumerate() {
            let b = Block {
                start: start.clone(),
                target: m.target.clone(),
                length_mm: m.length_mm,
                remaining_mm: m.length_mm,
                speed: m.speed,
                jog,
                started: false,
                log: if i + 1 == n { log.clone() } else { None },
            };
            start = m.target;
            self.queue.push_back(Entry::Motion(b));
            self.planner_used += 1;
        }
    }

    /// Queues a line without motion: logged now if the planner is empty, else when the planner
    /// reaches it.
    pub(super) fn enqueue_marker(&mut self, log: LogLine) {
        if self.queue.is_empty() {
            self.log(log);
        } else {
            self.queue.push_back(Entry::Marker(log));
        }
    }

    /// Where the queued moves end (the machine position if none).
    pub(super) fn queue_end_position(&self) -> Vec<f64> {
        self.queue
            .iter()
            .rev()
            .find_map(|e| match e {
                Entry::Motion(b) => Some(b.target.clone()),
                Entry::Marker(_) => None,
            })
            .unwrap_or_else(|| self.pos.clone())
    }

    /// The head block has run: its line goes to the log.
    pub(super) fn finish_head(&mut self) {
        if let Some(Entry::Motion(b)) = self.queue.pop_front() {
            self.planner_used -= 1;
            self.pos = b.target.clone();
            self.spindle_after_move(b.speed);
            if let Some(l) = b.log {
                self.log(l);
            }
        }
    }

    /// Drops every queued block; the parser position follows the machine.
    pub(super) fn flush_motion(&mut self) {
        self.queue.clear();
        self.planner_used = 0;
        self.modal.position = self.pos.clone();
    }

    /// Appends `l` to the executed-line log at the current time.
    pub(super) fn log(&mut self, l: LogLine) {
        let at_s = self.t;
        self.rec().log.push(ExecutedLine {
            text: l.text,
            seq: l.seq,
            connection: l.connection,
            at_s,
            parser: l.parser,
        });
    }
}
