//! `cell machine status|hold|resume|abort|override|arm|disarm|armed`: the operator's view of
//! a running `machine_bridge` node over DDS, so stopping a machine needs no ROS 2 command line.
//!
//! - `arm`, `disarm` and `armed` are local acts, not DDS: they speak to the bridge on this host
//!   over its arm socket (`cell_bridge::arming`), found from `ROS_DOMAIN_ID` and the bridge's
//!   name and namespace (`--ros-args -r __ns:=/cell`), or `--socket`. Runs, resume and overrides
//!   need the bridge armed; hold and abort never do.
//! - `hold`, `resume`, `abort` and `override` call the bridge's `machine_command` service
//!   (`cell_msgs/srv/SendMachineCommand`) for one controller (`--machine ID`) or every one, and
//!   print what the bridge answered.
//! - `status` prints each controller's latest `MachineStatus` from the bridge's
//!   `machine_status` topic once, or every change with `--follow` until Ctrl-C.
//!
//! The bridge is reached like any node reaches it: `ROS_DOMAIN_ID`, `--dds-network` (default
//! `CELL_DDS_NETWORK`, else `ROS_LOCALHOST_ONLY`, else all interfaces) and, last on the line,
//! `--ros-args -r __ns:=/cell` for a bridge in a namespace or `-r machine_command:=…` for
//! remapped names (parsed by [`cell_runtime::NodeSetup::from_args`]).
//!
//! Exit status: 0 done; 1 the bridge refused (unknown controller, not connected, an override
//! out of range) or has no such controller; 64 a bad command line; 69 no bridge found, or no
//! answer, within `--timeout`.

use std::collections::BTreeMap;
use std::process::ExitCode;
use std::time::Duration;

use cell_msgs::{
    MachineCommand, MachineStatus, SendMachineCommandRequest, SendMachineCommandResponse,
};
use cell_runtime::{CellNode, FastPathMode, NodeSetup, QosPreset, Shutdown, Subscriber};
use clap::{Args, Subcommand};
use tokio::time::{timeout_at, Instant};

use crate::exit;

/// Exit status when no bridge is found or none answers in time (as `sysexits`' EX_UNAVAILABLE).
pub const EXIT_NO_BRIDGE: u8 = 69;

/// How long `status` keeps listening after the first status: a bridge publishes every
/// controller at least 5 times a second, so every one of them is heard within this.
const STATUS_SWEEP: Duration = Duration::from_millis(500);

/// `cell machine` subcommands.
#[derive(Subcommand, Debug)]
pub enum MachineAction {
    /// Print each controller's latest status (state, job, acknowledged line of total, position
    /// per axis, feed, buffer fill, alarm text) from the bridge's machine_status topic.
    Status {
        /// Keep printing every change until Ctrl-C (ends with exit 69 when the bridge falls
        /// silent for --timeout).
        #[arg(long)]
        follow: bool,
        #[command(flatten)]
        bridge: BridgeArgs,
    },
    /// Feed hold: the machine decelerates to a stop and waits (resume continues).
    Hold(BridgeArgs),
    /// Cycle start: continue after a hold.
    Resume(BridgeArgs),
    /// Abort the running program with a safe stop (hold, reset, heat off); the goal ends
    /// aborted. Without --machine: every controller of the bridge (an e-stop for the cell).
    Abort(BridgeArgs),
    /// Feed or heat (spindle, laser, wire, torch) override in percent, 10..200.
    Override {
        #[command(flatten)]
        percent: OverrideArgs,
        #[command(flatten)]
        bridge: BridgeArgs,
    },
    /// Arm the bridge on this host (a local act over its Unix socket, not DDS): it takes runs,
    /// resume and overrides from its allowed peers until disarmed, or until --idle seconds
    /// (default and cap: its arm_idle_timeout_s) pass without machine activity.
    Arm {
        /// Idle time of this arming (s).
        #[arg(long = "idle", value_name = "SECONDS")]
        seconds: Option<f64>,
        #[command(flatten)]
        local: LocalBridgeArgs,
    },
    /// Disarm the bridge on this host: runs, resume and overrides are refused (hold and abort
    /// still work).
    Disarm(LocalBridgeArgs),
    /// Print whether the bridge on this host is armed, and for how long.
    Armed(LocalBridgeArgs),
}

