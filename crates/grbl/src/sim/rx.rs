//! The RX side of the protocol: the RX ring (GRBL: 128 bytes, 127 usable) and the line buffer
//! (GRBL: 80 bytes). Real-time bytes are picked off as they arrive and never stored; a byte
//! arriving while the ring is full is lost, as on the AVR, and the loss is recorded. Characters
//! move from the ring into the line buffer with GRBL's preprocessing: spaces, `/` and comments
//! dropped, upper case, and an overflow flag that turns the line into `error:11`. FluidNC
//! instead keeps the first 254 bytes of a line as received and drops the rest without a word.

use crate::protocol::Realtime;

use super::machine::Machine;
use super::SimEvent;

/// A complete line waiting for the protocol loop to execute it.
#[derive(Debug)]
pub(super) struct PendingLine {
    /// The line as stored (preprocessed).
    pub(super) stored: String,
    /// The line as received (without its line ending).
    pub(super) raw: String,
    /// The line overflowed the line buffer.
    pub(super) overflow: bool,
    /// G-code line count (1-based; 0 for `$` commands, empty and overflowed lines).
    pub(super) seq: u64,
    /// Connection it came in on.
    pub(super) connection: u64,
}

impl Machine {
    /// A byte arrives: real-time commands act at once, others go into the RX ring (or are lost).
    pub(super) fn receive_byte(&mut self, b: u8) {
        if self.frozen {
            return;
        }
        if let Some(rt) = Realtime::from_byte(b) {
            self.realtime(rt);
            return;
        }
        if self.rx.len() >= self.cfg.rx_buffer_bytes.saturating_sub(1) {
            let at_s = self.t;
            let mut r = self.rec();
            r.overflow_bytes += 1;
            r.events.push(SimEvent::RxOverflow { byte: b, at_s });
            return;
        }
        self.rx.push_back(b);
        let used = self.rx.len();
        let mut r = self.rec();
        r.rx_high_water = r.rx_high_water.max(used);
    }

    /// Moves characters from the RX ring into the line buffer until a line is complete.
    pub(super) fn read_line(&mut self) -> bool {
        while let Some(c) = self.rx.pop_front() {
            if c == b'\n' || c == b'\r' {
                let stored = std::mem::take(&mut self.line);
                let raw = std::mem::take(&mut self.raw);
                let overflow = self.line_overflow;
                self.clear_line();
                let is_gcode = !stored.is_empty() && !stored.starts_with('$') && !overflow;
                if is_gcode {
                    self.received += 1;
                }
                if stored.starts_with('$') {
                    self.event(SimEvent::SystemCommand {
                        line: raw.clone(),
                        at_s: self.t,
                    });
                }
                self.pending = Some(PendingLine {
                    stored,
                    raw,
                    overflow,
                    seq: if is_gcode { self.received } else { 0 },
                    connection: self.connection,
                });
                return true;
            }
            let limit = self.cfg.firmware.line_buffer_size() - 1;
            if !self.cfg.firmware.overflow_is_error() && self.raw.len() >= limit {
                continue;
            }
            self.raw.push(c as char);
            if self.line_overflow || self.in_paren || self.in_semicolon {
                if c == b')' && self.in_paren {
                    self.in_paren = false;
                }
                continue;
            }
            if c <= b' ' || c == b'/' {
                continue;
            }
            if c == b'(' {
                self.in_paren = true;
            } else if c == b';' {
                self.in_semicolon = true;
            } else if self.line.len() >= limit {
                self.line_overflow = true;
            } else {
                self.line.push((c as char).to_ascii_uppercase());
            }
        }
        false
    }

    /// Empties the line buffer and its comment and overflow state.
    pub(super) fn clear_line(&mut self) {
        self.line.clear();
        self.raw.clear();
        self.line_overflow = false;
        self.in_paren = false;
        self.in_semicolon = false;
    }
}
