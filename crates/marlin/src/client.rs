//! The host side of Marlin's serial protocol: ping-pong streaming (one numbered, checksummed
//! line in flight, the next once its `ok` came), `Resend:` handling, status queries, and the
//! safe stop.
//!
//! Ping-pong is what OctoPrint and Pronterface do with Marlin: `ok` comes once the command's
//! handler returned, so one line in flight never overruns the 128-byte RX buffer, and a line
//! lost or garbled on the wire is caught by Marlin's line-number and checksum checks and sent
//! again from its history when Marlin asks `Resend: n`.
//!
//! Liveness: a line in flight may take long (`M109` heats for a minute, `G28` homes), but
//! Marlin speaks meanwhile (`echo:busy: processing` every 2 s, wait reports every second), so
//! `command_timeout` of silence means the printer is gone.
//!
//! The safe stop ([`MarlinLink::heat_off`]): `M108` (ends a heating wait, emergency parser) and
//! `M410` (drops the planned moves) if a command is still running, then `M104 S0`, `M140 S0`,
//! `M107`, and `M105`, whose report must show both targets at 0: the heat is off by the
//! printer's own word.

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

use cell_grbl::transport::{BoxedTransport, Connect};
use tokio::io::{AsyncBufReadExt, AsyncWriteExt, BufReader, WriteHalf};
use tokio::sync::{mpsc, watch};

use crate::protocol::{numbered, parse_response, Response, Temps};

/// Lines kept for resends.
const HISTORY: usize = 64;

/// Client settings.
#[derive(Debug, Clone, PartialEq)]
pub struct ClientConfig {
    /// Silence (no `ok`, keepalive or wait report) while a line is in flight after which the
    /// printer is taken as gone.
    pub command_timeout: Duration,
    /// How long to wait for the `start` banner after opening the link (a board that resets on
    /// connect boots for about a second; one that does not says nothing).
    pub boot_wait: Duration,
}

impl Default for ClientConfig {
    fn default() -> Self {
        ClientConfig {
            command_timeout: Duration::from_secs(10),
            boot_wait: Duration::from_millis(1500),
        }
    }
}

/// Why the link cannot go on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinkError {
    /// The link closed or could not be opened.
    #[error("link lost: {0}")]
    Closed(String),
    /// The printer said nothing for this long with a line in flight.
    #[error("no answer from the printer for {0:?}")]
    Timeout(Duration),
    /// `kill()`: the printer halted (heaters off by the firmware); only a reset revives it.
    #[error("printer halted: {0}")]
    Killed(String),
    /// The printer rebooted (`start`) in the middle of a job: everything queued is lost.
    #[error("the printer reset itself (start) with a job running")]
    Reset,
}

/// What the host knows of the printer.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LinkState {
    /// The link is up.
    pub connected: bool,
    /// The last temperatures (from `ok T:`, a wait report or `M105`).
    pub temps: Option<Temps>,
    /// The highest hotend and bed temperatures reported on this link, °C.
    pub peak_c: (f64, f64),
    /// The last `M114` position.
    pub position: Vec<(char, f64)>,
    /// The kill reason (the `Error:` lines before the halt), once halted.
    pub killed: Option<String>,
    /// The last `Error:` that was not about a line.
    pub last_error: Option<String>,
    /// Numbered lines sent (resends not counted).
    pub lines_sent: u64,
    /// `ok`s received.
    pub oks: u64,
    /// Lines sent again on `Resend:`.
    pub resent: u64,
    /// Commands Marlin did not know (`echo:Unknown command`).
    pub unknown: Vec<String>,
}

/// A command sent with [`MarlinLink::send_until`] ended or was interrupted.
#[derive(Debug, Clone, PartialEq)]
pub enum Sent {
    /// Its `ok`, with temperatures for `M105`.
    Acked(Option<Temps>),
    /// The stop signal came first; the line is still in flight.
    Interrupted,
}

/// An open link to a Marlin printer.
pub struct MarlinLink {
    lines: mpsc::UnboundedReceiver<String>,
    writer: WriteHalf<BoxedTransport>,
    reader: tokio::task::JoinHandle<()>,
    next_n: u64,
    history: VecDeque<(u64, String)>,
    in_flight: usize,
    last_ok_temps: Option<Temps>,
    cfg: ClientConfig,
    state: watch::Sender<LinkState>,
}

impl LinkState {
    fn note(&mut self, t: Temps) {
        self.temps = Some(t);
        self.peak_c.0 = self.peak_c.0.max(t.hotend.current);
        self.peak_c.1 = self.peak_c.1.max(t.bed.map_or(0.0, |b| b.current));
    }
}

impl std::fmt::Debug for MarlinLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MarlinLink")
            .field("next_n", &self.next_n)
            .field("in_flight", &self.in_flight)
            .finish_non_exhaustive()
    }
}

