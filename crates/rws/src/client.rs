//! The RWS client: login and session, files, program load, execution, I/O.
//!
//! Session handling follows the controllers: the first request is answered 401 with a
//! challenge (`Digest` on RobotWare 6, `Basic` on RobotWare 7: ABB's RWS 1.0 samples use
//! `curl --digest`; abb-rws-client `src/rws2/core.ts` documents Basic for RWS 2.0); the
//! answered request gets the session cookies (`-http-session-`, `ABBCX`), which every later
//! request sends. Without them each request would open a new session and the controller's
//! small session pool fills within seconds (abb-rws-client `core.ts`). A 401 later on means the
//! session expired (controller restart, idle timeout): the client logs in again and repeats
//! the request once; a second 401 is [`RwsError::Auth`]. A 401 means the request was not
//! executed, so repeating a POST is safe. A Basic challenge over plain HTTP from another host
//! is not answered ([`RwsError::InsecureAuth`]): the password would cross the network in clear.
//!
//! Timeouts: logins, uploads and program loads may take `timeouts.request_s`; the requests that
//! drive and watch a run (start, stop, execution state, I/O) take at most `timeouts.control_s`,
//! so a caller polling a dead link gets its error within one poll.

use std::collections::BTreeMap;
use std::sync::{Mutex, MutexGuard};
use std::time::Duration;

use base64::Engine as _;

use crate::config::{ConfigError, ControllerConfig, Credentials, RwsVersion};
use crate::endpoints::{Api, Call, Method};
use crate::error::{codes, AbbStatus, RwsError};

/// RAPID execution state (`ctrlexecstate`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ExecState {
    /// `running`.
    Running,
    /// `stopped`.
    Stopped,
    /// Anything else the controller reports, as sent.
    Other(String),
}

/// What `GET /rw/rapid/execution` reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExecutionState {
    /// Running or stopped.
    pub state: ExecState,
    /// Run mode: `once`, `forever`, `asis` or `oncedone`, as sent.
    pub cycle: String,
}

impl ExecutionState {
    /// True while RAPID runs.
    pub fn is_running(&self) -> bool {
        self.state == ExecState::Running
    }
}

/// A program uploaded and loaded by [`RwsClient::install_program`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InstalledProgram {
    /// The `.pgf` as the controller spells it (`$HOME/cellsuite/X.pgf`).
    pub program: String,
    /// Every uploaded file, controller spelling, in upload order.
    pub files: Vec<String>,
}

#[derive(Default)]
struct Session {
    cookies: BTreeMap<String, String>,
    /// `Authorization` value sent with every request (Basic scheme only).
    basic: Option<String>,
    logged_in: bool,
    mastership: bool,
    logins: u64,
}

struct Answer {
    status: u16,
    body: String,
    challenges: Vec<String>,
}

/// Async client for one controller. Methods take `&self`; share it behind an `Arc`.
pub struct RwsClient {
    cfg: ControllerConfig,
    api: Api,
    base: String,
    creds: Credentials,
    http: reqwest::Client,
    session: Mutex<Session>,
    /// One login at a time: concurrent callers (a run, its poll, a hold) would otherwise
    /// each open a session, and the second would drop the first's mastership.
    login_lock: tokio::sync::Mutex<()>,
    /// Why the TLS verifier last refused the controller's certificate.
    #[cfg(feature = "tls")]
    refused: crate::tls::RefusalSlot,
}

impl std::fmt::Debug for RwsClient {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RwsClient")
            .field("id", &self.cfg.id)
            .field("base", &self.base)
            .field("rws", &self.cfg.rws)
            .finish_non_exhaustive()
    }
}

impl RwsClient {
    /// Reads the credentials, builds the HTTP client and logs in.
    ///
    /// # Errors
    /// [`RwsError::Config`] for unreadable credentials; the errors of [`RwsClient::login`].
    pub async fn connect(cfg: ControllerConfig) -> Result<Self, RwsError> {
        let client = Self::new(cfg)?;
        client.login().await?;
        Ok(client)
    }

