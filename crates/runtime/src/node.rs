//! [`CellNode`]: one ROS 2 node with its own DDS participant, fast path, Rerun sink and
//! shutdown signal. Every cellsuite node is built on one.

use std::{
    net::{IpAddr, Ipv4Addr},
    sync::{Arc, Mutex},
};

use anyhow::{anyhow, bail, Context as _};
use cell_msgs::builtin_interfaces::Time;
use ros2_client::{dds::rustdds::DomainParticipantBuilder, qos::QosProfile, Context, NodeName};
use serde::de::DeserializeOwned;

use crate::{
    args::{resolve_topic, NodeArgs},
    clock::{follow_clock, SimulatedTime},
    fastpath::FastPath,
    params::ParamSources,
    rerun_sink::{RerunSink, RerunTarget},
    shutdown::Shutdown,
    standard_params::{Endpoint, StandardParams},
};

/// Which network interfaces DDS may use.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum Network {
    /// Every interface (the DDS default): nodes on other hosts can join.
    #[default]
    All,
    /// Loopback only: discovery and data never leave the machine. Tests always use this.
    Loopback,
    /// Only the interfaces with these addresses (e.g. the cell's machine network).
    Only(Vec<IpAddr>),
}

impl std::str::FromStr for Network {
    type Err = anyhow::Error;

    /// `all`, `loopback` (or `lo`), or a comma-separated list of interface addresses.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "all" => Ok(Network::All),
            "loopback" | "lo" | "localhost" => Ok(Network::Loopback),
            list => list
                .split(',')
                .map(|a| a.trim().parse::<IpAddr>())
                .collect::<Result<Vec<_>, _>>()
                .map(Network::Only)
                .map_err(|_| anyhow!("DDS network {s:?}: expected all, loopback or interface addresses like 10.0.0.2,10.0.1.2")),
        }
    }
}

impl Network {
    /// What the environment asks for: `CELL_DDS_NETWORK`, else ROS 2's `ROS_LOCALHOST_ONLY=1` /
    /// `ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`, else all interfaces.
    pub fn from_env() -> anyhow::Result<Self> {
        if let Ok(v) = std::env::var("CELL_DDS_NETWORK") {
            return v.parse().context("CELL_DDS_NETWORK");
        }
        let localhost_only = std::env::var("ROS_LOCALHOST_ONLY").is_ok_and(|v| v == "1")
            || std::env::var("ROS_AUTOMATIC_DISCOVERY_RANGE").is_ok_and(|v| v == "LOCALHOST");
        Ok(if localhost_only {
            Network::Loopback
        } else {
            Network::All
        })
    }
}

/// Whether large-message topics may use iceoryx2 shared memory.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum FastPathMode {
    /// Use shared memory when `/dev/shm` works; fall back to DDS otherwise.
    #[default]
    Auto,
    /// DDS only.
    Off,
}

/// The highest domain id whose RTPS ports fit in 16 bits (7400 + 250·id + offsets).
pub const MAX_DOMAIN_ID: u16 = 232;

/// The ROS domain from `ROS_DOMAIN_ID` (0 when unset). ros2-client ignores the variable, so the
/// runtime reads it for every node.
pub fn domain_id_from_env() -> anyhow::Result<u16> {
    match std::env::var("ROS_DOMAIN_ID") {
        Err(_) => Ok(0),
        Ok(v) if v.trim().is_empty() => Ok(0),
        Ok(v) => match v.trim().parse::<u16>() {
            Ok(id) if id <= MAX_DOMAIN_ID => Ok(id),
            _ => bail!("ROS_DOMAIN_ID={v:?}: expected an integer from 0 to {MAX_DOMAIN_ID}"),
        },
    }
}

/// Everything needed to bring a node up. [`NodeSetup::from_args`] fills it from a command line
/// and the environment; tests build it directly.
#[derive(Debug, Clone)]
pub struct NodeSetup {
    /// Node name unless `-r __node:=` overrides it.
    pub default_name: String,
    /// The parsed command line.
    pub args: NodeArgs,
    /// DDS domain.
    pub domain_id: u16,
    /// Interfaces DDS may use.
    pub network: Network,
    /// Shared-memory fast path for large messages.
    pub fast_path: FastPathMode,
    /// Rerun output.
    pub rerun: RerunTarget,
    /// Ties the Rerun recordings of one cell run together.
    pub run_id: String,
    /// Shutdown signal; OS signals are added by [`crate::run_node`], not here.
    pub shutdown: Shutdown,
}

