//! The RWS requests this crate makes, per generation: method, path, body and headers.
//!
//! Sources, cited per call below:
//! - **ABB**: Robot Web Services application manual 3HAC050973-001 rev. M (RobotWare 6.16),
//!   the RWS 1.0 reference on ABB's developer center (pages `rapid_execution_start_page`,
//!   `rapid_execution_stop_page`, `rapid_execution_resetpp_page`, `rapid_task_loadmod_page`,
//!   `rapid_program_unload_page`, `msh_request_page`, `msh_release_page`).
//! - **librws**: ros-industrial `abb_librws` (NoMagicAi fork with `v1_0/` and `v2_0/`):
//!   `src/v1_0/rws.cpp`, `src/v1_0/rw/rapid.cpp`, `src/v2_0/rws.cpp`, `src/v2_0/rw/rapid.cpp`,
//!   `src/v2_0/rws_client.cpp`.
//! - **abb-rws-client**: ichbinmeraj/abb-rws-client `src/paths/{rapid,io,filesVision,
//!   systemMastership}.ts` and `src/rws2/core.ts`, each path live-verified by its author on
//!   RW6.16 (IRC5 VC) and RW7.21 (OmniCore VC).
//! - **bossymr**: the RAPID IntelliJ plugin's `Program` entity (`?action=loadprog` with
//!   `progpath` and `loadmode`, RWS 1.0).
//!
//! | operation | RWS 1.0 (RobotWare 6) | RWS 2.0 (RobotWare 7) |
//! |---|---|---|
//! | login probe | `GET /rw/system?json=1` | `GET /rw/system` |
//! | logout | `GET /logout` | `GET /logout` |
//! | make dir | `POST /fileservice/$HOME/D` `fs-action=create&fs-newname=N` | `POST /fileservice/HOME/D/create` `fs-newname=N` |
//! | upload | `PUT /fileservice/$HOME/D/F` | `PUT /fileservice/HOME/D/F`, `text/plain;v=2.0` |
//! | mastership | `POST /rw/mastership?action=request` / `release` | `POST /rw/mastership/edit/request` / `release` |
//! | load program | `POST /rw/rapid/tasks/T/program?action=loadprog` | `POST /rw/rapid/tasks/T/program/load` |
//! | load module | `POST /rw/rapid/tasks/T?action=loadmod` | `POST /rw/rapid/tasks/T/loadmod` |
//! | PP to main | `POST /rw/rapid/execution?action=resetpp` | `POST /rw/rapid/execution/resetpp` |
//! | start | `POST /rw/rapid/execution?action=start` | `POST /rw/rapid/execution/start?mastership=implicit` |
//! | stop | `POST /rw/rapid/execution?action=stop` | `POST /rw/rapid/execution/stop` |
//! | execution state | `GET /rw/rapid/execution?json=1` | `GET /rw/rapid/execution` |
//! | read signal | `GET /rw/iosystem/signals/S?json=1` | `GET /rw/iosystem/signals/NET/DEV/S` |
//! | write signal | `POST /rw/iosystem/signals/S?action=set` `lvalue=V` | `POST /rw/iosystem/signals/NET/DEV/S/set-value` `lvalue=V` |
//!
//! RWS 2.0 wants `Content-Type: application/x-www-form-urlencoded;v=2.0` on every POST, even
//! an empty one (abb-rws-client `core.ts`: some endpoints answer 406 without it), and reads are
//! asked for as `Accept: application/hal+json;v=2.0`; RWS 1.0 reads ask for JSON with `?json=1`.
//! In file paths RWS 1.0 wants the literal `$HOME` (it refuses `%24`), RWS 2.0 wants `HOME`
//! (abb-rws-client `filesVision.ts`); the same spelling goes into `modulepath`/`progpath`.

use crate::config::RwsVersion;

/// HTTP methods used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// GET.
    Get,
    /// POST.
    Post,
    /// PUT.
    Put,
}

impl Method {
    /// The method's name.
    pub fn as_str(self) -> &'static str {
        match self {
            Method::Get => "GET",
            Method::Post => "POST",
            Method::Put => "PUT",
        }
    }
}

