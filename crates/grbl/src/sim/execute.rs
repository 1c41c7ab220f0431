//! The protocol loop's execution of a received line: `$` commands go to `system`, G-code lines
//! through the parser into the planner. A motion line waits, holding the RX ring, while the
//! planner is full; `ok` is sent when the line is in the planner, not when it has run. Spindle
//! and coolant changes, `G4`, `M0/M1/M2/M30`, `G10`, `G28/G30` and `G92` wait for the planner to
//! empty first, as GRBL does. In alarm or jog state a G-code line gets `error:9`.

use crate::protocol::MachineState;

use super::gcode;
use super::machine::Machine;
use super::planner::LogLine;
use super::{ParserState, SimEvent};

impl Machine {
    /// Answers the host now, or after the injected slow-ack delay
    /// ([`Faults::ack_delay_s`](super::Faults::ack_delay_s)).
    pub(super) fn respond(&mut self, text: String) {
        if self.cfg.faults.ack_delay_s > 0.0 {
            self.busy_until = self.t + self.cfg.faults.ack_delay_s;
            self.delayed.push(text);
        } else {
            self.emit(&text);
        }
    }

    /// Answers `error:code` to `line` and records it.
    pub(super) fn error(&mut self, line: &str, code: u8) {
        self.event(SimEvent::Error {
            line: line.to_string(),
            code,
            at_s: self.t,
        });
        self.respond(format!("error:{code}"));
    }

    /// Executes the pending line if it can go now; false when it must wait (planner full, or
    /// the planner must empty first).
    pub(super) fn try_execute(&mut self) -> bool {
        let Some(p) = self.pending.take() else {
            return false;
        };
        if p.overflow {
            self.error(&p.raw, 11);
            return true;
        }
        if p.stored.is_empty() {
            self.respond("ok".into());
            return true;
        }
        if p.stored.starts_with('$') {
            let done = self.system_command(&p);
            if !done {
                self.pending = Some(p);
            }
            return done;
        }
        if self.line_fault(&p) {
            return true;
        }
        if matches!(self.state, MachineState::Alarm | MachineState::Jog) {
            self.error(&p.raw, 9);
            return true;
        }
        let (modal, action) = match gcode::execute(&self.modal, &p.stored, &self.cfg.axes, false) {
            Ok(x) => x,
            Err(code) => {
                self.error(&p.raw, code);
                return true;
            }
        };
        let log = LogLine {
            text: p.raw.clone(),
            seq: p.seq,
            connection: p.connection,
            parser: ParserState::of(&modal),
        };
        if self.check_mode {
            self.modal = modal;
            self.modal.position = self.pos.clone();
            self.respond("ok".into());
            return true;
        }
        if action.sync && !self.queue.is_empty() {
            self.pending = Some(p);
            return false;
        }
        if !self.planner_has_room(action.moves.len()) {
            self.pending = Some(p);
            return false;
        }
        let spindle_set =
            (modal.spindle, modal.spindle_speed) != (self.modal.spindle, self.modal.spindle_speed);
        self.modal = modal;
        if action.moves.is_empty() {
            self.enqueue_marker(log);
            if spindle_set {
                self.spindle_set_at_rest();
            }
        } else {
            let start = self.queue_end_position();
            self.enqueue_moves(start, action.moves, false, Some(log));
        }
        if action.program_end {
            self.overrides.reset();
            let msg = self.cfg.firmware.message("Pgm End");
            self.emit(&msg);
        }
        if action.pause {
            self.feed_hold();
        }
        match action.dwell_s {
            Some(d) if d > 0.0 => {
                self.busy_until = self.t + d;
                self.delayed.push("ok".into());
                if self.cfg.faults.ack_delay_s > 0.0 {
                    self.busy_until += self.cfg.faults.ack_delay_s;
                }
            }
            _ => self.respond("ok".into()),
        }
        true
    }
}
