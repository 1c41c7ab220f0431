//! `$` commands: `$`, `$$`, `$#`, `$G`, `$I`, `$N`, `$X`, `$H` (`error:5`: homing is disabled),
//! `$C`, `$SLP`, `$RST=`, `$J=` jogging and `$n=v` (only `$10`, the status mask, changes
//! behaviour). Those that GRBL runs only when idle answer `error:8` otherwise.

use crate::protocol::MachineState;

use super::gcode;
use super::machine::Machine;
use super::report::fmt_pos;
use super::rx::PendingLine;

impl Machine {
    /// Runs a `$` command; false when it must wait (a jog with the planner full).
    pub(super) fn system_command(&mut self, p: &PendingLine) -> bool {
        let cmd = p.stored.as_str();
        let idle_or_alarm = matches!(self.state, MachineState::Idle | MachineState::Alarm);
        let need_idle = |me: &mut Machine| -> bool {
            if !idle_or_alarm {
                me.error(&p.raw, 8);
                return false;
            }
            true
        };
        match cmd {
            "$" => {
                self.emit(
                    "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]",
                );
                self.respond("ok".into());
            }
            "$$" => {
                if need_idle(self) {
                    let settings = [
                        (0, "10".to_string()),
                        (1, "25".to_string()),
                        (10, self.cfg.status_mask.to_string()),
                        (13, "0".to_string()),
                        (22, "0".to_string()),
                        (30, "1000".to_string()),
                        (32, "0".to_string()),
                        (110, format!("{:.3}", self.cfg.rapid_mm_min)),
                        (
                            120,
                            format!("{:.3}", self.cfg.accel_mm_s2 * 3600.0 / 3600.0),
                        ),
                    ];
                    for (n, v) in settings {
                        self.emit(&format!("${n}={v}"));
                    }
                    self.respond("ok".into());
                }
            }
            "$G" => {
                let r = self.modal.gc_report();
                self.emit(&format!("[GC:{r}]"));
                self.respond("ok".into());
            }
            "$#" => {
                if need_idle(self) {
                    for (k, off) in self.modal.offsets.clone().iter().enumerate() {
                        self.emit(&format!("[G{}:{}]", 54 + k, fmt_pos(off)));
                    }
                    let zeros = vec![0.0; self.cfg.axes.len()];
                    self.emit(&format!("[G28:{}]", fmt_pos(&zeros)));
                    self.emit(&format!("[G30:{}]", fmt_pos(&zeros)));
                    let g92 = self.modal.g92.clone();
                    self.emit(&format!("[G92:{}]", fmt_pos(&g92)));
                    self.emit("[TLO:0.000]");
                    self.emit(&format!("[PRB:{}:0]", fmt_pos(&zeros)));
                    self.respond("ok".into());
                }
            }
            "$I" => {
                if need_idle(self) {
                    self.emit("[VER:1.1h.20190830:cellsuite grbl_sim]");
                    let opt = format!(
                        "[OPT:V,{},{}]",
                        self.cfg.planner_blocks, self.cfg.rx_buffer_bytes
                    );
                    self.emit(&opt);
                    self.respond("ok".into());
                }
            }
            "$N" => {
                if need_idle(self) {
                    self.emit("$N0=");
                    self.emit("$N1=");
                    self.respond("ok".into());
                }
            }
            "$X" => {
                if self.state == MachineState::Alarm {
                    self.state = MachineState::Idle;
                    self.critical_lock = false;
                    self.emit("[MSG:Caution: Unlocked]");
                }
                self.respond("ok".into());
            }
            "$H" => self.error(&p.raw, 5),
            "$C" => {
                if need_idle(self) && self.state != MachineState::Alarm {
                    self.check_mode = !self.check_mode;
                    self.state = if self.check_mode {
                        MachineState::Check
                    } else {
                        MachineState::Idle
                    };
                    self.emit(if self.check_mode {
                        "[MSG:Enabled]"
                    } else {
                        "[MSG:Disabled]"
                    });
                    self.respond("ok".into());
                }
            }
            "$SLP" => self.respond("ok".into()),
            _ if cmd.starts_with("$J=") => return self.jog(p),
            _ if cmd.starts_with("$RST=") => self.respond("ok".into()),
            _ => {
                let setting = cmd[1..]
                    .split_once('=')
                    .and_then(|(n, v)| Some((n.parse::<u16>().ok()?, v.parse::<f64>().ok()?)));
                match setting {
                    Some((n, v)) => {
                        if need_idle(self) {
                            if n == 10 && (0.0..=255.0).contains(&v) {
                                self.cfg.status_mask = v as u8;
                            }
                            self.respond("ok".into());
                        }
                    }
                    None => self.error(&p.raw, 3),
                }
            }
        }
        true
    }

    /// `$J=`: a jog move through the parser's jog rules; false when the planner is full.
    pub(super) fn jog(&mut self, p: &PendingLine) -> bool {
        if !matches!(self.state, MachineState::Idle | MachineState::Jog) {
            self.error(&p.raw, 8);
            return true;
        }
        let mut base = self.modal.clone();
        base.position = self.queue_end_position();
        let (modal, action) = match gcode::execute(&base, &p.stored[3..], &self.cfg.axes, true) {
            Ok(x) => x,
            Err(code) => {
                self.error(&p.raw, code);
                return true;
            }
        };
        if !self.planner_has_room(action.moves.len()) {
            return false;
        }
        self.enqueue_moves(base.position.clone(), action.moves, true, None);
        self.modal.position = modal.position;
        self.respond("ok".into());
        true
    }
}
