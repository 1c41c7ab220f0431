//! End to end: program → streamer → simulator, under a paused tokio clock (deterministic,
//! simulated time only), and over real TCP loopback and a real pty.

mod common;

use std::sync::Arc;
use std::time::Duration;

use cell_grbl::sim::{self, SimConfig};
use cell_grbl::stream::{FlowControl, GrblClient};
use cell_grbl::transport::Endpoint;
use common::*;

async fn run_in_process(flow: FlowControl) {
    let p = program(300);
    let (sim, client) = in_process(SimConfig::default(), flow).await;
    let report = client.stream(&p).await.expect("stream completes");
    assert_eq!(report.lines, p.len());
    assert_eq!(
        sim.executed_lines(),
        texts(&p),
        "executed log == program, line for line"
    );
    assert!(!sim.overflowed(), "RX buffer never overflowed");
    assert!(sim.rx_high_water() <= 127);
    let prog = client.progress().borrow().clone();
    assert_eq!(prog.last_acked_line, Some(p.lines().last().unwrap().number));
    assert_eq!(prog.lines_acked, p.len());
}

#[tokio::test(start_paused = true)]
async fn character_counting_in_process() {
    run_in_process(FlowControl::CharacterCounting).await;
}

#[tokio::test(start_paused = true)]
async fn send_response_in_process() {
    run_in_process(FlowControl::SendResponse).await;
}

async fn run_over(endpoint_of: impl FnOnce(&sim::SimHandle) -> Endpoint, flow: FlowControl) {
    // Real time: ten times faster than a real machine, generous timeouts, no timing asserts.
    let sim = sim::start(SimConfig {
        time_scale: 10.0,
        ..SimConfig::default()
    });
    let endpoint = endpoint_of(&sim);
    let client = GrblClient::connect(Arc::new(endpoint), client_config(flow))
        .await
        .expect("connect");
    let p = program(200);
    let report = tokio::time::timeout(Duration::from_secs(300), client.stream(&p))
        .await
        .expect("finishes")
        .expect("stream completes");
    assert_eq!(report.lines, p.len());
    assert_eq!(sim.executed_lines(), texts(&p));
    assert!(!sim.overflowed());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn character_counting_over_tcp() {
    run_over_tcp(FlowControl::CharacterCounting).await;
}

async fn run_over_tcp(flow: FlowControl) {
    let sim = sim::start(SimConfig {
        time_scale: 10.0,
        ..SimConfig::default()
    });
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let client = GrblClient::connect(
        Arc::new(Endpoint::Tcp(addr.to_string())),
        client_config(flow),
    )
    .await
    .expect("connect");
    let p = program(200);
    let report = tokio::time::timeout(Duration::from_secs(300), client.stream(&p))
        .await
        .expect("finishes")
        .expect("stream completes");
    assert_eq!(report.lines, p.len());
    assert_eq!(sim.executed_lines(), texts(&p));
    assert!(!sim.overflowed());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn send_response_over_tcp() {
    run_over_tcp(FlowControl::SendResponse).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn character_counting_over_pty() {
    run_over(
        |sim| Endpoint::Pty(sim.open_pty().expect("pty")),
        FlowControl::CharacterCounting,
    )
    .await;
}
