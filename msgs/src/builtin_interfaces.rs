//! Vendored `builtin_interfaces` types.

use std::time::{SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

/// ROS Time (<https://design.ros2.org/articles/clock_and_time.html>).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Time {
    /// The seconds component, valid over all int32 values.
    pub sec: i32,
    /// The nanoseconds component, in `[0, 1e9)`, added to the seconds component
    /// (-1.7 s is `{sec: -2, nanosec: 3e8}`).
    pub nanosec: u32,
}

impl Time {
    /// Converts a wall-clock time; times outside the `i32` seconds range saturate.
    pub fn from_system_time(time: SystemTime) -> Self {
        let (sec, nanosec) = match time.duration_since(UNIX_EPOCH) {
            Ok(d) => (i128::from(d.as_secs()), d.subsec_nanos()),
            Err(before) => {
                // Before the epoch: negative seconds, nanoseconds still counted upwards.
                let d = before.duration();
                let sec = -i128::from(d.as_secs());
                match d.subsec_nanos() {
                    0 => (sec, 0),
                    ns => (sec - 1, 1_000_000_000 - ns),
                }
            }
        };
        match i32::try_from(sec) {
            Ok(sec) => Self { sec, nanosec },
            Err(_) if sec > 0 => Self {
                sec: i32::MAX,
                nanosec: 999_999_999,
            },
            Err(_) => Self {
                sec: i32::MIN,
                nanosec: 0,
            },
        }
    }

    /// The current wall-clock time.
    pub fn now() -> Self {
        Self::from_system_time(SystemTime::now())
    }
}

/// A period between two time points (`builtin_interfaces/msg/Duration`), e.g. a marker's
/// lifetime (0: forever).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Duration {
    /// The seconds component, valid over all int32 values.
    pub sec: i32,
    /// The nanoseconds component, in `[0, 1e9)`, added to the seconds component.
    pub nanosec: u32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn from_system_time_handles_both_sides_of_the_epoch() {
        let t = |secs: f64| {
            let d = Duration::from_secs_f64(secs.abs());
            Time::from_system_time(if secs < 0.0 {
                UNIX_EPOCH - d
            } else {
                UNIX_EPOCH + d
            })
        };
        assert_eq!(
            t(1.7),
            Time {
                sec: 1,
                nanosec: 700_000_000
            }
        );
        assert_eq!(
            t(-1.7),
            Time {
                sec: -2,
                nanosec: 300_000_000
            }
        );
        assert_eq!(
            t(-2.0),
            Time {
                sec: -2,
                nanosec: 0
            }
        );
        assert_eq!(t(1e10).sec, i32::MAX);
    }
}
