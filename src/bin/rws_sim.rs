//! `rws_sim`: runs the RWS simulator on loopback until interrupted.
//!
//! ```sh
//! RWS_SIM_CREDENTIALS='Sim User:secret' rws_sim --rws rw6 --port 8080 --run-ms 5000
//! ```
//!
//! The credentials come from `$RWS_SIM_CREDENTIALS` (`user:password`).

use std::time::Duration;

use cell_rws::sim::{RwsSim, SimConfig};
use cell_rws::{CredentialsSource, RwsVersion};

fn usage() -> ! {
    eprintln!("usage: rws_sim [--rws rw6|rw7] [--port PORT] [--run-ms MS]   (credentials in $RWS_SIM_CREDENTIALS as user:password)");
    std::process::exit(64)
}

#[tokio::main(flavor = "current_thread")]
async fn main() {
    let mut version = RwsVersion::Rw6;
    let mut port = 0u16;
    let mut run_ms = 2000u64;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let value = args.next().unwrap_or_else(|| usage());
        match a.as_str() {
            "--rws" => {
                version = match value.as_str() {
                    "rw6" => RwsVersion::Rw6,
                    "rw7" => RwsVersion::Rw7,
                    _ => usage(),
                }
            }
            "--port" => port = value.parse().unwrap_or_else(|_| usage()),
            "--run-ms" => run_ms = value.parse().unwrap_or_else(|_| usage()),
            _ => usage(),
        }
    }
    let creds = match CredentialsSource::Env("RWS_SIM_CREDENTIALS".into()).load() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("rws_sim: {e}");
            std::process::exit(64)
        }
    };
    let mut cfg = SimConfig::new(version, &creds.user, &creds.password);
    cfg.run_time = Duration::from_millis(run_ms);
    let sim = match RwsSim::start_on(cfg, port).await {
        Ok(s) => s,
        Err(e) => {
            eprintln!("rws_sim: cannot listen on 127.0.0.1:{port}: {e}");
            std::process::exit(1)
        }
    };
    println!("rws_sim: {version} on {}", sim.url());
    let _ = tokio::signal::ctrl_c().await;
}
