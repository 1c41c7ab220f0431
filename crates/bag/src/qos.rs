//! Offered QoS profiles as rosbag2 stores them: a YAML *string* holding a list of profiles, in
//! the channel metadata (`offered_qos_profiles`) and in `metadata.yaml`'s `topic_metadata`.
//!
//! The layout is rosbag2's for metadata version 5 (ROS 2 Humble): policies as rmw enum integers
//! and durations as `sec`/`nsec`, an unset duration being rmw's "infinite" value. Every reader
//! that understands version 5 or later (rosbag2, `rosbags`) accepts it.

use serde::{Deserialize, Serialize};

/// Reliability policy (rmw `RMW_QOS_POLICY_RELIABILITY_*`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reliability {
    /// Every sample is delivered (retransmitted if lost). rmw value 1.
    Reliable,
    /// Samples may be lost. rmw value 2.
    BestEffort,
}

/// Durability policy (rmw `RMW_QOS_POLICY_DURABILITY_*`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Durability {
    /// Late joiners get the last `depth` samples. rmw value 1.
    TransientLocal,
    /// Only samples published after a reader joined. rmw value 2.
    Volatile,
}

/// History policy (rmw `RMW_QOS_POLICY_HISTORY_*`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum History {
    /// Keep the last `depth` samples. rmw value 1.
    KeepLast,
    /// Keep everything. rmw value 2.
    KeepAll,
}

/// One offered QoS profile of a topic's publisher.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QosProfile {
    /// History kind.
    pub history: History,
    /// History depth (ignored for keep-all, written as 0 there as rmw does).
    pub depth: u32,
    /// Reliability.
    pub reliability: Reliability,
    /// Durability.
    pub durability: Durability,
}

impl Default for QosProfile {
    /// rclcpp's default: reliable, volatile, keep-last 10.
    fn default() -> Self {
        Self::reliable_volatile(10)
    }
}

impl QosProfile {
    /// Reliable, transient-local, keep-last `depth` (the cell's `Plan` preset uses 16).
    pub fn reliable_transient_local(depth: u32) -> Self {
        Self {
            history: History::KeepLast,
            depth,
            reliability: Reliability::Reliable,
            durability: Durability::TransientLocal,
        }
    }

    /// Reliable, volatile, keep-last `depth` (the cell's `Status` preset uses 32).
    pub fn reliable_volatile(depth: u32) -> Self {
        Self {
            durability: Durability::Volatile,
            ..Self::reliable_transient_local(depth)
        }
    }

    /// Best-effort, volatile, keep-last `depth` (the cell's `Stream` preset uses 1).
    pub fn best_effort(depth: u32) -> Self {
        Self {
            reliability: Reliability::BestEffort,
            ..Self::reliable_volatile(depth)
        }
    }
}

/// rmw's infinite duration (`RMW_DURATION_INFINITE`) as rosbag2 writes it.
const INFINITE: Duration = Duration {
    sec: 9_223_372_036,
    nsec: 854_775_807,
};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
struct Duration {
    sec: i64,
    nsec: u32,
}

/// One profile as rosbag2 serializes it (field order as in rosbag2's `qos.cpp`).
#[derive(Debug, Serialize, Deserialize)]
struct ProfileYaml {
    history: u8,
    depth: u32,
    reliability: u8,
    durability: u8,
    deadline: Duration,
    lifespan: Duration,
    liveliness: u8,
    liveliness_lease_duration: Duration,
    avoid_ros_namespace_conventions: bool,
}

/// The YAML string rosbag2 stores for these profiles (a YAML list, one entry per publisher).
pub fn to_yaml(profiles: &[QosProfile]) -> String {
    let list: Vec<ProfileYaml> = profiles
        .iter()
        .map(|p| ProfileYaml {
            history: match p.history {
                History::KeepLast => 1,
                History::KeepAll => 2,
            },
            depth: match p.history {
                History::KeepLast => p.depth,
                History::KeepAll => 0,
            },
            reliability: match p.reliability {
                Reliability::Reliable => 1,
                Reliability::BestEffort => 2,
            },
            durability: match p.durability {
                Durability::TransientLocal => 1,
                Durability::Volatile => 2,
            },
            deadline: INFINITE,
            lifespan: INFINITE,
            liveliness: 1, // automatic
            liveliness_lease_duration: INFINITE,
            avoid_ros_namespace_conventions: false,
        })
        .collect();
    if list.is_empty() {
        return String::new();
    }
    // Serializing plain structs of integers cannot fail.
    let text = serde_norway::to_string(&list).unwrap_or_default();
    text.trim_end().to_owned()
}

