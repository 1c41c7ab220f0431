//! Publishers of the standard-type views ([`cell_views`]) that RViz, Foxglove and stock ROS 2
//! tools draw: one call per message a node publishes. Off (no endpoints at all) when the
//! node's `standard_views` parameter is false.
//!
//! | view | topic | type | QoS |
//! |---|---|---|---|
//! | toolpath as a path | `<toolpath topic>/path` | `nav_msgs/msg/Path` | as the toolpath (reliable, transient-local) |
//! | toolpath by kind and layer | `<toolpath topic>/markers` | `visualization_msgs/msg/MarkerArray` | same |
//! | a frame attached to `cell` | `/tf_static` | `tf2_msgs/msg/TFMessage` | reliable, transient-local |
//! | heat map | `<heat-map topic>/image` | `sensor_msgs/msg/Image` (`32FC1`) | reliable, volatile |
//! | machine axes | `joint_states` | `sensor_msgs/msg/JointState` | reliable, volatile |
//! | tool frames | `/tf` | `tf2_msgs/msg/TFMessage` | reliable, volatile |
//! | machine health | `/diagnostics` | `diagnostic_msgs/msg/DiagnosticArray` | reliable, volatile, 1 Hz |
//! | a printer's heaters | `<machine>/temperature/<heater>` | `sensor_msgs/msg/Temperature` | reliable, volatile |
//!
//! The views are for people: a view that cannot be made or sent is logged and skipped, and
//! the node carries on.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use cell_msgs::diagnostic_msgs::DiagnosticArray;
use cell_msgs::geometry_msgs::TransformStamped;
use cell_msgs::nav_msgs::Path;
use cell_msgs::sensor_msgs::{Image, JointState, Temperature};
use cell_msgs::tf2_msgs::TFMessage;
use cell_msgs::visualization_msgs::MarkerArray;
use cell_msgs::{HeatMap, MachineStatus, RosMessage, Toolpath};
use cell_views::{frames, topics};

/// A heater's reading, for [`MachineViews::publish`].
pub use cell_views::HeaterReading;

use crate::{CellNode, Publisher, QosPreset};

/// Logs a failed view once per call, as a warning; the node goes on.
fn warn_on_error(topic: &str, result: anyhow::Result<()>) {
    if let Err(e) = result {
        tracing::warn!("{topic}: view not published: {e:#}");
    }
}

/// Publishes `message` on `publisher`, logging a failure.
async fn send<T: RosMessage>(publisher: &Publisher<T>, message: T) {
    warn_on_error(publisher.topic(), publisher.publish(message).await);
}

/// The frames a node has attached to `cell` on `/tf_static`; each new frame republishes the
/// whole set, as tf2's static broadcaster does (a latched topic keeps only what was sent last).
struct StaticFrames {
    publisher: Publisher<TFMessage>,
    sent: Mutex<Vec<TransformStamped>>,
}

impl StaticFrames {
    fn new(node: &CellNode) -> anyhow::Result<Self> {
        Ok(Self {
            publisher: node.publisher(topics::TF_STATIC, QosPreset::Plan)?,
            sent: Mutex::new(Vec::new()),
        })
    }

    /// Attaches `frame` to `cell` with the identity, once.
    async fn attach(&self, node: &CellNode, frame: &str) {
        let message = {
            let mut sent = self.sent.lock().unwrap_or_else(|p| p.into_inner());
            if sent.iter().any(|t| t.child_frame_id == frame) {
                return;
            }
            let Some(transform) = frames::attach_to_cell(frame, node.now()) else {
                return;
            };
            sent.push(transform);
            TFMessage {
                transforms: sent.clone(),
            }
        };
        send(&self.publisher, message).await;
    }
}

struct ToolpathPublishers {
    node: CellNode,
    path: Publisher<Path>,
    markers: Publisher<MarkerArray>,
    frames: StaticFrames,
}

/// The `nav_msgs/Path` and `visualization_msgs/MarkerArray` views of one toolpath topic.
pub struct ToolpathViews(Option<ToolpathPublishers>);

impl ToolpathViews {
    /// Views below `toolpath`'s resolved topic ([`topics::path`], [`topics::markers`]), with
    /// its QoS; no endpoints when `enabled` is false.
    pub fn new(
        node: &CellNode,
        toolpath: &Publisher<Toolpath>,
        enabled: bool,
    ) -> anyhow::Result<Self> {
        if !enabled {
            return Ok(Self(None));
        }
        let topic = toolpath.topic();
        Ok(Self(Some(ToolpathPublishers {
            node: node.clone(),
            path: node.publisher(&topics::path(topic), QosPreset::Plan)?,
            markers: node.publisher(&topics::markers(topic), QosPreset::Plan)?,
            frames: StaticFrames::new(node)?,
        })))
    }

    /// Publishes the views of `toolpath` (and attaches its frame to `cell` the first time).
    pub async fn publish(&self, toolpath: &Toolpath) {
        let Some(p) = &self.0 else { return };
        p.frames
            .attach(&p.node, &frames::of_header(&toolpath.header))
            .await;
        send(&p.path, cell_views::toolpath_path(toolpath)).await;
        match cell_views::toolpath_markers(toolpath) {
            Ok(markers) => send(&p.markers, markers).await,
            Err(e) => warn_on_error(p.markers.topic(), Err(e.into())),
        }
    }
}

