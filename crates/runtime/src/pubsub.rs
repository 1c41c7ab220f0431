//! Typed publish/subscribe over DDS, with the iceoryx2 fast path behind the same API.
//!
//! Topics whose [`QosPreset`] is [`QosPreset::Stream`] (heat maps) use the fast path when the
//! node has one. Then:
//! - the publisher writes every frame to shared memory, and to DDS only when DDS has more
//!   matched readers than there are shared-memory subscribers, i.e. when some reader is on
//!   another host or speaks DDS only (a stock ROS 2 node, a Cyclone peer);
//! - the subscriber listens on both, and drops a DDS sample whose writer it has already heard
//!   from over shared memory. Shared memory is written before DDS, and the subscriber drains it
//!   before judging a DDS sample, so a frame that came both ways is delivered once.
//!
//! A sample that cannot be decoded is logged with its topic and skipped; the node keeps running.

use std::{
    collections::HashSet,
    marker::PhantomData,
    sync::{
        atomic::{AtomicBool, Ordering},
        Arc, Mutex,
    },
    time::Duration,
};

use anyhow::{anyhow, Context as _};
use cell_msgs::RosMessage;
use futures::StreamExt;
use ros2_client::{MessageTypeName, Name};
use tokio::sync::mpsc;

use crate::{
    fastpath::{FastPublisher, FastSubscriber, Frame},
    node::CellNode,
    qos::QosPreset,
    standard_params::Endpoint,
};

/// How a message reached a subscriber.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Via {
    /// Over DDS (RTPS/UDP).
    Dds,
    /// Over iceoryx2 shared memory.
    SharedMemory,
}

/// A received message with where it came from.
#[derive(Debug, Clone)]
pub struct Received<T> {
    /// The message.
    pub message: T,
    /// The transport it came over.
    pub via: Via,
    /// GID of the DDS writer that published it.
    pub writer_gid: [u8; 16],
}

fn topic_name(node: &CellNode, topic: &str) -> anyhow::Result<(String, Name)> {
    let resolved = node.resolve_topic(topic);
    let name = Name::parse(&resolved).map_err(|e| anyhow!("topic name {resolved:?}: {e:?}"))?;
    Ok((resolved, name))
}

fn type_name<T: RosMessage>() -> MessageTypeName {
    MessageTypeName::new(T::package(), T::type_name())
}

/// Publishes `T` on one topic.
pub struct Publisher<T: RosMessage> {
    topic: String,
    node: CellNode,
    dds: ros2_client::Publisher<Arc<T>>,
    fast: Option<FastPublisher>,
}

impl<T: RosMessage> Publisher<T> {
    /// Creates a publisher on `topic` (resolved against namespace and remappings).
    pub fn new(node: &CellNode, topic: &str, qos: QosPreset) -> anyhow::Result<Self> {
        let (resolved, name) = topic_name(node, topic)?;
        let profile = node.qos(&resolved, Endpoint::Publisher, qos.profile());
        let dds = node.with_ros_node(|n| {
            let t = n.create_topic(&name, type_name::<T>(), &profile)?;
            n.create_publisher::<Arc<T>>(&t, Some(profile.clone()))
        });
        let dds = dds.map_err(|e| anyhow!("publisher on {resolved}: {e:?}"))?;
        let fast = match (qos, node.fast_path()) {
            (QosPreset::Stream, Some(fp)) => {
                let gid = dds.gid().to_bytes16();
                match fp.publisher(&resolved, T::ROS_NAME, gid) {
                    Ok(p) => Some(p),
                    Err(e) => {
                        tracing::warn!("{resolved}: fast path unavailable, using DDS: {e}");
                        None
                    }
                }
            }
            _ => None,
        };
        Ok(Self {
            topic: resolved,
            node: node.clone(),
            dds,
            fast,
        })
    }

    /// The resolved topic name.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// DDS subscriptions discovered on this topic (including local ones that also read shared
    /// memory). Counted from discovery rather than ros2-client's per-writer match table, which
    /// logs an error for every query made before the graph spinner has caught up.
    pub fn dds_subscription_count(&self) -> usize {
        self.node
            .with_ros_node(|n| n.subscription_count(&self.topic))
    }

