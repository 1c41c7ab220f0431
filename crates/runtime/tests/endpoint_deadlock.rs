//! rustdds patch 8 (vendor/README.md): a node creating endpoints on a topic that already has
//! many must not deadlock. Before the patch, discovery sent one match notice per known endpoint
//! while holding the discovery database's read lock; with its queue of 32 full and the next
//! endpoint's creation waiting for the write lock, the event loop could never take its own read
//! lock, and the node went silent for good.

use std::time::Duration;

use cell_msgs::MachineStatus;
use cell_runtime::{CellNode, FastPathMode, NodeSetup, QosPreset};

/// Nodes of the crowd, each with this many readers on the topic; the writers then made beside
/// them, for at least this long (their participants' announcements keep the event loop
/// asking for its read lock meanwhile).
const CROWD: usize = 3;
const READERS: usize = 100;
const WRITERS: usize = 400;
const MAKING: Duration = Duration::from_secs(12);

fn node(name: &str, domain: u16) -> CellNode {
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = FastPathMode::Off;
    CellNode::new(setup).expect("node comes up")
}

/// A domain of its own: counted down from the top of the root package's test range.
fn domain() -> u16 {
    let base = std::env::var("CELL_TEST_DOMAIN_BASE")
        .ok()
        .and_then(|b| b.parse::<u16>().ok())
        .filter(|b| *b <= 216)
        .unwrap_or(100 + (std::process::id() % 8) as u16 * 16);
    base + 10
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn endpoints_made_among_many_known_ones_do_not_deadlock() {
    let domain = domain();
    let crowd: Vec<CellNode> = (0..CROWD)
        .map(|i| node(&format!("crowd{i}"), domain))
        .collect();
    let _readers: Vec<_> = crowd
        .iter()
        .flat_map(|n| {
            (0..READERS).map(move |_| {
                n.subscriber::<MachineStatus>("/crowd", QosPreset::Status)
                    .unwrap()
            })
        })
        .collect();
    let maker = node("maker", domain);
    let first = maker
        .publisher::<MachineStatus>("/crowd", QosPreset::Status)
        .unwrap();
    assert!(
        first
            .wait_for_subscribers(CROWD * READERS, Duration::from_secs(90))
            .await,
        "the maker discovered {} of {} readers",
        first.dds_subscription_count(),
        CROWD * READERS
    );
    // Each new writer now makes discovery send READERS match notices. On a thread of its own,
    // so a deadlock fails the test instead of hanging it.
    let (done, finished) = std::sync::mpsc::channel();
    let runtime = tokio::runtime::Handle::current();
    std::thread::spawn(move || {
        let _entered = runtime.enter();
        let started = std::time::Instant::now();
        let mut writers = Vec::new();
        while writers.len() < WRITERS && started.elapsed() < MAKING {
            writers.push(
                maker
                    .publisher::<MachineStatus>("/crowd", QosPreset::Status)
                    .unwrap(),
            );
        }
        let _ = done.send(writers.len());
        // The node and its writers stay with this thread.
        std::mem::forget((maker, writers));
    });
    let Ok(made) = finished.recv_timeout(MAKING + Duration::from_secs(90)) else {
        // Unwinding would hang too: dropping this node's endpoints needs its deadlocked event
        // loop. Unpatched, this is where the test ends.
        eprintln!("creating writers beside many known readers deadlocked (rustdds patch 8)");
        std::process::exit(101);
    };
    assert!(made > 0);
}
