//! Simulator settings: firmware flavour, time scale, link speed and latency, buffer sizes, axes,
//! rates, spindle settings, what a new host sees.

use super::{Faults, SimFirmware};

/// What a newly attached host sees.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnConnect {
    /// The banner, machine state untouched (grblHAL on USB or telnet; GRBL on a board whose
    /// auto-reset is disabled or behind a serial-to-TCP bridge).
    Banner,
    /// A hardware reset, as an Arduino does when the port opens (DTR): motion, planner,
    /// position, parser state and spindle gone, work offsets kept, then the banner.
    Reset,
    /// Nothing: no banner, no reset (FluidNC over telnet greets no one; the machine keeps
    /// running).
    Silent,
}

/// Simulator settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Which firmware the controller speaks as (banner, `$I`, messages, report rules). Set
    /// through [`SimConfig::for_firmware`], which also sets that firmware's buffer sizes and
    /// [`on_connect`](SimConfig::on_connect).
    pub firmware: SimFirmware,
    /// Simulated seconds per second of tokio time (10.0 runs ten times faster than real time).
    pub time_scale: f64,
    /// Serial baud rate (8N1: baud/10 bytes/s in each direction); `None` for an unthrottled
    /// link.
    pub baud: Option<u32>,
    /// One-way link latency (s), added to every byte in both directions (USB-serial adapters
    /// add 1-16 ms).
    pub latency_s: f64,
    /// RX buffer size (GRBL: 128, one slot stays empty; grblHAL 1024; FluidNC 1200). `Bf:` and
    /// `$I` report it.
    pub rx_buffer_bytes: usize,
    /// Usable planner blocks (GRBL on an AVR: 15; grblHAL 100; FluidNC 15).
    pub planner_blocks: usize,
    /// Axis letters, in report order (GRBL 1.1: `XYZ`; grblHAL-style `XYUV` etc. also work).
    pub axes: Vec<char>,
    /// Max rate of every axis (`$110`-`$112`, mm/min): rapids run at it, feed moves and jogs no
    /// faster.
    pub rapid_mm_min: f64,
    /// Deceleration for feed holds and jog cancels (mm/s²).
    pub accel_mm_s2: f64,
    /// `$10` status report mask: bit 0 MPos (else WPos), bit 1 `Bf:` buffer data.
    pub status_mask: u8,
    /// What a new host sees: the banner, a reset, or nothing.
    pub on_connect: OnConnect,
    /// `$30`: the spindle speed (laser power) at full PWM; `FS:` reports no more than this.
    pub spindle_max_rpm: f64,
    /// `$32`: laser mode. The laser fires only during feed moves (`M4`: power scaled with the
    /// speed, off between moves; `M3`: constant, also at rest after a feed move) and goes out
    /// when a feed hold completes (GRBL's `DISABLE_LASER_DURING_HOLD`).
    pub laser_mode: bool,
    /// Events and output due within this much tokio time are handled at once instead of
    /// sleeping for them: tokio's timer has a 1 ms resolution, which would otherwise delay every
    /// answer by up to 1 ms of real time (10 ms of simulated time at `time_scale` 10). The
    /// simulation then runs ahead of the clock by at most this much. Use zero under a paused
    /// clock for exact timing.
    pub timer_slack: std::time::Duration,
    /// Injected faults.
    pub faults: Faults,
}

impl SimConfig {
    /// The defaults for `firmware`: its RX buffer, planner blocks and connect behaviour.
    pub fn for_firmware(firmware: SimFirmware) -> SimConfig {
        SimConfig {
            firmware,
            time_scale: 1.0,
            baud: Some(115_200),
            latency_s: 0.0,
            rx_buffer_bytes: firmware.rx_buffer_bytes(),
            planner_blocks: firmware.planner_blocks(),
            axes: vec!['X', 'Y', 'Z'],
            rapid_mm_min: 3000.0,
            accel_mm_s2: 200.0,
            status_mask: 3,
            on_connect: firmware.on_connect(),
            spindle_max_rpm: 1000.0,
            laser_mode: false,
            timer_slack: std::time::Duration::from_millis(1),
            faults: Faults::default(),
        }
    }
}

impl Default for SimConfig {
    /// GRBL 1.1h: 128-byte RX buffer, 15 planner blocks, banner on connect.
    fn default() -> Self {
        SimConfig::for_firmware(SimFirmware::Grbl11h)
    }
}
