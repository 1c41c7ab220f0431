//! `rws_sim`: a small RWS server on loopback, for tests and bench work without a robot.
//!
//! It speaks the subset [`crate::RwsClient`] uses (see [`crate::endpoints`]), in either
//! generation, and behaves like a controller where that matters to a client:
//!
//! - **Authentication.** A request without a valid session cookie and without valid
//!   credentials gets 401 with `WWW-Authenticate: Digest realm="validusers@robapi.abb",
//!   qop="auth", nonce=..., algorithm=MD5` (RobotWare 6, the default) or `Basic` (RobotWare 7,
//!   the default there). Accepted credentials open a session: `Set-Cookie: -http-session-=...`
//!   and `ABBCX=...`. [`RwsSim::expire_sessions`] drops every session, as a controller restart
//!   would.
//! - **Headers.** In RWS 2.0 mode a POST without `application/x-www-form-urlencoded;v=2.0`
//!   gets 415, a file PUT without `text/plain;v=2.0` gets 415, a GET (other than files and
//!   `/logout`) whose `Accept` lacks `v=2.0` gets 406.
//! - **Files.** An in-memory file service under `$HOME` (RWS 1.0) or `HOME` (RWS 2.0):
//!   directories must exist before files go into them.
//! - **Program load.** A `.pgf` is read for its `<Module>` entries, every module is checked by
//!   [`rapid::check_module`], the modules together by [`rapid::check_names`] (every data name
//!   the motion, weld and I/O instructions use is declared in the program, or is
//!   [`SimConfig::controller_data`] or a signal), and the program replaces the task's; a
//!   failure answers 400 with
//!   the controller-style status block: `SYS_CTRL_E_RAPID_SYNTAX_ERROR` (-1073442803) for a
//!   module, `SYS_CTRL_E_INVALID_PROGRAMFILE` (-1073442814) for the `.pgf`,
//!   `SYS_CTRL_E_FILE_NOT_FOUND` (-1073438708) for a missing file (codes: [`crate::error::codes`]).
//! - **Mastership.** Loading and the program pointer need mastership (RWS 1.0, ABB:
//!   "Rapid Mastership Required"), RWS 2.0 also takes `?mastership=implicit`. Without it: 403
//!   with `SYS_CTRL_E_MASTER_REJECT`; held by another session: 403 with
//!   `SYS_CTRL_E_RESOURCE_HELD`. (The HTTP status the real controllers use for these is not
//!   documented; the codes are.) A session's mastership ends with the session.
//! - **Execution.** `resetpp` needs a loaded `PROC main`; `start` needs the program pointer
//!   and a stopped task, then "runs" for [`SimConfig::run_time`] and stops by itself (the
//!   program pointer is then spent: `resetpp` again before the next start); `stop` stops.
//! - **I/O.** A table of signals ([`SimConfig::signals`], `NETWORK/DEVICE/NAME`); RWS 1.0
//!   also finds them by bare name. Digital signals (names starting `do`/`di`) take 0 or 1.
//! - **Process outputs.** The simulator does not execute RAPID, but it keeps the one behaviour
//!   that matters for heat: a program that switches a weld output with `SetDO doWeld, 1` has it
//!   on while it runs. When RAPID starts (from `main` or resumed), every signal a loaded module
//!   sets with `SetDO NAME, 1` goes to 1; when the run ends by itself (its last `SetDO NAME, 0`)
//!   they go to 0; a `stop` leaves them where they are, as a real controller does.
//! - **Faults.** [`RwsSim::stall`] keeps matching requests unanswered, as a cut cable or a hung
//!   controller would; when the stall is lifted ([`RwsSim::answer_all`]) they are dropped
//!   without effect (they never reached the controller) and new requests are served again.
//! - **HTTPS** (feature `tls`): with `SimConfig::tls` it serves RWS over TLS with the given
//!   certificate, as an OmniCore does.
//!
//! Errors come back as XHTML `<div class="status">` blocks, or as JSON when the request asked
//! for JSON (`?json=1` on RWS 1.0, `Accept: application/hal+json` on RWS 2.0), in each
//! generation's JSON shape ([`crate::error`]).

pub mod rapid;

use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use base64::Engine as _;
use bytes::Bytes;
use http_body_util::{BodyExt, Full};
use hyper::header::{HeaderMap, HeaderValue};
use hyper::{Request, Response, StatusCode};

use crate::config::RwsVersion;
use crate::error::codes;

/// The realm RobotWare uses in its challenges.
pub const REALM: &str = "validusers@robapi.abb";

/// How the simulator asks clients to authenticate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AuthScheme {
    /// HTTP Digest (RFC 2617, MD5, `qop=auth`): RobotWare 6.
    Digest,
    /// HTTP Basic: RobotWare 7.
    Basic,
}

/// What the simulator is.
#[derive(Debug, Clone)]
pub struct SimConfig {
    /// RWS generation to speak.
    pub version: RwsVersion,
    /// The one user it knows.
    pub user: String,
    /// That user's password.
    pub password: String,
    /// Challenge scheme; [`SimConfig::new`] picks the generation's.
    pub auth: AuthScheme,
    /// How long a started program "runs" before it stops by itself.
    pub run_time: Duration,
    /// The RAPID task.
    pub task: String,
    /// Signals as `NETWORK/DEVICE/NAME` and their initial values.
    pub signals: Vec<(String, String)>,
    /// Data declared on the controller (system modules, predefined data), which a program may
    /// use without declaring them ([`rapid::check_names`]); the signals count as declared too.
    /// [`SimConfig::new`]: ABB's predefined data ([`rapid::PREDEFINED_DATA`]); add, e.g., the
    /// `seamdata` and `welddata` of a cell whose programs use controller-side weld data.
    pub controller_data: Vec<String>,
    /// Serve HTTPS with this certificate and key instead of plain HTTP.
    #[cfg(feature = "tls")]
    pub tls: Option<SimTls>,
}

/// The simulator's HTTPS identity (feature `tls`).
#[cfg(feature = "tls")]
#[derive(Debug, Clone)]
pub struct SimTls {
    /// PEM certificate chain, the leaf first.
    pub cert_pem: Vec<u8>,
    /// PEM private key of the leaf (PKCS#8, SEC1 or PKCS#1).
    pub key_pem: Vec<u8>,
}