impl Drop for MarlinLink {
    fn drop(&mut self) {
        self.reader.abort();
        self.state.send_modify(|s| s.connected = false);
    }
}

impl MarlinLink {
    /// Opens the link, waits for a booting board's `start` and sets the line number
    /// (`N0 M110 N0`). `state` carries what the link learns, for others to watch.
    ///
    /// # Errors
    /// The link cannot be opened; no `ok` to `M110` (a halted or frozen printer).
    pub async fn connect(
        connector: &Arc<dyn Connect>,
        cfg: ClientConfig,
        state: watch::Sender<LinkState>,
    ) -> Result<MarlinLink, LinkError> {
        let stream = connector
            .connect()
            .await
            .map_err(|e| LinkError::Closed(format!("{}: {e}", connector.describe())))?;
        let (rd, writer) = tokio::io::split(stream);
        let (tx, lines) = mpsc::unbounded_channel();
        let reader = tokio::spawn(async move {
            let mut rd = BufReader::new(rd).split(b'\n');
            while let Ok(Some(raw)) = rd.next_segment().await {
                let text = String::from_utf8_lossy(&raw)
                    .trim_end_matches('\r')
                    .to_owned();
                if tx.send(text).is_err() {
                    return;
                }
            }
        });
        state.send_modify(|s| {
            *s = LinkState {
                connected: true,
                ..LinkState::default()
            }
        });
        let mut link = MarlinLink {
            lines,
            writer,
            reader,
            next_n: 0,
            history: VecDeque::new(),
            in_flight: 0,
            last_ok_temps: None,
            cfg,
            state,
        };
        // A board that resets on connect boots first; its banner ends quickly after `start`.
        let boot_until = tokio::time::Instant::now() + link.cfg.boot_wait;
        let mut started = false;
        loop {
            let wait = if started {
                Duration::from_millis(100)
            } else {
                boot_until.saturating_duration_since(tokio::time::Instant::now())
            };
            match tokio::time::timeout(wait, link.lines.recv()).await {
                Ok(Some(l)) => {
                    if parse_response(&l) == Response::Start {
                        started = true;
                    }
                }
                Ok(None) => return Err(link.closed("closed while connecting")),
                Err(_) => break,
            }
        }
        link.send("M110 N0").await?;
        Ok(link)
    }

    /// What the link knows now.
    pub fn state(&self) -> LinkState {
        self.state.borrow().clone()
    }

    /// Commands sent without their `ok` yet.
    pub fn in_flight(&self) -> usize {
        self.in_flight
    }

    fn closed(&self, why: &str) -> LinkError {
        self.state.send_modify(|s| s.connected = false);
        LinkError::Closed(why.to_owned())
    }

    async fn write_line(&mut self, text: &str) -> Result<(), LinkError> {
        let mut bytes = text.as_bytes().to_vec();
        bytes.push(b'\n');
        match self.writer.write_all(&bytes).await {
            Ok(()) => Ok(()),
            Err(e) => Err(self.closed(&e.to_string())),
        }
    }

    /// Sends `command` numbered and checksummed (`M110` takes the number it sets).
    async fn put_numbered(&mut self, command: &str) -> Result<(), LinkError> {
        let n = self.next_n;
        let line = numbered(n, command);
        self.write_line(&line).await?;
        self.history.push_back((n, line));
        if self.history.len() > HISTORY {
            self.history.pop_front();
        }
        self.next_n = n + 1;
        self.in_flight += 1;
        self.state.send_modify(|s| s.lines_sent += 1);
        Ok(())
    }

    /// Sends a line without number or checksum (the emergency commands: Marlin acts on
    /// `M108`/`M112`/`M410` as they arrive, whatever the queue holds). It gets an `ok` too.
    ///
    /// # Errors
    /// The link is down.
    pub async fn send_unnumbered(&mut self, command: &str) -> Result<(), LinkError> {
        self.write_line(command).await?;
        if !command.starts_with("M112") {
            self.in_flight += 1;
        }
        Ok(())
    }

