//! Arming: a bridge starts motion (runs a program, resumes, overrides) only while it is armed,
//! and arming is a local act at the machine's computer, never a network message.
//!
//! - [`Arming`] holds the armed state. Arming lasts until it is disarmed or until the machine
//!   has been idle (no run, no command, nothing moving or held) for the arming's idle time, at
//!   most the bridge's `arm_idle_timeout_s`.
//! - [`MachineAct`] says what needs arming: running a program, resume and the overrides do;
//!   hold and abort never do (a stop must always work).
//! - The arm service is a Unix-domain stream socket, not DDS and not TCP: only processes on this
//!   host can reach it, and only this user's (the socket is `0600` in a `0700` directory the
//!   user owns; [`socket_dir`]). TCP on 127.0.0.1 would admit every local user and sits one
//!   configuration slip away from the network. One request line, one answer line:
//!   `arm [SECONDS]`, `disarm`, `state`; an answer starting `error:` is a refusal.
//!   `cell machine arm|disarm|armed` speaks it ([`request`]).

use std::io;
use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{anyhow, Context};
use cell_msgs::MachineCommand;
use tokio::io::{AsyncBufReadExt, AsyncReadExt, AsyncWriteExt, BufReader};
use tokio::net::{UnixListener, UnixStream};

/// What a peer asks of a machine, as far as arming goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MachineAct {
    /// Run a program (a goal or a program on the topic).
    Run,
    /// A `MachineCommand` (`COMMAND_*`).
    Command(u8),
}

impl MachineAct {
    /// Only stops (hold, abort) may run unarmed: a stop must always work.
    pub fn needs_arming(self) -> bool {
        !matches!(
            self,
            MachineAct::Command(MachineCommand::COMMAND_HOLD | MachineCommand::COMMAND_ABORT)
        )
    }

    /// Only stops may address every machine at once (an empty `machine_id`).
    pub fn may_address_all(self) -> bool {
        !self.needs_arming()
    }

    /// For log lines: `run`, `hold`, `resume`, `abort`, `feed override`, `spindle override`.
    pub fn name(self) -> &'static str {
        match self {
            MachineAct::Run => "run",
            MachineAct::Command(MachineCommand::COMMAND_HOLD) => "hold",
            MachineAct::Command(MachineCommand::COMMAND_RESUME) => "resume",
            MachineAct::Command(MachineCommand::COMMAND_ABORT) => "abort",
            MachineAct::Command(MachineCommand::COMMAND_FEED_OVERRIDE) => "feed override",
            MachineAct::Command(MachineCommand::COMMAND_SPINDLE_OVERRIDE) => "spindle override",
            MachineAct::Command(_) => "command",
        }
    }
}

/// An arming in force.
#[derive(Debug, Clone, Copy)]
struct Armed {
    idle: Duration,
    last_activity: Instant,
}

/// The armed state of a bridge (module docs). Shared between the node and its arm service.
#[derive(Debug)]
pub struct Arming {
    max_idle: Duration,
    state: Mutex<Option<Armed>>,
}

