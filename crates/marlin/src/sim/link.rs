//! The serial link and the clock: a reader task per host feeding received lines to the
//! firmware, a writer task per host, and a ticker advancing simulated time every 2 ms of tokio
//! time. The simulator runs until its last [`SimHandle`] is dropped.

use std::sync::{Arc, Mutex, MutexGuard, Weak};
use std::time::Duration;

use tokio::io::{AsyncBufReadExt, AsyncRead, AsyncWrite, AsyncWriteExt, BufReader};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;

use super::firmware::Firmware;
use super::{OnConnect, SimEvent, SimSnapshot};

/// The current host.
struct Host {
    id: u64,
    out: mpsc::UnboundedSender<String>,
    reader: JoinHandle<()>,
}

struct Inner {
    fw: Mutex<Firmware>,
    host: Mutex<Option<Host>>,
    next_id: std::sync::atomic::AtomicU64,
}

impl Drop for Inner {
    fn drop(&mut self) {
        if let Some(h) = lock(&self.host).take() {
            h.reader.abort();
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// A running simulator.
#[derive(Clone)]
pub struct SimHandle {
    inner: Arc<Inner>,
}

impl std::fmt::Debug for SimHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimHandle").finish_non_exhaustive()
    }
}

pub(super) fn spawn(fw: Firmware) -> SimHandle {
    let inner = Arc::new(Inner {
        fw: Mutex::new(fw),
        host: Mutex::new(None),
        next_id: std::sync::atomic::AtomicU64::new(1),
    });
    tokio::spawn(ticker(Arc::downgrade(&inner)));
    SimHandle { inner }
}

async fn ticker(inner: Weak<Inner>) {
    let period = Duration::from_millis(2);
    let mut last = tokio::time::Instant::now();
    let mut interval = tokio::time::interval(period);
    interval.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        interval.tick().await;
        let Some(inner) = inner.upgrade() else {
            return;
        };
        let now = tokio::time::Instant::now();
        let dt = (now - last).as_secs_f64();
        last = now;
        let (lines, drop_link) = {
            let mut fw = lock(&inner.fw);
            let scale = fw.cfg.time_scale;
            // Small steps keep the heater model and the handlers' timing fine-grained.
            let mut left = dt * scale;
            while left > 0.0 {
                let step = left.min(0.05);
                fw.tick(step);
                left -= step;
            }
            let drop_link = std::mem::take(&mut fw.drop_requested);
            (std::mem::take(&mut fw.out), drop_link)
        };
        let mut host = lock(&inner.host);
        if let Some(h) = host.as_ref() {
            for l in lines {
                let _ = h.out.send(l);
            }
        }
        if drop_link {
            if let Some(h) = host.take() {
                h.reader.abort();
            }
        }
    }
}

impl SimHandle {
    /// Attaches a host on a byte stream (TCP socket, pty master, in-memory pipe); it replaces
    /// the current host, whose link is closed. What the host sees first follows
    /// [`OnConnect`](super::OnConnect).
    pub fn attach<S>(&self, stream: S) -> u64
    where
        S: AsyncRead + AsyncWrite + Send + 'static,
    {
        let id = self
            .inner
            .next_id
            .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        let (rd, mut wr) = tokio::io::split(stream);
        let (out, mut out_rx) = mpsc::unbounded_channel::<String>();
        tokio::spawn(async move {
            while let Some(line) = out_rx.recv().await {
                let mut bytes = line.into_bytes();
                bytes.push(b'\n');
                if wr.write_all(&bytes).await.is_err() {
                    break;
                }
            }
            let _ = wr.shutdown().await;
        });
        let weak = Arc::downgrade(&self.inner);
        let reader = tokio::spawn(async move {
            let mut lines = BufReader::new(rd).split(b'\n');
            while let Ok(Some(raw)) = lines.next_segment().await {
                let Some(inner) = weak.upgrade() else {
                    return;
                };
                let text = String::from_utf8_lossy(&raw);
                for part in text.split('\r') {
                    lock(&inner.fw).receive_line(part);
                }
            }
            if let Some(inner) = weak.upgrade() {
                let mut host = lock(&inner.host);
                if host.as_ref().is_some_and(|h| h.id == id) {
                    *host = None;
                }
            }
        });
        {
            let mut fw = lock(&self.inner.fw);
            fw.frozen = false;
            fw.events.push(SimEvent::Connected);
            if fw.cfg.on_connect == OnConnect::Reset {
                fw.reset();
            }
        }
        let old = lock(&self.inner.host).replace(Host { id, out, reader });
        if let Some(old) = old {
            old.reader.abort();
        }
        id
    }

