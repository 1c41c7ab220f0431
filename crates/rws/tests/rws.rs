//! The RWS client against the loopback simulator, both generations: login, upload and load of
//! programs written by `cell_emitter::rapid::emit`, ABB-style load errors, execution, I/O,
//! sessions and credentials. No wall-clock assertions: waits are bounded generously.

use std::path::{Path, PathBuf};
use std::time::Duration;

use cell_emitter::rapid;
use cell_msgs::Toolpath;
use cell_profiles::MachineProfile;
use cell_rws::error::codes;
use cell_rws::sim::{AuthScheme, RwsSim, SimConfig};
use cell_rws::{ControllerConfig, CredentialsSource, ExecState, RwsClient, RwsError, RwsVersion};

const USER: &str = "Cell Operator";
const PASSWORD: &str = "weld:on-42";
const POLL: Duration = Duration::from_millis(20);
const PATIENCE: Duration = Duration::from_secs(60);

fn write_credentials(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("controller.cred");
    std::fs::write(&path, text).unwrap();
    path
}

/// A simulator and a configuration for it whose credentials are in a file.
async fn setup(version: RwsVersion) -> (RwsSim, ControllerConfig, tempfile::TempDir) {
    let sim = RwsSim::start(SimConfig::new(version, USER, PASSWORD))
        .await
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cred = write_credentials(dir.path(), &format!("{USER}:{PASSWORD}\n"));
    let cfg = ControllerConfig::loopback(
        "sim",
        sim.addr().port(),
        version,
        CredentialsSource::File(cred),
    );
    (sim, cfg, dir)
}

fn wall() -> Toolpath {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/toolpaths/wall.json"),
    )
    .unwrap();
    cell_msgs::json::from_str(&text).unwrap()
}

/// The emitter's files as (name, bytes) pairs.
fn emitted(profile: &str, toolpath: &Toolpath, job: &str) -> Vec<(String, Vec<u8>)> {
    let p = MachineProfile::resolve(profile).unwrap();
    rapid::emit(toolpath, &p, job)
        .unwrap()
        .into_iter()
        .map(|f| (f.name, f.text.into_bytes()))
        .collect()
}

fn as_refs(files: &[(String, Vec<u8>)]) -> Vec<(&str, &[u8])> {
    files
        .iter()
        .map(|(n, b)| (n.as_str(), b.as_slice()))
        .collect()
}

async fn run_emitted_program(version: RwsVersion, profile: &str, toolpath: &Toolpath) {
    let (sim, cfg, _dir) = setup(version).await;
    let files = emitted(profile, toolpath, "wall-7");
    let rws = RwsClient::connect(cfg).await.unwrap();

    let installed = rws.install_program(as_refs(&files)).await.unwrap();
    let home = match version {
        RwsVersion::Rw6 => "$HOME",
        RwsVersion::Rw7 => "HOME",
    };
    let pgf = &files.last().unwrap().0;
    assert_eq!(installed.program, format!("{home}/cellsuite/{pgf}"));
    assert_eq!(installed.files.len(), files.len());
    for (name, bytes) in &files {
        assert_eq!(
            sim.file(&format!("cellsuite/{name}")).as_ref(),
            Some(bytes),
            "{name} stored byte for byte"
        );
    }
    let modules = sim.modules();
    assert_eq!(modules.len(), files.len() - 1, "{modules:?}");
    let main_stem = files[0].0.rsplit_once('.').unwrap().0;
    assert_eq!(modules[0].name, main_stem);
    assert!(
        !sim.mastership_held(),
        "mastership given back after the load"
    );

    rws.set_pp_to_main().await.unwrap();
    rws.start().await.unwrap();
    let end = rws.wait_until_stopped(POLL, PATIENCE).await.unwrap();
    assert_eq!(end.state, ExecState::Stopped);
    assert_eq!(end.cycle, "once");
    // The run is over and the program pointer spent: a second start without resetting it is
    // refused by the controller, with its code carried through.
    let e = rws.start().await.unwrap_err();
    assert_eq!(e.abb_code(), Some(codes::NO_PP), "{e}");
    rws.logout().await.unwrap();
}