impl Arming {
    /// Disarmed; an arming lasts at most `max_idle` without machine activity.
    pub fn new(max_idle: Duration) -> Self {
        Arming {
            max_idle,
            state: Mutex::new(None),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Option<Armed>> {
        // The state is a plain value: a panic elsewhere cannot leave it half-written.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Arms for `idle` without activity (default and cap: the bridge's maximum); the answer.
    pub fn arm(&self, idle: Option<Duration>) -> String {
        let wanted = idle.unwrap_or(self.max_idle);
        let idle = wanted.min(self.max_idle);
        *self.lock() = Some(Armed {
            idle,
            last_activity: Instant::now(),
        });
        let capped = if wanted > idle {
            format!(
                " (asked {} s; arm_idle_timeout_s caps it)",
                wanted.as_secs_f64()
            )
        } else {
            String::new()
        };
        format!(
            "armed: disarms after {} s without machine activity{capped}",
            idle.as_secs_f64()
        )
    }

    /// Disarms; the answer.
    pub fn disarm(&self) -> String {
        *self.lock() = None;
        "disarmed".into()
    }

    /// Whether armed now. An arming idle for longer than its time ends here, logged once.
    pub fn is_armed(&self) -> bool {
        let mut state = self.lock();
        match *state {
            Some(a) if a.last_activity.elapsed() <= a.idle => true,
            Some(a) => {
                tracing::warn!(
                    "disarmed: no machine activity for {} s (arm again: cell machine arm)",
                    a.idle.as_secs_f64()
                );
                *state = None;
                false
            }
            None => false,
        }
    }

    /// The machine did something (a run, a command, it is moving): an arming in force starts
    /// its idle time again.
    pub fn touch(&self) {
        if !self.is_armed() {
            return;
        }
        if let Some(a) = self.lock().as_mut() {
            a.last_activity = Instant::now();
        }
    }

    /// `armed: …` with the time left, or `disarmed`.
    pub fn state(&self) -> String {
        if !self.is_armed() {
            return "disarmed".into();
        }
        match *self.lock() {
            Some(a) => format!(
                "armed: disarms in {:.0} s without machine activity (idle time {} s)",
                a.idle
                    .saturating_sub(a.last_activity.elapsed())
                    .as_secs_f64(),
                a.idle.as_secs_f64()
            ),
            None => "disarmed".into(),
        }
    }

    /// The answer to one request line of the arm service.
    pub fn answer(&self, line: &str) -> String {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["arm"] => self.arm(None),
            ["arm", seconds] => match seconds.parse::<f64>() {
                Ok(s) if s.is_finite() && s > 0.0 => self.arm(Some(Duration::from_secs_f64(s))),
                _ => format!("error: arm {seconds:?}: expected seconds > 0"),
            },
            ["disarm"] => self.disarm(),
            ["state"] => self.state(),
            _ => {
                format!("error: unknown request {line:?}; expected arm [SECONDS], disarm or state")
            }
        }
    }
}

/// Where a bridge's arm socket lives by default: `$XDG_RUNTIME_DIR/cellsuite`, else
/// `/tmp/cellsuite-<uid>`.
pub fn socket_dir() -> PathBuf {
    match std::env::var_os("XDG_RUNTIME_DIR").filter(|d| !d.is_empty()) {
        Some(dir) => PathBuf::from(dir).join("cellsuite"),
        None => std::env::temp_dir().join(format!("cellsuite-{}", nix::unistd::geteuid())),
    }
}

/// The default arm socket of the bridge node `node` (`/cell/machine_bridge`) on `domain`:
/// `<socket_dir>/arm-d<domain>-cell.machine_bridge.sock`, so bridges on other domains or
/// names do not collide.
pub fn default_socket_path(domain: u16, node: &str) -> PathBuf {
    let name = node.trim_start_matches('/').replace('/', ".");
    socket_dir().join(format!("arm-d{domain}-{name}.sock"))
}

/// Creates `dir` (mode 0700) if missing and checks it is this user's alone: a directory
/// others can write to would let them replace the socket.
fn private_dir(dir: &Path) -> anyhow::Result<()> {
    match std::fs::DirBuilder::new()
        .recursive(true)
        .mode(0o700)
        .create(dir)
    {
        Ok(()) => {}
        Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(anyhow!("arm socket directory {}: {e}", dir.display())),
    }
    let meta = std::fs::symlink_metadata(dir)
        .with_context(|| format!("arm socket directory {}", dir.display()))?;
    let me = nix::unistd::geteuid().as_raw();
    if !meta.is_dir() || meta.uid() != me || meta.mode() & 0o077 != 0 {
        return Err(anyhow!(
            "arm socket directory {}: must be a directory of uid {me} with mode 0700 (it is uid \
             {}, mode {:o})",
            dir.display(),
            meta.uid(),
            meta.mode() & 0o7777
        ));
    }
    Ok(())
}

/// A listening arm service; dropping it stops it and removes the socket file.
#[derive(Debug)]
pub struct ArmService {
    path: PathBuf,
    task: tokio::task::JoinHandle<()>,
}

impl ArmService {
    /// The socket's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for ArmService {
    fn drop(&mut self) {
        self.task.abort();
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Serves `arming` on the Unix socket `path` (module docs). A path in [`socket_dir`] gets
/// that directory created and checked (0700, this user's); the socket file is made 0600. A
/// socket left by a bridge that died is replaced; one a live process still answers on is not.
///
/// # Errors
/// The directory is not private, another process listens on `path`, the socket cannot be
/// bound.
pub async fn serve(path: &Path, arming: Arc<Arming>) -> anyhow::Result<ArmService> {
    if let Some(dir) = path.parent().filter(|d| *d == socket_dir()) {
        private_dir(dir)?;
    }
    if std::fs::symlink_metadata(path).is_ok() {
        if UnixStream::connect(path).await.is_ok() {
            return Err(anyhow!(
                "arm socket {}: another process (a second bridge with this name on this \
                 domain?) listens on it",
                path.display()
            ));
        }
        std::fs::remove_file(path)
            .with_context(|| format!("arm socket {}: removing a stale one", path.display()))?;
    }
    let listener =
        UnixListener::bind(path).with_context(|| format!("arm socket {}", path.display()))?;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o600))
        .with_context(|| format!("arm socket {}", path.display()))?;
    let shown = path.display().to_string();
    let task = tokio::spawn(async move {
        loop {
            let stream = match listener.accept().await {
                Ok((stream, _)) => stream,
                Err(e) => {
                    tracing::warn!("arm socket {shown}: {e}");
                    tokio::time::sleep(Duration::from_millis(100)).await;
                    continue;
                }
            };
            let (arming, shown) = (arming.clone(), shown.clone());
            tokio::spawn(async move {
                if let Err(e) = answer_one(stream, &arming, &shown).await {
                    tracing::warn!("arm socket {shown}: {e}");
                }
            });
        }
    });
    Ok(ArmService {
        path: path.to_owned(),
        task,
    })
}

/// The longest request line read.
const MAX_REQUEST: u64 = 128;

/// How long a client may take to send its line.
const REQUEST_TIMEOUT: Duration = Duration::from_secs(2);

async fn answer_one(stream: UnixStream, arming: &Arming, shown: &str) -> io::Result<()> {
    let who = match stream.peer_cred() {
        Ok(c) => format!("uid {} pid {}", c.uid(), c.pid().unwrap_or(0)),
        Err(_) => "a local process".into(),
    };
    let (read, mut write) = stream.into_split();
    let mut line = String::new();
    let mut reader = BufReader::new(read.take(MAX_REQUEST));
    tokio::time::timeout(REQUEST_TIMEOUT, reader.read_line(&mut line))
        .await
        .map_err(|_| io::Error::new(io::ErrorKind::TimedOut, "no request line"))??;
    let request = line.trim();
    let answer = arming.answer(request);
    if request != "state" {
        tracing::info!("arm socket {shown}: {who}: {request:?}: {answer}");
    }
    write.write_all(format!("{answer}\n").as_bytes()).await?;
    write.shutdown().await
}

/// Sends one request line to the arm service at `path` and returns its answer line.
///
/// # Errors
/// Nothing listens there (no bridge, or another user's), or no answer within `timeout`.
pub async fn request(path: &Path, line: &str, timeout: Duration) -> anyhow::Result<String> {
    let exchange = async {
        let mut stream = UnixStream::connect(path).await?;
        stream.write_all(format!("{line}\n").as_bytes()).await?;
        let mut answer = String::new();
        BufReader::new(stream.take(4096))
            .read_line(&mut answer)
            .await?;
        Ok::<_, io::Error>(answer.trim().to_owned())
    };
    match tokio::time::timeout(timeout, exchange).await {
        Ok(Ok(answer)) if !answer.is_empty() => Ok(answer),
        Ok(Ok(_)) => Err(anyhow!("arm socket {}: no answer", path.display())),
        Ok(Err(e)) => Err(anyhow!("arm socket {}: {e}", path.display())),
        Err(_) => Err(anyhow!(
            "arm socket {}: no answer within {:.1} s",
            path.display(),
            timeout.as_secs_f64()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_stops_run_unarmed_and_address_every_machine() {
        for c in [MachineCommand::COMMAND_HOLD, MachineCommand::COMMAND_ABORT] {
            assert!(!MachineAct::Command(c).needs_arming());
            assert!(MachineAct::Command(c).may_address_all());
        }
        for c in [
            MachineCommand::COMMAND_RESUME,
            MachineCommand::COMMAND_FEED_OVERRIDE,
            MachineCommand::COMMAND_SPINDLE_OVERRIDE,
            99,
        ] {
            assert!(MachineAct::Command(c).needs_arming());
        }
        assert!(MachineAct::Run.needs_arming() && !MachineAct::Run.may_address_all());
    }

    #[test]
    fn arming_is_capped_and_expires_when_idle() {
        let arming = Arming::new(Duration::from_millis(200));
        assert!(!arming.is_armed());
        assert!(arming.answer("arm 100").contains("caps it"));
        assert!(arming.is_armed());
        std::thread::sleep(Duration::from_millis(120));
        arming.touch();
        std::thread::sleep(Duration::from_millis(120));
        assert!(arming.is_armed(), "activity restarts the idle time");
        std::thread::sleep(Duration::from_millis(250));
        assert!(!arming.is_armed());
        assert_eq!(arming.state(), "disarmed");
        assert!(arming.answer("arm 0.05").starts_with("armed"));
        assert_eq!(arming.answer("disarm"), "disarmed");
        assert!(!arming.is_armed());
        assert!(arming.answer("arm -1").starts_with("error:"));
        assert!(arming.answer("launch").starts_with("error:"));
    }

    #[test]
    fn default_paths_name_domain_and_node() {
        let p = default_socket_path(7, "/cell/machine_bridge");
        assert_eq!(p.file_name().unwrap(), "arm-d7-cell.machine_bridge.sock");
        assert_eq!(p.parent().unwrap(), socket_dir());
    }

    #[tokio::test]
    async fn the_socket_is_private_and_answers_one_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("arm.sock");
        let arming = Arc::new(Arming::new(Duration::from_secs(60)));
        let service = serve(&path, arming.clone()).await.unwrap();
        let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o600);
        let t = Duration::from_secs(2);
        assert_eq!(request(&path, "state", t).await.unwrap(), "disarmed");
        assert!(request(&path, "arm 5", t)
            .await
            .unwrap()
            .starts_with("armed"));
        assert!(arming.is_armed());
        // A second service on the same live socket is refused.
        let e = serve(&path, Arc::new(Arming::new(Duration::from_secs(1))))
            .await
            .unwrap_err();
        assert!(e.to_string().contains("another process"), "{e}");
        drop(service);
        assert!(!path.exists());
        assert!(request(&path, "state", t).await.is_err());
    }
}