struct ImagePublishers {
    node: CellNode,
    image: Publisher<Image>,
    frames: StaticFrames,
}

/// The `sensor_msgs/Image` view of one heat-map topic.
pub struct HeatMapView(Option<ImagePublishers>);

impl HeatMapView {
    /// A view below `heat_map`'s resolved topic ([`topics::image`]); no endpoints when
    /// `enabled` is false. Reliable with a short volatile history (a stock viewer's reliable
    /// reader matches it; the heat map itself is best-effort).
    pub fn new(
        node: &CellNode,
        heat_map: &Publisher<HeatMap>,
        enabled: bool,
    ) -> anyhow::Result<Self> {
        if !enabled {
            return Ok(Self(None));
        }
        Ok(Self(Some(ImagePublishers {
            node: node.clone(),
            image: node.publisher(&topics::image(heat_map.topic()), QosPreset::Status)?,
            frames: StaticFrames::new(node)?,
        })))
    }

    /// Publishes the image of `heat_map`.
    pub async fn publish(&self, heat_map: &HeatMap) {
        let Some(p) = &self.0 else { return };
        p.frames
            .attach(&p.node, &frames::of_header(&heat_map.header))
            .await;
        match cell_views::heat_map_image(heat_map) {
            Ok(image) => send(&p.image, image).await,
            Err(e) => warn_on_error(p.image.topic(), Err(e.into())),
        }
    }
}

struct MachinePublishers {
    node: CellNode,
    joint_states: Publisher<JointState>,
    tf: Publisher<TFMessage>,
    diagnostics: Publisher<DiagnosticArray>,
    /// One per heater topic, made when its first reading comes (a printer may have no bed).
    temperatures: Mutex<BTreeMap<String, Arc<Publisher<Temperature>>>>,
    frames: StaticFrames,
    last_diagnostics: Mutex<Option<Instant>>,
}

impl MachinePublishers {
    /// The publisher of `topic`, made on first use.
    fn temperature(&self, topic: &str) -> anyhow::Result<Arc<Publisher<Temperature>>> {
        let mut all = self.temperatures.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = all.get(topic) {
            return Ok(p.clone());
        }
        let p = Arc::new(self.node.publisher(topic, QosPreset::Status)?);
        all.insert(topic.to_owned(), p.clone());
        Ok(p)
    }
}

/// The machine bridge's views: `joint_states`, the tool frames on `/tf`, each printer heater's
/// `sensor_msgs/Temperature` and the bridge's health on `/diagnostics`.
pub struct MachineViews(Option<MachinePublishers>);

/// How often `/diagnostics` is sent (`diagnostic_updater`'s default period).
pub const DIAGNOSTICS_PERIOD: Duration = Duration::from_secs(1);

impl MachineViews {
    /// The machine views; no endpoints when `enabled` is false.
    pub fn new(node: &CellNode, enabled: bool) -> anyhow::Result<Self> {
        if !enabled {
            return Ok(Self(None));
        }
        Ok(Self(Some(MachinePublishers {
            node: node.clone(),
            joint_states: node.publisher(topics::JOINT_STATES, QosPreset::Status)?,
            tf: node.publisher(topics::TF, QosPreset::Status)?,
            diagnostics: node.publisher(topics::DIAGNOSTICS, QosPreset::Status)?,
            temperatures: Mutex::new(BTreeMap::new()),
            frames: StaticFrames::new(node)?,
            last_diagnostics: Mutex::new(None),
        })))
    }

    /// Publishes one `JointState` per machine, one `/tf` message with every machine's tool
    /// frame, one `Temperature` per heater reading on [`topics::temperature`] (stamped now),
    /// and, at most every [`DIAGNOSTICS_PERIOD`], the diagnostics of all machines with their
    /// heaters. Each machine's frame is attached to `cell` the first time it is seen.
    pub async fn publish(&self, statuses: &[MachineStatus], heaters: &[HeaterReading]) {
        let Some(p) = &self.0 else { return };
        for s in statuses {
            p.frames
                .attach(&p.node, &frames::machine(&s.machine_id))
                .await;
            send(&p.joint_states, cell_views::joint_state(s)).await;
        }
        let transforms: Vec<TransformStamped> = statuses
            .iter()
            .filter_map(cell_views::tool_transform)
            .collect();
        if !transforms.is_empty() {
            send(&p.tf, TFMessage { transforms }).await;
        }
        let stamp = p.node.now();
        for h in heaters {
            let topic = topics::temperature(&h.machine_id, &h.heater);
            match p.temperature(&topic) {
                Ok(publisher) => send(&publisher, cell_views::temperature(h, stamp)).await,
                Err(e) => warn_on_error(&topic, Err(e)),
            }
        }
        let due = {
            let mut last = p.last_diagnostics.lock().unwrap_or_else(|e| e.into_inner());
            let due = last.is_none_or(|t| t.elapsed() >= DIAGNOSTICS_PERIOD);
            if due {
                *last = Some(Instant::now());
            }
            due
        };
        if due {
            let array = cell_views::diagnostics(p.node.name(), statuses, heaters, stamp);
            send(&p.diagnostics, array).await;
        }
    }
}
