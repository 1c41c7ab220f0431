//! Starting the planned nodes and watching over them.
//!
//! Every node runs in its own process group, so a terminal's Ctrl-C reaches
//! only us and we forward exactly one SIGINT to each node's whole group.
//! Children are killed when their handles are dropped, get SIGTERM if we die
//! without cleaning up (Linux `PR_SET_PDEATHSIG`, tied to the thread that
//! polls [`supervise`]), and whatever is left in a node's process group when
//! it exits (or when supervision ends) is killed with SIGKILL.

use std::collections::HashMap;
use std::io::Write;
use std::os::unix::process::ExitStatusExt;
use std::process::{ExitStatus, Stdio};
use std::time::{Duration, Instant};

use nix::sys::signal::{killpg, Signal};
use nix::unistd::Pid;
use tokio::io::{AsyncBufReadExt, AsyncRead, BufReader};
use tokio::process::{Child, Command};
use tokio::signal::unix::{signal, SignalKind};
use tokio::sync::mpsc::UnboundedSender;
use tokio::task::{Id, JoinError, JoinSet};
use tokio_util::sync::CancellationToken;

use crate::resolve::PlannedNode;
use crate::LaunchError;

/// How long to keep reading a node's output after it exited, for lines still
/// in the pipes (longer only if something it left behind keeps them open).
const DRAIN: Duration = Duration::from_millis(500);

/// After SIGKILL, how long to wait for the processes to be reaped before
/// giving up on them (they are killed again when dropped).
const REAP_AFTER_KILL: Duration = Duration::from_secs(5);

/// Which node finishing successfully ends the whole launch.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StopOthersWhen {
    /// The first node that exits with status 0.
    Any,
    /// The node with this label (see [`PlannedNode::label`]).
    Node(String),
}

/// Which of our output streams a line goes to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stream {
    /// Our stdout: the nodes' stdout.
    Stdout,
    /// Our stderr: the nodes' stderr and the supervisor's own lines.
    Stderr,
}

/// One line of output, as it is printed (without the newline): a node's
/// line prefixed with `[LABEL] `, or a supervisor line prefixed with
/// `[launch] `.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputLine {
    /// Where the line goes.
    pub stream: Stream,
    /// The line, prefix included.
    pub text: String,
}

/// How [`supervise`] behaves. `SupervisorOptions::default()` is what
/// `cell launch` wants.
#[derive(Debug, Clone)]
pub struct SupervisorOptions {
    /// A node that exits within this time after it was started, with any
    /// status, "died at start" and fails the launch. Default 2 s;
    /// `Duration::ZERO` turns the check off.
    pub grace: Duration,
    /// How long nodes get to exit after SIGINT before they are killed with
    /// SIGKILL. Default 5 s.
    pub stop_timeout: Duration,
    /// When set, the named node (or any node) exiting with status 0 stops
    /// the others with SIGINT and the launch succeeds, even within the
    /// grace period. Default: none, the launch succeeds once every node has
    /// exited with status 0.
    pub stop_others_when: Option<StopOthersWhen>,
    /// Cancel this to stop all nodes as if Ctrl-C was pressed. A fresh
    /// token by default.
    pub shutdown: CancellationToken,
    /// Also stop all nodes on SIGINT, SIGTERM or SIGHUP sent to this
    /// process (a second one while stopping kills them at once). Default
    /// true; tests turn it off and use `shutdown`.
    pub handle_signals: bool,
    /// Where output lines go: `None` (the default) prints them to our
    /// stdout/stderr, `Some` sends them down the channel instead.
    pub output: Option<UnboundedSender<OutputLine>>,
}

impl Default for SupervisorOptions {
    fn default() -> Self {
        Self {
            grace: Duration::from_secs(2),
            stop_timeout: Duration::from_secs(5),
            stop_others_when: None,
            shutdown: CancellationToken::new(),
            handle_signals: true,
            output: None,
        }
    }
}