impl SimConfig {
    /// A simulator of `version` with one user, the generation's auth scheme, a 200 ms run,
    /// task `T_ROB1`, signals `Local/DRV_1/doWeld` (0), `Local/DRV_1/diArcEst` (0) and
    /// `Local/DRV_1/goWireFeed` (0), and ABB's predefined data as the controller's data.
    pub fn new(version: RwsVersion, user: &str, password: &str) -> Self {
        SimConfig {
            version,
            user: user.into(),
            password: password.into(),
            auth: match version {
                RwsVersion::Rw6 => AuthScheme::Digest,
                RwsVersion::Rw7 => AuthScheme::Basic,
            },
            run_time: Duration::from_millis(200),
            task: "T_ROB1".into(),
            signals: ["doWeld", "diArcEst", "goWireFeed"]
                .iter()
                .map(|n| (format!("Local/DRV_1/{n}"), "0".to_owned()))
                .collect(),
            controller_data: rapid::PREDEFINED_DATA
                .iter()
                .map(|n| (*n).to_owned())
                .collect(),
            #[cfg(feature = "tls")]
            tls: None,
        }
    }
}

/// A module loaded in the simulated task.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoadedModule {
    /// Module name.
    pub name: String,
    /// The file it came from (`HOME/...`).
    pub file: String,
}

struct State {
    cfg: SimConfig,
    counter: u64,
    nonces: HashSet<String>,
    sessions: HashSet<String>,
    logins: u64,
    mastership: Option<String>,
    dirs: BTreeSet<String>,
    files: BTreeMap<String, Vec<u8>>,
    modules: Vec<LoadedModule>,
    program: Option<String>,
    has_main: bool,
    pp: bool,
    running_until: Option<Instant>,
    cycle: String,
    signals: BTreeMap<String, String>,
    requests: Vec<String>,
    starts: u64,
}

/// A running simulator; stops when dropped.
pub struct RwsSim {
    addr: SocketAddr,
    https: bool,
    state: Arc<Mutex<State>>,
    stall: Arc<Stall>,
    task: tokio::task::JoinHandle<()>,
}

/// [`RwsSim::stall`]'s state.
#[derive(Default)]
struct Stall {
    /// Requests (`METHOD path?query`) starting with this are left unanswered.
    prefix: tokio::sync::watch::Sender<Option<String>>,
    /// How many are held now.
    held: std::sync::atomic::AtomicUsize,
}

impl std::fmt::Debug for RwsSim {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RwsSim")
            .field("addr", &self.addr)
            .finish_non_exhaustive()
    }
}

impl Drop for RwsSim {
    fn drop(&mut self) {
        self.task.abort();
    }
}

fn lock(state: &Mutex<State>) -> MutexGuard<'_, State> {
    state
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

impl RwsSim {
    /// Starts a simulator on `127.0.0.1` and a free port.
    ///
    /// # Errors
    /// The port could not be bound.
    pub async fn start(cfg: SimConfig) -> std::io::Result<RwsSim> {
        Self::start_on(cfg, 0).await
    }

    /// Starts a simulator on `127.0.0.1:port` (0: a free port).
    ///
    /// # Errors
    /// The port could not be bound.
    pub async fn start_on(cfg: SimConfig, port: u16) -> std::io::Result<RwsSim> {
        #[cfg(feature = "tls")]
        let tls = match &cfg.tls {
            Some(t) => Some(
                crate::tls::acceptor(&t.cert_pem, &t.key_pem)
                    .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))?,
            ),
            None => None,
        };
        #[cfg(feature = "tls")]
        let https = tls.is_some();
        #[cfg(not(feature = "tls"))]
        let https = false;
        let listener = tokio::net::TcpListener::bind(("127.0.0.1", port)).await?;
        let addr = listener.local_addr()?;
        let signals = cfg.signals.iter().cloned().collect();
        let state = Arc::new(Mutex::new(State {
            cycle: "asis".into(),
            cfg,
            counter: 0,
            nonces: HashSet::new(),
            sessions: HashSet::new(),
            logins: 0,
            mastership: None,
            dirs: BTreeSet::from(["HOME".to_owned()]),
            files: BTreeMap::new(),
            modules: Vec::new(),
            program: None,
            has_main: false,
            pp: false,
            running_until: None,
            signals,
            requests: Vec::new(),
            starts: 0,
        }));
        let stall = Arc::new(Stall::default());
        let (shared, stall_shared) = (state.clone(), stall.clone());
        let task = tokio::spawn(async move {
            loop {
                let Ok((stream, _)) = listener.accept().await else {
                    continue;
                };
                let (state, stall) = (shared.clone(), stall_shared.clone());
                #[cfg(feature = "tls")]
                let tls = tls.clone();
                tokio::spawn(async move {
                    #[cfg(feature = "tls")]
                    if let Some(acceptor) = tls {
                        match acceptor.accept(stream).await {
                            Ok(secured) => serve_connection(secured, state, stall).await,
                            Err(e) => tracing::debug!("rws_sim TLS handshake: {e}"),
                        }
                        return;
                    }
                    serve_connection(stream, state, stall).await;
                });
            }
        });
        Ok(RwsSim {
            addr,
            https,
            state,
            stall,
            task,
        })
    }

    /// The address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Its base URL, `http://127.0.0.1:PORT` (`https://` when serving TLS).
    pub fn url(&self) -> String {
        let scheme = if self.https { "https" } else { "http" };
        format!("{scheme}://{}", self.addr)
    }

    /// Leaves every request whose `METHOD path?query` starts with `prefix` unanswered (`""`:
    /// all of them), as a cut cable or a hung controller would, until [`RwsSim::answer_all`].
    pub fn stall(&self, prefix: &str) {
        self.stall.prefix.send_replace(Some(prefix.to_owned()));
    }

    /// How many requests a stall holds now.
    pub fn stalled(&self) -> usize {
        self.stall.held.load(std::sync::atomic::Ordering::SeqCst)
    }

    /// Lifts [`RwsSim::stall`]: the requests it held are dropped unanswered and without effect,
    /// later ones are served.
    pub fn answer_all(&self) {
        self.stall.prefix.send_replace(None);
    }

    /// Whether RAPID runs now.
    pub fn rapid_running(&self) -> bool {
        let mut s = lock(&self.state);
        s.tick();
        s.running()
    }

    /// How many times RAPID was started.
    pub fn starts(&self) -> u64 {
        lock(&self.state).starts
    }

    /// Sets a signal by full path or bare name, as the process would (e.g. a weld output left
    /// on); false if there is no such signal.
    pub fn set_signal(&self, name: &str, value: &str) -> bool {
        let mut s = lock(&self.state);
        match s.find_signal(name, true) {
            Some(key) => {
                s.signals.insert(key, value.to_owned());
                true
            }
            None => false,
        }
    }

    /// Drops every session (and so mastership), as a controller restart would.
    pub fn expire_sessions(&self) {
        let mut s = lock(&self.state);
        s.sessions.clear();
        s.mastership = None;
    }

    /// Successful logins so far.
    pub fn logins(&self) -> u64 {
        lock(&self.state).logins
    }

    /// A stored file, by its path under HOME (`cellsuite/X.mod`).
    pub fn file(&self, path_under_home: &str) -> Option<Vec<u8>> {
        lock(&self.state)
            .files
            .get(&format!("HOME/{path_under_home}"))
            .cloned()
    }

    /// The modules loaded in the task, in load order.
    pub fn modules(&self) -> Vec<LoadedModule> {
        lock(&self.state).modules.clone()
    }

    /// The loaded program file (`HOME/...`), if a program was loaded.
    pub fn program(&self) -> Option<String> {
        lock(&self.state).program.clone()
    }

    /// A signal's current value, by full path or (any generation) bare name.
    pub fn signal(&self, name: &str) -> Option<String> {
        let s = lock(&self.state);
        s.find_signal(name, true).map(|k| s.signals[&k].clone())
    }

    /// Every request served so far as `METHOD path?query`, in order (not those a stall
    /// dropped).
    pub fn requests(&self) -> Vec<String> {
        lock(&self.state).requests.clone()
    }

    /// Whether any session holds mastership.
    pub fn mastership_held(&self) -> bool {
        lock(&self.state).mastership.is_some()
    }
}

