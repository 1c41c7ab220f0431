//! Issue 23: one DATA_FRAG announcing a sample of almost 4 GiB made the vendored rustdds
//! allocate (and zero) that size before any data arrived, so one datagram could crash any node.
//! Here a real `cell node emitter` process gets thousands of hostile DATA_FRAGs (RTPS 2.5
//! §9.4.5.3) on its own UDP sockets: it keeps running with bounded memory, logs the drops
//! (rate-limited), and a client that joins afterwards is still discovered and served.

mod common;

use std::net::UdpSocket;
use std::process::Command;
use std::time::Duration;

use cell_msgs::{EmitProgramRequest, EmitProgramResponse};
use common::node_process::NodeProcess;
use common::{fresh_domain, node, rectangle_cut, DELIVERY_TIMEOUT};

const CELL: &str = env!("CARGO_BIN_EXE_cell");

/// Built-in entity ids (RTPS 2.5 Table 9.2): the SEDP publications reader (reliable) and the
/// SPDP reader (best effort) exist in every participant, whatever its topics.
const SEDP_PUBLICATIONS_READER: [u8; 4] = [0, 0, 0x03, 0xC7];
const SEDP_PUBLICATIONS_WRITER: [u8; 4] = [0, 0, 0x03, 0xC2];
const SPDP_READER: [u8; 4] = [0, 0x01, 0x00, 0xC7];
const SPDP_WRITER: [u8; 4] = [0, 0x01, 0x00, 0xC2];

/// The sample size of the issue: the largest multiple of 16 below 4 GiB.
const HUGE: u32 = 0xFFFF_FFF0;
/// Just under the default cap (64 MiB) of the patched rustdds: accepted, so memory must follow
/// the bytes that arrived, not this size.
const UNDER_CAP: u32 = 63 << 20;
const FRAGMENT_SIZE: u16 = 1024;

/// What one hostile DATA_FRAG claims.
#[derive(Clone, Copy)]
struct Frag {
    source: [u8; 12],
    reader: [u8; 4],
    writer: [u8; 4],
    sn: u32,
    starting: u32,
    in_submessage: u16,
    fragment_size: u16,
    data_size: u32,
    payload: usize,
}

/// One RTPS message (header, RTPS 2.5 §9.4.4) holding one little-endian DATA_FRAG (§9.4.5.3).
fn message(f: &Frag) -> Vec<u8> {
    let mut body = Vec::new();
    body.extend(0u16.to_le_bytes()); // extraFlags
    body.extend(28u16.to_le_bytes()); // octetsToInlineQos: the fixed fields below
    body.extend(f.reader);
    body.extend(f.writer);
    body.extend(0i32.to_le_bytes()); // writerSN, high
    body.extend(f.sn.to_le_bytes()); // writerSN, low
    body.extend(f.starting.to_le_bytes());
    body.extend(f.in_submessage.to_le_bytes());
    body.extend(f.fragment_size.to_le_bytes());
    body.extend(f.data_size.to_le_bytes());
    body.resize(body.len() + f.payload, 0x5A);
    let mut m = b"RTPS".to_vec();
    m.extend([2, 5, 0x01, 0x0F]); // protocol 2.5, vendor id
    m.extend(f.source);
    m.extend([0x16, 0x01]); // DATA_FRAG, little endian
    m.extend(u16::try_from(body.len()).unwrap().to_le_bytes());
    m.extend(body);
    m
}

/// The hostile DATA_FRAGs sent to each port.
fn hostile_frags() -> Vec<Frag> {
    let mut frags = Vec::new();
    let readers = [
        (SEDP_PUBLICATIONS_READER, SEDP_PUBLICATIONS_WRITER),
        (SPDP_READER, SPDP_WRITER),
    ];
    for (reader, writer) in readers {
        let base = Frag {
            source: *b"bomb\0\0\0\0\0\0\0\x01",
            reader,
            writer,
            sn: 1,
            starting: 1,
            in_submessage: 1,
            fragment_size: FRAGMENT_SIZE,
            data_size: HUGE,
            payload: FRAGMENT_SIZE.into(),
        };
        let last_fragment = UNDER_CAP / u32::from(FRAGMENT_SIZE);
        for sn in 1..=1000 {
            // The message: the first fragment of a ~4 GiB sample, one per SN.
            frags.push(Frag { sn, ..base });
            // A sample under the cap, its last fragment first.
            frags.push(Frag {
                sn: 5000 + sn,
                starting: last_fragment,
                data_size: UNDER_CAP,
                ..base
            });
        }
        for sn in 1..=200 {
            // Malformed, under the size cap: fragment size 0, fragment number 0, a run past
            // the last fragment.
            let malformed = Frag {
                sn: 9000 + sn,
                data_size: UNDER_CAP,
                ..base
            };
            frags.push(Frag {
                fragment_size: 0,
                payload: 0,
                ..malformed
            });
            frags.push(Frag {
                starting: 0,
                ..malformed
            });
            frags.push(Frag {
                starting: last_fragment,
                in_submessage: 2,
                ..malformed
            });
        }
        for writer_no in 0..300u32 {
            // Ever new (forged) writers, each with one sample under the cap.
            let mut source = base.source;
            source[8..].copy_from_slice(&writer_no.to_be_bytes());
            frags.push(Frag {
                source,
                data_size: UNDER_CAP,
                ..base
            });
        }
    }
    frags
}

