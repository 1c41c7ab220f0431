//! `grbl_sim`: the GRBL 1.1 protocol simulator as a process, on TCP or a pseudo-terminal, so a
//! person can point Universal G-code Sender, bCNC or `machine_bridge` at it. It speaks as GRBL
//! 1.1h, grblHAL or FluidNC (`--firmware`).
//!
//! ```text
//! grbl_sim --tcp 127.0.0.1:2323              # telnet-style
//! grbl_sim --tcp 127.0.0.1:2323 --firmware fluidnc   # FluidNC over WiFi: 1200-byte buffer
//! grbl_sim --pty --link /tmp/grbl --firmware grblhal # grblHAL on USB: 1024-byte buffer
//! grbl_sim --pty --link /tmp/grbl --on-connect reset # an Arduino that resets on open
//! grbl_sim --pty --link /tmp/grbl            # serial-style; open /tmp/grbl at 115200
//! grbl_sim --tcp 127.0.0.1:2323 --drop-at-line 500 --ack-delay-ms 5 --log executed.nc
//! grbl_sim --tcp 127.0.0.1:2323 --drop-at-line 200,900 --drop-at-line 1500 --freeze-at-line 2000
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

use cell_grbl::sim::{self, Faults, OnConnect, SimConfig, SimEvent, SimFirmware};
use clap::{Parser, ValueEnum};

/// GRBL 1.1 protocol simulator (GRBL 1.1h, grblHAL or FluidNC; simulated motion).
#[derive(Debug, Parser)]
#[command(name = "grbl_sim", version)]
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
    /// Firmware to speak as: it sets the banner, `$I`, the RX buffer and planner sizes and what
    /// a new host sees.
    #[arg(long, value_enum, default_value_t = Firmware::Grbl)]
    firmware: Firmware,
    /// RX buffer size in bytes, instead of the firmware's.
    #[arg(long, value_name = "N")]
    rx_buffer_bytes: Option<usize>,
    /// What a new host sees, instead of the firmware's.
    #[arg(long, value_enum)]
    on_connect: Option<Connect>,
    /// Start in laser mode ($32=1): the laser fires during feed moves only and goes out in a
    /// completed feed hold.
    #[arg(long)]
    laser_mode: bool,
    /// Simulated seconds per real second.
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// Link baud rate (8N1); 0 for an unthrottled link.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Axis letters in report order.
    #[arg(long, default_value = "XYZ")]
    axes: String,
    /// Rapid rate (mm/min).
    #[arg(long, default_value_t = 3000.0)]
    rapid_mm_min: f64,
    /// Drop the link when this G-code line (count since start) arrives; repeat the flag or
    /// give a comma-separated list for several drops.
    #[arg(long, value_name = "N", value_delimiter = ',')]
    drop_at_line: Vec<u64>,
    /// Freeze (read and answer nothing, link left open) when this G-code line arrives, until
    /// the next connection.
    #[arg(long, value_name = "N")]
    freeze_at_line: Option<u64>,
    /// Raise ALARM:CODE when the move of G-code line N starts, as N:CODE.
    #[arg(long, value_name = "N:CODE", value_parser = parse_pair)]
    alarm_at_line: Option<(u64, u8)>,
    /// Answer G-code line N with error:CODE, as N:CODE.
    #[arg(long, value_name = "N:CODE", value_parser = parse_pair)]
    error_at_line: Option<(u64, u8)>,
    /// Simulated milliseconds spent on each line before answering.
    #[arg(long, default_value_t = 0.0)]
    ack_delay_ms: f64,
    /// Reset by itself (a brown-out: power-up state, banner, link kept) when G-code line N
    /// arrives.
    #[arg(long, value_name = "N")]
    reset_at_line: Option<u64>,
    /// Write the executed-line log here on exit (Ctrl-C).
    #[arg(long, value_name = "PATH")]
    log: Option<PathBuf>,
}

/// `--firmware`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Firmware {
    /// GRBL 1.1h (Arduino): 128-byte RX buffer, 15 planner blocks, banner when a host connects.
    Grbl,
    /// grblHAL 1.1f: 1024-byte RX buffer, 100 planner blocks, banner when a host connects.
    Grblhal,
    /// FluidNC v3.7.8 (ESP32 over telnet): 1200-byte RX buffer, 15 planner blocks, nothing when
    /// a host connects.
    Fluidnc,
}

impl From<Firmware> for SimFirmware {
    fn from(f: Firmware) -> Self {
        match f {
            Firmware::Grbl => SimFirmware::Grbl11h,
            Firmware::Grblhal => SimFirmware::GrblHal,
            Firmware::Fluidnc => SimFirmware::FluidNc,
        }
    }
}

/// `--on-connect`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Connect {
    /// The banner; the machine keeps running as it was.
    Banner,
    /// A hardware reset, as an Arduino when its port opens: motion and heat stop, position
    /// lost; then the banner.
    Reset,
    /// Nothing; the machine keeps running as it was.
    Silent,
}

impl From<Connect> for OnConnect {
    fn from(c: Connect) -> Self {
        match c {
            Connect::Banner => OnConnect::Banner,
            Connect::Reset => OnConnect::Reset,
            Connect::Silent => OnConnect::Silent,
        }
    }
}