/// Serves one HTTP/1.1 connection (plain or TLS).
async fn serve_connection<I>(io: I, state: Arc<Mutex<State>>, stall: Arc<Stall>)
where
    I: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin + Send + 'static,
{
    let service = hyper::service::service_fn(move |req| {
        let (state, stall) = (state.clone(), stall.clone());
        async move { serve(&state, &stall, req).await }
    });
    if let Err(e) = hyper::server::conn::http1::Builder::new()
        .serve_connection(hyper_util::rt::TokioIo::new(io), service)
        .await
    {
        tracing::debug!("rws_sim connection: {e}");
    }
}

/// A request [`RwsSim::stall`] held and then dropped.
#[derive(Debug)]
struct Dropped;

impl std::fmt::Display for Dropped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("request dropped by a stall")
    }
}

impl std::error::Error for Dropped {}

async fn serve(
    state: &Mutex<State>,
    stall: &Stall,
    req: Request<hyper::body::Incoming>,
) -> Result<Response<Full<Bytes>>, Dropped> {
    let (parts, body) = req.into_parts();
    let path_q = parts
        .uri
        .path_and_query()
        .map_or_else(|| "/".to_owned(), |p| p.as_str().to_owned());
    let line = format!("{} {path_q}", parts.method);
    let stalled = |p: &Option<String>| p.as_deref().is_some_and(|pre| line.starts_with(pre));
    let mut watch = stall.prefix.subscribe();
    if stalled(&watch.borrow_and_update()) {
        /// Counts a held request for as long as it is held (also if hyper drops it).
        struct Held<'a>(&'a std::sync::atomic::AtomicUsize);
        impl Drop for Held<'_> {
            fn drop(&mut self) {
                self.0.fetch_sub(1, std::sync::atomic::Ordering::SeqCst);
            }
        }
        stall.held.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        let _held = Held(&stall.held);
        while stalled(&watch.borrow_and_update()) {
            if watch.changed().await.is_err() {
                break;
            }
        }
        return Err(Dropped);
    }
    let body = match body.collect().await {
        Ok(b) => b.to_bytes(),
        Err(_) => Bytes::new(),
    };
    let mut s = lock(state);
    s.requests.push(line);
    Ok(s.handle(parts.method.as_str(), &path_q, &parts.headers, &body))
}

/// How to render an answer.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Repr {
    Xhtml,
    Json1,
    Hal2,
}

struct Ctx<'a> {
    method: &'a str,
    /// Path without the query, percent-decoded per segment.
    segs: Vec<String>,
    query: BTreeMap<String, String>,
    form: BTreeMap<String, String>,
    repr: Repr,
    session: String,
}

fn response(status: u16, content_type: &str, body: impl Into<Bytes>) -> Response<Full<Bytes>> {
    let mut r = Response::new(Full::new(body.into()));
    *r.status_mut() = StatusCode::from_u16(status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
    if let Ok(v) = HeaderValue::from_str(content_type) {
        r.headers_mut().insert(hyper::header::CONTENT_TYPE, v);
    }
    r
}

fn empty(status: u16) -> Response<Full<Bytes>> {
    let mut r = Response::new(Full::new(Bytes::new()));
    *r.status_mut() = StatusCode::from_u16(status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
    r
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn percent_decode(s: &str, plus_is_space: bool) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'+' if plus_is_space => out.push(b' '),
            b'%' if i + 2 < bytes.len() => {
                let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
                match hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                    Some(b) => {
                        out.push(b);
                        i += 2;
                    }
                    None => out.push(b'%'),
                }
            }
            b => out.push(b),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn parse_form(text: &str) -> BTreeMap<String, String> {
    text.split('&')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (k, v) = p.split_once('=').unwrap_or((p, ""));
            (percent_decode(k, true), percent_decode(v, true))
        })
        .collect()
}

fn header(headers: &HeaderMap, name: hyper::header::HeaderName) -> &str {
    headers
        .get(name)
        .and_then(|v| v.to_str().ok())
        .unwrap_or_default()
}

