//! Simulator settings: time scale, link speed and latency, buffer sizes, axes, rates.

use crate::protocol::{PLANNER_BLOCKS, RX_BUFFER_SIZE};

use super::Faults;

/// Simulator settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Simulated seconds per second of tokio time (10.0 runs ten times faster than real time).
    pub time_scale: f64,
    /// Serial baud rate (8N1: baud/10 bytes/s in each direction); `None` for an unthrottled
    /// link.
    pub baud: Option<u32>,
    /// One-way link latency (s), added to every byte in both directions (USB-serial adapters
    /// add 1-16 ms).
    pub latency_s: f64,
    /// Serial RX ring size (GRBL: 128; one slot stays empty).
    pub rx_buffer_bytes: usize,
    /// Usable planner blocks (GRBL on an AVR: 15).
    pub planner_blocks: usize,
    /// Axis letters, in report order (GRBL 1.1: `XYZ`; grblHAL-style `XYUV` etc. also work).
    pub axes: Vec<char>,
    /// Rapid rate for every axis (mm/min).
    pub rapid_mm_min: f64,
    /// Deceleration for feed holds and jog cancels (mm/s²).
    pub accel_mm_s2: f64,
    /// `$10` status report mask: bit 0 MPos (else WPos), bit 1 `Bf:` buffer data.
    pub status_mask: u8,
    /// Print the banner when a host connects (as an Arduino does when the port opens), without
    /// resetting anything.
    pub banner_on_connect: bool,
    /// Events and output due within this much tokio time are handled at once instead of
    /// sleeping for them: tokio's timer has a 1 ms resolution, which would otherwise delay every
    /// answer by up to 1 ms of real time (10 ms of simulated time at `time_scale` 10). The
    /// simulation then runs ahead of the clock by at most this much. Use zero under a paused
    /// clock for exact timing.
    pub timer_slack: std::time::Duration,
    /// Injected faults.
    pub faults: Faults,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            time_scale: 1.0,
            baud: Some(115_200),
            latency_s: 0.0,
            rx_buffer_bytes: RX_BUFFER_SIZE,
            planner_blocks: PLANNER_BLOCKS,
            axes: vec!['X', 'Y', 'Z'],
            rapid_mm_min: 3000.0,
            accel_mm_s2: 200.0,
            status_mask: 3,
            banner_on_connect: true,
            timer_slack: std::time::Duration::from_millis(1),
            faults: Faults::default(),
        }
    }
}
