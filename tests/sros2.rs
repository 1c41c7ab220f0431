//! SROS2: two secured cell nodes talk through DDS Security while an unsecured peer on the same
//! domain hears nothing of theirs and is not heard by them. Real `cell node` processes, a
//! keystore made by `scripts/sros2_keystore.sh` (openssl CLI), loopback. Needs the `security`
//! feature: `cargo test -p cellsuite --features security --test sros2`.
#![cfg(feature = "security")]

mod common;

use std::{
    path::Path,
    process::{Child, Command, Output, Stdio},
    time::{Duration, Instant},
};

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Whether the openssl CLI (the keystore script's only tool) is here; see `require_tool`.
fn have_openssl() -> bool {
    cell_testkit::require_command("openssl", "version", "apt-get install openssl")
}

/// A keystore with one enclave per name, for `domain` (sros2 writes the domain into the
/// governance and permissions).
fn keystore(dir: &Path, domain: u16, enclaves: &[&str]) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/sros2_keystore.sh");
    let run = |args: &[&str]| {
        let out = Command::new(&script)
            .args(args)
            .env("ROS_DOMAIN_ID", domain.to_string())
            .output()
            .expect("run scripts/sros2_keystore.sh");
        assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    };
    let ks = dir.to_str().unwrap();
    run(&["create_keystore", ks]);
    for enclave in enclaves {
        run(&["create_enclave", ks, enclave]);
    }
}

/// `cell node EXEC` on `domain`, loopback, fast path off (so only DDS could carry anything);
/// secured in `enclave` of `keystore` (Enforce) when given, with no ROS_SECURITY_* otherwise.
fn node(exec: &str, domain: u16, secured: Option<(&Path, &str)>, params: &[&str]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_cell"));
    cmd.args(["node", exec, "--fast-path", "off", "--ros-args"])
        .env("CELL_DDS_NETWORK", "loopback")
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env_remove("RUST_LOG")
        .env_remove("ROS_SECURITY_ENCLAVE_OVERRIDE")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    for p in params {
        cmd.args(["-p", p]);
    }
    match secured {
        Some((keystore, enclave)) => {
            cmd.args(["--enclave", enclave])
                .env("ROS_SECURITY_ENABLE", "true")
                .env("ROS_SECURITY_STRATEGY", "Enforce")
                .env("ROS_SECURITY_KEYSTORE", keystore);
        }
        None => {
            cmd.env_remove("ROS_SECURITY_ENABLE")
                .env_remove("ROS_SECURITY_STRATEGY")
                .env_remove("ROS_SECURITY_KEYSTORE");
        }
    }
    cmd
}