    /// Subscribers on this host reading the shared-memory fast path (0 without a fast path).
    pub fn shared_memory_subscriber_count(&self) -> usize {
        self.fast
            .as_ref()
            .map_or(0, FastPublisher::subscriber_count)
    }

    /// Waits until at least `count` subscribers (DDS or shared memory) are matched, or `timeout`.
    /// Returns whether they were.
    pub async fn wait_for_subscribers(&self, count: usize, timeout: Duration) -> bool {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            let fast = self
                .fast
                .as_ref()
                .map_or(0, FastPublisher::subscriber_count);
            if self.dds_subscription_count().max(fast) >= count {
                return true;
            }
            if tokio::time::Instant::now() >= deadline {
                return false;
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }

    /// Publishes one message.
    pub async fn publish(&self, message: T) -> anyhow::Result<()> {
        let message = Arc::new(message);
        if let Some(fast) = &self.fast {
            let local = fast.subscriber_count();
            if local > 0 {
                let bytes = message
                    .encode()
                    .with_context(|| format!("encoding for {}", self.topic))?;
                if let Err(e) = fast.send_copy(&bytes) {
                    tracing::warn!("{}: shared-memory send failed, using DDS: {e}", self.topic);
                } else if self.dds_subscription_count() <= local {
                    return Ok(());
                }
            }
        }
        self.dds
            .async_publish(message)
            .await
            .map_err(|e| anyhow!("publishing on {}: {e:?}", self.topic))
    }
}

/// Receives `T` from one topic, over DDS and, for stream topics, shared memory.
pub struct Subscriber<T> {
    topic: String,
    rx: mpsc::Receiver<Received<T>>,
    stop: Arc<AtomicBool>,
    task: tokio::task::JoinHandle<()>,
}

impl<T> Drop for Subscriber<T> {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        self.task.abort();
    }
}

/// Shared-memory side of a subscriber, drained from the listener thread and, before each DDS
/// sample is judged, from the DDS task.
struct FastSide<T> {
    sub: FastSubscriber,
    local_writers: Mutex<HashSet<[u8; 16]>>,
    topic: String,
    _t: PhantomData<fn() -> T>,
}

impl<T: RosMessage> FastSide<T> {
    /// Takes every waiting frame, decoded; undecodable frames are logged and skipped.
    fn drain(&self) -> Vec<Received<T>> {
        let mut out = Vec::new();
        loop {
            match self.sub.try_receive() {
                Ok(Some(frame)) => {
                    if let Some(r) = self.decode(&frame) {
                        out.push(r);
                    }
                }
                Ok(None) => break,
                Err(e) => {
                    tracing::warn!("{}: shared-memory receive failed: {e}", self.topic);
                    break;
                }
            }
        }
        out
    }

    fn decode(&self, frame: &Frame) -> Option<Received<T>> {
        let gid = frame.header().writer_gid;
        self.local_writers
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .insert(gid);
        match T::decode(frame.bytes()) {
            Ok(message) => Some(Received {
                message,
                via: Via::SharedMemory,
                writer_gid: gid,
            }),
            Err(e) => {
                tracing::warn!(
                    "{}: dropping undecodable shared-memory frame: {e}",
                    self.topic
                );
                None
            }
        }
    }

    fn is_local_writer(&self, gid: &[u8; 16]) -> bool {
        self.local_writers
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .contains(gid)
    }
}

