//! Controller configuration (`config/controllers/*.yaml`) and credentials.
//!
//! ```yaml
//! id: abb-irb2600-waam
//! url: http://192.168.125.1      # or `port: 8080` for a controller on this host (loopback)
//! rws: rw6                       # rw6 (RWS 1.0, IRC5) or rw7 (RWS 2.0, OmniCore)
//! credentials:
//!   env: CELL_RWS_IRB2600        # "user:password" in this environment variable
//! # credentials: {file: /etc/cellsuite/irb2600.cred}   # or in this file (first line)
//! task: T_ROB1                   # default
//! program_dir: cellsuite         # under the controller's HOME; default
//! timeouts: {connect_s: 5.0, request_s: 30.0, control_s: 2.0}
//! reconnect: {attempts: 5, delay_s: 1.0}   # stop + heat off after a lost link; default
//! protocol: rws                  # optional; the machine bridge reads it
//! heat_off_outputs:              # written on hold, abort and a lost link; default none
//!   - {signal: doWeld, value: "0"}
//! # tls: {pin_sha256: "3A:04:…"} # https:// only: the controller certificate's SHA-256
//! ```
//!
//! The password never crosses the network in clear: RobotWare 7 logs in with HTTP Basic, so
//! `rws: rw7` needs an `https://` URL (or a controller on this host); the client also refuses
//! a Basic challenge over plain HTTP from any other host ([`crate::RwsError::InsecureAuth`]).
//! RobotWare 6's Digest login sends no password and may use `http://`. Over HTTPS the client
//! accepts the certificate whose SHA-256 is `tls.pin_sha256` (OmniCore's own certificate is
//! self-signed), else one a public root vouches for; the old `accept_invalid_certs` is refused
//! with a pointer to the pin.
//!
//! Credentials never sit in the YAML: a `password` (or `user`) key anywhere in the file is
//! refused with an error that says where to put it instead. The secret is `user:password`
//! (split at the first `:`, so the password may hold colons), read from the environment
//! variable or from the first line of the file when the client is made, not when the YAML
//! is parsed.

use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Duration;

use cell_config::{Allowed, Bound, ParseError, Place, Problem};
use serde::Deserialize;

use crate::pin::CertPin;

/// Which Robot Web Services generation the controller speaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RwsVersion {
    /// RWS 1.0: RobotWare 6 on IRC5. HTTP, Digest login, query actions (`?action=start`),
    /// XHTML or `?json=1` bodies, files under `$HOME`.
    Rw6,
    /// RWS 2.0: RobotWare 7 on OmniCore. HTTPS, Basic login, path actions
    /// (`/execution/start`), `application/hal+json;v=2.0` bodies, files under `HOME`.
    Rw7,
}

impl fmt::Display for RwsVersion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RwsVersion::Rw6 => "rw6",
            RwsVersion::Rw7 => "rw7",
        })
    }
}

/// Where the `user:password` secret comes from (module docs). In YAML a map with exactly one
/// of the keys `env` and `file`.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(try_from = "CredentialsYaml")]
pub enum CredentialsSource {
    /// The named environment variable holds `user:password`.
    Env(String),
    /// The first line of this file holds `user:password`; a relative path is taken from the
    /// directory of the configuration file.
    File(PathBuf),
    /// Given in-process, never read from YAML: the bridge's own simulator (`simulator:`)
    /// makes a fresh login when it starts.
    Given(Credentials),
}

/// The YAML form of [`CredentialsSource`] (serde_norway reads enums only from YAML tags).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CredentialsYaml {
    env: Option<String>,
    file: Option<PathBuf>,
}

