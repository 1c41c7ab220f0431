//! GRBL: the response parser, the G-code program parser (with the resume preamble), the link
//! task fed a hostile controller, and the simulator's interpreter fed a hostile host.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::protocol::{parse_response, parse_status, MachineState};
use cell_grbl::sim::{SimConfig, SimFirmware};
use cell_grbl::stream::{ClientConfig, GrblClient};
use cell_grbl::words::Words;

use super::serial::{feed_lines, paused_runtime, say_lines, OnePipe};
use crate::{text, Target};

const TOKENS: &[&str] = &[
    "ok\r\n",
    "error:",
    "ALARM:",
    "<Idle|MPos:0.000,0.000,0.000|FS:0,0>\r\n",
    "<Run|WPos:",
    "|WCO:",
    "|Bf:15,128",
    "|Ov:100,100,100",
    "|FS:",
    "|F:",
    "|Ln:",
    "|Pn:XYZ",
    "|A:SFM",
    "Hold:0",
    "Door:1",
    "[MSG:",
    "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]",
    "[OPT:V,15,128]",
    "[VER:1.1h.20190825:]",
    "Grbl 1.1h ['$' for help]\r\n",
    "GrblHAL 1.1f ['$' or '$HELP' for help]\r\n",
    "$30=1000",
    "G0 ",
    "G1 X",
    "G2 X10 Y0 I5 J0 ",
    "G3 ",
    "G4 P",
    "G10 L2 P1 X",
    "G10 L20 P",
    "G28",
    "G38.2 Z-10 F100",
    "G53 ",
    "G92 X",
    "M3 S",
    "M5",
    "M30",
    "F",
    "$J=G91 X1 F100",
    "$H",
    "$X",
    "$$",
    "$#",
    "$I",
    "$G",
    "$N0=",
    "$10=",
    "$RST=*",
    "?",
    "!",
    "~",
    "\x18",
    "\u{85}",
    "\u{90}",
    "(",
    ")",
    ";",
    "\r\n",
];

const SEED_PROGRAM: &str = "G21 G90 (mm, absolute)\nG0 X0 Y0\nM3 S1000\nG1 X10 Y5 F600\n\
G2 X20 Y5 I5 J0\nG1 Y20 ; side\nG4 P0.5\nM5\nG0 X0 Y0\nM30\n";

fn response_seeds() -> Vec<Vec<u8>> {
    [
        "<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>",
        "<Run|MPos:10.000,5.000,0.000|Bf:14,100|FS:600,1000|Ov:100,100,100|A:S>",
        "<Hold:0|WPos:1.000,2.000,3.000,4.000|F:500|Ln:12|Pn:XP>",
        "ok\nerror:20\nALARM:3\n[MSG:'$H'|'$X' to unlock]\n[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]",
        "Grbl 1.1h ['$' for help]\n[VER:1.1h.20190825:]\n[OPT:V,15,128]\n$30=1000\n$10=1",
        "GrblHAL 1.1f ['$' or '$HELP' for help]\n[OPT:VNMSL,35,1024,3,0]",
        "[FluidNC v3.7.8 (wifi) '$' for help]\n[G54:0.000,0.000,0.000]\n[PRB:1.000,2.000,3.000:1]",
    ]
    .iter()
    .map(|s| s.as_bytes().to_vec())
    .collect()
}

/// Every response parser on every line: `parse_response`, `parse_status` and the positions it
/// derives, the banner and `$I` parsers.
fn response(data: &[u8]) {
    let text = text(data);
    let mut wco: Option<Vec<f64>> = None;
    for line in text.split('\n') {
        let _ = parse_response(line);
        if let Ok(report) = parse_status(line) {
            let _ = report.machine_position(wco.as_deref());
            let _ = report.work_position(wco.as_deref());
            if report.wco.is_some() {
                wco.clone_from(&report.wco);
            }
            let _ = report.state.map(MachineState::is_moving);
        }
        let _ = cell_grbl::firmware::parse_banner(line);
        let _ = cell_grbl::firmware::parse_build_options(line);
        let _ = cell_grbl::firmware::gc_spindle(line);
        let _ = MachineState::parse(line);
    }
}

/// The program parser (both cleaning modes), each line's words, the resume preamble from a
/// line the input picks, and the resume point.
fn program(data: &[u8]) {
    let pick = data.first().copied().unwrap_or(0) as usize;
    let text = text(data);
    let strict = Program::parse(&text, CleanOptions::default());
    let lenient = Program::parse(
        &text,
        CleanOptions {
            strip_whitespace: true,
            allowed_commands: vec!["$H".into(), "$X".into()],
        },
    );
    for program in [strict, lenient].into_iter().flatten() {
        for line in program.lines() {
            let _ = Words::scan(&line.text);
            let _ = cell_grbl::resume_point::is_motion_line(&line.text);
        }
        let _ = program.wire_bytes();
        let _ = program.longest_line();
        if !program.is_empty() {
            let from = program.lines()[pick % program.len()].number;
            let _ = program.index_of_line(from);
            let _ = cell_grbl::resume::preamble(&program, from);
            let texts: Vec<&str> = program.lines().iter().map(|l| l.text.as_str()).collect();
            let acked = pick % texts.len();
            let _ = cell_grbl::resume_point::first_unfinished(&texts, acked, pick % 17);
        }
    }
}