/// How a launch ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    /// Every node exited with status 0, or the node named by
    /// [`SupervisorOptions::stop_others_when`] did and the others were
    /// stopped.
    Success,
    /// A node died at start or exited with a failure status; the others
    /// were stopped.
    Failed {
        /// The label of the node that failed.
        node: String,
        /// The one-line report, e.g. `node monitor (exec monitor) died at
        /// start with exit status 1`.
        message: String,
    },
    /// A shutdown was requested (Ctrl-C, SIGTERM, SIGHUP or
    /// [`SupervisorOptions::shutdown`]); all nodes were stopped.
    Interrupted {
        /// What asked for the shutdown.
        reason: String,
    },
}

/// What happened to one node.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeReport {
    /// The node's label.
    pub label: String,
    /// Its process id.
    pub pid: Option<u32>,
    /// How it exited; `None` if waiting for it failed.
    pub status: Option<ExitStatus>,
    /// From start to exit.
    pub runtime: Duration,
    /// True if we told it to stop (SIGINT, then maybe SIGKILL).
    pub stopped: bool,
}

/// The result of [`supervise`]: how it ended and what each node did, in the
/// order they were given.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Summary {
    /// How the launch ended.
    pub outcome: Outcome,
    /// One report per started node.
    pub nodes: Vec<NodeReport>,
}

impl Summary {
    /// True for [`Outcome::Success`].
    pub fn is_success(&self) -> bool {
        self.outcome == Outcome::Success
    }

    /// The exit code the `cell` command should use: 0 for success, 1 for a
    /// failed node, 130 (as for a shell's Ctrl-C) when interrupted, even if
    /// every node then stopped cleanly.
    pub fn exit_code(&self) -> i32 {
        match self.outcome {
            Outcome::Success => 0,
            Outcome::Failed { .. } => 1,
            Outcome::Interrupted { .. } => 130,
        }
    }
}

/// Starts `nodes` in order and supervises them until the launch ends (see
/// [`SupervisorOptions`] and [`Outcome`]). Each node's stdout and stderr
/// lines are forwarded prefixed with `[LABEL] `; the supervisor reports
/// starts, exits and failures as `[launch] ...` lines on stderr.
///
/// Returns `Err` only if the options are wrong or a process cannot be
/// started (the nodes already started are stopped first). When it returns,
/// every process it started has been reaped; dropping the future early
/// kills them.
pub async fn supervise(
    nodes: Vec<PlannedNode>,
    options: SupervisorOptions,
) -> Result<Summary, LaunchError> {
    if let Some(StopOthersWhen::Node(name)) = &options.stop_others_when {
        if !nodes.iter().any(|n| &n.label == name) {
            let labels: Vec<&str> = nodes.iter().map(|n| n.label.as_str()).collect();
            return Err(LaunchError::Options(format!(
                "stop_others_when names node {name:?}, but the launched nodes are: {}",
                labels.join(", ")
            )));
        }
    }
    let mut signals = if options.handle_signals {
        Some(Signals::new()?)
    } else {
        None
    };
    let sink = Sink(options.output.clone());
    let mut sup = Supervisor {
        nodes,
        state: Vec::new(),
        tasks: JoinSet::new(),
        task_node: HashMap::new(),
        groups: Groups::default(),
        sink,
    };

    for i in 0..sup.nodes.len() {
        if let Err(source) = sup.start(i) {
            let node = &sup.nodes[i];
            let (label, program) = (node.label.clone(), node.program.clone());
            sup.sink.status(format!(
                "cannot start node {label} ({}): {source}",
                node.command_line()
            ));
            sup.stop_all(options.stop_timeout, signals.as_mut()).await;
            return Err(LaunchError::Spawn {
                node: label,
                program,
                source,
            });
        }
    }

    let outcome = loop {
        if sup.tasks.is_empty() {
            break Outcome::Success;
        }
        tokio::select! {
            Some(joined) = sup.tasks.join_next_with_id() => {
                if let Some(outcome) = sup.record(joined).and_then(|i| sup.judge(i, &options)) {
                    break outcome;
                }
            }
            () = options.shutdown.cancelled() => {
                sup.sink.status("shutdown requested".to_string());
                break Outcome::Interrupted { reason: "shutdown requested".to_string() };
            }
            name = next_signal(signals.as_mut()) => {
                sup.sink.status(format!("got {name}"));
                break Outcome::Interrupted { reason: format!("got {name}") };
            }
        }
    };
    sup.stop_all(options.stop_timeout, signals.as_mut()).await;
    let nodes = sup
        .state
        .iter()
        .map(|s| NodeReport {
            label: s.label.clone(),
            pid: s.pid,
            status: s.status,
            runtime: s.ended.unwrap_or_else(Instant::now) - s.started,
            stopped: s.stopped,
        })
        .collect();
    Ok(Summary { outcome, nodes })
}

