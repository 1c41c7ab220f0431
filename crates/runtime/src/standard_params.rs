//! The ROS-standard parameters every ROS 2 node accepts beside its own (issue 22, item 4):
//! a bringup's shared `/**: ros__parameters: {use_sim_time: false}` or a
//! `qos_overrides./topic.publisher.depth: 5` must not stop a cell node, whose own parameter
//! structs refuse unknown keys.
//!
//! - `use_sim_time` (bool, default false): declared on the graph. True makes the node follow
//!   `/clock` ([`crate::clock`]): [`crate::CellNode::now`] and so every stamp it publishes.
//! - `qos_overrides.<topic>.<publisher|subscription>.<policy>` (ROS 2's QoS override
//!   parameters): `reliability` (`reliable` | `best_effort`), `durability` (`volatile` |
//!   `transient_local`), `history` (`keep_last` | `keep_all`), `depth` (≥ 1),
//!   `deadline`, `lifespan`, `liveliness_lease_duration` (seconds, ≥ 0; 0 = infinite) and
//!   `liveliness` (`automatic` | `manual_by_topic`); applied to the node's publishers and
//!   subscriptions of that topic (the fully qualified name, as ROS 2 writes it). A policy or
//!   value outside these is an error naming the key.
//! - Other node-level keys ROS 2 defines (`start_type_description_service`): ignored with a
//!   debug line.

use std::time::Duration;

use ros2_client::qos::{Durability, History, Liveliness, QosProfile, Reliability, WhenFull};
use serde_norway::Value;

use crate::params::{ParamSources, ParamsError};

/// Standard keys a cell node accepts and ignores (with a debug line).
const IGNORED: &[&str] = &["start_type_description_service"];

/// Which side of a topic a QoS override is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endpoint {
    /// A publisher (`qos_overrides.<topic>.publisher.…`).
    Publisher,
    /// A subscription (`qos_overrides.<topic>.subscription.…`).
    Subscription,
}

/// One `qos_overrides.<topic>.<endpoint>.<policy>` value, parsed.
#[derive(Debug, Clone, PartialEq)]
struct QosOverride {
    topic: String,
    endpoint: Endpoint,
    policy: Policy,
}

#[derive(Debug, Clone, PartialEq)]
enum Policy {
    Reliability(bool),
    Durability(Durability),
    KeepAll,
    KeepLast,
    Depth(usize),
    Deadline(Option<Duration>),
    Lifespan(Option<Duration>),
    Liveliness(Liveliness),
    LivelinessLease(Option<Duration>),
}

/// The standard parameters of one node (module docs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StandardParams {
    /// `use_sim_time`.
    pub use_sim_time: bool,
    overrides: Vec<QosOverride>,
}

impl StandardParams {
    /// Takes the standard keys out of `sources` (so the node's own struct never sees them) and
    /// checks them.
    ///
    /// # Errors
    /// A standard key with a value of the wrong type or an unknown QoS policy or value, naming
    /// the key and where it came from.
    pub fn take(sources: &mut ParamSources) -> Result<Self, ParamsError> {
        let mut out = Self::default();
        if let Some((value, origin)) = sources.take("use_sim_time") {
            out.use_sim_time = value.as_bool().ok_or_else(|| ParamsError {
                origin,
                what: format!("parameter `use_sim_time`: expected true or false, found {value:?}"),
            })?;
        }
        for key in IGNORED {
            if sources.take(key).is_some() {
                tracing::debug!("standard parameter {key} ignored");
            }
        }
        if let Some((value, origin)) = sources.take("qos_overrides") {
            let mut leaves = Vec::new();
            flatten("qos_overrides", &value, &mut leaves);
            for (key, value) in leaves {
                out.overrides
                    .push(parse_override(&key, &value).map_err(|what| ParamsError {
                        origin: origin.clone(),
                        what: format!("parameter `{key}`: {what}"),
                    })?);
            }
        }
        Ok(out)
    }