impl State {
    fn next_id(&mut self) -> u64 {
        self.counter += 1;
        // Not secret, only unique: a simulator on loopback.
        self.counter
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(17)
            ^ u64::from(std::process::id())
    }

    fn handle(
        &mut self,
        method: &str,
        path_q: &str,
        headers: &HeaderMap,
        body: &[u8],
    ) -> Response<Full<Bytes>> {
        self.tick();
        let v2 = self.cfg.version == RwsVersion::Rw7;
        let (path, query_text) = path_q.split_once('?').unwrap_or((path_q, ""));
        let query = parse_form(query_text);
        let accept = header(headers, hyper::header::ACCEPT);
        let repr = if v2 && accept.contains("json") {
            Repr::Hal2
        } else if !v2 && query.get("json").map(String::as_str) == Some("1") {
            Repr::Json1
        } else {
            Repr::Xhtml
        };

        // Session or credentials.
        let cookie = header(headers, hyper::header::COOKIE);
        let existing = cookie.split(';').find_map(|c| {
            let (k, v) = c.trim().split_once('=')?;
            (k == "-http-session-" && self.sessions.contains(v)).then(|| v.to_owned())
        });
        let (session, new_session) = match existing {
            Some(s) => (s, false),
            None => {
                let auth = header(headers, hyper::header::AUTHORIZATION);
                if !self.authorized(method, path_q, auth) {
                    return self.challenge();
                }
                let id = format!("{:016x}", self.next_id());
                self.sessions.insert(id.clone());
                self.logins += 1;
                (id, true)
            }
        };

        // RWS 2.0 media types.
        let is_files = path.starts_with("/fileservice");
        let content_type = header(headers, hyper::header::CONTENT_TYPE).replace(' ', "");
        if v2 {
            if method == "POST"
                && !content_type.starts_with("application/x-www-form-urlencoded;v=2.0")
            {
                return self.with_cookie(
                    self.error(repr, 415, codes::INVALID_ARG, &format!("Content-Type {content_type:?}: expected application/x-www-form-urlencoded;v=2.0")),
                    &session,
                    new_session,
                );
            }
            if method == "PUT" && content_type != "text/plain;v=2.0" {
                return self.with_cookie(
                    self.error(
                        repr,
                        415,
                        codes::INVALID_ARG,
                        &format!("Content-Type {content_type:?}: expected text/plain;v=2.0"),
                    ),
                    &session,
                    new_session,
                );
            }
            if method == "GET" && !is_files && path != "/logout" && !accept.contains("v=2.0") {
                return self.with_cookie(
                    self.error(
                        repr,
                        406,
                        codes::INVALID_ARG,
                        &format!("Accept {accept:?}: expected a v=2.0 media type"),
                    ),
                    &session,
                    new_session,
                );
            }
        }

        let raw_segs: Vec<&str> = path.split('/').filter(|s| !s.is_empty()).collect();
        let ctx = Ctx {
            method,
            segs: raw_segs.iter().map(|s| percent_decode(s, false)).collect(),
            query,
            form: if method == "POST" {
                parse_form(&String::from_utf8_lossy(body))
            } else {
                BTreeMap::new()
            },
            repr,
            session: session.clone(),
        };
        let resp = self.route(&ctx, &raw_segs, body);
        self.with_cookie(resp, &session, new_session)
    }

    fn with_cookie(
        &self,
        mut resp: Response<Full<Bytes>>,
        session: &str,
        new_session: bool,
    ) -> Response<Full<Bytes>> {
        if new_session {
            for c in [
                format!("-http-session-={session}; Path=/; httponly"),
                format!("ABBCX={}; Path=/; httponly", self.logins),
            ] {
                if let Ok(v) = HeaderValue::from_str(&c) {
                    resp.headers_mut().append(hyper::header::SET_COOKIE, v);
                }
            }
        }
        resp
    }

    fn challenge(&mut self) -> Response<Full<Bytes>> {
        let value = match self.cfg.auth {
            AuthScheme::Digest => {
                let nonce = format!(
                    "{:032x}",
                    u128::from(self.next_id()) << 64 | u128::from(self.next_id())
                );
                self.nonces.insert(nonce.clone());
                format!("Digest realm=\"{REALM}\", qop=\"auth\", nonce=\"{nonce}\", algorithm=MD5")
            }
            AuthScheme::Basic => format!("Basic realm=\"{REALM}\""),
        };
        let mut r = response(
            401,
            "text/html",
            "<html><body><h1>401 Unauthorized</h1></body></html>",
        );
        if let Ok(v) = HeaderValue::from_str(&value) {
            r.headers_mut().insert(hyper::header::WWW_AUTHENTICATE, v);
        }
        r
    }

    fn authorized(&self, method: &str, path_q: &str, auth: &str) -> bool {
        match self.cfg.auth {
            AuthScheme::Basic => {
                let Some(token) = auth.strip_prefix("Basic ") else {
                    return false;
                };
                let Ok(decoded) = base64::engine::general_purpose::STANDARD.decode(token.trim())
                else {
                    return false;
                };
                decoded == format!("{}:{}", self.cfg.user, self.cfg.password).as_bytes()
            }
            AuthScheme::Digest => {
                if !auth.starts_with("Digest ") {
                    return false;
                }
                let Ok(given) = digest_auth::AuthorizationHeader::parse(auth) else {
                    return false;
                };
                if given.username != self.cfg.user
                    || given.realm != REALM
                    || !self.nonces.contains(&given.nonce)
                    || given.uri != path_q
                {
                    return false;
                }
                let mut expected = given.clone();
                let ctx = digest_auth::AuthContext::new_with_method(
                    self.cfg.user.as_str(),
                    self.cfg.password.as_str(),
                    given.uri.as_str(),
                    Option::<&[u8]>::None,
                    digest_auth::HttpMethod(method.to_owned().into()),
                );
                expected.digest(&ctx);
                expected.response == given.response
            }
        }
    }

    /// Ends a run whose time is up: the program's last `SetDO NAME, 0` switches its process
    /// outputs off.
    fn tick(&mut self) {
        if let Some(until) = self.running_until {
            if Instant::now() >= until {
                self.running_until = None;
                self.pp = false;
                self.set_process_outputs("0");
            }
        }
    }

