//! Errors of the RWS client, with the controller's own status code carried through.
//!
//! A failed RWS request answers with an HTTP status and, usually, a body holding the
//! controller's return code and message. Both generations use the same code space and put it
//! in one of three shapes (ichbinmeraj/abb-rws-client `src/ControllerError.ts`
//! `parseControllerStatus`, live-captured on RW6.16 and RW7.21):
//!
//! - XHTML, both generations: `<div class="status"><span class="code">-1073445859</span>
//!   <span class="msg">...</span></div>`;
//! - RWS 1.0 `?json=1`: `{"_embedded": {"status": {"code": -1073445859, "msg": "..."}}}`;
//! - RWS 2.0 `application/hal+json;v=2.0`: `{"status": {"code": -1073445859, "msg": "..."}}`.
//!
//! [`AbbStatus::parse`] reads all three; [`RwsError::Controller`] keeps the parsed status and
//! the raw body, so nothing the controller said is lost.

use std::fmt;
use std::time::Duration;

use crate::config::ConfigError;

/// The controller's return code and message from an RWS error body.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AbbStatus {
    /// The controller return code, negative for errors (e.g. -1073442803).
    pub code: i64,
    /// The controller's message, if the body carried one.
    pub message: String,
}

impl AbbStatus {
    /// Reads the status block from an error body in any of the three shapes (module docs).
    /// `None` if the body carries no numeric code.
    pub fn parse(body: &str) -> Option<AbbStatus> {
        let trimmed = body.trim_start();
        if trimmed.starts_with('{') {
            let value: serde_json::Value = serde_json::from_str(trimmed).ok()?;
            let status = value
                .get("status")
                .or_else(|| value.get("_embedded").and_then(|e| e.get("status")))?;
            let code = status.get("code").and_then(|c| {
                c.as_i64()
                    .or_else(|| c.as_str().and_then(|s| s.trim().parse().ok()))
            })?;
            let message = status
                .get("msg")
                .and_then(|m| m.as_str())
                .unwrap_or_default()
                .trim()
                .to_owned();
            return Some(AbbStatus { code, message });
        }
        let code = span_text(body, "code")?.trim().parse().ok()?;
        let message = span_text(body, "msg").unwrap_or_default().trim().to_owned();
        Some(AbbStatus {
            code,
            message: xml_unescape(&message),
        })
    }

    /// ABB's symbolic name of the code (`SYS_CTRL_E_RAPID_SYNTAX_ERROR`), for the codes this
    /// crate meets; `None` for others.
    pub fn name(&self) -> Option<&'static str> {
        code_name(self.code)
    }
}

impl fmt::Display for AbbStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(name) => write!(f, "{} ({name})", self.code)?,
            None => write!(f, "{}", self.code)?,
        }
        if !self.message.is_empty() {
            write!(f, ": {}", self.message)?;
        }
        Ok(())
    }
}

/// Controller return codes this crate produces (simulator) or reacts to (client), with ABB's
/// names. Source: ABB, Robot Web Services manual 3HAC050973-001, "Robot controller return
/// codes" (`/rw/retcode`), as transcribed in Clement-RACINET/abb-rws-client-python-rw6
/// `_core/exceptions.py` and cross-checked against the live captures listed in
/// ichbinmeraj/abb-rws-client `src/ControllerError.ts`.
pub mod codes {
    /// `SYS_CTRL_E_REJECT`: the operation was rejected (permission, RMMP, UAS).
    pub const REJECT: i64 = -1_073_445_881;
    /// `SYS_CTRL_E_INVALIDARG`: an argument is invalid.
    pub const INVALID_ARG: i64 = -1_073_445_879;
    /// `SYS_CTRL_E_UNRESOLVED_URL`: no such resource (e.g. an unknown I/O signal).
    pub const UNRESOLVED_URL: i64 = -1_073_445_866;
    /// `SYS_CTRL_E_RESOURCE_HELD`: mastership is held by another client.
    pub const RESOURCE_HELD: i64 = -1_073_445_862;
    /// `SYS_CTRL_E_MASTER_REJECT`: the operation needs mastership this client does not hold.
    pub const MASTER_REJECT: i64 = -1_073_445_859;
    /// `SYS_CTRL_E_NO_SUCH_SYMBOL`: e.g. program pointer to `main` without a `main`.
    pub const NO_SUCH_SYMBOL: i64 = -1_073_442_816;
    /// `SYS_CTRL_E_INVALID_PROGRAMFILE`: the `.pgf` could not be read.
    pub const INVALID_PROGRAMFILE: i64 = -1_073_442_814;
    /// `SYS_CTRL_E_EXEC_STATE`: not allowed in the current execution state.
    pub const EXEC_STATE: i64 = -1_073_442_809;
    /// `SYS_CTRL_E_RAPID_SYNTAX_ERROR`: a module failed to load with syntax errors.
    pub const RAPID_SYNTAX_ERROR: i64 = -1_073_442_803;
    /// `SYS_CTRL_E_NO_PP`: no program pointer (nothing to start).
    pub const NO_PP: i64 = -1_073_442_783;
    /// `SYS_CTRL_E_DIR_NOT_EXIST`: the directory does not exist.
    pub const DIR_NOT_EXIST: i64 = -1_073_438_713;
    /// `SYS_CTRL_E_DIR_EXIST`: the directory already exists.
    pub const DIR_EXIST: i64 = -1_073_438_712;
    /// `SYS_CTRL_E_FILE_NOT_FOUND`: the file does not exist.
    pub const FILE_NOT_FOUND: i64 = -1_073_438_708;
}

