//! ABB Robot Web Services for cellsuite's machine bridge: an async client for RWS 1.0
//! (RobotWare 6, IRC5) and RWS 2.0 (RobotWare 7, OmniCore), and [`sim`], a loopback RWS
//! simulator for tests. Pure library: no ROS, no DDS.
//!
//! ```no_run
//! # async fn run() -> Result<(), cell_rws::RwsError> {
//! use std::time::Duration;
//! let cfg = cell_rws::ControllerConfig::load("config/controllers/abb-irb2600-waam.yaml")?;
//! let rws = cell_rws::RwsClient::connect(cfg).await?;
//! let files = [("WAAM_wall.mod", &b"MODULE WAAM_wall ... ENDMODULE"[..]), ("WAAM_wall.pgf", &b"..."[..])];
//! rws.install_program(files).await?;   // upload, load the .pgf
//! rws.set_pp_to_main().await?;
//! rws.start().await?;
//! let end = rws.wait_until_stopped(Duration::from_millis(250), Duration::from_secs(3600)).await?;
//! # let _ = end; Ok(()) }
//! ```
//!
//! Modules: [`config`] (controller YAML and credentials), [`client`] ([`RwsClient`]),
//! [`endpoints`] (every request per generation, with its sources), [`error`] ([`RwsError`],
//! ABB return codes), [`pin`] (the pinned certificate's fingerprint), [`sim`] (the simulator).
//!
//! HTTPS (needed for RobotWare 7 controllers) is the optional cargo feature `tls` (rustls),
//! off by default; with it the client pins the controller's certificate (`tls.pin_sha256`)
//! and the simulator can serve HTTPS.

#![warn(missing_docs)]

pub mod client;
pub mod config;
pub mod endpoints;
pub mod error;
pub mod pin;
pub mod sim;
#[cfg(feature = "tls")]
mod tls;

pub use client::{ExecState, ExecutionState, InstalledProgram, RwsClient};
pub use config::{
    ControllerConfig, Credentials, CredentialsSource, Reconnect, RwsVersion, SignalValue,
    SimulatorEndpoint, Timeouts, TlsConfig,
};
pub use error::{AbbStatus, RwsError};
pub use pin::CertPin;
