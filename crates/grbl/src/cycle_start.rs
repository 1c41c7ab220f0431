//! A cycle start (`~`) that waits for the feed hold to be complete and confirms it was taken.
//!
//! GRBL takes `~` only when idle or when a hold is complete: during the deceleration
//! (`Hold:1`) it clears the cycle-start flag and does nothing (gnea/grbl 1.1h `protocol.c`,
//! `protocol_exec_rt_system`: "Cycle start only when IDLE or when a hold is complete and ready
//! to resume"). grblHAL's `state_await_hold` handles only the cycle-complete event, and
//! FluidNC v3.7's `protocol_do_cycle_start` resumes a `Hold` only with `holdComplete` set: all
//! three drop a `~` sent while the machine decelerates, and the machine stays held. The GRBL 1.1
//! interface notes (`Hold:0` "hold complete, ready to resume", `Hold:1` "hold in progress,
//! reset will throw an alarm") are what a sender reads.
//!
//! So [`GrblClient::cycle_start_confirmed`]:
//! 1. polls `?` until a report that answers a `?` sent after the call shows the hold complete
//!    (`Hold:0`, or `Door:0`: door closed, ready to resume). GRBL prints a status report before
//!    it acts on a `!` that arrived in the same pass of its real-time loop, so a `Run` right
//!    after a hold was asked for counts as "not held" only when a second fresh report says so;
//! 2. writes `~` once;
//! 3. polls until the controller has left that hold (`Run`, `Idle` with an empty planner,
//!    `Jog`, or a new `Hold:1`).
//!
//! Both waits share one timeout; a hold that does not complete in time gets no
//! `~` (the machine stays held, and the error says so), and a `~` the controller did not take
//! is an error as well.

use std::time::Duration;

use tokio::time::Instant;

use crate::protocol::{MachineState, Realtime};
use crate::stream::{ClientError, GrblClient};

/// The least time left, after `~` went out, for the controller to report that it left the
/// hold (a few status polls).
pub const CONFIRM_AT_LEAST: Duration = Duration::from_secs(1);

/// What a confirmed cycle start did.
#[derive(Debug, Clone, PartialEq)]
pub enum CycleStart {
    /// The hold was complete, `~` went out and the controller left the hold.
    Resumed {
        /// The state `~` was sent in (`Hold:0`, `Door:0`).
        from: MachineState,
        /// The first state reported after it.
        to: MachineState,
        /// From the call until the hold was complete (the deceleration waited out).
        waited_for_hold: Duration,
    },
    /// The controller was moving, not held: nothing was sent.
    NotHeld(MachineState),
}

impl std::fmt::Display for CycleStart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CycleStart::Resumed {
                from,
                to,
                waited_for_hold,
            } if waited_for_hold.as_millis() >= 10 => write!(
                f,
                "resumed: waited {:.2} s for the hold to complete, cycle start (~) taken ({from} -> {to})",
                waited_for_hold.as_secs_f64()
            ),
            CycleStart::Resumed { from, to, .. } => {
                write!(f, "resumed: cycle start (~) taken ({from} -> {to})")
            }
            CycleStart::NotHeld(state) => {
                write!(f, "not in a hold ({state}): nothing to resume, no cycle start sent")
            }
        }
    }
}

/// Why a confirmed cycle start failed. Every variant says whether `~` went out.
#[derive(Debug, thiserror::Error)]
pub enum CycleStartError {
    /// The link is down or the link task has ended.
    #[error("cycle start (~) not sent: {0}")]
    Link(#[from] ClientError),
    /// The hold was still decelerating (or the door open) when the wait ended; `~` was not
    /// sent, since the controller would drop it.
    #[error("the feed hold did not complete within {waited:.1?} (still {state}): cycle start (~) not sent, because GRBL ignores it until the hold is complete (Hold:0); the machine stays held: resume again once it has stopped")]
    HoldNotComplete {
        /// The last reported state (`Hold:1`, `Door:1`..`Door:3`).
        state: MachineState,
        /// How long we waited.
        waited: Duration,
    },
    /// `~` went out in a complete hold, but the controller still reports that hold.
    #[error("cycle start (~) sent in {state}, but the controller still reports {state} after {waited:.1?}: the resume was not taken and the machine stays held")]
    NotTaken {
        /// The hold it stayed in.
        state: MachineState,
        /// How long we waited after sending.
        waited: Duration,
    },
    /// A state no cycle start resumes (`Idle` with nothing held, `Alarm`, `Check`, `Sleep`).
    #[error(
        "cycle start (~) not sent: the controller is in {0}, not in a hold: nothing to resume"
    )]
    NothingToResume(MachineState),
    /// `~` went out, but the controller went to a state that is not motion (`Alarm`, `Door`).
    #[error("cycle start (~) sent in {from}, but the controller went to {to}: the program is not running")]
    Interrupted {
        /// The hold `~` was sent in.
        from: MachineState,
        /// Where it went instead.
        to: MachineState,
    },
    /// No status report came back in time.
    #[error("cycle start (~) not sent: no status report within {0:?}")]
    NoStatus(Duration),
}

