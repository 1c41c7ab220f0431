//! The firmware's main loop in simulated time: the RX buffer, `get_serial_commands` (line
//! numbers, checksums, resend), the `BUFSIZE` command queue, command handlers, the planner and
//! the heaters. Pure and synchronous: the link feeds it lines and drains its output.

use std::collections::VecDeque;

use super::heater::{Heater, HeaterSpec};
use super::{SimConfig, SimEvent};
use crate::protocol::{code_of, parse_host_line, word, HeaterReading, KILLED};

/// Steps per mm Marlin reports in `M114`'s `Count` (a stock i3: 80, 80, 400).
const STEPS_PER_MM: [f64; 3] = [80.0, 80.0, 400.0];
/// `HOMING_FEEDRATE_MM_M` XY: 50 mm/s.
const HOMING_MM_S: f64 = 50.0;

/// One planned move.
#[derive(Debug, Clone)]
struct Block {
    remaining_s: f64,
    to: [f64; 4],
}

/// The handler that holds the main loop (Marlin's blocking handlers).
#[derive(Debug, Clone)]
enum Running {
    /// `M109`/`M190`: waits until the temperature settled in the window for the residency.
    Heat {
        bed: bool,
        cooling_too: bool,
        residency_start: Option<f64>,
        last_report: f64,
    },
    /// A move waiting for a free planner block.
    PlannerRoom(Block),
    /// `M400`, and the synchronize before `G28`, `G4` and `M84`; then what follows.
    Synchronize(After),
    /// A dwell or homing running until a time.
    Until(f64, [Option<f64>; 3]),
}

/// What runs once the planner is empty.
#[derive(Debug, Clone, Copy)]
enum After {
    Nothing,
    Dwell(f64),
    Home([bool; 3]),
}

/// Marlin 2.1's state, as far as a host can see it.
#[derive(Debug)]
pub(crate) struct Firmware {
    pub(crate) cfg: SimConfig,
    pub(crate) now_s: f64,
    last_n: i64,
    rx: VecDeque<String>,
    rx_bytes: usize,
    queue: VecDeque<String>,
    running: Option<Running>,
    /// When the running handler started (host keepalive).
    running_since: f64,
    last_keepalive: f64,
    pub(crate) hotend: Heater,
    pub(crate) bed: Heater,
    planner: VecDeque<Block>,
    /// `current_position`: where the planned moves end.
    planned: [f64; 4],
    /// Where the steppers are.
    pub(crate) stepper: [f64; 4],
    relative: bool,
    e_relative: bool,
    feed_mm_s: f64,
    feed_percent: f64,
    flow_percent: f64,
    wait_for_heatup: bool,
    last_activity: f64,
    /// The kill reason once `kill()` ran: nothing is read until a reset.
    pub(crate) halted: Option<String>,
    /// Frozen by a fault: reads and answers nothing until the next connection.
    pub(crate) frozen: bool,
    /// The link task closes the connection when this is set (a fault).
    pub(crate) drop_requested: bool,
    pub(crate) out: Vec<String>,
    pub(crate) events: Vec<SimEvent>,
    /// Commands processed, without `N…*cs`, in order.
    pub(crate) executed: Vec<String>,
    /// Lines received since the simulator started (fault positions count these).
    pub(crate) received: u64,
    pub(crate) moves_done: u64,
}

impl Firmware {
    pub(crate) fn new(cfg: SimConfig) -> Self {
        Firmware {
            cfg,
            now_s: 0.0,
            last_n: 0,
            rx: VecDeque::new(),
            rx_bytes: 0,
            queue: VecDeque::new(),
            running: None,
            running_since: 0.0,
            last_keepalive: 0.0,
            hotend: Heater::new(HeaterSpec::HOTEND),
            bed: Heater::new(HeaterSpec::BED),
            planner: VecDeque::new(),
            planned: [0.0; 4],
            stepper: [0.0; 4],
            relative: false,
            e_relative: false,
            feed_mm_s: 25.0,
            feed_percent: 100.0,
            flow_percent: 100.0,
            wait_for_heatup: true,
            last_activity: 0.0,
            halted: None,
            frozen: false,
            drop_requested: false,
            out: Vec::new(),
            events: Vec::new(),
            executed: Vec::new(),
            received: 0,
            moves_done: 0,
        }
    }

