//! Record-and-replay benchmark: the `recorder` node writing a bag from a live publisher, then
//! the replayer playing it back with its recorded timing to a subscriber, over real DDS on
//! loopback (and the iceoryx2 fast path for heat maps), one process, one participant per node.
//!
//! `cargo bench -p replayer --bench record_replay [-- --seconds S --heat-seconds S]`
//!
//! Two streams:
//! - `MachineStatus` at 1 kHz (reliable, volatile: the `Status` preset) for `--seconds` (10);
//! - 1024×1024 f32 `HeatMap`s (4 MiB) at 30 Hz (best-effort: the `Stream` preset, over shared
//!   memory on one host) for `--heat-seconds` (5).
//!
//! Figures per stream: record throughput (CDR bytes recorded / publishing time) and messages
//! lost between publisher and bag; replay throughput (CDR bytes received / replay time) and
//! messages lost between replayer and subscriber; and the replay timing error, the time a
//! message reached the subscriber minus the time the replay schedule said it was due (the
//! replayer's own lateness plus the transport's latency), p50 / p99 / max.
//!
//! Each message carries its index (`acked_line`, the heat map's `frame_id`), so losses are
//! counted exactly and each arrival is matched to its own scheduled time.

use std::collections::HashMap;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use cell_bag::BagReader;
use cell_msgs::{HeatMap, MachineStatus, RosMessage};
use cell_runtime::node::ParticipantGuard;
use cell_runtime::{CellNode, FastPathMode, NodeSetup, QosPreset};
use recorder::RecorderParams;
use replayer::{Replay, ReplayerParams};

/// Domains far from those the tests pick (100..=227), so a test run elsewhere does not interfere.
const DOMAINS: [u16; 4] = [229, 230, 231, 232];

/// One stream to record and replay.
struct Spec<T> {
    name: &'static str,
    topic: &'static str,
    qos: QosPreset,
    hz: f64,
    count: u64,
    make: Box<dyn Fn(u64) -> T + Send + Sync>,
    index: fn(&T) -> Option<u64>,
}

/// The figures of one stream.
struct Row {
    name: &'static str,
    count: u64,
    bytes_per_message: usize,
    record_mb_s: f64,
    published: u64,
    recorded: u64,
    bag_mb: f64,
    replay_mb_s: f64,
    replayed: u64,
    received: u64,
    error_ms: [f64; 3],
}

/// Keeps every node's DDS participant until the runtime (and with it each graph spinner) is
/// gone, as `run_node` does, so dropping the nodes logs no errors.
static PARTICIPANTS: Mutex<Vec<ParticipantGuard>> = Mutex::new(Vec::new());

