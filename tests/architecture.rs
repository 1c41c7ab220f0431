//! The layout is the architecture (ARCHITECTURE.md), checked:
//!
//! - every workspace crate declares its layer (`[package.metadata.cellsuite] layer = "…"`), and
//!   its folder agrees with it: `crates/<dir>` holds libraries (`algorithm`, `io`, `runtime`,
//!   and `test` support that is only ever a dev-dependency) named `cell_<dir>`, `nodes/<dir>`
//!   holds node crates named `<dir>` whose binary is `<dir>`;
//! - a crate's dependency tree, as `cargo test -p` of that crate builds it (its own
//!   dev-dependencies included, features resolved for it alone), holds none of the crates its
//!   layer forbids: an algorithm crate knows nothing of ROS, DDS, tokio or Rerun, an I/O crate
//!   nothing of ROS, DDS or Rerun.
//!
//! The check runs `cargo metadata` and `cargo tree`; a failure names the crate, the forbidden
//! dependency and the chain that brings it in.

use std::path::Path;
use std::process::Command;

/// Crates an `algorithm` crate must not reach, directly or through anything it depends on.
const ALGORITHM_FORBIDS: &[&str] = &[
    "cell_runtime",
    "cell_launch",
    "cell_bag",
    "cell_grbl",
    "cell_rws",
    "cell_bridge",
    "tokio",
    "rerun",
    "ros2-client",
    "rustdds",
    "iceoryx2",
];

/// Crates an `io` crate (controller protocols, bags) must not reach: no ROS, DDS or Rerun.
const IO_FORBIDS: &[&str] = &[
    "cell_runtime",
    "cell_launch",
    "rerun",
    "ros2-client",
    "rustdds",
    "iceoryx2",
];

/// The message crate, with its default features (the `ros2` feature is for nodes).
const MESSAGES_FORBIDS: &[&str] = &[
    "cell_runtime",
    "tokio",
    "rerun",
    "ros2-client",
    "rustdds",
    "iceoryx2",
];

fn forbidden_for(layer: &str) -> &'static [&'static str] {
    match layer {
        "algorithm" => ALGORITHM_FORBIDS,
        "io" => IO_FORBIDS,
        "messages" => MESSAGES_FORBIDS,
        _ => &[],
    }
}

/// One workspace crate as `cargo metadata` describes it.
struct Member {
    name: String,
    dir: String,
    layer: Option<String>,
    bins: Vec<String>,
    /// What it depends on outside `[dev-dependencies]` (normal and build dependencies).
    non_dev_deps: Vec<String>,
}

fn cargo() -> Command {
    let mut cmd = Command::new(env!("CARGO"));
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"));
    cmd
}

