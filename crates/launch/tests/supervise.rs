//! Supervising real processes (`sh`, `sleep`, `true`, `false`).
//!
//! Timing: only generous upper bounds are asserted; the short grace periods
//! used here are far from the processes' own run times.

use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::time::{Duration, Instant};

use cell_launch::{
    default_resolver, supervise, LaunchError, LaunchFile, Outcome, OutputLine, PlannedNode,
    StopOthersWhen, Stream, Summary, SupervisorOptions,
};
use tokio::sync::mpsc::{unbounded_channel, UnboundedReceiver};

/// Far longer than anything here should take.
const PATIENCE: Duration = Duration::from_secs(20);

fn sh(label: &str, script: &str) -> PlannedNode {
    PlannedNode::new(label, "/bin/sh", &["-c", script])
}

/// Options that send output to a channel and ignore real signals.
fn options() -> (SupervisorOptions, UnboundedReceiver<OutputLine>) {
    let (tx, rx) = unbounded_channel();
    let options = SupervisorOptions {
        handle_signals: false,
        output: Some(tx),
        ..SupervisorOptions::default()
    };
    (options, rx)
}

fn lines(rx: &mut UnboundedReceiver<OutputLine>) -> Vec<OutputLine> {
    let mut out = Vec::new();
    while let Ok(line) = rx.try_recv() {
        out.push(line);
    }
    out
}

fn texts(lines: &[OutputLine]) -> String {
    lines
        .iter()
        .map(|l| format!("{:?} {}\n", l.stream, l.text))
        .collect()
}

async fn run(nodes: Vec<PlannedNode>, options: SupervisorOptions) -> Summary {
    tokio::time::timeout(PATIENCE, supervise(nodes, options))
        .await
        .expect("supervise took far too long")
        .expect("supervise failed to start")
}

fn report<'a>(summary: &'a Summary, label: &str) -> &'a cell_launch::NodeReport {
    summary
        .nodes
        .iter()
        .find(|n| n.label == label)
        .unwrap_or_else(|| panic!("no report for {label}: {summary:?}"))
}

/// True while a process (or, for a negative pid, a process group) with
/// this id exists and is not a zombie.
fn alive(pid: i32) -> bool {
    if nix::sys::signal::kill(nix::unistd::Pid::from_raw(pid), None).is_err() {
        return false;
    }
    // A killed orphan stays a zombie until init reaps it.
    pid < 0
        || std::fs::read_to_string(format!("/proc/{pid}/stat"))
            .ok()
            .and_then(|stat| {
                stat.rsplit_once(") ")
                    .map(|(_, rest)| !rest.starts_with('Z'))
            })
            .unwrap_or(false)
}

