//! The client against the simulator over TCP: streaming through line noise (resends), the safe
//! stop in the middle of an `M109` wait confirmed by `M105`, a kill seen as a kill.

use std::sync::Arc;
use std::time::Duration;

use cell_grbl::transport::{Connect, Endpoint};
use cell_marlin::client::{ClientConfig, LinkError, LinkState, MarlinLink, Sent};
use cell_marlin::sim::{self, Faults, SimConfig};
use tokio::sync::watch;

async fn setup(cfg: SimConfig) -> (sim::SimHandle, MarlinLink, watch::Receiver<LinkState>) {
    let sim = sim::start(cfg);
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let connector: Arc<dyn Connect> = Arc::new(Endpoint::Tcp(addr.to_string()));
    let (tx, rx) = watch::channel(LinkState::default());
    let link = MarlinLink::connect(
        &connector,
        ClientConfig {
            command_timeout: Duration::from_secs(2),
            ..ClientConfig::default()
        },
        tx,
    )
    .await
    .unwrap();
    (sim, link, rx)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn streams_through_line_noise_with_resends() {
    // Received lines 3, 10 and 11 (M110 is line 1) get a flipped bit.
    let (sim, mut link, state) = setup(SimConfig {
        time_scale: 50.0,
        faults: Faults {
            corrupt_at_lines: vec![3, 10, 11],
            ..Faults::default()
        },
        ..SimConfig::default()
    })
    .await;
    let program: Vec<String> = (0..40)
        .map(|i| format!("G1 X{} Y{} F6000", i % 7 * 10, i % 5 * 10))
        .collect();
    for l in &program {
        link.send(l).await.unwrap();
    }
    link.send("M400").await.unwrap();
    let s = state.borrow().clone();
    assert_eq!(s.resent, 3, "{s:?}");
    let executed: Vec<String> = sim
        .executed()
        .into_iter()
        .filter(|c| c.starts_with("G1"))
        .collect();
    assert_eq!(executed, program, "every line ran once, in order");
    assert_eq!(sim.snapshot().planned_blocks, 0);
    let pos = link.position().await.unwrap();
    assert_eq!(pos[0], ('X', 40.0));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn heat_off_in_the_middle_of_m109_is_confirmed_by_m105() {
    let (sim, mut link, _state) = setup(SimConfig {
        time_scale: 10.0,
        ..SimConfig::default()
    })
    .await;
    link.send("M140 S60").await.unwrap();
    let (stop_tx, mut stop) = watch::channel(false);
    let stopper = tokio::spawn(async move {
        tokio::time::sleep(Duration::from_millis(800)).await;
        stop_tx.send(true).unwrap();
    });
    let sent = link.send_until("M109 S210", &mut stop).await.unwrap();
    assert_eq!(sent, Sent::Interrupted);
    stopper.await.unwrap();
    let before = sim.snapshot();
    assert_eq!(before.hotend.target, 210.0, "still heating at the stop");
    let t = link.heat_off().await.unwrap();
    assert!(t.targets_off(), "{t}");
    let after = sim.snapshot();
    assert_eq!((after.hotend.target, after.bed.target), (0.0, 0.0));
    assert!(
        after.halted.is_none(),
        "M108 ended the wait; no kill needed"
    );
    assert!(
        after.now_s - before.now_s < 15.0,
        "M108 ends the wait at once, not after heating: {} s",
        after.now_s - before.now_s
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_kill_is_reported_with_its_reason() {
    let (_sim, mut link, state) = setup(SimConfig {
        time_scale: 50.0,
        faults: Faults {
            thermistor_open_at_line: Some(3),
            ..Faults::default()
        },
        ..SimConfig::default()
    })
    .await;
    link.send("M104 S200").await.unwrap();
    let e = link.send("G4 S5").await.unwrap_err();
    assert!(
        matches!(&e, LinkError::Killed(why) if why.contains("MINTEMP")),
        "{e:?}"
    );
    assert!(state.borrow().killed.is_some());
    assert!(matches!(
        link.send("M105").await,
        Err(LinkError::Timeout(_))
    ));
}