    fn say(&mut self, line: impl Into<String>) {
        self.out.push(line.into());
    }

    /// A hardware reset (reset button, DTR on port open): the board reboots, heaters off,
    /// planner and queue gone, position unknown; the nozzle keeps its heat. Prints the banner.
    pub(crate) fn reset(&mut self) {
        let (hot, bed) = (self.hotend.temp_c, self.bed.temp_c);
        let (h_fault, b_fault) = (
            (self.hotend.power_lost, self.hotend.sensor_open),
            (self.bed.power_lost, self.bed.sensor_open),
        );
        let keep = Firmware::new(self.cfg.clone());
        let events = std::mem::take(&mut self.events);
        let executed = std::mem::take(&mut self.executed);
        let (now, received, moves) = (self.now_s, self.received, self.moves_done);
        *self = keep;
        self.now_s = now;
        self.last_activity = now;
        self.received = received;
        self.moves_done = moves;
        self.events = events;
        self.executed = executed;
        self.hotend.temp_c = hot;
        self.bed.temp_c = bed;
        (self.hotend.power_lost, self.hotend.sensor_open) = h_fault;
        (self.bed.power_lost, self.bed.sensor_open) = b_fault;
        self.events.push(SimEvent::Reset);
        self.say("start");
        self.say("echo:Marlin 2.1.2.4");
        self.say("echo: Last Updated: 2024-06-27 | Author: (cellsuite simulator)");
        self.say("echo:Compiled: Jun 27 2024");
        self.say(format!(
            "echo:Free Memory: 2048  PlannerBufferBytes: {}",
            self.cfg.block_buffer_size * 64
        ));
    }

    /// A line arrived (line end stripped). The emergency parser sees it at once; the rest waits
    /// in the RX buffer for room in the command queue.
    pub(crate) fn receive_line(&mut self, raw: &str) {
        if raw.trim().is_empty() {
            return;
        }
        self.received += 1;
        let n = self.received;
        if self.cfg.faults.drop_at_lines.contains(&n) {
            self.events.push(SimEvent::LinkDropped { at_line: n });
            self.drop_requested = true;
            return;
        }
        if self.cfg.faults.freeze_at_line == Some(n) {
            self.events.push(SimEvent::Frozen { at_line: n });
            self.frozen = true;
        }
        if self.frozen || self.halted.is_some() {
            return;
        }
        if self.cfg.faults.heater_fail_at_line == Some(n) {
            self.hotend.power_lost = true;
        }
        if self.cfg.faults.thermistor_open_at_line == Some(n) {
            self.hotend.sensor_open = true;
        }
        let mut line = raw.to_owned();
        if self.cfg.faults.corrupt_at_lines.contains(&n) {
            // Line noise: one bit flipped in the first byte after the N word.
            let at = line.find(' ').map_or(0, |i| i + 1).min(line.len() - 1);
            let mut bytes = line.into_bytes();
            bytes[at] ^= 0x04;
            line = String::from_utf8_lossy(&bytes).into_owned();
            self.events.push(SimEvent::Corrupted { at_line: n });
        }
        // EMERGENCY_PARSER (feature/e_parser.h): M108, M112, M410 act as they arrive, even
        // while a handler blocks or the queue is full; they still go through the queue after.
        match code_of(parse_host_line(&line).command) {
            Some(('M', 108)) => {
                self.wait_for_heatup = false;
                self.events.push(SimEvent::Emergency("M108".into()));
            }
            Some(('M', 112)) => {
                self.events.push(SimEvent::Emergency("M112".into()));
                self.kill("M112 Shutdown");
                return;
            }
            Some(('M', 410)) => {
                self.events.push(SimEvent::Emergency("M410".into()));
                self.quickstop();
            }
            _ => {}
        }
        if self.rx_bytes + line.len() + 1 > self.cfg.rx_buffer_bytes {
            self.events.push(SimEvent::RxOverflow { at_line: n });
            return;
        }
        self.rx_bytes += line.len() + 1;
        self.rx.push_back(line);
    }