fn members() -> Vec<Member> {
    let out = cargo()
        .args(["metadata", "--no-deps", "--format-version", "1"])
        .output()
        .expect("run cargo metadata");
    assert!(
        out.status.success(),
        "cargo metadata: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("cargo metadata JSON");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    meta["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .map(|p| {
            let manifest = Path::new(p["manifest_path"].as_str().expect("manifest_path"));
            let dir = manifest.parent().unwrap().strip_prefix(root).unwrap();
            Member {
                name: p["name"].as_str().unwrap().to_string(),
                dir: dir.to_string_lossy().into_owned(),
                layer: p["metadata"]["cellsuite"]["layer"]
                    .as_str()
                    .map(str::to_string),
                bins: p["targets"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|t| t["kind"].as_array().unwrap().iter().any(|k| k == "bin"))
                    .map(|t| t["name"].as_str().unwrap().to_string())
                    .collect(),
                non_dev_deps: p["dependencies"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|d| d["kind"] != "dev")
                    .map(|d| d["name"].as_str().unwrap().to_string())
                    .collect(),
            }
        })
        .collect()
}

/// Where a crate's folder says it belongs; `None` when its folder and layer agree.
fn layout_problem(m: &Member) -> Option<String> {
    let (folder, dir) = m.dir.split_once('/').unwrap_or((m.dir.as_str(), ""));
    let layer = m.layer.as_deref();
    match (folder, layer) {
        ("", _) if m.name == "cellsuite" => None,
        ("msgs", Some("messages")) => None,
        ("crates", Some("algorithm" | "io" | "runtime" | "test"))
            if m.name == format!("cell_{dir}") =>
        {
            None
        }
        ("crates", Some("algorithm" | "io" | "runtime")) => Some(format!(
            "{} is in crates/{dir}, so its package is named cell_{dir}",
            m.name
        )),
        ("nodes", Some("node")) if m.name == dir && m.bins.iter().any(|b| b == dir) => None,
        ("nodes", Some("node")) => Some(format!(
            "{} is in nodes/{dir}, so its package and its binary are named {dir} (binaries: {:?})",
            m.name, m.bins
        )),
        (_, None) => Some(format!(
            "{} ({}) declares no layer: add [package.metadata.cellsuite] layer = \"…\"",
            m.name, m.dir
        )),
        (_, Some(layer)) => Some(format!(
            "{} ({}) has layer {layer:?}, which does not belong there",
            m.name, m.dir
        )),
    }
}

/// The forbidden crates in a `cargo tree --prefix depth -f '{p}'` listing, each with the chain
/// from the root that brings it in (`cell_wing -> cell_emitter -> cell_runtime`).
fn forbidden_chains(tree: &str, forbidden: &[&str]) -> Vec<String> {
    let mut stack: Vec<&str> = Vec::new();
    let mut found = Vec::new();
    for line in tree.lines() {
        let digits = line.chars().take_while(char::is_ascii_digit).count();
        let Ok(depth) = line[..digits].parse::<usize>() else {
            continue;
        };
        let name = line[digits..].split_whitespace().next().unwrap_or("");
        stack.truncate(depth);
        stack.push(name);
        if depth > 0 && forbidden.contains(&name) {
            let chain = stack.join(" -> ");
            if !found.contains(&chain) {
                found.push(chain);
            }
        }
    }
    found
}

fn dependency_tree(package: &str) -> String {
    let out = cargo()
        .args([
            "tree",
            "-p",
            package,
            "-e",
            "normal,build,dev",
            "--prefix",
            "depth",
            "-f",
            "{p}",
        ])
        .output()
        .expect("run cargo tree");
    assert!(
        out.status.success(),
        "cargo tree -p {package}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn every_crate_sits_in_the_folder_of_its_layer() {
    let members = members();
    let problems: Vec<String> = members.iter().filter_map(layout_problem).collect();
    assert!(problems.is_empty(), "layout:\n{}", problems.join("\n"));
    // The layers are all there (a rename of the metadata key would make the check vacuous).
    for layer in ["algorithm", "io", "runtime", "node", "messages"] {
        assert!(
            members.iter().any(|m| m.layer.as_deref() == Some(layer)),
            "no crate declares layer {layer:?}"
        );
    }
}

#[test]
fn algorithm_and_io_crates_depend_on_nothing_their_layer_forbids() {
    let members = members();
    let mut checked = Vec::new();
    let mut problems = Vec::new();
    for m in &members {
        let Some(layer) = m.layer.as_deref() else {
            continue;
        };
        let forbidden = forbidden_for(layer);
        if forbidden.is_empty() {
            continue;
        }
        checked.push(m.name.as_str());
        for chain in forbidden_chains(&dependency_tree(&m.name), forbidden) {
            problems.push(format!(
                "{} ({layer}) depends on {}: {chain}",
                m.name,
                chain.rsplit(" -> ").next().unwrap()
            ));
        }
    }
    assert!(
        checked.contains(&"cell_planner") && checked.contains(&"cell_grbl"),
        "checked only {checked:?}"
    );
    assert!(
        problems.is_empty(),
        "forbidden dependencies:\n{}",
        problems.join("\n")
    );
}

#[test]
fn test_support_is_only_ever_a_dev_dependency() {
    let members = members();
    let support: Vec<&str> = members
        .iter()
        .filter(|m| m.layer.as_deref() == Some("test"))
        .map(|m| m.name.as_str())
        .collect();
    assert!(
        support.contains(&"cell_testkit"),
        "test-support crates: {support:?}"
    );
    let problems: Vec<String> = members
        .iter()
        .flat_map(|m| {
            m.non_dev_deps
                .iter()
                .filter(|d| support.contains(&d.as_str()))
                .map(move |d| format!("{} depends on {d} outside [dev-dependencies]", m.name))
        })
        .collect();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_check_names_the_chain_to_a_forbidden_dependency() {
    // What `cargo tree` prints for an algorithm crate that gained a runtime dependency through
    // a dev-dependency on another crate.
    let tree = "0cell_wing v0.1.0 (/w/crates/wing)\n\
                1cell_airfoil v0.1.0 (/w/crates/airfoil)\n\
                2nalgebra v0.33.2\n\
                1cell_emitter v0.1.0 (/w/crates/emitter)\n\
                2cell_runtime v0.1.0 (/w/crates/runtime)\n\
                3tokio v1.54.1\n\
                1tokio v1.54.1\n";
    assert_eq!(
        forbidden_chains(tree, ALGORITHM_FORBIDS),
        [
            "cell_wing -> cell_emitter -> cell_runtime",
            "cell_wing -> cell_emitter -> cell_runtime -> tokio",
            "cell_wing -> tokio"
        ]
    );
    assert!(forbidden_chains(tree, &["rerun"]).is_empty());
    // A node in the wrong folder, a library without the cell_ prefix, a crate without a layer.
    let node = |name: &str, dir: &str, bins: &[&str], layer: Option<&str>| Member {
        name: name.into(),
        dir: dir.into(),
        layer: layer.map(str::to_string),
        bins: bins.iter().map(|b| b.to_string()).collect(),
        non_dev_deps: Vec::new(),
    };
    assert!(layout_problem(&node(
        "planner",
        "nodes/planner",
        &["planner"],
        Some("node")
    ))
    .is_none());
    assert!(layout_problem(&node(
        "cell_bridge",
        "nodes/bridge",
        &["machine_bridge"],
        Some("node")
    ))
    .is_some());
    assert!(layout_problem(&node("planner", "crates/planner", &[], Some("algorithm"))).is_some());
    assert!(layout_problem(&node("cell_x", "crates/x", &[], None)).is_some());
    assert!(layout_problem(&node("cell_x", "crates/x", &[], Some("node"))).is_some());
}
