//! Clean shutdown on SIGINT/SIGTERM, or on request (tests, the launcher).

use tokio_util::sync::CancellationToken;

/// A cloneable shutdown signal. Node loops `select!` on [`Shutdown::requested`].
#[derive(Debug, Clone, Default)]
pub struct Shutdown {
    token: CancellationToken,
}

impl Shutdown {
    /// A signal nobody has triggered yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Also triggers on SIGINT or SIGTERM. Needs a running tokio runtime.
    pub fn with_os_signals(self) -> Self {
        let token = self.token.clone();
        tokio::spawn(async move {
            let name = wait_for_signal().await;
            tracing::info!("{name} received, shutting down");
            token.cancel();
        });
        self
    }

    /// Asks everything holding this signal to stop.
    pub fn trigger(&self) {
        self.token.cancel();
    }

    /// Whether shutdown was asked for.
    pub fn is_triggered(&self) -> bool {
        self.token.is_cancelled()
    }

    /// Completes once shutdown is asked for.
    pub async fn requested(&self) {
        self.token.cancelled().await
    }
}

#[cfg(unix)]
async fn wait_for_signal() -> &'static str {
    use tokio::signal::unix::{signal, SignalKind};
    match (
        signal(SignalKind::interrupt()),
        signal(SignalKind::terminate()),
    ) {
        (Ok(mut int), Ok(mut term)) => tokio::select! {
            _ = int.recv() => "SIGINT",
            _ = term.recv() => "SIGTERM",
        },
        _ => {
            let _ = tokio::signal::ctrl_c().await;
            "Ctrl-C"
        }
    }
}

#[cfg(not(unix))]
async fn wait_for_signal() -> &'static str {
    let _ = tokio::signal::ctrl_c().await;
    "Ctrl-C"
}