/// Waits (generously) for a process or group to be gone; true if it is.
async fn gone(pid: i32) -> bool {
    let deadline = Instant::now() + PATIENCE;
    while alive(pid) {
        if Instant::now() > deadline {
            return false;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    true
}

#[tokio::test]
async fn all_nodes_succeeding_is_success() {
    let (mut opts, mut rx) = options();
    opts.grace = Duration::from_millis(100);
    let summary = run(vec![sh("a", "sleep 1"), sh("b", "sleep 1; exit 0")], opts).await;
    let out = texts(&lines(&mut rx));
    assert_eq!(summary.outcome, Outcome::Success, "{out}");
    assert!(summary.is_success());
    assert_eq!(summary.exit_code(), 0);
    assert_eq!(summary.nodes.len(), 2);
    for node in &summary.nodes {
        assert!(node.status.is_some_and(|s| s.success()), "{node:?}");
        assert!(!node.stopped);
        assert!(node.runtime >= Duration::from_millis(900), "{node:?}");
        assert!(node.pid.is_some());
    }
    assert!(out.contains("[launch] node a finished after"), "{out}");
}

#[tokio::test]
async fn grace_zero_accepts_instant_exits_and_no_nodes_is_success() {
    let (mut opts, _rx) = options();
    opts.grace = Duration::ZERO;
    let nodes = vec![PlannedNode::new("t", "true", &[])];
    assert_eq!(run(nodes, opts).await.outcome, Outcome::Success);
    let (opts, _rx) = options();
    let summary = run(vec![], opts).await;
    assert_eq!(summary.outcome, Outcome::Success);
    assert!(summary.nodes.is_empty());
}

#[tokio::test]
async fn a_node_dying_at_start_stops_the_others() {
    let (mut opts, mut rx) = options();
    opts.grace = Duration::from_secs(10);
    let started = Instant::now();
    let summary = run(
        vec![
            PlannedNode::new("sleeper", "sleep", &["30"]),
            sh("bad", "echo about to fail >&2; exit 1"),
            PlannedNode::new("other", "sleep", &["30"]),
        ],
        opts,
    )
    .await;
    assert!(started.elapsed() < Duration::from_secs(10));
    let out = lines(&mut rx);
    let text = texts(&out);
    let Outcome::Failed { node, message } = &summary.outcome else {
        panic!("expected a failure: {summary:?}\n{text}");
    };
    assert_eq!(node, "bad");
    assert_eq!(
        message,
        "node bad (exec /bin/sh) died at start with exit status 1"
    );
    assert_eq!(summary.exit_code(), 1);
    // The message is printed once as a supervisor line, after the node's
    // own last words.
    let said = out
        .iter()
        .position(|l| l.text == "[bad] about to fail")
        .expect(&text);
    let died = out
        .iter()
        .position(|l| l.text == format!("[launch] {message}"))
        .expect(&text);
    assert!(said < died, "{text}");
    assert_eq!(out[died].stream, Stream::Stderr);
    for label in ["sleeper", "other"] {
        let r = report(&summary, label);
        assert!(r.stopped, "{r:?}");
        assert_eq!(r.status.and_then(|s| s.signal()), Some(2), "{r:?}");
        assert!(gone(r.pid.unwrap() as i32).await);
    }
    assert_eq!(
        report(&summary, "bad").status.and_then(|s| s.code()),
        Some(1)
    );
}

#[tokio::test]
async fn false_at_start_is_reported_with_its_exec() {
    let (mut opts, _rx) = options();
    opts.grace = Duration::from_secs(10);
    let nodes = vec![
        PlannedNode::new("f", "false", &[]),
        PlannedNode::new("s", "sleep", &["30"]),
    ];
    let started = Instant::now();
    let summary = run(nodes, opts).await;
    assert!(started.elapsed() < Duration::from_secs(10));
    assert_eq!(
        summary.outcome,
        Outcome::Failed {
            node: "f".into(),
            message: "node f (exec false) died at start with exit status 1".into()
        }
    );
    assert!(report(&summary, "s").stopped);
}

#[tokio::test]
async fn exiting_zero_during_the_grace_period_is_dying_at_start() {
    let (mut opts, _rx) = options();
    opts.grace = Duration::from_secs(10);
    let summary = run(vec![PlannedNode::new("t", "true", &[])], opts).await;
    match &summary.outcome {
        Outcome::Failed { message, .. } => assert_eq!(
            message,
            "node t (exec true) died at start with exit status 0 (within the 10s start-up grace period)"
        ),
        other => panic!("{other:?}"),
    }
}

#[tokio::test]
async fn failing_after_the_grace_period_stops_the_others() {
    let (mut opts, _rx) = options();
    opts.grace = Duration::from_millis(100);
    let summary = run(
        vec![
            sh("late", "sleep 1; exit 3"),
            PlannedNode::new("s", "sleep", &["30"]),
        ],
        opts,
    )
    .await;
    assert_eq!(
        summary.outcome,
        Outcome::Failed {
            node: "late".into(),
            message: "node late (exec /bin/sh) exited with status 3".into()
        }
    );
    assert!(report(&summary, "s").stopped);
}

#[tokio::test]
async fn shutdown_forwards_sigint_to_every_node() {
    let (opts, mut rx) = options();
    let shutdown = opts.shutdown.clone();
    let script = r#"trap "echo got-int; exit 0" INT; sleep 30 & echo "ready $!"; wait"#;
    let task = tokio::spawn(supervise(
        vec![
            sh("trapper", script),
            PlannedNode::new("s", "sleep", &["30"]),
        ],
        opts,
    ));
    let mut seen = Vec::new();
    let background: i32 = tokio::time::timeout(PATIENCE, async {
        loop {
            let line = rx.recv().await.expect("output ended early");
            seen.push(line.clone());
            if let Some(pid) = line.text.strip_prefix("[trapper] ready ") {
                break pid.parse().unwrap();
            }
        }
    })
    .await
    .expect("the node never got ready");
    shutdown.cancel();
    let started = Instant::now();
    let summary = tokio::time::timeout(PATIENCE, task)
        .await
        .expect("no stop after shutdown")
        .unwrap()
        .unwrap();
    assert!(started.elapsed() < Duration::from_secs(10));
    seen.extend(lines(&mut rx));
    let text = texts(&seen);
    assert_eq!(
        summary.outcome,
        Outcome::Interrupted {
            reason: "shutdown requested".into()
        }
    );
    assert_eq!(summary.exit_code(), 130);
    assert!(
        seen.iter()
            .any(|l| l.stream == Stream::Stdout && l.text == "[trapper] got-int"),
        "{text}"
    );
    let trapper = report(&summary, "trapper");
    assert!(trapper.stopped);
    assert_eq!(trapper.status.and_then(|s| s.code()), Some(0), "{text}");
    assert_eq!(
        report(&summary, "s").status.and_then(|s| s.signal()),
        Some(2)
    );
    // The shell's background `sleep` ignores SIGINT; it was killed anyway.
    assert!(
        gone(background).await,
        "background sleep {background} survived"
    );
}

#[tokio::test]
async fn nodes_ignoring_sigint_are_killed_after_the_timeout() {
    let (mut opts, mut rx) = options();
    opts.stop_timeout = Duration::from_millis(300);
    let shutdown = opts.shutdown.clone();
    let task = tokio::spawn(supervise(
        vec![sh("stubborn", "trap '' INT; echo ready; sleep 30")],
        opts,
    ));
    tokio::time::timeout(PATIENCE, async {
        while rx.recv().await.expect("output ended early").text != "[stubborn] ready" {}
    })
    .await
    .expect("the node never got ready");
    shutdown.cancel();
    let started = Instant::now();
    let summary = tokio::time::timeout(PATIENCE, task)
        .await
        .expect("no stop after shutdown")
        .unwrap()
        .unwrap();
    assert!(started.elapsed() < Duration::from_secs(10));
    let r = report(&summary, "stubborn");
    assert_eq!(r.status.and_then(|s| s.signal()), Some(9), "{r:?}");
    let text = texts(&lines(&mut rx));
    assert!(text.contains("killing them (SIGKILL)"), "{text}");
    assert!(
        text.contains("node stubborn stopped: was killed by signal 9 (SIGKILL)"),
        "{text}"
    );
}

#[tokio::test]
async fn a_designated_node_finishing_ends_the_launch() {
    let (mut opts, _rx) = options();
    opts.stop_others_when = Some(StopOthersWhen::Node("driver".into()));
    let started = Instant::now();
    let summary = run(
        vec![
            PlannedNode::new("s", "sleep", &["30"]),
            // Within the grace period: fine for the designated node.
            PlannedNode::new("driver", "true", &[]),
        ],
        opts,
    )
    .await;
    assert!(started.elapsed() < Duration::from_secs(10));
    assert_eq!(summary.outcome, Outcome::Success);
    assert_eq!(summary.exit_code(), 0);
    assert!(report(&summary, "s").stopped);
    assert!(!report(&summary, "driver").stopped);

    // The designated node failing is still a failure.
    let (mut opts, _rx) = options();
    opts.stop_others_when = Some(StopOthersWhen::Any);
    let summary = run(
        vec![
            PlannedNode::new("s", "sleep", &["30"]),
            PlannedNode::new("driver", "false", &[]),
        ],
        opts,
    )
    .await;
    assert!(matches!(summary.outcome, Outcome::Failed { ref node, .. } if node == "driver"));

    let (mut opts, _rx) = options();
    opts.stop_others_when = Some(StopOthersWhen::Node("nobody".into()));
    let e = supervise(vec![PlannedNode::new("s", "true", &[])], opts)
        .await
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "launch options: stop_others_when names node \"nobody\", but the launched nodes are: s"
    );
}

#[tokio::test]
async fn output_lines_are_prefixed_and_env_is_passed() {
    let (mut opts, mut rx) = options();
    opts.grace = Duration::ZERO;
    let mut node = sh(
        "greeter",
        "echo \"hello $GREETING\"; printf 'no newline'; echo oops >&2",
    );
    node.env.push(("GREETING".into(), "world".into()));
    let summary = run(vec![node], opts).await;
    assert_eq!(summary.outcome, Outcome::Success);
    let out = lines(&mut rx);
    let text = texts(&out);
    let node_lines: Vec<&OutputLine> = out
        .iter()
        .filter(|l| !l.text.starts_with("[launch]"))
        .collect();
    let mut stdout: Vec<&str> = node_lines
        .iter()
        .filter(|l| l.stream == Stream::Stdout)
        .map(|l| l.text.as_str())
        .collect();
    stdout.sort();
    assert_eq!(
        stdout,
        ["[greeter] hello world", "[greeter] no newline"],
        "{text}"
    );
    let stderr: Vec<&str> = node_lines
        .iter()
        .filter(|l| l.stream == Stream::Stderr)
        .map(|l| l.text.as_str())
        .collect();
    assert_eq!(stderr, ["[greeter] oops"], "{text}");
    assert!(text.contains("[launch] started greeter (pid "), "{text}");
}

#[tokio::test]
async fn a_node_that_cannot_start_stops_those_already_started() {
    let (opts, mut rx) = options();
    let dir = tempfile::tempdir().unwrap();
    let not_executable = dir.path().join("plain");
    std::fs::write(&not_executable, "").unwrap();
    let started = Instant::now();
    let result = tokio::time::timeout(
        PATIENCE,
        supervise(
            vec![
                PlannedNode::new("s", "sleep", &["30"]),
                PlannedNode::new("broken", &not_executable, &[]),
                PlannedNode::new("never", "sleep", &["30"]),
            ],
            opts,
        ),
    )
    .await
    .unwrap();
    assert!(started.elapsed() < Duration::from_secs(10));
    let e = result.unwrap_err();
    assert!(
        matches!(e, LaunchError::Spawn { ref node, .. } if node == "broken"),
        "{e}"
    );
    assert!(
        e.to_string().starts_with("node broken: cannot start"),
        "{e}"
    );
    let out = lines(&mut rx);
    let text = texts(&out);
    let pid: i32 = out
        .iter()
        .find_map(|l| l.text.strip_prefix("[launch] started s (pid "))
        .and_then(|rest| rest.split(')').next())
        .and_then(|pid| pid.parse().ok())
        .expect(&text);
    assert!(gone(pid).await, "{text}");
    assert!(!text.contains("started never"), "{text}");
    assert!(text.contains("node s stopped"), "{text}");
}

#[tokio::test]
async fn dropping_the_supervisor_kills_the_nodes() {
    let (opts, mut rx) = options();
    let task = tokio::spawn(supervise(
        vec![sh("n", "echo \"ready $$\"; sleep 30 & wait")],
        opts,
    ));
    let pid: i32 = tokio::time::timeout(PATIENCE, async {
        loop {
            let line = rx.recv().await.expect("output ended early");
            if let Some(pid) = line.text.strip_prefix("[n] ready ") {
                break pid.parse().unwrap();
            }
        }
    })
    .await
    .unwrap();
    task.abort();
    let _ = task.await;
    // The shell is killed on drop (then reaped by tokio in the
    // background); its background sleep goes with its process group.
    assert!(gone(-pid).await, "process group {pid} survived");
}

#[tokio::test]
async fn a_launch_file_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("e2e.launch.yaml");
    std::fs::write(
        &path,
        r#"
launch:
- arg: {name: word, default: "hi"}
- node:
    pkg: test
    exec: sh
    name: talker
    args: "-c 'echo $(var word) $ROLE; sleep 0.5' sh"
    env: [{name: ROLE, value: talker}]
"#,
    )
    .unwrap();
    let file = LaunchFile::load(&path, &[("word".into(), "hello".into())]).unwrap();
    let plan = file.plan(default_resolver).unwrap();
    assert!(Path::new(&plan[0].program).is_absolute());
    let (mut opts, mut rx) = options();
    opts.grace = Duration::from_millis(100);
    let summary = run(plan, opts).await;
    let text = texts(&lines(&mut rx));
    assert_eq!(summary.outcome, Outcome::Success, "{text}");
    assert!(text.contains("Stdout [talker] hello talker\n"), "{text}");
}