impl TryFrom<CredentialsYaml> for CredentialsSource {
    type Error = String;
    fn try_from(y: CredentialsYaml) -> Result<Self, String> {
        match (y.env, y.file) {
            (Some(var), None) if !var.trim().is_empty() => Ok(CredentialsSource::Env(var)),
            (None, Some(path)) if !path.as_os_str().is_empty() => Ok(CredentialsSource::File(path)),
            (Some(_), Some(_)) => Err("give either `env` or `file`, not both".into()),
            _ => Err("give `env: VARIABLE` or `file: PATH` (non-empty)".into()),
        }
    }
}

impl fmt::Display for CredentialsSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CredentialsSource::Env(var) => write!(f, "${var}"),
            CredentialsSource::File(path) => write!(f, "{}", path.display()),
            CredentialsSource::Given(c) => write!(f, "the simulator's login for {}", c.user),
        }
    }
}

/// A user name and password for the controller. `Debug` does not show the password.
#[derive(Clone, PartialEq, Eq)]
pub struct Credentials {
    /// Controller user name (RobotWare's UAS user, e.g. the factory "Default User").
    pub user: String,
    /// Its password.
    pub password: String,
}

impl fmt::Debug for Credentials {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Credentials")
            .field("user", &self.user)
            .field("password", &"<redacted>")
            .finish()
    }
}

impl CredentialsSource {
    /// Reads the secret now.
    ///
    /// # Errors
    /// The variable is unset or not Unicode, the file is unreadable, or the secret is not
    /// `user:password` with a non-empty user.
    pub fn load(&self) -> Result<Credentials, ConfigError> {
        let (text, from) = match self {
            CredentialsSource::Given(c) => return Ok(c.clone()),
            CredentialsSource::Env(var) => match std::env::var(var) {
                Ok(v) => (v, format!("${var}")),
                Err(std::env::VarError::NotPresent) => {
                    return Err(ConfigError::Credentials {
                        from: format!("${var}"),
                        message: format!("not set (export {var}='user:password')"),
                    })
                }
                Err(std::env::VarError::NotUnicode(_)) => {
                    return Err(ConfigError::Credentials {
                        from: format!("${var}"),
                        message: "not valid Unicode".into(),
                    })
                }
            },
            CredentialsSource::File(path) => match std::fs::read_to_string(path) {
                Ok(t) => (
                    t.lines().next().unwrap_or_default().to_owned(),
                    path.display().to_string(),
                ),
                Err(e) => {
                    return Err(ConfigError::Credentials {
                        from: path.display().to_string(),
                        message: format!("cannot read: {e}"),
                    })
                }
            },
        };
        let text = text.trim_end_matches(['\r', '\n']);
        match text.split_once(':') {
            Some((user, password)) if !user.trim().is_empty() => Ok(Credentials {
                user: user.to_owned(),
                password: password.to_owned(),
            }),
            _ => Err(ConfigError::Credentials {
                from,
                message: "expected `user:password` (user non-empty)".into(),
            }),
        }
    }
}

/// Request timeouts, seconds.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Timeouts {
    /// TCP (and TLS) connect timeout, s.
    pub connect_s: f64,
    /// Whole-request timeout (send and read the answer) of logins, uploads and program
    /// loads, s.
    pub request_s: f64,
    /// Whole-request timeout of the requests that drive and watch a run (start, stop, the
    /// execution state, I/O), s: short, so a poll that hangs on a dead link cannot keep an
    /// abort or a safe stop waiting. At most 60.
    pub control_s: f64,
}

impl Default for Timeouts {
    fn default() -> Self {
        Timeouts {
            connect_s: 5.0,
            request_s: 30.0,
            control_s: 2.0,
        }
    }
}

impl Timeouts {
    /// The connect timeout as a `Duration`.
    pub fn connect(&self) -> Duration {
        Duration::from_secs_f64(self.connect_s)
    }
    /// The request timeout as a `Duration`.
    pub fn request(&self) -> Duration {
        Duration::from_secs_f64(self.request_s)
    }
    /// The run-control request timeout as a `Duration`.
    pub fn control(&self) -> Duration {
        Duration::from_secs_f64(self.control_s)
    }
}