/// The bridge on this host, reached over its arm socket.
#[derive(Args, Debug)]
pub struct LocalBridgeArgs {
    /// The bridge's arm socket (its `arm_socket` parameter); default: the one a bridge of this
    /// name and namespace on ROS_DOMAIN_ID uses.
    #[arg(long, value_name = "PATH")]
    pub socket: Option<std::path::PathBuf>,
    /// Seconds to wait for the bridge's answer.
    #[arg(long, value_name = "S", default_value_t = 5.0)]
    pub timeout: f64,
    /// Last on the line: ROS arguments naming the bridge, e.g. `--ros-args -r __ns:=/cell`.
    #[arg(
        value_name = "--ros-args …",
        trailing_var_arg = true,
        allow_hyphen_values = true
    )]
    pub ros_args: Vec<String>,
}

/// Which override, and how much.
#[derive(Args, Debug)]
#[group(required = true, multiple = false)]
pub struct OverrideArgs {
    /// Feed override (%).
    #[arg(long, value_name = "PCT")]
    pub feed: Option<u16>,
    /// Heat (spindle) override (%).
    #[arg(long, value_name = "PCT")]
    pub spindle: Option<u16>,
}

/// Which bridge and controller, and how long to wait for them.
#[derive(Args, Debug)]
pub struct BridgeArgs {
    /// Controller id (the `id` of its controller file); default: every controller of the
    /// bridge.
    #[arg(long, value_name = "ID")]
    pub machine: Option<String>,
    /// Seconds to wait for the bridge to be found, and then for its answer.
    #[arg(long, value_name = "S", default_value_t = 5.0)]
    pub timeout: f64,
    /// DDS interfaces: all, loopback or ADDR[,ADDR…] (default: CELL_DDS_NETWORK, else by
    /// ROS_LOCALHOST_ONLY, else all). The domain is ROS_DOMAIN_ID's.
    #[arg(long, value_name = "NETWORK")]
    pub dds_network: Option<String>,
    /// Last on the line: ROS arguments to reach a bridge in a namespace or with remapped
    /// names, e.g. `--ros-args -r __ns:=/cell`.
    #[arg(
        value_name = "--ros-args …",
        trailing_var_arg = true,
        allow_hyphen_values = true
    )]
    pub ros_args: Vec<String>,
}

impl MachineAction {
    /// The DDS bridge arguments; `None` for the local arming actions.
    fn bridge(&self) -> Option<&BridgeArgs> {
        match self {
            MachineAction::Status { bridge, .. }
            | MachineAction::Hold(bridge)
            | MachineAction::Resume(bridge)
            | MachineAction::Abort(bridge)
            | MachineAction::Override { bridge, .. } => Some(bridge),
            MachineAction::Arm { .. } | MachineAction::Disarm(_) | MachineAction::Armed(_) => None,
        }
    }

    /// The service command and its value; `None` for `status`.
    fn command(&self) -> Option<(u8, u16)> {
        match self {
            MachineAction::Status { .. }
            | MachineAction::Arm { .. }
            | MachineAction::Disarm(_)
            | MachineAction::Armed(_) => None,
            MachineAction::Hold(_) => Some((MachineCommand::COMMAND_HOLD, 0)),
            MachineAction::Resume(_) => Some((MachineCommand::COMMAND_RESUME, 0)),
            MachineAction::Abort(_) => Some((MachineCommand::COMMAND_ABORT, 0)),
            MachineAction::Override { percent, .. } => {
                Some(match (percent.feed, percent.spindle) {
                    (Some(feed), _) => (MachineCommand::COMMAND_FEED_OVERRIDE, feed),
                    (None, spindle) => (
                        MachineCommand::COMMAND_SPINDLE_OVERRIDE,
                        spindle.unwrap_or_default(),
                    ),
                })
            }
        }
    }
}

