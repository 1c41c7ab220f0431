//! `/rosout` (issue 22, item 5): the log events a node's filter lets through (`RUST_LOG` or
//! `--log-level`, [`crate::logging::init`]) are also published on `/rosout` as
//! `rcl_interfaces/msg/Log`, so `rqt_console`, `ros2 topic echo /rosout` and Foxglove's log
//! panel show them.
//!
//! `tracing` has one global subscriber per process, so the forwarding is a `tracing` layer
//! ([`RosoutLayer`]) over a process-wide list of the live nodes' rosout writers: each
//! [`crate::CellNode`] registers its writer when it comes up, and an event goes out once per
//! live node, under that node's logger name as rclcpp writes it (`cell.emitter` for
//! `/cell/emitter`). Events of the DDS stack itself (`rustdds`, `ros2_client`, also when they
//! come through the `log` crate) are not forwarded: publishing them would log again.

use std::cell::Cell;
use std::fmt::Write as _;
use std::sync::{Arc, Mutex, OnceLock, Weak};

use ros2_client::log::Log;
use ros2_client::Publisher;
use tracing::field::{Field, Visit};
use tracing::{Event, Level, Subscriber};
use tracing_log::NormalizeEvent as _;
use tracing_subscriber::layer::{Context, Layer};

type Writer = Option<Publisher<Log>>;

/// Node name and rosout writer of every node that came up in this process.
type Registry = Mutex<Vec<(String, Weak<Writer>)>>;

/// The live nodes' names and rosout writers.
fn writers() -> &'static Registry {
    static WRITERS: OnceLock<Registry> = OnceLock::new();
    WRITERS.get_or_init(|| Mutex::new(Vec::new()))
}

thread_local! {
    /// Set while an event is being published, so logging from inside the publish is dropped.
    static FORWARDING: Cell<bool> = const { Cell::new(false) };
}

/// Registers the rosout writer of node `name` in `namespace`; it is dropped from the list when
/// the node goes.
pub(crate) fn register(namespace: &str, name: &str, writer: Arc<Writer>) {
    let mut list = writers().lock().unwrap_or_else(|p| p.into_inner());
    list.retain(|(_, w)| w.strong_count() > 0);
    list.push((logger_name(namespace, name), Arc::downgrade(&writer)));
}

/// rcl's logger name of a node: its namespace and name joined by dots (`/cell`, `emitter` →
/// `cell.emitter`).
fn logger_name(namespace: &str, name: &str) -> String {
    namespace
        .split('/')
        .filter(|part| !part.is_empty())
        .chain([name])
        .collect::<Vec<_>>()
        .join(".")
}

/// The layer [`crate::logging::init`] installs (module docs).
#[derive(Debug, Default, Clone, Copy)]
pub struct RosoutLayer;

/// Collects an event's message and its other fields (`key=value`) as one line.
#[derive(Default)]
struct Line(String);

impl Visit for Line {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name().starts_with("log.") {
            return; // the `log` crate's metadata, already in the normalised metadata
        }
        if field.name() == "message" {
            let rest = std::mem::take(&mut self.0);
            let _ = write!(self.0, "{value:?}{rest}");
        } else {
            let _ = write!(self.0, " {}={value:?}", field.name());
        }
    }

    fn record_str(&mut self, field: &Field, value: &str) {
        if field.name().starts_with("log.") {
            return;
        }
        if field.name() == "message" {
            let rest = std::mem::take(&mut self.0);
            self.0 = format!("{value}{rest}");
        } else {
            let _ = write!(self.0, " {}={value}", field.name());
        }
    }
}

impl<S: Subscriber> Layer<S> for RosoutLayer {
    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        // Events from the `log` crate (rustdds logs that way) carry their real target, file
        // and line in fields; normalised, they are filtered like the others.
        let normalized = event.normalized_metadata();
        let meta = normalized.as_ref().unwrap_or_else(|| event.metadata());
        let target = meta.target();
        if target.starts_with("rustdds") || target.starts_with("ros2_client") {
            return;
        }
        if FORWARDING.with(Cell::get) {
            return;
        }
        let live: Vec<(String, Arc<Writer>)> = {
            let list = writers().lock().unwrap_or_else(|p| p.into_inner());
            list.iter()
                .filter_map(|(name, w)| w.upgrade().map(|w| (name.clone(), w)))
                .collect()
        };
        if live.is_empty() {
            return;
        }
        let mut line = Line::default();
        event.record(&mut line);
        let level = match *meta.level() {
            Level::ERROR => Log::ERROR,
            Level::WARN => Log::WARN,
            Level::INFO => Log::INFO,
            _ => Log::DEBUG,
        };
        FORWARDING.with(|f| f.set(true));
        for (name, writer) in live {
            if let Some(publisher) = writer.as_ref() {
                let _ = publisher.publish(Log {
                    stamp: ros2_client::builtin_interfaces::Time::now(),
                    level,
                    name,
                    msg: line.0.clone(),
                    file: meta.file().unwrap_or_default().to_string(),
                    function: target.to_string(),
                    line: meta.line().unwrap_or(0),
                });
            }
        }
        FORWARDING.with(|f| f.set(false));
    }
}

#[cfg(test)]
mod tests {
    use super::logger_name;

    #[test]
    fn logger_names_join_namespace_and_name_with_dots() {
        assert_eq!(logger_name("/cell", "emitter"), "cell.emitter");
        assert_eq!(logger_name("/", "planner"), "planner");
        assert_eq!(logger_name("/a/b/", "n"), "a.b.n");
    }
}