    /// `kill()`: heaters off, steppers off, everything dropped; the halt message.
    pub(crate) fn kill(&mut self, reason: &str) {
        self.hotend.off();
        self.bed.off();
        self.planner.clear();
        self.queue.clear();
        self.rx.clear();
        self.rx_bytes = 0;
        self.running = None;
        self.say(format!("Error:{KILLED}"));
        self.say("//action:kill");
        self.events.push(SimEvent::Killed {
            reason: reason.to_owned(),
        });
        self.halted = Some(reason.to_owned());
    }

    fn quickstop(&mut self) {
        self.planner.clear();
        if matches!(self.running, Some(Running::PlannerRoom(_))) {
            self.running = None;
            self.say("ok");
        }
        self.planned = self.stepper;
    }

    /// Advances simulated time by `dt_s` and runs the main loop.
    pub(crate) fn tick(&mut self, dt_s: f64) {
        if self.frozen {
            return;
        }
        self.now_s += dt_s;
        if self.halted.is_some() {
            // Heaters are off; the nozzle still cools.
            let _ = self.hotend.step(dt_s, self.now_s);
            let _ = self.bed.step(dt_s, self.now_s);
            return;
        }
        for (i, bed) in [(0, false), (1, true)] {
            let h = if bed { &mut self.bed } else { &mut self.hotend };
            if let Some(e) = h.step(dt_s, self.now_s) {
                let id = if i == 0 { "0" } else { "bed" };
                self.say(format!(
                    "Error:{}, system stopped! Heater_ID: {id}",
                    e.text()
                ));
                self.events.push(SimEvent::Thermal {
                    bed,
                    error: e,
                    at_s: self.now_s,
                });
                self.kill(&format!("{} (heater {id})", e.text()));
                return;
            }
        }
        self.advance_planner(dt_s);
        self.main_loop();
        self.keepalive();
        self.idle_timeout();
    }

    fn advance_planner(&mut self, dt_s: f64) {
        let mut left = dt_s;
        while left > 0.0 {
            let Some(b) = self.planner.front_mut() else {
                break;
            };
            if b.remaining_s > left {
                b.remaining_s -= left;
                break;
            }
            left -= b.remaining_s;
            self.stepper = b.to;
            self.planner.pop_front();
            self.moves_done += 1;
            self.last_activity = self.now_s;
        }
    }

    fn main_loop(&mut self) {
        loop {
            if let Some(r) = self.running.take() {
                match self.resume(r) {
                    Some(still) => {
                        self.running = Some(still);
                        return;
                    }
                    None => self.say("ok"),
                }
            }
            self.get_serial_commands();
            let Some(cmd) = self.queue.pop_front() else {
                return;
            };
            self.last_activity = self.now_s;
            self.running_since = self.now_s;
            self.last_keepalive = self.now_s;
            self.process(&cmd);
            if self.halted.is_some() {
                return;
            }
        }
    }

    /// `get_serial_commands`: RX lines into the queue while it has room, checking numbered
    /// lines (`queue.cpp`).
    fn get_serial_commands(&mut self) {
        while self.queue.len() < self.cfg.bufsize {
            let Some(line) = self.rx.pop_front() else {
                return;
            };
            self.rx_bytes -= line.len() + 1;
            let text = line.split(';').next().unwrap_or("").trim().to_owned();
            if text.is_empty() {
                continue;
            }
            let parsed = parse_host_line(&text);
            if let Some(n) = parsed.number {
                let is_m110 = code_of(parsed.command) == Some(('M', 110));
                let n = if is_m110 {
                    word(parsed.command, 'N').map_or(n, |v| v as i64)
                } else {
                    n
                };
                if n != self.last_n + 1 && !is_m110 {
                    self.line_error("Line Number is not Last Line Number+1");
                    return;
                }
                match parsed.checksum_ok {
                    Some(true) => {}
                    Some(false) => {
                        self.line_error("checksum mismatch");
                        return;
                    }
                    None => {
                        self.line_error("No Checksum with line number");
                        return;
                    }
                }
                self.last_n = n;
            }
            self.queue.push_back(parsed.command.to_owned());
        }
    }