/// A running node whose output is drained as it comes (a secured node logs every message an
/// unsecured peer sends it, which would fill a pipe nobody reads and stall the node).
/// Killed when dropped, so a failing test leaves no node behind.
struct Running {
    child: Child,
    stdout: Option<std::thread::JoinHandle<Vec<u8>>>,
    stderr: Option<std::thread::JoinHandle<Vec<u8>>>,
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start(mut cmd: Command) -> Running {
    let mut child = cmd.spawn().expect("spawn cell");
    let drain = |mut r: Box<dyn std::io::Read + Send>| {
        std::thread::spawn(move || {
            let mut all = Vec::new();
            let _ = r.read_to_end(&mut all);
            all
        })
    };
    let stdout = Some(drain(Box::new(child.stdout.take().unwrap())));
    let stderr = Some(drain(Box::new(child.stderr.take().unwrap())));
    Running {
        child,
        stdout,
        stderr,
    }
}

/// A node's log without the one line per message an unsecured peer sends (they would bury
/// whatever explains a failure).
fn without_flood(stderr: &[u8]) -> String {
    text(stderr)
        .lines()
        .filter(|l| !l.contains("Received an unprotected message"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Waits for the node up to `limit`; kills it (and fails) past that.
fn finish(mut node: Running, what: &str, limit: Duration) -> Output {
    let start = Instant::now();
    let status = loop {
        if let Some(status) = node.child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > limit {
            let _ = node.child.kill();
            let _ = node.child.wait();
            let stderr = node.stderr.take().unwrap().join().unwrap();
            panic!(
                "{what} still running after {limit:?}: {}",
                without_flood(&stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    Output {
        status,
        stdout: node.stdout.take().unwrap().join().unwrap(),
        stderr: node.stderr.take().unwrap().join().unwrap(),
    }
}

#[test]
fn secured_nodes_talk_and_an_unsecured_peer_neither_hears_nor_is_heard() {
    if !have_openssl() {
        return;
    }
    let domain = common::fresh_domain();
    let ks = tempfile::tempdir().unwrap();
    keystore(ks.path(), domain, &["/cell/probe", "/cell/monitor"]);
    let secured = |enclave| Some((ks.path(), enclave));

    // The unsecured peer: a probe that keeps offering its toolpath (transient local) and a
    // monitor. The monitor hearing that probe shows the peer is alive on this domain. It
    // listens until told to stop (SIGINT, after the secured pair is done, however long the
    // handshakes take on a loaded machine) and would end early on hearing any heat map.
    let intruder = start(node(
        "probe",
        domain,
        None,
        &["job_id:=intruder", "heat_map_frames:=0", "linger:=true"],
    ));
    let eavesdropper = start(node(
        "monitor",
        domain,
        None,
        &[
            "expect_toolpaths:=1",
            "expect_heat_maps:=1",
            "timeout_s:=0.0",
        ],
    ));
    std::thread::sleep(Duration::from_secs(1));

    // The secured pair: the probe waits until it has matched the secured monitor, then sends
    // the test block and 30 heat maps (256×256, so fragmented and encrypted per fragment).
    // Limits are generous: the security handshakes (RSA/ECDSA in a debug build) take seconds
    // each when CI runs other test binaries beside this one.
    let monitor = start(node(
        "monitor",
        domain,
        secured("/cell/monitor"),
        &[
            "expect_toolpaths:=1",
            "expect_heat_maps:=10",
            "timeout_s:=100.0",
        ],
    ));
    let probe = start(node(
        "probe",
        domain,
        secured("/cell/probe"),
        &[
            "job_id:=secured",
            "heat_map_frames:=30",
            "wait_for_subscribers:=1",
            "wait_timeout_s:=45.0",
        ],
    ));

    let probe = finish(probe, "secured probe", Duration::from_secs(110));
    assert!(
        probe.status.success(),
        "the secured probe found no secured subscriber: {}",
        without_flood(&probe.stderr)
    );
    let monitor = finish(monitor, "secured monitor", Duration::from_secs(110));
    let heard = text(&monitor.stdout);
    assert!(
        monitor.status.success(),
        "the secured monitor missed the secured probe: {}{heard}",
        without_flood(&monitor.stderr)
    );
    // Exactly the secured probe's block: the intruder's was offered all along and ignored.
    assert!(heard.contains("1 toolpath(s)"), "{heard}");
    assert!(heard.contains("job \"secured\""), "{heard}");
    let all = format!("{heard}{}", text(&monitor.stderr));
    assert!(
        !all.contains("intruder"),
        "the secured monitor heard the intruder: {all}"
    );

    // The eavesdropper listened the whole time the pair talked: still running now, so it heard
    // no heat map; stopped, it prints what it did hear.
    let mut eavesdropper = eavesdropper;
    assert!(
        eavesdropper.child.try_wait().unwrap().is_none(),
        "the unsecured monitor stopped early (it heard a heat map?)"
    );
    let pid = eavesdropper.child.id().to_string();
    let sent = Command::new("kill").args(["-INT", &pid]).status().unwrap();
    assert!(sent.success(), "kill -INT {pid}");
    let eavesdropper = finish(eavesdropper, "unsecured monitor", Duration::from_secs(20));
    let eaves = format!(
        "{}{}",
        text(&eavesdropper.stdout),
        text(&eavesdropper.stderr)
    );
    assert!(
        eavesdropper.status.success(),
        "the unsecured monitor failed: {eaves}"
    );
    assert!(
        eaves.contains("1 toolpath(s), 0 heat map(s)") && eaves.contains("job \"intruder\""),
        "the unsecured monitor should hear its own kind only: {eaves}"
    );
    assert!(!eaves.contains("\"secured\""), "{eaves}");

    drop(intruder);
}

#[test]
fn enforce_without_the_enclave_files_is_one_clear_error() {
    if !have_openssl() {
        return;
    }
    let domain = common::fresh_domain();
    let ks = tempfile::tempdir().unwrap();
    keystore(ks.path(), domain, &["/cell/probe"]);
    let permissions = ks.path().join("enclaves/cell/probe/permissions.p7s");
    std::fs::remove_file(&permissions).unwrap();
    let out = node(
        "probe",
        domain,
        Some((ks.path(), "/cell/probe")),
        &["heat_map_frames:=0"],
    )
    .output()
    .unwrap();
    let stderr = text(&out.stderr);
    assert!(
        !out.status.success(),
        "started without permissions.p7s: {stderr}"
    );
    assert!(
        stderr.contains(&permissions.display().to_string()),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");

    // An enclave the keystore does not have.
    let out = node("probe", domain, Some((ks.path(), "/cell/nobody")), &[])
        .output()
        .unwrap();
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(stderr.contains("no enclave /cell/nobody"), "{stderr}");
}
