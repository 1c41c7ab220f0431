//! The Marlin simulator on a real TCP socket, spoken to byte by byte as a host would: `ok` per
//! line, `M105`, `M109` waits with wait reports, resend on a bad checksum or a skipped line
//! number, host keepalive, `M112` kill with heaters off, thermal runaway, reset on connect.

use std::time::Duration;

use cell_marlin::protocol::{numbered, parse_temps};
use cell_marlin::sim::{self, Faults, SimConfig, SimEvent};
use tokio::io::{AsyncBufReadExt, AsyncWriteExt, BufReader, Lines};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::TcpStream;

struct Host {
    rd: Lines<BufReader<OwnedReadHalf>>,
    wr: OwnedWriteHalf,
}

impl Host {
    async fn connect(addr: std::net::SocketAddr) -> Host {
        let s = TcpStream::connect(addr).await.unwrap();
        let (r, w) = s.into_split();
        Host {
            rd: BufReader::new(r).lines(),
            wr: w,
        }
    }
    async fn send(&mut self, line: &str) {
        self.wr
            .write_all(format!("{line}\n").as_bytes())
            .await
            .unwrap();
    }
    async fn line(&mut self, within: Duration) -> Option<String> {
        tokio::time::timeout(within, self.rd.next_line())
            .await
            .ok()
            .and_then(|r| r.ok().flatten())
    }
    /// Lines up to and including the first `ok…`.
    async fn until_ok(&mut self) -> Vec<String> {
        let mut got = Vec::new();
        loop {
            let l = self
                .line(Duration::from_secs(10))
                .await
                .unwrap_or_else(|| panic!("no ok; got {got:?}"));
            let done = l.starts_with("ok");
            got.push(l);
            if done {
                return got;
            }
        }
    }
    async fn banner(&mut self) -> Vec<String> {
        let mut got = Vec::new();
        while let Some(l) = self.line(Duration::from_millis(300)).await {
            got.push(l);
        }
        got
    }
}