    /// Sets every signal a loaded module switches on with `SetDO NAME, 1` to `value`.
    fn set_process_outputs(&mut self, value: &str) {
        let mut keys = Vec::new();
        for m in &self.modules {
            let Some(text) = self.files.get(&m.file) else {
                continue;
            };
            for name in rapid::outputs_switched_on(&String::from_utf8_lossy(text)) {
                if let Some(key) = self.find_signal(&name, true) {
                    keys.push(key);
                }
            }
        }
        for key in keys {
            self.signals.insert(key, value.to_owned());
        }
    }

    fn running(&self) -> bool {
        self.running_until.is_some()
    }

    fn error(&self, repr: Repr, status: u16, code: i64, msg: &str) -> Response<Full<Bytes>> {
        match repr {
            Repr::Xhtml => response(
                status,
                if self.cfg.version == RwsVersion::Rw7 {
                    "application/xhtml+xml;v=2.0"
                } else {
                    "application/xhtml+xml"
                },
                format!(
                    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<html xmlns=\"http://www.w3.org/1999/xhtml\"><head><title>Error</title></head><body><div class=\"status\"><span class=\"code\">{code}</span><span class=\"msg\">{}</span></div></body></html>\n",
                    xml_escape(msg)
                ),
            ),
            Repr::Json1 => response(
                status,
                "application/json",
                serde_json::json!({"_links": {"base": {"href": "/"}}, "_embedded": {"status": {"code": code, "msg": msg}}}).to_string(),
            ),
            Repr::Hal2 => response(
                status,
                "application/hal+json;v=2.0",
                serde_json::json!({"status": {"code": code, "msg": msg}}).to_string(),
            ),
        }
    }

    fn items(&self, repr: Repr, base: &str, items: &[serde_json::Value]) -> Response<Full<Bytes>> {
        match repr {
            Repr::Json1 => response(
                200,
                "application/json",
                serde_json::json!({"_links": {"base": {"href": base}}, "_embedded": {"_state": items}}).to_string(),
            ),
            Repr::Hal2 => response(
                200,
                "application/hal+json;v=2.0",
                serde_json::json!({"_links": {"base": {"href": base}}, "state": items}).to_string(),
            ),
            Repr::Xhtml => {
                let mut html = format!("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<html xmlns=\"http://www.w3.org/1999/xhtml\"><head><base href=\"{base}\"/></head><body><div class=\"state\"><ul>");
                for item in items {
                    let Some(obj) = item.as_object() else { continue };
                    let ty = obj.get("_type").and_then(|v| v.as_str()).unwrap_or_default();
                    let title = obj.get("_title").and_then(|v| v.as_str()).unwrap_or_default();
                    html.push_str(&format!("<li class=\"{}\" title=\"{}\">", xml_escape(ty), xml_escape(title)));
                    for (k, v) in obj.iter().filter(|(k, _)| !k.starts_with('_')) {
                        let text = v.as_str().map_or_else(|| v.to_string(), str::to_owned);
                        html.push_str(&format!("<span class=\"{}\">{}</span>", xml_escape(k), xml_escape(&text)));
                    }
                    html.push_str("</li>");
                }
                html.push_str("</ul></div></body></html>\n");
                response(200, "application/xhtml+xml", html)
            }
        }
    }

    fn route(&mut self, c: &Ctx<'_>, raw: &[&str], body: &[u8]) -> Response<Full<Bytes>> {
        let v2 = self.cfg.version == RwsVersion::Rw7;
        let segs: Vec<&str> = c.segs.iter().map(String::as_str).collect();
        let action = c.query.get("action").map(String::as_str);
        let not_found = |s: &Self| {
            s.error(
                c.repr,
                404,
                codes::UNRESOLVED_URL,
                &format!("no resource {} /{}", c.method, c.segs.join("/")),
            )
        };
        match (c.method, segs.as_slice()) {
            ("GET", ["rw", "system"]) => {
                let version = if v2 { "7.21.0" } else { "6.16.0" };
                self.items(c.repr, "/rw/", &[serde_json::json!({"_type": "sys-system", "_title": "system", "name": "cellsim", "rwversion": version, "rwversionname": version})])
            }
            ("GET", ["logout"]) => {
                self.sessions.remove(&c.session);
                if self.mastership.as_deref() == Some(c.session.as_str()) {
                    self.mastership = None;
                }
                empty(204)
            }
            ("POST", ["rw", "mastership", rest @ ..]) => {
                let act = if v2 {
                    match rest {
                        [a] | ["edit" | "motion", a] => Some(*a),
                        _ => None,
                    }
                } else {
                    match rest {
                        [] | ["rapid" | "cfg" | "motion"] => action,
                        _ => None,
                    }
                };
                match act {
                    Some("request") => match &self.mastership {
                        Some(holder) if *holder != c.session => self.error(
                            c.repr,
                            403,
                            codes::RESOURCE_HELD,
                            "Requested resource is held by someone else",
                        ),
                        _ => {
                            self.mastership = Some(c.session.clone());
                            empty(204)
                        }
                    },
                    Some("release") => {
                        if self.mastership.as_deref() == Some(c.session.as_str()) {
                            self.mastership = None;
                        }
                        empty(204)
                    }
                    _ => not_found(self),
                }
            }
            (_, ["fileservice", ..]) => self.fileservice(c, raw, body),
            ("POST", ["rw", "rapid", "tasks", task, rest @ ..]) => {
                if *task != self.cfg.task {
                    return self.error(
                        c.repr,
                        400,
                        codes::UNRESOLVED_URL,
                        &format!("no task {task}"),
                    );
                }
                match (v2, rest, action) {
                    (false, ["program"], Some("loadprog")) | (true, ["program", "load"], None) => {
                        self.edit(c, |s| s.load_program(c))
                    }
                    (false, [], Some("loadmod")) | (true, ["loadmod"], None) => {
                        self.edit(c, |s| s.load_module(c))
                    }
                    _ => not_found(self),
                }
            }
            ("GET", ["rw", "rapid", "execution"]) => {
                let state = if self.running() { "running" } else { "stopped" };
                self.items(c.repr, "/rw/rapid/", &[serde_json::json!({"_type": "rap-execution", "_title": "execution", "ctrlexecstate": state, "cycle": self.cycle})])
            }
            ("POST", ["rw", "rapid", "execution", rest @ ..]) => {
                let op: &str = match (v2, rest, action) {
                    (false, [], Some(a)) => a,
                    (true, [a], _) => a,
                    _ => return not_found(self),
                };
                match op {
                    "resetpp" => self.edit(c, |s| s.reset_pp(c)),
                    "start" => self.start(c),
                    "stop" => {
                        self.running_until = None;
                        empty(204)
                    }
                    _ => not_found(self),
                }
            }
            ("GET", ["rw", "iosystem", "signals", rest @ ..]) => match self.signal_key(rest) {
                Some(key) => {
                    let name = key.rsplit('/').next().unwrap_or_default().to_owned();
                    let ty = signal_type(&name);
                    self.items(c.repr, "/rw/iosystem/", &[serde_json::json!({"_type": "ios-signal", "_title": key, "name": name, "type": ty, "lvalue": self.signals[&key], "lstate": "not simulated"})])
                }
                None => self.error(
                    c.repr,
                    404,
                    codes::UNRESOLVED_URL,
                    &format!("Invalid IO signal name: {}", rest.join("/")),
                ),
            },
            ("POST", ["rw", "iosystem", "signals", rest @ ..]) => {
                let target = match (v2, rest.split_last(), action) {
                    (false, _, Some("set")) => rest,
                    (true, Some((&"set-value", path)), None) => path,
                    _ => return not_found(self),
                };
                let Some(key) = self.signal_key(target) else {
                    return self.error(
                        c.repr,
                        404,
                        codes::UNRESOLVED_URL,
                        &format!("Invalid IO signal name: {}", target.join("/")),
                    );
                };
                let Some(value) = c.form.get("lvalue") else {
                    return self.error(c.repr, 400, codes::INVALID_ARG, "lvalue missing");
                };
                let name = key.rsplit('/').next().unwrap_or_default();
                let ok = match signal_type(name) {
                    "DO" | "DI" => value == "0" || value == "1",
                    _ => value.parse::<f64>().is_ok_and(f64::is_finite),
                };
                if !ok {
                    return self.error(
                        c.repr,
                        400,
                        codes::INVALID_ARG,
                        &format!("invalid value {value:?} for signal {name}"),
                    );
                }
                self.signals.insert(key, value.clone());
                empty(204)
            }
            _ => not_found(self),
        }
    }

