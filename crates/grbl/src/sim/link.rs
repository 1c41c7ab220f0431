//! The serial link, both ends. Bytes travel at the configured baud (8N1: baud/10 bytes/s) in
//! each direction, plus an optional one-way latency, in simulated time. On the host side a
//! reader task drains the host's stream at once (so the stream never acts as a hidden buffer)
//! and a writer task delivers output at the time the machine computed for it; on the machine
//! side each byte gets its arrival time, and output is serialised at the baud.

use std::sync::Arc;

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio::time::Instant;

use super::clock::SimClock;
use super::machine::Machine;
use super::{OnConnect, SimEvent, SimHandle};

/// What the host side tells the machine.
pub(super) enum Inbox {
    Attach {
        connection: u64,
        out: mpsc::UnboundedSender<Out>,
        reader: JoinHandle<()>,
    },
    Bytes {
        connection: u64,
        at_s: f64,
        data: Vec<u8>,
    },
    Closed {
        connection: u64,
    },
}

/// What the machine sends the host side's writer.
pub(super) enum Out {
    Data { at_s: f64, bytes: Vec<u8> },
    Close,
}

impl SimHandle {
    /// Attaches a host on any byte stream (TCP socket, pty master, in-memory pipe). A new host
    /// replaces the current one, whose link is closed.
    pub fn attach<S>(&self, stream: S) -> u64
    where
        S: AsyncRead + AsyncWrite + Send + 'static,
    {
        let connection = self
            .next_conn
            .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        let (mut rd, wr) = tokio::io::split(stream);
        let (out_tx, out_rx) = mpsc::unbounded_channel();
        let inbox = self.inbox.clone();
        let clock = self.clock;
        let reader = tokio::spawn(async move {
            let mut buf = vec![0u8; 4096];
            loop {
                match rd.read(&mut buf).await {
                    Ok(0) | Err(_) => break,
                    Ok(n) => {
                        let msg = Inbox::Bytes {
                            connection,
                            at_s: clock.now(),
                            data: buf[..n].to_vec(),
                        };
                        if inbox.send(msg).is_err() {
                            return;
                        }
                    }
                }
            }
            let _ = inbox.send(Inbox::Closed { connection });
        });
        let _ = self.inbox.send(Inbox::Attach {
            connection,
            out: out_tx.clone(),
            reader,
        });
        tokio::spawn(writer(wr, out_rx, clock, self.slack));
        connection
    }

    /// Accepts hosts on a TCP listener bound to `addr` (`127.0.0.1:0` for a free port) and
    /// returns the bound address. Each accepted connection replaces the previous one.
    pub async fn listen_tcp(&self, addr: &str) -> std::io::Result<std::net::SocketAddr> {
        let listener = tokio::net::TcpListener::bind(addr).await?;
        let local = listener.local_addr()?;
        let me = self.clone();
        tokio::spawn(async move {
            while let Ok((sock, _)) = listener.accept().await {
                let _ = sock.set_nodelay(true);
                me.attach(sock);
                if me.inbox.is_closed() {
                    break;
                }
            }
        });
        Ok(local)
    }

    /// Creates a pseudo-terminal, attaches its master side, and returns the slave's device path
    /// for a sender to open. The pty stays open as long as the simulator runs.
    pub fn open_pty(&self) -> std::io::Result<std::path::PathBuf> {
        let (master, path, slave) = crate::transport::open_pty()?.into_parts();
        self.attach(master);
        let inbox = self.inbox.clone();
        tokio::spawn(async move {
            inbox.closed().await;
            drop(slave);
        });
        Ok(path)
    }

    /// A [`Connect`](crate::transport::Connect) that opens an in-memory link to this simulator
    /// (each connect replaces the previous host, like a new TCP connection).
    pub fn connector(&self) -> Arc<dyn crate::transport::Connect> {
        Arc::new(InProcess(self.clone()))
    }
}

struct InProcess(SimHandle);