#[tokio::test]
async fn emitted_rw6_program_uploads_loads_and_runs() {
    run_emitted_program(RwsVersion::Rw6, "abb-irb2600-waam", &wall()).await;
}

#[tokio::test]
async fn emitted_rw7_program_uploads_loads_and_runs() {
    // The wall moved into the IRB 1600's reach (X 500..900, Y -300..300, Z 100..500 mm).
    let mut tp = wall();
    for seg in &mut tp.segments {
        for p in &mut seg.points {
            p.x += 500.0;
            p.y -= 100.0;
            p.z += 150.0;
        }
    }
    run_emitted_program(RwsVersion::Rw7, "abb-irb1600-rw7-do", &tp).await;
}

#[tokio::test]
async fn requests_follow_each_generation() {
    for version in [RwsVersion::Rw6, RwsVersion::Rw7] {
        let (sim, cfg, _dir) = setup(version).await;
        let rws = RwsClient::connect(cfg).await.unwrap();
        rws.execution_state().await.unwrap();
        rws.stop().await.unwrap();
        let requests = sim.requests();
        let expected: &[&str] = match version {
            RwsVersion::Rw6 => &[
                "GET /rw/system?json=1",
                "GET /rw/system?json=1",
                "GET /rw/rapid/execution?json=1",
                "POST /rw/rapid/execution?action=stop",
            ],
            RwsVersion::Rw7 => &[
                "GET /rw/system",
                "GET /rw/system",
                "GET /rw/rapid/execution",
                "POST /rw/rapid/execution/stop",
            ],
        };
        assert_eq!(requests, expected, "{version}");
    }
}

