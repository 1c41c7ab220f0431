//! Replay timing, pure: no DDS, no bag, no clock of its own. Every call that needs the time
//! takes `now`, a [`Duration`] since any fixed origin (the replayer uses the moment it started),
//! so the tests can drive it by hand.
//!
//! - [`Timeline`] places each message of a pass on the replay timeline: a message logged
//!   before `bag start + start_offset` is skipped; the first one kept is offset 0 and every
//!   later one keeps its log-time gap to it. Time before the first kept message is not waited
//!   out (a bag whose selected topic starts 40 s in plays it at once).
//! - [`ReplayClock`] maps that bag time to real time at a rate: a message at bag offset `b`
//!   is due at `real₀ + (b − bag₀) / rate`, where (`real₀`, `bag₀`) is the clock's last anchor
//!   (its start, or the last resume). Pausing freezes bag time; resuming re-anchors at the
//!   paused position, so the time spent paused is not made up in a burst. A new pass (loop)
//!   re-anchors at bag time 0.

use std::time::Duration;

/// Checks a replay rate: finite and > 0.
///
/// # Errors
/// The rate, in words (the caller names the parameter).
pub fn check_rate(rate: f64) -> Result<f64, String> {
    if rate.is_finite() && rate > 0.0 {
        Ok(rate)
    } else {
        Err(format!(
            "{rate}: expected a number > 0 (1 = recorded speed)"
        ))
    }
}

/// Where each message of one pass falls on the replay timeline; see the [module docs](self).
#[derive(Debug, Clone)]
pub struct Timeline {
    start_ns: u64,
    origin_ns: Option<u64>,
}

impl Timeline {
    /// A timeline for a bag whose first message was logged at `bag_start_ns`, skipping the
    /// first `start_offset` of it.
    pub fn new(bag_start_ns: u64, start_offset: Duration) -> Self {
        let offset_ns = u64::try_from(start_offset.as_nanos()).unwrap_or(u64::MAX);
        Timeline {
            start_ns: bag_start_ns.saturating_add(offset_ns),
            origin_ns: None,
        }
    }

    /// The bag offset of a message logged at `log_time_ns` (messages come in log-time order),
    /// or `None` if it lies before the start offset and is skipped.
    pub fn place(&mut self, log_time_ns: u64) -> Option<Duration> {
        if log_time_ns < self.start_ns {
            return None;
        }
        let origin = *self.origin_ns.get_or_insert(log_time_ns);
        // A reader yields log-time order; an out-of-order message is simply due at once.
        Some(Duration::from_nanos(log_time_ns.saturating_sub(origin)))
    }

    /// Starts the next pass (a loop): same start offset, origin found again.
    pub fn rewind(&mut self) {
        self.origin_ns = None;
    }
}

