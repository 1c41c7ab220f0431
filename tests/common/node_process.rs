//! A node started as its own process (`cell node …`) whose stderr is collected line by line
//! (and echoed, tagged), killed when dropped so a failing test leaves no node behind.

use std::{
    io::{BufRead, BufReader},
    process::{Child, Command, Stdio},
    sync::{Arc, Mutex},
    time::{Duration, Instant},
};

use super::DELIVERY_TIMEOUT;

/// A running node process and the lines it has written to stderr so far.
pub struct NodeProcess {
    child: Child,
    log: Arc<Mutex<Vec<String>>>,
}

impl NodeProcess {
    /// Spawns `command` (stdout discarded, stderr collected); `tag` prefixes the echoed lines.
    pub fn spawn(tag: &str, mut command: Command) -> NodeProcess {
        let mut child = command
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("start {tag}: {e}"));
        let log = Arc::new(Mutex::new(Vec::new()));
        let stderr = child.stderr.take().unwrap();
        let sink = log.clone();
        let tag = tag.to_owned();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                eprintln!("[{tag}] {line}");
                sink.lock().unwrap().push(line);
            }
        });
        NodeProcess { child, log }
    }

    /// The stderr lines so far.
    pub fn lines(&self) -> Vec<String> {
        self.log.lock().unwrap().clone()
    }

    /// The stderr so far, one text.
    pub fn log(&self) -> String {
        self.lines().join("\n")
    }

    /// Waits (up to [`DELIVERY_TIMEOUT`]) until a line contains `text`, and returns it.
    pub async fn logged(&self, text: &str) -> String {
        let deadline = Instant::now() + DELIVERY_TIMEOUT;
        loop {
            if let Some(line) = self.lines().into_iter().find(|l| l.contains(text)) {
                return line;
            }
            assert!(
                Instant::now() < deadline,
                "never logged {text:?}:\n{}",
                self.log()
            );
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }

    /// Whether the process has not exited.
    pub fn is_running(&mut self) -> bool {
        self.child.try_wait().unwrap().is_none()
    }

    /// The process id.
    pub fn id(&self) -> u32 {
        self.child.id()
    }
}

impl Drop for NodeProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
