//! QoS presets shared by every node, so publishers and subscribers of one topic always match.

use ros2_client::qos::{Durability, History, QosProfile, Reliability, WhenFull};
use std::time::Duration;

/// What a topic carries, which decides its QoS.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QosPreset {
    /// Plans and programs (`Toolpath`, `MachineProgram`): reliable and transient-local, so a
    /// node that starts late (a recorder, an emitter restarted mid-job) still gets the last ones.
    Plan,
    /// Large periodic rasters (`HeatMap`): best-effort, keep-last-1; a stale frame is worth
    /// nothing, so never block the producer for it.
    Stream,
    /// Status and events (`MachineStatus`): reliable, volatile, a short history.
    Status,
    /// The time source on `/clock`: best-effort, volatile, keep-last-1, as rclcpp's
    /// `ClockQoS` (so it matches `ros2 bag play --clock` and simulators).
    Clock,
}

/// How many plans a late joiner can catch up on.
pub const PLAN_HISTORY_DEPTH: usize = 16;

impl QosPreset {
    /// The ros2-client profile for this preset.
    pub fn profile(self) -> QosProfile {
        let reliable = Reliability::Reliable {
            when_full: WhenFull::Wait(Duration::from_secs(1)),
        };
        match self {
            QosPreset::Plan => QosProfile::publisher_default()
                .reliability(reliable)
                .durability(Durability::TransientLocal)
                .history(History::KeepLast {
                    depth: PLAN_HISTORY_DEPTH,
                }),
            QosPreset::Stream => QosProfile::subscription_default()
                .reliability(Reliability::BestEffort)
                .durability(Durability::Volatile)
                .history(History::KeepLast { depth: 1 }),
            QosPreset::Status => QosProfile::publisher_default()
                .reliability(reliable)
                .durability(Durability::Volatile)
                .history(History::KeepLast { depth: 32 }),
            QosPreset::Clock => QosProfile::subscription_default()
                .reliability(Reliability::BestEffort)
                .durability(Durability::Volatile)
                .history(History::KeepLast { depth: 1 }),
        }
    }
}