/// Runs `cell machine`.
pub fn run(action: MachineAction) -> ExitCode {
    cell_runtime::logging::init(Some("warn"));
    let bridge = match (&action, action.bridge()) {
        (MachineAction::Arm { seconds, local }, _) => {
            return match seconds {
                Some(s) if !(s.is_finite() && *s > 0.0) => exit::usage("--idle must be > 0"),
                Some(s) => arm(local, &format!("arm {s}")),
                None => arm(local, "arm"),
            }
        }
        (MachineAction::Disarm(local), _) => return arm(local, "disarm"),
        (MachineAction::Armed(local), _) => return arm(local, "state"),
        (_, Some(bridge)) => bridge,
        (_, None) => unreachable!("only the arming actions have no DDS bridge"),
    };
    if !(bridge.timeout.is_finite() && bridge.timeout > 0.0) {
        return exit::usage("--timeout must be > 0");
    }
    if bridge.ros_args.first().is_some_and(|a| a != "--ros-args") {
        return exit::usage(format!(
            "unexpected argument {:?} (ROS arguments go last, after --ros-args)",
            bridge.ros_args[0]
        ));
    }
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => return exit::failure(format!("cannot start the async runtime: {e}")),
    };
    let mut participant = None;
    let code = runtime.block_on(async {
        let listen = matches!(action, MachineAction::Status { .. });
        let node = match operator_node(bridge, listen) {
            Ok(node) => node,
            Err(e) => return exit::usage(format!("{e:#}")),
        };
        participant = Some(node.participant_guard());
        let timeout = Duration::from_secs_f64(bridge.timeout);
        let machine = bridge.machine.as_deref().unwrap_or_default();
        match (&action, action.command()) {
            (MachineAction::Status { follow, .. }, _) => {
                status(&node, machine, timeout, *follow).await
            }
            (_, Some((command, value))) => {
                let command = MachineCommand {
                    machine_id: machine.into(),
                    command,
                    value,
                };
                send(&node, command, timeout).await
            }
            (_, None) => unreachable!("every action but status is a command"),
        }
    });
    // The runtime drops the graph spinner; only then may the DDS participant go.
    drop(runtime);
    drop(participant);
    code
}

/// Sends one request to the arm socket of the bridge on this host and prints its answer.
fn arm(local: &LocalBridgeArgs, request: &str) -> ExitCode {
    if !(local.timeout.is_finite() && local.timeout > 0.0) {
        return exit::usage("--timeout must be > 0");
    }
    if local.ros_args.first().is_some_and(|a| a != "--ros-args") {
        return exit::usage(format!(
            "unexpected argument {:?} (ROS arguments go last, after --ros-args)",
            local.ros_args[0]
        ));
    }
    let path = match &local.socket {
        Some(path) => path.clone(),
        None => match NodeSetup::from_args("machine_bridge", local.ros_args.clone()) {
            Ok(setup) => {
                let ros = &setup.args.ros;
                let name = ros.node_name.as_deref().unwrap_or("machine_bridge");
                let namespace = ros.namespace.as_deref().unwrap_or("/");
                let node = cell_runtime::params::fully_qualified(namespace, name);
                cell_bridge::arming::default_socket_path(setup.domain_id, &node)
            }
            Err(e) => return exit::usage(format!("{e:#}")),
        },
    };
    let runtime = match tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => return exit::failure(format!("cannot start the async runtime: {e}")),
    };
    let timeout = Duration::from_secs_f64(local.timeout);
    match runtime.block_on(cell_bridge::arming::request(&path, request, timeout)) {
        Ok(answer) if answer.starts_with("error") => exit::failure(answer),
        Ok(answer) => {
            println!("{answer}");
            ExitCode::SUCCESS
        }
        Err(e) => no_bridge(format!(
            "{e:#}: is a machine_bridge running on this host, as this user, with this name, \
             namespace (--ros-args -r __ns:=…) and ROS_DOMAIN_ID (or pass --socket)?"
        )),
    }
}