/// `Accept` for RWS 2.0 reads.
pub const ACCEPT_HAL_V2: &str = "application/hal+json;v=2.0";
/// `Accept` for RWS 2.0 writes (their answers are XHTML only).
pub const ACCEPT_XHTML_V2: &str = "application/xhtml+xml;v=2.0";
/// Form body type, RWS 2.0.
pub const FORM_V2: &str = "application/x-www-form-urlencoded;v=2.0";
/// Form body type, RWS 1.0.
pub const FORM_V1: &str = "application/x-www-form-urlencoded";
/// File upload body type, RWS 2.0 (plain `text/plain` is answered 415: abb-rws-client, and
/// librws `v2_0/rws_client.cpp` `uploadFile`).
pub const TEXT_V2: &str = "text/plain;v=2.0";
/// File upload body type, RWS 1.0.
pub const TEXT_V1: &str = "text/plain";

/// One request: method, path with query, body and its type, and what to accept.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Call {
    /// HTTP method.
    pub method: Method,
    /// Path and query, percent-encoded where needed.
    pub path: String,
    /// Body bytes (form-encoded, or the file).
    pub body: Vec<u8>,
    /// `Content-Type`, for POST and PUT.
    pub content_type: Option<&'static str>,
    /// `Accept`, when the generation wants one.
    pub accept: Option<&'static str>,
}

/// Encodes `pairs` as `application/x-www-form-urlencoded`.
pub fn form(pairs: &[(&str, &str)]) -> String {
    pairs
        .iter()
        .map(|(k, v)| format!("{}={}", form_escape(k), form_escape(v)))
        .collect::<Vec<_>>()
        .join("&")
}

fn form_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for b in s.bytes() {
        match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'*' => {
                out.push(b as char);
            }
            b' ' => out.push('+'),
            _ => out.push_str(&format!("%{b:02X}")),
        }
    }
    out
}

/// Percent-encodes one path segment (keeps unreserved characters and `$`, which RWS 1.0
/// needs literal in `$HOME`).
pub fn segment(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for b in s.bytes() {
        match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' | b'$' => {
                out.push(b as char);
            }
            _ => out.push_str(&format!("%{b:02X}")),
        }
    }
    out
}

/// Percent-encodes each `/`-separated segment of `path`.
pub fn segments(path: &str) -> String {
    path.split('/').map(segment).collect::<Vec<_>>().join("/")
}

/// Builds the calls for one RWS generation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Api {
    /// The generation.
    pub version: RwsVersion,
}