    /// Reads and handles one line from the printer; `Ok(true)` when it was an `ok`.
    async fn pump(&mut self) -> Result<bool, LinkError> {
        let timeout = self.cfg.command_timeout;
        let line = match tokio::time::timeout(timeout, self.lines.recv()).await {
            Ok(Some(l)) => l,
            Ok(None) => return Err(self.closed("the printer closed the link")),
            Err(_) => return Err(LinkError::Timeout(timeout)),
        };
        match parse_response(&line) {
            Response::Ok(temps) => {
                self.in_flight = self.in_flight.saturating_sub(1);
                self.last_ok_temps = temps;
                self.state.send_modify(|s| {
                    s.oks += 1;
                    if let Some(t) = temps {
                        s.note(t);
                    }
                });
                return Ok(true);
            }
            Response::Resend(n) => {
                // Marlin dropped everything after line n-1: send it all again, in order.
                let again: Vec<String> = self
                    .history
                    .iter()
                    .filter(|(k, _)| *k >= n)
                    .map(|(_, l)| l.clone())
                    .collect();
                if again.is_empty() && n < self.next_n {
                    return Err(LinkError::Closed(format!(
                        "Marlin asks to resend line {n}, older than the {HISTORY} kept"
                    )));
                }
                for l in &again {
                    self.write_line(l).await?;
                }
                self.in_flight += again.len();
                let k = again.len() as u64;
                self.state.send_modify(|s| s.resent += k);
                tracing::debug!("marlin: resend from line {n} ({k} lines)");
            }
            Response::LineError(e) => tracing::debug!("marlin: {e}"),
            Response::Killed => {
                let why = self
                    .state
                    .borrow()
                    .last_error
                    .clone()
                    .unwrap_or_else(|| "kill() called".into());
                self.state.send_modify(|s| s.killed = Some(why.clone()));
                return Err(LinkError::Killed(why));
            }
            Response::Error(e) => {
                tracing::warn!("marlin: Error:{e}");
                self.state.send_modify(|s| s.last_error = Some(e));
            }
            Response::WaitReport(t) => self.state.send_modify(|s| s.note(t)),
            Response::Position(p) => self.state.send_modify(|s| s.position = p),
            Response::Start => return Err(LinkError::Reset),
            Response::Unknown(c) => {
                tracing::warn!("marlin: unknown command {c:?}");
                self.state.send_modify(|s| s.unknown.push(c));
            }
            Response::Busy | Response::Other(_) => {}
        }
        Ok(false)
    }

    /// Reads until nothing is in flight.
    ///
    /// # Errors
    /// As [`LinkError`].
    pub async fn drain(&mut self) -> Result<(), LinkError> {
        while self.in_flight > 0 {
            self.pump().await?;
        }
        Ok(())
    }

    /// Sends `command` and waits for its `ok`; the temperatures it carried (`M105`).
    ///
    /// # Errors
    /// As [`LinkError`].
    pub async fn send(&mut self, command: &str) -> Result<Option<Temps>, LinkError> {
        self.drain().await?;
        self.put_numbered(command).await?;
        self.drain().await?;
        Ok(self.last_ok_temps)
    }

    /// Sends `command` and waits for its `ok`, unless `stop` turns true first (then the line
    /// stays in flight: [`MarlinLink::heat_off`] deals with it).
    ///
    /// # Errors
    /// As [`LinkError`].
    pub async fn send_until(
        &mut self,
        command: &str,
        stop: &mut watch::Receiver<bool>,
    ) -> Result<Sent, LinkError> {
        self.drain().await?;
        self.put_numbered(command).await?;
        while self.in_flight > 0 {
            if *stop.borrow_and_update() {
                return Ok(Sent::Interrupted);
            }
            tokio::select! {
                r = self.pump() => { r?; }
                _ = stop.changed() => {}
            }
        }
        Ok(Sent::Acked(self.last_ok_temps))
    }

    /// `M105`: the temperatures.
    ///
    /// # Errors
    /// As [`LinkError`]; an `ok` without temperatures is a closed link's error.
    pub async fn temps(&mut self) -> Result<Temps, LinkError> {
        self.send("M105")
            .await?
            .ok_or_else(|| LinkError::Closed("M105 answered without temperatures".into()))
    }

    /// `M114`: the position (axis, mm).
    ///
    /// # Errors
    /// As [`LinkError`].
    pub async fn position(&mut self) -> Result<Vec<(char, f64)>, LinkError> {
        self.send("M114").await?;
        Ok(self.state.borrow().position.clone())
    }

    /// The safe stop: ends a running command (`M108` for a heating wait, `M410` for moves),
    /// switches the heaters and the fan off and returns the `M105` report that shows both
    /// targets at 0.
    ///
    /// # Errors
    /// As [`LinkError`]; targets still set after `M104 S0`/`M140 S0` are a closed link's error
    /// (the printer does not obey).
    pub async fn heat_off(&mut self) -> Result<Temps, LinkError> {
        if self.in_flight > 0 {
            self.send_unnumbered("M108").await?;
            self.send_unnumbered("M410").await?;
            self.drain().await?;
        }
        self.send("M104 S0").await?;
        self.send("M140 S0").await?;
        self.send("M107").await?;
        let t = self.temps().await?;
        if t.targets_off() {
            Ok(t)
        } else {
            Err(LinkError::Closed(format!(
                "heaters still set after M104 S0/M140 S0: {t}"
            )))
        }
    }

    /// `M112`: the emergency stop (the firmware kills: heaters off, halted until reset).
    ///
    /// # Errors
    /// The link is down.
    pub async fn emergency_stop(&mut self) -> Result<(), LinkError> {
        self.send_unnumbered("M112").await
    }
}
