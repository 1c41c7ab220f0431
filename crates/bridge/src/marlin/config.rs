//! Marlin controller files (`protocol: marlin`):
//!
//! ```yaml
//! id: marlin-sim
//! protocol: marlin
//! machine_profile: marlin-extruder  # programs emitted for another profile are refused
//! endpoint:
//!   simulator: {time_scale: 20}     # the in-repo Marlin simulator, started by the bridge
//!   # tcp: 192.168.1.50:8080        # a serial-to-TCP bridge (ser2net, ESP3D)
//!   # serial: {path: /dev/ttyUSB0, baud: 115200}
//!   # pty: /dev/pts/7               # e.g. `marlin_sim --pty`
//! status_period_s: 1.0              # M105/M114 poll period
//! command_timeout_s: 10             # silence with a line in flight = the printer is gone
//! ```

use std::time::Duration;

use cell_config::{Allowed, Bound};
use cell_grbl::transport::Endpoint;
use serde::Deserialize;

use crate::config::{in_range, invalid, ControllerFileError, EndpointConfig};

/// Where a Marlin printer is reached.
pub type MarlinEndpoint = EndpointConfig<MarlinSimulatorConfig>;

/// What a new host sees, as written in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum OnConnectConfig {
    /// The board resets (8-bit boards: DTR on port open).
    #[default]
    Reset,
    /// Nothing (native USB, network bridges).
    Silent,
}

/// The simulator the bridge starts for `endpoint: {simulator: …}`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MarlinSimulatorConfig {
    /// Simulated seconds per real second.
    pub time_scale: f64,
    /// What a new host sees.
    pub on_connect: OnConnectConfig,
    /// HOTEND_IDLE_TIMEOUT: heaters off after this long idle (s); 0 = off.
    pub hotend_idle_timeout_s: f64,
}

impl Default for MarlinSimulatorConfig {
    fn default() -> Self {
        MarlinSimulatorConfig {
            time_scale: 1.0,
            on_connect: OnConnectConfig::Reset,
            hotend_idle_timeout_s: 0.0,
        }
    }
}

impl MarlinSimulatorConfig {
    /// The simulator's settings.
    pub fn sim_config(&self) -> cell_marlin::sim::SimConfig {
        cell_marlin::sim::SimConfig {
            time_scale: self.time_scale,
            on_connect: match self.on_connect {
                OnConnectConfig::Reset => cell_marlin::sim::OnConnect::Reset,
                OnConnectConfig::Silent => cell_marlin::sim::OnConnect::Silent,
            },
            hotend_idle_timeout_s: (self.hotend_idle_timeout_s > 0.0)
                .then_some(self.hotend_idle_timeout_s),
            ..cell_marlin::sim::SimConfig::default()
        }
    }
}

/// Reconnection after a link loss (to switch the heat off and read it back).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MarlinReconnect {
    /// Attempts.
    pub attempts: u32,
    /// Pause between attempts (s).
    pub delay_s: f64,
}

impl Default for MarlinReconnect {
    fn default() -> Self {
        MarlinReconnect {
            attempts: 5,
            delay_s: 0.5,
        }
    }
}

/// A Marlin controller file (module docs).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarlinControllerConfig {
    /// Controller id.
    pub id: String,
    /// Always `marlin`.
    pub protocol: String,
    /// One line for people.
    #[serde(default)]
    pub description: String,
    /// The machine profile this printer runs; programs emitted for another are refused.
    #[serde(default)]
    pub machine_profile: String,
    /// Where it is reached (a one-key map: `tcp`, `serial`, `pty` or `simulator`).
    #[serde(with = "serde_norway::with::singleton_map")]
    pub endpoint: MarlinEndpoint,
    /// `M105`/`M114` poll period (s).
    #[serde(default = "default_status_period")]
    pub status_period_s: f64,
    /// Silence with a line in flight after which the printer is taken as gone (s).
    #[serde(default = "default_command_timeout")]
    pub command_timeout_s: f64,
    /// Reconnection after a link loss.
    #[serde(default)]
    pub reconnect: MarlinReconnect,
}

fn default_status_period() -> f64 {
    1.0
}

fn default_command_timeout() -> f64 {
    10.0
}

impl MarlinControllerConfig {
    /// Checks values and the machine profile.
    pub(crate) fn check(&self, file: &str) -> Result<(), ControllerFileError> {
        if self.id.trim().is_empty() {
            return Err(invalid(file, "id", "empty".into()));
        }
        in_range(
            file,
            "status_period_s",
            self.status_period_s,
            Allowed::between(Bound::Inclusive(0.05), Bound::Inclusive(10.0)),
            "s",
        )?;
        in_range(
            file,
            "command_timeout_s",
            self.command_timeout_s,
            Allowed::between(Bound::Inclusive(2.5), Bound::Inclusive(600.0)),
            "s",
        )?;
        in_range(
            file,
            "reconnect.delay_s",
            self.reconnect.delay_s,
            Allowed::between(Bound::Inclusive(0.0), Bound::Inclusive(60.0)),
            "s",
        )?;
        if let MarlinEndpoint::Simulator(s) = &self.endpoint {
            in_range(
                file,
                "endpoint.simulator.time_scale",
                s.time_scale,
                Allowed::between(Bound::Exclusive(0.0), Bound::Inclusive(1000.0)),
                "",
            )?;
        }
        if !self.machine_profile.is_empty() {
            let profile = cell_profiles::MachineProfile::resolve(&self.machine_profile)
                .map_err(|e| invalid(file, "machine_profile", e.to_string().into()))?;
            if profile.gcode.as_ref().map(|g| g.dialect)
                != Some(cell_profiles::gcode::Dialect::Marlin)
            {
                return Err(invalid(
                    file,
                    "machine_profile",
                    format!(
                        "{}: not a Marlin profile (gcode.dialect must be marlin)",
                        self.machine_profile
                    )
                    .into(),
                ));
            }
        }
        Ok(())
    }

    /// The client's settings.
    pub fn client_config(&self) -> cell_marlin::client::ClientConfig {
        cell_marlin::client::ClientConfig {
            command_timeout: Duration::from_secs_f64(self.command_timeout_s),
            ..cell_marlin::client::ClientConfig::default()
        }
    }

    /// The endpoint, unless it is the simulator.
    pub fn endpoint(&self) -> Option<Endpoint> {
        self.endpoint.real_endpoint()
    }
}
