//! Same-host shared-memory transport over iceoryx2, for large messages such as heat maps.
//!
//! Each ROS topic gets one iceoryx2 publish-subscribe service carrying the message's CDR bytes
//! (the same bytes DDS would carry, encapsulation header included), plus an event service that
//! wakes subscribers. Every frame has a [`FrameHeader`] naming the DDS writer that also owns the
//! topic, so a subscriber that gets a frame both ways can drop the DDS copy (see
//! [`crate::pubsub`]).
//!
//! Service names are `cellsuite/<domain>/<topic>/<type>`, so two ROS domains on one host never
//! share memory, and a type mismatch is a different service rather than garbage.
//!
//! This layer is synchronous and thread-safe (`ipc_threadsafe`), so it serves both the async
//! node API and the benchmark's busy threads.

use std::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use iceoryx2::sample_mut::SampleMut;
use iceoryx2::service::ipc_threadsafe;

type Svc = ipc_threadsafe::Service;

/// Metadata sent with every shared-memory frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend)]
#[repr(C)]
pub struct FrameHeader {
    /// GID of the DDS writer that publishes the same topic from the same node.
    pub writer_gid: [u8; 16],
    /// Per-writer frame counter, starting at 1.
    pub sequence: u64,
    /// Send time, nanoseconds since the Unix epoch (for latency figures).
    pub sent_at_ns: u64,
}

/// Why the fast path is not available; the caller falls back to DDS.
#[derive(Debug, thiserror::Error)]
pub enum FastPathError {
    /// `/dev/shm` is missing or not writable (containers without shared memory, for example).
    #[error("shared memory unavailable: {0}")]
    NoSharedMemory(String),
    /// iceoryx2 refused to create or open something.
    #[error("iceoryx2 {what}: {detail}")]
    Iceoryx {
        /// The step that failed.
        what: &'static str,
        /// iceoryx2's error.
        detail: String,
    },
    /// The frame is larger than the service allows.
    #[error("frame of {0} bytes is too large for the fast path")]
    TooLarge(usize),
}

fn ice<E: std::fmt::Debug>(what: &'static str) -> impl FnOnce(E) -> FastPathError {
    move |e| FastPathError::Iceoryx {
        what,
        detail: format!("{e:?}"),
    }
}

/// Bounds shared by every opener of a service; iceoryx2 requires them to agree.
const MAX_PUBLISHERS: usize = 8;
const MAX_SUBSCRIBERS: usize = 16;
const MAX_NODES: usize = 32;
const SUBSCRIBER_BUFFER: usize = 4;
/// First shared-memory segment size; segments grow by powers of two for larger frames.
const INITIAL_SLICE_BYTES: usize = 64 * 1024;

/// One process's handle on iceoryx2, scoped to a ROS domain.
pub struct FastPath {
    node: Node<Svc>,
    domain_id: u16,
}

impl std::fmt::Debug for FastPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FastPath")
            .field("domain_id", &self.domain_id)
            .finish()
    }
}

impl FastPath {
    /// Opens the fast path for `domain_id`, or says why it cannot be used on this host.
    pub fn open(domain_id: u16) -> Result<Self, FastPathError> {
        check_shared_memory()?;
        // iceoryx2 warns on stdout about running without a config file; only errors matter here.
        set_log_level_from_env_or(LogLevel::Error);
        let node = NodeBuilder::new()
            // The node runtime owns SIGINT/SIGTERM handling.
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<Svc>()
            .map_err(ice("node"))?;
        Ok(Self { node, domain_id })
    }

    fn service_name(
        &self,
        topic: &str,
        ros_type: &str,
        suffix: &str,
    ) -> Result<ServiceName, FastPathError> {
        let name = format!(
            "cellsuite/{}{}/{}{}",
            self.domain_id, topic, ros_type, suffix
        );
        ServiceName::new(&name).map_err(ice("service name"))
    }