    /// Like [`RwsClient::connect`] without logging in; the first request logs in.
    ///
    /// # Errors
    /// [`RwsError::Config`] for unreadable credentials; [`RwsError::Transport`] if the HTTP
    /// client cannot be built.
    pub fn new(cfg: ControllerConfig) -> Result<Self, RwsError> {
        let creds = cfg
            .credentials
            .as_ref()
            .ok_or_else(|| ConfigError::Invalid {
                file: cfg.id.clone(),
                field: "credentials".into(),
                reason: "missing (a simulator controller gets its login when the bridge starts it)"
                    .into(),
            })?
            .load()?;
        let builder = reqwest::Client::builder()
            .connect_timeout(cfg.timeouts.connect())
            .timeout(cfg.timeouts.request())
            .redirect(reqwest::redirect::Policy::none());
        let setup_error = |message: String| RwsError::Transport {
            controller: cfg.id.clone(),
            method: "",
            path: String::new(),
            message,
        };
        #[cfg(feature = "tls")]
        let (builder, refused) = {
            let pin = cfg.tls.as_ref().and_then(|t| t.pin_sha256);
            let (tls, refused) = crate::tls::client_config(pin).map_err(setup_error)?;
            (builder.use_preconfigured_tls(tls), refused)
        };
        let http = builder.build().map_err(|e| setup_error(error_chain(&e)))?;
        Ok(RwsClient {
            api: Api { version: cfg.rws },
            base: cfg.base_url(),
            creds,
            http,
            session: Mutex::new(Session::default()),
            login_lock: tokio::sync::Mutex::new(()),
            #[cfg(feature = "tls")]
            refused,
            cfg,
        })
    }

    /// The configuration this client was made from.
    pub fn config(&self) -> &ControllerConfig {
        &self.cfg
    }

    /// How many logins this client has done (the first one included).
    pub fn logins(&self) -> u64 {
        self.session().logins
    }

    /// Whether this client believes it holds mastership (taken and not yet given back; a call
    /// cancelled between taking and releasing it leaves it held).
    pub fn holds_mastership(&self) -> bool {
        self.session().mastership
    }

    fn session(&self) -> MutexGuard<'_, Session> {
        // A panic while holding the lock cannot leave the session half-updated in a way
        // that matters (worst case: one extra login), so a poisoned lock is taken over.
        self.session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Opens a session: answers the controller's `Digest` or `Basic` challenge and keeps the
    /// session cookies.
    ///
    /// # Errors
    /// [`RwsError::Auth`] when the controller refuses the credentials; transport errors.
    pub async fn login(&self) -> Result<(), RwsError> {
        let _one = self.login_lock.lock().await;
        self.open_session().await
    }

    /// Logs in unless logged in already; with `expired` (the login count a request was sent
    /// under, answered 401), unless another caller has logged in again since.
    async fn ensure_login(&self, expired: Option<u64>) -> Result<(), RwsError> {
        let _one = self.login_lock.lock().await;
        {
            let s = self.session();
            if s.logged_in && expired.is_none_or(|n| s.logins != n) {
                return Ok(());
            }
        }
        if expired.is_some() {
            tracing::info!(controller = %self.cfg.id, "RWS session expired, logging in again");
        }
        self.open_session().await
    }

