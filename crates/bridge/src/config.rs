//! Controller files (`config/controllers/*.yaml`): one file per controller, naming its protocol.
//!
//! A GRBL-class controller (GRBL 1.1, FluidNC, grblHAL):
//!
//! ```yaml
//! id: grbl-xyuv
//! protocol: grbl
//! machine_profile: grbl-xyuv        # programs emitted for another profile are refused
//! axes: XYUV                        # axis letters in the order the status report gives them
//! endpoint:
//!   serial: {path: /dev/ttyUSB0, baud: 115200}
//!   # tcp: 192.168.4.1:23           # FluidNC / ESP32 telnet
//!   # pty: /dev/pts/7               # e.g. `grbl_sim --pty`
//!   # simulator: {time_scale: 10}   # the in-repo GRBL 1.1 simulator, started by the bridge
//! flow: character_counting          # or send_response
//! status_period_s: 0.1              # `?` poll and MachineStatus period (GRBL: at most 5 Hz advised)
//! on_fault: safe_stop               # or hold: leave the machine in feed hold
//! resume_after_link_drop: operator  # or auto: reconnect and go on from the last acked line + 1
//! resume_timeout_s: 3               # resume: longest wait for the hold to complete (Hold:0)
//! allowed_commands: ["$H"]          # controller commands a program may carry; others are refused
//! ```
//!
//! An ABB robot is a [`cell_rws::ControllerConfig`] file with `protocol: rws`; its credentials
//! come from an environment variable or a file, never from the YAML.
//!
//! A Marlin printer is a `protocol: marlin` file ([`crate::marlin::config`]).
//!
//! Every error names the file and, where known, the line and the dotted field.

use std::path::{Path, PathBuf};
use std::time::Duration;

use cell_config::{Allowed, Bound, ParseError, Place, Problem};
use cell_grbl::stream::{ClientConfig, FaultAction, FlowControl};
use cell_grbl::transport::Endpoint;
use serde::Deserialize;

/// The controller files shipped in `config/controllers/`, embedded so the bridge finds them from
/// any directory: (id, YAML text).
pub const EMBEDDED_CONTROLLERS: &[(&str, &str)] = &[
    (
        "grbl-sim",
        include_str!("../../../config/controllers/grbl-sim.yaml"),
    ),
    (
        "grbl-xyuv",
        include_str!("../../../config/controllers/grbl-xyuv.yaml"),
    ),
    (
        "grbl-laser-sim",
        include_str!("../../../config/controllers/grbl-laser-sim.yaml"),
    ),
    (
        "abb-irb2600-waam",
        include_str!("../../../config/controllers/abb-irb2600-waam.yaml"),
    ),
    (
        "abb-irb1600-rw7-do",
        include_str!("../../../config/controllers/abb-irb1600-rw7-do.yaml"),
    ),
    (
        "abb-irb2600-waam-sim",
        include_str!("../../../config/controllers/abb-irb2600-waam-sim.yaml"),
    ),
    (
        "marlin-sim",
        include_str!("../../../config/controllers/marlin-sim.yaml"),
    ),
];

/// A controller the bridge drives.
#[derive(Debug, Clone, PartialEq)]
pub enum ControllerSpec {
    /// GRBL 1.1 protocol over serial, TCP, a pty or the in-process simulator.
    Grbl(GrblControllerConfig),
    /// ABB Robot Web Services.
    Rws(cell_rws::ControllerConfig),
    /// A Marlin 2 printer (or the in-process Marlin simulator).
    Marlin(crate::marlin::MarlinControllerConfig),
}

impl ControllerSpec {
    /// The controller id.
    pub fn id(&self) -> &str {
        match self {
            ControllerSpec::Grbl(g) => &g.id,
            ControllerSpec::Rws(r) => &r.id,
            ControllerSpec::Marlin(m) => &m.id,
        }
    }