/// How hard a safe stop is tried when the link is lost during a run: RAPID stop and the
/// heat-off outputs, read back, up to `attempts` times, `delay_s` apart.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Reconnect {
    /// Attempts, 1 to 1000.
    pub attempts: u32,
    /// Pause between attempts, s.
    pub delay_s: f64,
}

impl Default for Reconnect {
    fn default() -> Self {
        Reconnect {
            attempts: 5,
            delay_s: 1.0,
        }
    }
}

impl Reconnect {
    /// The pause as a `Duration`.
    pub fn delay(&self) -> Duration {
        Duration::from_secs_f64(self.delay_s)
    }
}

/// HTTPS settings (`tls:`), for an `https://` URL.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TlsConfig {
    /// SHA-256 fingerprint of the controller's certificate (`AB:CD:…`, as `openssl x509
    /// -noout -fingerprint -sha256` prints it): only that certificate is accepted. Without
    /// it the certificate must chain to a public root.
    #[serde(default)]
    pub pin_sha256: Option<CertPin>,
}

fn default_task() -> String {
    "T_ROB1".into()
}

fn default_program_dir() -> String {
    "cellsuite".into()
}

/// One controller, as read from `config/controllers/NAME.yaml` (module docs).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerConfig {
    /// Controller id, used in every error message and log line.
    pub id: String,
    /// Base URL, e.g. `http://192.168.125.1` or `https://omnicore:443`. Exactly one of `url`
    /// and `port` is given.
    #[serde(default)]
    pub url: Option<String>,
    /// Port on this host (loopback, plain HTTP): a virtual controller or the simulator.
    #[serde(default)]
    pub port: Option<u16>,
    /// RWS generation.
    pub rws: RwsVersion,
    /// Where the login secret comes from; never the secret itself. Required unless
    /// `simulator` is given.
    #[serde(default)]
    pub credentials: Option<CredentialsSource>,
    /// Instead of `url`/`port`: the in-repo RWS simulator ([`crate::sim`]), started by the
    /// machine bridge on loopback with a fresh login (no `credentials`).
    #[serde(default)]
    pub simulator: Option<SimulatorEndpoint>,
    /// Request timeouts.
    #[serde(default)]
    pub timeouts: Timeouts,
    /// RAPID task the program is loaded into.
    #[serde(default = "default_task")]
    pub task: String,
    /// Directory under the controller's HOME that programs are uploaded to (created if
    /// missing); empty means HOME itself.
    #[serde(default = "default_program_dir")]
    pub program_dir: String,
    /// HTTPS settings: the pinned certificate.
    #[serde(default)]
    pub tls: Option<TlsConfig>,
    /// Retries of the safe stop after a lost link.
    #[serde(default)]
    pub reconnect: Reconnect,
    /// `rws` when given (the machine bridge's controller files name their protocol; a GRBL
    /// controller file says `grbl` and is not read by this crate).
    #[serde(default)]
    pub protocol: Option<String>,
    /// Outputs written, in order, whenever RAPID is stopped by the bridge (hold, abort, cancel,
    /// a lost link), and read back to confirm the heat is off: RAPID keeps a digital output
    /// where it is when it stops, so a program stopped between its `SetDO doWeld, 1` and its
    /// `SetDO doWeld, 0` would leave the weld power on. Arc-welding cells (`ArcL`) stop the
    /// arc with the program and need none.
    #[serde(default)]
    pub heat_off_outputs: Vec<SignalValue>,
}

/// The `simulator:` endpoint of a controller file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimulatorEndpoint {
    /// How long a started program "runs" before RAPID stops by itself, s. Default 2.
    pub run_s: f64,
}

impl Default for SimulatorEndpoint {
    fn default() -> Self {
        SimulatorEndpoint { run_s: 2.0 }
    }
}