impl crate::transport::Connect for InProcess {
    fn connect(&self) -> crate::transport::ConnectFuture<'_> {
        Box::pin(async move {
            let (host, sim) = tokio::io::duplex(1 << 16);
            self.0.attach(sim);
            Ok(Box::new(host) as crate::transport::BoxedTransport)
        })
    }

    fn describe(&self) -> String {
        "in-process grbl_sim".into()
    }
}

/// Writes the machine's output to the host at the simulated times it carries.
async fn writer<W: AsyncWrite + Send + 'static>(
    wr: tokio::io::WriteHalf<W>,
    rx: mpsc::UnboundedReceiver<Out>,
    clock: SimClock,
    slack: std::time::Duration,
) {
    let mut wr = wr;
    let mut rx = rx;
    while let Some(msg) = rx.recv().await {
        match msg {
            Out::Data { at_s, bytes } => {
                // The machine computed the delivery time; wait for it unless it is (nearly) due.
                let due = clock.instant_at(at_s);
                if due > Instant::now() + slack {
                    tokio::time::sleep_until(due).await;
                }
                if wr.write_all(&bytes).await.is_err() {
                    break;
                }
            }
            Out::Close => {
                let _ = wr.flush().await;
                let _ = wr.shutdown().await;
                break;
            }
        }
    }
}

impl Machine {
    /// Handles a message from the host side: a new host, bytes on the wire, a closed link.
    pub(super) fn inbox(&mut self, msg: Inbox) {
        match msg {
            Inbox::Attach {
                connection,
                out,
                reader,
            } => {
                self.close_link(false);
                // A new host finds a frozen controller answering again.
                self.frozen = false;
                self.connection = connection;
                self.out = Some(out);
                self.reader = Some(reader);
                self.out_free_at = self.t;
                self.event(SimEvent::Connected {
                    connection,
                    at_s: self.t,
                });
                match self.cfg.on_connect {
                    OnConnect::Banner => {
                        let banner = self.cfg.firmware.banner();
                        self.emit(&format!("\r\n{banner}"));
                    }
                    OnConnect::Reset => self.hardware_reset(),
                    OnConnect::Silent => {}
                }
            }
            Inbox::Bytes {
                connection,
                at_s,
                data,
            } => {
                // A frozen controller reads nothing: the bytes are lost.
                if connection != self.connection || self.out.is_none() || self.frozen {
                    return;
                }
                let enter = (at_s + self.cfg.latency_s).max(self.t);
                for b in data {
                    let start = enter.max(self.wire_free_at);
                    let arrival = start + self.byte_time;
                    self.wire_free_at = arrival;
                    self.wire.push_back((arrival, b));
                }
            }
            Inbox::Closed { connection } => {
                if connection == self.connection && self.out.is_some() {
                    self.close_link(false);
                }
            }
        }
    }

    /// Closes the current link: output already queued is still delivered, input is discarded.
    pub(super) fn close_link(&mut self, injected: bool) {
        if let Some(out) = self.out.take() {
            let _ = out.send(Out::Close);
            self.event(SimEvent::Disconnected {
                connection: self.connection,
                injected,
                at_s: self.t,
            });
        }
        if let Some(r) = self.reader.take() {
            r.abort();
        }
        self.wire.clear();
        self.rx.clear();
        self.clear_line();
        self.pending = None;
        self.delayed.clear();
    }

    /// Queues `text` + `\r\n` for the host at the current simulated time.
    pub(super) fn emit(&mut self, text: &str) {
        if self.frozen {
            return;
        }
        let Some(out) = &self.out else { return };
        let mut bytes = text.as_bytes().to_vec();
        bytes.extend_from_slice(b"\r\n");
        let start = self.t.max(self.out_free_at);
        let done = start + self.byte_time * bytes.len() as f64;
        self.out_free_at = done;
        let _ = out.send(Out::Data {
            at_s: done + self.cfg.latency_s,
            bytes,
        });
    }
}