    /// An embedded controller by id (case-insensitive), else a file path.
    ///
    /// # Errors
    /// [`ControllerFileError::Unknown`] for an id that is neither embedded nor a file; the
    /// errors of [`ControllerSpec::load`].
    pub fn resolve(id_or_path: &str) -> Result<Self, ControllerFileError> {
        let looks_like_path = id_or_path.contains('/')
            || id_or_path.ends_with(".yaml")
            || id_or_path.ends_with(".yml");
        if !looks_like_path {
            if let Some((id, text)) = EMBEDDED_CONTROLLERS
                .iter()
                .find(|(id, _)| id.eq_ignore_ascii_case(id_or_path))
            {
                return Self::from_yaml_str(text, &format!("config/controllers/{id}.yaml"), None);
            }
        }
        if looks_like_path || Path::new(id_or_path).is_file() {
            return Self::load(id_or_path);
        }
        Err(ControllerFileError::Unknown {
            id: id_or_path.into(),
            known: EMBEDDED_CONTROLLERS
                .iter()
                .map(|(id, _)| *id)
                .collect::<Vec<_>>()
                .join(", "),
        })
    }

    /// Reads and checks a controller file.
    ///
    /// # Errors
    /// [`ControllerFileError::Io`]; the errors of [`ControllerSpec::from_yaml_str`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ControllerFileError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ControllerFileError::Io {
            file: file.clone(),
            message: e.to_string(),
        })?;
        Self::from_yaml_str(&text, &file, path.parent())
    }

    /// Parses and checks a controller file's text; `file` names it in errors and `dir` (the
    /// file's directory) anchors a relative credentials file.
    ///
    /// # Errors
    /// Bad YAML, a missing or unknown `protocol`, an unknown or mistyped key (named with its
    /// line and dotted path), an invalid value; for RWS also a secret written in the YAML.
    pub fn from_yaml_str(
        text: &str,
        file: &str,
        dir: Option<&Path>,
    ) -> Result<Self, ControllerFileError> {
        let value: serde_norway::Value = cell_config::from_yaml_str(text, file)?;
        let protocol = value
            .get("protocol")
            .and_then(|p| p.as_str())
            .map(str::to_owned);
        match protocol.as_deref() {
            Some("grbl") => {
                let cfg: GrblControllerConfig = cell_config::from_yaml_str(text, file)?;
                cfg.check(file)?;
                Ok(ControllerSpec::Grbl(cfg))
            }
            Some("marlin") => {
                let cfg: crate::marlin::MarlinControllerConfig =
                    cell_config::from_yaml_str(text, file)?;
                cfg.check(file)?;
                Ok(ControllerSpec::Marlin(cfg))
            }
            Some("rws") => {
                let mut cfg = cell_rws::ControllerConfig::from_yaml_str(text, file)
                    .map_err(ControllerFileError::Rws)?;
                if let (Some(cell_rws::CredentialsSource::File(p)), Some(dir)) =
                    (&mut cfg.credentials, dir)
                {
                    if p.is_relative() {
                        *p = dir.join(&*p);
                    }
                }
                Ok(ControllerSpec::Rws(cfg))
            }
            other => Err(ControllerFileError::Invalid {
                file: file.into(),
                field: "protocol".into(),
                reason: match other {
                    Some(p) => format!("{p:?}: expected `grbl`, `marlin` or `rws`").into(),
                    None => "missing: say `protocol: grbl`, `protocol: marlin` or `protocol: rws`"
                        .into(),
                },
            }),
        }
    }
}

/// `file`'s `field` is wrong for `reason`.
pub(crate) fn invalid(file: &str, field: &str, reason: Problem) -> ControllerFileError {
    ControllerFileError::Invalid {
        file: file.into(),
        field: field.into(),
        reason,
    }
}

/// `value` of `file`'s `field` within `allowed`, in `unit`.
pub(crate) fn in_range(
    file: &str,
    field: &str,
    value: f64,
    allowed: Allowed,
    unit: &'static str,
) -> Result<(), ControllerFileError> {
    allowed
        .check(value, unit)
        .map_err(|e| invalid(file, field, e.into()))
}

