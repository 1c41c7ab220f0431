//! Real signals to this process: the only test in its binary, because it
//! installs process-wide handlers and signals the whole test process.

use std::time::{Duration, Instant};

use cell_launch::{supervise, Outcome, OutputLine, PlannedNode, SupervisorOptions};
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;
use tokio::sync::mpsc::{unbounded_channel, UnboundedReceiver};

const PATIENCE: Duration = Duration::from_secs(20);

/// Waits for a line starting with `wanted`.
async fn wait_for(rx: &mut UnboundedReceiver<OutputLine>, wanted: &str) {
    tokio::time::timeout(PATIENCE, async {
        loop {
            let line = rx.recv().await.expect("output ended early");
            if line.text.starts_with(wanted) {
                break;
            }
        }
    })
    .await
    .unwrap_or_else(|_| panic!("never saw {wanted:?}"))
}

#[tokio::test]
async fn sigint_stops_the_nodes_and_a_second_signal_kills_them() {
    let (tx, mut rx) = unbounded_channel();
    let options = SupervisorOptions {
        stop_timeout: Duration::from_secs(60),
        output: Some(tx),
        ..SupervisorOptions::default()
    };
    assert!(options.handle_signals, "handles signals by default");
    let node = PlannedNode::new(
        "stubborn",
        "/bin/sh",
        &["-c", "trap '' INT; echo ready; sleep 60"],
    );
    let task = tokio::spawn(supervise(vec![node], options));
    // The handlers are installed before the first node starts.
    wait_for(&mut rx, "[stubborn] ready").await;
    let started = Instant::now();
    kill(Pid::this(), Signal::SIGINT).unwrap();
    wait_for(&mut rx, "[launch] stopping stubborn (SIGINT)").await;
    // The node ignores SIGINT; a second signal kills it without waiting
    // for the 60 s stop timeout.
    kill(Pid::this(), Signal::SIGTERM).unwrap();
    let summary = tokio::time::timeout(PATIENCE, task)
        .await
        .expect("no stop after the second signal")
        .unwrap()
        .unwrap();
    assert!(started.elapsed() < Duration::from_secs(10));
    assert_eq!(
        summary.outcome,
        Outcome::Interrupted {
            reason: "got SIGINT".into()
        }
    );
    assert_eq!(summary.exit_code(), 130);
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(summary.nodes[0].status.and_then(|s| s.signal()), Some(9));
}
