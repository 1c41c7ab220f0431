//! Every YAML config type, through its own loader (which validates after parsing): machine
//! profiles, controller files (GRBL and ABB RWS), kerf materials, G-Wing specs, the WAAM
//! process, launch files, and a bag's `metadata.yaml` with its QoS profiles.

use std::path::Path;

use cell_bag::MetadataFile;
use cell_bridge::config::ControllerSpec;
use cell_launch::LaunchFile;
use cell_planner::kerf::MaterialLibrary;
use cell_profiles::MachineProfile;
use cell_waam::WaamProcess;
use cell_wing::spec::WingSpec;

use crate::{repo_root, seed_files, text, Target};

const TOKENS: &[&str] = &[
    "\n",
    "\n  ",
    ": ",
    "- ",
    "{",
    "}",
    "[",
    "]",
    ", ",
    "~",
    "null",
    "true",
    "'",
    "\"",
    "&a ",
    "*a",
    "<<: *a\n",
    "!!str ",
    "!!binary ",
    "? ",
    "|\n  ",
    ">-\n  ",
    "---\n",
    "#",
    ".inf",
    "-.inf",
    ".nan",
    "0x7fffffff",
    "1e400",
    "-1",
    "0",
    "protocol: grbl\n",
    "protocol: rws\n",
    "$(env HOME)",
    "$(find-pkg-share cell_msgs)",
    "$(var x)",
];

fn machine(data: &[u8]) {
    let _ = MachineProfile::from_yaml_str(&text(data), "fuzz.yaml");
}

fn controller(data: &[u8]) {
    let text = text(data);
    let _ = ControllerSpec::from_yaml_str(&text, "fuzz.yaml", None);
    let _ = cell_rws::ControllerConfig::from_yaml_str(&text, "fuzz.yaml");
}

fn materials(data: &[u8]) {
    let _ = MaterialLibrary::from_yaml_str(&text(data), "fuzz.yaml");
}

fn wing(data: &[u8]) {
    let _ = WingSpec::from_yaml_str(&text(data), "fuzz.yaml");
}

fn waam(data: &[u8]) {
    let _ = WaamProcess::from_yaml_str(&text(data), "fuzz.yaml");
}

fn launch(data: &[u8]) {
    let path = repo_root().join("launch_scripts/fuzz.launch.yaml");
    let args = [("use_sim".to_string(), "true".to_string())];
    let _ = LaunchFile::parse(&text(data), path, &args);
}

fn bag_metadata(data: &[u8]) {
    let text = text(data);
    if let Ok(meta) = MetadataFile::from_yaml(&text, Path::new("metadata.yaml")) {
        let _ = MetadataFile::from_yaml(&meta.to_yaml(), Path::new("again.yaml"));
    }
    let _ = cell_bag::qos::from_yaml(&text);
}

fn machine_seeds() -> Vec<Vec<u8>> {
    seed_files("config/machines", &[".yaml"], 1 << 16)
}
fn controller_seeds() -> Vec<Vec<u8>> {
    seed_files("config/controllers", &[".yaml"], 1 << 16)
}
fn material_seeds() -> Vec<Vec<u8>> {
    seed_files("config/materials", &[".yaml"], 1 << 16)
}
fn wing_seeds() -> Vec<Vec<u8>> {
    seed_files("config/wings", &[".yaml"], 1 << 16)
}
fn waam_seeds() -> Vec<Vec<u8>> {
    seed_files("config/processes", &[".yaml"], 1 << 16)
}
fn launch_seeds() -> Vec<Vec<u8>> {
    seed_files("launch_scripts", &[".yaml"], 1 << 16)
}

/// The `metadata.yaml` of a bag the library writes, and a QoS list as rosbag2 writes it.
fn metadata_seeds() -> Vec<Vec<u8>> {
    let dir = crate::scratch_dir("metadata_seed").join("seed");
    let _ = std::fs::remove_dir_all(&dir);
    let mut out = Vec::new();
    if let Ok(mut w) = cell_bag::BagWriter::create(&dir, cell_bag::BagWriterOptions::default()) {
        let msg = cell_msgs::std_msgs::StringMsg { data: "x".into() };
        let _ = w.write("/chatter", &msg, 1_000);
        if let Ok(meta) = w.finish() {
            out.push(meta.to_yaml().into_bytes());
        }
    }
    let qos = cell_bag::qos::to_yaml(&[
        cell_bag::QosProfile::reliable_transient_local(1),
        cell_bag::QosProfile::best_effort(10),
    ]);
    out.push(qos.into_bytes());
    out
}

/// The config targets.
pub fn targets() -> Vec<Target> {
    let t = |name, about, run, seeds| Target {
        name,
        about,
        run,
        seeds,
        tokens: TOKENS,
        max_len: 1 << 14,
    };
    vec![
        t(
            "config_machine",
            "machine profiles (config/machines)",
            machine,
            machine_seeds,
        ),
        t(
            "config_controller",
            "controller files, GRBL and RWS (config/controllers)",
            controller,
            controller_seeds,
        ),
        t(
            "config_materials",
            "kerf material libraries (config/materials)",
            materials,
            material_seeds,
        ),
        t(
            "config_wing",
            "G-Wing specs (config/wings)",
            wing,
            wing_seeds,
        ),
        t(
            "config_waam",
            "WAAM process (config/processes)",
            waam,
            waam_seeds,
        ),
        t(
            "config_launch",
            "ROS 2 YAML launch files (launch_scripts)",
            launch,
            launch_seeds,
        ),
        t(
            "config_bag_metadata",
            "a bag's metadata.yaml and QoS profiles",
            bag_metadata,
            metadata_seeds,
        ),
    ]
}