    async fn open_session(&self) -> Result<(), RwsError> {
        {
            let mut s = self.session();
            s.cookies.clear();
            s.basic = None;
            s.logged_in = false;
            s.mastership = false;
        }
        let call = self.api.system();
        let timeout = self.cfg.timeouts.request();
        let first = self.exchange(&call, None, timeout).await?;
        if (200..300).contains(&first.status) {
            // No authentication asked for (a controller with open access).
            self.mark_logged_in(None);
            return Ok(());
        }
        if first.status != 401 {
            return Err(self.controller_error(&call, first));
        }
        let digest = first
            .challenges
            .iter()
            .find(|c| c.trim_start().to_ascii_lowercase().starts_with("digest"));
        let (scheme, header) = if let Some(challenge) = digest {
            let mut prompt = digest_auth::parse(challenge).map_err(|e| RwsError::Protocol {
                controller: self.cfg.id.clone(),
                method: call.method.as_str(),
                path: call.path.clone(),
                message: format!("unreadable Digest challenge {challenge:?}: {e}"),
            })?;
            let ctx = digest_auth::AuthContext::new_with_method(
                self.creds.user.as_str(),
                self.creds.password.as_str(),
                call.path.as_str(),
                Option::<&[u8]>::None,
                digest_auth::HttpMethod::GET,
            );
            let answer = prompt.respond(&ctx).map_err(|e| RwsError::Protocol {
                controller: self.cfg.id.clone(),
                method: call.method.as_str(),
                path: call.path.clone(),
                message: format!("cannot answer Digest challenge {challenge:?}: {e}"),
            })?;
            ("digest", answer.to_header_string())
        } else {
            if self.base.starts_with("http://") && !self.cfg.is_loopback() {
                return Err(RwsError::InsecureAuth {
                    controller: self.cfg.id.clone(),
                    url: self.base.clone(),
                });
            }
            let token = base64::engine::general_purpose::STANDARD
                .encode(format!("{}:{}", self.creds.user, self.creds.password));
            ("basic", format!("Basic {token}"))
        };
        let second = self.exchange(&call, Some(&header), timeout).await?;
        if second.status == 401 {
            return Err(self.auth_error(scheme));
        }
        if !(200..300).contains(&second.status) {
            return Err(self.controller_error(&call, second));
        }
        self.mark_logged_in((scheme == "basic").then_some(header));
        tracing::debug!(controller = %self.cfg.id, scheme, "RWS login");
        Ok(())
    }

    fn mark_logged_in(&self, basic: Option<String>) {
        let mut s = self.session();
        s.basic = basic;
        s.logged_in = true;
        s.logins += 1;
    }

    fn auth_error(&self, scheme: &'static str) -> RwsError {
        RwsError::Auth {
            controller: self.cfg.id.clone(),
            scheme,
            credentials: self
                .cfg
                .credentials
                .as_ref()
                .map_or_else(|| "none".into(), ToString::to_string),
        }
    }

    /// Ends the session (`GET /logout`); on RobotWare 7 this also releases mastership.
    ///
    /// # Errors
    /// Transport errors; an error status other than 401 (an expired session is already
    /// logged out).
    pub async fn logout(&self) -> Result<(), RwsError> {
        if !self.session().logged_in {
            return Ok(());
        }
        let call = self.api.logout();
        let answer = self
            .exchange(&call, None, self.cfg.timeouts.control())
            .await?;
        {
            let mut s = self.session();
            s.logged_in = false;
            s.mastership = false;
            s.cookies.clear();
            s.basic = None;
        }
        if answer.status == 401 || (200..300).contains(&answer.status) {
            Ok(())
        } else {
            Err(self.controller_error(&call, answer))
        }
    }

