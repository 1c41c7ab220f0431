//! `$` commands: `$`, `$$`, `$#`, `$G`, `$I` (the firmware's build info), `$N` and `$Nx=line`
//! (startup blocks: executed when stored and after every reset), `$X`, `$H` (`error:5`: homing
//! is disabled), `$C`, `$SLP`, `$RST=$|#|*` (settings, offsets and startup blocks back to
//! defaults, then a reset), `$J=` jogging and `$n=v` (`$10` status mask, `$30` spindle speed at
//! full PWM and `$32` laser mode change behaviour). Those that GRBL runs only when idle answer
//! `error:8` otherwise. Every `$` line is recorded ([`SimEvent::SystemCommand`]).

use crate::protocol::MachineState;

use super::gcode;
use super::machine::Machine;
use super::planner::LogLine;
use super::report::fmt_pos;
use super::rx::PendingLine;

/// GRBL's `$N` slots.
const STARTUP_LINES: usize = 2;
/// GRBL's EEPROM line size: a longer startup block is `error:14`.
const EEPROM_LINE_SIZE: usize = 80;
/// `error:14`: line length exceeded.
const LINE_LENGTH_EXCEEDED: u8 = 14;

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
                self.emit(self.cfg.firmware.help());
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
                        (30, fmt_setting(self.cfg.spindle_max_rpm)),
                        (32, u8::from(self.cfg.laser_mode).to_string()),
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
                    let lines = self.cfg.firmware.build_info(
                        self.cfg.planner_blocks,
                        self.cfg.rx_buffer_bytes,
                        &self.cfg.axes,
                    );
                    for l in lines {
                        self.emit(&l);
                    }
                    self.respond("ok".into());
                }
            }
            "$N" => {
                if need_idle(self) {
                    for (n, line) in self.startup_lines.clone().iter().enumerate() {
                        self.emit(&format!("$N{n}={line}"));
                    }
                    self.respond("ok".into());
                }
            }
            "$X" => {
                if self.state == MachineState::Alarm {
                    self.state = MachineState::Idle;
                    self.critical_lock = false;
                    let msg = self.cfg.firmware.message("Caution: Unlocked");
                    self.emit(&msg);
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
                    let msg = self.cfg.firmware.message(if self.check_mode {
                        "Enabled"
                    } else {
                        "Disabled"
                    });
                    self.emit(&msg);
                    self.respond("ok".into());
                }
            }
            "$SLP" => self.respond("ok".into()),
            _ if cmd.starts_with("$J=") => return self.jog(p),
            _ if cmd.starts_with("$RST=") => {
                if need_idle(self) {
                    self.restore(p);
                }
            }
            _ if startup_slot(cmd).is_some() => {
                if let Some((n, line)) = startup_slot(cmd) {
                    self.store_startup_line(p, n, line);
                }
            }
            _ => {
                let setting = cmd[1..]
                    .split_once('=')
                    .and_then(|(n, v)| Some((n.parse::<u16>().ok()?, v.parse::<f64>().ok()?)));
                match setting {
                    Some((n, v)) => {
                        if need_idle(self) {
                            match n {
                                10 if (0.0..=255.0).contains(&v) => self.cfg.status_mask = v as u8,
                                30 => self.cfg.spindle_max_rpm = v,
                                32 => self.cfg.laser_mode = v != 0.0,
                                _ => {}
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

impl Machine {
    /// `$RST=$` (settings), `$RST=#` (work offsets), `$RST=*` (everything, startup blocks
    /// too): `[MSG:Restoring defaults]`, `ok`, then a reset as GRBL's `mc_reset`.
    fn restore(&mut self, p: &PendingLine) {
        let what = &p.stored["$RST=".len()..];
        let (settings, offsets, startup) = match what {
            "$" => (true, false, false),
            "#" => (false, true, false),
            "*" => (true, true, true),
            _ => return self.error(&p.raw, 3),
        };
        if settings {
            // GRBL's defaults.h for the settings the simulator models.
            self.cfg.status_mask = 1;
            self.cfg.spindle_max_rpm = 1000.0;
            self.cfg.laser_mode = false;
        }
        if offsets {
            let n = self.cfg.axes.len();
            self.modal.offsets = std::array::from_fn(|_| vec![0.0; n]);
        }
        if startup {
            self.startup_lines = Default::default();
        }
        let msg = self.cfg.firmware.message("Restoring defaults");
        self.emit(&msg);
        // Straight out: the reset right after would drop a delayed answer.
        self.emit("ok");
        self.soft_reset();
    }

    /// `$Nx=line`: GRBL executes the block to check it (so it takes effect now), then stores
    /// it to run after every reset. Only when idle.
    fn store_startup_line(&mut self, p: &PendingLine, n: usize, line: &str) {
        if self.state != MachineState::Idle {
            return self.error(&p.raw, 8);
        }
        if line.len() + 1 > EEPROM_LINE_SIZE {
            return self.error(&p.raw, LINE_LENGTH_EXCEEDED);
        }
        // `$Nx=` with nothing after it clears the slot.
        if line.is_empty() {
            self.startup_lines[n].clear();
            return self.respond("ok".into());
        }
        if let Err(code) = self.execute_block(line, p.connection) {
            return self.error(&p.raw, code);
        }
        self.startup_lines[n] = line.to_string();
        self.respond("ok".into());
    }

    /// Runs the stored startup blocks, each answered `>line:ok` or `>line:error:N`.
    pub(super) fn run_startup_lines(&mut self) {
        for line in self.startup_lines.clone() {
            if line.is_empty() {
                continue;
            }
            let status = match self.execute_block(&line, self.connection) {
                Ok(()) => "ok".to_string(),
                Err(code) => format!("error:{code}"),
            };
            self.emit(&format!(">{line}:{status}"));
        }
    }

    /// Parses and applies a stored G-code block now (the planner is empty: idle), logging it.
    fn execute_block(&mut self, line: &str, connection: u64) -> Result<(), u8> {
        let (modal, action) = gcode::execute(&self.modal, line, &self.cfg.axes, false)?;
        let log = LogLine {
            text: line.to_string(),
            seq: 0,
            connection,
            parser: super::ParserState::of(&modal),
        };
        self.modal = modal;
        if action.moves.is_empty() {
            self.enqueue_marker(log);
            self.spindle_set_at_rest();
        } else {
            let start = self.queue_end_position();
            self.enqueue_moves(start, action.moves, false, Some(log));
        }
        self.track_report_changes();
        Ok(())
    }
}

/// `$N0=line` → (0, line); `None` for anything else.
fn startup_slot(cmd: &str) -> Option<(usize, &str)> {
    let rest = cmd.strip_prefix("$N")?;
    let (n, line) = rest.split_once('=')?;
    let n: usize = n.parse().ok()?;
    (n < STARTUP_LINES).then_some((n, line))
}

/// A speed setting as `$$` prints it (GRBL's `N_DECIMAL_RPMVALUE` is 0): `1000`.
fn fmt_setting(v: f64) -> String {
    format!("{v:.0}")
}
