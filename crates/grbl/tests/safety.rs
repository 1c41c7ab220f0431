//! The streaming client's stop paths against the in-process simulator under a paused clock:
//! the heat read back from the controller, a stale `ok` that must not answer the safe stop's
//! `M5`, a line the RX buffer cannot take, a link that does not come back, a bad `$I`.

mod common;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::protocol::MachineState;
use cell_grbl::sim::{Faults, SimConfig};
use cell_grbl::stream::{ClientConfig, Fault, FlowControl, GrblClient, HeatState};
use cell_grbl::transport::{Connect, ConnectFuture};
use common::{in_process, program, WAIT};

#[tokio::test(start_paused = true)]
async fn the_heat_is_read_from_the_controller_on_while_cutting_and_off_after_the_safe_stop() {
    let p = program(300);
    let (sim, client) = in_process(SimConfig::default(), FlowControl::CharacterCounting).await;
    assert!(
        matches!(client.heat_state().await, HeatState::Off { .. }),
        "a fresh controller is cold"
    );
    let streamer = {
        let (client, p) = (client.clone(), p.clone());
        tokio::spawn(async move { client.stream(&p).await })
    };
    sim.wait_for(WAIT, |s| s.state == MachineState::Run && s.spindle_on)
        .await
        .expect("cutting");
    let heat = client.heat_state().await;
    assert!(
        matches!(&heat, HeatState::On { evidence } if evidence.contains("$G M3")),
        "{heat}"
    );
    client.abort().await.unwrap();
    let stop = streamer.await.unwrap().unwrap_err().safe_stop.unwrap();
    assert!(stop.heat.is_confirmed_off(), "{}", stop.summary());
    assert!(
        stop.summary().contains("heat off confirmed ($G M5"),
        "{}",
        stop.summary()
    );
    assert!(!sim.snapshot().spindle_on);
}

