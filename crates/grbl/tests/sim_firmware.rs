//! The simulator speaks as GRBL 1.1h, grblHAL and FluidNC: banners on reset and on connect,
//! `$I` and `Bf:` buffer sizes, a FluidNC telnet reconnect that keeps the job, `FS:`/`A:`
//! following the spindle through M3, hold, M5 and reset (laser mode too), startup blocks and
//! `$RST`. Each test talks to the simulator byte for byte, as a sender would, under a paused
//! tokio clock.

use std::time::Duration;

use cell_grbl::protocol::MachineState;
use cell_grbl::sim::{
    self, OnConnect, SimConfig, SimEvent, SimFirmware, SimHandle, FLUIDNC_BUILD_INFO,
    GRBLHAL_BUILD_INFO, GRBL_BUILD_INFO,
};
use tokio::io::{AsyncBufReadExt, AsyncWriteExt, BufReader, DuplexStream, ReadHalf, WriteHalf};

/// How long (tokio time) to wait for a line before failing instead of hanging.
const WAIT: Duration = Duration::from_secs(60);

const FIRMWARES: [SimFirmware; 3] = [
    SimFirmware::Grbl11h,
    SimFirmware::GrblHal,
    SimFirmware::FluidNc,
];

/// A sender on an in-memory link: writes bytes, reads the controller's lines.
struct Host {
    rd: BufReader<ReadHalf<DuplexStream>>,
    wr: WriteHalf<DuplexStream>,
}

impl Host {
    fn attach(sim: &SimHandle) -> Host {
        let (host, controller) = tokio::io::duplex(1 << 16);
        sim.attach(controller);
        let (rd, wr) = tokio::io::split(host);
        Host {
            rd: BufReader::new(rd),
            wr,
        }
    }

    /// Attaches and reads the greeting the firmware gives a new host (its banner, or nothing).
    async fn greeted(sim: &SimHandle, fw: SimFirmware) -> Host {
        let mut host = Host::attach(sim);
        if fw.on_connect() == OnConnect::Banner {
            assert_eq!(host.line().await, fw.banner());
        }
        host
    }

    async fn send(&mut self, bytes: &[u8]) {
        self.wr
            .write_all(bytes)
            .await
            .expect("write to the simulator");
    }

    /// The next non-empty line, or `None` when nothing comes within `wait`.
    async fn line_within(&mut self, wait: Duration) -> Option<String> {
        loop {
            let mut buf = String::new();
            match tokio::time::timeout(wait, self.rd.read_line(&mut buf)).await {
                Ok(Ok(0)) | Err(_) => return None,
                Ok(Ok(_)) => {
                    let line = buf.trim_end_matches(['\r', '\n']).to_string();
                    if !line.is_empty() {
                        return Some(line);
                    }
                }
                Ok(Err(e)) => panic!("read from the simulator: {e}"),
            }
        }
    }

    async fn line(&mut self) -> String {
        self.line_within(WAIT)
            .await
            .expect("the simulator answers within the wait")
    }

    /// Lines up to and including the first that `last` accepts.
    async fn until(&mut self, last: impl Fn(&str) -> bool) -> Vec<String> {
        let mut lines = Vec::new();
        loop {
            let l = self.line().await;
            let done = last(&l);
            lines.push(l);
            if done {
                return lines;
            }
        }
    }

    /// Sends a command line; its output up to `ok` or `error:N`.
    async fn command(&mut self, cmd: &str) -> Vec<String> {
        self.send(format!("{cmd}\n").as_bytes()).await;
        self.until(|l| l == "ok" || l.starts_with("error:")).await
    }

    /// Sends `?` and returns the status report (other lines on the way are dropped).
    async fn status(&mut self) -> String {
        self.send(b"?").await;
        self.until(|l| l.starts_with('<')).await.pop().unwrap()
    }