    /// `gcode_line_error`: the error, the RX buffer emptied, `Resend:` and `ok`.
    fn line_error(&mut self, why: &str) {
        self.say(format!("Error:{why}, Last Line: {}", self.last_n));
        self.rx.clear();
        self.rx_bytes = 0;
        self.say(format!("Resend: {}", self.last_n + 1));
        self.say("ok");
        self.events.push(SimEvent::ResendRequested {
            line: (self.last_n + 1) as u64,
            why: why.to_owned(),
        });
    }

    fn heater_states(&self) -> String {
        let (h, b) = (&self.hotend, &self.bed);
        format!(
            "T:{:.2} /{:.2} B:{:.2} /{:.2} @:{} B@:{}",
            h.reading(),
            h.target_c,
            b.reading(),
            b.target_c,
            (h.duty * 127.0).round() as u32,
            (b.duty * 127.0).round() as u32
        )
    }

    /// Runs one command from the queue; leaves a blocking handler in `running` or says `ok`.
    fn process(&mut self, cmd: &str) {
        self.executed.push(cmd.to_owned());
        let Some((letter, code)) = code_of(cmd) else {
            if cmd.starts_with('T') {
                self.say("ok");
            } else {
                self.unknown(cmd);
            }
            return;
        };
        let blocking = match (letter, code) {
            ('G', 0..=3) => self.motion(cmd, code),
            ('G', 4) => {
                let s = word(cmd, 'S').unwrap_or(0.0) + word(cmd, 'P').unwrap_or(0.0) / 1000.0;
                Some(Running::Synchronize(After::Dwell(s)))
            }
            ('G', 20 | 21) => None,
            ('G', 28) => {
                let axes = ['X', 'Y', 'Z'].map(|a| cmd.to_ascii_uppercase().contains(a));
                let axes = if axes.iter().any(|&a| a) {
                    axes
                } else {
                    [true; 3]
                };
                Some(Running::Synchronize(After::Home(axes)))
            }
            ('G', 90) => {
                self.relative = false;
                self.e_relative = false;
                None
            }
            ('G', 91) => {
                self.relative = true;
                self.e_relative = true;
                None
            }
            ('G', 92) => {
                for (i, a) in ['X', 'Y', 'Z', 'E'].into_iter().enumerate() {
                    if let Some(v) = word(cmd, a) {
                        self.planned[i] = v;
                        if self.planner.is_empty() {
                            self.stepper[i] = v;
                        }
                    }
                }
                None
            }
            ('M', 82) => {
                self.e_relative = false;
                None
            }
            ('M', 83) => {
                self.e_relative = true;
                None
            }
            ('M', 18 | 84 | 400) => Some(Running::Synchronize(After::Nothing)),
            ('M', 104 | 109) => {
                let target = word(cmd, 'S').or_else(|| word(cmd, 'R'));
                if let Some(t) = target {
                    self.hotend.set_target(t, self.now_s);
                }
                (code == 109 && target.is_some_and(|t| t > 0.0)).then(|| {
                    self.wait_for_heatup = true;
                    Running::Heat {
                        bed: false,
                        cooling_too: word(cmd, 'R').is_some(),
                        residency_start: None,
                        last_report: self.now_s,
                    }
                })
            }
            ('M', 140 | 190) => {
                let target = word(cmd, 'S').or_else(|| word(cmd, 'R'));
                if let Some(t) = target {
                    self.bed.set_target(t, self.now_s);
                }
                (code == 190 && target.is_some_and(|t| t > 0.0)).then(|| {
                    self.wait_for_heatup = true;
                    Running::Heat {
                        bed: true,
                        cooling_too: word(cmd, 'R').is_some(),
                        residency_start: None,
                        last_report: self.now_s,
                    }
                })
            }
            ('M', 105) => {
                // M105 says its own `ok` with the temperatures.
                let s = format!("ok {}", self.heater_states());
                self.say(s);
                return;
            }
            ('M', 114) => {
                let p = self.planned;
                let c = self.stepper;
                let s = format!(
                    "X:{:.2} Y:{:.2} Z:{:.2} E:{:.2} Count X:{} Y:{} Z:{}",
                    p[0],
                    p[1],
                    p[2],
                    p[3],
                    (c[0] * STEPS_PER_MM[0]).round() as i64,
                    (c[1] * STEPS_PER_MM[1]).round() as i64,
                    (c[2] * STEPS_PER_MM[2]).round() as i64
                );
                self.say(s);
                None
            }
            ('M', 115) => {
                self.say("FIRMWARE_NAME:Marlin 2.1.2.4 (cellsuite simulator) SOURCE_CODE_URL:github.com/MarlinFirmware/Marlin PROTOCOL_VERSION:1.0 MACHINE_TYPE:3D Printer EXTRUDER_COUNT:1 UUID:cede2a2f-41a2-4748-9b12-c55c62f367ff");
                self.say("Cap:EMERGENCY_PARSER:1");
                self.say("Cap:HOST_ACTION_COMMANDS:1");
                None
            }
            ('M', 110) => {
                if let Some(n) = word(cmd, 'N') {
                    self.last_n = n as i64;
                }
                None
            }
            ('M', 220) => {
                if let Some(s) = word(cmd, 'S') {
                    self.feed_percent = s.clamp(10.0, 999.0);
                }
                None
            }
            ('M', 221) => {
                if let Some(s) = word(cmd, 'S') {
                    self.flow_percent = s.clamp(10.0, 999.0);
                }
                None
            }
            // Fan, LCD message, resume-from-stopped; the emergency commands already acted.
            ('M', 106 | 107 | 117 | 999 | 108 | 112 | 410) => None,
            _ => {
                self.unknown(cmd);
                return;
            }
        };
        match blocking {
            None => self.say("ok"),
            Some(r) => match self.resume(r) {
                None => self.say("ok"),
                Some(still) => self.running = Some(still),
            },
        }
    }