    /// One HTTP exchange, no login logic, answered within `timeout`. `auth` overrides the
    /// session's `Authorization`.
    async fn exchange(
        &self,
        call: &Call,
        auth: Option<&str>,
        timeout: Duration,
    ) -> Result<Answer, RwsError> {
        let url = format!("{}{}", self.base, call.path);
        let method = match call.method {
            Method::Get => reqwest::Method::GET,
            Method::Post => reqwest::Method::POST,
            Method::Put => reqwest::Method::PUT,
        };
        let (cookie, basic) = {
            let s = self.session();
            let cookie = (!s.cookies.is_empty()).then(|| {
                s.cookies
                    .iter()
                    .map(|(k, v)| format!("{k}={v}"))
                    .collect::<Vec<_>>()
                    .join("; ")
            });
            (cookie, s.basic.clone())
        };
        let mut req = self.http.request(method, &url).timeout(timeout);
        if let Some(c) = cookie {
            req = req.header(reqwest::header::COOKIE, c);
        }
        if let Some(a) = auth.map(str::to_owned).or(basic) {
            req = req.header(reqwest::header::AUTHORIZATION, a);
        }
        if let Some(accept) = call.accept {
            req = req.header(reqwest::header::ACCEPT, accept);
        }
        if let Some(ct) = call.content_type {
            req = req.header(reqwest::header::CONTENT_TYPE, ct);
        }
        if call.method != Method::Get {
            req = req.body(call.body.clone());
        }
        let resp = req
            .send()
            .await
            .map_err(|e| self.transport_error(call, &e, timeout))?;
        let status = resp.status().as_u16();
        let challenges = resp
            .headers()
            .get_all(reqwest::header::WWW_AUTHENTICATE)
            .iter()
            .filter_map(|v| v.to_str().ok().map(str::to_owned))
            .collect();
        {
            let mut s = self.session();
            for v in resp.headers().get_all(reqwest::header::SET_COOKIE) {
                let Ok(text) = v.to_str() else { continue };
                let pair = text.split(';').next().unwrap_or_default();
                if let Some((name, value)) = pair.split_once('=') {
                    s.cookies
                        .insert(name.trim().to_owned(), value.trim().to_owned());
                }
            }
        }
        let bytes = resp
            .bytes()
            .await
            .map_err(|e| self.transport_error(call, &e, timeout))?;
        tracing::trace!(controller = %self.cfg.id, method = call.method.as_str(), path = %call.path, status, "RWS");
        Ok(Answer {
            status,
            body: String::from_utf8_lossy(&bytes).into_owned(),
            challenges,
        })
    }

    fn transport_error(&self, call: &Call, e: &reqwest::Error, timeout: Duration) -> RwsError {
        #[cfg(feature = "tls")]
        if e.is_connect() {
            let refusal = self
                .refused
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .take();
            let controller = self.cfg.id.clone();
            match refusal {
                Some(crate::tls::Refusal::Mismatch { expected, seen }) => {
                    return RwsError::CertificatePin {
                        controller,
                        expected: expected.to_string(),
                        seen: seen.to_string(),
                    }
                }
                Some(crate::tls::Refusal::Untrusted { reason, seen }) => {
                    return RwsError::CertificateUntrusted {
                        controller,
                        reason,
                        seen: seen.to_string(),
                    }
                }
                None => {}
            }
        }
        if e.is_timeout() {
            RwsError::Timeout {
                controller: self.cfg.id.clone(),
                method: call.method.as_str(),
                path: call.path.clone(),
                after: timeout,
            }
        } else {
            RwsError::Transport {
                controller: self.cfg.id.clone(),
                method: call.method.as_str(),
                path: call.path.clone(),
                message: error_chain(e),
            }
        }
    }

    fn controller_error(&self, call: &Call, answer: Answer) -> RwsError {
        RwsError::Controller {
            controller: self.cfg.id.clone(),
            method: call.method.as_str(),
            path: call.path.clone(),
            status: answer.status,
            abb: AbbStatus::parse(&answer.body).map(Box::new),
            body: answer.body,
        }
    }

    /// A request in the session, answered within `timeouts.request_s`: logs in first if
    /// needed, logs in again once on 401.
    async fn send(&self, call: &Call) -> Result<String, RwsError> {
        self.send_within(call, self.cfg.timeouts.request()).await
    }

    /// A request that drives or watches a run: as [`RwsClient::send`], answered within
    /// `timeouts.control_s`.
    async fn send_control(&self, call: &Call) -> Result<String, RwsError> {
        self.send_within(call, self.cfg.timeouts.control()).await
    }