#[tokio::test(start_paused = true)]
async fn a_stale_ok_after_a_reset_is_not_taken_for_the_next_commands_answer() {
    // 40 ms each way: the `ok`s of lines GRBL took just before the reset are still on the wire
    // when the reset goes out.
    let sim_cfg = SimConfig {
        latency_s: 0.04,
        ..SimConfig::default()
    };
    let p = program(300);
    let (sim, client) = in_process(sim_cfg, FlowControl::CharacterCounting).await;
    let streamer = {
        let (client, p) = (client.clone(), p.clone());
        tokio::spawn(async move { client.stream(&p).await })
    };
    sim.wait_for(WAIT, |s| s.state == MachineState::Run && s.executed > 20)
        .await
        .expect("cutting");
    client.soft_reset().await.unwrap();
    // At once, without waiting for the banner: only the controller's answer to this very line
    // may complete it.
    client.command("M5").await.expect("M5 answered");
    assert_eq!(
        sim.executed_lines().last().map(String::as_str),
        Some("M5"),
        "when the client says M5 is acknowledged, the controller has taken it"
    );
    assert!(!sim.snapshot().spindle_on);
    let _ = streamer.await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn a_line_longer_than_the_rx_buffer_is_refused_before_anything_is_sent() {
    // A board with a 64-byte RX buffer (63 usable): a 70-byte line could never be sent under
    // character counting, and the stream would stall on it mid-program.
    let mut text = String::from("G21 G90\nM3 S100\n");
    for i in 0..10 {
        text += &format!("G1 X{i} Y0 F600\n");
    }
    text += &format!("G1 X1.{} Y1 F600\nM5\n", "0".repeat(55));
    let program = Program::parse(&text, CleanOptions::default()).unwrap();
    let sim = cell_grbl::sim::start(SimConfig {
        rx_buffer_bytes: 64,
        ..SimConfig::default()
    });
    let client = GrblClient::connect(
        sim.connector(),
        ClientConfig {
            rx_buffer_bytes: 64,
            ..ClientConfig::default()
        },
    )
    .await
    .unwrap();
    let err = client.stream(&program).await.unwrap_err();
    match &err.fault {
        Fault::LineTooLong {
            line,
            bytes,
            budget,
        } => {
            assert_eq!((*line, *budget), (13, 63));
            assert!(*bytes > 63);
        }
        other => panic!("{other}"),
    }
    assert!(err.safe_stop.is_none(), "nothing was sent, nothing to stop");
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert!(
        sim.executed_lines().is_empty(),
        "not a line of the program ran"
    );
}

#[tokio::test(start_paused = true)]
async fn a_link_that_does_not_come_back_leaves_the_heat_state_unknown_and_says_so() {
    let p = program(300);
    let sim_cfg = dropping_at(60);
    let sim = cell_grbl::sim::start(sim_cfg);
    // The cable is cut at the drop: every later connection attempt fails.
    let cut = Arc::new(CutAfterFirst {
        inner: sim.connector(),
        used: AtomicBool::new(false),
    });
    let client = GrblClient::connect(
        cut,
        ClientConfig {
            reconnect_attempts: 3,
            ..ClientConfig::default()
        },
    )
    .await
    .unwrap();
    let err = client.stream(&p).await.unwrap_err();
    assert!(matches!(err.fault, Fault::LinkLost(_)), "{err}");
    let stop = client.reconnect_and_stop().await;
    assert!(
        matches!(&stop.heat, HeatState::Unknown { why } if why.contains("did not come back")),
        "{}",
        stop.summary()
    );
    assert!(
        stop.summary().contains("heat state unknown"),
        "{}",
        stop.summary()
    );
}

#[tokio::test(start_paused = true)]
async fn after_a_drop_the_first_byte_on_the_new_link_is_the_feed_hold() {
    let p = program(300);
    let sim_cfg = dropping_at(60);
    let (sim, client) = in_process(sim_cfg, FlowControl::CharacterCounting).await;
    let err = client.stream(&p).await.unwrap_err();
    assert!(matches!(err.fault, Fault::LinkLost(_)), "{err}");
    let stop = client.reconnect_and_stop().await;
    assert!(stop.heat.is_confirmed_off(), "{}", stop.summary());
    assert_eq!(
        stop.sent.first().map(String::as_str),
        Some("! (first byte on the new link)")
    );
    assert!(!sim.snapshot().spindle_on);
    assert!(matches!(
        sim.snapshot().state,
        MachineState::Idle | MachineState::Alarm
    ));
}

#[tokio::test(start_paused = true)]
async fn the_rx_buffer_a_controller_reports_is_the_budget() {
    let sim = cell_grbl::sim::start(SimConfig {
        rx_buffer_bytes: 1024,
        ..SimConfig::default()
    });
    let client = GrblClient::connect(
        sim.connector(),
        ClientConfig {
            detect_rx_buffer: true,
            ..ClientConfig::default()
        },
    )
    .await
    .unwrap();
    assert_eq!(client.rx_budget(), 1023, "from $I's [OPT:…,1024]");
    let fixed = GrblClient::connect(sim.connector(), ClientConfig::default())
        .await
        .unwrap();
    assert_eq!(
        fixed.rx_budget(),
        127,
        "the configured 128 without detection"
    );
}

/// A simulator whose link drops when G-code line `line` arrives.
fn dropping_at(line: u64) -> SimConfig {
    SimConfig {
        faults: Faults {
            drop_at_lines: vec![line],
            ..Faults::default()
        },
        ..SimConfig::default()
    }
}

/// A link whose cable is cut after the first connection.
struct CutAfterFirst {
    inner: Arc<dyn Connect>,
    used: AtomicBool,
}

impl Connect for CutAfterFirst {
    fn connect(&self) -> ConnectFuture<'_> {
        if self.used.swap(true, Ordering::SeqCst) {
            return Box::pin(async {
                Err(std::io::Error::new(
                    std::io::ErrorKind::ConnectionRefused,
                    "cable cut",
                ))
            });
        }
        self.inner.connect()
    }

    fn describe(&self) -> String {
        "a cut cable".into()
    }
}