    fn unknown(&mut self, cmd: &str) {
        let head = cmd.split_whitespace().next().unwrap_or(cmd);
        self.say(format!("echo:Unknown command: \"{head}\""));
        self.say("ok");
    }

    /// A move: into the planner if it has room, else the handler waits for room.
    fn motion(&mut self, cmd: &str, code: u32) -> Option<Running> {
        if let Some(f) = word(cmd, 'F') {
            self.feed_mm_s = (f / 60.0).max(0.01);
        }
        let mut to = self.planned;
        for (i, a) in ['X', 'Y', 'Z', 'E'].into_iter().enumerate() {
            if let Some(v) = word(cmd, a) {
                let rel = if i == 3 {
                    self.e_relative
                } else {
                    self.relative
                };
                to[i] = if rel { self.planned[i] + v } else { v };
            }
        }
        let from = self.planned;
        let chord =
            ((to[0] - from[0]).powi(2) + (to[1] - from[1]).powi(2) + (to[2] - from[2]).powi(2))
                .sqrt();
        let length = if code == 2 || code == 3 {
            let (i, j) = (word(cmd, 'I').unwrap_or(0.0), word(cmd, 'J').unwrap_or(0.0));
            let (cx, cy) = (from[0] + i, from[1] + j);
            let r = i.hypot(j);
            let a0 = (from[1] - cy).atan2(from[0] - cx);
            let a1 = (to[1] - cy).atan2(to[0] - cx);
            let mut sweep = if code == 3 { a1 - a0 } else { a0 - a1 };
            if sweep <= 1e-9 {
                sweep += std::f64::consts::TAU;
            }
            (r * sweep).hypot(to[2] - from[2])
        } else {
            chord
        };
        let length = if length > 0.0 {
            length
        } else {
            (to[3] - from[3]).abs()
        };
        self.planned = to;
        if length <= 0.0 {
            return None;
        }
        let speed = (self.feed_mm_s * self.feed_percent / 100.0).min(self.cfg.max_feed_mm_s);
        let block = Block {
            remaining_s: length / speed,
            to,
        };
        Some(Running::PlannerRoom(block))
    }

