//! `marlin_sim`: the Marlin 2.1 protocol simulator as a process, on TCP or a pseudo-terminal,
//! so a person can point OctoPrint, Pronterface or `machine_bridge` at it.
//!
//! ```text
//! marlin_sim --tcp 127.0.0.1:2324                  # a printer behind a serial-to-TCP bridge
//! marlin_sim --pty --link /tmp/marlin             # serial-style; open /tmp/marlin at 115200
//! marlin_sim --tcp 127.0.0.1:2324 --time-scale 20 --corrupt-at-line 40,41 --drop-at-line 300
//! marlin_sim --tcp 127.0.0.1:2324 --heater-fail-at-line 50   # thermal runaway, then kill()
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

use cell_marlin::sim::{self, Faults, OnConnect, SimConfig, SimEvent};
use clap::Parser;

/// Marlin 2.1 protocol simulator (heaters, planner, thermal protection, kill).
#[derive(Debug, Parser)]
#[command(name = "marlin_sim", version)]
struct Args {
    /// Listen for TCP connections on this address (each new connection replaces the last).
    #[arg(long, value_name = "ADDR", conflicts_with = "pty")]
    tcp: Option<String>,
    /// Create a pseudo-terminal and print its device path.
    #[arg(long)]
    pty: bool,
    /// With --pty: also make this symlink to the pty's device.
    #[arg(long, value_name = "PATH", requires = "pty")]
    link: Option<PathBuf>,
    /// A new host does not reset the board (native USB, network bridges); by default it does,
    /// as an 8-bit board whose port opens.
    #[arg(long)]
    no_reset_on_connect: bool,
    /// Simulated seconds per real second.
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// HOTEND_IDLE_TIMEOUT: heaters off after this many idle seconds (0: off).
    #[arg(long, default_value_t = 0.0)]
    idle_timeout_s: f64,
    /// Close the link when these received lines arrive (comma-separated or repeated).
    #[arg(long, value_name = "N", value_delimiter = ',')]
    drop_at_line: Vec<u64>,
    /// Flip a bit in these received lines (line noise: a checksum error and a resend).
    #[arg(long, value_name = "N", value_delimiter = ',')]
    corrupt_at_line: Vec<u64>,
    /// Freeze (read and answer nothing) from this received line on, until the next host.
    #[arg(long, value_name = "N")]
    freeze_at_line: Option<u64>,
    /// The hotend heater loses power at this line (thermal protection trips).
    #[arg(long, value_name = "N")]
    heater_fail_at_line: Option<u64>,
    /// The hotend thermistor opens at this line (MINTEMP).
    #[arg(long, value_name = "N")]
    thermistor_open_at_line: Option<u64>,
    /// Write every executed command here on exit (Ctrl-C).
    #[arg(long, value_name = "PATH")]
    log: Option<PathBuf>,
}

#[tokio::main(flavor = "current_thread")]
async fn main() -> ExitCode {
    match run(Args::parse()).await {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("marlin_sim: {e}");
            ExitCode::FAILURE
        }
    }
}

async fn run(args: Args) -> Result<(), String> {
    if !(args.time_scale.is_finite() && args.time_scale > 0.0) {
        return Err("--time-scale must be positive".into());
    }
    if !(args.idle_timeout_s.is_finite() && args.idle_timeout_s >= 0.0) {
        return Err("--idle-timeout-s must be 0 or positive".into());
    }
    let config = SimConfig {
        time_scale: args.time_scale,
        on_connect: if args.no_reset_on_connect {
            OnConnect::Silent
        } else {
            OnConnect::Reset
        },
        hotend_idle_timeout_s: (args.idle_timeout_s > 0.0).then_some(args.idle_timeout_s),
        faults: Faults {
            drop_at_lines: args.drop_at_line,
            corrupt_at_lines: args.corrupt_at_line,
            freeze_at_line: args.freeze_at_line,
            heater_fail_at_line: args.heater_fail_at_line,
            thermistor_open_at_line: args.thermistor_open_at_line,
        },
        ..SimConfig::default()
    };
    let sim = sim::start(config);
    if let Some(addr) = &args.tcp {
        let bound = sim
            .listen_tcp(addr)
            .await
            .map_err(|e| format!("cannot listen on {addr}: {e}"))?;
        println!("marlin_sim: Marlin 2.1 on tcp {bound}");
    } else if args.pty {
        let path = sim
            .open_pty()
            .map_err(|e| format!("cannot open a pty: {e}"))?;
        println!("marlin_sim: Marlin 2.1 on pty {}", path.display());
        if let Some(link) = &args.link {
            cellsuite::sim_process::link_pty("marlin_sim", &path, link)?;
        }
    } else {
        return Err("give --tcp ADDR or --pty".into());
    }
    tokio::signal::ctrl_c()
        .await
        .map_err(|e| format!("cannot wait for Ctrl-C: {e}"))?;
    let executed = sim.executed();
    let events = sim.events();
    let count = |f: fn(&SimEvent) -> bool| events.iter().filter(|e| f(e)).count();
    let s = sim.snapshot();
    println!(
        "marlin_sim: {} commands executed, {} moves, {} resends asked, {} kills; hotend {:.1} /{:.0}, bed {:.1} /{:.0}",
        executed.len(),
        s.moves_done,
        count(|e| matches!(e, SimEvent::ResendRequested { .. })),
        count(|e| matches!(e, SimEvent::Killed { .. })),
        s.hotend.current,
        s.hotend.target,
        s.bed.current,
        s.bed.target
    );
    let link = args.link.as_deref().filter(|_| args.pty);
    cellsuite::sim_process::finish(&executed, args.log.as_deref(), link)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fault_flags_take_lists() {
        let a = Args::try_parse_from([
            "marlin_sim",
            "--tcp",
            "127.0.0.1:0",
            "--corrupt-at-line",
            "4,9",
            "--drop-at-line",
            "20",
            "--heater-fail-at-line",
            "7",
        ])
        .unwrap();
        assert_eq!(a.corrupt_at_line, vec![4, 9]);
        assert_eq!(a.drop_at_line, vec![20]);
        assert_eq!(a.heater_fail_at_line, Some(7));
        assert!(Args::try_parse_from(["marlin_sim", "--pty", "--corrupt-at-line", "x"]).is_err());
    }
}
