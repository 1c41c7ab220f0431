//! What the machine reports: status reports for `?` and the snapshots its handle watches.
//!
//! A status report always carries the state, `MPos:` or `WPos:`, `Bf:` (planner blocks free,
//! RX bytes free) and `FS:` (current feed, spindle speed as the output runs: see `spindle`).
//! `WCO:`, `Ov:` and `A:` come now and then, as each firmware refreshes them:
//!
//! - **GRBL 1.1h** (`report_realtime_status`) and **FluidNC**: two counters. `WCO:` when its
//!   counter is 0 (then reloaded: 10 reports idle, 30 busy) and it sets the override counter
//!   to 1 if it was 0, so `Ov:` comes on the next report; `Ov:` when its counter is 0 (reloaded:
//!   10 idle, 20 busy). `A:` is printed only with `Ov:`, and only when the spindle or coolant
//!   is on (`A:S`, `A:C`, `F`, `M`); a report with no `A:` says nothing about the spindle
//!   unless it has `Ov:`. A spindle, coolant or override change zeroes the override counter,
//!   so the next report carries `Ov:` (and `A:` if anything is on); a work-offset change
//!   zeroes the `WCO:` counter. After a reset both counters are 0: the first report has
//!   `WCO:`, the second `Ov:`. "Busy" is Run, Hold, Jog, Home or Door; FluidNC v3.7.8 uses the
//!   idle counts in every state.
//! - **grblHAL**: the same counts, but `Ov:` takes precedence (a due `WCO:` waits for the next
//!   report), counters are cut to the idle count when idle, and a spindle or coolant change
//!   makes the next report carry `A:` with or without `Ov:`: after `M5` that is an empty `|A:`.
//!   With `Ov:` it prints `A:` when the spindle or coolant is on.

use super::gcode::Spindle;
use super::machine::Machine;
use super::overrides::Overrides;
use super::spindle::SpindleOutput;
use super::{ParserState, SimSnapshot};
use crate::protocol::MachineState;

/// The refresh counters and the changes that force a field into the next report.
#[derive(Debug, Clone, Default)]
pub(super) struct ReportCounters {
    wco_counter: u8,
    ovr_counter: u8,
    /// grblHAL: print `Ov:` next time.
    force_ovr: bool,
    /// grblHAL: print `A:` next time.
    force_accessories: bool,
    /// grblHAL: print `WCO:` next time.
    force_wco: bool,
    /// What the counters last saw, to notice changes.
    seen: Option<Seen>,
}

/// The state whose changes GRBL reports at once.
#[derive(Debug, Clone, PartialEq)]
struct Seen {
    spindle: Spindle,
    spindle_speed: f64,
    spindle_stopped: bool,
    flood: bool,
    mist: bool,
    overrides: Overrides,
    wco: Vec<f64>,
}

impl Machine {
    fn seen(&self) -> Seen {
        Seen {
            spindle: self.modal.spindle,
            spindle_speed: self.modal.spindle_speed,
            spindle_stopped: self.spindle_stopped,
            flood: self.modal.flood,
            mist: self.modal.mist,
            overrides: self.overrides,
            wco: self.modal.wco(),
        }
    }

    /// Notes spindle, coolant, override and work-offset changes since the last call, so the
    /// next status report carries them. Called at every step: it allocates only on a change.
    pub(super) fn track_report_changes(&mut self) {
        let Some(before) = &self.report.seen else {
            self.report.seen = Some(self.seen());
            return;
        };
        let m = &self.modal;
        let accessories = before.spindle != m.spindle
            || (m.spindle != Spindle::Off && before.spindle_speed != m.spindle_speed)
            || before.spindle_stopped != self.spindle_stopped
            || before.flood != m.flood
            || before.mist != m.mist;
        let overrides = before.overrides != self.overrides;
        let wco = !m.offsets[m.coord]
            .iter()
            .zip(&m.g92)
            .map(|(a, b)| a + b)
            .eq(before.wco.iter().copied());
        if !(accessories || overrides || wco) {
            return;
        }
        self.report.seen = Some(self.seen());
        let r = &mut self.report;
        if self.cfg.firmware.grblhal_reporting() {
            r.force_accessories |= accessories;
            r.force_ovr |= overrides;
            r.force_wco |= wco;
        } else {
            if accessories || overrides {
                r.ovr_counter = 0;
            }
            if wco {
                r.wco_counter = 0;
            }
        }
    }

    /// After a reset: both counters at 0, nothing pending.
    pub(super) fn reset_report_counters(&mut self) {
        self.report = ReportCounters {
            seen: Some(self.seen()),
            ..ReportCounters::default()
        };
    }

