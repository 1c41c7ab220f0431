//! The ABB safe stop, shared by hold, abort, cancel, a lost link and the start-up check: stop
//! RAPID, write the controller file's heat-off outputs, then read both back. "Heat off
//! confirmed" means the controller itself reports RAPID stopped and every heat-off output at
//! its off value; anything less is "heat state unknown", with the reason.
//!
//! RAPID leaves a digital output where it is when it stops, so stopping alone would leave
//! `doWeld` on if the program stopped between its `SetDO doWeld, 1` and `SetDO doWeld, 0`.
//! RAPID is stopped first, so a running program cannot set an output again after it was
//! written.

use cell_rws::{Reconnect, RwsClient, SignalValue};

/// What one safe stop achieved, as the controller reports it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SafeStop {
    /// RAPID reads stopped.
    pub rapid_stopped: bool,
    /// `None`: heat off confirmed; else why the heat state is unknown.
    pub unknown: Option<String>,
    /// Every heat-off output read back at its off value (`signal = value`).
    pub read_back: Vec<String>,
    /// Attempts made.
    pub attempts: u32,
}

impl SafeStop {
    /// The heat is confirmed off.
    pub fn confirmed(&self) -> bool {
        self.unknown.is_none()
    }

    /// One phrase for results and logs: "RAPID stopped, heat off confirmed (…)" or
    /// "heat state unknown: …".
    pub fn note(&self) -> String {
        let tries = if self.attempts > 1 {
            format!(" after {} attempts", self.attempts)
        } else {
            String::new()
        };
        match &self.unknown {
            None if self.read_back.is_empty() => format!(
                "RAPID stopped, heat off confirmed{tries} (RAPID reads stopped; the controller file names no heat_off_outputs: the arc stops with RAPID)"
            ),
            None => format!(
                "RAPID stopped, heat off confirmed{tries} ({} read back)",
                self.read_back.join(", ")
            ),
            Some(why) => format!("heat state unknown{tries}: {why}"),
        }
    }
}

/// Stops RAPID, writes `outputs`, reads both back; once.
pub(crate) async fn once(client: &RwsClient, outputs: &[SignalValue]) -> SafeStop {
    let mut problems = Vec::new();
    if let Err(e) = client.stop().await {
        problems.push(format!("RAPID stop failed: {e}"));
    }
    for out in outputs {
        if let Err(e) = client.write_signal(&out.signal, &out.value).await {
            problems.push(format!("{} not written: {e}", out.signal));
        }
    }
    let rapid_stopped = match client.execution_state().await {
        Ok(s) if !s.is_running() => true,
        Ok(_) => {
            problems.push("RAPID still reads running".into());
            false
        }
        Err(e) => {
            problems.push(format!("RAPID state not read: {e}"));
            false
        }
    };
    let mut read_back = Vec::new();
    for out in outputs {
        match client.read_signal(&out.signal).await {
            Ok(v) if v.trim() == out.value.trim() => {
                read_back.push(format!("{} = {}", out.signal, out.value));
            }
            Ok(v) => problems.push(format!("{} reads {v}, not {}", out.signal, out.value)),
            Err(e) => problems.push(format!("{} not read: {e}", out.signal)),
        }
    }
    // A failed request whose effect the read-back shows anyway (a stop answered late) is no
    // problem: only what the controller reports counts.
    let confirmed = rapid_stopped && read_back.len() == outputs.len();
    let why = match problems.len() {
        0 | 1 => problems.join(""),
        n => format!("{} (and {} more failed)", problems[0], n - 1),
    };
    SafeStop {
        rapid_stopped,
        unknown: (!confirmed).then_some(why),
        read_back,
        attempts: 1,
    }
}

/// [`once`] until confirmed, at most `reconnect.attempts` times, `reconnect.delay_s` apart;
/// `on_attempt` hears of each failed attempt (attempt number, what it left unknown).
pub(crate) async fn retrying(
    client: &RwsClient,
    outputs: &[SignalValue],
    reconnect: Reconnect,
    mut on_attempt: impl FnMut(u32, &str),
) -> SafeStop {
    let attempts = reconnect.attempts.max(1);
    let mut attempt = 1;
    loop {
        let mut stop = once(client, outputs).await;
        stop.attempts = attempt;
        match &stop.unknown {
            None => return stop,
            Some(_) if attempt >= attempts => return stop,
            Some(why) => on_attempt(attempt, why),
        }
        attempt += 1;
        tokio::time::sleep(reconnect.delay()).await;
    }
}

/// Whether any heat-off output reads other than its off value (`Ok(None)`: all off); errors
/// name the output that could not be read.
pub(crate) async fn heat_on(
    client: &RwsClient,
    outputs: &[SignalValue],
) -> Result<Option<String>, String> {
    for out in outputs {
        match client.read_signal(&out.signal).await {
            Ok(v) if v.trim() == out.value.trim() => {}
            Ok(v) => return Ok(Some(format!("{} reads {v}", out.signal))),
            Err(e) => return Err(format!("{} not read: {e}", out.signal)),
        }
    }
    Ok(None)
}
