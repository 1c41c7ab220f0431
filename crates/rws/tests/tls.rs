//! HTTPS with a pinned certificate: the RWS simulator serves RWS 2.0 over TLS with the test
//! certificate in `tests/data/tls` (made with openssl; its README), and the client accepts it
//! only by its SHA-256 fingerprint, the one `openssl x509 -fingerprint -sha256` printed for it.
//! (This crate's tests build it with the `tls` feature.)

use std::path::{Path, PathBuf};

use base64::Engine as _;
use cell_rws::sim::{RwsSim, SimConfig, SimTls};
use cell_rws::{CertPin, ControllerConfig, RwsClient, RwsError, RwsVersion};

/// `openssl x509 -in tests/data/tls/rws_sim.crt -noout -fingerprint -sha256`.
const FINGERPRINT: &str = "3A:04:1F:B9:6B:6C:96:35:CD:43:A4:A6:91:31:B8:2D:34:55:F5:ED:6B:36:60:E1:E7:6D:5E:31:70:A6:84:43";

fn data(name: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/tls")
            .join(name),
    )
    .unwrap()
}

/// An OmniCore simulator serving HTTPS with the test certificate, and a directory with its
/// login in `op.cred`.
async fn omnicore() -> (RwsSim, tempfile::TempDir) {
    let mut cfg = SimConfig::new(RwsVersion::Rw7, "Operator", "s3cret");
    cfg.tls = Some(SimTls {
        cert_pem: data("rws_sim.crt"),
        key_pem: data("rws_sim.key"),
    });
    let sim = RwsSim::start(cfg).await.unwrap();
    assert!(sim.url().starts_with("https://"), "{}", sim.url());
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("op.cred"), "Operator:s3cret\n").unwrap();
    (sim, dir)
}

fn config(sim: &RwsSim, dir: &Path, tls: &str) -> ControllerConfig {
    let path: PathBuf = dir.join("omnicore.yaml");
    std::fs::write(
        &path,
        format!(
            "id: omnicore\nurl: {}\nrws: rw7\ncredentials: {{file: op.cred}}\n{tls}",
            sim.url()
        ),
    )
    .unwrap();
    ControllerConfig::load(&path).unwrap()
}

#[test]
fn the_fingerprint_is_openssls() {
    let pem = String::from_utf8(data("rws_sim.crt")).unwrap();
    let body: String = pem.lines().filter(|l| !l.starts_with("-----")).collect();
    let der = base64::engine::general_purpose::STANDARD
        .decode(body)
        .unwrap();
    assert_eq!(CertPin::of_der(&der).to_string(), FINGERPRINT);
}

#[tokio::test]
async fn the_pinned_certificate_is_accepted() {
    let (sim, dir) = omnicore().await;
    let cfg = config(
        &sim,
        dir.path(),
        &format!("tls: {{pin_sha256: \"{FINGERPRINT}\"}}\n"),
    );
    let rws = RwsClient::connect(cfg).await.unwrap();
    rws.write_signal("Local/DRV_1/doWeld", "1").await.unwrap();
    assert_eq!(rws.read_signal("Local/DRV_1/doWeld").await.unwrap(), "1");
    assert_eq!(sim.signal("doWeld").as_deref(), Some("1"));
    assert!(!rws.execution_state().await.unwrap().is_running());
    assert_eq!(sim.logins(), 1, "Basic login over HTTPS");
}

#[tokio::test]
async fn another_certificate_is_refused_naming_the_expected_and_the_seen() {
    let (sim, dir) = omnicore().await;
    let other = "AB:".repeat(31) + "AB";
    let cfg = config(
        &sim,
        dir.path(),
        &format!("tls: {{pin_sha256: \"{other}\"}}\n"),
    );
    let e = RwsClient::connect(cfg).await.unwrap_err();
    match &e {
        RwsError::CertificatePin { expected, seen, .. } => {
            assert_eq!(expected, &other);
            assert_eq!(seen, FINGERPRINT);
        }
        other => panic!("{other}"),
    }
    let text = e.to_string();
    assert!(
        text.contains(&other) && text.contains(FINGERPRINT) && text.contains("tls.pin_sha256"),
        "{text}"
    );
    assert_eq!(sim.logins(), 0, "no password was sent");
    assert!(sim.requests().is_empty(), "no request got through");
}

#[tokio::test]
async fn without_a_pin_a_self_signed_certificate_is_refused_with_its_fingerprint() {
    let (sim, dir) = omnicore().await;
    let cfg = config(&sim, dir.path(), "");
    let e = RwsClient::connect(cfg).await.unwrap_err();
    assert!(matches!(e, RwsError::CertificateUntrusted { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains(&format!("pin_sha256: \"{FINGERPRINT}\"")),
        "{text}"
    );
    assert!(sim.requests().is_empty(), "no request got through");
}

#[test]
fn certificate_settings_are_checked_where_they_are_written() {
    // The old switch that accepted any certificate points to the pin.
    let e = ControllerConfig::from_yaml_str(
        "id: r\nurl: https://10.0.0.9\nrws: rw7\ncredentials: {env: X}\naccept_invalid_certs: true\n",
        "r.yaml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("r.yaml: field `accept_invalid_certs`: no longer read")
            && e.contains("tls: {pin_sha256:"),
        "{e}"
    );
    // A pin is for HTTPS only.
    let e = ControllerConfig::from_yaml_str(
        &format!("id: r\nport: 8080\nrws: rw6\ncredentials: {{env: X}}\ntls: {{pin_sha256: \"{FINGERPRINT}\"}}\n"),
        "r.yaml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("r.yaml: field `tls`: only for an https:// url"),
        "{e}"
    );
    // A pin that is not a SHA-256 is named with its line.
    let e = ControllerConfig::from_yaml_str(
        "id: r\nurl: https://10.0.0.9\nrws: rw7\ncredentials: {env: X}\ntls:\n  pin_sha256: \"AB:CD\"\n",
        "r.yaml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("r.yaml:6: field `tls.pin_sha256`") && e.contains("found 4 hex digits"),
        "{e}"
    );
}