impl<T: RosMessage> Subscriber<T> {
    /// Subscribes to `topic` (resolved against namespace and remappings).
    pub fn new(node: &CellNode, topic: &str, qos: QosPreset) -> anyhow::Result<Self> {
        let (resolved, name) = topic_name(node, topic)?;
        let profile = node.qos(&resolved, Endpoint::Subscription, qos.profile());
        let dds = node.with_ros_node(|n| {
            let t = n.create_topic(&name, type_name::<T>(), &profile)?;
            n.create_subscription::<T>(&t, Some(profile.clone()))
        });
        let dds = dds.map_err(|e| anyhow!("subscription on {resolved}: {e:?}"))?;
        let fast = match (qos, node.fast_path()) {
            (QosPreset::Stream, Some(fp)) => match fp.subscriber(&resolved, T::ROS_NAME) {
                Ok(sub) => Some(Arc::new(FastSide::<T> {
                    sub,
                    local_writers: Mutex::new(HashSet::new()),
                    topic: resolved.clone(),
                    _t: PhantomData,
                })),
                Err(e) => {
                    tracing::warn!("{resolved}: fast path unavailable, using DDS: {e}");
                    None
                }
            },
            _ => None,
        };
        // Streams keep only the newest frames; plans and status queue up.
        let capacity = if qos == QosPreset::Stream { 4 } else { 64 };
        let lossy = qos == QosPreset::Stream;
        let (tx, rx) = mpsc::channel(capacity);
        let stop = Arc::new(AtomicBool::new(false));

        if let Some(fast) = &fast {
            let (fast, tx, stop) = (fast.clone(), tx.clone(), stop.clone());
            std::thread::Builder::new()
                .name(format!("shm {resolved}"))
                .spawn(move || {
                    while !stop.load(Ordering::Relaxed) && !tx.is_closed() {
                        if let Err(e) = fast.sub.wait(Duration::from_millis(100)) {
                            tracing::warn!("{}: shared-memory wait failed: {e}", fast.topic);
                            std::thread::sleep(Duration::from_millis(100));
                        }
                        for r in fast.drain() {
                            forward_blocking(&tx, r, lossy);
                        }
                    }
                })
                .context("starting the shared-memory receive thread")?;
        }

        let topic = resolved.clone();
        let task = tokio::spawn(async move {
            let mut stream = std::pin::pin!(dds.async_stream());
            while let Some(item) = stream.next().await {
                let (message, info) = match item {
                    Ok(ok) => ok,
                    Err(e) => {
                        tracing::warn!("{topic}: dropping undecodable DDS sample: {e:?}");
                        continue;
                    }
                };
                let gid = info.publisher_gid().to_bytes16();
                if let Some(fast) = &fast {
                    for r in fast.drain() {
                        if !forward(&tx, r, lossy).await {
                            return;
                        }
                    }
                    if fast.is_local_writer(&gid) {
                        continue; // already delivered over shared memory
                    }
                }
                let r = Received {
                    message,
                    via: Via::Dds,
                    writer_gid: gid,
                };
                if !forward(&tx, r, lossy).await {
                    return;
                }
            }
        });
        Ok(Self {
            topic: resolved,
            rx,
            stop,
            task,
        })
    }

    /// The resolved topic name.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// The next message; `None` only if the subscriber's background task has ended.
    pub async fn recv(&mut self) -> Option<Received<T>> {
        self.rx.recv().await
    }
}

/// Hands a message to the subscriber's queue; streams drop it when the queue is full rather
/// than stall the transport. Returns false once the subscriber is gone.
async fn forward<T>(tx: &mpsc::Sender<Received<T>>, r: Received<T>, lossy: bool) -> bool {
    if lossy {
        !matches!(tx.try_send(r), Err(mpsc::error::TrySendError::Closed(_)))
    } else {
        tx.send(r).await.is_ok()
    }
}

fn forward_blocking<T>(tx: &mpsc::Sender<Received<T>>, r: Received<T>, lossy: bool) {
    if lossy {
        let _ = tx.try_send(r);
    } else {
        let _ = tx.blocking_send(r);
    }
}

impl CellNode {
    /// Creates a [`Publisher`] of `T` on `topic`.
    pub fn publisher<T: RosMessage>(
        &self,
        topic: &str,
        qos: QosPreset,
    ) -> anyhow::Result<Publisher<T>> {
        Publisher::new(self, topic, qos)
    }

    /// Creates a [`Subscriber`] of `T` on `topic`.
    pub fn subscriber<T: RosMessage>(
        &self,
        topic: &str,
        qos: QosPreset,
    ) -> anyhow::Result<Subscriber<T>> {
        Subscriber::new(self, topic, qos)
    }
}