    fn pubsub(
        &self,
        topic: &str,
        ros_type: &str,
    ) -> Result<
        iceoryx2::service::port_factory::publish_subscribe::PortFactory<Svc, [u8], FrameHeader>,
        FastPathError,
    > {
        self.node
            .service_builder(&self.service_name(topic, ros_type, "")?)
            .publish_subscribe::<[u8]>()
            .user_header::<FrameHeader>()
            .max_publishers(MAX_PUBLISHERS)
            .max_subscribers(MAX_SUBSCRIBERS)
            .max_nodes(MAX_NODES)
            .subscriber_max_buffer_size(SUBSCRIBER_BUFFER)
            .history_size(0)
            .enable_safe_overflow(true)
            .open_or_create()
            .map_err(ice("publish-subscribe service"))
    }

    fn event(
        &self,
        topic: &str,
        ros_type: &str,
    ) -> Result<iceoryx2::service::port_factory::event::PortFactory<Svc>, FastPathError> {
        self.node
            .service_builder(&self.service_name(topic, ros_type, "/wake")?)
            .event()
            .max_notifiers(MAX_PUBLISHERS)
            .max_listeners(MAX_SUBSCRIBERS)
            .max_nodes(MAX_NODES)
            .open_or_create()
            .map_err(ice("event service"))
    }

    /// A publisher for `topic` (fully qualified ROS name) carrying `ros_type` frames.
    pub fn publisher(
        &self,
        topic: &str,
        ros_type: &str,
        writer_gid: [u8; 16],
    ) -> Result<FastPublisher, FastPathError> {
        let pubsub = self.pubsub(topic, ros_type)?;
        let publisher = pubsub
            .publisher_builder()
            .initial_max_slice_len(INITIAL_SLICE_BYTES)
            .allocation_strategy(AllocationStrategy::PowerOfTwo)
            .max_loaned_samples(2)
            .create()
            .map_err(ice("publisher"))?;
        let notifier = self
            .event(topic, ros_type)?
            .notifier_builder()
            .create()
            .map_err(ice("notifier"))?;
        Ok(FastPublisher {
            pubsub,
            publisher,
            notifier,
            writer_gid,
            sequence: std::sync::atomic::AtomicU64::new(0),
        })
    }

    /// A subscriber for `topic` carrying `ros_type` frames.
    pub fn subscriber(&self, topic: &str, ros_type: &str) -> Result<FastSubscriber, FastPathError> {
        let subscriber = self
            .pubsub(topic, ros_type)?
            .subscriber_builder()
            .create()
            .map_err(ice("subscriber"))?;
        let listener = self
            .event(topic, ros_type)?
            .listener_builder()
            .create()
            .map_err(ice("listener"))?;
        Ok(FastSubscriber {
            subscriber,
            listener,
        })
    }
}

fn check_shared_memory() -> Result<(), FastPathError> {
    check_shared_memory_at(std::path::Path::new("/dev/shm"))
}

/// iceoryx2 keeps its segments in `shm` (`/dev/shm` on Linux); containers often lack it.
fn check_shared_memory_at(shm: &std::path::Path) -> Result<(), FastPathError> {
    let unavailable =
        |why: String| FastPathError::NoSharedMemory(format!("{}: {why}", shm.display()));
    let meta = std::fs::metadata(shm).map_err(|e| unavailable(e.to_string()))?;
    if !meta.is_dir() || meta.permissions().readonly() {
        return Err(unavailable("not a writable directory".into()));
    }
    Ok(())
}

/// Now, in nanoseconds since the Unix epoch.
pub fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or_default()
}

/// Sends CDR frames on one topic over shared memory.
pub struct FastPublisher {
    pubsub: iceoryx2::service::port_factory::publish_subscribe::PortFactory<Svc, [u8], FrameHeader>,
    publisher: Publisher<Svc, [u8], FrameHeader>,
    notifier: Notifier<Svc>,
    writer_gid: [u8; 16],
    sequence: std::sync::atomic::AtomicU64,
}