/// Errors reading a controller file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ControllerFileError {
    /// Neither an embedded controller nor a file.
    #[error(
        "unknown controller {id:?}: not a file, and not one of the shipped controllers ({known})"
    )]
    Unknown {
        /// What was asked for.
        id: String,
        /// The embedded ids.
        known: String,
    },
    /// The file could not be read.
    #[error("{file}: {message}")]
    Io {
        /// The file.
        file: String,
        /// The I/O error.
        message: String,
    },
    /// The YAML does not parse or does not fit the schema (with its line and field).
    #[error(transparent)]
    Parse(#[from] ParseError),
    /// A value is out of range.
    #[error("{}{reason}", Place::field(file, field))]
    Invalid {
        /// The file.
        file: String,
        /// The field.
        field: String,
        /// What is wrong: a value out of range, or a rule.
        reason: Problem,
    },
    /// An RWS controller file's error.
    #[error(transparent)]
    Rws(cell_rws::config::ConfigError),
}

/// Where a serial-protocol controller is reached: a GRBL controller (`S` =
/// [`SimulatorConfig`]) or a Marlin printer (`S` = the Marlin simulator's settings).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum EndpointConfig<S = SimulatorConfig> {
    /// TCP/telnet `host:port` (a serial-to-network bridge for a printer).
    Tcp(String),
    /// A serial port.
    Serial {
        /// Device path.
        path: PathBuf,
        /// Baud rate (Marlin boards: 250 000 on many AVR ones, 115 200 on most others).
        #[serde(default = "default_baud")]
        baud: u32,
    },
    /// A pseudo-terminal device path.
    Pty(PathBuf),
    /// The in-repo simulator of the protocol, started by the bridge and reached over loopback
    /// TCP.
    Simulator(S),
}

impl<S> EndpointConfig<S> {
    /// The endpoint, unless it is the simulator (which has no address until it is started).
    pub fn real_endpoint(&self) -> Option<Endpoint> {
        match self {
            EndpointConfig::Tcp(a) => Some(Endpoint::Tcp(a.clone())),
            EndpointConfig::Serial { path, baud } => Some(Endpoint::Serial {
                path: path.clone(),
                baud: *baud,
            }),
            EndpointConfig::Pty(p) => Some(Endpoint::Pty(p.clone())),
            EndpointConfig::Simulator(_) => None,
        }
    }
}

fn default_baud() -> u32 {
    115_200
}

/// The simulator the bridge starts for an `endpoint: {simulator: …}` controller.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimulatorConfig {
    /// Simulated seconds per real second (10: ten times faster than the machine).
    pub time_scale: f64,
    /// Simulated serial baud rate; 0 for an unthrottled link.
    pub baud: u32,
    /// Rapid rate of every axis (mm/min).
    pub rapid_mm_min: f64,
    /// Which firmware the simulator speaks as: `grbl` (GRBL 1.1h, the default), `grblhal` or
    /// `fluidnc` (banner, `$I`, buffer sizes, report rules).
    pub firmware: SimulatorFirmware,
    /// GRBL's laser mode (`$32=1`): the output fires only during feed moves.
    pub laser_mode: bool,
}

impl Default for SimulatorConfig {
    fn default() -> Self {
        SimulatorConfig {
            time_scale: 1.0,
            baud: 115_200,
            rapid_mm_min: 3000.0,
            firmware: SimulatorFirmware::Grbl,
            laser_mode: false,
        }
    }
}

/// The simulator's firmware, as written in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SimulatorFirmware {
    /// GRBL 1.1h.
    #[default]
    Grbl,
    /// grblHAL.
    Grblhal,
    /// FluidNC.
    Fluidnc,
}