/// The replay clock: bag time at a rate, with pause; see the [module docs](self).
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayClock {
    rate: f64,
    state: State,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum State {
    /// Bag time `bag` was reached at real time `real`, and bag time runs on from there.
    Running { real: Duration, bag: Duration },
    /// Bag time stands still at `bag`.
    Paused { bag: Duration },
}

impl ReplayClock {
    /// A clock at bag time 0 from `now`, running at `rate` (×N; checked by [`check_rate`]),
    /// or paused there.
    ///
    /// # Errors
    /// A rate that is not finite and > 0.
    pub fn new(rate: f64, now: Duration, paused: bool) -> Result<Self, String> {
        let rate = check_rate(rate)?;
        let state = if paused {
            State::Paused {
                bag: Duration::ZERO,
            }
        } else {
            State::Running {
                real: now,
                bag: Duration::ZERO,
            }
        };
        Ok(ReplayClock { rate, state })
    }

    /// The rate (×N).
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// Whether bag time stands still.
    pub fn is_paused(&self) -> bool {
        matches!(self.state, State::Paused { .. })
    }

    /// Bag time at real time `now` (`now` before the last anchor counts as the anchor).
    pub fn position(&self, now: Duration) -> Duration {
        match self.state {
            State::Running { real, bag } => bag + now.saturating_sub(real).mul_f64(self.rate),
            State::Paused { bag } => bag,
        }
    }

    /// Pauses (or resumes) at `now`. Returns whether that changed anything.
    pub fn set_paused(&mut self, paused: bool, now: Duration) -> bool {
        match (self.state, paused) {
            (State::Running { .. }, true) => {
                self.state = State::Paused {
                    bag: self.position(now),
                };
                true
            }
            (State::Paused { bag }, false) => {
                self.state = State::Running { real: now, bag };
                true
            }
            _ => false,
        }
    }

    /// The real time at which the message at bag offset `offset` is due (possibly already
    /// past: then it is late and goes at once); `None` while paused.
    pub fn due(&self, offset: Duration) -> Option<Duration> {
        match self.state {
            State::Running { real, bag } => {
                Some(real + offset.saturating_sub(bag).div_f64(self.rate))
            }
            State::Paused { .. } => None,
        }
    }

    /// A new pass starts at `now`: bag time 0 again, paused or running as before.
    pub fn restart(&mut self, now: Duration) {
        self.state = match self.state {
            State::Running { .. } => State::Running {
                real: now,
                bag: Duration::ZERO,
            },
            State::Paused { .. } => State::Paused {
                bag: Duration::ZERO,
            },
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(secs: f64) -> Duration {
        Duration::from_secs_f64(secs)
    }

    fn ns(secs: f64) -> u64 {
        (secs * 1e9) as u64
    }

    /// Publish times of messages at `offsets` when the replayer publishes each as soon as it is
    /// due, pausing and resuming at the given real times (a model of the node's loop).
    fn simulate(
        clock: &mut ReplayClock,
        offsets: &[Duration],
        mut toggles: Vec<(Duration, bool)>,
    ) -> Vec<Duration> {
        toggles.reverse();
        let mut now = Duration::ZERO;
        let mut out = Vec::new();
        for &offset in offsets {
            loop {
                let due = clock.due(offset);
                let next_toggle = toggles.last().copied();
                match (due, next_toggle) {
                    (Some(d), Some((t, _))) if d.max(now) <= t => {
                        now = d.max(now);
                        break;
                    }
                    (Some(d), None) => {
                        now = d.max(now);
                        break;
                    }
                    (_, Some((t, paused))) => {
                        now = t.max(now);
                        clock.set_paused(paused, now);
                        toggles.pop();
                    }
                    (None, None) => panic!("paused for ever"),
                }
            }
            out.push(now);
        }
        out
    }

    #[test]
    fn rates_must_be_positive_and_finite() {
        assert_eq!(check_rate(2.5), Ok(2.5));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(check_rate(bad).is_err(), "{bad}");
            assert!(ReplayClock::new(bad, Duration::ZERO, false).is_err());
        }
    }

    #[test]
    fn the_rate_scales_the_gaps() {
        let offsets = [s(0.0), s(1.0), s(3.0)];
        let mut clock = ReplayClock::new(4.0, Duration::ZERO, false).unwrap();
        assert_eq!(
            simulate(&mut clock, &offsets, vec![]),
            [s(0.0), s(0.25), s(0.75)]
        );
        let mut slow = ReplayClock::new(0.5, s(10.0), false).unwrap();
        assert_eq!(slow.due(s(1.0)), Some(s(12.0)));
        assert_eq!(slow.position(s(11.0)), s(0.5));
        // Before its anchor the clock stands at it.
        assert_eq!(slow.position(s(9.0)), s(0.0));
        slow.restart(s(20.0));
        assert_eq!(slow.due(s(0.0)), Some(s(20.0)));
    }

    #[test]
    fn pausing_freezes_bag_time_and_resuming_does_not_burst() {
        let mut clock = ReplayClock::new(1.0, Duration::ZERO, false).unwrap();
        assert!(clock.set_paused(true, s(1.5)));
        assert!(!clock.set_paused(true, s(2.0)), "already paused");
        assert!(clock.is_paused());
        assert_eq!(clock.position(s(1.5)), s(1.5));
        assert_eq!(clock.position(s(9.0)), s(1.5), "frozen");
        assert_eq!(clock.due(s(2.0)), None);
        assert!(clock.set_paused(false, s(5.0)));
        // The message at bag 2 s was 0.5 s away at the pause, so it is 0.5 s after the resume.
        assert_eq!(clock.due(s(2.0)), Some(s(5.5)));
        // Messages at 1 s gaps, paused from 1.5 s to 5 s real time: the later ones shift by
        // the 3.5 s paused and keep their gaps; none is published while paused.
        let offsets = [s(0.0), s(1.0), s(2.0), s(3.0)];
        let mut clock = ReplayClock::new(1.0, Duration::ZERO, false).unwrap();
        let times = simulate(&mut clock, &offsets, vec![(s(1.5), true), (s(5.0), false)]);
        assert_eq!(times, [s(0.0), s(1.0), s(5.5), s(6.5)]);
        assert!(times.iter().all(|t| *t <= s(1.5) || *t >= s(5.0)));
    }

    #[test]
    fn a_clock_started_paused_waits_for_the_resume() {
        let offsets = [s(0.0), s(0.5)];
        let mut clock = ReplayClock::new(2.0, Duration::ZERO, true).unwrap();
        assert_eq!(clock.due(s(0.0)), None);
        let times = simulate(&mut clock, &offsets, vec![(s(3.0), false)]);
        assert_eq!(times, [s(3.0), s(3.25)]);
    }

    #[test]
    fn late_messages_are_due_at_once_and_do_not_shift_the_rest() {
        let clock = ReplayClock::new(1.0, s(1.0), false).unwrap();
        // Due at 1.2 s even if the replayer only gets to it at 3 s ...
        assert_eq!(clock.due(s(0.2)), Some(s(1.2)));
        // ... and the next one keeps its own schedule.
        assert_eq!(clock.due(s(4.0)), Some(s(5.0)));
    }

    #[test]
    fn restart_keeps_the_pause_state() {
        let mut clock = ReplayClock::new(1.0, Duration::ZERO, false).unwrap();
        clock.set_paused(true, s(2.0));
        clock.restart(s(3.0));
        assert!(clock.is_paused());
        assert_eq!(clock.position(s(4.0)), Duration::ZERO);
        clock.set_paused(false, s(4.0));
        assert_eq!(clock.due(s(1.0)), Some(s(5.0)));
    }

    #[test]
    fn the_start_offset_skips_the_beginning_and_later_gaps_stay() {
        let t0 = 1_700_000_000_000_000_000u64;
        let logs = [t0, t0 + ns(1.0), t0 + ns(2.0), t0 + ns(3.5)];
        let mut timeline = Timeline::new(t0, s(1.5));
        let placed: Vec<Option<Duration>> = logs.iter().map(|&t| timeline.place(t)).collect();
        assert_eq!(placed, [None, None, Some(s(0.0)), Some(s(1.5))]);
        // A loop's next pass finds the same origin again.
        timeline.rewind();
        let again: Vec<Option<Duration>> = logs.iter().map(|&t| timeline.place(t)).collect();
        assert_eq!(again, placed);
        // No offset: leading time before the first message is not waited out either.
        let mut timeline = Timeline::new(t0, Duration::ZERO);
        assert_eq!(timeline.place(t0 + ns(40.0)), Some(Duration::ZERO));
        assert_eq!(timeline.place(t0 + ns(41.0)), Some(s(1.0)));
        // An offset past the end keeps nothing.
        let mut timeline = Timeline::new(t0, s(10.0));
        assert!(logs.iter().all(|&t| timeline.place(t).is_none()));
    }

    #[test]
    fn a_looped_schedule_restarts_each_pass_at_its_end() {
        let offsets = [s(0.0), s(1.0)];
        let mut clock = ReplayClock::new(2.0, Duration::ZERO, false).unwrap();
        let first = simulate(&mut clock, &offsets, vec![]);
        assert_eq!(first, [s(0.0), s(0.5)]);
        clock.restart(s(0.5));
        assert_eq!(clock.due(s(0.0)), Some(s(0.5)));
        assert_eq!(clock.due(s(1.0)), Some(s(1.0)));
    }
}