    async fn send_within(&self, call: &Call, timeout: Duration) -> Result<String, RwsError> {
        self.ensure_login(None).await?;
        let under = self.session().logins;
        let mut answer = self.exchange(call, None, timeout).await?;
        if answer.status == 401 {
            self.ensure_login(Some(under)).await?;
            answer = self.exchange(call, None, timeout).await?;
            if answer.status == 401 {
                let scheme = if self.session().basic.is_some() {
                    "basic"
                } else {
                    "digest"
                };
                return Err(self.auth_error(scheme));
            }
        }
        if (200..300).contains(&answer.status) {
            Ok(answer.body)
        } else {
            Err(self.controller_error(call, answer))
        }
    }

    /// A request that changes RAPID: takes mastership around it unless already held (and
    /// takes it again once if the controller says it was lost, e.g. with an expired session).
    async fn send_edit(&self, call: &Call) -> Result<String, RwsError> {
        let held = self.session().mastership;
        if !held {
            self.request_mastership().await?;
        }
        let mut result = self.send(call).await;
        if matches!(&result, Err(e) if e.abb_code() == Some(codes::MASTER_REJECT)) {
            // Mastership was lost, e.g. with a session that expired (the controller releases
            // it with the session): take it again and repeat once.
            self.request_mastership().await?;
            result = self.send(call).await;
        }
        if !held {
            if let Err(e) = self.release_mastership().await {
                if result.is_ok() {
                    tracing::warn!(controller = %self.cfg.id, "releasing mastership: {e}");
                }
            }
        }
        result
    }

    /// Takes mastership (RWS 1.0: all domains; RWS 2.0: `edit`). Loading, unloading and
    /// moving the program pointer need it; this client takes it around each of those calls
    /// when it does not hold it already, so calling this is only needed to keep it across
    /// several calls.
    ///
    /// # Errors
    /// Controller code `SYS_CTRL_E_RESOURCE_HELD` when another client holds it.
    pub async fn request_mastership(&self) -> Result<(), RwsError> {
        self.send(&self.api.mastership(true)).await?;
        self.session().mastership = true;
        Ok(())
    }

    /// Gives mastership back.
    ///
    /// # Errors
    /// Controller and transport errors.
    pub async fn release_mastership(&self) -> Result<(), RwsError> {
        self.session().mastership = false;
        self.send(&self.api.mastership(false)).await?;
        Ok(())
    }

    /// Creates `dir` (and its parents) under HOME if missing.
    ///
    /// # Errors
    /// Controller and transport errors other than "already exists".
    pub async fn ensure_dir(&self, dir: &str) -> Result<(), RwsError> {
        check_rel_path("directory", dir)?;
        let mut parent = String::new();
        for part in dir.split('/').filter(|p| !p.is_empty()) {
            match self.send(&self.api.create_dir(&parent, part)).await {
                Ok(_) => {}
                Err(e)
                    if e.http_status() == Some(409) || e.abb_code() == Some(codes::DIR_EXIST) => {}
                Err(e) => return Err(e),
            }
            if !parent.is_empty() {
                parent.push('/');
            }
            parent.push_str(part);
        }
        Ok(())
    }

    /// Uploads `bytes` as `HOME/dir/name`, replacing a file of that name; returns the path as
    /// the controller spells it (`$HOME/dir/name` or `HOME/dir/name`).
    ///
    /// # Errors
    /// [`RwsError::BadInput`] for a name or directory that is not a plain relative path;
    /// controller and transport errors.
    pub async fn upload_file(
        &self,
        dir: &str,
        name: &str,
        bytes: Vec<u8>,
    ) -> Result<String, RwsError> {
        check_rel_path("directory", dir)?;
        check_file_name(name)?;
        self.send(&self.api.upload(dir, name, bytes)).await?;
        Ok(self.api.controller_path(dir, name))
    }

