//! Heat-map transport benchmark: 1024×1024 f32 frames (4 MiB), DDS vs iceoryx2.
//!
//! `cargo bench -p cell_runtime --bench heatmap_transport` (add `-- --frames N` to change the
//! count). Three transports, each measured the same two ways, in one process with one DDS
//! participant per side (DDS still goes through UDP on loopback):
//! - **throughput**: the publisher sends as fast as it can; frames/s counted at the receiver,
//!   with the loss (heat maps are best-effort, keep-last);
//! - **latency**: one frame in flight at a time; send-to-receive time, p50 and p99.
//!
//! Transports:
//! - `dds`: the typed `Publisher<HeatMap>` with the fast path off (CDR over RTPS/UDP);
//! - `iceoryx2 typed`: the same typed API with the fast path on (CDR copied into shared memory
//!   and decoded into a `HeatMap` on arrival);
//! - `iceoryx2 zero-copy`: the raw fast path: the producer writes the CDR frame straight into a
//!   shared-memory loan, the consumer reads it in place.

use std::{
    sync::{
        atomic::{AtomicBool, AtomicU64, Ordering},
        Arc,
    },
    time::{Duration, Instant},
};

use cell_msgs::{geometry_msgs::Point, std_msgs::Header, HeatMap, RosMessage};
use cell_runtime::{
    fastpath::{now_ns, FastPath},
    CellNode, FastPathMode, NodeSetup, QosPreset,
};

const SIDE: u32 = 1024;

fn frame(index: u32) -> HeatMap {
    HeatMap {
        header: Header::default(),
        quantity: "bench".into(),
        unit: "K".into(),
        width: SIDE,
        height: SIDE,
        cell_width_mm: 1.0,
        cell_height_mm: 1.0,
        origin: Point::default(),
        threshold: 573.0,
        data: vec![index as f32; (SIDE * SIDE) as usize],
    }
}

fn stamp_now(h: &mut Header) {
    let ns = now_ns();
    h.stamp.sec = (ns / 1_000_000_000) as i32;
    h.stamp.nanosec = (ns % 1_000_000_000) as u32;
}

fn stamp_ns(h: &Header) -> u64 {
    h.stamp.sec as u64 * 1_000_000_000 + h.stamp.nanosec as u64
}

struct Figures {
    name: &'static str,
    fps: f64,
    loss: f64,
    p50_us: f64,
    p99_us: f64,
    samples: usize,
}

fn percentile(sorted: &[u64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i] as f64 / 1000.0
}

fn figures(
    name: &'static str,
    sent: usize,
    received: usize,
    elapsed: Duration,
    mut lat_ns: Vec<u64>,
) -> Figures {
    lat_ns.sort_unstable();
    Figures {
        name,
        fps: received as f64 / elapsed.as_secs_f64(),
        loss: 1.0 - received as f64 / sent as f64,
        p50_us: percentile(&lat_ns, 0.50),
        p99_us: percentile(&lat_ns, 0.99),
        samples: lat_ns.len(),
    }
}