/// A signal and the value to write to it.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SignalValue {
    /// Signal name: bare on RobotWare 6 (`doWeld`), `NETWORK/DEVICE/NAME` on RobotWare 7.
    pub signal: String,
    /// Value as RWS writes it (`0`/`1` for digital signals).
    pub value: String,
}

/// Errors reading a controller configuration or its credentials.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{file}: {message}")]
    Io {
        /// The configuration file.
        file: String,
        /// The I/O error.
        message: String,
    },
    /// The YAML does not parse or does not fit the schema (with its line and field).
    #[error(transparent)]
    Parse(#[from] ParseError),
    /// A password (or user name) is written in the YAML.
    #[error("{}credentials must not be written in the configuration; put `user:password` in an environment variable (credentials: {{env: VAR}}) or a file outside the repository (credentials: {{file: PATH}})", Place::field(file, field))]
    InlineSecret {
        /// The configuration file.
        file: String,
        /// The offending key.
        field: String,
    },
    /// A value is out of range or inconsistent with another.
    #[error("{}{reason}", Place::field(file, field))]
    Invalid {
        /// The configuration file.
        file: String,
        /// The offending field.
        field: String,
        /// What is wrong: a value out of range, or a rule.
        reason: Problem,
    },
    /// The credentials could not be read.
    #[error("credentials from {from}: {message}")]
    Credentials {
        /// `$VAR` or the file path.
        from: String,
        /// What is wrong.
        message: String,
    },
}

/// Keys that hold secrets and so may not appear in the YAML.
const SECRET_KEYS: [&str; 5] = ["password", "passwd", "pass", "user", "username"];

fn find_secret(value: &serde_norway::Value, prefix: &str) -> Option<String> {
    let serde_norway::Value::Mapping(map) = value else {
        return None;
    };
    for (k, v) in map {
        let Some(key) = k.as_str() else { continue };
        let path = if prefix.is_empty() {
            key.to_owned()
        } else {
            format!("{prefix}.{key}")
        };
        if SECRET_KEYS.contains(&key.to_ascii_lowercase().as_str()) {
            return Some(path);
        }
        if let Some(found) = find_secret(v, &path) {
            return Some(found);
        }
    }
    None
}