    /// Goes on with a blocking handler; `None` once it is done.
    fn resume(&mut self, r: Running) -> Option<Running> {
        match r {
            Running::PlannerRoom(b) => {
                if self.planner.len() < self.cfg.block_buffer_size {
                    self.planner.push_back(b);
                    None
                } else {
                    Some(Running::PlannerRoom(b))
                }
            }
            Running::Synchronize(after) => {
                if !self.planner.is_empty() {
                    return Some(Running::Synchronize(after));
                }
                match after {
                    After::Nothing => None,
                    After::Dwell(s) => Some(Running::Until(self.now_s + s, [None; 3])),
                    After::Home(axes) => {
                        let mut at = [None; 3];
                        let mut t = 0.0f64;
                        for i in 0..3 {
                            if axes[i] {
                                at[i] = Some(0.0);
                                // Fast approach, back off 5 mm, slow bump at half speed.
                                t = t.max(self.stepper[i].abs() / HOMING_MM_S + 0.3);
                            }
                        }
                        Some(Running::Until(self.now_s + t, at))
                    }
                }
            }
            Running::Until(until, home) => {
                if self.now_s < until {
                    return Some(Running::Until(until, home));
                }
                for (i, v) in home.iter().enumerate() {
                    if let Some(v) = v {
                        self.stepper[i] = *v;
                        self.planned[i] = *v;
                    }
                }
                None
            }
            Running::Heat {
                bed,
                cooling_too,
                mut residency_start,
                mut last_report,
            } => {
                let h = if bed { &self.bed } else { &self.hotend };
                let (temp, target) = (h.reading(), h.target_c);
                if !self.wait_for_heatup || target <= 0.0 {
                    return None;
                }
                // `M109 S`: no wait for cooling.
                if !cooling_too && temp > target + self.cfg.temp_window_k {
                    return None;
                }
                let residency = if bed {
                    self.cfg.bed_residency_s
                } else {
                    self.cfg.temp_residency_s
                };
                match residency_start {
                    None if (temp - target).abs() <= self.cfg.temp_window_k => {
                        residency_start = Some(self.now_s)
                    }
                    Some(_) if (temp - target).abs() > self.cfg.temp_hysteresis_k => {
                        residency_start = None
                    }
                    _ => {}
                }
                if residency_start.is_some_and(|s| self.now_s - s >= residency) {
                    return None;
                }
                if self.now_s - last_report >= 1.0 {
                    last_report = self.now_s;
                    let w = residency_start.map_or("?".to_owned(), |s| {
                        format!("{}", (residency - (self.now_s - s)).max(0.0) as i64)
                    });
                    let line = format!(" {} W:{w}", self.heater_states());
                    self.say(line);
                }
                Some(Running::Heat {
                    bed,
                    cooling_too,
                    residency_start,
                    last_report,
                })
            }
        }
    }

    /// HOST_KEEPALIVE_FEATURE: `echo:busy: processing` every interval while a handler (other
    /// than a heating wait, which reports temperatures instead) holds the loop.
    fn keepalive(&mut self) {
        let busy = matches!(
            self.running,
            Some(Running::PlannerRoom(_) | Running::Synchronize(_) | Running::Until(..))
        );
        if busy && self.now_s - self.last_keepalive >= self.cfg.keepalive_interval_s {
            self.last_keepalive = self.now_s;
            self.say("echo:busy: processing");
        }
    }

    /// HOTEND_IDLE_TIMEOUT: heaters off after this long with no command and no motion.
    fn idle_timeout(&mut self) {
        let Some(limit) = self.cfg.hotend_idle_timeout_s else {
            return;
        };
        let heating = self.hotend.target_c > 0.0 || self.bed.target_c > 0.0;
        if heating
            && self.running.is_none()
            && self.planner.is_empty()
            && self.now_s - self.last_activity >= limit
        {
            self.hotend.off();
            self.bed.off();
            self.events.push(SimEvent::IdleTimeout { at_s: self.now_s });
        }
    }

    pub(crate) fn readings(&self) -> (HeaterReading, HeaterReading) {
        (
            HeaterReading {
                current: self.hotend.reading(),
                target: self.hotend.target_c,
            },
            HeaterReading {
                current: self.bed.reading(),
                target: self.bed.target_c,
            },
        )
    }

    pub(crate) fn overrides(&self) -> (f64, f64) {
        (self.feed_percent, self.flow_percent)
    }

    pub(crate) fn planned_blocks(&self) -> usize {
        self.planner.len()
    }

    pub(crate) fn busy(&self) -> bool {
        self.running.is_some() || !self.queue.is_empty() || !self.rx.is_empty()
    }

    pub(crate) fn last_line_number(&self) -> i64 {
        self.last_n
    }
}