/// The typed API, over DDS or the fast path.
async fn typed(name: &'static str, fast_path: bool, domain: u16, frames: usize) -> Figures {
    let mode = if fast_path {
        FastPathMode::Auto
    } else {
        FastPathMode::Off
    };
    let make = |n: &str| {
        let mut s = NodeSetup::local(n, domain);
        s.fast_path = mode;
        CellNode::new(s).expect("node")
    };
    let (talker, listener) = (make("bench_talker"), make("bench_listener"));
    let mut sub = listener
        .subscriber::<HeatMap>("/bench/heat", QosPreset::Stream)
        .unwrap();
    let publisher = talker
        .publisher::<HeatMap>("/bench/heat", QosPreset::Stream)
        .unwrap();
    assert!(
        publisher
            .wait_for_subscribers(1, Duration::from_secs(30))
            .await,
        "no subscriber"
    );
    // Warm up until frames flow (DDS discovery, shared-memory segment growth).
    let template = frame(1);
    loop {
        publisher.publish(template.clone()).await.unwrap();
        if tokio::time::timeout(Duration::from_millis(200), sub.recv())
            .await
            .is_ok()
        {
            break;
        }
    }
    while tokio::time::timeout(Duration::from_millis(200), sub.recv())
        .await
        .is_ok()
    {}

    // Throughput: send flat out, count at the receiver.
    let received = Arc::new(AtomicU64::new(0));
    let last = Arc::new(AtomicU64::new(0));
    let counter = {
        let (received, last) = (received.clone(), last.clone());
        tokio::spawn(async move {
            while let Ok(Some(_)) = tokio::time::timeout(Duration::from_secs(2), sub.recv()).await {
                received.fetch_add(1, Ordering::Relaxed);
                last.store(now_ns(), Ordering::Relaxed);
            }
            sub
        })
    };
    let start_ns = now_ns();
    for _ in 0..frames {
        publisher.publish(template.clone()).await.unwrap();
    }
    let mut sub = counter.await.unwrap();
    let got = received.load(Ordering::Relaxed) as usize;
    let elapsed =
        Duration::from_nanos(last.load(Ordering::Relaxed).saturating_sub(start_ns).max(1));

    // Latency: one frame in flight.
    let mut lat = Vec::with_capacity(frames);
    for _ in 0..frames {
        let mut f = template.clone();
        stamp_now(&mut f.header);
        publisher.publish(f).await.unwrap();
        if let Ok(Some(r)) = tokio::time::timeout(Duration::from_secs(1), sub.recv()).await {
            lat.push(now_ns().saturating_sub(stamp_ns(&r.message.header)));
        }
    }
    figures(name, frames, got, elapsed, lat)
}

/// The raw fast path: frames written into and read from shared memory in place.
fn zero_copy(domain: u16, frames: usize) -> Figures {
    let fp = FastPath::open(domain).expect("fast path");
    let topic = "/bench/heat_zero_copy";
    let ros_type = "cell_msgs/msg/HeatMap";
    let publisher = fp.publisher(topic, ros_type, [1; 16]).unwrap();
    let subscriber = fp.subscriber(topic, ros_type).unwrap();

    // A HeatMap's CDR is its fixed prefix, the data length, then the floats: encode the prefix
    // once and patch the length, then producers write floats straight into the loan.
    let mut empty = frame(0);
    empty.data.clear();
    let mut prefix = cell_msgs::to_cdr(&empty).unwrap();
    let n = (SIDE * SIDE) as usize;
    let len_at = prefix.len() - 4;
    prefix[len_at..].copy_from_slice(&(n as u32).to_le_bytes());
    let frame_len = prefix.len() + 4 * n;

    let stop = Arc::new(AtomicBool::new(false));
    let (tx, rx) = std::sync::mpsc::channel::<(u64, u64)>(); // (sequence, latency ns)
    let reader = {
        let stop = stop.clone();
        let prefix_len = prefix.len();
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                match subscriber.try_receive().unwrap() {
                    Some(frame) => {
                        let latency = now_ns().saturating_sub(frame.header().sent_at_ns);
                        // Read in place: the first and last float, no copy.
                        let bytes = frame.bytes();
                        assert_eq!(bytes.len(), frame_len);
                        let first = f32::from_le_bytes(
                            bytes[prefix_len..prefix_len + 4].try_into().unwrap(),
                        );
                        let last = f32::from_le_bytes(bytes[bytes.len() - 4..].try_into().unwrap());
                        assert_eq!(first, last);
                        let _ = tx.send((frame.header().sequence, latency));
                    }
                    None => std::hint::spin_loop(),
                }
            }
        })
    };
    let send_one = |value: f32| {
        let mut loan = publisher.loan(frame_len).unwrap();
        let bytes = loan.bytes_mut();
        bytes[..prefix.len()].copy_from_slice(&prefix);
        for chunk in bytes[prefix.len()..].chunks_exact_mut(4) {
            chunk.copy_from_slice(&value.to_le_bytes());
        }
        publisher.send(loan).unwrap();
    };
    // Check once that what travels is a valid HeatMap.
    {
        let check = fp.subscriber(topic, ros_type).unwrap();
        send_one(42.0);
        let f = check.try_receive().unwrap().expect("frame");
        let decoded: HeatMap =
            cell_msgs::from_cdr(f.bytes()).expect("zero-copy frame is valid CDR");
        assert!(decoded.data.len() == n && decoded.data.iter().all(|v| *v == 42.0));
    }
    std::thread::sleep(Duration::from_millis(100));
    while rx.try_recv().is_ok() {}

    let start = Instant::now();
    for i in 0..frames {
        send_one(i as f32);
    }
    let mut got = 0;
    let mut last_at = start;
    while rx.recv_timeout(Duration::from_millis(500)).is_ok() {
        got += 1;
        last_at = Instant::now();
    }
    let elapsed = last_at - start;

    let mut lat = Vec::with_capacity(frames);
    for i in 0..frames {
        send_one(i as f32);
        if let Ok((_, ns)) = rx.recv_timeout(Duration::from_secs(1)) {
            lat.push(ns);
        }
    }
    stop.store(true, Ordering::Relaxed);
    reader.join().unwrap();
    figures("iceoryx2 zero-copy", frames, got, elapsed, lat)
}