impl ControllerConfig {
    /// Reads and checks a configuration file; a relative credentials file is resolved against
    /// the file's directory.
    ///
    /// # Errors
    /// See [`ControllerConfig::from_yaml_str`]; also [`ConfigError::Io`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ConfigError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ConfigError::Io {
            file: name.clone(),
            message: e.to_string(),
        })?;
        let mut cfg = Self::from_yaml_str(&text, &name)?;
        if let Some(CredentialsSource::File(p)) = &mut cfg.credentials {
            if p.is_relative() {
                if let Some(dir) = path.parent() {
                    *p = dir.join(&*p);
                }
            }
        }
        Ok(cfg)
    }

    /// Parses and checks YAML text; `source_name` names it in errors.
    ///
    /// # Errors
    /// Bad YAML, an unknown or mistyped key (named with its dotted path), a secret in the
    /// YAML, both or neither of `url` and `port`, a URL that is not `http://` or `https://`,
    /// an `https://` URL without the `tls` feature, a timeout that is not positive.
    pub fn from_yaml_str(text: &str, source_name: &str) -> Result<Self, ConfigError> {
        let value: serde_norway::Value = cell_config::from_yaml_str(text, source_name)?;
        if let Some(field) = find_secret(&value, "") {
            return Err(ConfigError::InlineSecret {
                file: source_name.into(),
                field,
            });
        }
        if value.get("accept_invalid_certs").is_some() {
            return Err(ConfigError::Invalid {
                file: source_name.into(),
                field: "accept_invalid_certs".into(),
                reason: "no longer read (it accepted any certificate, a man in the middle's too): pin the controller's own certificate instead, `tls: {pin_sha256: \"AB:CD:…\"}` with its SHA-256 fingerprint (a mismatch names the one seen)".into(),
            });
        }
        let cfg: ControllerConfig = cell_config::from_yaml_str(text, source_name)?;
        cfg.check(source_name)?;
        Ok(cfg)
    }

    fn check(&self, file: &str) -> Result<(), ConfigError> {
        let invalid = |field: &str, reason: Problem| ConfigError::Invalid {
            file: file.into(),
            field: field.into(),
            reason,
        };
        if self.id.trim().is_empty() {
            return Err(invalid("id", "empty".into()));
        }
        if let Some(sim) = &self.simulator {
            if self.url.is_some() || self.port.is_some() {
                return Err(invalid(
                    "simulator",
                    "give one of `url`, `port` and `simulator`".into(),
                ));
            }
            if self.credentials.is_some() {
                return Err(invalid(
                    "credentials",
                    "the simulator makes its own login: remove `credentials`".into(),
                ));
            }
            Allowed::between(Bound::Inclusive(0.0), Bound::Exclusive(1e6))
                .check(sim.run_s, "s")
                .map_err(|e| invalid("simulator.run_s", e.into()))?;
        } else if self.credentials.is_none() {
            return Err(invalid(
                "credentials",
                "missing: give `credentials: {env: VARIABLE}` or `{file: PATH}`".into(),
            ));
        }
        match (&self.url, self.port) {
            _ if self.simulator.is_some() => {}
            (Some(_), Some(_)) => {
                return Err(invalid(
                    "url",
                    "give either `url` or `port`, not both".into(),
                ))
            }
            (None, None) => {
                return Err(invalid(
                    "url",
                    "missing (or give `port` or `simulator`)".into(),
                ))
            }
            (Some(url), None) => {
                let https = url.starts_with("https://");
                if !https && !url.starts_with("http://") {
                    return Err(invalid(
                        "url",
                        format!("{url:?}: expected http://HOST[:PORT] or https://HOST[:PORT]")
                            .into(),
                    ));
                }
                if https && !cfg!(feature = "tls") {
                    return Err(invalid(
                        "url",
                        format!("{url:?}: HTTPS needs cell_rws built with the `tls` feature")
                            .into(),
                    ));
                }
                if !https && self.rws == RwsVersion::Rw7 && !is_loopback_url(url) {
                    return Err(invalid(
                        "url",
                        format!("{url:?}: rws: rw7 logs in with HTTP Basic, which would send the password in clear over http://; use https://")
                            .into(),
                    ));
                }
            }
            (None, Some(0)) => return Err(invalid("port", "0 is not a port".into())),
            (None, Some(_)) => {}
        }
        if self.tls.is_some() && !self.base_url().starts_with("https://") {
            return Err(invalid(
                "tls",
                "only for an https:// url (this controller is reached over plain HTTP)".into(),
            ));
        }
        for (field, v) in [
            ("timeouts.connect_s", self.timeouts.connect_s),
            ("timeouts.request_s", self.timeouts.request_s),
        ] {
            Allowed::between(Bound::Exclusive(0.0), Bound::Exclusive(1e6))
                .check(v, "s")
                .map_err(|e| invalid(field, e.into()))?;
        }
        Allowed::between(Bound::Exclusive(0.0), Bound::Inclusive(60.0))
            .check(self.timeouts.control_s, "s")
            .map_err(|e| invalid("timeouts.control_s", e.into()))?;
        Allowed::between(Bound::Inclusive(1.0), Bound::Inclusive(1000.0))
            .check(f64::from(self.reconnect.attempts), "")
            .map_err(|e| invalid("reconnect.attempts", e.into()))?;
        Allowed::between(Bound::Inclusive(0.0), Bound::Inclusive(3600.0))
            .check(self.reconnect.delay_s, "s")
            .map_err(|e| invalid("reconnect.delay_s", e.into()))?;
        if self.task.trim().is_empty() {
            return Err(invalid("task", "empty".into()));
        }
        if let Some(p) = self.protocol.as_deref().filter(|p| *p != "rws") {
            return Err(invalid(
                "protocol",
                format!("{p:?}: an RWS controller file says `rws`").into(),
            ));
        }
        for (i, out) in self.heat_off_outputs.iter().enumerate() {
            if out.signal.trim().is_empty() || out.value.trim().is_empty() {
                return Err(invalid(
                    &format!("heat_off_outputs[{i}]"),
                    "signal and value must not be empty".into(),
                ));
            }
        }
        if self
            .program_dir
            .split('/')
            .any(|s| s == ".." || s == "." || s.contains('\\'))
            || self.program_dir.starts_with('/')
        {
            return Err(invalid(
                "program_dir",
                format!("{:?}: a relative path under HOME", self.program_dir).into(),
            ));
        }
        Ok(())
    }

    /// Whether the controller is on this host (`port:`, the simulator, or a loopback URL).
    pub fn is_loopback(&self) -> bool {
        is_loopback_url(&self.base_url())
    }

    /// The base URL (no trailing slash).
    pub fn base_url(&self) -> String {
        match (&self.url, self.port) {
            (Some(url), _) => url.trim_end_matches('/').to_owned(),
            (None, Some(port)) => format!("http://127.0.0.1:{port}"),
            (None, None) => String::new(),
        }
    }

    /// A configuration for a controller on this host, e.g. a simulator: credentials from the
    /// given source, other fields at their defaults.
    pub fn loopback(id: &str, port: u16, rws: RwsVersion, credentials: CredentialsSource) -> Self {
        ControllerConfig {
            id: id.into(),
            url: None,
            port: Some(port),
            rws,
            credentials: Some(credentials),
            simulator: None,
            timeouts: Timeouts::default(),
            task: default_task(),
            program_dir: default_program_dir(),
            tls: None,
            reconnect: Reconnect::default(),
            protocol: None,
            heat_off_outputs: Vec::new(),
        }
    }
}