async fn sim_on_tcp(cfg: SimConfig) -> (sim::SimHandle, Host) {
    let sim = sim::start(cfg);
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let mut host = Host::connect(addr).await;
    let banner = host.banner().await;
    assert_eq!(
        banner.first().map(String::as_str),
        Some("start"),
        "{banner:?}"
    );
    (sim, host)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ok_per_line_m105_and_m109_waits_with_reports() {
    let (sim, mut host) = sim_on_tcp(SimConfig {
        time_scale: 20.0,
        ..SimConfig::default()
    })
    .await;
    host.send(&numbered(0, "M110 N0")).await;
    assert_eq!(host.until_ok().await, ["ok"]);
    host.send(&numbered(1, "M104 S210")).await;
    assert_eq!(host.until_ok().await, ["ok"]);
    host.send(&numbered(2, "M105")).await;
    let r = host.until_ok().await;
    let t = parse_temps(&r[0]).expect("ok T:");
    assert_eq!(t.hotend.target, 210.0);
    assert!(t.hotend.current < 60.0, "{t:?}");
    let t0 = sim.snapshot().now_s;
    host.send(&numbered(3, "M109 S210")).await;
    let r = host.until_ok().await;
    let waited = sim.snapshot().now_s - t0;
    let reports: Vec<_> = r.iter().filter(|l| l.contains(" W:")).collect();
    // 22 → 209 °C takes τ·ln(278/91) ≈ 33 s on this hotend, then TEMP_RESIDENCY_TIME (10 s).
    // (The upper bound leaves room for a loaded machine: 20 simulated s per real s.)
    assert!(waited > 38.0 && waited < 75.0, "waited {waited} s");
    assert!(
        reports.len() as f64 >= waited - 3.0,
        "a wait report a second: {} in {waited} s",
        reports.len()
    );
    assert!(reports[0].starts_with(" T:") && reports[0].ends_with("W:?"));
    assert!(reports.last().unwrap().ends_with("W:0") || reports.last().unwrap().ends_with("W:1"));
    let end = sim.snapshot();
    assert!((end.hotend.current - 210.0).abs() <= 1.0, "{end:?}");
    // Moves take their time: 100 mm at 50 mm/s is 2 s, and M400 waits for it.
    let t1 = sim.snapshot().now_s;
    host.send(&numbered(4, "G1 X100 F3000")).await;
    assert_eq!(host.until_ok().await, ["ok"]);
    host.send(&numbered(5, "M400")).await;
    host.until_ok().await;
    let moved = sim.snapshot();
    assert!(moved.now_s - t1 >= 2.0, "{}", moved.now_s - t1);
    assert_eq!(moved.position[0], 100.0);
    host.send(&numbered(6, "M114")).await;
    let r = host.until_ok().await;
    assert!(
        r[0].starts_with("X:100.00 Y:0.00 Z:0.00 E:0.00 Count X:8000"),
        "{r:?}"
    );
    host.send(&numbered(7, "M104 S0")).await;
    host.until_ok().await;
    host.send(&numbered(8, "M105")).await;
    let t = parse_temps(&host.until_ok().await[0]).unwrap();
    assert!(t.targets_off(), "{t:?}");
    host.send(&numbered(9, "M4242")).await;
    let r = host.until_ok().await;
    assert_eq!(r[0], "echo:Unknown command: \"M4242\"");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_checksum_and_skipped_numbers_ask_for_a_resend() {
    let (sim, mut host) = sim_on_tcp(SimConfig::default()).await;
    host.send(&numbered(0, "M110 N0")).await;
    host.until_ok().await;
    host.send(&numbered(1, "G92 X0")).await;
    host.until_ok().await;
    // A flipped bit: the checksum is now wrong.
    let bad = numbered(2, "G1 X10 F600").replace("X10", "X11");
    host.send(&bad).await;
    assert_eq!(
        host.until_ok().await,
        ["Error:checksum mismatch, Last Line: 1", "Resend: 2", "ok"]
    );
    // Line 2 lost on the wire: 3 arrives.
    host.send(&numbered(3, "G1 X10 F600")).await;
    assert_eq!(
        host.until_ok().await,
        [
            "Error:Line Number is not Last Line Number+1, Last Line: 1",
            "Resend: 2",
            "ok"
        ]
    );
    host.send("N2 G1 X10").await;
    assert_eq!(
        host.until_ok().await[0],
        "Error:No Checksum with line number, Last Line: 1"
    );
    host.send(&numbered(2, "G1 X10 F600")).await;
    assert_eq!(host.until_ok().await, ["ok"]);
    // M110 renumbers.
    host.send(&numbered(100, "M110 N100")).await;
    assert_eq!(host.until_ok().await, ["ok"]);
    host.send(&numbered(101, "M400")).await;
    host.until_ok().await;
    let s = sim.snapshot();
    assert_eq!(s.last_line_number, 101);
    assert_eq!(s.position[0], 10.0);
    // The bad lines never ran: one G1 X10 moved, nothing moved to X11.
    let ex = sim.executed();
    assert_eq!(
        ex.iter().filter(|c| c.starts_with("G1")).count(),
        1,
        "{ex:?}"
    );
    assert_eq!(
        sim.events()
            .iter()
            .filter(|e| matches!(e, SimEvent::ResendRequested { line: 2, .. }))
            .count(),
        3
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn long_commands_keep_the_host_alive() {
    let (_sim, mut host) = sim_on_tcp(SimConfig {
        time_scale: 10.0,
        ..SimConfig::default()
    })
    .await;
    host.send(&numbered(0, "M110 N0")).await;
    host.until_ok().await;
    host.send(&numbered(1, "G4 S7")).await;
    let r = host.until_ok().await;
    let busy = r.iter().filter(|l| *l == "echo:busy: processing").count();
    assert_eq!(busy, 3, "every 2 s of a 7 s dwell: {r:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn m112_kills_heaters_off_and_only_a_reset_revives() {
    let (sim, mut host) = sim_on_tcp(SimConfig {
        time_scale: 20.0,
        ..SimConfig::default()
    })
    .await;
    host.send(&numbered(0, "M110 N0")).await;
    host.until_ok().await;
    host.send(&numbered(1, "M140 S60")).await;
    host.until_ok().await;
    host.send(&numbered(2, "M109 S210")).await;
    // Mid-wait: the emergency parser acts on M112 at once.
    let first = host.line(Duration::from_secs(5)).await.unwrap();
    assert!(first.contains(" W:"), "{first}");
    host.send("M112").await;
    let mut got = Vec::new();
    while let Some(l) = host.line(Duration::from_millis(500)).await {
        got.push(l);
    }
    assert!(
        got.contains(&"Error:Printer halted. kill() called!".to_string()),
        "{got:?}"
    );
    let s = sim.snapshot();
    assert_eq!((s.hotend.target, s.bed.target), (0.0, 0.0));
    assert!(s.halted.is_some());
    // Halted: nothing is read.
    host.send(&numbered(3, "M105")).await;
    assert_eq!(host.line(Duration::from_millis(400)).await, None);
    // A new connection resets the board (DTR): start, then M105 answers with targets 0.
    let addr_host = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let mut again = Host::connect(addr_host).await;
    assert_eq!(
        again.banner().await.first().map(String::as_str),
        Some("start")
    );
    again.send(&numbered(0, "M110 N0")).await;
    again.until_ok().await;
    again.send(&numbered(1, "M105")).await;
    let t = parse_temps(&again.until_ok().await[0]).unwrap();
    assert!(t.targets_off() && t.hotend.current > 22.0, "{t:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_heater_that_loses_power_trips_thermal_protection() {
    let (sim, mut host) = sim_on_tcp(SimConfig {
        time_scale: 50.0,
        faults: Faults {
            heater_fail_at_line: Some(4),
            ..Faults::default()
        },
        ..SimConfig::default()
    })
    .await;
    for (n, c) in ["M110 N0", "M104 S200", "G4 S40"].iter().enumerate() {
        host.send(&numbered(n as u64, c)).await;
        host.until_ok().await;
    }
    // Line 4: the heater cartridge's wire breaks; the temperature falls away from 200 °C.
    host.send(&numbered(3, "G4 S60")).await;
    let mut got = Vec::new();
    while let Some(l) = host.line(Duration::from_secs(3)).await {
        got.push(l);
    }
    let i = got
        .iter()
        .position(|l| l == "Error:Thermal Runaway, system stopped! Heater_ID: 0")
        .unwrap_or_else(|| panic!("{got:?}"));
    assert_eq!(got[i + 1], "Error:Printer halted. kill() called!");
    assert!(sim.snapshot().hotend.target == 0.0);
    assert!(sim.events().iter().any(|e| matches!(
        e,
        SimEvent::Thermal {
            error: sim::ThermalError::Runaway,
            ..
        }
    )));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hotend_idle_timeout_switches_the_heat_off_when_the_host_is_gone() {
    // A board on a network bridge (no reset when a host connects) with HOTEND_IDLE_TIMEOUT.
    let sim = sim::start(SimConfig {
        time_scale: 50.0,
        on_connect: sim::OnConnect::Silent,
        hotend_idle_timeout_s: Some(60.0),
        ..SimConfig::default()
    });
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let mut host = Host::connect(addr).await;
    host.send("M104 S200").await;
    host.until_ok().await;
    drop(host);
    let t0 = sim.snapshot().now_s;
    let (s, off) = sim
        .wait_for(Duration::from_secs(10), |s| s.hotend.target == 0.0)
        .await;
    assert!(off, "{s:?}");
    assert!(
        s.now_s - t0 >= 55.0,
        "not before the timeout: {}",
        s.now_s - t0
    );
    assert!(sim
        .events()
        .iter()
        .any(|e| matches!(e, SimEvent::IdleTimeout { .. })));
}