    /// Uploads a program (modules and one `.pgf`, e.g. `cell_emitter::rapid::emit`'s files)
    /// to the configured `program_dir` and loads the `.pgf` into the configured task,
    /// replacing the task's program. Modules go up before the `.pgf`.
    ///
    /// # Errors
    /// [`RwsError::BadInput`] without exactly one `.pgf` or with an unsafe file name; the
    /// controller's load error (e.g. `SYS_CTRL_E_RAPID_SYNTAX_ERROR` with its message).
    pub async fn install_program<'a>(
        &self,
        files: impl IntoIterator<Item = (&'a str, &'a [u8])>,
    ) -> Result<InstalledProgram, RwsError> {
        let files: Vec<(&str, &[u8])> = files.into_iter().collect();
        for (name, _) in &files {
            check_file_name(name)?;
        }
        let pgfs: Vec<&str> = files
            .iter()
            .map(|(n, _)| *n)
            .filter(|n| n.to_ascii_lowercase().ends_with(".pgf"))
            .collect();
        let [pgf] = pgfs[..] else {
            return Err(RwsError::BadInput {
                what: "program files".into(),
                message: format!(
                    "expected exactly one .pgf among {:?}, found {}",
                    files.iter().map(|(n, _)| *n).collect::<Vec<_>>(),
                    pgfs.len()
                ),
            });
        };
        let dir = self.cfg.program_dir.clone();
        if !dir.is_empty() {
            self.ensure_dir(&dir).await?;
        }
        let mut uploaded = Vec::new();
        let ordered = files
            .iter()
            .filter(|(n, _)| *n != pgf)
            .chain(files.iter().filter(|(n, _)| *n == pgf));
        for (name, bytes) in ordered {
            uploaded.push(self.upload_file(&dir, name, bytes.to_vec()).await?);
        }
        let program = self.api.controller_path(&dir, pgf);
        self.load_program(&program).await?;
        Ok(InstalledProgram {
            program,
            files: uploaded,
        })
    }

    /// Loads a program file already on the controller (controller spelling, e.g.
    /// `$HOME/cellsuite/X.pgf`) into the configured task, replacing its program.
    ///
    /// # Errors
    /// The controller's load error; mastership errors.
    pub async fn load_program(&self, progpath: &str) -> Result<(), RwsError> {
        self.send_edit(&self.api.load_program(&self.cfg.task, progpath))
            .await
            .map(drop)
    }

    /// Loads one module already on the controller (controller spelling) into the configured
    /// task, replacing a module of the same name.
    ///
    /// # Errors
    /// The controller's load error; mastership errors.
    pub async fn load_module(&self, modulepath: &str) -> Result<(), RwsError> {
        self.send_edit(&self.api.load_module(&self.cfg.task, modulepath))
            .await
            .map(drop)
    }

    /// Moves the program pointer of every task to its `main`.
    ///
    /// # Errors
    /// `SYS_CTRL_E_NO_SUCH_SYMBOL` without a `main`; `SYS_CTRL_E_EXEC_STATE` while running.
    pub async fn set_pp_to_main(&self) -> Result<(), RwsError> {
        self.send_edit(&self.api.reset_pp()).await.map(drop)
    }

    /// Starts RAPID from the program pointer, one cycle.
    ///
    /// # Errors
    /// `SYS_CTRL_E_EXEC_STATE` when already running, `SYS_CTRL_E_NO_PP` without a program
    /// pointer; on a real controller also motors off or manual mode.
    pub async fn start(&self) -> Result<(), RwsError> {
        self.send_control(&self.api.start()).await.map(drop)
    }

    /// Stops RAPID.
    ///
    /// # Errors
    /// Controller and transport errors.
    pub async fn stop(&self) -> Result<(), RwsError> {
        self.send_control(&self.api.stop()).await.map(drop)
    }

    /// Reads the execution state and cycle.
    ///
    /// # Errors
    /// [`RwsError::Protocol`] if the answer has no `rap-execution` with `ctrlexecstate`.
    pub async fn execution_state(&self) -> Result<ExecutionState, RwsError> {
        let call = self.api.execution();
        let body = self.send_control(&call).await?;
        parse_execution_state(&body).map_err(|what| self.protocol(&call, &what, &body))
    }

    /// Polls the execution state every `poll` until RAPID is not running; gives up after
    /// `timeout` with [`RwsError::StillRunning`]. (RWS subscriptions over WebSocket would
    /// avoid polling; this client polls.)
    ///
    /// # Errors
    /// [`RwsError::StillRunning`]; the errors of [`RwsClient::execution_state`].
    pub async fn wait_until_stopped(
        &self,
        poll: Duration,
        timeout: Duration,
    ) -> Result<ExecutionState, RwsError> {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            let s = self.execution_state().await?;
            if !s.is_running() {
                return Ok(s);
            }
            if tokio::time::Instant::now() >= deadline {
                return Err(RwsError::StillRunning {
                    controller: self.cfg.id.clone(),
                    state: "running".into(),
                    after: timeout,
                });
            }
            tokio::time::sleep(poll).await;
        }
    }

    /// Reads a signal's value (`lvalue`, as the controller writes it: `0`/`1` for digital
    /// signals). `signal` is a bare name on RobotWare 6 (`doWeld`) or the full
    /// `NETWORK/DEVICE/NAME` path, which RobotWare 7 requires (`Local/DRV_1/doWeld`).
    ///
    /// # Errors
    /// `SYS_CTRL_E_UNRESOLVED_URL` for an unknown signal; [`RwsError::Protocol`].
    pub async fn read_signal(&self, signal: &str) -> Result<String, RwsError> {
        check_signal(signal)?;
        let call = self.api.read_signal(signal);
        let body = self.send_control(&call).await?;
        parse_signal_value(&body).map_err(|what| self.protocol(&call, &what, &body))
    }

    /// Sets a signal (`signal` as in [`RwsClient::read_signal`]) to `value` (`0`/`1` for
    /// digital signals).
    ///
    /// # Errors
    /// `SYS_CTRL_E_UNRESOLVED_URL` for an unknown signal, `SYS_CTRL_E_INVALIDARG` for a bad
    /// value.
    pub async fn write_signal(&self, signal: &str, value: &str) -> Result<(), RwsError> {
        check_signal(signal)?;
        self.send_control(&self.api.write_signal(signal, value))
            .await
            .map(drop)
    }

    fn protocol(&self, call: &Call, what: &str, body: &str) -> RwsError {
        let head: String = body.chars().take(200).collect();
        RwsError::Protocol {
            controller: self.cfg.id.clone(),
            method: call.method.as_str(),
            path: call.path.clone(),
            message: format!("{what}; body starts {head:?}"),
        }
    }

    /// The RWS generation this client speaks.
    pub fn version(&self) -> RwsVersion {
        self.cfg.rws
    }
}

