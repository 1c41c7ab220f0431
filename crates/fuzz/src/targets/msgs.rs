//! `cell_msgs`: the dynamic CDR decoder over every registered type (and the typed decoders of
//! our own messages), and the `.msg`/`.srv`/`.action` parser with a schema built from the parsed
//! text decoding bytes.

use std::sync::OnceLock;

use cell_msgs::dynamic::Schema;
use cell_msgs::idl::{parse_action, parse_message, parse_service};
use cell_msgs::{from_cdr, to_cdr, HeatMap, MachineStatus, Toolpath};

use crate::{repo_root, text, Target};

const CDR_TOKENS: &[&str] = &[
    "\u{0}\u{1}\u{0}\u{0}",
    "\u{0}\u{0}\u{0}\u{0}",
    "\u{1}\u{0}\u{0}\u{0}",
    "\u{ff}\u{ff}\u{ff}\u{ff}",
    "\u{ff}\u{ff}\u{ff}\u{7f}",
    "\u{0}\u{0}\u{0}\u{80}",
    "\u{4}\u{0}\u{0}\u{0}abc\u{0}",
];

const MSG_TOKENS: &[&str] = &[
    "\n---\n",
    "\n",
    "#",
    "int32 ",
    "uint8[] ",
    "float64[3] ",
    "string<=10 ",
    "string ",
    "wstring ",
    "bool ",
    "byte ",
    "char ",
    "time ",
    "duration ",
    "std_msgs/Header ",
    "builtin_interfaces/Time ",
    "geometry_msgs/Point[<=4] ",
    "Root ",
    "[] ",
    "[<=",
    "=",
    " x",
    " X=1",
    " value 0",
    "\"quoted\"",
    "[1, 2, 3]",
    "================================================================================\nMSG: ",
    "fuzz_pkg/msg/Inner\n",
];

/// Every registered type with its schema, built once.
fn schemas() -> &'static [(String, Schema)] {
    static ALL: OnceLock<Vec<(String, Schema)>> = OnceLock::new();
    ALL.get_or_init(|| {
        cell_msgs::registry::list()
            .into_iter()
            .filter_map(|name| Schema::from_registry(&name).ok().map(|s| (name, s)))
            .collect()
    })
}

/// Two bytes pick the type, the rest is the serialized message.
fn cdr(data: &[u8]) {
    let all = schemas();
    if data.len() < 2 || all.is_empty() {
        return;
    }
    let pick = u16::from_le_bytes([data[0], data[1]]) as usize % all.len();
    let bytes = &data[2..];
    let _ = all[pick].1.decode(bytes);
    let _ = from_cdr::<Toolpath>(bytes);
    let _ = from_cdr::<MachineStatus>(bytes);
    let _ = HeatMap::from_cdr_bulk(bytes);
}

fn type_index(name: &str) -> u16 {
    schemas().iter().position(|(n, _)| n == name).unwrap_or(0) as u16
}

fn cdr_seeds() -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut push = |name: &str, bytes: Vec<u8>| {
        let mut v = type_index(name).to_le_bytes().to_vec();
        v.extend(bytes);
        out.push(v);
    };
    for file in crate::seed_files("tests/data/toolpaths", &[".json"], 1 << 16) {
        if let Ok(tp) = cell_msgs::json::from_str::<Toolpath>(&String::from_utf8_lossy(&file)) {
            if let Ok(b) = to_cdr(&tp) {
                push("cell_msgs/msg/Toolpath", b);
            }
        }
    }
    if let Ok(b) = to_cdr(&MachineStatus::default()) {
        push("cell_msgs/msg/MachineStatus", b);
    }
    let msg = cell_msgs::std_msgs::StringMsg {
        data: "hello".into(),
    };
    if let Ok(b) = to_cdr(&msg) {
        push("std_msgs/msg/String", b);
    }
    out
}

/// One byte picks message, service or action; the rest is the file's text. A message that
/// parses is also the root of a schema that decodes the input's own bytes.
fn msg(data: &[u8]) {
    let kind = data.first().copied().unwrap_or(0) % 3;
    let body = data.get(1..).unwrap_or_default();
    let text = text(body);
    match kind {
        0 => {
            if parse_message("fuzz_pkg/msg/Root", &text).is_ok() {
                if let Ok(schema) = Schema::from_full_definition("fuzz_pkg/msg/Root", &text) {
                    let mut bytes = vec![0, 1, 0, 0];
                    bytes.extend_from_slice(&body[..body.len().min(256)]);
                    let _ = schema.decode(&bytes);
                }
            }
        }
        1 => {
            let _ = parse_service("fuzz_pkg/srv/Root", &text);
        }
        _ => {
            let _ = parse_action("fuzz_pkg/action/Root", &text);
        }
    }
    let _ = cell_msgs::idl::sections(&text);
}

fn msg_seeds() -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut add = |kind: u8, dir: &str, ext: &str| {
        for f in crate::seed_files(dir, &[ext], 1 << 16) {
            let mut v = vec![kind];
            v.extend(f);
            out.push(v);
        }
    };
    add(0, "msgs/msg", ".msg");
    add(1, "msgs/srv", ".srv");
    add(2, "msgs/action", ".action");
    if let Ok(packages) = std::fs::read_dir(repo_root().join("msgs/std")) {
        let mut names: Vec<String> = packages
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        for p in names {
            add(0, &format!("msgs/std/{p}/msg"), ".msg");
            add(1, &format!("msgs/std/{p}/srv"), ".srv");
        }
    }
    out
}

/// The message targets.
pub fn targets() -> Vec<Target> {
    vec![
        Target {
            name: "cdr_dynamic",
            about: "dynamic CDR decoder over every registered type, typed decoders",
            run: cdr,
            seeds: cdr_seeds,
            tokens: CDR_TOKENS,
            max_len: 1 << 14,
        },
        Target {
            name: "msg_parser",
            about: ".msg/.srv/.action parser, schema from the parsed text",
            run: msg,
            seeds: msg_seeds,
            tokens: MSG_TOKENS,
            max_len: 1 << 14,
        },
    ]
}