/// The IPv4 UDP ports process `pid` has bound: its socket inodes looked up in /proc/net/udp.
fn udp_ports(pid: u32) -> Vec<u16> {
    let inodes: Vec<String> = std::fs::read_dir(format!("/proc/{pid}/fd"))
        .unwrap()
        .filter_map(|fd| std::fs::read_link(fd.ok()?.path()).ok())
        .filter_map(|target| {
            let target = target.to_string_lossy().into_owned();
            Some(
                target
                    .strip_prefix("socket:[")?
                    .strip_suffix(']')?
                    .to_owned(),
            )
        })
        .collect();
    let table = std::fs::read_to_string(format!("/proc/{pid}/net/udp")).unwrap();
    let mut ports: Vec<u16> = table
        .lines()
        .skip(1)
        .filter_map(|line| {
            let cols: Vec<&str> = line.split_whitespace().collect();
            let port = cols.get(1)?.split(':').nth(1)?;
            inodes
                .contains(&cols.get(9)?.to_string())
                .then(|| u16::from_str_radix(port, 16).ok())?
        })
        .collect();
    ports.sort_unstable();
    ports.dedup();
    ports
}

/// A `/proc/<pid>/status` field in KiB (VmRSS: resident now, VmHWM: the peak).
fn status_kib(pid: u32, field: &str) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    status
        .lines()
        .find_map(|l| l.strip_prefix(field)?.strip_prefix(':'))
        .and_then(|v| v.trim().strip_suffix("kB")?.trim().parse().ok())
        .unwrap_or_else(|| panic!("{field} in {status}"))
}

fn start_emitter(domain: u16) -> NodeProcess {
    let mut command = Command::new(CELL);
    command
        .args(["node", "emitter", "--dds-network", "loopback"])
        .args(["--fast-path", "off", "--ros-args", "-p"])
        .arg("machine_profile:=grbl-xy")
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env_remove("RUST_LOG"); // the default filter: rustdds errors only
    NodeProcess::spawn("emitter", command)
}

async fn emit_through_a_new_client(domain: u16, name: &str) -> EmitProgramResponse {
    let client_node = node(name, domain, false);
    let client = client_node
        .service_client::<EmitProgramRequest, EmitProgramResponse>("/emit_program")
        .unwrap();
    assert!(
        client_node
            .wait_for_service("/emit_program", DELIVERY_TIMEOUT)
            .await,
        "{name}: emitter service never discovered"
    );
    let request = EmitProgramRequest {
        toolpath: rectangle_cut("after-bomb"),
        ..Default::default()
    };
    client
        .call(request, DELIVERY_TIMEOUT)
        .await
        .expect("request answered")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hostile_data_frags_leave_a_node_running_with_bounded_memory() {
    let domain = fresh_domain();
    let mut emitter = start_emitter(domain);
    let pid = emitter.id();

    // Up and serving before the attack.
    let before = emit_through_a_new_client(domain, "client_before").await;
    assert!(before.success, "{}", before.message);
    let ports = udp_ports(pid);
    assert!(!ports.is_empty(), "the emitter has no UDP socket");
    let rss_before = status_kib(pid, "VmRSS");

    let frags = hostile_frags();
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut sent = 0usize;
    for port in &ports {
        for (i, frag) in frags.iter().enumerate() {
            socket
                .send_to(&message(frag), ("127.0.0.1", *port))
                .unwrap();
            sent += 1;
            if i % 100 == 99 {
                // Paced, so that the node reads them rather than its socket dropping them.
                std::thread::sleep(Duration::from_millis(2));
            }
        }
    }
    tokio::time::sleep(Duration::from_secs(2)).await;

    assert!(emitter.is_running(), "the emitter died: {}", emitter.log());
    let (rss_after, rss_peak) = (status_kib(pid, "VmRSS"), status_kib(pid, "VmHWM"));
    eprintln!(
        "{sent} DATA_FRAGs to ports {ports:?}: VmRSS {rss_before} → {rss_after} KiB, \
         peak {rss_peak} KiB"
    );
    assert!(rss_peak < 300 << 10, "peak resident {rss_peak} KiB");
    assert!(
        rss_after < rss_before + (64 << 10),
        "resident {rss_before} → {rss_after} KiB"
    );

    // The drops are logged, once per 5 s at most, never as a panic.
    let log = emitter.lines();
    let drop_lines: Vec<&String> = log
        .iter()
        .filter(|l| l.contains("DATA_FRAG of sample"))
        .collect();
    assert!(
        drop_lines.iter().any(|l| l.contains("over the limit")),
        "no drop logged: {log:?}"
    );
    assert!(drop_lines.len() <= 3, "not rate-limited: {drop_lines:?}");
    assert!(!log.iter().any(|l| l.contains("panicked")), "{log:?}");

    // Discovery (the bombed SEDP and SPDP readers) and the service still work.
    let after = emit_through_a_new_client(domain, "client_after").await;
    assert!(after.success, "{}", after.message);
    assert_eq!(after.program.files, before.program.files);
    assert!(after.program.line_count > 0);
}