    /// Runs `op` if this session holds mastership (or, on RWS 2.0, asked for it implicitly).
    fn edit(
        &mut self,
        c: &Ctx<'_>,
        op: impl FnOnce(&mut Self) -> Response<Full<Bytes>>,
    ) -> Response<Full<Bytes>> {
        let implicit = self.cfg.version == RwsVersion::Rw7
            && c.query.get("mastership").map(String::as_str) == Some("implicit");
        match &self.mastership {
            Some(holder) if *holder == c.session => op(self),
            Some(_) => self.error(
                c.repr,
                403,
                codes::RESOURCE_HELD,
                "Requested resource is held by someone else",
            ),
            None if implicit => op(self),
            None => self.error(
                c.repr,
                403,
                codes::MASTER_REJECT,
                "The user does not have required mastership for the operation",
            ),
        }
    }

    /// `HOME/...` for a controller path in this generation's spelling.
    fn home_key(&self, path: &str) -> Option<String> {
        let rest = match self.cfg.version {
            RwsVersion::Rw6 => path.strip_prefix("$HOME"),
            RwsVersion::Rw7 => path.strip_prefix("HOME"),
        }?;
        if !(rest.is_empty() || rest.starts_with('/')) || rest.split('/').any(|p| p == "..") {
            return None;
        }
        Some(format!("HOME{}", rest.trim_end_matches('/')))
    }

    fn fileservice(&mut self, c: &Ctx<'_>, raw: &[&str], body: &[u8]) -> Response<Full<Bytes>> {
        let v2 = self.cfg.version == RwsVersion::Rw7;
        // RWS 1.0 takes `$HOME` literally and refuses `%24HOME`.
        let home = raw.get(1).copied().unwrap_or_default();
        let expect = if v2 { "HOME" } else { "$HOME" };
        if home != expect {
            return self.error(
                c.repr,
                404,
                codes::DIR_NOT_EXIST,
                &format!("no volume {home:?}"),
            );
        }
        let mut rel: Vec<&str> = c.segs[2..].iter().map(String::as_str).collect();
        let create_v2 = v2 && c.method == "POST" && rel.last() == Some(&"create");
        if create_v2 {
            rel.pop();
        }
        if rel.iter().any(|p| *p == ".." || *p == "." || p.is_empty()) {
            return self.error(c.repr, 400, codes::INVALID_ARG, "bad path");
        }
        let key = if rel.is_empty() {
            "HOME".to_owned()
        } else {
            format!("HOME/{}", rel.join("/"))
        };
        match c.method {
            "PUT" => {
                let parent = key.rsplit_once('/').map_or("HOME", |(p, _)| p).to_owned();
                if rel.is_empty() || !self.dirs.contains(&parent) {
                    return self.error(
                        c.repr,
                        404,
                        codes::DIR_NOT_EXIST,
                        &format!("Path does not exist: {parent}"),
                    );
                }
                if self.dirs.contains(&key) {
                    return self.error(
                        c.repr,
                        409,
                        codes::DIR_EXIST,
                        &format!("{key} is a directory"),
                    );
                }
                let existed = self.files.insert(key, body.to_vec()).is_some();
                empty(if existed { 200 } else { 201 })
            }
            "GET" => match self.files.get(&key) {
                Some(bytes) => response(200, "text/plain", bytes.clone()),
                None => self.error(
                    c.repr,
                    404,
                    codes::FILE_NOT_FOUND,
                    &format!("File not found: {key}"),
                ),
            },
            "POST"
                if create_v2
                    || (!v2 && c.form.get("fs-action").map(String::as_str) == Some("create")) =>
            {
                let Some(name) = c
                    .form
                    .get("fs-newname")
                    .filter(|n| !n.is_empty() && !n.contains('/') && *n != "..")
                else {
                    return self.error(
                        c.repr,
                        400,
                        codes::INVALID_ARG,
                        "fs-newname missing or invalid",
                    );
                };
                if !self.dirs.contains(&key) {
                    return self.error(
                        c.repr,
                        404,
                        codes::DIR_NOT_EXIST,
                        &format!("Path does not exist: {key}"),
                    );
                }
                let dir = format!("{key}/{name}");
                if self.dirs.contains(&dir) || self.files.contains_key(&dir) {
                    return self.error(
                        c.repr,
                        409,
                        codes::DIR_EXIST,
                        &format!("Directory exists: {dir}"),
                    );
                }
                self.dirs.insert(dir);
                empty(201)
            }
            _ => self.error(c.repr, 405, codes::INVALID_ARG, "method not allowed here"),
        }
    }