/// Whether `url`'s host is this host: `localhost`, `127.0.0.0/8` or `[::1]`.
pub(crate) fn is_loopback_url(url: &str) -> bool {
    let rest = url.split_once("://").map_or(url, |(_, r)| r);
    let authority = rest.split(['/', '?', '#']).next().unwrap_or_default();
    let host_port = authority.rsplit_once('@').map_or(authority, |(_, h)| h);
    let host = match host_port.strip_prefix('[') {
        Some(v6) => v6.split(']').next().unwrap_or_default(),
        None => host_port.split(':').next().unwrap_or_default(),
    };
    host.eq_ignore_ascii_case("localhost")
        || host
            .parse::<std::net::IpAddr>()
            .is_ok_and(|ip| ip.is_loopback())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_a_full_file() {
        let cfg = ControllerConfig::from_yaml_str(
            "id: r1\nurl: http://10.0.0.1/\nrws: rw6\ncredentials:\n  env: R1_CRED\ntimeouts: {request_s: 10}\n",
            "r1.yaml",
        )
        .unwrap();
        assert_eq!(cfg.base_url(), "http://10.0.0.1");
        assert_eq!(
            cfg.credentials,
            Some(CredentialsSource::Env("R1_CRED".into()))
        );
        assert_eq!(cfg.task, "T_ROB1");
        assert_eq!(cfg.timeouts.connect_s, 5.0);
        assert_eq!(cfg.timeouts.request_s, 10.0);
    }

    #[test]
    fn errors_name_file_and_field() {
        let e = ControllerConfig::from_yaml_str(
            "id: r1\nport: 80\nrws: rw6\ncredentials: {env: X}\ntimeouts: {request: 10}\n",
            "r1.yaml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("r1.yaml:5: field `timeouts.request`: unknown field `request`"),
            "{e}"
        );

        let e = ControllerConfig::from_yaml_str(
            "id: r1\nport: 80\nrws: rw8\ncredentials: {env: X}\n",
            "r1.yaml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("field `rws`"), "{e}");

        let e = ControllerConfig::from_yaml_str(
            "id: r1\nport: 80\nurl: http://x\nrws: rw6\ncredentials: {env: X}\n",
            "r1.yaml",
        )
        .unwrap_err()
        .to_string();
        assert_eq!(
            e,
            "r1.yaml: field `url`: give either `url` or `port`, not both"
        );
    }

    #[test]
    fn inline_password_is_refused() {
        for yaml in [
            "id: r1\nport: 80\nrws: rw6\ncredentials: {env: X}\npassword: robotics\n",
            "id: r1\nport: 80\nrws: rw6\ncredentials:\n  user: Default User\n  password: robotics\n",
        ] {
            let e = ControllerConfig::from_yaml_str(yaml, "r1.yaml").unwrap_err();
            assert!(matches!(e, ConfigError::InlineSecret { .. }), "{e}");
            let text = e.to_string();
            assert!(text.contains("must not be written in the configuration"), "{text}");
            assert!(!text.contains("robotics"), "{text}");
        }
    }

    #[test]
    fn run_timeouts_and_retries_are_checked() {
        let cfg = ControllerConfig::from_yaml_str(
            "id: r1\nport: 80\nrws: rw6\ncredentials: {env: X}\n",
            "r1.yaml",
        )
        .unwrap();
        assert_eq!(cfg.timeouts.control_s, 2.0);
        assert_eq!(cfg.reconnect, Reconnect::default());
        for (extra, field) in [
            ("timeouts: {control_s: 0}", "timeouts.control_s"),
            ("timeouts: {control_s: 120}", "timeouts.control_s"),
            ("reconnect: {attempts: 0}", "reconnect.attempts"),
            ("reconnect: {delay_s: -1}", "reconnect.delay_s"),
        ] {
            let e = ControllerConfig::from_yaml_str(
                &format!("id: r1\nport: 80\nrws: rw6\ncredentials: {{env: X}}\n{extra}\n"),
                "r1.yaml",
            )
            .unwrap_err()
            .to_string();
            assert!(
                e.starts_with(&format!("r1.yaml: field `{field}`: ")),
                "{extra}: {e}"
            );
        }
    }

    #[test]
    fn basic_login_over_plain_http_to_another_host_is_refused() {
        let e = ControllerConfig::from_yaml_str(
            "id: r7\nurl: http://192.168.125.1\nrws: rw7\ncredentials: {env: X}\n",
            "r7.yaml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("r7.yaml: field `url`: ") && e.contains("in clear"),
            "{e}"
        );
        // RWS 1.0 logs in with Digest; a controller on this host is not on the network.
        for ok in [
            "id: r6\nurl: http://192.168.125.1\nrws: rw6\ncredentials: {env: X}\n",
            "id: r7\nport: 8080\nrws: rw7\ncredentials: {env: X}\n",
            "id: r7\nurl: http://localhost:8080\nrws: rw7\ncredentials: {env: X}\n",
        ] {
            ControllerConfig::from_yaml_str(ok, "ok.yaml").unwrap();
        }
        for (url, local) in [
            ("http://127.0.0.1:80", true),
            ("http://127.1.2.3", true),
            ("http://[::1]:8080/", true),
            ("http://LOCALHOST", true),
            ("http://user@localhost:1", true),
            ("http://192.168.125.1", false),
            ("http://localhost.example.com", false),
            ("http://[::ffff:10.0.0.1]:80", false),
        ] {
            assert_eq!(is_loopback_url(url), local, "{url}");
        }
    }

    #[test]
    fn credentials_debug_hides_the_password() {
        let c = Credentials {
            user: "u".into(),
            password: "secret".into(),
        };
        assert!(!format!("{c:?}").contains("secret"));
    }
}
