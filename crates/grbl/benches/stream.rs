//! Streaming throughput over a simulated 115 200 baud link (GRBL 1.1 simulator).
//!
//! `cargo bench -p cell_grbl --bench stream` streams a 100 000-line program with character
//! counting and with send-response and prints lines/s against the link's theoretical line rate
//! (11 520 bytes/s ÷ mean line length, `\n` included).
//!
//! Two link set-ups:
//! - in-process link under a paused tokio clock: simulated time only, so the figures are the
//!   protocol's own efficiency (optionally with a one-way USB-serial latency of 1 ms);
//! - TCP loopback on the real clock with the simulator at 10× real time: adds this host's
//!   scheduling and the 1 ms timer resolution (10 ms of simulated time per wake-up at most).
//!
//! Motion is not the bottleneck: the program's moves are 0.01-0.02 mm at 6000 mm/min
//! (0.1-0.2 ms each), far shorter than a line's 1.7 ms on the wire.

use std::sync::Arc;
use std::time::{Duration, Instant};

use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::sim::{self, Faults, SimConfig};
use cell_grbl::stream::{ClientConfig, FlowControl, GrblClient};
use cell_grbl::transport::Endpoint;

const LINES: usize = 100_000;
const BYTES_PER_S: f64 = 11_520.0;

fn program() -> Program {
    let mut s = String::with_capacity(LINES * 20);
    s += "G21 G90 G94 F6000\n";
    for i in 1..LINES {
        let x = 10.0 + (i % 2) as f64 * 0.01;
        let y = 20.0 + (i % 1000) as f64 * 0.001;
        s += &format!("G1 X{x:.3} Y{y:.3}\n");
    }
    Program::parse(&s, CleanOptions::default()).expect("valid program")
}

struct Row {
    flow: FlowControl,
    link: &'static str,
    sim_s: f64,
    wall_s: f64,
    overflow: bool,
    exact: bool,
}

async fn run(
    p: &Program,
    flow: FlowControl,
    link: &'static str,
    latency_s: f64,
    tcp: bool,
    scale: f64,
) -> Row {
    let sim = sim::start(SimConfig {
        time_scale: scale,
        latency_s,
        // Exact timing under the paused clock; the real clock needs the 1 ms slack.
        timer_slack: if tcp {
            Duration::from_millis(1)
        } else {
            Duration::ZERO
        },
        faults: Faults::default(),
        ..SimConfig::default()
    });
    let config = ClientConfig {
        flow,
        ..ClientConfig::default()
    };
    let client = if tcp {
        let addr = sim.listen_tcp("127.0.0.1:0").await.expect("listen");
        GrblClient::connect(Arc::new(Endpoint::Tcp(addr.to_string())), config).await
    } else {
        GrblClient::connect(sim.connector(), config).await
    }
    .expect("connect");
    let wall = Instant::now();
    let report = client.stream(p).await.expect("stream completes");
    let wall_s = wall.elapsed().as_secs_f64();
    let executed = sim.executed();
    Row {
        flow,
        link,
        sim_s: report.stream_time.as_secs_f64() * scale,
        wall_s,
        overflow: sim.overflowed(),
        exact: executed.len() == p.len()
            && executed
                .iter()
                .zip(p.lines())
                .all(|(e, l)| e.text == l.text),
    }
}

fn main() {
    let p = program();
    let mean = p.wire_bytes() as f64 / p.len() as f64;
    let theoretical = BYTES_PER_S / mean;
    println!(
        "grbl stream bench: {} lines, mean {:.2} bytes/line with \\n, link 115200 baud 8N1 = {} bytes/s, theoretical {:.1} lines/s",
        p.len(),
        mean,
        BYTES_PER_S,
        theoretical
    );
    let mut rows = Vec::new();
    let paused = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .expect("runtime");
    for flow in [FlowControl::CharacterCounting, FlowControl::SendResponse] {
        rows.push(paused.block_on(run(&p, flow, "in-process, virtual clock", 0.0, false, 1.0)));
        rows.push(paused.block_on(run(
            &p,
            flow,
            "in-process, virtual clock, 1 ms latency",
            0.001,
            false,
            1.0,
        )));
    }
    drop(paused);
    let real = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    for flow in [FlowControl::CharacterCounting, FlowControl::SendResponse] {
        rows.push(real.block_on(async {
            tokio::time::timeout(
                Duration::from_secs(120),
                run(
                    &p,
                    flow,
                    "TCP loopback, real clock, sim x10",
                    0.0,
                    true,
                    10.0,
                ),
            )
            .await
            .expect("finishes within 2 minutes")
        }));
    }
    println!();
    println!(
        "| flow control       | link                                    | sim time (s) | lines/s | % of theoretical | log == program | RX overflow | wall (s) |"
    );
    println!(
        "|--------------------|-----------------------------------------|-------------:|--------:|-----------------:|----------------|-------------|---------:|"
    );
    for r in &rows {
        let lps = p.len() as f64 / r.sim_s;
        println!(
            "| {:<18} | {:<39} | {:>12.1} | {:>7.1} | {:>15.1}% | {:<14} | {:<11} | {:>8.1} |",
            format!("{:?}", r.flow),
            r.link,
            r.sim_s,
            lps,
            100.0 * lps / theoretical,
            if r.exact { "yes" } else { "NO" },
            if r.overflow { "YES" } else { "no" },
            r.wall_s
        );
    }
    let cc = &rows[0];
    let pct = 100.0 * (p.len() as f64 / cc.sim_s) / theoretical;
    println!();
    println!(
        "target: >= 95% of the theoretical line rate with character counting: {:.1}% ({})",
        pct,
        if pct >= 95.0 { "met" } else { "NOT met" }
    );
}