/// The `cell_machine` node: the bridge's domain, network, namespace and remappings; no fast
/// path (status and commands are small), no Rerun. With `listen`, Ctrl-C ends the wait for
/// statuses quietly; otherwise it ends the process as usual.
fn operator_node(bridge: &BridgeArgs, listen: bool) -> anyhow::Result<CellNode> {
    let mut argv: Vec<String> = Vec::new();
    if let Some(network) = &bridge.dds_network {
        argv.extend(["--dds-network".into(), network.clone()]);
    }
    argv.extend(bridge.ros_args.iter().cloned());
    let mut setup = NodeSetup::from_args("cell_machine", argv)?;
    setup.fast_path = FastPathMode::Off;
    if listen {
        setup.shutdown = Shutdown::new().with_os_signals();
    }
    CellNode::new(setup)
}

/// Where the bridge was looked for, for error messages: `/cell/machine_command on
/// ROS_DOMAIN_ID=7`.
fn place(node: &CellNode, name: &str) -> String {
    format!("{name} on ROS_DOMAIN_ID={}", node.domain_id())
}

/// Calls the bridge's command service and prints its answer.
async fn send(node: &CellNode, command: MachineCommand, timeout: Duration) -> ExitCode {
    let service = machine_bridge::COMMAND_SERVICE;
    let client = match node
        .service_client::<SendMachineCommandRequest, SendMachineCommandResponse>(service)
    {
        Ok(c) => c,
        Err(e) => return exit::usage(format!("{e:#}")),
    };
    let at = place(node, client.name());
    if !node.wait_for_service(service, timeout).await {
        return no_bridge(format!(
            "no machine_bridge serves {at} (waited {:.1} s): is it running, in this namespace \
             (--ros-args -r __ns:=…) and domain?",
            timeout.as_secs_f64()
        ));
    }
    match client
        .call(SendMachineCommandRequest { command }, timeout)
        .await
    {
        Ok(answer) if answer.success => {
            println!("{}", answer.message);
            ExitCode::SUCCESS
        }
        Ok(answer) => exit::failure(answer.message),
        Err(e) => no_bridge(format!(
            "{at}: {e:#}; the command may still have been acted on (check with `cell machine \
             status`)"
        )),
    }
}

fn no_bridge(message: String) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(EXIT_NO_BRIDGE)
}

/// Prints the controllers' statuses once (every controller heard within [`STATUS_SWEEP`] of
/// the first, or only `machine`), or every change until Ctrl-C with `follow`.
async fn status(node: &CellNode, machine: &str, timeout: Duration, follow: bool) -> ExitCode {
    let topic = machine_bridge::BridgeParams::default().status_topic;
    let mut sub = match node.subscriber::<MachineStatus>(&topic, QosPreset::Status) {
        Ok(s) => s,
        Err(e) => return exit::usage(format!("{e:#}")),
    };
    let at = place(node, sub.topic());
    let wanted =
        |s: &MachineStatus| machine.is_empty() || s.machine_id.eq_ignore_ascii_case(machine);
    // Every controller heard, by id: which exist, if `machine` is not among them.
    let mut heard: BTreeMap<String, MachineStatus> = BTreeMap::new();
    let deadline = Instant::now() + timeout;
    let mut sweep_end: Option<Instant> = None;
    loop {
        let until = sweep_end.unwrap_or(deadline);
        match timeout_at(until, next(&mut sub, node)).await {
            Ok(Some(s)) => {
                if wanted(&s) && sweep_end.is_none() {
                    sweep_end = Some(Instant::now() + STATUS_SWEEP);
                }
                heard.insert(s.machine_id.clone(), s);
            }
            Ok(None) => return ExitCode::SUCCESS,
            Err(_) => break,
        }
    }
    if sweep_end.is_none() {
        if heard.is_empty() {
            return no_bridge(format!(
                "no MachineStatus on {at} within {:.1} s: is a machine_bridge running, in this \
                 namespace (--ros-args -r __ns:=…) and domain?",
                timeout.as_secs_f64()
            ));
        }
        return exit::failure(format!(
            "machine status: no controller {machine:?} on {at} (the bridge has: {})",
            heard.keys().cloned().collect::<Vec<_>>().join(", ")
        ));
    }
    let mut printed: BTreeMap<String, MachineStatus> = BTreeMap::new();
    for s in heard.into_values().filter(|s| wanted(s)) {
        println!("{}", describe(&s));
        printed.insert(s.machine_id.clone(), s);
    }
    if !follow {
        return ExitCode::SUCCESS;
    }
    loop {
        match tokio::time::timeout(timeout, next(&mut sub, node)).await {
            Ok(Some(s)) if wanted(&s) => {
                let changed = printed
                    .get(&s.machine_id)
                    .is_none_or(|last| !same_but_stamp(last, &s));
                if changed {
                    println!("{}", describe(&s));
                    printed.insert(s.machine_id.clone(), s);
                }
            }
            Ok(Some(_)) => {}
            Ok(None) => return ExitCode::SUCCESS,
            Err(_) => {
                return no_bridge(format!(
                    "no MachineStatus on {at} for {:.1} s: the bridge stopped?",
                    timeout.as_secs_f64()
                ))
            }
        }
    }
}