fn code_name(code: i64) -> Option<&'static str> {
    Some(match code {
        codes::REJECT => "SYS_CTRL_E_REJECT",
        codes::INVALID_ARG => "SYS_CTRL_E_INVALIDARG",
        codes::UNRESOLVED_URL => "SYS_CTRL_E_UNRESOLVED_URL",
        codes::RESOURCE_HELD => "SYS_CTRL_E_RESOURCE_HELD",
        codes::MASTER_REJECT => "SYS_CTRL_E_MASTER_REJECT",
        codes::NO_SUCH_SYMBOL => "SYS_CTRL_E_NO_SUCH_SYMBOL",
        codes::INVALID_PROGRAMFILE => "SYS_CTRL_E_INVALID_PROGRAMFILE",
        codes::EXEC_STATE => "SYS_CTRL_E_EXEC_STATE",
        codes::RAPID_SYNTAX_ERROR => "SYS_CTRL_E_RAPID_SYNTAX_ERROR",
        codes::NO_PP => "SYS_CTRL_E_NO_PP",
        codes::DIR_NOT_EXIST => "SYS_CTRL_E_DIR_NOT_EXIST",
        codes::DIR_EXIST => "SYS_CTRL_E_DIR_EXIST",
        codes::FILE_NOT_FOUND => "SYS_CTRL_E_FILE_NOT_FOUND",
        _ => return None,
    })
}

/// The text of the first `<span class="NAME">...</span>` in an XHTML body.
fn span_text<'a>(body: &'a str, class: &str) -> Option<&'a str> {
    let needle = format!("class=\"{class}\"");
    let at = body.find(&needle)?;
    let rest = &body[at + needle.len()..];
    let open_end = rest.find('>')?;
    let rest = &rest[open_end + 1..];
    let close = rest.find("</span>")?;
    Some(&rest[..close])
}