#[tokio::test(start_paused = true)]
async fn a_controller_that_resets_mid_program_is_recognised_by_its_banner_and_stopped() {
    use cell_grbl::firmware::Firmware;
    use cell_grbl::sim::SimFirmware;
    for (flavour, firmware) in [
        (SimFirmware::Grbl11h, Firmware::Grbl),
        (SimFirmware::GrblHal, Firmware::GrblHal),
        (SimFirmware::FluidNc, Firmware::FluidNc),
    ] {
        let p = program(300);
        let sim_cfg = SimConfig {
            faults: Faults {
                reset_at_line: Some(60),
                ..Faults::default()
            },
            ..SimConfig::for_firmware(flavour)
        };
        let (sim, client) = in_process(sim_cfg, FlowControl::CharacterCounting).await;
        // Without a banner on reset the stream would wait for answers that never come.
        let err = tokio::time::timeout(WAIT, client.stream(&p))
            .await
            .unwrap_or_else(|_| panic!("{flavour:?}: the stream hangs after the reset"))
            .unwrap_err();
        assert_eq!(err.fault, Fault::UnexpectedReset, "{flavour:?}: {err}");
        assert_eq!(client.progress().borrow().firmware, Some(firmware));
        let stop = err.safe_stop.expect("the safe stop ran");
        assert!(
            stop.heat.is_confirmed_off(),
            "{flavour:?}: {}",
            stop.summary()
        );
        assert!(!sim.snapshot().spindle_on, "{flavour:?}");
    }
}

#[tokio::test(start_paused = true)]
async fn a_late_ok_on_a_new_link_is_not_taken_for_a_line_of_the_resumed_run() {
    let p = program(300);
    let sim = cell_grbl::sim::start(dropping_at(60));
    // A USB-serial adapter that still held two `ok`s from the old link hands them out first on
    // the new one.
    let link = Arc::new(StaleBytesOnReconnect {
        inner: sim.connector(),
        connections: std::sync::atomic::AtomicU32::new(0),
        stale: b"ok\r\nok\r\n",
    });
    let client = GrblClient::connect(link, ClientConfig::default())
        .await
        .unwrap();
    let err = client.stream(&p).await.unwrap_err();
    assert!(matches!(err.fault, Fault::LinkLost(_)), "{err}");
    let acked = err.last_acked_line.expect("some lines were acknowledged");
    client.reconnect().await.expect("the link is back");
    // Resume after the last acknowledged line: if a stale `ok` answered one of the resumed
    // lines, the client would count it sent and acknowledged twice over and the accounting
    // (and the next resume) would skip a line.
    let next = p.lines()[p.index_of_line(acked).unwrap() + 1].number;
    let report = client.stream_from(&p, next).await.expect("the rest runs");
    assert_eq!(report.last_line, p.lines().last().unwrap().number);
    sim.wait_for(WAIT, |s| {
        s.state == MachineState::Idle && s.planner_used == 0
    })
    .await
    .unwrap();
    assert_eq!(
        sim.executed_lines(),
        common::texts(&p),
        "every line ran once, in order"
    );
}

/// A link that, from the second connection on, first delivers `stale` bytes (answers from
/// before the drop that a serial adapter still buffered).
struct StaleBytesOnReconnect {
    inner: Arc<dyn Connect>,
    connections: std::sync::atomic::AtomicU32,
    stale: &'static [u8],
}

impl Connect for StaleBytesOnReconnect {
    fn connect(&self) -> ConnectFuture<'_> {
        let n = self.connections.fetch_add(1, Ordering::SeqCst);
        Box::pin(async move {
            let link = self.inner.connect().await?;
            if n == 0 {
                return Ok(link);
            }
            let (read, write) = tokio::io::split(link);
            let read = tokio::io::AsyncReadExt::chain(self.stale, read);
            Ok(Box::new(tokio::io::join(read, write)) as cell_grbl::transport::BoxedTransport)
        })
    }

    fn describe(&self) -> String {
        "a serial adapter with stale bytes".into()
    }
}