impl NodeSetup {
    /// A setup for in-process use (tests, tools): loopback-only DDS, no Rerun, no arguments.
    pub fn local(name: &str, domain_id: u16) -> Self {
        Self {
            default_name: name.to_string(),
            args: NodeArgs::default(),
            domain_id,
            network: Network::Loopback,
            fast_path: FastPathMode::Auto,
            rerun: RerunTarget::Off,
            run_id: default_run_id(),
            shutdown: Shutdown::new(),
        }
    }

    /// Reads the command line (program name excluded) and the environment. The runtime's own
    /// flags precede `--ros-args`: `--rerun off|save:PATH|connect:ADDR`,
    /// `--dds-network all|loopback|ADDR,…`, `--fast-path auto|off`.
    pub fn from_args<I, S>(default_name: &str, argv: I) -> anyhow::Result<Self>
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        let args = NodeArgs::parse(argv)?;
        let mut setup = Self::local(default_name, domain_id_from_env()?);
        setup.network = Network::from_env()?;
        if let Ok(id) = std::env::var("CELL_RUN_ID") {
            setup.run_id = id;
        }
        let mut user = args.user.iter();
        while let Some(flag) = user.next() {
            let mut value = || user.next().ok_or_else(|| anyhow!("{flag} needs a value"));
            match flag.as_str() {
                "--rerun" => setup.rerun = value()?.parse()?,
                "--dds-network" => setup.network = value()?.parse()?,
                "--fast-path" => {
                    setup.fast_path = match value()?.as_str() {
                        "auto" => FastPathMode::Auto,
                        "off" => FastPathMode::Off,
                        other => bail!("--fast-path {other:?}: expected auto or off"),
                    }
                }
                other => bail!(
                    "unknown argument {other:?} (node flags: --rerun, --dds-network, --fast-path; ROS flags go after --ros-args)"
                ),
            }
        }
        setup.args = args;
        Ok(setup)
    }
}

fn default_run_id() -> String {
    format!(
        "cell-{}-{}",
        std::process::id(),
        crate::fastpath::now_ns() / 1_000_000
    )
}

/// The node's parameter sources for its name and namespace, with the ROS-standard keys taken
/// out ([`StandardParams::take`]).
fn collect_params(setup: &NodeSetup) -> anyhow::Result<(ParamSources, StandardParams)> {
    let ros = &setup.args.ros;
    let name = ros.node_name.as_deref().unwrap_or(&setup.default_name);
    let namespace = ros.namespace.as_deref().unwrap_or("/");
    let mut sources = ParamSources::collect(ros, namespace, name)?;
    let standard = StandardParams::take(&mut sources)?;
    Ok((sources, standard))
}

struct NodeInner {
    name: String,
    namespace: String,
    domain_id: u16,
    remaps: Vec<(String, String)>,
    params: ParamSources,
    standard: StandardParams,
    ros_node: Mutex<ros2_client::Node>,
    _context: Context,
    fast_path: Option<FastPath>,
    rerun: RerunSink,
    shutdown: Shutdown,
    sim_time: std::sync::OnceLock<SimulatedTime>,
}

/// A running ROS 2 node: DDS participant, names and remappings, parameters, fast path, Rerun
/// sink and shutdown signal. Cheap to clone; the node lives while any clone does.
#[derive(Clone)]
pub struct CellNode {
    inner: Arc<NodeInner>,
}

impl std::fmt::Debug for CellNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CellNode")
            .field("name", &self.fully_qualified_name())
            .field("domain_id", &self.inner.domain_id)
            .finish()
    }
}

impl CellNode {
    /// Brings the node up: one DDS participant of its own, the ROS graph spinner, the fast path
    /// (or the reason it is off) and the Rerun sink. Must run inside a tokio runtime.
    pub fn new(setup: NodeSetup) -> anyhow::Result<Self> {
        let (sources, standard) = collect_params(&setup)?;
        Self::build(setup, Vec::new(), sources, standard)
    }

    /// Like [`CellNode::new`], and also validates the parameters into `P` and declares their
    /// effective values (defaults included) on the ROS graph, so `ros2 param list/get` show
    /// them. They are read once, at start-up: a remote `ros2 param set` is refused with a reason.
    pub fn with_params<P>(setup: NodeSetup) -> anyhow::Result<(Self, P)>
    where
        P: serde::Serialize + DeserializeOwned,
    {
        let (sources, standard) = collect_params(&setup)?;
        let params: P = sources.parse()?;
        let effective = serde_norway::to_value(&params).context("parameters")?;
        let mut declared = Vec::new();
        crate::params::flatten_for_ros("", &effective, &mut declared);
        Ok((Self::build(setup, declared, sources, standard)?, params))
    }

