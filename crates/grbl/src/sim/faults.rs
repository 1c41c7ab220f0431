//! Injected faults: link drops, a controller that freezes, alarms, forced errors, slow
//! acknowledgements and a spontaneous reset, each at a given G-code line and each firing once.

use crate::protocol::MachineState;

use super::gcode::Spindle;
use super::machine::Machine;
use super::rx::PendingLine;
use super::SimEvent;

/// Faults the simulator injects. Line numbers count G-code lines received since the simulator
/// started (1-based, `$` commands not counted), across connections; each fault fires once.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Faults {
    /// For each N listed, when G-code line N has been received, drop the link: line N and
    /// everything still in the RX buffer or on the wire are lost, output already queued is
    /// delivered, and the connection closes. The planner keeps running what it holds (as a
    /// controller whose host went away). Each entry fires once; the order does not matter.
    pub drop_at_lines: Vec<u64>,
    /// When G-code line N has been received, the controller freezes: line N and everything
    /// still in the RX buffer or on the wire are lost, and from then on nothing is read or
    /// answered (real-time bytes included, so `?` gets no status report), but the connection
    /// stays open. The planner keeps running what it holds. The next host to attach finds the
    /// controller answering again (a hung USB-serial bridge or network stack that recovers on a
    /// new connection).
    pub freeze_at_line: Option<u64>,
    /// When the move of G-code line N starts, raise `ALARM:code` (1 or 2 behave like GRBL's
    /// critical hard/soft-limit alarms: motion killed, `[MSG:Reset to continue]`, nothing read
    /// until a reset).
    pub alarm_at_line: Option<(u64, u8)>,
    /// Answer G-code line N with `error:code` instead of executing it.
    pub error_at_line: Option<(u64, u8)>,
    /// Simulated seconds the controller spends on each line before answering (slow acks). The
    /// protocol loop is busy meanwhile, as on a slow controller.
    pub ack_delay_s: f64,
    /// When G-code line N has been received, the controller resets by itself (a brown-out, a
    /// watchdog, electrical noise on the reset line): as at power-up, position zero, planner,
    /// buffers and modal state lost, the banner printed; the link stays up.
    pub reset_at_line: Option<u64>,
}

/// Which one-shot faults have fired.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct FiredFaults {
    /// Lines of [`Faults::drop_at_lines`] whose drop has fired.
    pub(super) drops: Vec<u64>,
    pub(super) freeze: bool,
    pub(super) alarm: bool,
    pub(super) error: bool,
    pub(super) reset: bool,
}

impl Machine {
    /// Fires the fault injected at the received G-code line `p` (link drop, freeze or forced
    /// error), if any; true when one fired and took the line.
    pub(super) fn line_fault(&mut self, p: &PendingLine) -> bool {
        if self.cfg.faults.drop_at_lines.contains(&p.seq) && !self.fired.drops.contains(&p.seq) {
            self.fired.drops.push(p.seq);
            self.close_link(true);
            return true;
        }
        if self.cfg.faults.freeze_at_line == Some(p.seq) && !self.fired.freeze {
            self.fired.freeze = true;
            self.freeze();
            return true;
        }
        if self.cfg.faults.reset_at_line == Some(p.seq) && !self.fired.reset {
            self.fired.reset = true;
            self.hardware_reset();
            return true;
        }
        if let Some((n, code)) = self.cfg.faults.error_at_line {
            if n == p.seq && !self.fired.error {
                self.fired.error = true;
                self.error(&p.raw, code);
                return true;
            }
        }
        false
    }

    /// Raises the alarm injected at the start of G-code line `seq`'s move, if any; true when it
    /// fired.
    pub(super) fn alarm_fault(&mut self, seq: u64) -> bool {
        if let Some((n, code)) = self.cfg.faults.alarm_at_line {
            if seq == n && !self.fired.alarm {
                self.fired.alarm = true;
                self.raise_alarm(code);
                return true;
            }
        }
        false
    }

    /// Stops reading and answering with the link left open; the next attach ends it.
    pub(super) fn freeze(&mut self) {
        self.frozen = true;
        self.event(SimEvent::Frozen {
            connection: self.connection,
            at_s: self.t,
        });
        self.wire.clear();
        self.rx.clear();
        self.clear_line();
        self.pending = None;
        self.delayed.clear();
    }

    /// Raises `ALARM:code`: motion killed, spindle and coolant off; 1 and 2 lock until a reset.
    pub(super) fn raise_alarm(&mut self, code: u8) {
        self.flush_motion();
        self.hold = None;
        self.hold_complete = false;
        self.state = MachineState::Alarm;
        self.modal.spindle = Spindle::Off;
        self.modal.flood = false;
        self.modal.mist = false;
        self.event(SimEvent::Alarm { code, at_s: self.t });
        self.emit(&format!("ALARM:{code}"));
        if code == 1 || code == 2 {
            self.critical_lock = true;
            let msg = self.cfg.firmware.message("Reset to continue");
            self.emit(&msg);
        }
    }
}