/// Per started node.
struct NodeState {
    label: String,
    pid: Option<u32>,
    started: Instant,
    ended: Option<Instant>,
    status: Option<ExitStatus>,
    stopped: bool,
}

/// What a node's task returns: node index, wait result, when it exited.
type TaskResult = (usize, std::io::Result<ExitStatus>, Instant);

struct Supervisor {
    nodes: Vec<PlannedNode>,
    state: Vec<NodeState>,
    tasks: JoinSet<TaskResult>,
    task_node: HashMap<Id, usize>,
    groups: Groups,
    sink: Sink,
}

impl Supervisor {
    /// Spawns node `i` and the task that forwards its output and waits.
    fn start(&mut self, i: usize) -> std::io::Result<()> {
        let node = &self.nodes[i];
        let mut cmd = Command::new(&node.program);
        cmd.args(&node.args)
            .envs(node.env.iter().map(|(k, v)| (k, v)))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .kill_on_drop(true)
            .process_group(0);
        // SAFETY: between fork and exec we only make the sigaction and prctl system calls,
        // which are async-signal-safe and touch no memory of ours.
        unsafe {
            cmd.pre_exec(|| {
                // A launcher started in the background of a non-interactive shell (`cell demo &`
                // in a script, nohup) inherits SIGINT ignored, and so would every node: then
                // our stop signal is lost and nodes are killed without finishing (a bag left
                // unfinished). Nodes always start with the default action.
                nix::sys::signal::signal(Signal::SIGINT, nix::sys::signal::SigHandler::SigDfl)
                    .map_err(std::io::Error::from)?;
                #[cfg(target_os = "linux")]
                nix::sys::prctl::set_pdeathsig(Signal::SIGTERM).map_err(std::io::Error::from)?;
                Ok(())
            });
        }
        let mut child = cmd.spawn()?;
        let started = Instant::now();
        let pid = child.id();
        if let Some(pid) = pid {
            self.groups.0.push(pid);
        }
        tracing::debug!(node = %node.label, ?pid, command = %node.command_line(), "started");
        self.sink.status(format!(
            "started {} (pid {}): {}",
            node.label,
            pid.map_or_else(|| "?".to_string(), |p| p.to_string()),
            node.command_line()
        ));
        let stdout = child.stdout.take();
        let stderr = child.stderr.take();
        let handle = self.tasks.spawn(run_node(
            i,
            child,
            stdout,
            stderr,
            node.label.clone(),
            self.sink.clone(),
        ));
        self.task_node.insert(handle.id(), i);
        self.state.push(NodeState {
            label: node.label.clone(),
            pid,
            started,
            ended: None,
            status: None,
            stopped: false,
        });
        Ok(())
    }

    /// Stores a node's exit; returns its index.
    fn record(&mut self, joined: Result<(Id, TaskResult), JoinError>) -> Option<usize> {
        let (i, status, ended) = match joined {
            Ok((_, (i, status, ended))) => (i, status.ok(), ended),
            // The task was aborted or panicked: its child was killed on drop.
            Err(e) => (*self.task_node.get(&e.id())?, None, Instant::now()),
        };
        let state = &mut self.state[i];
        state.status = status;
        state.ended = Some(ended);
        if let Some(pid) = state.pid {
            // The node's task kills what is left in its group when it exits;
            // after a JoinError do it here.
            if status.is_none() {
                signal_group(pid, Signal::SIGKILL);
            }
            self.groups.0.retain(|&p| p != pid);
        }
        Some(i)
    }