    /// `profile` with this node's overrides for `topic` (fully qualified) and `endpoint`
    /// applied in the order given.
    pub fn qos(&self, topic: &str, endpoint: Endpoint, mut profile: QosProfile) -> QosProfile {
        for o in self
            .overrides
            .iter()
            .filter(|o| o.topic == topic && o.endpoint == endpoint)
        {
            profile = match o.policy {
                Policy::Reliability(true) => profile.reliability(Reliability::Reliable {
                    when_full: WhenFull::Wait(Duration::from_secs(1)),
                }),
                Policy::Reliability(false) => profile.reliability(Reliability::BestEffort),
                Policy::Durability(d) => profile.durability(d),
                Policy::KeepAll => profile.history(History::KeepAll),
                Policy::KeepLast => match profile.history {
                    History::KeepAll => profile.history(History::KeepLast { depth: 1 }),
                    _ => profile,
                },
                Policy::Depth(depth) => match profile.history {
                    History::KeepAll => profile,
                    _ => profile.history(History::KeepLast { depth }),
                },
                Policy::Deadline(d) => QosProfile {
                    deadline: d,
                    ..profile
                },
                Policy::Lifespan(d) => QosProfile {
                    lifespan: d,
                    ..profile
                },
                Policy::Liveliness(l) => QosProfile {
                    liveliness: l,
                    ..profile
                },
                Policy::LivelinessLease(d) => QosProfile {
                    liveliness_lease: d,
                    ..profile
                },
            };
        }
        profile
    }
}

/// Leaves of a nested mapping as dotted keys.
fn flatten(prefix: &str, value: &Value, out: &mut Vec<(String, Value)>) {
    match value {
        Value::Mapping(map) if !map.is_empty() => {
            for (k, v) in map {
                flatten(&format!("{prefix}.{}", k.as_str().unwrap_or("?")), v, out);
            }
        }
        other => out.push((prefix.to_string(), other.clone())),
    }
}