    /// Polls until a report carries `Ov:` (at most 40 reports, 50 ms apart).
    async fn status_with_overrides(&mut self) -> String {
        for _ in 0..40 {
            let s = self.status().await;
            if s.contains("|Ov:") {
                return s;
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
        panic!("no status report with Ov: in 40 reports");
    }

    /// Polls until a report's state starts with `state`.
    async fn status_until(&mut self, state: &str) -> String {
        for _ in 0..400 {
            let s = self.status().await;
            if s[1..].starts_with(state) {
                return s;
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
        panic!("the state never became {state}");
    }
}

fn config(firmware: SimFirmware) -> SimConfig {
    SimConfig {
        timer_slack: Duration::ZERO,
        ..SimConfig::for_firmware(firmware)
    }
}

/// A status report's field (`FS`, `Bf`, `A`, ...) after its `:`.
fn field<'a>(report: &'a str, name: &str) -> Option<&'a str> {
    report
        .trim_start_matches('<')
        .trim_end_matches('>')
        .split('|')
        .find_map(|f| f.strip_prefix(name)?.strip_prefix(':'))
}

/// The X of `MPos:`.
fn mpos_x(report: &str) -> f64 {
    let v = field(report, "MPos").unwrap_or_else(|| panic!("no MPos: in {report}"));
    v.split(',').next().unwrap().parse().unwrap()
}

/// `FS:` as (feed, spindle).
fn fs(report: &str) -> (f64, f64) {
    let v = field(report, "FS").unwrap_or_else(|| panic!("no FS: in {report}"));
    let (f, s) = v.split_once(',').unwrap();
    (f.parse().unwrap(), s.parse().unwrap())
}

#[tokio::test(start_paused = true)]
async fn each_firmware_prints_its_banner_after_a_reset_and_as_it_greets_a_host() {
    for fw in FIRMWARES {
        let sim = sim::start(config(fw));
        let mut host = Host::attach(&sim);
        match fw.on_connect() {
            OnConnect::Banner => assert_eq!(host.line().await, fw.banner(), "{fw}"),
            OnConnect::Silent => {
                // FluidNC greets a telnet client with nothing: its first line answers `?`.
                assert!(host.status().await.starts_with("<Idle|"), "{fw}");
            }
            OnConnect::Reset => unreachable!("no firmware defaults to a reset"),
        }
        host.send(&[0x18]).await;
        assert_eq!(host.line().await, fw.banner(), "{fw}: banner after Ctrl-X");
    }
    assert_eq!(SimFirmware::Grbl11h.banner(), "Grbl 1.1h ['$' for help]");
    assert_eq!(
        SimFirmware::GrblHal.banner(),
        "GrblHAL 1.1f ['$' or '$HELP' for help]"
    );
    assert_eq!(
        SimFirmware::FluidNc.banner(),
        "Grbl 3.7 [FluidNC v3.7.8 (wifi) '$' for help]"
    );
}

#[tokio::test(start_paused = true)]
async fn build_info_and_bf_report_each_firmwares_buffers() {
    for (fw, info, rx, blocks) in [
        (SimFirmware::Grbl11h, GRBL_BUILD_INFO.as_slice(), 128, 15),
        (
            SimFirmware::GrblHal,
            GRBLHAL_BUILD_INFO.as_slice(),
            1024,
            100,
        ),
        (
            SimFirmware::FluidNc,
            FLUIDNC_BUILD_INFO.as_slice(),
            1200,
            15,
        ),
    ] {
        let sim = sim::start(config(fw));
        let mut host = Host::greeted(&sim, fw).await;
        let out = host.command("$I").await;
        assert_eq!(out[..out.len() - 1], *info, "{fw}");
        assert_eq!(out.last().map(String::as_str), Some("ok"));
        let bf = field(&host.status().await, "Bf").unwrap().to_string();
        assert_eq!(bf, format!("{blocks},{rx}"), "{fw}");
    }
    // The configured size wins over the firmware's, in `$I` and in `Bf:`.
    let sim = sim::start(SimConfig {
        rx_buffer_bytes: 256,
        ..config(SimFirmware::GrblHal)
    });
    let mut host = Host::greeted(&sim, SimFirmware::GrblHal).await;
    let out = host.command("$I").await;
    assert!(
        out.contains(&"[OPT:VNMSL,100,256,3,0]".to_string()),
        "{out:?}"
    );
    assert_eq!(field(&host.status().await, "Bf"), Some("100,256"));
}

#[tokio::test(start_paused = true)]
async fn a_fluidnc_telnet_reconnect_keeps_the_job_running_and_the_modal_state() {
    let sim = sim::start(config(SimFirmware::FluidNc));
    let mut first = Host::attach(&sim);
    for line in ["G21 G90 G93", "M3 S800", "G1 X200 F0.5", "G1 X0 F0.5"] {
        assert_eq!(first.command(line).await, ["ok"], "{line}");
    }
    first.status_until("Run").await;
    drop(first);
    sim.wait_for(WAIT, |s| !s.connected)
        .await
        .expect("the first link closes");
    let mut second = Host::attach(&sim);
    // No banner, no reset: the first thing the new client reads answers its `?`.
    let report = second.status().await;
    assert!(report.starts_with("<Run|"), "{report}");
    assert_eq!(fs(&report).1, 800.0, "the heat stays on: {report}");
    let x0 = mpos_x(&report);
    let gc = second.command("$G").await;
    assert_eq!(gc[0], "[GC:G1 G54 G17 G21 G90 G93 M3 M9 T0 F0.500 S800]");
    // G93 F0.5: 200 mm in 2 minutes. Ten seconds later the move has gone on.
    tokio::time::sleep(Duration::from_secs(10)).await;
    let report = second.status().await;
    assert!(report.starts_with("<Run|"), "{report}");
    assert!(mpos_x(&report) > x0 + 10.0, "{x0} then {report}");
    assert_eq!(sim.snapshot().state, MachineState::Run);
    assert!(sim.snapshot().spindle_on);
    assert!(!sim
        .events()
        .iter()
        .any(|e| matches!(e, SimEvent::Reset { .. } | SimEvent::HardwareReset { .. })));
}

#[tokio::test(start_paused = true)]
async fn an_arduino_that_resets_on_connect_loses_the_job_and_the_heat() {
    let sim = sim::start(SimConfig {
        on_connect: OnConnect::Reset,
        ..config(SimFirmware::Grbl11h)
    });
    let mut first = Host::attach(&sim);
    assert_eq!(first.line().await, SimFirmware::Grbl11h.banner());
    for line in ["G10 L2 P1 X5", "M3 S800", "G1 X200 F300"] {
        assert_eq!(first.command(line).await, ["ok"], "{line}");
    }
    first.status_until("Run").await;
    drop(first);
    let mut second = Host::attach(&sim);
    assert_eq!(second.line().await, SimFirmware::Grbl11h.banner());
    let report = second.status().await;
    assert!(
        report.starts_with("<Idle|MPos:0.000,0.000,0.000|"),
        "{report}"
    );
    assert_eq!(fs(&report), (0.0, 0.0));
    let gc = second.command("$G").await;
    assert_eq!(gc[0], "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]");
    // Work offsets live in EEPROM and survive.
    let offsets = second.command("$#").await;
    assert_eq!(offsets[0], "[G54:5.000,0.000,0.000]");
    assert!(!sim.snapshot().spindle_on);
    assert!(sim
        .events()
        .iter()
        .any(|e| matches!(e, SimEvent::HardwareReset { .. })));
}

#[tokio::test(start_paused = true)]
async fn fs_and_a_follow_the_spindle_through_m3_hold_m5_and_reset() {
    for fw in FIRMWARES {
        let sim = sim::start(config(fw));
        let mut host = Host::greeted(&sim, fw).await;
        // Two reports after a reset: WCO first, then Ov (grblHAL: Ov first, then WCO).
        host.send(&[0x18]).await;
        host.until(|l| l == fw.banner()).await;
        let (r1, r2) = (host.status().await, host.status().await);
        let (ov_first, wco_first) = if fw == SimFirmware::GrblHal {
            (&r1, &r2)
        } else {
            (&r2, &r1)
        };
        assert!(
            wco_first.contains("|WCO:") && !wco_first.contains("|Ov:"),
            "{fw}: {r1} {r2}"
        );
        assert!(
            ov_first.contains("|Ov:100,100,100") && !ov_first.contains("|A:"),
            "{fw}"
        );

        // M3: the next report carries A:S at once (GRBL and FluidNC with Ov:, grblHAL by itself).
        assert_eq!(host.command("M3 S1000").await, ["ok"]);
        let r = host.status().await;
        assert_eq!(field(&r, "A"), Some("S"), "{fw}: {r}");
        assert_eq!(r.contains("|Ov:"), fw != SimFirmware::GrblHal, "{fw}: {r}");
        assert_eq!(fs(&r), (0.0, 1000.0), "{fw}: {r}");

        // Running, then held: the spindle stays on in a hold without laser mode.
        assert_eq!(host.command("G1 X100 F600").await, ["ok"]);
        let r = host.status_until("Run").await;
        assert_eq!(fs(&r), (600.0, 1000.0), "{fw}: {r}");
        host.send(b"!").await;
        let r = host.status_until("Hold:0").await;
        assert_eq!(fs(&r), (0.0, 1000.0), "{fw}: held with the heat on: {r}");
        let r = host.status_with_overrides().await;
        assert_eq!(field(&r, "A"), Some("S"), "{fw}: {r}");
        assert!(sim.snapshot().spindle_on);

        // Resume to the end, then M5: the next report says the spindle is off.
        host.send(b"~").await;
        host.status_until("Idle").await;
        assert_eq!(host.command("M5").await, ["ok"]);
        let r = host.status().await;
        assert_eq!(fs(&r).1, 0.0, "{fw}: {r}");
        if fw == SimFirmware::GrblHal {
            // grblHAL reports the change with an empty `A:`.
            assert_eq!(field(&r, "A"), Some(""), "{fw}: {r}");
            assert!(!r.contains("|Ov:"), "{fw}: {r}");
        } else {
            assert!(r.contains("|Ov:") && !r.contains("|A:"), "{fw}: {r}");
        }
        assert!(!sim.snapshot().spindle_on);

        // On again, then a reset: off, and the reports say so.
        assert_eq!(host.command("M3 S400").await, ["ok"]);
        assert_eq!(fs(&host.status().await).1, 400.0);
        host.send(&[0x18]).await;
        host.until(|l| l == fw.banner()).await;
        let r = host.status_with_overrides().await;
        assert_eq!(fs(&r), (0.0, 0.0), "{fw}: {r}");
        assert!(!r.contains("|A:"), "{fw}: {r}");
        assert!(!sim.snapshot().spindle_on);
    }
}

#[tokio::test(start_paused = true)]
async fn grbl_refreshes_wco_and_ov_every_ten_idle_reports_one_after_the_other() {
    for fw in [SimFirmware::Grbl11h, SimFirmware::FluidNc] {
        let sim = sim::start(config(fw));
        let mut host = Host::greeted(&sim, fw).await;
        let mut wco = Vec::new();
        let mut ov = Vec::new();
        for n in 1..=25 {
            let r = host.status().await;
            if r.contains("|WCO:") {
                wco.push(n);
            }
            if r.contains("|Ov:") {
                ov.push(n);
            }
        }
        assert_eq!(wco, [1, 11, 21], "{fw}");
        assert_eq!(ov, [2, 12, 22], "{fw}");
    }
}

#[tokio::test(start_paused = true)]
async fn speeds_above_dollar_30_are_reported_at_dollar_30_and_s0_disables_grbls_pwm() {
    let sim = sim::start(config(SimFirmware::Grbl11h));
    let mut host = Host::greeted(&sim, SimFirmware::Grbl11h).await;
    assert_eq!(host.command("M3 S12000").await, ["ok"]);
    assert_eq!(fs(&host.status().await).1, 1000.0);
    // GRBL 1.1 disables the PWM at S0: no A:S although the parser says M3.
    assert_eq!(host.command("S0").await, ["ok"]);
    let r = host.status().await;
    assert!(r.contains("|Ov:") && !r.contains("|A:"), "{r}");
    assert!(!sim.snapshot().spindle_on);
    // grblHAL keeps the enable on at S0.
    let sim = sim::start(config(SimFirmware::GrblHal));
    let mut host = Host::greeted(&sim, SimFirmware::GrblHal).await;
    assert_eq!(host.command("M3 S0").await, ["ok"]);
    let r = host.status().await;
    assert_eq!(field(&r, "A"), Some("S"), "{r}");
    assert_eq!(fs(&r).1, 0.0);
}

#[tokio::test(start_paused = true)]
async fn in_laser_mode_m4_fires_only_while_cutting_and_a_hold_puts_it_out() {
    let sim = sim::start(SimConfig {
        laser_mode: true,
        ..config(SimFirmware::Grbl11h)
    });
    let mut host = Host::greeted(&sim, SimFirmware::Grbl11h).await;
    assert_eq!(host.command("M4 S1000").await, ["ok"]);
    let r = host.status().await;
    assert_eq!(fs(&r), (0.0, 0.0), "off at rest: {r}");
    assert!(!r.contains("|A:"), "{r}");
    assert!(!sim.snapshot().spindle_on);

    assert_eq!(host.command("G1 X100 F600").await, ["ok"]);
    let r = host.status_until("Run").await;
    assert_eq!(fs(&r), (600.0, 1000.0), "on while cutting: {r}");
    let r = host.status_with_overrides().await;
    assert_eq!(field(&r, "A"), Some("C"), "{r}");
    assert!(sim.snapshot().spindle_on);

    host.send(b"!").await;
    let r = host.status_until("Hold:0").await;
    assert_eq!(fs(&r), (0.0, 0.0), "out in the hold: {r}");
    assert!(!sim.snapshot().spindle_on);
    let gc = host.command("$G").await;
    assert!(gc[0].contains(" M4 "), "the parser still says M4: {gc:?}");

    host.send(b"~").await;
    let r = host.status_until("Run").await;
    assert_eq!(fs(&r).1, 1000.0, "back with the motion: {r}");
    host.status_until("Idle").await;
    assert_eq!(fs(&host.status().await).1, 0.0, "off again at rest");

    // A rapid does not fire it either.
    assert_eq!(host.command("G0 X0").await, ["ok"]);
    let r = host.status_until("Run").await;
    assert_eq!(fs(&r).1, 0.0, "{r}");

    // M3 is constant power: it stays on at rest after a feed move, not after a rapid.
    host.status_until("Idle").await;
    assert_eq!(host.command("M3").await, ["ok"]);
    assert_eq!(host.command("G1 X10 F600").await, ["ok"]);
    host.status_until("Run").await;
    let r = host.status_until("Idle").await;
    assert_eq!(fs(&r).1, 1000.0, "{r}");
    assert!(sim.snapshot().spindle_on);
    assert_eq!(host.command("G0 X0").await, ["ok"]);
    host.status_until("Run").await;
    let r = host.status_until("Idle").await;
    assert_eq!(fs(&r).1, 0.0, "{r}");
}

#[tokio::test(start_paused = true)]
async fn a_startup_block_runs_when_stored_and_after_every_reset_until_rst_wipes_it() {
    let sim = sim::start(config(SimFirmware::Grbl11h));
    let mut host = Host::greeted(&sim, SimFirmware::Grbl11h).await;
    // `$N0=M3S1000` switches the heat on now and at every reset.
    assert_eq!(host.command("$N0=M3S1000").await, ["ok"]);
    assert!(sim.snapshot().spindle_on);
    assert_eq!(host.command("$N").await, ["$N0=M3S1000", "$N1=", "ok"]);
    host.send(&[0x18]).await;
    assert_eq!(host.line().await, SimFirmware::Grbl11h.banner());
    assert_eq!(host.line().await, ">M3S1000:ok");
    assert!(
        sim.snapshot().spindle_on,
        "the reset switched the heat on again"
    );
    assert_eq!(fs(&host.status().await).1, 1000.0);
    assert!(sim
        .events()
        .iter()
        .any(|e| matches!(e, SimEvent::SystemCommand { line, .. } if line == "$N0=M3S1000")));

    // `$RST=*` wipes settings, offsets and startup blocks, then resets.
    assert_eq!(host.command("$10=3").await, ["ok"]);
    let out = host.command("$RST=*").await;
    assert_eq!(out, ["[MSG:Restoring defaults]", "ok"]);
    assert_eq!(host.line().await, SimFirmware::Grbl11h.banner());
    assert!(!sim.snapshot().spindle_on);
    assert_eq!(host.command("$N").await, ["$N0=", "$N1=", "ok"]);
    let settings = host.command("$$").await;
    assert!(settings.contains(&"$10=1".to_string()), "{settings:?}");
    assert!(
        !host.status().await.contains("|Bf:"),
        "$10=1: no buffer state"
    );
}

#[tokio::test(start_paused = true)]
async fn a_long_line_is_error_11_on_grbl_taken_by_grblhal_and_truncated_by_fluidnc() {
    // 100 characters after GRBL drops spaces and comments.
    let long = format!("G1 X1.{} F100", "0".repeat(90));
    for (fw, expected) in [
        (SimFirmware::Grbl11h, "error:11"),
        (SimFirmware::GrblHal, "ok"),
    ] {
        let sim = sim::start(config(fw));
        let mut host = Host::greeted(&sim, fw).await;
        assert_eq!(host.command(&long).await.last().unwrap(), expected, "{fw}");
    }
    // FluidNC keeps 254 bytes as received and runs them without a word.
    let sim = sim::start(config(SimFirmware::FluidNc));
    let mut host = Host::attach(&sim);
    let line = format!("G1 X7 F6000 ({}) Y3", "c".repeat(300));
    assert_eq!(host.command(&line).await, ["ok"]);
    host.status_until("Idle").await;
    let done = sim.executed();
    assert_eq!(done.len(), 1);
    assert_eq!(done[0].text.len(), 254);
    assert_eq!(
        sim.snapshot().position,
        vec![7.0, 0.0, 0.0],
        "Y3 was cut off"
    );
}
