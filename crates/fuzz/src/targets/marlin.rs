//! Marlin: the answer and host-line parsers, the client fed a hostile printer, and the
//! simulator fed a hostile host.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use cell_grbl::transport::Connect;
use cell_marlin::client::{ClientConfig, LinkState, MarlinLink};
use cell_marlin::protocol::{code_of, parse_host_line, parse_response, parse_temps, word};
use cell_marlin::sim::{Faults, SimConfig};

use super::serial::{feed_lines, paused_runtime, say_lines, OnePipe};
use crate::{text, Target};

const TOKENS: &[&str] = &[
    "ok\n",
    "ok T:21.23 /0.00 B:20.98 /0.00 @:0 B@:0\n",
    " T:180.00 /210.00 B:60.00 /60.00 @:127 B@:0 W:?\n",
    " W:3",
    "Resend: ",
    "rs ",
    "Error:checksum mismatch, Last Line: ",
    "Error:Line Number is not Last Line Number+1, Last Line: ",
    "Error:No Checksum with line number, Last Line: ",
    "Error:Printer halted. kill() called!\n",
    "Error:Thermal Runaway, system stopped! Heater_ID: 0\n",
    "echo:busy: processing\n",
    "echo:Unknown command: \"",
    "start\n",
    "X:10.00 Y:20.00 Z:0.20 E:1.50 Count X:800 Y:1600 Z:80\n",
    "N0 M110 N0*125\n",
    "N",
    "*",
    "M104 S",
    "M109 S210",
    "M140 S",
    "M190 R",
    "M105",
    "M108\n",
    "M112\n",
    "M410\n",
    "M114",
    "M400",
    "G1 X",
    "G2 X10 Y0 I5 J0 ",
    "G3 ",
    "G4 S",
    "G28 X Y",
    "G91\n",
    "M220 S",
    "E",
    "F",
];

fn response_seeds() -> Vec<Vec<u8>> {
    [
        "start\necho:Marlin 2.1.2.4\nok\nok T:21.23 /0.00 B:20.98 /0.00 @:0 B@:0",
        " T:180.00 /210.00 B:60.00 /60.00 @:127 B@:0 W:?\n T:209.80 /210.00 B:60.00 /60.00 @:80 B@:0 W:9",
        "Error:checksum mismatch, Last Line: 11\nResend: 12\nok",
        "Error:Thermal Runaway, system stopped! Heater_ID: 0\nError:Printer halted. kill() called!",
        "X:10.00 Y:20.00 Z:0.20 E:1.50 Count X:800 Y:1600 Z:80\nok",
        "N12 G1 X10 Y5 E0.5 F1800*15\nN0 M110 N0*125\nM112",
    ]
    .iter()
    .map(|s| s.as_bytes().to_vec())
    .collect()
}

/// Every parser on every line: answers, temperature reports, host lines, codes and words.
fn response(data: &[u8]) {
    for line in text(data).split('\n') {
        let _ = parse_response(line);
        let _ = parse_temps(line);
        let h = parse_host_line(line);
        let _ = code_of(h.command);
        for letter in ['N', 'S', 'R', 'X', 'E', 'F', 'P'] {
            let _ = word(h.command, letter);
        }
    }
}

fn link_seeds() -> Vec<Vec<u8>> {
    [
        "start\nok\nok\nok T:21.00 /0.00 B:21.00 /0.00 @:0 B@:0\nok\nok\nok\nok T:21.00 /0.00 B:21.00 /0.00 @:0 B@:0\n",
        "ok\nError:checksum mismatch, Last Line: 0\nResend: 1\nok\nok\nok\nok\nok\nok T:30.0 /0.0\n",
        "ok\nResend: 99999999999\nok\nResend: 0\nok\n",
        "ok\necho:busy: processing\n T:100.0 /210.0 W:?\nError:Printer halted. kill() called!\n",
    ]
    .iter()
    .map(|s| s.as_bytes().to_vec())
    .collect()
}

/// The client against a printer that says the input, one line every 20 ms (simulated):
/// connect, `M105`, a few lines, the safe stop.
fn link(data: &[u8]) {
    let said = data.to_vec();
    paused_runtime().block_on(async move {
        let (host, printer) = tokio::io::duplex(1 << 16);
        let connector: Arc<dyn Connect> = Arc::new(OnePipe(Mutex::new(Some(host))));
        let speaker = tokio::spawn(say_lines(printer, said));
        let config = ClientConfig {
            command_timeout: Duration::from_secs(1),
            boot_wait: Duration::from_millis(200),
        };
        let state = tokio::sync::watch::channel(LinkState::default()).0;
        let session = async {
            let mut link = MarlinLink::connect(&connector, config, state).await?;
            let _ = link.temps().await;
            for l in ["G28", "G1 X10 Y10 E1 F1800", "M109 S210"] {
                if link.send(l).await.is_err() {
                    break;
                }
            }
            let _ = link.position().await;
            link.heat_off().await
        };
        let _ = tokio::time::timeout(Duration::from_secs(60), session).await;
        speaker.abort();
    });
}

fn sim_seeds() -> Vec<Vec<u8>> {
    [
        "\x00N0 M110 N0*125\nM140 S60\nM104 S200\nG28\nG1 X10 Y10 E1 F1800\nM105\nM114\nM400\n",
        "\x01N5 G1 X1*0\nN1 G1 X2\nM109 S210\nM108\nM410\nG4 P500\nM112\nM105\n",
        "\x02G91\nG2 X10 Y0 I5 J0 F600\nG3 X-10 Y0 I-5 J0\nM220 S150\nM221 S90\nM4242\nT0\n",
    ]
    .iter()
    .map(|s| s.as_bytes().to_vec())
    .collect()
}

/// The simulator fed a hostile host, one line every 5 ms; the first byte picks faults.
fn sim(data: &[u8]) {
    let flags = data.first().copied().unwrap_or(0);
    let body = data.get(1..).unwrap_or_default().to_vec();
    let faults = Faults {
        corrupt_at_lines: if flags & 1 != 0 { vec![2, 3] } else { vec![] },
        heater_fail_at_line: (flags & 2 != 0).then_some(3),
        thermistor_open_at_line: (flags & 4 != 0).then_some(5),
        drop_at_lines: if flags & 8 != 0 { vec![4] } else { vec![] },
        freeze_at_line: (flags & 16 != 0).then_some(6),
    };
    paused_runtime().block_on(async move {
        let sim = cell_marlin::sim::start(SimConfig {
            time_scale: 20.0,
            faults,
            ..SimConfig::default()
        });
        let (host, printer) = tokio::io::duplex(1 << 16);
        sim.attach(printer);
        feed_lines(host, body).await;
        let _ = sim.snapshot();
        let _ = sim.executed();
        let _ = sim.events();
    });
}

/// The Marlin targets.
pub fn targets() -> Vec<Target> {
    vec![
        Target {
            name: "marlin_response",
            about: "Marlin answers, temperature reports, numbered host lines",
            run: response,
            seeds: response_seeds,
            tokens: TOKENS,
            max_len: 4096,
        },
        Target {
            name: "marlin_link",
            about: "the Marlin client talking to a hostile printer",
            run: link,
            seeds: link_seeds,
            tokens: TOKENS,
            max_len: 4096,
        },
        Target {
            name: "marlin_sim",
            about: "the Marlin simulator fed a hostile host",
            run: sim,
            seeds: sim_seeds,
            tokens: TOKENS,
            max_len: 4096,
        },
    ]
}