fn xml_unescape(text: &str) -> String {
    text.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// Everything that can go wrong talking to a controller.
#[derive(Debug, thiserror::Error)]
pub enum RwsError {
    /// The controller configuration or its credentials could not be read.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The controller still answered 401 after a fresh login.
    #[error("{controller}: 401 after {scheme} login: check the credentials in {credentials}")]
    Auth {
        /// Controller id (from the configuration).
        controller: String,
        /// `digest` or `basic`: the scheme the controller asked for.
        scheme: &'static str,
        /// Where the credentials came from: `$VAR` or the file path.
        credentials: String,
    },
    /// The controller answered with an error status.
    #[error("{controller}: {method} {path}: HTTP {status}{}", match abb {
        Some(s) => format!(", controller code {s}"),
        None if body.trim().is_empty() => String::new(),
        None => format!(": {}", body.trim()),
    })]
    Controller {
        /// Controller id.
        controller: String,
        /// HTTP method of the request.
        method: &'static str,
        /// Path and query of the request.
        path: String,
        /// HTTP status code.
        status: u16,
        /// The controller's return code and message, when the body carried one.
        abb: Option<Box<AbbStatus>>,
        /// The whole response body, as received.
        body: String,
    },
    /// A request got no answer in time.
    #[error("{controller}: {method} {path}: no answer within {after:?}")]
    Timeout {
        /// Controller id.
        controller: String,
        /// HTTP method of the request.
        method: &'static str,
        /// Path and query of the request.
        path: String,
        /// The configured request timeout.
        after: Duration,
    },
    /// The connection failed (refused, reset, DNS, TLS).
    #[error("{controller}: {method} {path}: {message}")]
    Transport {
        /// Controller id.
        controller: String,
        /// HTTP method of the request.
        method: &'static str,
        /// Path and query of the request.
        path: String,
        /// The transport error, with its causes.
        message: String,
    },
    /// The controller answered 2xx with a body this client cannot read.
    #[error("{controller}: {method} {path}: unexpected answer: {message}")]
    Protocol {
        /// Controller id.
        controller: String,
        /// HTTP method of the request.
        method: &'static str,
        /// Path and query of the request.
        path: String,
        /// What was missing or wrong, with the start of the body.
        message: String,
    },
    /// The controller presented another certificate than the one pinned in its controller
    /// file (`tls.pin_sha256`): another machine answers at its address, or the controller's
    /// certificate was replaced.
    #[error("{controller}: the certificate presented is not the pinned one: expected SHA-256 {expected} (tls.pin_sha256), seen {seen}")]
    CertificatePin {
        /// Controller id.
        controller: String,
        /// The pin, as `AB:CD:…`.
        expected: String,
        /// The fingerprint of the certificate presented.
        seen: String,
    },
    /// No pin is given and no public root vouches for the controller's certificate (an
    /// OmniCore's own certificate is self-signed).
    #[error("{controller}: the controller's certificate is not trusted ({reason}); if it is the controller's own certificate (check its SHA-256 on the controller), pin it in the controller file: tls: {{pin_sha256: \"{seen}\"}}")]
    CertificateUntrusted {
        /// Controller id.
        controller: String,
        /// Why rustls refused it.
        reason: String,
        /// The fingerprint of the certificate presented.
        seen: String,
    },
    /// The controller asked for Basic authentication over plain HTTP to another host: the
    /// password would cross the network in clear, so it is not sent.
    #[error("{controller}: the controller asks for Basic authentication over plain HTTP ({url}), which would send the password in clear; use https:// (RobotWare 7 serves RWS over HTTPS; build with the `tls` feature)")]
    InsecureAuth {
        /// Controller id.
        controller: String,
        /// The controller's base URL.
        url: String,
    },
    /// An argument given to the client is unusable (e.g. a file name with a `/`).
    #[error("{what}: {message}")]
    BadInput {
        /// The argument.
        what: String,
        /// Why it was refused.
        message: String,
    },
    /// RAPID execution did not stop within the time the caller allowed.
    #[error("{controller}: RAPID still {state} after {after:?}")]
    StillRunning {
        /// Controller id.
        controller: String,
        /// The last execution state read.
        state: String,
        /// How long the caller waited.
        after: Duration,
    },
}

impl RwsError {
    /// The controller return code, if the error came from the controller with one.
    pub fn abb_code(&self) -> Option<i64> {
        match self {
            RwsError::Controller { abb: Some(s), .. } => Some(s.code),
            _ => None,
        }
    }

    /// The HTTP status, if the controller answered with an error status.
    pub fn http_status(&self) -> Option<u16> {
        match self {
            RwsError::Controller { status, .. } => Some(*status),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_three_shapes() {
        let xhtml = r#"<html><body><div class="status"><span class="code">-1073445859</span><span class="msg">The user does not have required mastership &amp; more</span></div></body></html>"#;
        let s = AbbStatus::parse(xhtml).unwrap();
        assert_eq!(s.code, codes::MASTER_REJECT);
        assert_eq!(
            s.message,
            "The user does not have required mastership & more"
        );
        assert_eq!(s.name(), Some("SYS_CTRL_E_MASTER_REJECT"));

        let rws1 = r#"{"_links":{},"_embedded":{"status":{"code":-1073442803,"msg":"syntax"}}}"#;
        assert_eq!(
            AbbStatus::parse(rws1).unwrap().code,
            codes::RAPID_SYNTAX_ERROR
        );

        let rws2 = r#"{"status":{"code":-1073442809,"msg":"state"}}"#;
        let s = AbbStatus::parse(rws2).unwrap();
        assert_eq!((s.code, s.message.as_str()), (codes::EXEC_STATE, "state"));

        assert_eq!(AbbStatus::parse(""), None);
        assert_eq!(AbbStatus::parse("<html>Not Found</html>"), None);
        assert_eq!(AbbStatus::parse("{not json"), None);
    }
}