    /// Accepts hosts on `addr` (`127.0.0.1:0` for a free port); returns the bound address. Each
    /// connection replaces the previous one.
    ///
    /// # Errors
    /// The address cannot be bound.
    pub async fn listen_tcp(&self, addr: &str) -> std::io::Result<std::net::SocketAddr> {
        let listener = tokio::net::TcpListener::bind(addr).await?;
        let local = listener.local_addr()?;
        let weak = Arc::downgrade(&self.inner);
        tokio::spawn(async move {
            while let Ok((sock, _)) = listener.accept().await {
                let _ = sock.set_nodelay(true);
                let Some(inner) = weak.upgrade() else {
                    return;
                };
                SimHandle { inner }.attach(sock);
            }
        });
        Ok(local)
    }

    /// Creates a pseudo-terminal, attaches its master side and returns the device path a host
    /// opens.
    ///
    /// # Errors
    /// No pty could be opened.
    pub fn open_pty(&self) -> std::io::Result<std::path::PathBuf> {
        let (master, path, slave) = cell_grbl::transport::open_pty()?.into_parts();
        self.attach(master);
        // The slave end stays open while the simulator lives, so the master does not see EOF
        // between hosts.
        let weak = Arc::downgrade(&self.inner);
        tokio::spawn(async move {
            while weak.strong_count() > 0 {
                tokio::time::sleep(Duration::from_millis(200)).await;
            }
            drop(slave);
        });
        Ok(path)
    }

    /// Presses the reset button (or power-cycles): heaters off, `start` to the current host.
    pub fn reset(&self) {
        lock(&self.inner.fw).reset();
    }

    /// Presses the kill button (`KILL_PIN`): `kill()` as for `M112`.
    pub fn press_kill(&self) {
        lock(&self.inner.fw).kill("Kill button");
    }

    /// Drops the current host's link now (a cable pulled).
    pub fn drop_link(&self) {
        if let Some(h) = lock(&self.inner.host).take() {
            h.reader.abort();
        }
    }

    /// The state now.
    pub fn snapshot(&self) -> SimSnapshot {
        let fw = lock(&self.inner.fw);
        let (hotend, bed) = fw.readings();
        SimSnapshot {
            now_s: fw.now_s,
            hotend,
            bed,
            halted: fw.halted.clone(),
            last_line_number: fw.last_line_number(),
            planned_blocks: fw.planned_blocks(),
            busy: fw.busy(),
            position: fw.stepper,
            moves_done: fw.moves_done,
            commands_executed: fw.executed.len(),
            overrides: fw.overrides(),
        }
    }

    /// Every command processed, in order (without `N…*cs`).
    pub fn executed(&self) -> Vec<String> {
        lock(&self.inner.fw).executed.clone()
    }

    /// Everything that happened.
    pub fn events(&self) -> Vec<SimEvent> {
        lock(&self.inner.fw).events.clone()
    }

    /// Lines received since the start.
    pub fn received_lines(&self) -> u64 {
        lock(&self.inner.fw).received
    }

    /// Waits until `pred` holds for a snapshot, polling every 5 ms, or `timeout` passes;
    /// returns the last snapshot and whether `pred` held.
    pub async fn wait_for(
        &self,
        timeout: Duration,
        pred: impl Fn(&SimSnapshot) -> bool,
    ) -> (SimSnapshot, bool) {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            let s = self.snapshot();
            if pred(&s) {
                return (s, true);
            }
            if tokio::time::Instant::now() >= deadline {
                return (s, false);
            }
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    }
}