impl SimulatorFirmware {
    /// The simulator's flavour.
    pub fn flavour(self) -> cell_grbl::sim::SimFirmware {
        match self {
            SimulatorFirmware::Grbl => cell_grbl::sim::SimFirmware::Grbl11h,
            SimulatorFirmware::Grblhal => cell_grbl::sim::SimFirmware::GrblHal,
            SimulatorFirmware::Fluidnc => cell_grbl::sim::SimFirmware::FluidNc,
        }
    }
}

/// Flow control, as written in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FlowConfig {
    /// Fill the controller's RX buffer (bCNC, UGS default).
    #[default]
    CharacterCounting,
    /// One line at a time.
    SendResponse,
}

/// What happens after an alarm, a rejected line or an abort.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum OnFault {
    /// Feed hold, soft reset, `M5` (heat off).
    #[default]
    SafeStop,
    /// Feed hold only, for the operator.
    Hold,
}

/// What the bridge does when the link drops during a program.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ResumePolicy {
    /// End the goal with the last acknowledged line; the operator checks the machine and sends
    /// the program again with `start_line` set.
    #[default]
    Operator,
    /// Reconnect and go on from the line after the last acknowledged one. Only for controllers
    /// that lose unparsed input with the link and keep running their planner (FluidNC over
    /// TCP, the simulator); a board that resets when the port opens loses its planner.
    Auto,
}

/// Reconnection after a link drop.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReconnectConfig {
    /// Attempts per drop.
    pub attempts: u32,
    /// Pause between attempts (s).
    pub delay_s: f64,
    /// Most drops one goal survives with `resume_after_link_drop: auto`.
    pub max_resumes: u32,
}

impl Default for ReconnectConfig {
    fn default() -> Self {
        ReconnectConfig {
            attempts: 5,
            delay_s: 0.5,
            max_resumes: 100,
        }
    }
}

/// A GRBL-class controller file (module docs).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrblControllerConfig {
    /// Controller id (goals' `machine_id`, `MachineStatus.machine_id`).
    pub id: String,
    /// Always `grbl`.
    pub protocol: String,
    /// One line for people.
    #[serde(default)]
    pub description: String,
    /// The machine profile (`config/machines`) this controller runs; programs emitted for
    /// another profile are refused. Empty: any GRBL program.
    #[serde(default)]
    pub machine_profile: String,
    /// Axis letters in status-report order.
    #[serde(default = "default_axes")]
    pub axes: String,
    /// Where the controller is (a one-key map: `tcp`, `serial`, `pty` or `simulator`).
    #[serde(with = "serde_norway::with::singleton_map")]
    pub endpoint: EndpointConfig,
    /// Flow control.
    #[serde(default)]
    pub flow: FlowConfig,
    /// The controller's serial RX buffer (GRBL 1.1 on an AVR: 128; grblHAL often 1024).
    #[serde(default = "default_rx")]
    pub rx_buffer_bytes: usize,
    /// Ask the controller (`$I`) for its RX buffer on every connect and use what it says
    /// (grblHAL, FluidNC); `rx_buffer_bytes` stays the fallback.
    #[serde(default)]
    pub detect_rx_buffer: bool,
    /// Longest wait for the answer to a command (`M5`, `$G`, `$X`) and for a connection
    /// attempt (s), 0.5..120.
    #[serde(default = "default_command_timeout")]
    pub command_timeout_s: f64,
    /// Longest time (s), 0.5..120, a resume takes: waiting for the feed hold to complete before
    /// it sends `~` (GRBL drops a `~` while the hold decelerates), then for the controller to
    /// leave the hold (at least 1 s for that). Under `cell machine`'s 5 s answer timeout.
    #[serde(default = "default_resume_timeout")]
    pub resume_timeout_s: f64,
    /// Status poll and `MachineStatus` period (s).
    #[serde(default = "default_status_period")]
    pub status_period_s: f64,
    /// After a fault.
    #[serde(default)]
    pub on_fault: OnFault,
    /// Send `$X` after a safe stop's reset left the controller in alarm.
    #[serde(default)]
    pub unlock_after_reset: bool,
    /// After a link drop during a program.
    #[serde(default)]
    pub resume_after_link_drop: ResumePolicy,
    /// Reconnection.
    #[serde(default)]
    pub reconnect: ReconnectConfig,
    /// Controller commands (`$…`, `[ESP…]`) a program may carry, each a whole line, e.g. `$H`
    /// for homing at the start. None by default: a program line such as `$N0=M3S1000` or
    /// `$RST=*` is refused, naming the file, line and text, before anything is sent.
    #[serde(default)]
    pub allowed_commands: Vec<String>,
}

