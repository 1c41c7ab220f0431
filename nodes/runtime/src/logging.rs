//! `tracing` set-up shared by every node and the `cell` command.

use tracing_subscriber::EnvFilter;

/// Directives applied under `RUST_LOG`: the DDS stack logs every discovery event at `info`,
/// which buries the cell's own messages, so it is held to warnings unless asked for.
pub const QUIET_DEPENDENCIES: &str =
    "rustdds=warn,ros2_client=warn,ros2_client::distributions=error,iceoryx2=warn,re_sdk=warn";

/// Installs the global subscriber: `RUST_LOG` if set (plus [`QUIET_DEPENDENCIES`] for crates it
/// does not mention), else `default_level`. Safe to call more than once (later calls do nothing),
/// which in-process tests rely on.
pub fn init(default_level: Option<&str>) {
    let user = std::env::var("RUST_LOG").ok();
    let mut directives = user
        .clone()
        .or_else(|| default_level.map(str::to_string))
        .unwrap_or_else(|| "info".to_string());
    for quiet in QUIET_DEPENDENCIES.split(',') {
        let target = quiet.split('=').next().unwrap_or_default();
        if !directives.contains(target) {
            directives.push(',');
            directives.push_str(quiet);
        }
    }
    let filter = EnvFilter::try_new(&directives).unwrap_or_else(|e| {
        eprintln!("warning: ignoring bad log filter {directives:?}: {e}");
        EnvFilter::new(format!("info,{QUIET_DEPENDENCIES}"))
    });
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .try_init();
}