/// Parses a stored profile list; policies this crate does not model (system default, unknown)
/// make that profile `None`. An empty string is an empty list. Policies may be rmw integers (up
/// to rosbag2 metadata version 8) or rmw's names (`keep_last`, `reliable`, `transient_local`:
/// version 9, as ROS 2 Jazzy writes them).
pub fn from_yaml(text: &str) -> Result<Vec<Option<QosProfile>>, String> {
    if text.trim().is_empty() {
        return Ok(Vec::new());
    }
    /// A policy as an rmw enum integer or its rmw name (`rmw/qos_string_conversions.h`).
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Policy {
        Number(u8),
        Name(String),
    }
    impl Policy {
        /// 1 and 2 (the policies modelled here) by number or by their two names.
        fn code(&self, names: [&str; 2]) -> Option<u8> {
            match self {
                Policy::Number(n) => Some(*n),
                Policy::Name(name) => names.iter().position(|n| n == name).map(|i| i as u8 + 1),
            }
        }
    }
    #[derive(Deserialize)]
    struct Loose {
        history: Policy,
        depth: u32,
        reliability: Policy,
        durability: Policy,
    }
    let list: Vec<Loose> = serde_norway::from_str(text).map_err(|e| e.to_string())?;
    Ok(list
        .into_iter()
        .map(|l| {
            Some(QosProfile {
                history: match l.history.code(["keep_last", "keep_all"])? {
                    1 => History::KeepLast,
                    2 => History::KeepAll,
                    _ => return None,
                },
                depth: l.depth,
                reliability: match l.reliability.code(["reliable", "best_effort"])? {
                    1 => Reliability::Reliable,
                    2 => Reliability::BestEffort,
                    _ => return None,
                },
                durability: match l.durability.code(["transient_local", "volatile"])? {
                    1 => Durability::TransientLocal,
                    2 => Durability::Volatile,
                    _ => return None,
                },
            })
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaml_layout_and_round_trip() {
        let profiles = [
            QosProfile::reliable_transient_local(16),
            QosProfile::reliable_volatile(32),
            QosProfile::best_effort(1),
        ];
        let text = to_yaml(&profiles);
        assert!(text.starts_with("- history: 1\n  depth: 16\n  reliability: 1\n  durability: 1\n  deadline:\n    sec: 9223372036\n    nsec: 854775807\n"), "{text}");
        assert!(text.contains("  liveliness: 1\n"));
        assert!(text.ends_with("avoid_ros_namespace_conventions: false"));
        let back: Vec<QosProfile> = from_yaml(&text).unwrap().into_iter().flatten().collect();
        assert_eq!(back, profiles);
        assert_eq!(to_yaml(&[]), "");
        assert!(from_yaml("").unwrap().is_empty());
        assert!(from_yaml("- nope").is_err());
    }

    #[test]
    fn reads_jazzys_policy_names() {
        // One profile as rosbag2 Jazzy writes it (metadata version 9, `qos.cpp`).
        let jazzy = "- history: keep_last\n  depth: 16\n  reliability: reliable\n  \
                     durability: transient_local\n  deadline:\n    sec: 9223372036\n    \
                     nsec: 854775807\n  liveliness: automatic\n\
                     - history: keep_last\n  depth: 1\n  reliability: best_effort\n  \
                     durability: volatile\n\
                     - history: system_default\n  depth: 0\n  reliability: reliable\n  \
                     durability: volatile\n";
        assert_eq!(
            from_yaml(jazzy).unwrap(),
            [
                Some(QosProfile::reliable_transient_local(16)),
                Some(QosProfile::best_effort(1)),
                None
            ]
        );
    }
}
