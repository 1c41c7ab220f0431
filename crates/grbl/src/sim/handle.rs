//! The simulator's handle: read the executed-line log, the events and the machine state, and
//! wait for a state. Hosts attach through it too (`link`).

use std::sync::{Arc, Mutex, MutexGuard};

use tokio::sync::{mpsc, watch};

use super::clock::SimClock;
use super::link::Inbox;
use super::record::Record;
use super::{ExecutedLine, ParserState, SimEvent, SimSnapshot};

/// Handle to a running simulator: attach hosts, read the executed-line log, the events and the
/// machine state. Cloning gives another handle to the same simulator; dropping the last one stops
/// it.
#[derive(Clone)]
pub struct SimHandle {
    pub(super) inbox: mpsc::UnboundedSender<Inbox>,
    pub(super) record: Arc<Mutex<Record>>,
    pub(super) snapshot: watch::Receiver<SimSnapshot>,
    pub(super) clock: SimClock,
    /// Output due within this much tokio time is written at once
    /// ([`SimConfig::timer_slack`](super::SimConfig::timer_slack)).
    pub(super) slack: std::time::Duration,
    pub(super) next_conn: Arc<std::sync::atomic::AtomicU64>,
}

impl std::fmt::Debug for SimHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimHandle").finish_non_exhaustive()
    }
}

impl SimHandle {
    /// Simulated time now (s).
    pub fn now_s(&self) -> f64 {
        self.clock.now()
    }

    fn record(&self) -> MutexGuard<'_, Record> {
        self.record.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Every executed line so far.
    pub fn executed(&self) -> Vec<ExecutedLine> {
        self.record().log.clone()
    }

    /// The text of every executed line so far.
    pub fn executed_lines(&self) -> Vec<String> {
        self.record().log.iter().map(|l| l.text.clone()).collect()
    }

    /// Every event so far.
    pub fn events(&self) -> Vec<SimEvent> {
        self.record().events.clone()
    }

    /// True when any byte was lost to a full RX ring.
    pub fn overflowed(&self) -> bool {
        self.record().overflow_bytes > 0
    }

    /// Bytes lost to a full RX ring.
    pub fn overflow_bytes(&self) -> u64 {
        self.record().overflow_bytes
    }

    /// Most bytes ever waiting in the RX ring at once.
    pub fn rx_high_water(&self) -> usize {
        self.record().rx_high_water
    }

    /// The parser's modal state now (`$G`'s content) and its position. The parser runs ahead
    /// of the motion by the planner's length; [`ExecutedLine::parser`] has the state right after
    /// each executed line.
    pub fn parser_state(&self) -> ParserState {
        self.record().parser.clone()
    }

    /// The latest machine snapshot.
    pub fn snapshot(&self) -> SimSnapshot {
        self.snapshot.borrow().clone()
    }

    /// Waits until `pred` holds for a snapshot (snapshots are published after every step of the
    /// simulation), for at most `timeout` of tokio time. `Err` carries the latest snapshot when
    /// the time ran out or the simulator stopped first, so a test can fail with it instead of
    /// hanging.
    pub async fn wait_for(
        &self,
        timeout: std::time::Duration,
        mut pred: impl FnMut(&SimSnapshot) -> bool,
    ) -> Result<SimSnapshot, SimSnapshot> {
        let mut rx = self.snapshot.clone();
        let got = tokio::time::timeout(timeout, rx.wait_for(|s| pred(s)))
            .await
            .map(|r| r.map(|s| s.clone()));
        match got {
            Ok(Ok(s)) => Ok(s),
            Ok(Err(_)) | Err(_) => Err(self.snapshot()),
        }
    }
}