impl FastPublisher {
    /// How many shared-memory subscribers are connected right now (any process on this host).
    pub fn subscriber_count(&self) -> usize {
        self.pubsub.dynamic_config().number_of_subscribers()
    }

    /// Lends a frame of `len` bytes in shared memory; fill it and pass it to [`Self::send`].
    /// Writing the message straight into the loan is what makes the path zero-copy.
    pub fn loan(&self, len: usize) -> Result<FrameLoan, FastPathError> {
        let sample = self.publisher.loan_slice(len).map_err(|e| match e {
            iceoryx2::port::LoanError::ExceedsMaxLoanSize => FastPathError::TooLarge(len),
            other => ice("loan")(other),
        })?;
        Ok(FrameLoan { sample })
    }

    /// Sends a filled loan and wakes the subscribers. Returns how many received it.
    pub fn send(&self, mut loan: FrameLoan) -> Result<usize, FastPathError> {
        let sequence = self
            .sequence
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed)
            + 1;
        *loan.sample.user_header_mut() = FrameHeader {
            writer_gid: self.writer_gid,
            sequence,
            sent_at_ns: now_ns(),
        };
        let delivered = loan.sample.send().map_err(ice("send"))?;
        if delivered > 0 {
            self.notifier.notify().map_err(ice("notify"))?;
        }
        Ok(delivered)
    }

    /// Copies `bytes` into a loan and sends it.
    pub fn send_copy(&self, bytes: &[u8]) -> Result<usize, FastPathError> {
        let mut loan = self.loan(bytes.len())?;
        loan.bytes_mut().copy_from_slice(bytes);
        self.send(loan)
    }
}

/// A shared-memory frame being filled by its publisher.
pub struct FrameLoan {
    sample: SampleMut<Svc, [u8], FrameHeader>,
}

impl FrameLoan {
    /// The frame's bytes, in shared memory.
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        self.sample.payload_mut()
    }
}

/// Receives CDR frames on one topic over shared memory.
pub struct FastSubscriber {
    subscriber: Subscriber<Svc, [u8], FrameHeader>,
    listener: Listener<Svc>,
}

/// A received frame, still in shared memory until dropped.
pub struct Frame {
    sample: Sample<Svc, [u8], FrameHeader>,
}

impl Frame {
    /// The CDR bytes (encapsulation header included).
    pub fn bytes(&self) -> &[u8] {
        self.sample.payload()
    }

    /// Who sent it, and when.
    pub fn header(&self) -> &FrameHeader {
        self.sample.user_header()
    }
}

impl FastSubscriber {
    /// The next frame if one is waiting.
    pub fn try_receive(&self) -> Result<Option<Frame>, FastPathError> {
        Ok(self
            .subscriber
            .receive()
            .map_err(ice("receive"))?
            .map(|sample| Frame { sample }))
    }

    /// Waits up to `timeout` for a publisher's wake-up (returns early on one). Spurious
    /// returns are fine: callers loop on [`Self::try_receive`].
    pub fn wait(&self, timeout: Duration) -> Result<(), FastPathError> {
        self.listener
            .timed_wait(|_| {}, timeout)
            .map(|_| ())
            .map_err(ice("wait"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_or_unusable_shared_memory_is_reported_not_fatal() {
        let err = check_shared_memory_at(std::path::Path::new("/nonexistent/shm")).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("shared memory unavailable: /nonexistent/shm:"),
            "{err}"
        );
        let file = tempfile::NamedTempFile::new().unwrap();
        let err = check_shared_memory_at(file.path()).unwrap_err();
        assert!(
            err.to_string().contains("not a writable directory"),
            "{err}"
        );
        let dir = tempfile::tempdir().unwrap();
        assert!(check_shared_memory_at(dir.path()).is_ok());
    }
}
