//! Simulated time: tokio's clock times `time_scale`, counted from the simulator's start.

use std::time::Duration;

use tokio::time::Instant;

/// The farthest instant the simulator schedules: a century, which no test or job outlives.
const FAR: Duration = Duration::from_secs(100 * 365 * 24 * 3600);

/// Simulated seconds = tokio seconds since `origin` × `scale`.
#[derive(Debug, Clone, Copy)]
pub(super) struct SimClock {
    origin: Instant,
    scale: f64,
}

impl SimClock {
    /// A clock starting now, `time_scale` times faster than tokio's (1 unless `time_scale` > 0).
    pub(super) fn start(time_scale: f64) -> SimClock {
        SimClock {
            origin: Instant::now(),
            scale: if time_scale > 0.0 { time_scale } else { 1.0 },
        }
    }

    /// Simulated time now (s).
    pub(super) fn now(&self) -> f64 {
        self.origin.elapsed().as_secs_f64() * self.scale
    }

    /// The tokio instant of simulated time `t` (s); the origin for `t` < 0 (or NaN), and at
    /// most [`FAR`] after it, so a dwell of `P1e70` or a move at `F1e-9` waits "for ever"
    /// instead of overflowing the conversion.
    pub(super) fn instant_at(&self, t: f64) -> Instant {
        let wait = Duration::try_from_secs_f64((t / self.scale).max(0.0)).unwrap_or(FAR);
        self.origin + wait.min(FAR)
    }
}