impl Api {
    /// HOME as this generation spells it in file paths and in `modulepath`/`progpath`.
    pub fn home(self) -> &'static str {
        match self.version {
            RwsVersion::Rw6 => "$HOME",
            RwsVersion::Rw7 => "HOME",
        }
    }

    /// `HOME/dir/name` as the controller spells it (`dir` may be empty).
    pub fn controller_path(self, dir: &str, name: &str) -> String {
        if dir.is_empty() {
            format!("{}/{name}", self.home())
        } else {
            format!("{}/{dir}/{name}", self.home())
        }
    }

    fn get(self, path: String) -> Call {
        let (path, accept) = match self.version {
            RwsVersion::Rw6 => {
                let sep = if path.contains('?') { '&' } else { '?' };
                (format!("{path}{sep}json=1"), None)
            }
            RwsVersion::Rw7 => (path, Some(ACCEPT_HAL_V2)),
        };
        Call {
            method: Method::Get,
            path,
            body: Vec::new(),
            content_type: None,
            accept,
        }
    }

    fn post(self, path: String, body: String) -> Call {
        let (content_type, accept) = match self.version {
            RwsVersion::Rw6 => (FORM_V1, None),
            RwsVersion::Rw7 => (FORM_V2, Some(ACCEPT_XHTML_V2)),
        };
        Call {
            method: Method::Post,
            path,
            body: body.into_bytes(),
            content_type: Some(content_type),
            accept,
        }
    }

    /// Login probe and system information. Source: librws `RWSClient` constructors call
    /// `getRobotWareSystem` (`/rw/system`) to start authentication, both generations.
    pub fn system(self) -> Call {
        self.get("/rw/system".into())
    }

    /// Ends the session (and, on RobotWare 7, releases mastership). Source: librws
    /// `Resources::LOGOUT`; abb-rws-client `systemMastership.ts` note on `/logout`.
    pub fn logout(self) -> Call {
        let mut c = self.get("/logout".into());
        c.path = "/logout".into();
        c
    }

    /// Creates directory `name` in `HOME/parent`. Source: abb-rws-client `filesVision.ts`
    /// `createDirectory` (1.0: `fs-action=create` in the body; 2.0: `/create` suffix).
    pub fn create_dir(self, parent: &str, name: &str) -> Call {
        let base = if parent.is_empty() {
            format!("/fileservice/{}", self.home())
        } else {
            format!("/fileservice/{}/{}", self.home(), segments(parent))
        };
        match self.version {
            RwsVersion::Rw6 => {
                self.post(base, form(&[("fs-action", "create"), ("fs-newname", name)]))
            }
            RwsVersion::Rw7 => self.post(format!("{base}/create"), form(&[("fs-newname", name)])),
        }
    }

    /// Uploads (creates or replaces) `HOME/dir/name`. Sources: librws `uploadFile` (PUT to
    /// `/fileservice/DIR/FILE`; 2.0 with `text/plain;v=2.0`); abb-rws-client `filesVision.ts`.
    pub fn upload(self, dir: &str, name: &str, bytes: Vec<u8>) -> Call {
        let path = format!(
            "/fileservice/{}",
            segments(&self.controller_path(dir, name))
        );
        let content_type = match self.version {
            RwsVersion::Rw6 => TEXT_V1,
            RwsVersion::Rw7 => TEXT_V2,
        };
        Call {
            method: Method::Put,
            path,
            body: bytes,
            content_type: Some(content_type),
            accept: None,
        }
    }

    /// Requests (`request = true`) or releases mastership: all domains on RWS 1.0 (ABB
    /// `msh_request_page`, `msh_release_page`), the `edit` domain on RWS 2.0, which replaces
    /// 1.0's `cfg` and `rapid` (librws `v2_0::MastershipDomain::edit`; abb-rws-client
    /// `systemMastership.ts`).
    pub fn mastership(self, request: bool) -> Call {
        let action = if request { "request" } else { "release" };
        match self.version {
            RwsVersion::Rw6 => self.post(format!("/rw/mastership?action={action}"), String::new()),
            RwsVersion::Rw7 => self.post(format!("/rw/mastership/edit/{action}"), String::new()),
        }
    }

    /// Loads program file `progpath` (controller spelling) into `task`, replacing the task's
    /// program. Sources: abb-rws-client `rapid.ts` `loadProgram` (1.0 `?action=loadprog`,
    /// 2.0 `/program/load` with `loadmode`); bossymr `Program.load` (1.0 with `loadmode`).
    pub fn load_program(self, task: &str, progpath: &str) -> Call {
        let body = form(&[("progpath", progpath), ("loadmode", "replace")]);
        match self.version {
            RwsVersion::Rw6 => self.post(
                format!("/rw/rapid/tasks/{}/program?action=loadprog", segment(task)),
                body,
            ),
            RwsVersion::Rw7 => self.post(
                format!("/rw/rapid/tasks/{}/program/load", segment(task)),
                body,
            ),
        }
    }

    /// Loads module `modulepath` (controller spelling) into `task`, replacing a module of the
    /// same name. Sources: ABB `rapid_task_loadmod_page` (1.0); librws `v2_0/rw/rapid.cpp`
    /// `loadModuleIntoTask` (2.0 `/loadmod`).
    pub fn load_module(self, task: &str, modulepath: &str) -> Call {
        let body = form(&[("modulepath", modulepath), ("replace", "true")]);
        match self.version {
            RwsVersion::Rw6 => self.post(
                format!("/rw/rapid/tasks/{}?action=loadmod", segment(task)),
                body,
            ),
            RwsVersion::Rw7 => {
                self.post(format!("/rw/rapid/tasks/{}/loadmod", segment(task)), body)
            }
        }
    }

    /// Program pointer of every task to its `main`. Sources: ABB
    /// `rapid_execution_resetpp_page` (1.0); librws `v2_0` `resetRAPIDProgramPointer` (2.0).
    pub fn reset_pp(self) -> Call {
        match self.version {
            RwsVersion::Rw6 => {
                self.post("/rw/rapid/execution?action=resetpp".into(), String::new())
            }
            RwsVersion::Rw7 => self.post("/rw/rapid/execution/resetpp".into(), String::new()),
        }
    }

    /// Starts RAPID, one cycle (`cycle=once`: the job runs once, then execution stops).
    /// Sources: ABB `rapid_execution_start_page` (1.0 parameters, all required); librws
    /// `v2_0` `startRAPIDExecution` (2.0 path and `?mastership=implicit`).
    pub fn start(self) -> Call {
        let body = form(&[
            ("regain", "continue"),
            ("execmode", "continue"),
            ("cycle", "once"),
            ("condition", "none"),
            ("stopatbp", "disabled"),
            ("alltaskbytsp", "false"),
        ]);
        match self.version {
            RwsVersion::Rw6 => self.post("/rw/rapid/execution?action=start".into(), body),
            RwsVersion::Rw7 => {
                self.post("/rw/rapid/execution/start?mastership=implicit".into(), body)
            }
        }
    }

    /// Stops RAPID (`stopmode=stop`). Sources: ABB `rapid_execution_stop_page` (1.0); librws
    /// `v2_0` `stopRAPIDExecution` (2.0).
    pub fn stop(self) -> Call {
        let body = form(&[("stopmode", "stop"), ("usetsp", "normal")]);
        match self.version {
            RwsVersion::Rw6 => self.post("/rw/rapid/execution?action=stop".into(), body),
            RwsVersion::Rw7 => self.post("/rw/rapid/execution/stop".into(), body),
        }
    }

    /// Execution state and cycle (`rap-execution`: `ctrlexecstate`, `cycle`). Sources: librws
    /// `getRAPIDExecution` (both); abb-rws-client `rapid.ts` (same path both).
    pub fn execution(self) -> Call {
        self.get("/rw/rapid/execution".into())
    }

    /// Reads signal `signal`: a bare name (RWS 1.0's flat form) or `NETWORK/DEVICE/NAME`
    /// (required by RWS 2.0). Sources: librws `getIOSignal`; abb-rws-client `io.ts`.
    pub fn read_signal(self, signal: &str) -> Call {
        self.get(format!("/rw/iosystem/signals/{}", segments(signal)))
    }

    /// Sets signal `signal` to `value`. Sources: librws `setIOSignal` (1.0 `?action=set`,
    /// 2.0 `/set-value`, body `lvalue`); abb-rws-client `io.ts`.
    pub fn write_signal(self, signal: &str, value: &str) -> Call {
        let body = form(&[("lvalue", value)]);
        let path = format!("/rw/iosystem/signals/{}", segments(signal));
        match self.version {
            RwsVersion::Rw6 => self.post(format!("{path}?action=set"), body),
            RwsVersion::Rw7 => self.post(format!("{path}/set-value"), body),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn form_and_segments_escape() {
        assert_eq!(
            form(&[("modulepath", "$HOME/a b.mod"), ("replace", "true")]),
            "modulepath=%24HOME%2Fa+b.mod&replace=true"
        );
        assert_eq!(
            segments("$HOME/cell suite/x.mod"),
            "$HOME/cell%20suite/x.mod"
        );
    }

    #[test]
    fn paths_differ_by_generation() {
        let v1 = Api {
            version: RwsVersion::Rw6,
        };
        let v2 = Api {
            version: RwsVersion::Rw7,
        };
        assert_eq!(v1.execution().path, "/rw/rapid/execution?json=1");
        assert_eq!(v2.execution().accept, Some(ACCEPT_HAL_V2));
        assert_eq!(
            v1.upload("cellsuite", "A.mod", vec![]).path,
            "/fileservice/$HOME/cellsuite/A.mod"
        );
        assert_eq!(
            v2.upload("", "A.modx", vec![]).path,
            "/fileservice/HOME/A.modx"
        );
        assert_eq!(v2.mastership(true).path, "/rw/mastership/edit/request");
        assert_eq!(v1.mastership(false).path, "/rw/mastership?action=release");
        assert_eq!(v2.mastership(true).content_type, Some(FORM_V2));
        assert_eq!(
            v1.write_signal("doWeld", "1").path,
            "/rw/iosystem/signals/doWeld?action=set"
        );
        assert_eq!(
            v2.write_signal("Local/DRV_1/doWeld", "1").path,
            "/rw/iosystem/signals/Local/DRV_1/doWeld/set-value"
        );
    }
}