/// The next status, or `None` on Ctrl-C (or when the subscription ends).
async fn next(sub: &mut Subscriber<MachineStatus>, node: &CellNode) -> Option<MachineStatus> {
    tokio::select! {
        r = sub.recv() => r.map(|r| r.message),
        _ = node.shutdown().requested() => None,
    }
}

/// Whether two statuses differ only in their header (time stamp).
fn same_but_stamp(a: &MachineStatus, b: &MachineStatus) -> bool {
    let mut a = a.clone();
    a.header = b.header.clone();
    &a == b
}

/// A state's name as the status line shows it.
pub fn state_name(state: u8) -> &'static str {
    match state {
        MachineStatus::STATE_DISCONNECTED => "DISCONNECTED",
        MachineStatus::STATE_IDLE => "IDLE",
        MachineStatus::STATE_RUNNING => "RUNNING",
        MachineStatus::STATE_HOLD => "HOLD",
        MachineStatus::STATE_ALARM => "ALARM",
        MachineStatus::STATE_DONE => "DONE",
        _ => "UNKNOWN",
    }
}

/// One status as one line: `cutter  RUNNING  job wing  line 120/603  X=12.300 Y=45.000  feed
/// 4.0 mm/s  buffer 45%`, then `alarm: …` when there is one.
pub fn describe(s: &MachineStatus) -> String {
    let mut fields = vec![s.machine_id.clone(), state_name(s.state).to_string()];
    if !s.job_id.is_empty() {
        fields.push(format!("job {}", s.job_id));
    }
    fields.push(format!("line {}/{}", s.acked_line, s.total_lines));
    if !s.axis_names.is_empty() {
        let axes: Vec<String> = s
            .axis_names
            .iter()
            .zip(&s.axis_positions)
            .map(|(name, at)| format!("{name}={at:.3}"))
            .collect();
        fields.push(axes.join(" "));
    }
    fields.push(format!("feed {:.1} mm/s", s.feed_mm_s));
    fields.push(format!("buffer {:.0}%", s.buffer_fill * 100.0));
    if !s.alarm.is_empty() {
        fields.push(format!("alarm: {}", s.alarm));
    }
    fields.join("  ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_status_line_names_the_controller_state_line_axes_and_alarm() {
        let s = MachineStatus {
            machine_id: "cutter".into(),
            state: MachineStatus::STATE_ALARM,
            job_id: "wing".into(),
            acked_line: 12,
            total_lines: 300,
            axis_names: vec!["X".into(), "U".into()],
            axis_positions: vec![1.5, -2.25],
            feed_mm_s: 4.0,
            buffer_fill: 0.5,
            alarm: "ALARM:1 hard limit".into(),
            ..MachineStatus::default()
        };
        assert_eq!(
            describe(&s),
            "cutter  ALARM  job wing  line 12/300  X=1.500 U=-2.250  feed 4.0 mm/s  buffer 50%  \
             alarm: ALARM:1 hard limit"
        );
        assert_eq!(state_name(200), "UNKNOWN");
    }
}