#[tokio::test]
async fn login_with_good_and_bad_credentials() {
    for version in [RwsVersion::Rw6, RwsVersion::Rw7] {
        let (sim, cfg, dir) = setup(version).await;
        RwsClient::connect(cfg.clone()).await.unwrap();
        assert_eq!(sim.logins(), 1);

        let wrong = write_credentials(dir.path(), &format!("{USER}:robotics\n"));
        let mut bad = cfg.clone();
        bad.credentials = Some(CredentialsSource::File(wrong.clone()));
        let e = RwsClient::connect(bad).await.unwrap_err();
        let scheme = match version {
            RwsVersion::Rw6 => "digest",
            RwsVersion::Rw7 => "basic",
        };
        assert!(matches!(e, RwsError::Auth { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            format!(
                "sim: 401 after {scheme} login: check the credentials in {}",
                wrong.display()
            )
        );
        assert_eq!(sim.logins(), 1, "no session for wrong credentials");
    }
}

#[tokio::test]
async fn digest_can_be_asked_for_on_rw7_too() {
    let mut sc = SimConfig::new(RwsVersion::Rw7, USER, PASSWORD);
    sc.auth = AuthScheme::Digest;
    let sim = RwsSim::start(sc).await.unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cred = write_credentials(dir.path(), &format!("{USER}:{PASSWORD}"));
    let cfg = ControllerConfig::loopback(
        "sim",
        sim.addr().port(),
        RwsVersion::Rw7,
        CredentialsSource::File(cred),
    );
    let rws = RwsClient::connect(cfg).await.unwrap();
    assert!(!rws.execution_state().await.unwrap().is_running());
}

/// A raw request without credentials: 401 with the controller's Digest challenge; a wrong
/// session cookie does not help.
#[tokio::test]
async fn simulator_challenges_requests_without_auth() {
    let sim = RwsSim::start(SimConfig::new(RwsVersion::Rw6, USER, PASSWORD))
        .await
        .unwrap();
    let http = reqwest::Client::new();
    for cookie in [None, Some("-http-session-=forged; ABBCX=1")] {
        let mut req = http.get(format!("{}/rw/rapid/execution?json=1", sim.url()));
        if let Some(c) = cookie {
            req = req.header("Cookie", c);
        }
        let resp = req.send().await.unwrap();
        assert_eq!(resp.status().as_u16(), 401);
        let challenge = resp.headers()["www-authenticate"].to_str().unwrap();
        assert!(
            challenge.starts_with("Digest realm=\"validusers@robapi.abb\", qop=\"auth\", nonce=\""),
            "{challenge}"
        );
    }
    assert_eq!(sim.logins(), 0);
}

#[tokio::test]
async fn malformed_module_is_rejected_with_the_controller_code() {
    for version in [RwsVersion::Rw6, RwsVersion::Rw7] {
        let (sim, cfg, _dir) = setup(version).await;
        let rws = RwsClient::connect(cfg).await.unwrap();
        let ext = match version {
            RwsVersion::Rw6 => "mod",
            RwsVersion::Rw7 => "modx",
        };
        let module = format!("Job9.{ext}");
        let text = "MODULE Job9\n    PROC main()\n        TPWrite \"hello\";\n    ENDPROC\n";
        let pgf = format!("<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<Program>\n    <Module>{module}</Module>\n</Program>\n");
        let files = [
            (module.as_str(), text.as_bytes()),
            ("Job9.pgf", pgf.as_bytes()),
        ];
        let e = rws.install_program(files).await.unwrap_err();
        assert_eq!(e.abb_code(), Some(codes::RAPID_SYNTAX_ERROR), "{e}");
        assert_eq!(e.http_status(), Some(400));
        let msg = e.to_string();
        assert!(
            msg.contains("-1073442803 (SYS_CTRL_E_RAPID_SYNTAX_ERROR)"),
            "{msg}"
        );
        assert!(
            msg.contains(&format!("cellsuite/{module}, line 4: ENDMODULE missing")),
            "{msg}"
        );
        assert!(sim.modules().is_empty(), "nothing loaded");
        // The uploaded file stays on the controller for inspection.
        assert_eq!(
            sim.file(&format!("cellsuite/{module}")).unwrap(),
            text.as_bytes()
        );
        assert!(!sim.mastership_held());

        // A module whose name is not its file name, loaded on its own.
        let path = rws
            .upload_file(
                "",
                &format!("Other.{ext}"),
                b"MODULE Job9\nENDMODULE\n".to_vec(),
            )
            .await
            .unwrap();
        let e = rws.load_module(&path).await.unwrap_err();
        assert_eq!(e.abb_code(), Some(codes::RAPID_SYNTAX_ERROR), "{e}");
        assert!(
            e.to_string()
                .contains("module name `Job9` differs from the file name `Other`"),
            "{e}"
        );

        // A .pgf that is not one.
        let e = rws
            .install_program([("Bad.pgf", &b"MODULE x\n"[..])])
            .await
            .unwrap_err();
        assert_eq!(e.abb_code(), Some(codes::INVALID_PROGRAMFILE), "{e}");
    }
}

/// A simulator whose controller declares `extra` besides ABB's predefined data, and a client
/// for it.
async fn controller_with(extra: &[&str]) -> (RwsSim, RwsClient, tempfile::TempDir) {
    let mut sim_cfg = SimConfig::new(RwsVersion::Rw6, USER, PASSWORD);
    sim_cfg
        .controller_data
        .extend(extra.iter().map(|n| (*n).to_owned()));
    let sim = RwsSim::start(sim_cfg).await.unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cred = write_credentials(dir.path(), &format!("{USER}:{PASSWORD}\n"));
    let cfg = ControllerConfig::loopback(
        "sim",
        sim.addr().port(),
        RwsVersion::Rw6,
        CredentialsSource::File(cred),
    );
    let rws = RwsClient::connect(cfg).await.unwrap();
    (sim, rws, dir)
}

/// The WAAM profile with `weld: {data: controller}`: the program names seamWAAM and weldWAAM.
fn controller_weld_data_profile() -> MachineProfile {
    use cell_profiles::rapid::{WeldDataSource, WeldMode};
    let mut p = MachineProfile::resolve("abb-irb2600-waam").unwrap();
    if let WeldMode::Arc {
        data,
        arc,
        seam_value,
        ..
    } = &mut p.rapid.as_mut().unwrap().weld
    {
        *data = WeldDataSource::Controller;
        *arc = None;
        *seam_value = None;
    }
    p.validate("abb-irb2600-waam (data: controller)").unwrap();
    p
}

/// Issue 20: the shipped WAAM profile's program declares its own seamdata and welddata and
/// loads and runs on a controller that has only ABB's predefined data. A `data: controller`
/// program names data the controller must have: without them the load fails with a
/// reference error naming the module, line and name; with them it loads and runs.
#[tokio::test]
async fn weld_data_come_with_the_program_or_must_be_on_the_controller() {
    let (sim, rws, _dir) = controller_with(&[]).await;
    let files = emitted("abb-irb2600-waam", &wall(), "self");
    let main = String::from_utf8_lossy(&files[0].1).into_owned();
    assert!(
        main.contains("LOCAL PERS seamdata seamWAAM := ")
            && main.contains("LOCAL PERS welddata weldWAAM1 := [8,8,")
            && main.contains("LOCAL PERS welddata weldWAAM2 := [10,10,"),
        "{main}"
    );
    rws.install_program(as_refs(&files)).await.unwrap();
    assert_eq!(sim.modules()[0].name, "WAAM_self");
    rws.set_pp_to_main().await.unwrap();
    rws.start().await.unwrap();
    let end = rws.wait_until_stopped(POLL, PATIENCE).await.unwrap();
    assert_eq!(end.state, ExecState::Stopped);

    // Controller-side data on a controller without them: refused, the loaded program kept.
    let controller_files: Vec<(String, Vec<u8>)> =
        rapid::emit(&wall(), &controller_weld_data_profile(), "ctrl")
            .unwrap()
            .into_iter()
            .map(|f| (f.name, f.text.into_bytes()))
            .collect();
    let text = String::from_utf8_lossy(&controller_files[0].1).into_owned();
    assert!(
        !text.contains("seamdata") && !text.contains("welddata"),
        "{text}"
    );
    let first_weld_line = 1 + text
        .lines()
        .position(|l| l.trim_start().starts_with("ArcLStart"))
        .unwrap();
    let e = rws
        .install_program(as_refs(&controller_files))
        .await
        .unwrap_err();
    assert_eq!(e.abb_code(), Some(codes::RAPID_SYNTAX_ERROR), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains(&format!(
            "Reference error in HOME/cellsuite/WAAM_ctrl.mod: module WAAM_ctrl, line {first_weld_line}: `seamWAAM` is not declared"
        )),
        "{msg}"
    );
    assert_eq!(sim.modules()[0].name, "WAAM_self", "the old program stays");
    assert!(!sim.mastership_held());

    // A controller with only the seamdata: the welddata is named.
    let (_sim, rws, _dir) = controller_with(&["seamWAAM"]).await;
    let e = rws
        .install_program(as_refs(&controller_files))
        .await
        .unwrap_err();
    assert!(e.to_string().contains("`weldWAAM` is not declared"), "{e}");

    // A controller that declares both: loads and runs.
    let (sim, rws, _dir) = controller_with(&["seamWAAM", "weldWAAM"]).await;
    rws.install_program(as_refs(&controller_files))
        .await
        .unwrap();
    assert_eq!(sim.modules()[0].name, "WAAM_ctrl");
    rws.set_pp_to_main().await.unwrap();
    rws.start().await.unwrap();
    let end = rws.wait_until_stopped(POLL, PATIENCE).await.unwrap();
    assert_eq!(end.state, ExecState::Stopped);
}

#[tokio::test]
async fn bad_program_input_is_refused_before_any_request() {
    let (sim, cfg, _dir) = setup(RwsVersion::Rw6).await;
    let rws = RwsClient::connect(cfg).await.unwrap();
    let before = sim.requests().len();
    let e = rws
        .install_program([("A.mod", &b"MODULE A\nENDMODULE\n"[..])])
        .await
        .unwrap_err();
    assert!(e.to_string().contains("expected exactly one .pgf"), "{e}");
    let e = rws
        .upload_file("", "../evil.mod", Vec::new())
        .await
        .unwrap_err();
    assert!(matches!(e, RwsError::BadInput { .. }), "{e}");
    assert_eq!(sim.requests().len(), before);
}

#[tokio::test]
async fn pp_to_main_needs_a_main_and_start_needs_the_pp() {
    let (_sim, cfg, _dir) = setup(RwsVersion::Rw6).await;
    let rws = RwsClient::connect(cfg).await.unwrap();
    let e = rws.start().await.unwrap_err();
    assert_eq!(e.abb_code(), Some(codes::NO_PP), "{e}");
    let e = rws.set_pp_to_main().await.unwrap_err();
    assert_eq!(e.abb_code(), Some(codes::NO_SUCH_SYMBOL), "{e}");
}

#[tokio::test]
async fn stop_ends_a_run() {
    let mut sc = SimConfig::new(RwsVersion::Rw7, USER, PASSWORD);
    sc.run_time = Duration::from_secs(3600);
    let sim = RwsSim::start(sc).await.unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cred = write_credentials(dir.path(), &format!("{USER}:{PASSWORD}"));
    let cfg = ControllerConfig::loopback(
        "sim",
        sim.addr().port(),
        RwsVersion::Rw7,
        CredentialsSource::File(cred),
    );
    let rws = RwsClient::connect(cfg).await.unwrap();
    let files = emitted("abb-irb2600-waam", &wall(), "w");
    // An RW6 program (.mod) loads on RW7 too.
    rws.install_program(as_refs(&files)).await.unwrap();
    rws.set_pp_to_main().await.unwrap();
    rws.start().await.unwrap();
    assert!(rws.execution_state().await.unwrap().is_running());
    let e = rws.set_pp_to_main().await.unwrap_err();
    assert_eq!(e.abb_code(), Some(codes::EXEC_STATE), "{e}");
    let e = rws
        .wait_until_stopped(POLL, Duration::from_millis(1))
        .await
        .unwrap_err();
    assert!(matches!(e, RwsError::StillRunning { .. }), "{e}");
    rws.stop().await.unwrap();
    let s = rws.wait_until_stopped(POLL, PATIENCE).await.unwrap();
    assert_eq!(s.state, ExecState::Stopped);
}

#[tokio::test]
async fn signals_write_and_read() {
    for (version, signal) in [
        (RwsVersion::Rw6, "doWeld"),
        (RwsVersion::Rw7, "Local/DRV_1/doWeld"),
    ] {
        let (sim, cfg, _dir) = setup(version).await;
        let rws = RwsClient::connect(cfg).await.unwrap();
        assert_eq!(rws.read_signal(signal).await.unwrap(), "0");
        rws.write_signal(signal, "1").await.unwrap();
        assert_eq!(rws.read_signal(signal).await.unwrap(), "1");
        assert_eq!(sim.signal("doWeld").as_deref(), Some("1"));
        rws.write_signal("Local/DRV_1/goWireFeed", "120")
            .await
            .unwrap();
        assert_eq!(
            rws.read_signal("Local/DRV_1/goWireFeed").await.unwrap(),
            "120"
        );

        let e = rws.write_signal(signal, "2").await.unwrap_err();
        assert_eq!(e.abb_code(), Some(codes::INVALID_ARG), "{e}");
        let e = rws.read_signal("Local/DRV_1/doNothing").await.unwrap_err();
        assert_eq!(e.abb_code(), Some(codes::UNRESOLVED_URL), "{e}");
        assert!(e.to_string().contains("Invalid IO signal name"), "{e}");
    }
    // RWS 2.0 has no flat signal form.
    let (_sim, cfg, _dir) = setup(RwsVersion::Rw7).await;
    let rws = RwsClient::connect(cfg).await.unwrap();
    let e = rws.read_signal("doWeld").await.unwrap_err();
    assert_eq!(e.http_status(), Some(404), "{e}");
}

#[tokio::test]
async fn logs_in_again_after_the_session_expires() {
    for version in [RwsVersion::Rw6, RwsVersion::Rw7] {
        let (sim, cfg, _dir) = setup(version).await;
        let rws = RwsClient::connect(cfg).await.unwrap();
        rws.execution_state().await.unwrap();
        assert_eq!((sim.logins(), rws.logins()), (1, 1));
        sim.expire_sessions();
        rws.write_signal(
            if version == RwsVersion::Rw6 {
                "doWeld"
            } else {
                "Local/DRV_1/doWeld"
            },
            "1",
        )
        .await
        .unwrap();
        // RobotWare 6: the stale cookie gets a 401 and the client answers a new Digest
        // challenge. RobotWare 7: Basic credentials go with every request, so the controller
        // opens a new session without a 401 and the client adopts its cookie.
        let client_logins = match version {
            RwsVersion::Rw6 => 2,
            RwsVersion::Rw7 => 1,
        };
        assert_eq!(
            (sim.logins(), rws.logins()),
            (2, client_logins),
            "{version}"
        );
        rws.execution_state().await.unwrap();
        assert_eq!(sim.logins(), 2, "{version}: the new session is kept");
        assert_eq!(
            sim.signal("doWeld").as_deref(),
            Some("1"),
            "the request went through once"
        );
    }
}

/// Callers that share a client (a run, its poll, a hold) and start at once open one session:
/// a second login would replace the first's cookie and strand the mastership it holds.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn concurrent_first_requests_log_in_once() {
    for version in [RwsVersion::Rw6, RwsVersion::Rw7] {
        let (sim, cfg, _dir) = setup(version).await;
        let rws = std::sync::Arc::new(RwsClient::new(cfg).unwrap());
        let polls: Vec<_> = (0..8)
            .map(|_| {
                let rws = rws.clone();
                tokio::spawn(async move { rws.execution_state().await.map(drop) })
            })
            .collect();
        for p in polls {
            p.await.unwrap().unwrap();
        }
        assert_eq!((sim.logins(), rws.logins()), (1, 1), "{version}");
    }
}

#[tokio::test]
async fn lost_mastership_is_taken_again() {
    let (sim, cfg, _dir) = setup(RwsVersion::Rw6).await;
    let rws = RwsClient::connect(cfg).await.unwrap();
    let files = emitted("abb-irb2600-waam", &wall(), "m");
    rws.request_mastership().await.unwrap();
    sim.expire_sessions();
    rws.install_program(as_refs(&files)).await.unwrap();
    assert_eq!(sim.modules().len(), 1);
    rws.release_mastership().await.unwrap();
    assert!(!sim.mastership_held());
}

#[tokio::test]
async fn mastership_held_elsewhere_is_reported() {
    let (sim, cfg, _dir) = setup(RwsVersion::Rw7).await;
    let holder = RwsClient::connect(cfg.clone()).await.unwrap();
    holder.request_mastership().await.unwrap();
    let other = RwsClient::connect(cfg).await.unwrap();
    let files = emitted("abb-irb2600-waam", &wall(), "h");
    let e = other.install_program(as_refs(&files)).await.unwrap_err();
    assert_eq!(e.abb_code(), Some(codes::RESOURCE_HELD), "{e}");
    assert_eq!(e.http_status(), Some(403));
    // Logging out gives it back (RobotWare 7 releases mastership with the session).
    holder.logout().await.unwrap();
    assert!(!sim.mastership_held());
    other.install_program(as_refs(&files)).await.unwrap();
}

#[tokio::test]
async fn credentials_from_environment_and_file() {
    let sim = RwsSim::start(SimConfig::new(RwsVersion::Rw6, USER, PASSWORD))
        .await
        .unwrap();
    let port = sim.addr().port();
    let var = "CELL_RWS_TEST_CREDENTIALS_ENV";
    std::env::set_var(var, format!("{USER}:{PASSWORD}"));
    let cfg = ControllerConfig::loopback(
        "env",
        port,
        RwsVersion::Rw6,
        CredentialsSource::Env(var.into()),
    );
    RwsClient::connect(cfg).await.unwrap();

    let missing = "CELL_RWS_TEST_CREDENTIALS_UNSET";
    std::env::remove_var(missing);
    let cfg = ControllerConfig::loopback(
        "env",
        port,
        RwsVersion::Rw6,
        CredentialsSource::Env(missing.into()),
    );
    let e = RwsClient::connect(cfg).await.unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("credentials from ${missing}: not set (export {missing}='user:password')")
    );

    // A file named relative to the configuration file, read through ControllerConfig::load.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("secrets")).unwrap();
    std::fs::write(
        dir.path().join("secrets/r1.cred"),
        format!("{USER}:{PASSWORD}\n"),
    )
    .unwrap();
    let yaml = dir.path().join("r1.yaml");
    std::fs::write(
        &yaml,
        format!("id: r1\nport: {port}\nrws: rw6\ncredentials:\n  file: secrets/r1.cred\n"),
    )
    .unwrap();
    let cfg = ControllerConfig::load(&yaml).unwrap();
    assert_eq!(
        cfg.credentials,
        Some(CredentialsSource::File(dir.path().join("secrets/r1.cred")))
    );
    RwsClient::connect(cfg).await.unwrap();

    std::fs::write(dir.path().join("secrets/r1.cred"), "no separator\n").unwrap();
    let e = RwsClient::connect(ControllerConfig::load(&yaml).unwrap())
        .await
        .unwrap_err();
    assert!(e.to_string().contains("expected `user:password`"), "{e}");
    assert!(
        !e.to_string().contains("no separator"),
        "the secret is not echoed: {e}"
    );
}