/// The execution state in the answer to `GET /rw/rapid/execution` (the `rap-execution` item's
/// `ctrlexecstate` and `cycle`); `Err` says what is missing.
pub fn parse_execution_state(body: &str) -> Result<ExecutionState, String> {
    let item = find_item(body, "rap-execution")?;
    let state = match field(&item, "ctrlexecstate").as_deref() {
        Some("running") => ExecState::Running,
        Some("stopped") => ExecState::Stopped,
        Some(other) => ExecState::Other(other.to_owned()),
        None => return Err("no `ctrlexecstate` in rap-execution".into()),
    };
    Ok(ExecutionState {
        state,
        cycle: field(&item, "cycle").unwrap_or_default(),
    })
}

/// A signal's value (`lvalue` of the `ios-signal` item) in the answer to a signal read; `Err`
/// says what is missing.
pub fn parse_signal_value(body: &str) -> Result<String, String> {
    let item = find_item(body, "ios-signal")?;
    field(&item, "lvalue").ok_or_else(|| "no `lvalue` in ios-signal".into())
}

/// The first object with `"_type": ty` in a JSON answer (`_embedded._state` in RWS 1.0
/// `?json=1`, `state` in RWS 2.0 HAL).
fn find_item(body: &str, ty: &str) -> Result<serde_json::Value, String> {
    let value: serde_json::Value =
        serde_json::from_str(body).map_err(|e| format!("not JSON ({e})"))?;
    find_typed(&value, ty)
        .cloned()
        .ok_or_else(|| format!("no `{ty}` item"))
}