    fn load_failure(&self, c: &Ctx<'_>, code: i64, msg: String) -> Response<Full<Bytes>> {
        self.error(c.repr, 400, code, &msg)
    }

    /// Checks one module file; `Ok((name, has_main))`.
    fn check_file(&self, key: &str) -> Result<(String, bool), (i64, String)> {
        let Some(bytes) = self.files.get(key) else {
            return Err((
                codes::FILE_NOT_FOUND,
                format!("Load error: file not found: {key}"),
            ));
        };
        let file_name = key.rsplit('/').next().unwrap_or_default();
        match rapid::check_module(file_name, bytes, self.cfg.version) {
            Ok(name) => Ok((name, rapid::has_main(bytes))),
            Err(f) if f.line == 0 => Err((
                codes::RAPID_SYNTAX_ERROR,
                format!("Syntax error in {key}: {}", f.message),
            )),
            Err(f) => Err((
                codes::RAPID_SYNTAX_ERROR,
                format!("Syntax error in {key}, line {}: {}", f.line, f.message),
            )),
        }
    }

    /// [`rapid::check_names`] over the modules of a program being loaded: a name used but
    /// declared nowhere is a reference error naming the file, module, line and name. (A
    /// single module loaded into the task is not checked: it may use data of modules loaded
    /// after it.)
    fn check_program_names(&self, modules: &[LoadedModule]) -> Result<(), (i64, String)> {
        let texts: Vec<(String, String)> = modules
            .iter()
            .map(|m| {
                let bytes = self.files.get(&m.file).map_or(&[][..], Vec::as_slice);
                // RobotWare 6 reads ISO-8859-1: every byte is a character.
                let text = std::str::from_utf8(bytes).map_or_else(
                    |_| bytes.iter().map(|&b| b as char).collect(),
                    str::to_owned,
                );
                (m.name.clone(), text)
            })
            .collect();
        let pairs: Vec<(&str, &str)> = texts
            .iter()
            .map(|(n, t)| (n.as_str(), t.as_str()))
            .collect();
        let mut known: Vec<&str> = self
            .cfg
            .controller_data
            .iter()
            .map(String::as_str)
            .collect();
        // Signals by their bare name, as RAPID names them.
        known.extend(
            self.signals
                .keys()
                .map(|k| k.rsplit('/').next().unwrap_or(k)),
        );
        rapid::check_names(&pairs, &known).map_err(|u| {
            let file = modules
                .iter()
                .find(|m| m.name == u.module)
                .map_or("", |m| m.file.as_str());
            (
                codes::RAPID_SYNTAX_ERROR,
                format!("Reference error in {file}: {u}"),
            )
        })
    }

    /// The controller's answer to a program edit while RAPID runs, if it runs.
    fn refuse_while_running(&self, c: &Ctx<'_>) -> Option<Response<Full<Bytes>>> {
        self.running().then(|| {
            self.error(
                c.repr,
                400,
                codes::EXEC_STATE,
                "Not allowed while RAPID is running",
            )
        })
    }

    fn load_program(&mut self, c: &Ctx<'_>) -> Response<Full<Bytes>> {
        if let Some(refused) = self.refuse_while_running(c) {
            return refused;
        }
        let Some(path) = c.form.get("progpath") else {
            return self.error(c.repr, 400, codes::INVALID_ARG, "progpath missing");
        };
        if let Some(mode) = c.form.get("loadmode") {
            if mode != "replace" && mode != "add" {
                return self.error(
                    c.repr,
                    400,
                    codes::INVALID_ARG,
                    &format!("loadmode {mode:?}"),
                );
            }
        }
        let Some(key) = self.home_key(path) else {
            return self.load_failure(
                c,
                codes::FILE_NOT_FOUND,
                format!("Load error: no such file {path:?}"),
            );
        };
        let Some(bytes) = self.files.get(&key) else {
            return self.load_failure(
                c,
                codes::FILE_NOT_FOUND,
                format!("Load error: file not found: {key}"),
            );
        };
        let text = String::from_utf8_lossy(bytes).into_owned();
        let dir = key.rsplit_once('/').map_or("HOME", |(d, _)| d).to_owned();
        let modules = match pgf_modules(&text) {
            Ok(m) => m,
            Err(msg) => {
                return self.load_failure(
                    c,
                    codes::INVALID_PROGRAMFILE,
                    format!("Invalid program file {key}: {msg}"),
                )
            }
        };
        let mut loaded = Vec::new();
        let mut has_main = false;
        for m in &modules {
            if m.contains('/') || m.contains("..") {
                return self.load_failure(
                    c,
                    codes::INVALID_PROGRAMFILE,
                    format!("Invalid program file {key}: module path {m:?}"),
                );
            }
            let file = format!("{dir}/{m}");
            match self.check_file(&file) {
                Ok((name, main)) => {
                    if loaded
                        .iter()
                        .any(|l: &LoadedModule| l.name.eq_ignore_ascii_case(&name))
                    {
                        return self.load_failure(
                            c,
                            codes::INVALID_PROGRAMFILE,
                            format!("Invalid program file {key}: module {name} listed twice"),
                        );
                    }
                    has_main |= main;
                    loaded.push(LoadedModule { name, file });
                }
                Err((code, msg)) => return self.load_failure(c, code, msg),
            }
        }
        if let Err((code, msg)) = self.check_program_names(&loaded) {
            return self.load_failure(c, code, msg);
        }
        self.modules = loaded;
        self.program = Some(key);
        self.has_main = has_main;
        self.pp = false;
        empty(204)
    }