fn node(name: &str, domain: u16) -> (CellNode, cell_runtime::Shutdown) {
    let mut setup = NodeSetup::local(name, domain);
    setup.fast_path = FastPathMode::Auto;
    let shutdown = setup.shutdown.clone();
    let node = CellNode::new(setup).expect("node comes up");
    PARTICIPANTS.lock().unwrap().push(node.participant_guard());
    (node, shutdown)
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

async fn measure<T: RosMessage>(
    spec: &Spec<T>,
    dir: &Path,
    domains: (u16, u16),
) -> anyhow::Result<Row> {
    let bytes_per_message = (spec.make)(0).encode()?.len();
    let bag = dir.join(spec.name);

    // Record: a publisher at the stream's rate, the recorder node writing the bag.
    let (recorder, recorder_stop) = node("recorder", domains.0);
    let recording = tokio::spawn(recorder::run(
        recorder,
        RecorderParams {
            output: bag.display().to_string(),
            topics: vec!["/bench/.*".into()],
            discover_every_s: 0.1,
            ..RecorderParams::default()
        },
    ));
    let (source, _) = node("source", domains.0);
    let publisher = source.publisher::<T>(spec.topic, spec.qos)?;
    anyhow::ensure!(
        publisher
            .wait_for_subscribers(1, Duration::from_secs(30))
            .await,
        "the recorder never subscribed to {}",
        spec.topic
    );
    tokio::time::sleep(Duration::from_secs(1)).await;
    let period = Duration::from_secs_f64(1.0 / spec.hz);
    let start = tokio::time::Instant::now();
    let mut published = 0;
    for i in 0..spec.count {
        tokio::time::sleep_until(start + period * i as u32).await;
        publisher.publish((spec.make)(i)).await?;
        published += 1;
    }
    let publishing = start.elapsed();
    tokio::time::sleep(Duration::from_millis(1500)).await;
    recorder_stop.trigger();
    recording.await??;
    drop(publisher);
    drop(source);

    // What the bag holds, in replay order.
    let mut reader = BagReader::open(&bag)?;
    let bag_mb = reader.info().size as f64 / 1e6;
    let mut order = Vec::new();
    let mut recorded_bytes = 0usize;
    for m in reader.messages() {
        let m = m?;
        recorded_bytes += m.data.len();
        if let Some(i) = (spec.index)(&m.decode::<T>()?) {
            order.push(i);
        }
    }
    let recorded = {
        let mut unique = order.clone();
        unique.sort_unstable();
        unique.dedup();
        unique.len() as u64
    };

    // Replay: the replayer on a fresh domain, a subscriber noting arrival times.
    let (sink, _) = node("sink", domains.1);
    let mut sub = sink.subscriber::<T>(spec.topic, spec.qos)?;
    let arrivals: Arc<Mutex<Vec<(u64, Instant)>>> = Arc::default();
    let arrived = arrivals.clone();
    let index = spec.index;
    let receiving = tokio::spawn(async move {
        while let Some(r) = sub.recv().await {
            if let Some(i) = index(&r.message) {
                arrived.lock().unwrap().push((i, Instant::now()));
            }
        }
    });
    let (replayer, _) = node("replayer", domains.1);
    let mut scheduled: Vec<Instant> = Vec::new();
    let summary = Replay::open(&ReplayerParams {
        bag: bag.display().to_string(),
        wait_for_subscribers_s: 30.0,
        linger_s: 1.5,
        progress_every_s: 60.0,
        ..ReplayerParams::default()
    })?
    .run(&replayer, |p| scheduled.extend(p.scheduled_at))
    .await?;
    receiving.abort();
    let arrivals = arrivals.lock().unwrap().clone();
    let due: HashMap<u64, Instant> = order.iter().copied().zip(scheduled).collect();
    let mut errors: Vec<f64> = arrivals
        .iter()
        .filter_map(|(i, at)| Some(at.saturating_duration_since(*due.get(i)?).as_secs_f64() * 1e3))
        .collect();
    errors.sort_by(f64::total_cmp);
    let received = {
        let mut unique: Vec<u64> = arrivals.iter().map(|(i, _)| *i).collect();
        unique.sort_unstable();
        unique.dedup();
        unique.len() as u64
    };
    let replay_span = match (due.values().min(), arrivals.iter().map(|(_, t)| *t).max()) {
        (Some(first), Some(last)) => last.saturating_duration_since(*first),
        _ => Duration::ZERO,
    };
    let received_bytes = received as f64 * recorded_bytes as f64 / order.len().max(1) as f64;
    Ok(Row {
        name: spec.name,
        count: spec.count,
        bytes_per_message,
        record_mb_s: recorded_bytes as f64 / 1e6 / publishing.as_secs_f64(),
        published,
        recorded,
        bag_mb,
        replay_mb_s: received_bytes / 1e6 / replay_span.as_secs_f64().max(1e-9),
        replayed: summary.published,
        received,
        error_ms: [
            percentile(&errors, 0.5),
            percentile(&errors, 0.99),
            errors.last().copied().unwrap_or(f64::NAN),
        ],
    })
}

/// A smooth 1024×1024 temperature field with a hot spot that moves from frame to frame
/// (compresses like a real one, unlike a constant frame).
fn heat_frames(n: usize) -> Vec<HeatMap> {
    const SIDE: u32 = 1024;
    (0..n)
        .map(|k| {
            let (cx, cy) = (200.0 + 60.0 * k as f32, 500.0 + 20.0 * k as f32);
            let data = (0..SIDE * SIDE)
                .map(|i| {
                    let (x, y) = ((i % SIDE) as f32, (i / SIDE) as f32);
                    let r2 = (x - cx).powi(2) + (y - cy).powi(2);
                    293.0 + 400.0 * (-r2 / 5000.0).exp()
                })
                .collect();
            HeatMap::new("sheet_temperature", "K", SIDE, SIDE, data).expect("sized")
        })
        .collect()
}

fn arg(name: &str, default: f64) -> f64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() -> anyhow::Result<()> {
    cell_runtime::logging::init(Some("warn"));
    let seconds = arg("--seconds", 10.0);
    let heat_seconds = arg("--heat-seconds", 5.0);
    let dir = tempfile::tempdir()?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let rows = runtime.block_on(async {
        let status = Spec {
            name: "status_1khz",
            topic: "/bench/machine_status",
            qos: QosPreset::Status,
            hz: 1000.0,
            count: (seconds * 1000.0) as u64,
            make: Box::new(|i: u64| MachineStatus {
                machine_id: "bench".into(),
                state: MachineStatus::STATE_RUNNING,
                acked_line: i as u32,
                axis_names: vec!["X".into(), "Y".into(), "U".into(), "V".into()],
                axis_positions: vec![i as f64 * 0.01, 1.0, 2.0, 3.0],
                ..MachineStatus::default()
            }),
            index: |m: &MachineStatus| Some(u64::from(m.acked_line)),
        };
        let frames = Arc::new(heat_frames(8));
        let heat = Spec {
            name: "heat_map_30hz",
            topic: "/bench/heat",
            qos: QosPreset::Stream,
            hz: 30.0,
            count: (heat_seconds * 30.0) as u64,
            make: Box::new(move |i: u64| {
                let mut m = frames[i as usize % frames.len()].clone();
                m.header.frame_id = i.to_string();
                m
            }),
            index: |m: &HeatMap| m.header.frame_id.parse().ok(),
        };
        let a = measure(&status, dir.path(), (DOMAINS[0], DOMAINS[1])).await?;
        let b = measure(&heat, dir.path(), (DOMAINS[2], DOMAINS[3])).await?;
        anyhow::Ok(vec![a, b])
    })?;
    drop(runtime);
    PARTICIPANTS.lock().unwrap().clear();

    println!(
        "record and replay over DDS on loopback (heat maps over iceoryx2), one process; \
         {seconds} s of 1 kHz status, {heat_seconds} s of 30 Hz heat maps"
    );
    println!(
        "| stream | messages | bytes each | record MB/s | recorded / published | bag MB | replay MB/s | received / replayed | timing error p50 / p99 / max (ms) |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---|");
    for r in &rows {
        println!(
            "| {} | {} | {} | {:.2} | {} / {} | {:.1} | {:.2} | {} / {} | {:.2} / {:.2} / {:.2} |",
            r.name,
            r.count,
            r.bytes_per_message,
            r.record_mb_s,
            r.recorded,
            r.published,
            r.bag_mb,
            r.replay_mb_s,
            r.received,
            r.replayed,
            r.error_ms[0],
            r.error_ms[1],
            r.error_ms[2],
        );
    }
    Ok(())
}
