//! Two hosts, simulated by two network namespaces joined by a veth pair: a probe on one and a
//! monitor on the other discover each other over DDS (multicast SPDP on the veth link) and
//! exchange a Toolpath and heat maps. Needs root and iproute2 (CI has both); elsewhere the test
//! says why it did not run, and under CI it fails instead ([`cell_testkit::require_tool`]).

use std::process::{Command, Output};

fn run(cmd: &[&str]) -> Output {
    Command::new(cmd[0])
        .args(&cmd[1..])
        .output()
        .unwrap_or_else(|e| panic!("{cmd:?}: {e}"))
}

fn must(cmd: &[&str]) {
    let out = run(cmd);
    assert!(
        out.status.success(),
        "{cmd:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Deletes the namespaces (and with them the veth pair) however the test ends.
struct Namespaces(Vec<String>);

impl Drop for Namespaces {
    fn drop(&mut self) {
        for ns in &self.0 {
            let _ = run(&["ip", "netns", "del", ns]);
        }
    }
}

fn can_make_namespaces() -> Result<(), String> {
    let out = Command::new("ip")
        .args(["netns", "add", "cellsuite-probe"])
        .output()
        .map_err(|e| format!("ip: {e}"))?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).trim().to_string());
    }
    let _ = run(&["ip", "netns", "del", "cellsuite-probe"]);
    Ok(())
}

#[test]
fn nodes_in_two_network_namespaces_exchange_a_toolpath_over_dds() {
    if !cell_testkit::require_tool(
        "root and iproute2 (network namespaces)",
        can_make_namespaces(),
        "run the tests as root; `scripts/test` installs iproute2",
    ) {
        return;
    }
    let id = std::process::id() % 10_000;
    let (ns_a, ns_b) = (format!("cellA{id}"), format!("cellB{id}"));
    let (veth_a, veth_b) = (format!("cva{id}"), format!("cvb{id}"));
    let subnet = 200 + (id % 50);
    let (addr_a, addr_b) = (format!("10.{subnet}.77.1"), format!("10.{subnet}.77.2"));
    let _guard = Namespaces(vec![ns_a.clone(), ns_b.clone()]);
    must(&["ip", "netns", "add", &ns_a]);
    must(&["ip", "netns", "add", &ns_b]);
    must(&[
        "ip", "link", "add", &veth_a, "type", "veth", "peer", "name", &veth_b,
    ]);
    for (ns, veth, addr) in [(&ns_a, &veth_a, &addr_a), (&ns_b, &veth_b, &addr_b)] {
        must(&["ip", "link", "set", veth, "netns", ns]);
        must(&[
            "ip",
            "-n",
            ns,
            "addr",
            "add",
            &format!("{addr}/24"),
            "dev",
            veth,
        ]);
        must(&["ip", "-n", ns, "link", "set", veth, "up", "multicast", "on"]);
        must(&["ip", "-n", ns, "link", "set", "lo", "up"]);
        // DDS discovery is multicast; give it a route out of the veth.
        must(&["ip", "-n", ns, "route", "add", "224.0.0.0/4", "dev", veth]);
    }

    let cell = env!("CARGO_BIN_EXE_cell");
    let node = |ns: &str, addr: &str, exec: &str, params: &[&str]| {
        let mut cmd = Command::new("ip");
        cmd.args([
            "netns",
            "exec",
            ns,
            cell,
            "node",
            exec,
            "--dds-network",
            addr,
            "--fast-path",
            "off",
            "--ros-args",
        ]);
        for p in params {
            cmd.args(["-p", p]);
        }
        cmd.env("ROS_DOMAIN_ID", "42").env_remove("RUST_LOG");
        cmd
    };
    let mut probe = node(
        &ns_a,
        &addr_a,
        "probe",
        &[
            "wait_for_subscribers:=1",
            "wait_timeout_s:=60.0",
            "heat_map_frames:=100",
            "heat_map_width:=64",
            "heat_map_height:=64",
            "linger:=true",
        ],
    )
    .stdout(std::process::Stdio::null())
    .stderr(std::process::Stdio::piped())
    .spawn()
    .expect("start the probe");
    let monitor = node(
        &ns_b,
        &addr_b,
        "monitor",
        &[
            "expect_toolpaths:=1",
            "expect_heat_maps:=3",
            "timeout_s:=90.0",
        ],
    )
    .output()
    .expect("run the monitor");
    let _ = probe.kill();
    let probe_out = probe.wait_with_output().unwrap();

    let stdout = String::from_utf8_lossy(&monitor.stdout);
    assert!(
        monitor.status.success(),
        "monitor in {ns_b}: {}\n{stdout}\nprobe in {ns_a}: {}",
        String::from_utf8_lossy(&monitor.stderr),
        String::from_utf8_lossy(&probe_out.stderr)
    );
    assert!(stdout.contains("1 toolpath(s)"), "{stdout}");
    assert!(
        stdout.contains("0 over shared memory"),
        "heat maps must cross the veth link over DDS: {stdout}"
    );
    assert!(stdout.contains("job \"probe\", 4 segments"), "{stdout}");
}
