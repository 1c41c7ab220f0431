//! Motion in simulated time: the head block runs at the commanded feed (times the feed
//! override; jogs without it) up to the max rate, or the rapid rate (times the rapid
//! override), with instant acceleration, except for a feed hold or jog cancel, which
//! decelerates at the configured acceleration a: from speed v₀ at t₀ the speed is
//! max(v₀ − a(t − t₀), 0), and a block with r mm left ends after 2r / (v + √(v² − 2ar)) if
//! v² ≥ 2ar, else the hold completes after v/a.

use crate::protocol::MachineState;

use super::gcode::Speed;
use super::machine::Machine;
use super::planner::{Block, Entry};
use super::SimEvent;

impl Machine {
    /// Current speed of the head block (mm/s), before any hold deceleration. A feed move (after
    /// the feed override; a jog without it) runs no faster than the axes' max rate, as GRBL 1.1's
    /// `plan_compute_profile_nominal_speed` clamps it to the block's `rapid_rate` (from
    /// `$110`-`$112`; here one rate along the path, as for rapids).
    pub(super) fn block_speed(&self, b: &Block) -> f64 {
        let max_rate = self.cfg.rapid_mm_min / 60.0;
        match b.speed {
            Speed::Rapid => max_rate * self.overrides.rapid as f64 / 100.0,
            Speed::Feed(v) => {
                let v = if b.jog {
                    v
                } else {
                    v * self.overrides.feed as f64 / 100.0
                };
                v.min(max_rate)
            }
        }
    }

    /// True while the head block runs (not held to a stop).
    pub(super) fn moving(&self) -> bool {
        matches!(self.queue.front(), Some(Entry::Motion(_))) && !self.hold_complete
    }

    /// Speed now, and whether it is decelerating.
    pub(super) fn speed_at(&self, t: f64) -> (f64, bool) {
        let Some(Entry::Motion(b)) = self.queue.front() else {
            return (0.0, false);
        };
        if self.hold_complete {
            return (0.0, false);
        }
        match self.hold {
            Some((t0, v0)) => ((v0 - self.cfg.accel_mm_s2 * (t - t0)).max(0.0), true),
            None => (self.block_speed(b), false),
        }
    }

    /// When the head block ends or a hold finishes decelerating.
    pub(super) fn motion_event(&self) -> Option<f64> {
        if !self.moving() {
            return None;
        }
        let Some(Entry::Motion(b)) = self.queue.front() else {
            return None;
        };
        let (v, decel) = self.speed_at(self.t);
        let a = self.cfg.accel_mm_s2;
        let r = b.remaining_mm;
        if decel {
            if v * v >= 2.0 * a * r {
                // (v - sqrt(v² - 2ar)) / a, in the form that does not cancel for small r.
                Some(self.t + 2.0 * r / (v + (v * v - 2.0 * a * r).max(0.0).sqrt()))
            } else {
                Some(self.t + v / a)
            }
        } else if v > 0.0 {
            Some(self.t + r / v)
        } else {
            None
        }
    }

    /// Moves the machine from `self.t` to `t` (no event lies strictly between them).
    pub(super) fn integrate(&mut self, t: f64) {
        let t = t.max(self.t);
        let dt = t - self.t;
        // The head block (or hold) whose end falls due by `t` ends at `t`, even if rounding
        // leaves it a sliver of path, or its duration is below the resolution of `t` (an
        // enormous rate): else the event loop would wait for an event that never comes.
        let due = self.motion_event().is_some_and(|e| e <= t);
        if dt <= 0.0 && !due {
            return;
        }
        if self.moving() {
            let (v, decel) = self.speed_at(self.t);
            let a = self.cfg.accel_mm_s2;
            // Due while decelerating: the block ends first if it can within the stop, else the
            // hold completes.
            let block_due = due && !(decel && v * v < 2.0 * a * self.head_remaining_mm());
            let dist = if decel {
                let dt_eff = dt.min(v / a);
                v * dt_eff - 0.5 * a * dt_eff * dt_eff
            } else {
                v * dt
            };
            let mut done = false;
            if let Some(Entry::Motion(b)) = self.queue.front_mut() {
                b.remaining_mm -= dist;
                if b.remaining_mm <= 1e-9 || block_due {
                    b.remaining_mm = 0.0;
                    done = true;
                }
                let f = if b.length_mm > 0.0 {
                    1.0 - b.remaining_mm / b.length_mm
                } else {
                    1.0
                };
                self.pos = b
                    .start
                    .iter()
                    .zip(&b.target)
                    .map(|(s, e)| s + (e - s) * f)
                    .collect();
            }
            self.t = t;
            if done {
                self.finish_head();
            }
            if decel {
                // The hold completes when the speed reaches zero, or when the planner runs out
                // of moves first (GRBL's cycle stop in a hold: `Hold:0` with nothing queued).
                let out_of_moves = !self.queue.iter().any(|e| matches!(e, Entry::Motion(_)));
                if let Some((t0, v0)) = self.hold {
                    if t >= t0 + v0 / a - 1e-12 || out_of_moves || (due && !block_due) {
                        self.hold_stopped();
                    }
                }
            }
        } else {
            self.t = t;
        }
    }

    /// Path left in the head block (mm; 0 without one).
    fn head_remaining_mm(&self) -> f64 {
        match self.queue.front() {
            Some(Entry::Motion(b)) => b.remaining_mm,
            _ => 0.0,
        }
    }

    /// A hold finished decelerating: `Hold:0`, or back to idle after a jog cancel.
    pub(super) fn hold_stopped(&mut self) {
        if self.jog_cancel {
            self.flush_motion();
            self.jog_cancel = false;
            self.hold = None;
            self.state = MachineState::Idle;
            return;
        }
        self.hold_complete = true;
        self.state = MachineState::Hold(0);
        self.spindle_hold_complete();
        self.event(SimEvent::HoldComplete { at_s: self.t });
    }

    /// Feed hold (`!`, `M0`/`M1`): decelerate to `Hold:0`; cancels a jog.
    pub(super) fn feed_hold(&mut self) {
        match self.state {
            MachineState::Run if self.hold.is_none() && !self.hold_complete => {
                let (v, _) = self.speed_at(self.t);
                self.hold = Some((self.t, v));
                self.state = MachineState::Hold(1);
                if v <= 0.0 {
                    self.hold_stopped();
                }
            }
            MachineState::Idle => {
                self.hold_complete = true;
                self.state = MachineState::Hold(0);
                self.spindle_hold_complete();
                self.event(SimEvent::HoldComplete { at_s: self.t });
            }
            MachineState::Jog => self.jog_cancel(),
            _ => {}
        }
    }

    /// Jog cancel (0x85): decelerate and drop the queued jog moves.
    pub(super) fn jog_cancel(&mut self) {
        if self.state == MachineState::Jog && self.hold.is_none() {
            let (v, _) = self.speed_at(self.t);
            self.jog_cancel = true;
            self.hold = Some((self.t, v));
            if v <= 0.0 {
                self.hold_stopped();
            }
        }
    }
}
