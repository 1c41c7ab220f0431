//! `tracing` set-up shared by every node and the `cell` command.

use std::io::IsTerminal;

use tracing_subscriber::EnvFilter;

/// Directives applied under `RUST_LOG`. rustdds reports routine discovery conditions as
/// warnings (no multicast on `lo`, peers whose locators are not confirmed yet) and, on loopback,
/// an error when it leaves a multicast group it never joined; those bury the cell's own
/// messages, so rustdds is held to errors and its UDP listener is silent unless asked for
/// (e.g. `RUST_LOG=info,rustdds=warn`). ros2-client warns on every service request that rustdds
/// sends without a related sample identity, which is how this DDS stack always sends them; and
/// Rerun's chunk store warns about out-of-order timelines, which the planner's loss curve
/// (logged live, then whole) has by design.
pub const QUIET_DEPENDENCIES: &str =
    "rustdds=error,rustdds::network::udp_listener=off,ros2_client=warn,\
     ros2_client::distributions=error,ros2_client::service::wrappers=error,iceoryx2=warn,\
     re_sdk=warn,re_chunk=error";

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
    use tracing_subscriber::layer::SubscriberExt as _;
    use tracing_subscriber::util::SubscriberInitExt as _;
    let _ = tracing_subscriber::registry()
        .with(filter)
        .with(
            tracing_subscriber::fmt::layer()
                .with_writer(std::io::stderr)
                .with_ansi(
                    std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
                ),
        )
        // What passes the filter also goes to /rosout (crate::rosout).
        .with(crate::rosout::RosoutLayer)
        .try_init();
}