    /// The `?` status report.
    pub(super) fn status_report(&mut self) -> String {
        self.track_report_changes();
        let wco = self.modal.wco();
        let mut s = format!("<{}", self.state);
        if self.cfg.status_mask & 1 != 0 {
            s += &format!("|MPos:{}", fmt_pos(&self.pos));
        } else {
            let w: Vec<f64> = self.pos.iter().zip(&wco).map(|(p, o)| p - o).collect();
            s += &format!("|WPos:{}", fmt_pos(&w));
        }
        if self.cfg.status_mask & 2 != 0 {
            let planner_free = self.cfg.planner_blocks.saturating_sub(self.planner_used);
            // GRBL's serial_get_rx_buffer_available(): 128 when empty.
            let rx_free = self.cfg.rx_buffer_bytes.saturating_sub(self.rx.len());
            s += &format!("|Bf:{planner_free},{rx_free}");
        }
        let (v, _) = self.speed_at(self.t);
        let out = self.spindle_output();
        s += &format!("|FS:{},{}", fmt_int(v * 60.0), fmt_int(out.rpm));
        let (with_wco, with_ov, with_a) = if self.cfg.firmware.grblhal_reporting() {
            self.refresh_grblhal(&out)
        } else {
            self.refresh_grbl(&out)
        };
        if with_wco {
            s += &format!("|WCO:{}", fmt_pos(&wco));
        }
        if with_ov {
            let o = self.overrides;
            s += &format!("|Ov:{},{},{}", o.feed, o.rapid, o.spindle);
        }
        if with_a {
            s += &format!("|A:{}", self.accessories(&out));
        }
        s.push('>');
        s
    }

    /// Busy for the refresh counters: Run, Hold, Jog (Home and Door are not simulated).
    fn busy(&self) -> bool {
        self.cfg.firmware.slow_refresh_when_busy()
            && matches!(
                self.state,
                MachineState::Run | MachineState::Hold(_) | MachineState::Jog
            )
    }

    /// GRBL 1.1h and FluidNC: which of `WCO:`, `Ov:`, `A:` this report carries.
    fn refresh_grbl(&mut self, out: &SpindleOutput) -> (bool, bool, bool) {
        let busy = self.busy();
        let r = &mut self.report;
        let mut with_wco = false;
        if r.wco_counter > 0 {
            r.wco_counter -= 1;
        } else {
            r.wco_counter = if busy { 29 } else { 9 };
            if r.ovr_counter == 0 {
                r.ovr_counter = 1;
            }
            with_wco = true;
        }
        let mut with_ov = false;
        if r.ovr_counter > 0 {
            r.ovr_counter -= 1;
        } else {
            r.ovr_counter = if busy { 19 } else { 9 };
            with_ov = true;
        }
        let with_a = with_ov && (out.shown.is_some() || self.modal.flood || self.modal.mist);
        (with_wco, with_ov, with_a)
    }

    /// grblHAL: which of `WCO:`, `Ov:`, `A:` this report carries.
    fn refresh_grblhal(&mut self, out: &SpindleOutput) -> (bool, bool, bool) {
        let busy = self.busy();
        let idle = self.state == MachineState::Idle;
        let coolant = self.modal.flood || self.modal.mist;
        let r = &mut self.report;
        let with_ov = r.ovr_counter == 0 || r.force_ovr;
        let mut with_a = r.force_accessories;
        if with_ov {
            r.ovr_counter = if busy { 19 } else { 9 };
            with_a |= out.shown.is_some() || coolant;
        } else {
            r.ovr_counter -= 1;
        }
        if r.ovr_counter > 9 && idle {
            r.ovr_counter = 9;
        }
        let mut with_wco = false;
        let mut wco_later = false;
        if r.wco_counter == 0 || r.force_wco {
            r.wco_counter = if busy { 29 } else { 9 };
            with_wco = !with_ov;
            wco_later = with_ov;
        } else {
            r.wco_counter -= 1;
        }
        if r.wco_counter > 9 && idle {
            r.wco_counter = 9;
        }
        r.force_ovr = false;
        r.force_accessories = false;
        r.force_wco = wco_later;
        (with_wco, with_ov, with_a)
    }

    /// The `A:` letters: spindle `S`/`C`, flood `F`, mist `M` (empty when all are off).
    fn accessories(&self, out: &SpindleOutput) -> String {
        let mut acc = String::new();
        match out.shown {
            Some(Spindle::Cw) => acc.push('S'),
            Some(Spindle::Ccw) => acc.push('C'),
            _ => {}
        }
        if self.modal.flood {
            acc.push('F');
        }
        if self.modal.mist {
            acc.push('M');
        }
        acc
    }

    /// Publishes a snapshot to the handle if anything changed.
    pub(super) fn publish(&self) {
        self.rec().parser = ParserState::of(&self.modal);
        let executed = self.rec().log.len();
        let snap = SimSnapshot {
            at_s: self.t,
            state: self.state,
            position: self.pos.clone(),
            planner_used: self.planner_used,
            rx_used: self.rx.len(),
            connected: self.out.is_some(),
            frozen: self.frozen,
            spindle_on: self.spindle_output().energised(),
            executed,
            received: self.received,
        };
        self.snap_tx.send_if_modified(|s| {
            if *s != snap {
                *s = snap;
                true
            } else {
                false
            }
        });
    }
}

/// Positions as GRBL prints them: three decimals, comma-separated.
pub(super) fn fmt_pos(p: &[f64]) -> String {
    p.iter()
        .map(|x| format!("{x:.3}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// A rate as GRBL prints it in `FS:`: rounded to an integer.
fn fmt_int(x: f64) -> String {
    format!("{}", x.round() as i64)
}
