//! ABB Robot Web Services answers: the execution state, a signal's value, the controller's
//! error status (JSON and XHTML shapes), the Digest challenge of a 401 and a pinned
//! certificate's fingerprint, each as `cell_rws` reads them.

use cell_rws::client::{parse_execution_state, parse_signal_value};
use cell_rws::{AbbStatus, CertPin};

use crate::{text, Target};

const TOKENS: &[&str] = &[
    "{",
    "}",
    "[",
    "]",
    ",",
    ":",
    "\"_type\"",
    "\"rap-execution\"",
    "\"ios-signal\"",
    "\"ctrlexecstate\"",
    "\"running\"",
    "\"stopped\"",
    "\"cycle\"",
    "\"lvalue\"",
    "\"_embedded\"",
    "\"status\"",
    "\"code\"",
    "\"msg\"",
    "-1073442803",
    "<span class=\"code\">",
    "<span class=\"msg\">",
    "</span>",
    "&amp;",
    "&#",
    "Digest ",
    "realm=\"validusers@robapi.abb\"",
    "nonce=\"",
    "qop=\"auth\"",
    "qop=\"auth-int\"",
    "algorithm=MD5",
    "algorithm=SHA-256",
    "opaque=\"",
    "stale=true",
    ", ",
];

fn answer(data: &[u8]) {
    let body = text(data);
    let _ = parse_execution_state(&body);
    let _ = parse_signal_value(&body);
    if let Some(status) = AbbStatus::parse(&body) {
        let _ = status.name();
        let _ = status.to_string();
    }
    let _ = CertPin::parse(&body);
    // A 401's challenge, answered as the client answers it.
    // The client reads header values with `HeaderValue::to_str`, which passes visible ASCII
    // only (digest_auth 0.3.1 slices by char index and panics on multi-byte characters).
    let header_text = |l: &&str| l.bytes().all(|b| b == b'\t' || (32..127).contains(&b));
    for challenge in body.lines().filter(header_text) {
        if let Ok(mut prompt) = digest_auth::parse(challenge) {
            let ctx = digest_auth::AuthContext::new_with_method(
                "Default User",
                "robotics",
                "/rw/system",
                Option::<&[u8]>::None,
                digest_auth::HttpMethod::GET,
            );
            if let Ok(a) = prompt.respond(&ctx) {
                let _ = a.to_header_string();
            }
        }
    }
}

fn seeds() -> Vec<Vec<u8>> {
    [
        r#"{"_links":{"base":{"href":"http://127.0.0.1/rw/rapid/"}},"_embedded":{"_state":[{"_type":"rap-execution","_title":"execution","ctrlexecstate":"running","cycle":"forever"}]}}"#,
        r#"{"state":[{"_type":"rap-execution","ctrlexecstate":"stopped","cycle":"once"}]}"#,
        r#"{"_embedded":{"_state":[{"_type":"ios-signal","lvalue":"1","lstate":"not simulated"}]}}"#,
        r#"{"status":{"code":-1073442803,"msg":"Mastership is held by another client"}}"#,
        r#"{"_embedded":{"status":{"code":"-1073445865","msg":"Resource not found"}}}"#,
        "<html><body><div class=\"status\"><span class=\"code\">-1073442803</span><span class=\"msg\">held &amp; busy</span></div></body></html>",
        "Digest realm=\"validusers@robapi.abb\", domain=\"/\", qop=\"auth\", nonce=\"8f1d2e\", opaque=\"799d5\", algorithm=MD5, stale=FALSE",
        "AB:CD:EF:01:23:45:67:89:AB:CD:EF:01:23:45:67:89:AB:CD:EF:01:23:45:67:89:AB:CD:EF:01:23:45:67:89",
    ]
    .iter()
    .map(|s| s.as_bytes().to_vec())
    .collect()
}

/// The RWS target.
pub fn targets() -> Vec<Target> {
    vec![Target {
        name: "rws_answers",
        about: "RWS answers: execution state, signal, error status, Digest challenge, pin",
        run: answer,
        seeds,
        tokens: TOKENS,
        max_len: 1 << 14,
    }]
}