    fn load_module(&mut self, c: &Ctx<'_>) -> Response<Full<Bytes>> {
        if let Some(refused) = self.refuse_while_running(c) {
            return refused;
        }
        let Some(path) = c.form.get("modulepath") else {
            return self.error(c.repr, 400, codes::INVALID_ARG, "modulepath missing");
        };
        let Some(key) = self.home_key(path) else {
            return self.load_failure(
                c,
                codes::FILE_NOT_FOUND,
                format!("Load error: no such file {path:?}"),
            );
        };
        let replace = c.form.get("replace").map(String::as_str) == Some("true");
        match self.check_file(&key) {
            Ok((name, main)) => {
                if let Some(i) = self
                    .modules
                    .iter()
                    .position(|m| m.name.eq_ignore_ascii_case(&name))
                {
                    if !replace {
                        return self.load_failure(
                            c,
                            codes::INVALID_ARG,
                            format!("Module {name} already loaded (replace=false)"),
                        );
                    }
                    self.modules.remove(i);
                }
                self.modules.push(LoadedModule { name, file: key });
                self.has_main |= main;
                self.pp = false;
                empty(204)
            }
            Err((code, msg)) => self.load_failure(c, code, msg),
        }
    }

    fn reset_pp(&mut self, c: &Ctx<'_>) -> Response<Full<Bytes>> {
        if let Some(refused) = self.refuse_while_running(c) {
            return refused;
        }
        if !self.has_main {
            return self.error(
                c.repr,
                400,
                codes::NO_SUCH_SYMBOL,
                "No such symbol: main (no program with a main routine loaded)",
            );
        }
        self.pp = true;
        empty(204)
    }

    fn start(&mut self, c: &Ctx<'_>) -> Response<Full<Bytes>> {
        let v2 = self.cfg.version == RwsVersion::Rw7;
        for p in [
            "regain",
            "execmode",
            "cycle",
            "condition",
            "stopatbp",
            "alltaskbytsp",
        ] {
            if !c.form.contains_key(p) {
                return self.error(c.repr, 400, codes::INVALID_ARG, &format!("{p} missing"));
            }
        }
        if v2 {
            let implicit = c.query.get("mastership").map(String::as_str) == Some("implicit");
            match &self.mastership {
                Some(h) if *h != c.session => {
                    return self.error(
                        c.repr,
                        403,
                        codes::RESOURCE_HELD,
                        "Requested resource is held by someone else",
                    )
                }
                None if !implicit => {
                    return self.error(
                        c.repr,
                        403,
                        codes::MASTER_REJECT,
                        "The user does not have required mastership for the operation",
                    )
                }
                _ => {}
            }
        }
        if self.running() {
            return self.error(c.repr, 400, codes::EXEC_STATE, "RAPID is already running");
        }
        if !self.pp {
            return self.error(
                c.repr,
                400,
                codes::NO_PP,
                "No program pointer: set the program pointer to main first",
            );
        }
        self.cycle = c.form["cycle"].clone();
        self.running_until = Some(Instant::now() + self.cfg.run_time);
        self.starts += 1;
        self.set_process_outputs("1");
        empty(204)
    }

    fn find_signal(&self, name: &str, any_form: bool) -> Option<String> {
        if self.signals.contains_key(name) {
            return Some(name.to_owned());
        }
        if !name.contains('/') && (any_form || self.cfg.version == RwsVersion::Rw6) {
            return self
                .signals
                .keys()
                .find(|k| k.rsplit('/').next() == Some(name))
                .cloned();
        }
        None
    }

    /// The table key of a signal path: `NET/DEV/NAME`, or (RWS 1.0 only) a bare name.
    fn signal_key(&self, segs: &[&str]) -> Option<String> {
        match segs {
            [_, _, _] => self.find_signal(&segs.join("/"), false),
            [name] if self.cfg.version == RwsVersion::Rw6 => self.find_signal(name, false),
            _ => None,
        }
    }
}

fn signal_type(name: &str) -> &'static str {
    let lower = name.to_ascii_lowercase();
    if lower.starts_with("do") {
        "DO"
    } else if lower.starts_with("di") {
        "DI"
    } else if lower.starts_with("go") {
        "GO"
    } else if lower.starts_with("gi") {
        "GI"
    } else if lower.starts_with("ao") {
        "AO"
    } else {
        "AI"
    }
}

/// The `<Module>` entries of a `.pgf`.
fn pgf_modules(text: &str) -> Result<Vec<String>, String> {
    let start = text.find("<Program>").ok_or("no <Program> element")?;
    let end = text.find("</Program>").ok_or("<Program> not closed")?;
    if end < start {
        return Err("</Program> before <Program>".into());
    }
    let mut rest = &text[start + "<Program>".len()..end];
    let mut modules = Vec::new();
    while let Some(open) = rest.find("<Module>") {
        let after = &rest[open + "<Module>".len()..];
        let close = after.find("</Module>").ok_or("<Module> not closed")?;
        let name = after[..close].trim();
        if name.is_empty() {
            return Err("empty <Module>".into());
        }
        modules.push(name.to_owned());
        rest = &after[close + "</Module>".len()..];
    }
    if modules.is_empty() {
        return Err("no <Module> entries".into());
    }
    Ok(modules)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_forms_and_pgfs() {
        let f = parse_form("modulepath=%24HOME%2Fa+b.mod&replace=true&x");
        assert_eq!(f["modulepath"], "$HOME/a b.mod");
        assert_eq!(f["replace"], "true");
        assert_eq!(f["x"], "");
        assert_eq!(percent_decode("%zz%4", false), "%zz%4");
        assert_eq!(
            pgf_modules("<?xml version=\"1.0\"?>\n<Program>\n <Module>A.mod</Module>\n <Module>A_1.mod</Module>\n</Program>\n").unwrap(),
            ["A.mod", "A_1.mod"]
        );
        assert!(pgf_modules("<Program></Program>").is_err());
        assert!(pgf_modules("MODULE x").is_err());
    }
}