    /// Decides what node `i` exiting means: `Some` ends the launch.
    fn judge(&self, i: usize, options: &SupervisorOptions) -> Option<Outcome> {
        let node = &self.nodes[i];
        let state = &self.state[i];
        let runtime = state.ended.unwrap_or_else(Instant::now) - state.started;
        let at_start = runtime < options.grace;
        let ok = state.status.is_some_and(|s| s.success());
        let ends_launch = match &options.stop_others_when {
            Some(StopOthersWhen::Any) => true,
            Some(StopOthersWhen::Node(name)) => name == &node.label,
            None => false,
        };
        if ok && ends_launch {
            self.sink.status(format!(
                "node {} finished after {runtime:.1?}; stopping the others",
                node.label
            ));
            return Some(Outcome::Success);
        }
        if ok && !at_start {
            self.sink
                .status(format!("node {} finished after {runtime:.1?}", node.label));
            return None;
        }
        let mut message = format!(
            "node {} (exec {}) {}",
            node.label,
            node.exec,
            how_it_ended(state.status, at_start)
        );
        if ok {
            message.push_str(&format!(
                " (within the {:?} start-up grace period)",
                options.grace
            ));
        }
        self.sink.status(message.clone());
        Some(Outcome::Failed {
            node: node.label.clone(),
            message,
        })
    }

    /// Sends SIGINT to every running node, waits up to `timeout`, then
    /// SIGKILLs the rest and reaps them. A signal to us while waiting
    /// kills at once.
    async fn stop_all(&mut self, timeout: Duration, mut signals: Option<&mut Signals>) {
        let running: Vec<usize> = (0..self.state.len())
            .filter(|&i| self.state[i].ended.is_none())
            .collect();
        if !running.is_empty() {
            let labels: Vec<&str> = running
                .iter()
                .map(|&i| self.state[i].label.as_str())
                .collect();
            self.sink
                .status(format!("stopping {} (SIGINT)", labels.join(", ")));
            self.signal_running(Signal::SIGINT);
        }
        let deadline = tokio::time::sleep(timeout);
        tokio::pin!(deadline);
        let mut killed = false;
        while !self.tasks.is_empty() {
            tokio::select! {
                Some(joined) = self.tasks.join_next_with_id() => {
                    if let Some(i) = self.record(joined) {
                        let state = &self.state[i];
                        self.sink.status(format!(
                            "node {} stopped: {}",
                            state.label,
                            how_it_ended(state.status, false)
                        ));
                    }
                }
                () = &mut deadline => {
                    if killed {
                        self.sink.status("giving up waiting for killed nodes".to_string());
                        self.tasks.shutdown().await;
                    } else {
                        killed = true;
                        self.sink.status(format!(
                            "nodes still running {timeout:?} after SIGINT; killing them (SIGKILL)"
                        ));
                        self.signal_running(Signal::SIGKILL);
                        deadline.as_mut().reset(tokio::time::Instant::now() + REAP_AFTER_KILL);
                    }
                }
                name = next_signal(signals.as_deref_mut()), if !killed => {
                    killed = true;
                    self.sink.status(format!("got {name} while stopping; killing the nodes (SIGKILL)"));
                    self.signal_running(Signal::SIGKILL);
                    deadline.as_mut().reset(tokio::time::Instant::now() + REAP_AFTER_KILL);
                }
            }
        }
        // Leftovers in the groups of nodes that did not exit by themselves.
        self.groups.kill_all();
    }

    /// Sends `signal` to the process group of every node still running.
    fn signal_running(&mut self, signal: Signal) {
        for state in self.state.iter_mut().filter(|s| s.ended.is_none()) {
            state.stopped = true;
            if let Some(pid) = state.pid {
                signal_group(pid, signal);
            }
        }
    }
}

/// Waits for a node while forwarding its output; afterwards kills whatever
/// the node left in its process group and drains the pipes briefly.
async fn run_node(
    i: usize,
    mut child: Child,
    stdout: Option<impl AsyncRead + Unpin>,
    stderr: Option<impl AsyncRead + Unpin>,
    label: String,
    sink: Sink,
) -> TaskResult {
    let pumps = async {
        tokio::join!(
            forward(stdout, Stream::Stdout, &label, &sink),
            forward(stderr, Stream::Stderr, &label, &sink)
        )
    };
    tokio::pin!(pumps);
    let pid = child.id();
    let mut drained = false;
    let status = loop {
        tokio::select! {
            status = child.wait() => break status,
            _ = &mut pumps, if !drained => drained = true,
        }
    };
    let ended = Instant::now();
    if let Some(pid) = pid {
        signal_group(pid, Signal::SIGKILL);
    }
    if !drained {
        let _ = tokio::time::timeout(DRAIN, &mut pumps).await;
    }
    (i, status, ended)
}