    fn build(
        setup: NodeSetup,
        mut declared: Vec<(String, ros2_client::ParameterValue)>,
        params: ParamSources,
        standard: StandardParams,
    ) -> anyhow::Result<Self> {
        let ros = &setup.args.ros;
        let name = ros.node_name.clone().unwrap_or(setup.default_name.clone());
        let namespace = ros.namespace.clone().unwrap_or_else(|| "/".to_string());
        let node_name = NodeName::new(&namespace, &name)
            .map_err(|e| anyhow!("node name {namespace}/{name}: {e:?}"))?;
        // ROS 2 declares use_sim_time on every node.
        declared.push((
            "use_sim_time".into(),
            ros2_client::ParameterValue::Boolean(standard.use_sim_time),
        ));

        let mut participant = DomainParticipantBuilder::new(setup.domain_id);
        match &setup.network {
            Network::All => {}
            Network::Loopback => {
                participant = participant.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)])
            }
            Network::Only(addrs) => participant = participant.with_only_networks(addrs.clone()),
        }
        // SROS2: ROS_SECURITY_* and --enclave decide; a node asked to be secured never starts
        // unsecured without saying so (crate::security).
        let enclave =
            crate::security::SecurityEnv::from_env().enclave_dir(ros.enclave.as_deref())?;
        #[cfg(feature = "security")]
        if let Some(dir) = &enclave {
            use ros2_client::dds::rustdds::DomainParticipantSecurityConfigFiles as Files;
            // sros2 writes the private key unencrypted, so there is no password.
            participant =
                participant.builtin_security(Files::with_ros_default_names(dir, String::new()));
        }
        let participant = participant.build().with_context(|| match &enclave {
            Some(dir) => format!(
                "secured DDS participant on domain {} (enclave {})",
                setup.domain_id,
                dir.display()
            ),
            None => format!("DDS participant on domain {}", setup.domain_id),
        })?;
        // Every endpoint announces its REP-2011 type hash, as Jazzy peers expect.
        participant.set_endpoint_user_data(crate::type_hash::user_data);
        let context = Context::from_domain_participant(participant).context("ROS 2 context")?;
        let mut options = ros2_client::NodeOptions::new().enable_rosout(true);
        for (key, value) in declared {
            options = options.declare_parameter(&key, value);
        }
        // ros2-client validates the declarations too; refuse changes only once the node is up.
        let sealed = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let seal = sealed.clone();
        let options = options.parameter_validator(Box::new(move |key, _| {
            if !seal.load(std::sync::atomic::Ordering::Relaxed) {
                return Ok(());
            }
            Err(format!(
                "{key} is read at start-up: restart the node with -p {key}:=... or a params file"
            ))
        }));
        let mut ros_node = context
            .new_node(node_name, options)
            .map_err(|e| anyhow!("creating node {name}: {e:?}"))?;
        sealed.store(true, std::sync::atomic::Ordering::Relaxed);
        {
            use ros2_client::dds::RosoutRaw as _;
            crate::rosout::register(&namespace, &name, ros_node.rosout_writer());
        }
        let spinner = ros_node
            .spinner()
            .map_err(|e| anyhow!("node spinner: {e:?}"))?;
        tokio::spawn(async move {
            if let Err(e) = spinner.spin().await {
                tracing::warn!("ROS graph spinner stopped: {e:?}");
            }
        });

        let fast_path = match setup.fast_path {
            FastPathMode::Off => None,
            // Shared memory is neither authenticated nor encrypted: a secured node's data
            // stays on (secured) DDS.
            FastPathMode::Auto if enclave.is_some() => {
                tracing::info!("SROS2: fast path off, every message goes over secured DDS");
                None
            }
            FastPathMode::Auto => match FastPath::open(setup.domain_id) {
                Ok(fp) => Some(fp),
                Err(e) => {
                    tracing::warn!("fast path unavailable, large messages go over DDS: {e}");
                    None
                }
            },
        };
        let rerun = RerunSink::open(&setup.rerun, &name, &setup.run_id)?;
        tracing::debug!(
            "node {namespace}/{name} up on domain {} ({:?}, fast path {})",
            setup.domain_id,
            setup.network,
            if fast_path.is_some() { "on" } else { "off" }
        );
        let node = Self {
            inner: Arc::new(NodeInner {
                name,
                namespace,
                domain_id: setup.domain_id,
                remaps: ros.remaps.clone(),
                params,
                standard,
                ros_node: Mutex::new(ros_node),
                _context: context,
                fast_path,
                rerun,
                shutdown: setup.shutdown,
                sim_time: std::sync::OnceLock::new(),
            }),
        };
        if node.inner.standard.use_sim_time {
            let sim = follow_clock(&node).context("following /clock (use_sim_time)")?;
            let _ = node.inner.sim_time.set(sim);
        }
        Ok(node)
    }

    /// The node's current time: the system clock, or while its `use_sim_time` parameter is
    /// true (at start-up or set later) the last `/clock` message, zero before the first; see
    /// [`crate::clock`]. Stamp what the node publishes with this.
    pub fn now(&self) -> Time {
        let simulated = self.with_ros_node(|n| n.get_parameter("use_sim_time"))
            == Some(ros2_client::ParameterValue::Boolean(true));
        if !simulated {
            return Time::now();
        }
        if let Some(sim) = self.inner.sim_time.get() {
            return sim.now();
        }
        match follow_clock(self) {
            Ok(sim) => {
                tracing::info!("use_sim_time is now true: following /clock");
                let _ = self.inner.sim_time.set(sim);
                self.inner
                    .sim_time
                    .get()
                    .map_or_else(Time::now, SimulatedTime::now)
            }
            Err(e) => {
                tracing::warn!("use_sim_time is true but /clock cannot be followed: {e:#}");
                Time::now()
            }
        }
    }

    /// `profile` with the node's `qos_overrides` parameters for `topic` (fully qualified) and
    /// `endpoint` applied ([`StandardParams::qos`]).
    pub fn qos(&self, topic: &str, endpoint: Endpoint, profile: QosProfile) -> QosProfile {
        self.inner.standard.qos(topic, endpoint, profile)
    }

    /// The ROS-standard parameters the node was started with (`use_sim_time`, QoS
    /// overrides).
    pub fn standard_params(&self) -> &StandardParams {
        &self.inner.standard
    }

    /// The node's base name.
    pub fn name(&self) -> &str {
        &self.inner.name
    }

    /// `/namespace/name`.
    pub fn fully_qualified_name(&self) -> String {
        crate::params::fully_qualified(&self.inner.namespace, &self.inner.name)
    }

    /// The DDS domain the node is on.
    pub fn domain_id(&self) -> u16 {
        self.inner.domain_id
    }

    /// The node's parameters, validated into `P` (which should use
    /// `#[serde(deny_unknown_fields, default)]`). Errors name the file and key.
    pub fn params<P: DeserializeOwned>(&self) -> anyhow::Result<P> {
        Ok(self.inner.params.parse()?)
    }

    /// Resolves a topic name against the namespace and the `-r` remappings.
    pub fn resolve_topic(&self, name: &str) -> String {
        resolve_topic(
            name,
            &self.inner.namespace,
            &self.inner.name,
            &self.inner.remaps,
        )
    }

    /// The node's Rerun sink (disabled unless `--rerun` asked for one).
    pub fn rerun(&self) -> &RerunSink {
        &self.inner.rerun
    }

    /// The node's shutdown signal.
    pub fn shutdown(&self) -> &Shutdown {
        &self.inner.shutdown
    }

    /// Whether the shared-memory fast path is up.
    pub fn has_fast_path(&self) -> bool {
        self.inner.fast_path.is_some()
    }

    pub(crate) fn fast_path(&self) -> Option<&FastPath> {
        self.inner.fast_path.as_ref()
    }

    /// A handle that keeps the DDS participant alive. ros2-client's graph spinner drops its
    /// context before its own readers and writers, which then log errors as they find the
    /// participant gone; holding this until the tokio runtime has dropped the spinner avoids that.
    pub fn participant_guard(&self) -> ParticipantGuard {
        ParticipantGuard(self.inner._context.clone())
    }

    pub(crate) fn domain_participant(&self) -> ros2_client::dds::rustdds::DomainParticipant {
        self.inner._context.domain_participant()
    }

    pub(crate) fn with_ros_node<R>(&self, f: impl FnOnce(&mut ros2_client::Node) -> R) -> R {
        let mut guard = self
            .inner
            .ros_node
            .lock()
            .unwrap_or_else(|p| p.into_inner());
        f(&mut guard)
    }
}

/// Keeps a node's DDS participant alive while held; see [`CellNode::participant_guard`].
pub struct ParticipantGuard(#[allow(dead_code)] Context);
