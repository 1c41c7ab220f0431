//! A launcher that inherited SIGINT ignored (started with `&` from a script, or under nohup)
//! still stops its nodes with SIGINT. Its own binary: ignoring SIGINT is process-wide.

use std::os::unix::process::ExitStatusExt;
use std::time::Duration;

use cell_launch::{supervise, Outcome, PlannedNode, SupervisorOptions};
use nix::sys::signal::{signal, SigHandler, Signal};

#[tokio::test]
async fn nodes_get_the_default_sigint_action_even_if_the_launcher_ignores_it() {
    // SAFETY: installs SIG_IGN, no handler code runs; nothing else in this binary uses SIGINT.
    unsafe { signal(Signal::SIGINT, SigHandler::SigIgn) }.unwrap();
    let options = SupervisorOptions {
        handle_signals: false,
        ..SupervisorOptions::default()
    };
    let nodes = vec![
        PlannedNode::new("sleeper", "sleep", &["30"]),
        // A shell script can only trap a signal it did not inherit ignored.
        PlannedNode::new(
            "trapper",
            "/bin/sh",
            &["-c", r#"trap "exit 7" INT; sleep 30 & wait"#],
        ),
        PlannedNode::new("bad", "/bin/sh", &["-c", "sleep 0.5; exit 1"]),
    ];
    let summary = tokio::time::timeout(Duration::from_secs(20), supervise(nodes, options))
        .await
        .expect("supervise took far too long")
        .expect("supervise failed to start");
    assert!(
        matches!(summary.outcome, Outcome::Failed { .. }),
        "{summary:?}"
    );
    let status = |label: &str| {
        summary
            .nodes
            .iter()
            .find(|n| n.label == label)
            .and_then(|n| n.status)
            .unwrap_or_else(|| panic!("{label}: {summary:?}"))
    };
    assert_eq!(status("sleeper").signal(), Some(2), "{summary:?}");
    assert_eq!(status("trapper").code(), Some(7), "{summary:?}");
}