/// The link task against a controller that says the input, one line every 20 ms (simulated):
/// connect (first status report, `$I`), a command and a short stream, then drop.
fn link(data: &[u8]) {
    let flags = data.first().copied().unwrap_or(0);
    let body = data.get(1..).unwrap_or_default();
    let mut said = Vec::new();
    if flags & 1 == 0 {
        said.extend_from_slice(b"<Idle|MPos:0.000,0.000,0.000|FS:0,0>\r\n");
    }
    said.extend_from_slice(body);
    let config = ClientConfig {
        detect_rx_buffer: flags & 2 != 0,
        reconnect_attempts: 1,
        ..ClientConfig::default()
    };
    let program = Program::parse(
        "G21 G90\nM3 S1000\nG1 X10 Y10 F600\nG1 X0 Y0\nM5\n",
        CleanOptions::default(),
    )
    .expect("a valid program");
    paused_runtime().block_on(async move {
        let (host, controller) = tokio::io::duplex(1 << 16);
        let connector = Arc::new(OnePipe(Mutex::new(Some(host))));
        let speaker = tokio::spawn(say_lines(controller, said));
        let session = async {
            let client = GrblClient::connect(connector, config).await?;
            let _ = client.command("$G").await;
            let _ = client.stream(&program).await;
            let _ = client.hold().await;
            let _ = client.safe_stop_within(Duration::from_secs(2)).await;
            Ok::<_, cell_grbl::stream::ClientError>(())
        };
        let _ = tokio::time::timeout(Duration::from_secs(120), session).await;
        speaker.abort();
    });
}

/// The simulator's interpreter fed the input as a host's bytes (one line every 5 ms, simulated),
/// for 30 s of simulated time; firmware flavour from the first byte.
fn sim(data: &[u8]) {
    let flags = data.first().copied().unwrap_or(0);
    let body = data.get(1..).unwrap_or_default().to_vec();
    let firmware = match flags % 3 {
        0 => SimFirmware::Grbl11h,
        1 => SimFirmware::GrblHal,
        _ => SimFirmware::FluidNc,
    };
    paused_runtime().block_on(async move {
        let sim = cell_grbl::sim::start(SimConfig::for_firmware(firmware));
        let (host, controller) = tokio::io::duplex(1 << 16);
        sim.attach(controller);
        feed_lines(host, body).await;
        let _ = sim.parser_state();
        let _ = sim.snapshot();
        let _ = sim.executed_lines();
    });
}

fn program_seeds() -> Vec<Vec<u8>> {
    vec![
        SEED_PROGRAM.as_bytes().to_vec(),
        b"$H\nG10 L20 P1 X0 Y0\nG91 G1 X1 F100\nG90\n".to_vec(),
        b"G17 G21\nG0 X0 Y0 U0 V0\nG1 X10 Y0 U10 V0 F300\nG93 G1 X20 F2\nG94\n".to_vec(),
    ]
}

fn link_seeds() -> Vec<Vec<u8>> {
    vec![
        b"\x00Grbl 1.1h ['$' for help]\r\n[VER:1.1h.20190825:]\r\n[OPT:V,15,128]\r\nok\r\n\
[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\nok\r\nok\r\nok\r\nok\r\nok\r\n\
<Run|MPos:1.000,1.000,0.000|Bf:14,100|FS:600,1000>\r\nok\r\n<Hold:0|MPos:1.000,1.000,0.000|FS:0,0>\r\n\
<Idle|MPos:1.000,1.000,0.000|FS:0,0|A:>\r\nok\r\n"
            .to_vec(),
        b"\x01<Idle|MPos:0.000,0.000,0.000|FS:0,0>\r\nerror:20\r\nALARM:1\r\n[MSG:Reset to continue]\r\n"
            .to_vec(),
        b"\x02GrblHAL 1.1f ['$' or '$HELP' for help]\r\n[OPT:VNMSL,35,1024,3,0]\r\nok\r\n".to_vec(),
    ]
}

fn sim_seeds() -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    for (flag, program) in [(0u8, SEED_PROGRAM), (1, "$$\n$#\n$I\n$G\n$N0=G21\n$X\n?\n")] {
        let mut v = vec![flag];
        v.extend_from_slice(program.as_bytes());
        out.push(v);
    }
    out.push(b"\x02G1 X5 F100\n!\n~\n?\x18$X\n$J=G91 X1 F100\n\x85\n".to_vec());
    out
}

/// The GRBL targets.
pub fn targets() -> Vec<Target> {
    vec![
        Target {
            name: "grbl_response",
            about: "status reports, ok/error/ALARM, push messages, banners, $I",
            run: response,
            seeds: response_seeds,
            tokens: TOKENS,
            max_len: 4096,
        },
        Target {
            name: "grbl_program",
            about: "G-code program parser, words, resume preamble and point",
            run: program,
            seeds: program_seeds,
            tokens: TOKENS,
            max_len: 8192,
        },
        Target {
            name: "grbl_link",
            about: "the streaming client's link task talking to a hostile controller",
            run: link,
            seeds: link_seeds,
            tokens: TOKENS,
            max_len: 4096,
        },
        Target {
            name: "grbl_sim",
            about: "the GRBL simulator's interpreter fed a hostile host",
            run: sim,
            seeds: sim_seeds,
            tokens: TOKENS,
            max_len: 4096,
        },
    ]
}