#[test]
fn inline_password_in_yaml_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let yaml = dir.path().join("r1.yaml");
    std::fs::write(
        &yaml,
        "id: r1\nport: 80\nrws: rw6\ncredentials:\n  env: R1\n  password: robotics\n",
    )
    .unwrap();
    let e = ControllerConfig::load(&yaml).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!("{}: field `credentials.password`: credentials must not be written in the configuration", yaml.display())),
        "{e}"
    );
    assert!(!e.contains("robotics"), "{e}");
}

#[test]
fn a_simulator_controller_needs_no_credentials_and_takes_no_address() {
    let ok =
        ControllerConfig::from_yaml_str("id: s\nrws: rw6\nsimulator: {run_s: 1.5}\n", "s.yaml")
            .unwrap();
    assert_eq!(ok.simulator.as_ref().map(|s| s.run_s), Some(1.5));
    assert!(ok.credentials.is_none());
    for (yaml, field) in [
        ("id: s\nrws: rw6\nport: 80\nsimulator: {}\n", "simulator"),
        (
            "id: s\nrws: rw6\nsimulator: {}\ncredentials: {env: X}\n",
            "credentials",
        ),
        (
            "id: s\nrws: rw6\nsimulator: {run_s: -1}\n",
            "simulator.run_s",
        ),
        ("id: s\nrws: rw6\nport: 80\n", "credentials"),
    ] {
        let e = ControllerConfig::from_yaml_str(yaml, "s.yaml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("s.yaml") && e.contains(field), "{yaml}: {e}");
    }
}

#[test]
fn committed_controller_configs_parse() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/controllers");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        // GRBL and Marlin controllers share the directory; they are the machine bridge's to
        // read.
        let other = std::fs::read_to_string(&path)
            .unwrap()
            .lines()
            .any(|l| matches!(l.trim(), "protocol: grbl" | "protocol: marlin"));
        if path.extension().is_some_and(|e| e == "yaml") && !other {
            let r = ControllerConfig::load(&path);
            // An https URL needs the `tls` feature; everything else must parse.
            match r {
                // Real controllers read their login from the environment; the simulator
                // makes its own and names no credentials.
                Ok(cfg) => assert!(
                    matches!(cfg.credentials, Some(CredentialsSource::Env(_)))
                        || (cfg.simulator.is_some() && cfg.credentials.is_none()),
                    "{}",
                    path.display()
                ),
                Err(e) => assert!(
                    !cfg!(feature = "tls") && e.to_string().contains("`tls` feature"),
                    "{}: {e}",
                    path.display()
                ),
            }
            n += 1;
        }
    }
    assert!(n >= 2, "controller configs in {}", dir.display());
}

#[tokio::test]
async fn unreachable_controller_is_a_transport_error() {
    // Bind and drop to get a port that nothing listens on.
    let port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().port()
    };
    let dir = tempfile::tempdir().unwrap();
    let cred = write_credentials(dir.path(), "u:p");
    let cfg =
        ControllerConfig::loopback("gone", port, RwsVersion::Rw6, CredentialsSource::File(cred));
    let e = RwsClient::connect(cfg).await.unwrap_err();
    assert!(matches!(e, RwsError::Transport { .. }), "{e}");
    assert!(
        e.to_string().starts_with("gone: GET /rw/system?json=1: "),
        "{e}"
    );
}