/// Forwards lines from `pipe` to `sink` with the `[LABEL] ` prefix.
async fn forward(pipe: Option<impl AsyncRead + Unpin>, stream: Stream, label: &str, sink: &Sink) {
    let Some(pipe) = pipe else { return };
    let mut reader = BufReader::new(pipe);
    let mut buf = Vec::new();
    loop {
        buf.clear();
        match reader.read_until(b'\n', &mut buf).await {
            Ok(0) | Err(_) => break,
            Ok(_) => {
                while buf.last().is_some_and(|&b| b == b'\n' || b == b'\r') {
                    buf.pop();
                }
                sink.line(
                    stream,
                    format!("[{label}] {}", String::from_utf8_lossy(&buf)),
                );
            }
        }
    }
}

fn signal_group(pid: u32, signal: Signal) {
    if let Ok(pid) = i32::try_from(pid) {
        // ESRCH (group already empty) is fine.
        let _ = killpg(Pid::from_raw(pid), signal);
    }
}

/// "died at start with exit status 1", "exited with status 1", ...
fn how_it_ended(status: Option<ExitStatus>, at_start: bool) -> String {
    let Some(status) = status else {
        return "ended, but its exit status could not be read".to_string();
    };
    match (status.code(), status.signal(), at_start) {
        (Some(code), _, true) => format!("died at start with exit status {code}"),
        (Some(code), _, false) => format!("exited with status {code}"),
        (None, Some(sig), at_start) => {
            let name = Signal::try_from(sig).map_or("unknown", |s| s.as_str());
            let what = if at_start {
                "died at start, killed by"
            } else {
                "was killed by"
            };
            format!("{what} signal {sig} ({name})")
        }
        (None, None, _) => format!("ended with {status}"),
    }
}

/// The process groups (= leader pids) of nodes that have not been seen to
/// exit; all are killed with SIGKILL when this is dropped, so nothing
/// outlives a dropped or failed supervision.
#[derive(Default)]
struct Groups(Vec<u32>);

impl Groups {
    fn kill_all(&mut self) {
        for pid in self.0.drain(..) {
            signal_group(pid, Signal::SIGKILL);
        }
    }
}

impl Drop for Groups {
    fn drop(&mut self) {
        self.kill_all();
    }
}

/// Where lines go: our stdout/stderr, or a channel.
#[derive(Clone)]
struct Sink(Option<UnboundedSender<OutputLine>>);

impl Sink {
    fn line(&self, stream: Stream, text: String) {
        match &self.0 {
            Some(tx) => {
                let _ = tx.send(OutputLine { stream, text });
            }
            None => {
                // A closed stdout must not stop supervision.
                let _ = match stream {
                    Stream::Stdout => writeln!(std::io::stdout().lock(), "{text}"),
                    Stream::Stderr => writeln!(std::io::stderr().lock(), "{text}"),
                };
            }
        }
    }

    fn status(&self, text: String) {
        self.line(Stream::Stderr, format!("[launch] {text}"));
    }
}

/// The signals that stop a launch.
struct Signals {
    int: tokio::signal::unix::Signal,
    term: tokio::signal::unix::Signal,
    hup: tokio::signal::unix::Signal,
}

impl Signals {
    fn new() -> Result<Self, LaunchError> {
        let install = |kind: SignalKind, name: &'static str| {
            signal(kind).map_err(|source| LaunchError::Signal {
                signal: name,
                source,
            })
        };
        Ok(Self {
            int: install(SignalKind::interrupt(), "SIGINT")?,
            term: install(SignalKind::terminate(), "SIGTERM")?,
            hup: install(SignalKind::hangup(), "SIGHUP")?,
        })
    }
}

/// The name of the next stop signal; never resolves without handlers.
async fn next_signal(signals: Option<&mut Signals>) -> &'static str {
    let Some(s) = signals else {
        return std::future::pending().await;
    };
    tokio::select! {
        Some(()) = s.int.recv() => "SIGINT",
        Some(()) = s.term.recv() => "SIGTERM",
        Some(()) = s.hup.recv() => "SIGHUP",
        else => std::future::pending().await,
    }
}