fn default_axes() -> String {
    "XYZ".into()
}

fn default_rx() -> usize {
    cell_grbl::protocol::RX_BUFFER_SIZE
}

fn default_command_timeout() -> f64 {
    10.0
}

fn default_resume_timeout() -> f64 {
    3.0
}

fn default_status_period() -> f64 {
    0.1
}

impl GrblControllerConfig {
    fn check(&self, file: &str) -> Result<(), ControllerFileError> {
        if self.id.trim().is_empty() {
            return Err(invalid(file, "id", "empty".into()));
        }
        if let Some(bad) = self
            .allowed_commands
            .iter()
            .find(|c| !cell_grbl::program::is_controller_command(c.trim()))
        {
            return Err(invalid(
                file,
                "allowed_commands",
                format!("{bad:?} is not a controller command (`$…` or `[ESP…]`)").into(),
            ));
        }
        let axes: Vec<char> = self.axes.chars().collect();
        if axes.is_empty()
            || axes.len() > 6
            || axes.iter().any(|c| !"XYZABCUVW".contains(*c))
            || (1..axes.len()).any(|i| axes[..i].contains(&axes[i]))
        {
            return Err(invalid(
                file,
                "axes",
                format!(
                    "{:?}: 1 to 6 distinct letters of XYZABCUVW, in report order",
                    self.axes
                )
                .into(),
            ));
        }
        if !self.machine_profile.is_empty() {
            let profile = cell_profiles::MachineProfile::resolve(&self.machine_profile)
                .map_err(|e| invalid(file, "machine_profile", e.to_string().into()))?;
            if let Some(missing) = axes.iter().find(|a| !profile.axes.contains_key(a)) {
                return Err(invalid(
                    file,
                    "axes",
                    format!("{missing} is not an axis of machine {}", profile.name).into(),
                ));
            }
        }
        in_range(
            file,
            "rx_buffer_bytes",
            self.rx_buffer_bytes as f64,
            Allowed::closed(16.0, 65_536.0).whole(),
            "bytes",
        )?;
        in_range(
            file,
            "command_timeout_s",
            self.command_timeout_s,
            Allowed::closed(0.5, 120.0),
            "s",
        )?;
        in_range(
            file,
            "resume_timeout_s",
            self.resume_timeout_s,
            Allowed::closed(0.5, 120.0),
            "s",
        )?;
        // GRBL advises at most 5 Hz of `?`; faster than 50 Hz only loads the link.
        in_range(
            file,
            "status_period_s",
            self.status_period_s,
            Allowed::closed(0.02, 1.0),
            "s",
        )?;
        let r = &self.reconnect;
        if r.attempts == 0 || !(r.delay_s.is_finite() && (0.0..=60.0).contains(&r.delay_s)) {
            return Err(invalid(
                file,
                "reconnect",
                "attempts >= 1 and delay_s in 0..60 s".into(),
            ));
        }
        match &self.endpoint {
            EndpointConfig::Serial { baud, .. } => in_range(
                file,
                "endpoint.serial.baud",
                f64::from(*baud),
                Allowed::at_least(1.0).whole(),
                "baud",
            )?,
            EndpointConfig::Simulator(s) => {
                in_range(
                    file,
                    "endpoint.simulator.time_scale",
                    s.time_scale,
                    Allowed::between(Bound::Exclusive(0.0), Bound::Inclusive(1000.0)),
                    "",
                )?;
                in_range(
                    file,
                    "endpoint.simulator.rapid_mm_min",
                    s.rapid_mm_min,
                    Allowed::POSITIVE,
                    "mm/min",
                )?;
            }
            _ => {}
        }
        // A board on a serial line (or a pty standing in for one) resets when the port is
        // opened again: its planner, modal state and position are gone, so going on from the
        // last acknowledged line would run the rest of the program from the wrong state.
        if self.resume_after_link_drop == ResumePolicy::Auto
            && matches!(
                self.endpoint,
                EndpointConfig::Serial { .. } | EndpointConfig::Pty(_)
            )
        {
            return Err(invalid(
                file,
                "resume_after_link_drop",
                "`auto` needs a controller that keeps its state over a reconnect (TCP, e.g. \
                 FluidNC, or the simulator); a serial or pty board resets when its port is \
                 opened: use `operator`"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Axis letters in report order.
    pub fn axis_letters(&self) -> Vec<char> {
        self.axes.chars().collect()
    }

    /// The streaming client's settings.
    pub fn client_config(&self) -> ClientConfig {
        let period = Duration::from_secs_f64(self.status_period_s);
        ClientConfig {
            flow: match self.flow {
                FlowConfig::CharacterCounting => FlowControl::CharacterCounting,
                FlowConfig::SendResponse => FlowControl::SendResponse,
            },
            rx_buffer_bytes: self.rx_buffer_bytes,
            status_period: period,
            on_fault: match self.on_fault {
                OnFault::SafeStop => FaultAction::SafeStop,
                OnFault::Hold => FaultAction::HoldOnly,
            },
            unlock_after_reset: self.unlock_after_reset,
            reconnect_attempts: self.reconnect.attempts,
            reconnect_delay: Duration::from_secs_f64(self.reconnect.delay_s),
            // A controller silent for ten polls (at least 2 s) is gone, though its link is up.
            status_timeout: (period * 10).max(Duration::from_secs(2)),
            command_timeout: Duration::from_secs_f64(self.command_timeout_s),
            detect_rx_buffer: self.detect_rx_buffer,
            ..ClientConfig::default()
        }
    }

    /// The endpoint, unless it is the simulator (which has no address until it is started).
    pub fn endpoint(&self) -> Option<Endpoint> {
        self.endpoint.real_endpoint()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_controller_file_loads() {
        // RobotWare 7 serves RWS over HTTPS only, which needs the `tls` feature.
        let needs_tls = |text: &str| text.contains("url: https://");
        for (id, text) in EMBEDDED_CONTROLLERS {
            match ControllerSpec::resolve(id) {
                Ok(spec) => assert_eq!(spec.id(), *id),
                Err(e) if needs_tls(text) && !cfg!(feature = "tls") => {
                    assert!(e.to_string().contains("`tls` feature"), "{e}")
                }
                Err(e) => panic!("{e}"),
            }
        }
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/controllers");
        let mut on_disk: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
            .map(|p| {
                let text = std::fs::read_to_string(&p).unwrap();
                match ControllerSpec::load(&p) {
                    Ok(spec) => spec.id().to_owned(),
                    Err(_) if needs_tls(&text) && !cfg!(feature = "tls") => {
                        p.file_stem().unwrap().to_string_lossy().into_owned()
                    }
                    Err(e) => panic!("{e}"),
                }
            })
            .collect();
        on_disk.sort();
        let mut embedded: Vec<String> = EMBEDDED_CONTROLLERS
            .iter()
            .map(|(id, _)| id.to_string())
            .collect();
        embedded.sort();
        assert_eq!(
            on_disk, embedded,
            "every file in config/controllers is embedded"
        );
    }

    #[test]
    fn grbl_files_parse_with_defaults() {
        let text = "id: bench\nprotocol: grbl\nendpoint:\n  tcp: 10.0.0.5:23\n";
        let ControllerSpec::Grbl(g) = ControllerSpec::from_yaml_str(text, "t.yaml", None).unwrap()
        else {
            panic!("grbl")
        };
        assert_eq!(g.endpoint(), Some(Endpoint::Tcp("10.0.0.5:23".into())));
        assert_eq!(g.axis_letters(), vec!['X', 'Y', 'Z']);
        let c = g.client_config();
        assert_eq!(c.flow, FlowControl::CharacterCounting);
        assert_eq!(c.status_period, Duration::from_millis(100));
        assert_eq!(g.resume_after_link_drop, ResumePolicy::Operator);
    }

    #[test]
    fn auto_resume_is_refused_for_boards_that_reset_when_their_port_opens() {
        let load = |endpoint: &str, policy: &str| {
            let text = format!(
                "id: a\nprotocol: grbl\nendpoint: {endpoint}\nresume_after_link_drop: {policy}\n"
            );
            ControllerSpec::from_yaml_str(&text, "c.yaml", None).map_err(|e| e.to_string())
        };
        for endpoint in ["{serial: {path: /dev/ttyUSB0}}", "{pty: /dev/pts/7}"] {
            let e = load(endpoint, "auto").unwrap_err();
            assert!(
                e.contains("c.yaml")
                    && e.contains("resume_after_link_drop")
                    && e.contains("`operator`"),
                "{endpoint}: {e}"
            );
            assert!(load(endpoint, "operator").is_ok(), "{endpoint}");
        }
        assert!(load("{tcp: '192.168.4.1:23'}", "auto").is_ok());
        assert!(load("{simulator: {time_scale: 10}}", "auto").is_ok());
    }

    #[test]
    fn errors_name_file_line_and_field() {
        let err = |text: &str| {
            ControllerSpec::from_yaml_str(text, "c.yaml", None)
                .unwrap_err()
                .to_string()
        };
        let e = err("id: a\nendpoint: {tcp: 'h:1'}\n");
        assert!(e.contains("c.yaml") && e.contains("protocol"), "{e}");
        let e = err("id: a\nprotocol: modbus\n");
        assert!(e.contains("\"modbus\""), "{e}");
        let e = err("id: a\nprotocol: grbl\nendpoint: {tcp: 'h:1'}\nflwo: send_response\n");
        assert!(e.starts_with("c.yaml:4") && e.contains("flwo"), "{e}");
        let e = err("id: a\nprotocol: grbl\nendpoint: {tcp: 'h:1'}\nflow: xon_xoff\n");
        assert!(e.contains("field `flow`"), "{e}");
        let e = err("id: a\nprotocol: grbl\nendpoint: {usb: 'x'}\n");
        assert!(e.contains("c.yaml:3") && e.contains("usb"), "{e}");
        let e = err("id: a\nprotocol: grbl\naxes: XXY\nendpoint: {tcp: 'h:1'}\n");
        assert!(e.contains("field `axes`"), "{e}");
        let e = err(
            "id: a\nprotocol: grbl\nmachine_profile: grbl-xy\naxes: XYZ\nendpoint: {tcp: 'h:1'}\n",
        );
        assert!(e.contains("Z is not an axis of machine grbl-xy"), "{e}");
        let e = err("id: a\nprotocol: grbl\nstatus_period_s: 5\nendpoint: {tcp: 'h:1'}\n");
        assert!(e.contains("status_period_s"), "{e}");
        let e = err("id: a\nprotocol: grbl\nresume_timeout_s: 0\nendpoint: {tcp: 'h:1'}\n");
        assert!(e.contains("resume_timeout_s"), "{e}");
        let e = err(
            "id: a\nprotocol: rws\nrws: rw6\nport: 80\ncredentials: {env: X}\npassword: hunter2\n",
        );
        assert!(
            e.contains("password") && e.contains("environment variable"),
            "{e}"
        );
        let e = ControllerSpec::resolve("abb-9000").unwrap_err().to_string();
        assert!(e.contains("abb-9000") && e.contains("grbl-sim"), "{e}");
    }
}
