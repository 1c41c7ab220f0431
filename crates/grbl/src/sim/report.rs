//! What the machine reports: status reports for `?` (`MPos` or `WPos`, `Bf`, `FS`; `WCO` on every
//! 10th report and `Ov`/`A` on the one after, as GRBL refreshes them), and the snapshots its handle
//! watches.

use super::gcode::Spindle;
use super::machine::Machine;
use super::SimSnapshot;

impl Machine {
    /// The `?` status report.
    pub(super) fn status_report(&mut self) -> String {
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
        let spindle = if self.modal.spindle == Spindle::Off {
            0.0
        } else {
            self.modal.spindle_speed * self.overrides.spindle as f64 / 100.0
        };
        s += &format!("|FS:{},{}", fmt_int(v * 60.0), fmt_int(spindle));
        if self.reports.is_multiple_of(10) {
            s += &format!("|WCO:{}", fmt_pos(&wco));
        } else if self.reports % 10 == 1 {
            s += &format!(
                "|Ov:{},{},{}",
                self.overrides.feed, self.overrides.rapid, self.overrides.spindle
            );
            let mut acc = String::new();
            match self.modal.spindle {
                Spindle::Cw => acc.push('S'),
                Spindle::Ccw => acc.push('C'),
                Spindle::Off => {}
            }
            if self.modal.flood {
                acc.push('F');
            }
            if self.modal.mist {
                acc.push('M');
            }
            if !acc.is_empty() {
                s += &format!("|A:{acc}");
            }
        }
        self.reports += 1;
        s.push('>');
        s
    }

    /// Publishes a snapshot to the handle if anything changed.
    pub(super) fn publish(&self) {
        let executed = self.rec().log.len();
        let snap = SimSnapshot {
            at_s: self.t,
            state: self.state,
            position: self.pos.clone(),
            planner_used: self.planner_used,
            rx_used: self.rx.len(),
            connected: self.out.is_some(),
            frozen: self.frozen,
            spindle_on: self.modal.spindle != Spindle::Off,
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
