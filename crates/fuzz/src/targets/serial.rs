//! The harness the serial-controller targets share (GRBL, Marlin): a paused clock, a pipe for
//! the client to connect to, a controller that says the input line by line, and a host that
//! feeds a simulator the input line by line.

use std::sync::Mutex;
use std::time::Duration;

use cell_grbl::transport::{BoxedTransport, Connect, ConnectFuture};
use tokio::io::{AsyncReadExt, AsyncWriteExt, DuplexStream};

/// A runtime on a paused clock: every timeout and poll period passes as soon as nothing else
/// can run, so a run is deterministic and takes CPU time only.
pub(crate) fn paused_runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .expect("a current-thread runtime")
}

/// The lines of `bytes`, each with its `\n`.
pub(crate) fn lines(bytes: &[u8]) -> Vec<Vec<u8>> {
    bytes
        .split_inclusive(|&b| b == b'\n')
        .map(<[u8]>::to_vec)
        .collect()
}

/// A controller that is one in-memory pipe, handed out once.
pub(crate) struct OnePipe(pub(crate) Mutex<Option<DuplexStream>>);

impl Connect for OnePipe {
    fn connect(&self) -> ConnectFuture<'_> {
        let pipe = self.0.lock().ok().and_then(|mut p| p.take());
        Box::pin(async move {
            pipe.map(|p| Box::new(p) as BoxedTransport).ok_or_else(|| {
                std::io::Error::new(std::io::ErrorKind::ConnectionRefused, "fuzz pipe used")
            })
        })
    }

    fn describe(&self) -> String {
        "fuzz pipe".into()
    }
}

/// The controller's side: says `said` one line every 20 ms (simulated), draining what the host
/// sent meanwhile without waiting for it, then listens until the host goes.
pub(crate) async fn say_lines(mut controller: DuplexStream, said: Vec<u8>) {
    let mut sink = vec![0u8; 4096];
    for line in lines(&said) {
        if controller.write_all(&line).await.is_err() {
            return;
        }
        while let Ok(Ok(n)) = tokio::time::timeout(Duration::ZERO, controller.read(&mut sink)).await
        {
            if n == 0 {
                break;
            }
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    while let Ok(n) = controller.read(&mut sink).await {
        if n == 0 {
            break;
        }
    }
}

/// The host's side against a simulator: sends `body` one line every 5 ms (simulated) while
/// reading everything back, for 30 s of simulated time.
pub(crate) async fn feed_lines(host: DuplexStream, body: Vec<u8>) {
    let (mut rd, mut wr) = tokio::io::split(host);
    let talker = async move {
        for line in lines(&body) {
            if wr.write_all(&line).await.is_err() {
                break;
            }
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
        std::future::pending::<()>().await;
    };
    let reader = async move {
        let mut sink = vec![0u8; 4096];
        while let Ok(n) = rd.read(&mut sink).await {
            if n == 0 {
                break;
            }
        }
        std::future::pending::<()>().await;
    };
    let both = async { tokio::join!(talker, reader) };
    let _ = tokio::time::timeout(Duration::from_secs(30), both).await;
}
