//! The spindle output (the heat: hot wire, laser, torch) as the hardware sees it, which is what
//! `FS:` and `A:` report, not the parser's `M3`/`M4`/`M5`:
//! - the speed is `S` times the spindle override, capped at `$30` (GRBL's
//!   `spindle_compute_pwm_value`);
//! - without laser mode the output follows the parser state; GRBL 1.1 disables the PWM at `S0`,
//!   so `A:` shows no spindle then, while grblHAL and FluidNC keep the enable on;
//! - in laser mode (`$32=1`) the laser fires during feed moves and jogs only: `M4` scales the
//!   power with the speed and is off between moves, `M3` keeps the last feed move's power at
//!   rest (GRBL leaves the PWM as the last segment set it) and is off after a rapid;
//! - in laser mode a completed feed hold switches the laser off until cycle start
//!   (`DISABLE_LASER_DURING_HOLD`); without it a hold keeps the spindle on, as GRBL does.

use super::gcode::{MotionMode, Speed, Spindle};
use super::machine::Machine;
use super::planner::Entry;

/// The spindle output now.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SpindleOutput {
    /// The direction `A:` shows (`S` or `C`), `None` when it shows no spindle.
    pub(super) shown: Option<Spindle>,
    /// The speed `FS:` shows.
    pub(super) rpm: f64,
}

impl SpindleOutput {
    const OFF: SpindleOutput = SpindleOutput {
        shown: None,
        rpm: 0.0,
    };

    /// True when anything drives the heat: a speed above zero or an enabled output.
    pub(super) fn energised(&self) -> bool {
        self.rpm > 0.0 || self.shown.is_some()
    }
}

impl Machine {
    /// The programmed speed after the override, capped at `$30`.
    fn programmed_rpm(&self) -> f64 {
        let rpm = self.modal.spindle_speed * self.overrides.spindle as f64 / 100.0;
        rpm.clamp(0.0, self.cfg.spindle_max_rpm.max(0.0))
    }

    /// What the spindle output does now.
    pub(super) fn spindle_output(&self) -> SpindleOutput {
        let dir = self.modal.spindle;
        if dir == Spindle::Off || self.spindle_stopped {
            return SpindleOutput::OFF;
        }
        let programmed = self.programmed_rpm();
        let rpm = if self.cfg.laser_mode {
            self.laser_rpm(dir, programmed)
        } else {
            programmed
        };
        let pwm_on = rpm > 0.0;
        let shown = if self.cfg.firmware.accessory_follows_pwm() {
            pwm_on.then_some(dir)
        } else {
            Some(dir)
        };
        SpindleOutput { shown, rpm }
    }

    /// Laser power in laser mode: on during feed moves (`M4` scaled by the speed), `M3` also at
    /// rest after a feed move.
    fn laser_rpm(&self, dir: Spindle, programmed: f64) -> f64 {
        if self.moving() {
            if let Some(Entry::Motion(b)) = self.queue.front() {
                if matches!(b.speed, Speed::Rapid) {
                    return 0.0;
                }
                if dir == Spindle::Ccw {
                    let nominal = self.block_speed(b);
                    let (now, _) = self.speed_at(self.t);
                    return if nominal > 0.0 {
                        programmed * (now / nominal).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                }
                return programmed;
            }
        }
        if dir == Spindle::Cw && self.laser_rest_on {
            programmed
        } else {
            0.0
        }
    }

    /// A line changed the spindle state or speed without moving: in laser mode `M3` fires at
    /// rest only in a feed motion mode (GRBL syncs the spindle with speed 0 otherwise).
    pub(super) fn spindle_set_at_rest(&mut self) {
        self.laser_rest_on = matches!(
            self.modal.motion,
            MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
        );
    }

    /// A move ended: in laser mode `M3` keeps its power at rest after a feed move, not after a
    /// rapid.
    pub(super) fn spindle_after_move(&mut self, speed: Speed) {
        self.laser_rest_on = matches!(speed, Speed::Feed(_));
    }

    /// A feed hold completed: in laser mode the laser goes out until cycle start.
    pub(super) fn spindle_hold_complete(&mut self) {
        if self.cfg.laser_mode {
            self.spindle_stopped = true;
        }
    }
}
