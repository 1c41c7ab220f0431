//! Hostile value words (issue 23): negative, huge and tiny values of every word the simulator
//! reads, sent to each firmware flavour as a sender would. Each line gets GRBL's answer
//! (`error:N` from GRBL 1.1's gcode.c where it has one, else `ok`, or no answer yet for an
//! endless dwell), and the simulator keeps answering status reports with finite positions;
//! a panic in the simulator's task would silence it and fail the test.

use std::time::Duration;

use cell_grbl::sim::{self, OnConnect, SimConfig, SimFirmware, SimHandle};
use tokio::io::{AsyncBufReadExt, AsyncWriteExt, BufReader, DuplexStream, ReadHalf, WriteHalf};

const WAIT: Duration = Duration::from_secs(60);

struct Host {
    rd: BufReader<ReadHalf<DuplexStream>>,
    wr: WriteHalf<DuplexStream>,
}

impl Host {
    async fn attach(sim: &SimHandle, fw: SimFirmware) -> Host {
        let (host, controller) = tokio::io::duplex(1 << 16);
        sim.attach(controller);
        let (rd, wr) = tokio::io::split(host);
        let mut host = Host {
            rd: BufReader::new(rd),
            wr,
        };
        if fw.on_connect() == OnConnect::Banner {
            assert_eq!(host.line().await, fw.banner());
        }
        host
    }

    async fn send(&mut self, bytes: &[u8]) {
        self.wr.write_all(bytes).await.expect("write");
    }

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
            .expect("the simulator answers (a panic in it would silence it)")
    }

    async fn until(&mut self, last: impl Fn(&str) -> bool) -> String {
        loop {
            let l = self.line().await;
            if last(&l) {
                return l;
            }
        }
    }
}

/// `n` nines: a value as large as the line buffer allows.
fn nines(n: usize) -> String {
    "9".repeat(n)
}

/// (line, GRBL's answer: `Some("ok")`, `Some("error:N")`, or `None` for none within a second).
/// `digits`: the longest number the line buffer holds beside a few letters.
fn cases(digits: usize) -> Vec<(String, Option<&'static str>)> {
    // The firmware's words are 32-bit floats: 38 nines is about the largest one (9.99e37),
    // and GRBL's `read_float` keeps 8 significant digits, leading zeros included (1e-7).
    let big = nines(38);
    let tiny = "0.0000001";
    let too_big = nines(digits);
    let ok = Some("ok");
    vec![
        // GRBL reads P, N, F, S and T and refuses a negative one at once (error:4).
        ("G10L2P-1".into(), Some("error:4")),
        ("G10L2P-1X1".into(), Some("error:4")),
        ("G10L20P-0.5X1".into(), Some("error:4")),
        ("N-1G0X1".into(), Some("error:4")),
        ("G4P-1".into(), Some("error:4")),
        ("G1X1F-1".into(), Some("error:4")),
        ("S-1M3".into(), Some("error:4")),
        ("T-1".into(), Some("error:4")),
        // G10 in GRBL's order: axis words (26), P/L (28), trunc(P) <= 6 (29), L 2 or 20 (20).
        ("G10L2P1".into(), Some("error:26")),
        ("G10L2X1".into(), Some("error:28")),
        ("G10L2P7X1".into(), Some("error:29")),
        (format!("G10L2P{big}X1"), Some("error:29")),
        ("G10L2P6.9X1".into(), ok),
        ("G10L-2P1X1".into(), Some("error:20")),
        (format!("G10L{big}P1X1"), Some("error:20")),
        (format!("G10L2P1X{big}"), ok),
        (format!("N{big}G0X1"), Some("error:27")),
        (format!("T{big}"), Some("error:38")),
        // Huge and tiny values where GRBL has no error: accepted, and the machine keeps going.
        (format!("G0X{big}"), ok),
        (format!("G0X-{big}Y1"), ok),
        (format!("G1X1F{big}"), ok),
        (format!("G1X1F{tiny}"), ok),
        (format!("G1X{big}F{tiny}"), ok),
        (format!("S{big}M3"), ok),
        (format!("G91G2X1Y1R{big}F100"), ok),
        (format!("G91G2X0Y0I{big}F100"), ok),
        (format!("G92X{big}"), ok),
        (format!("G20G0X{big}"), ok),
        // A dwell of 1e38 s: no answer until it is over.
        (format!("G4P{big}"), None),
        // Beyond a 32-bit float: a bad number (GRBL would compute with infinity).
        (format!("G0X{too_big}"), Some("error:2")),
        (format!("G4P{too_big}"), Some("error:2")),
    ]
}

async fn hostile_words_get_grbls_answers(fw: SimFirmware) {
    let sim = sim::start(SimConfig {
        timer_slack: Duration::ZERO,
        ..SimConfig::for_firmware(fw)
    });
    let mut host = Host::attach(&sim, fw).await;
    let digits = fw.line_buffer_size() - 16;
    for (line, expected) in cases(digits) {
        host.send(format!("{line}\n").as_bytes()).await;
        let answer = host.line_within(Duration::from_secs(1)).await;
        assert_eq!(answer.as_deref(), expected, "{fw:?}: {line}");
        // Still alive, with finite positions.
        host.send(b"?").await;
        let report = host.until(|l| l.starts_with('<')).await;
        let lower = report.to_lowercase();
        assert!(
            !lower.contains("nan") && !lower.contains("inf"),
            "{fw:?}: {line}: {report}"
        );
        // A soft reset clears the motion and the modal state for the next case.
        host.send(&[0x18]).await;
        host.until(|l| l == fw.banner()).await;
        // A reset while moving leaves GRBL in alarm: unlock (answered `ok` when idle too).
        host.send(b"$X\n").await;
        host.until(|l| l == "ok" || l.starts_with("error:")).await;
    }
}

#[tokio::test(start_paused = true)]
async fn grbl_1_1h() {
    hostile_words_get_grbls_answers(SimFirmware::Grbl11h).await;
}

#[tokio::test(start_paused = true)]
async fn grblhal() {
    hostile_words_get_grbls_answers(SimFirmware::GrblHal).await;
}

#[tokio::test(start_paused = true)]
async fn fluidnc() {
    hostile_words_get_grbls_answers(SimFirmware::FluidNc).await;
}