/// What the first wait found.
enum Found {
    /// A complete hold: `~` is taken now.
    Ready(MachineState),
    /// Moving in two fresh reports: not held.
    Moving(MachineState),
    /// Not held and not moving.
    Other(MachineState),
}

impl GrblClient {
    /// Waits for a feed hold to be complete, sends `~`, and waits for the controller to leave
    /// the hold, all within about `timeout` (the confirmation gets at least
    /// [`CONFIRM_AT_LEAST`] after `~`); see the module documentation.
    pub async fn cycle_start_confirmed(
        &self,
        timeout: Duration,
    ) -> Result<CycleStart, CycleStartError> {
        let started = Instant::now();
        let mut moving_reports = 0u32;
        let found = self
            .poll_state(started + timeout, |state| match state {
                MachineState::Hold(0) | MachineState::Door(0) => Some(Found::Ready(state)),
                MachineState::Hold(_) | MachineState::Door(_) => None,
                MachineState::Run | MachineState::Jog | MachineState::Home => {
                    moving_reports += 1;
                    (moving_reports >= 2).then_some(Found::Moving(state))
                }
                MachineState::Idle
                | MachineState::Alarm
                | MachineState::Check
                | MachineState::Sleep => Some(Found::Other(state)),
            })
            .await?;
        let from = match found {
            Polled::Got(Found::Ready(state)) => state,
            Polled::Got(Found::Moving(state)) => return Ok(CycleStart::NotHeld(state)),
            Polled::Got(Found::Other(state)) => {
                return Err(CycleStartError::NothingToResume(state))
            }
            Polled::TimedOut(Some(state)) => {
                return Err(CycleStartError::HoldNotComplete {
                    state,
                    waited: started.elapsed(),
                })
            }
            Polled::TimedOut(None) => return Err(CycleStartError::NoStatus(timeout)),
        };
        let waited_for_hold = started.elapsed();
        let sent_at = Instant::now();
        self.realtime(&[Realtime::CycleStart]).await?;
        let left = self
            .poll_state(
                (started + timeout).max(sent_at + CONFIRM_AT_LEAST),
                |state| (state != from).then_some(state),
            )
            .await?;
        match left {
            Polled::Got(
                to @ (MachineState::Run
                | MachineState::Idle
                | MachineState::Jog
                | MachineState::Hold(_)),
            ) => Ok(CycleStart::Resumed {
                from,
                to,
                waited_for_hold,
            }),
            Polled::Got(to) => Err(CycleStartError::Interrupted { from, to }),
            Polled::TimedOut(_) => Err(CycleStartError::NotTaken {
                state: from,
                waited: sent_at.elapsed(),
            }),
        }
    }

    /// Sends `?` every 50 ms until `decide` returns a value for a fresh report, or `deadline`
    /// (a timeout carries the last fresh state). Fresh: counted after the call's first `?`
    /// could have been answered, so a `?` already on its way (answered with the state from
    /// before whatever the caller just sent) does not count.
    async fn poll_state<T>(
        &self,
        deadline: Instant,
        mut decide: impl FnMut(MachineState) -> Option<T>,
    ) -> Result<Polled<T>, ClientError> {
        let mut rx = self.progress();
        let mut seen = rx.borrow().status_count + 1;
        let mut last = None;
        let mut next_poll = Instant::now();
        loop {
            let (count, state) = {
                let p = rx.borrow_and_update();
                if !p.connected {
                    return Err(ClientError::NotConnected);
                }
                (p.status_count, p.status.as_ref().and_then(|s| s.state))
            };
            if count > seen {
                seen = count;
                if let Some(state) = state {
                    last = Some(state);
                    if let Some(v) = decide(state) {
                        return Ok(Polled::Got(v));
                    }
                }
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(Polled::TimedOut(last));
            }
            if now >= next_poll {
                self.realtime(&[Realtime::StatusQuery]).await?;
                next_poll = now + Duration::from_millis(50);
            }
            let _ = tokio::time::timeout_at(next_poll.min(deadline), rx.changed()).await;
        }
    }
}

enum Polled<T> {
    Got(T),
    TimedOut(Option<MachineState>),
}
