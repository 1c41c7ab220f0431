//! Simulated time: tokio's clock times `time_scale`, counted from the simulator's start.

use tokio::time::Instant;

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

    /// The tokio instant of simulated time `t` (s); the origin for `t` < 0.
    pub(super) fn instant_at(&self, t: f64) -> Instant {
        self.origin + std::time::Duration::from_secs_f64((t / self.scale).max(0.0))
    }
}
