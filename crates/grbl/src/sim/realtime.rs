//! Real-time commands, acted on as their byte arrives: status report, feed hold, cycle start
//! (after the hold completes), soft reset (`ALARM:3` when reset in motion, the firmware's
//! banner, `[MSG:'$H'|'$X' to unlock]` in alarm, then the `$N` startup blocks), jog cancel and
//! the overrides. A hardware reset (an Arduino's port opening) is here too.

use crate::protocol::{MachineState, Realtime};

use super::machine::Machine;
use super::SimEvent;

impl Machine {
    /// Acts on a real-time command as it arrives.
    pub(super) fn realtime(&mut self, rt: Realtime) {
        self.event(SimEvent::Realtime {
            command: rt,
            state: self.state,
            at_s: self.t,
        });
        match rt {
            Realtime::StatusQuery => {
                let r = self.status_report();
                self.emit(&r);
            }
            Realtime::FeedHold => self.feed_hold(),
            Realtime::CycleStart => {
                // Taken only once the hold is complete (`Hold:0`); during the deceleration it
                // is dropped, as GRBL 1.1h, grblHAL and FluidNC all do (see
                // `crate::cycle_start`), whichever flavour the simulator speaks.
                if self.hold_complete && matches!(self.state, MachineState::Hold(_)) {
                    self.hold = None;
                    self.hold_complete = false;
                    // The laser a hold switched off comes back with the motion.
                    self.spindle_stopped = false;
                    self.state = if self.queue.is_empty() {
                        MachineState::Idle
                    } else {
                        MachineState::Run
                    };
                }
            }
            Realtime::SoftReset => self.soft_reset(),
            Realtime::JogCancel => self.jog_cancel(),
            Realtime::FeedOverrideReset
            | Realtime::FeedOverridePlus10
            | Realtime::FeedOverrideMinus10
            | Realtime::FeedOverridePlus1
            | Realtime::FeedOverrideMinus1
            | Realtime::RapidOverride100
            | Realtime::RapidOverride50
            | Realtime::RapidOverride25
            | Realtime::SpindleOverrideReset
            | Realtime::SpindleOverridePlus10
            | Realtime::SpindleOverrideMinus10
            | Realtime::SpindleOverridePlus1
            | Realtime::SpindleOverrideMinus1 => self.overrides.apply(rt),
            Realtime::SafetyDoor
            | Realtime::SpindleStopToggle
            | Realtime::FloodToggle
            | Realtime::MistToggle => {}
        }
    }

    /// Ctrl-X: motion, buffers and modal state reset; `ALARM:3` if it was moving.
    pub(super) fn soft_reset(&mut self) {
        // Moving: a block executing (not held to a stop) or decelerating into a hold.
        let in_motion = self.moving();
        self.event(SimEvent::Reset {
            in_motion,
            at_s: self.t,
        });
        self.clear_controller();
        if in_motion {
            self.state = MachineState::Alarm;
            self.event(SimEvent::Alarm {
                code: 3,
                at_s: self.t,
            });
            self.emit("ALARM:3");
        }
        self.critical_lock = false;
        if self.state != MachineState::Alarm {
            self.state = MachineState::Idle;
        }
        self.start_up();
    }

    /// A hardware reset (an Arduino's DTR when the port opens): the controller starts from
    /// power-up, position zero, work offsets and startup blocks kept (EEPROM), no alarm.
    pub(super) fn hardware_reset(&mut self) {
        self.event(SimEvent::HardwareReset { at_s: self.t });
        self.clear_controller();
        self.pos = vec![0.0; self.cfg.axes.len()];
        self.modal.position = self.pos.clone();
        self.critical_lock = false;
        self.state = MachineState::Idle;
        self.start_up();
    }

    /// Motion, buffers, overrides and parser state back to their reset values.
    fn clear_controller(&mut self) {
        self.flush_motion();
        self.rx.clear();
        self.clear_line();
        self.pending = None;
        self.delayed.clear();
        self.busy_until = self.t;
        self.hold = None;
        self.hold_complete = false;
        self.jog_cancel = false;
        self.check_mode = false;
        self.overrides.reset();
        self.spindle_stopped = false;
        self.laser_rest_on = false;
        self.modal = self.modal.reset(self.pos.clone());
        self.reset_report_counters();
    }

    /// What the controller prints and runs as it starts: the banner, the unlock message in
    /// alarm, else the `$N` startup blocks.
    fn start_up(&mut self) {
        let banner = self.cfg.firmware.banner();
        self.emit(&format!("\r\n{banner}"));
        if self.state == MachineState::Alarm {
            let msg = self.cfg.firmware.message("'$H'|'$X' to unlock");
            self.emit(&msg);
        } else {
            self.run_startup_lines();
        }
    }
}