/// `qos_overrides.<topic>.<endpoint>.<policy>`: the topic may itself contain dots only as
/// ROS 2 writes it (`/ns/topic`), so the last two parts are endpoint and policy.
fn parse_override(key: &str, value: &Value) -> Result<QosOverride, String> {
    let rest = key.strip_prefix("qos_overrides.").unwrap_or(key);
    let mut parts = rest.rsplitn(3, '.');
    let (policy, endpoint, topic) = match (parts.next(), parts.next(), parts.next()) {
        (Some(p), Some(e), Some(t)) if !t.is_empty() => (p, e, t),
        _ => return Err("expected qos_overrides.<topic>.<publisher|subscription>.<policy>".into()),
    };
    let endpoint = match endpoint {
        "publisher" => Endpoint::Publisher,
        "subscription" => Endpoint::Subscription,
        other => return Err(format!("`{other}` is not publisher or subscription")),
    };
    let text = || value.as_str().map(str::to_ascii_lowercase);
    let seconds = || -> Result<Option<Duration>, String> {
        let s = value
            .as_f64()
            .filter(|s| s.is_finite() && *s >= 0.0)
            .ok_or_else(|| format!("expected seconds >= 0 (0: infinite), found {value:?}"))?;
        Ok((s > 0.0).then(|| Duration::from_secs_f64(s)))
    };
    let bad = |allowed: &str| format!("expected {allowed}, found {value:?}");
    let policy = match policy {
        "reliability" => match text().as_deref() {
            Some("reliable") => Policy::Reliability(true),
            Some("best_effort") => Policy::Reliability(false),
            _ => return Err(bad("reliable or best_effort")),
        },
        "durability" => match text().as_deref() {
            Some("volatile") => Policy::Durability(Durability::Volatile),
            Some("transient_local") => Policy::Durability(Durability::TransientLocal),
            _ => return Err(bad("volatile or transient_local")),
        },
        "history" => match text().as_deref() {
            Some("keep_last") => Policy::KeepLast,
            Some("keep_all") => Policy::KeepAll,
            _ => return Err(bad("keep_last or keep_all")),
        },
        "depth" => match value.as_u64() {
            Some(d) if d >= 1 => Policy::Depth(d as usize),
            _ => return Err(bad("an integer >= 1")),
        },
        "deadline" => Policy::Deadline(seconds()?),
        "lifespan" => Policy::Lifespan(seconds()?),
        "liveliness_lease_duration" => Policy::LivelinessLease(seconds()?),
        "liveliness" => match text().as_deref() {
            Some("automatic") => Policy::Liveliness(Liveliness::Automatic),
            Some("manual_by_topic") => Policy::Liveliness(Liveliness::ManualByTopic),
            _ => return Err(bad("automatic or manual_by_topic")),
        },
        other => {
            return Err(format!(
                "unknown QoS policy `{other}` (reliability, durability, history, depth, deadline, \
                 lifespan, liveliness, liveliness_lease_duration)"
            ))
        }
    };
    Ok(QosOverride {
        topic: topic.to_string(),
        endpoint,
        policy,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::args::RosArgs;
    use serde::Deserialize;

    #[derive(Debug, Deserialize, Default, PartialEq)]
    #[serde(deny_unknown_fields, default)]
    struct Own {
        rate_hz: f64,
    }

    fn sources(params: &[(&str, &str)]) -> ParamSources {
        let ros = RosArgs {
            params: params
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            ..Default::default()
        };
        ParamSources::collect(&ros, "/cell", "node").unwrap()
    }

    #[test]
    fn standard_keys_leave_the_nodes_own_parameters_alone() {
        let mut s = sources(&[
            ("rate_hz", "2.5"),
            ("use_sim_time", "false"),
            ("start_type_description_service", "true"),
            ("qos_overrides./cell/a.publisher.reliability", "best_effort"),
            ("qos_overrides./cell/a.publisher.depth", "3"),
            (
                "qos_overrides./cell/a.subscription.durability",
                "transient_local",
            ),
            ("qos_overrides./cell/a.publisher.deadline", "0.5"),
        ]);
        let standard = StandardParams::take(&mut s).unwrap();
        assert_eq!(s.parse::<Own>().unwrap(), Own { rate_hz: 2.5 });
        assert!(!standard.use_sim_time);
        let base = QosProfile::publisher_default();
        let p = standard.qos("/cell/a", Endpoint::Publisher, base.clone());
        assert_eq!(p.reliability, Reliability::BestEffort);
        assert_eq!(p.history, History::KeepLast { depth: 3 });
        assert_eq!(p.deadline, Some(Duration::from_millis(500)));
        assert_eq!(p.durability, base.durability);
        let sub = standard.qos("/cell/a", Endpoint::Subscription, base.clone());
        assert_eq!(sub.durability, Durability::TransientLocal);
        assert_eq!(sub.reliability, base.reliability);
        // Other topics keep their profile.
        assert_eq!(
            standard.qos("/cell/b", Endpoint::Publisher, base.clone()),
            base
        );
        // Still an error: the node's own unknown keys.
        let mut s = sources(&[("rate_hz", "1"), ("use_sim_tim", "false")]);
        StandardParams::take(&mut s).unwrap();
        assert!(s
            .parse::<Own>()
            .unwrap_err()
            .to_string()
            .contains("use_sim_tim"));
    }

    #[test]
    fn bad_standard_values_are_named() {
        for (key, value, says) in [
            ("use_sim_time", "maybe", "use_sim_time"),
            (
                "qos_overrides./cell/a.publisher.reliability",
                "sometimes",
                "reliable or best_effort",
            ),
            ("qos_overrides./cell/a.publisher.depth", "0", "integer >= 1"),
            (
                "qos_overrides./cell/a.writer.depth",
                "1",
                "publisher or subscription",
            ),
            (
                "qos_overrides./cell/a.publisher.colour",
                "red",
                "unknown QoS policy `colour`",
            ),
            (
                "qos_overrides./cell/a.publisher.lifespan",
                "-1",
                "seconds >= 0",
            ),
        ] {
            let mut s = sources(&[(key, value)]);
            let e = StandardParams::take(&mut s).unwrap_err().to_string();
            assert!(e.contains(says), "{key}: {e}");
            assert!(
                e.starts_with(&format!("-p {key}")) || e.contains("-p "),
                "{e}"
            );
        }
    }
}