fn parse_pair(s: &str) -> Result<(u64, u8), String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("expected N:CODE, got {s:?}"))?;
    Ok((
        a.parse().map_err(|e| format!("{a:?}: {e}"))?,
        b.parse().map_err(|e| format!("{b:?}: {e}"))?,
    ))
}

#[tokio::main(flavor = "current_thread")]
async fn main() -> ExitCode {
    let args = Args::parse();
    match run(args).await {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("grbl_sim: {e}");
            ExitCode::FAILURE
        }
    }
}

async fn run(args: Args) -> Result<(), String> {
    let axes: Vec<char> = args.axes.chars().map(|c| c.to_ascii_uppercase()).collect();
    if axes.is_empty() || axes.iter().any(|c| !"XYZABCUVW".contains(*c)) {
        return Err(format!(
            "--axes {:?}: use letters from XYZABCUVW",
            args.axes
        ));
    }
    if args.time_scale <= 0.0 || !args.time_scale.is_finite() {
        return Err("--time-scale must be positive".into());
    }
    if args.rx_buffer_bytes.is_some_and(|n| n < 2) {
        return Err("--rx-buffer-bytes must be at least 2 (one byte stays free)".into());
    }
    let firmware = SimFirmware::from(args.firmware);
    let defaults = SimConfig::for_firmware(firmware);
    let config = SimConfig {
        rx_buffer_bytes: args.rx_buffer_bytes.unwrap_or(defaults.rx_buffer_bytes),
        on_connect: args.on_connect.map_or(defaults.on_connect, OnConnect::from),
        laser_mode: args.laser_mode,
        time_scale: args.time_scale,
        baud: (args.baud > 0).then_some(args.baud),
        axes,
        rapid_mm_min: args.rapid_mm_min,
        faults: Faults {
            drop_at_lines: args.drop_at_line,
            freeze_at_line: args.freeze_at_line,
            alarm_at_line: args.alarm_at_line,
            error_at_line: args.error_at_line,
            ack_delay_s: args.ack_delay_ms / 1000.0,
            reset_at_line: args.reset_at_line,
        },
        ..defaults
    };
    let rx = config.rx_buffer_bytes;
    let sim = sim::start(config);
    if let Some(addr) = &args.tcp {
        let bound = sim
            .listen_tcp(addr)
            .await
            .map_err(|e| format!("cannot listen on {addr}: {e}"))?;
        println!("grbl_sim: {firmware} ({rx}-byte RX buffer) on tcp {bound}");
    } else if args.pty {
        let path = sim
            .open_pty()
            .map_err(|e| format!("cannot open a pty: {e}"))?;
        println!(
            "grbl_sim: {firmware} ({rx}-byte RX buffer) on pty {}",
            path.display()
        );
        if let Some(link) = &args.link {
            cellsuite::sim_process::link_pty("grbl_sim", &path, link)?;
        }
    } else {
        return Err("give --tcp ADDR or --pty".into());
    }
    tokio::signal::ctrl_c()
        .await
        .map_err(|e| format!("cannot wait for Ctrl-C: {e}"))?;
    let executed = sim.executed_lines();
    let overflow = sim.overflow_bytes();
    let alarms = sim
        .events()
        .iter()
        .filter(|e| matches!(e, SimEvent::Alarm { .. }))
        .count();
    println!(
        "grbl_sim: {} lines executed, {} RX bytes lost to overflow, {} alarms",
        executed.len(),
        overflow,
        alarms
    );
    let link = args.link.as_deref().filter(|_| args.pty);
    cellsuite::sim_process::finish(&executed, args.log.as_deref(), link)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drop_at_line_takes_repeats_and_lists() {
        let a = Args::try_parse_from([
            "grbl_sim",
            "--tcp",
            "127.0.0.1:0",
            "--drop-at-line",
            "500,20",
            "--drop-at-line",
            "900",
            "--freeze-at-line",
            "1200",
        ])
        .unwrap();
        assert_eq!(a.drop_at_line, vec![500, 20, 900]);
        assert_eq!(a.freeze_at_line, Some(1200));
        let none = Args::try_parse_from(["grbl_sim", "--pty"]).unwrap();
        assert!(none.drop_at_line.is_empty() && none.freeze_at_line.is_none());
        assert!(Args::try_parse_from(["grbl_sim", "--drop-at-line", "5,x"]).is_err());
    }

    #[test]
    fn firmware_and_buffer_flags() {
        let a = Args::try_parse_from([
            "grbl_sim",
            "--pty",
            "--firmware",
            "grblhal",
            "--rx-buffer-bytes",
            "512",
            "--on-connect",
            "reset",
        ])
        .unwrap();
        assert_eq!(SimFirmware::from(a.firmware), SimFirmware::GrblHal);
        assert_eq!(a.rx_buffer_bytes, Some(512));
        assert_eq!(a.on_connect.map(OnConnect::from), Some(OnConnect::Reset));
        let d = Args::try_parse_from(["grbl_sim", "--tcp", "127.0.0.1:0"]).unwrap();
        assert_eq!(SimFirmware::from(d.firmware), SimFirmware::Grbl11h);
        assert!(d.rx_buffer_bytes.is_none() && d.on_connect.is_none() && !d.laser_mode);
        assert!(Args::try_parse_from(["grbl_sim", "--pty", "--firmware", "marlin"]).is_err());
    }
}
