//! Shared helpers for the in-process integration tests: fresh domains, loopback nodes.
#![allow(dead_code)] // each test binary uses a different subset

use std::{
    sync::atomic::{AtomicU16, Ordering},
    time::Duration,
};

use cell_runtime::{CellNode, FastPathMode, NodeSetup};

static NEXT: AtomicU16 = AtomicU16::new(0);

/// A DDS domain no other running test uses: test binaries run one at a time, tests inside one
/// binary get consecutive ids from a per-process base.
pub fn fresh_domain() -> u16 {
    let base = 100 + (std::process::id() % 8) as u16 * 16;
    base + NEXT.fetch_add(1, Ordering::Relaxed) % 16
}

/// A node on `domain`, DDS on loopback only, with or without the shared-memory fast path.
pub fn node(name: &str, domain: u16, fast_path: bool) -> CellNode {
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = if fast_path {
        FastPathMode::Auto
    } else {
        FastPathMode::Off
    };
    CellNode::new(setup).expect("node comes up")
}

/// Generous bound for discovery and delivery on a loaded 2-core machine.
pub const DELIVERY_TIMEOUT: Duration = Duration::from_secs(30);