fn find_typed<'a>(v: &'a serde_json::Value, ty: &str) -> Option<&'a serde_json::Value> {
    match v {
        serde_json::Value::Object(map) => {
            if map.get("_type").and_then(|t| t.as_str()) == Some(ty) {
                return Some(v);
            }
            map.values().find_map(|x| find_typed(x, ty))
        }
        serde_json::Value::Array(items) => items.iter().find_map(|x| find_typed(x, ty)),
        _ => None,
    }
}

fn field(item: &serde_json::Value, name: &str) -> Option<String> {
    match item.get(name)? {
        serde_json::Value::String(s) => Some(s.clone()),
        serde_json::Value::Number(n) => Some(n.to_string()),
        serde_json::Value::Bool(b) => Some(b.to_string()),
        _ => None,
    }
}

fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

fn bad(what: &str, value: &str, message: &str) -> RwsError {
    RwsError::BadInput {
        what: format!("{what} {value:?}"),
        message: message.into(),
    }
}

fn check_file_name(name: &str) -> Result<(), RwsError> {
    if name.is_empty()
        || name.starts_with('.')
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
    {
        return Err(bad(
            "file name",
            name,
            "expected letters, digits, `_`, `-` and `.` (no directories)",
        ));
    }
    Ok(())
}

fn check_rel_path(what: &str, path: &str) -> Result<(), RwsError> {
    if path.is_empty() {
        return Ok(());
    }
    for part in path.split('/') {
        if part == "." || part == ".." || check_file_name(part).is_err() {
            return Err(bad(
                what,
                path,
                "expected a relative path of plain names under HOME",
            ));
        }
    }
    Ok(())
}

fn check_signal(signal: &str) -> Result<(), RwsError> {
    let parts: Vec<&str> = signal.split('/').collect();
    let ok = matches!(parts.len(), 1 | 3)
        && parts.iter().all(|p| {
            !p.is_empty()
                && p.chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
        });
    if ok {
        Ok(())
    } else {
        Err(bad(
            "signal",
            signal,
            "expected NAME or NETWORK/DEVICE/NAME",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_items_in_both_json_shapes() {
        let v1: serde_json::Value = serde_json::from_str(
            r#"{"_links":{},"_embedded":{"_state":[{"_type":"rap-execution","_title":"execution","ctrlexecstate":"running","cycle":"once"}]}}"#,
        )
        .unwrap();
        let v2: serde_json::Value = serde_json::from_str(
            r#"{"_links":{},"state":[{"_type":"ios-signal","_title":"doWeld","lvalue":1}]}"#,
        )
        .unwrap();
        let e = find_typed(&v1, "rap-execution").unwrap();
        assert_eq!(field(e, "ctrlexecstate").as_deref(), Some("running"));
        let s = find_typed(&v2, "ios-signal").unwrap();
        assert_eq!(field(s, "lvalue").as_deref(), Some("1"));
        assert!(find_typed(&v2, "rap-execution").is_none());
    }

    #[test]
    fn refuses_unsafe_names() {
        assert!(check_file_name("WAAM_wall_42.mod").is_ok());
        for bad in ["", "../x.mod", "a/b.mod", ".hidden", "a b.mod", "x\\y"] {
            assert!(check_file_name(bad).is_err(), "{bad}");
        }
        assert!(check_rel_path("d", "cellsuite/jobs").is_ok());
        assert!(check_rel_path("d", "a/../b").is_err());
        assert!(check_signal("doWeld").is_ok());
        assert!(check_signal("Local/DRV_1/doWeld").is_ok());
        assert!(check_signal("a/b").is_err());
    }
}