fn main() {
    cell_runtime::logging::init(Some("warn"));
    let mut frames = 200usize;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--frames" {
            frames = args
                .next()
                .and_then(|v| v.parse().ok())
                .expect("--frames N");
        }
    }
    let domain = 150 + (std::process::id() % 50) as u16;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    println!(
        "heat-map transport: {SIDE}x{SIDE} f32 frames ({:.1} MiB), {frames} frames per figure, one process, loopback",
        (SIDE * SIDE * 4) as f64 / (1024.0 * 1024.0)
    );
    let sample = frame(3);
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let bytes = cell_msgs::to_cdr(&sample).unwrap();
    let serde_encode = ms(t);
    let t = Instant::now();
    let decoded: HeatMap = cell_msgs::from_cdr(&bytes).unwrap();
    let serde_decode = ms(t);
    let t = Instant::now();
    let bulk = sample.encode().unwrap();
    let bulk_encode = ms(t);
    let t = Instant::now();
    let bulk_decoded = HeatMap::decode(&bulk).unwrap();
    let bulk_decode = ms(t);
    assert!(bulk == bytes && bulk_decoded == decoded);
    println!(
        "CDR per frame: serde encode {serde_encode:.2} ms, decode {serde_decode:.2} ms (DDS path); \
         bulk encode {bulk_encode:.2} ms, decode {bulk_decode:.2} ms (iceoryx2 typed path)"
    );
    let results = vec![
        rt.block_on(typed("dds", false, domain, frames)),
        rt.block_on(typed("iceoryx2 typed", true, domain + 1, frames)),
        zero_copy(domain + 2, frames),
    ];
    println!(
        "{:<20} {:>10} {:>8} {:>12} {:>12} {:>8}",
        "transport", "frames/s", "loss", "p50 µs", "p99 µs", "samples"
    );
    for r in &results {
        println!(
            "{:<20} {:>10.1} {:>7.1}% {:>12.1} {:>12.1} {:>8}",
            r.name,
            r.fps,
            100.0 * r.loss,
            r.p50_us,
            r.p99_us,
            r.samples
        );
    }
    let zc = &results[2];
    println!(
        "target for iceoryx2 on one host: >= 1000 frames/s and p99 < 100 µs: {}",
        if zc.fps >= 1000.0 && zc.p99_us < 100.0 {
            "met"
        } else {
            "NOT met"
        }
    );
}
