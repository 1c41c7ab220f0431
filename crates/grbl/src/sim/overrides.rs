//! Feed, rapid and spindle overrides (GRBL's real-time override commands), in percent.

use crate::protocol::Realtime;

/// The three overrides: feed 10–200 %, rapid 25/50/100 %, spindle 10–200 %.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Overrides {
    pub(super) feed: u16,
    pub(super) rapid: u16,
    pub(super) spindle: u16,
}

impl Default for Overrides {
    /// 100 % each (power-up, reset, program end).
    fn default() -> Self {
        Overrides {
            feed: 100,
            rapid: 100,
            spindle: 100,
        }
    }
}

impl Overrides {
    /// Back to 100 % each.
    pub(super) fn reset(&mut self) {
        *self = Overrides::default();
    }

    /// Applies an override command; other real-time commands change nothing.
    pub(super) fn apply(&mut self, command: Realtime) {
        match command {
            Realtime::FeedOverrideReset => self.feed = 100,
            Realtime::FeedOverridePlus10 => self.feed = (self.feed + 10).min(200),
            Realtime::FeedOverrideMinus10 => self.feed = self.feed.saturating_sub(10).max(10),
            Realtime::FeedOverridePlus1 => self.feed = (self.feed + 1).min(200),
            Realtime::FeedOverrideMinus1 => self.feed = self.feed.saturating_sub(1).max(10),
            Realtime::RapidOverride100 => self.rapid = 100,
            Realtime::RapidOverride50 => self.rapid = 50,
            Realtime::RapidOverride25 => self.rapid = 25,
            Realtime::SpindleOverrideReset => self.spindle = 100,
            Realtime::SpindleOverridePlus10 => self.spindle = (self.spindle + 10).min(200),
            Realtime::SpindleOverrideMinus10 => {
                self.spindle = self.spindle.saturating_sub(10).max(10)
            }
            Realtime::SpindleOverridePlus1 => self.spindle = (self.spindle + 1).min(200),
            Realtime::SpindleOverrideMinus1 => {
                self.spindle = self.spindle.saturating_sub(1).max(10)
            }
            _ => {}
        }
    }
}
