//! The cellsuite node runtime: what every node is built on.
//!
//! - [`action`]: ROS 2 actions (goal, feedback, result, cancel) for long jobs;
//! - [`goal_server`]: the one action-goal server every action node uses ([`goal_server::serve`]);
//! - [`service`]: ROS 2 services (request, response) for short queries;
//! - [`args`]: the ROS 2 command line (`--ros-args -r … -p … --params-file …`);
//! - [`params`]: ROS 2 parameter YAML validated into typed structs;
//! - [`data_files`]: files named in goals, confined to the data directories, capped, unquoted;
//! - [`node`]: [`CellNode`], one DDS participant per node, `ROS_DOMAIN_ID`, interface binding;
//! - [`qos`]: QoS presets for plans, streams and status;
//! - [`type_hash`]: the REP-2011 type hash every endpoint announces in its DDS USER_DATA;
//! - [`pubsub`]: typed publish/subscribe, DDS plus the iceoryx2 [`fastpath`] for large messages;
//! - [`rerun_sink`]: the shared Rerun sink and its entity-path conventions;
//! - [`views`]: the standard-type views for RViz and Foxglove ([`cell_views`]);
//! - [`logging`], [`shutdown`]: `tracing` set-up and clean SIGINT/SIGTERM handling;
//! - [`run_node`]: the `main` of every node binary.

pub mod action;
pub mod args;
pub mod clock;
pub mod data_files;
pub mod fastpath;
pub mod goal_server;
pub mod graph;
pub mod logging;
pub mod node;
pub mod params;
pub mod peers;
pub mod pubsub;
pub mod qos;
pub mod rerun_sink;
pub mod rosout;
pub mod security;
pub mod service;
pub mod shutdown;
pub mod standard_params;
pub mod type_hash;
pub mod views;

use std::{future::Future, process::ExitCode};

pub use node::{CellNode, FastPathMode, Network, NodeSetup};
pub use pubsub::{Publisher, Received, Subscriber, Via};
pub use qos::QosPreset;
pub use rerun_sink::{MachineStatusLogger, RerunSink, RerunTarget};
pub use service::{ServiceClient, ServiceServer};
pub use shutdown::Shutdown;

/// Exit status for a bad command line, parameter or launch file (as `sysexits`' EX_USAGE).
pub const EXIT_USAGE: u8 = 64;

/// Exit status for input data that cannot be used, e.g. a toolpath file the emitter refuses
/// (as `sysexits`' EX_DATAERR).
pub const EXIT_DATA: u8 = 65;

/// How long a node's exit waits for blocking work still running once its async tasks are gone.
const BLOCKING_WORK_GRACE: std::time::Duration = std::time::Duration::from_secs(1);

/// A node parameter value the node's body finds unusable after parsing (e.g. a machine profile
/// name that does not resolve). [`run_node`] exits with [`EXIT_USAGE`] when the body's error is
/// one. (Reading the parameters themselves fails with [`params::ParamsError`].)
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct NodeParamError(pub String);

/// Input data a node's body cannot use (e.g. a bag that is truncated or corrupt). [`run_node`]
/// exits with [`EXIT_DATA`] when the body's error is one.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct DataError(pub String);

/// Runs a node binary: logging, command line (`argv` excludes the program name), node set-up
/// with OS-signal shutdown, parameters validated into `P`, then `body`. Any error is printed
/// once, as one line, and becomes a non-zero exit; set-up errors (arguments, parameters, the
/// environment) and a [`NodeParamError`] from `body` exit with [`EXIT_USAGE`], a [`DataError`] from
/// `body` with [`EXIT_DATA`].
pub fn run_node<P, F, Fut>(default_name: &str, argv: Vec<String>, body: F) -> ExitCode
where
    P: serde::Serialize + serde::de::DeserializeOwned,
    F: FnOnce(CellNode, P) -> Fut,
    Fut: Future<Output = anyhow::Result<()>>,
{
    let parsed = args::NodeArgs::parse(argv.clone());
    logging::init(
        parsed
            .as_ref()
            .ok()
            .and_then(|a| a.ros.log_level.as_deref()),
    );
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("error: {default_name}: cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut participant = None;
    let code = runtime.block_on(async {
        let node = NodeSetup::from_args(default_name, argv).and_then(|mut setup| {
            setup.shutdown = Shutdown::new().with_os_signals();
            CellNode::with_params::<P>(setup)
        });
        let (node, params) = match node {
            Ok(pair) => pair,
            Err(e) => {
                eprintln!("error: {default_name}: {e:#}");
                return ExitCode::from(EXIT_USAGE);
            }
        };
        let sink = node.rerun().clone();
        participant = Some(node.participant_guard());
        let result = body(node, params).await;
        sink.flush();
        match result {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {default_name}: {e:#}");
                if e.downcast_ref::<NodeParamError>().is_some() {
                    ExitCode::from(EXIT_USAGE)
                } else if e.downcast_ref::<DataError>().is_some() {
                    ExitCode::from(EXIT_DATA)
                } else {
                    ExitCode::FAILURE
                }
            }
        }
    });
    // The runtime drops the graph spinner; only then may the DDS participant go. A blocking
    // computation still running (a goal that ignored its cancel) is left behind after a
    // moment rather than holding the process past its launcher's patience.
    runtime.shutdown_timeout(BLOCKING_WORK_GRACE);
    drop(participant);
    code
}
