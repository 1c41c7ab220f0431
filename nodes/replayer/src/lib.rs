//! The `replayer` node: republishes a rosbag2 MCAP bag ([`cell_bag::BagReader`]) over DDS with
//! its recorded timing, for `cell node replayer` and `cell bag play`.
//!
//! - **Timing**: each message goes out when its log-time gap to the first replayed message,
//!   divided by `rate`, has passed; `start_offset_s` skips the beginning of the bag; `loop`
//!   starts over at the end. Pausing (the `~/set_paused` service, `std_srvs/srv/SetBool`)
//!   freezes that clock and resuming continues from where it stood, without a burst. The
//!   arithmetic is in [`schedule`], which knows nothing of DDS.
//! - **Types and QoS**: every topic is published with its Rust type from
//!   [`cell_msgs::for_each_message!`] and the QoS the bag recorded for it (reliable +
//!   transient-local → [`QosPreset::Plan`], so a late joiner still gets the plans;
//!   best-effort → [`QosPreset::Stream`], heat maps over the iceoryx2 fast path on one host;
//!   reliable + volatile → [`QosPreset::Status`]; anything else → `Status`). A topic of a type
//!   this suite does not know is skipped with one warning.
//! - **Selection**: `topics`/`exclude` regexes (whole-name, as the recorder's) and `remap`
//!   (`from:=to`) pick and rename topics.
//! - **Safe by default**: topics of the [`MACHINE_TYPES`] (programs, machine commands, their
//!   service requests and action goals: what makes a `machine_bridge` move a machine) are left
//!   out, with one line naming them, unless an entry of `topics` names one exactly. When one is
//!   played, the replay first looks for a machine bridge on the domain (a reader of a machine
//!   type, or of the topics it would publish them on; [`BRIDGE_DISCOVERY`]) and refuses (exit
//!   64, naming what it found) unless `allow_machine_topics` (`--allow-machine-topics`).
//!
//! - **Clock**: with `clock_hz` > 0 (`cell bag play --clock [HZ]`) the node is a ROS time
//!   source, as `ros2 bag play --clock`: it publishes the bag's time (the recorded log time
//!   of the replay position, frozen while paused) as `rosgraph_msgs/msg/Clock` on `/clock`
//!   that many times a second while it plays, for nodes with `use_sim_time` true.
//!
//! A reader thread reads, filters and decodes ahead of the clock (within a memory budget), so
//! decompressing a chunk does not hold up a message that is due.

#![warn(missing_docs)]

pub mod schedule;

use std::any::Any;
use std::collections::{HashMap, HashSet};
use std::fmt;
use std::future::Future;
use std::path::PathBuf;
use std::pin::Pin;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use anyhow::anyhow;
use cell_bag::qos::{Durability, Reliability};
use cell_bag::BagReader;
use cell_msgs::builtin_interfaces::Time;
use cell_msgs::rosgraph_msgs::Clock;
use cell_msgs::std_srvs::{SetBoolRequest, SetBoolResponse};
use cell_msgs::{CdrError, RosMessage};
use cell_runtime::{CellNode, DataError, NodeParamError, Publisher, QosPreset, Shutdown};
use recorder::TopicFilter;
use schedule::{check_rate, ReplayClock, Timeline};
use serde::{Deserialize, Serialize};
use tokio::sync::{mpsc, oneshot};

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ReplayerParams {
    /// The bag to play: a bag directory or one `.mcap` file.
    pub bag: String,
    /// Speed factor (×N, > 0): 2 plays twice as fast.
    pub rate: f64,
    /// Start over at the end, until shutdown.
    pub r#loop: bool,
    /// Regular expressions for the topics to play (whole-name match).
    pub topics: Vec<String>,
    /// Regular expressions for topics never to play.
    pub exclude: Vec<String>,
    /// Renames, `"from:=to"` (bag topic to published topic).
    pub remap: Vec<String>,
    /// Skip the first this many seconds of the bag.
    pub start_offset_s: f64,
    /// Start paused (resume with the `~/set_paused` service).
    pub start_paused: bool,
    /// Before the first message, wait up to this long (s) for every played topic to have a
    /// subscriber; 0: start at once.
    pub wait_for_subscribers_s: f64,
    /// After the last message, keep the publishers up this long (s), so reliable readers get
    /// retransmissions and late joiners the transient-local plans.
    pub linger_s: f64,
    /// Log progress at most this often (s).
    pub progress_every_s: f64,
    /// Publish the bag's time on `/clock` this many times a second (0: not at all).
    pub clock_hz: f64,
    /// Play machine topics (named in `topics`) even onto a domain where a machine bridge runs.
    pub allow_machine_topics: bool,
}

impl Default for ReplayerParams {
    fn default() -> Self {
        ReplayerParams {
            bag: String::new(),
            rate: 1.0,
            r#loop: false,
            topics: vec![".*".into()],
            exclude: vec!["/rosout".into(), "/parameter_events".into()],
            remap: Vec::new(),
            start_offset_s: 0.0,
            start_paused: false,
            wait_for_subscribers_s: 1.0,
            linger_s: 1.0,
            progress_every_s: 5.0,
            clock_hz: 0.0,
            allow_machine_topics: false,
        }
    }
}

/// Types whose messages make a machine move: `machine_bridge` runs every `MachineProgram` on
/// its program topic and acts on `MachineCommand`s (topic and service) and `execute_program`
/// goals at once. A replay leaves their topics out unless one is named (module docs).
pub const MACHINE_TYPES: [&str; 5] = [
    "cell_msgs/msg/MachineProgram",
    "cell_msgs/msg/MachineCommand",
    "cell_msgs/srv/SendMachineCommand_Request",
    "cell_msgs/action/ExecuteProgram_Goal",
    "cell_msgs/action/ExecuteProgram_SendGoal_Request",
];

/// Whether `ros_type` is one of the [`MACHINE_TYPES`].
pub fn is_machine_type(ros_type: &str) -> bool {
    MACHINE_TYPES.contains(&ros_type)
}

/// Whether an entry of `topics` is `topic`'s name itself, rather than a pattern matching it.
fn named(topics: &[String], topic: &str) -> bool {
    topics.iter().any(|t| t == topic)
}

/// How long a replay of machine topics looks for a machine bridge on the domain before it
/// starts (discovery on one host takes well under a second; across hosts, a few).
pub const BRIDGE_DISCOVERY: Duration = Duration::from_secs(3);

/// Topic renames from `remap` entries, `"from:=to"`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Remaps(Vec<(String, String)>);

impl Remaps {
    /// Parses the entries; a relative `from` means the absolute name (`a` is `/a`), as bag
    /// topics are absolute.
    ///
    /// # Errors
    /// An entry without `:=`, or with an empty or blank side, named with its index.
    pub fn parse(entries: &[String]) -> Result<Self, NodeParamError> {
        entries
            .iter()
            .enumerate()
            .map(|(i, entry)| {
                let bad = || {
                    NodeParamError(format!(
                        "remap[{i}]: {entry:?}: expected FROM:=TO (e.g. /cell/toolpath:=/replay/toolpath)"
                    ))
                };
                let (from, to) = entry.split_once(":=").ok_or_else(bad)?;
                let blank = |s: &str| s.is_empty() || s.chars().any(char::is_whitespace);
                if blank(from) || blank(to) {
                    return Err(bad());
                }
                let from = if from.starts_with('/') {
                    from.to_owned()
                } else {
                    format!("/{from}")
                };
                Ok((from, to.to_owned()))
            })
            .collect::<Result<_, _>>()
            .map(Remaps)
    }

    /// The published name of bag topic `topic`, and which entry renamed it.
    pub fn apply<'a>(&'a self, topic: &'a str) -> (&'a str, Option<usize>) {
        match self.0.iter().position(|(from, _)| from == topic) {
            Some(i) => (&self.0[i].1, Some(i)),
            None => (topic, None),
        }
    }

    /// The `from` of every entry that renames none of `topics`.
    pub fn unused<'a>(&'a self, topics: &[&str]) -> Vec<&'a str> {
        self.0
            .iter()
            .filter(|(from, _)| !topics.contains(&from.as_str()))
            .map(|(from, _)| from.as_str())
            .collect()
    }
}

/// The preset to publish with, from a topic's stored `offered_qos_profiles` (see
/// [`cell_bag::qos`]), and a note when it had to fall back to `Status`.
///
/// Like rosbag2's player with several recorded publishers: reliable only if every one was,
/// transient-local only if every one was. Reliable + transient-local is `Plan`, best-effort is
/// `Stream`, reliable + volatile is `Status`.
pub fn preset_for(offered_qos_profiles: &str) -> (QosPreset, Option<String>) {
    let list = match cell_bag::qos::from_yaml(offered_qos_profiles) {
        Ok(list) => list,
        Err(e) => {
            return (
                QosPreset::Status,
                Some(format!("unreadable recorded QoS ({e})")),
            )
        }
    };
    let known: Vec<_> = list.into_iter().flatten().collect();
    if known.is_empty() {
        return (QosPreset::Status, Some("no recorded QoS".into()));
    }
    let reliable = known.iter().all(|q| q.reliability == Reliability::Reliable);
    let transient = known
        .iter()
        .all(|q| q.durability == Durability::TransientLocal);
    let preset = match (reliable, transient) {
        (false, _) => QosPreset::Stream,
        (true, true) => QosPreset::Plan,
        (true, false) => QosPreset::Status,
    };
    (preset, None)
}

/// What happens to one topic of the bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicPlan {
    /// The topic in the bag.
    pub topic: String,
    /// The name it is published under (after `remap`; a relative name joins the node's
    /// namespace).
    pub output: String,
    /// Its ROS 2 type.
    pub ros_type: String,
    /// The QoS it is published with.
    pub qos: QosPreset,
    /// Its messages in the bag.
    pub messages: u64,
    /// Whether this suite knows the type (unknown ones are skipped).
    pub known: bool,
}

/// Where a replay stands; handed to the observer of [`Replay::run`] after every message and
/// on every pause or resume.
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// Messages published in this pass.
    pub published: u64,
    /// Messages a pass plays (those of the played topics after the start offset).
    pub total: u64,
    /// Messages published over all passes.
    pub all_published: u64,
    /// The pass, from 1 (more than one with `loop`).
    pub pass: u32,
    /// Bag time since the pass's first message.
    pub position: Duration,
    /// Whether the replay is paused.
    pub paused: bool,
    /// When the message just published was due (`None` for a pause or resume).
    pub scheduled_at: Option<std::time::Instant>,
}

/// How a replay went: [`Replay::run`]'s result, one line as `Display`.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplaySummary {
    /// Messages published (all passes).
    pub published: u64,
    /// Messages whose publishing failed (logged).
    pub failed: u64,
    /// Messages that could not be decoded as their type (logged once per topic).
    pub undecodable: u64,
    /// Messages skipped because this suite does not know their type.
    pub unknown_type: u64,
    /// Messages before the start offset (first pass).
    pub before_offset: u64,
    /// Machine topics left out (not named in `topics`) and their messages.
    pub machine_left_out: Vec<(String, u64)>,
    /// Passes started.
    pub passes: u32,
    /// Topics played.
    pub topics: usize,
    /// Wall time from the first message to the last.
    pub elapsed: Duration,
    /// Whether shutdown stopped it before the end.
    pub stopped: bool,
    /// The rate.
    pub rate: f64,
}

impl fmt::Display for ReplaySummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "replayed {} messages on {} topic{} in {:.1} s at ×{} ({} pass{}){}",
            self.published,
            self.topics,
            if self.topics == 1 { "" } else { "s" },
            self.elapsed.as_secs_f64(),
            self.rate,
            self.passes,
            if self.passes == 1 { "" } else { "es" },
            if self.stopped { ", stopped early" } else { "" },
        )?;
        for (n, what) in [
            (self.before_offset, "before the start offset"),
            (self.unknown_type, "of unknown types"),
            (self.undecodable, "undecodable"),
            (self.failed, "failed to publish"),
        ] {
            if n > 0 {
                write!(f, "; {n} {what}")?;
            }
        }
        if !self.machine_left_out.is_empty() {
            write!(
                f,
                "; left out machine topics {}",
                left_out(&self.machine_left_out)
            )?;
        }
        Ok(())
    }
}

/// `/a (3 messages), /b (1 message)`.
fn left_out(topics: &[(String, u64)]) -> String {
    let each: Vec<String> = topics
        .iter()
        .map(|(t, n)| format!("{t} ({n} message{})", if *n == 1 { "" } else { "s" }))
        .collect();
    each.join(", ")
}

/// A bag opened and checked for replay; [`Replay::run`] plays it.
pub struct Replay {
    path: PathBuf,
    reader: BagReader,
    plans: Vec<TopicPlan>,
    machine_left_out: Vec<(String, u64)>,
    allow_machine_topics: bool,
    bag_start_ns: u64,
    rate: f64,
    looping: bool,
    start_offset: Duration,
    start_paused: bool,
    wait_for_subscribers: Duration,
    linger: Duration,
    clock_period: Option<Duration>,
}

/// A non-negative, finite number of seconds.
fn seconds(v: f64, field: &str) -> Result<Duration, NodeParamError> {
    if v.is_finite() && v >= 0.0 {
        Ok(Duration::from_secs_f64(v))
    } else {
        Err(NodeParamError(format!(
            "{field}: {v}: expected seconds >= 0"
        )))
    }
}

impl Replay {
    /// Checks the parameters and opens the bag.
    ///
    /// # Errors
    /// [`NodeParamError`] (exit 64) for a bad parameter or a bag path that does not exist, named;
    /// [`DataError`] (exit 65) for a bag that cannot be read (unfinished, truncated, corrupt:
    /// the message names the file).
    pub fn open(p: &ReplayerParams) -> anyhow::Result<Self> {
        if p.bag.is_empty() {
            return Err(
                NodeParamError("bag: no bag given (a bag directory or .mcap file)".into()).into(),
            );
        }
        let path = PathBuf::from(&p.bag);
        if !path.exists() {
            return Err(NodeParamError(format!(
                "bag: {}: no such bag (a directory or .mcap file)",
                path.display()
            ))
            .into());
        }
        let rate = check_rate(p.rate).map_err(|e| NodeParamError(format!("rate: {e}")))?;
        let start_offset = seconds(p.start_offset_s, "start_offset_s")?;
        let wait_for_subscribers = seconds(p.wait_for_subscribers_s, "wait_for_subscribers_s")?;
        let linger = seconds(p.linger_s, "linger_s")?;
        if !(p.progress_every_s.is_finite() && p.progress_every_s > 0.0) {
            return Err(NodeParamError(format!(
                "progress_every_s: {}: expected seconds > 0",
                p.progress_every_s
            ))
            .into());
        }
        let clock_period = match p.clock_hz {
            0.0 => None,
            hz if hz.is_finite() && hz > 0.0 && hz <= MAX_CLOCK_HZ => {
                Some(Duration::from_secs_f64(1.0 / hz))
            }
            hz => {
                return Err(NodeParamError(format!(
                    "clock_hz: {hz}: expected 0 (off) or a rate in (0, {MAX_CLOCK_HZ}] Hz"
                ))
                .into())
            }
        };
        let filter = TopicFilter::new(&p.topics, &p.exclude)?;
        let remaps = Remaps::parse(&p.remap)?;
        let reader = BagReader::open(&path).map_err(|e| DataError(format!("bag: {e}")))?;
        let info = reader.info();

        let mut plans = Vec::new();
        let mut machine_left_out = Vec::new();
        let mut outputs: HashMap<String, (String, Option<usize>)> = HashMap::new();
        for t in info.topics.iter().filter(|t| filter.wants(&t.name)) {
            if is_machine_type(&t.type_name) && !named(&p.topics, &t.name) {
                machine_left_out.push((t.name.clone(), t.message_count));
                continue;
            }
            let (output, remap) = remaps.apply(&t.name);
            let (qos, note) = preset_for(&t.offered_qos_profiles);
            if let Some(note) = note {
                tracing::info!("{}: {note}; publishing it as {qos:?}", t.name);
            }
            let known = decoder_for(&t.type_name).is_some();
            if !known {
                tracing::warn!(
                    "{}: type {} is not known here; its {} messages are skipped",
                    t.name,
                    t.type_name,
                    t.message_count
                );
            } else if let Some((other_type, other_remap)) =
                outputs.insert(output.to_owned(), (t.type_name.clone(), remap))
            {
                // Two bag topics may share a name only if they share a type.
                if other_type != t.type_name {
                    let which = remap
                        .or(other_remap)
                        .map_or("remap".to_owned(), |i| format!("remap[{i}]"));
                    return Err(NodeParamError(format!(
                        "{which}: {output} would carry both {other_type} and {}",
                        t.type_name
                    ))
                    .into());
                }
            }
            plans.push(TopicPlan {
                topic: t.name.clone(),
                output: output.to_owned(),
                ros_type: t.type_name.clone(),
                qos,
                messages: t.message_count,
                known,
            });
        }
        if !machine_left_out.is_empty() {
            tracing::info!(
                "left out machine topics {} (they would drive a machine); name one in topics \
                 (--topics) to play it",
                left_out(&machine_left_out)
            );
        }
        if plans.is_empty() && !machine_left_out.is_empty() {
            return Err(NodeParamError(format!(
                "topics: every selected topic of {} is a machine topic ({}); name one in topics \
                 (--topics) to play it",
                path.display(),
                left_out(&machine_left_out)
            ))
            .into());
        }
        if plans.is_empty() && !info.topics.is_empty() {
            let names: Vec<&str> = info.topics.iter().map(|t| t.name.as_str()).collect();
            return Err(NodeParamError(format!(
                "topics/exclude: no topic of {} is selected (it has {})",
                path.display(),
                names.join(", ")
            ))
            .into());
        }
        let names: Vec<&str> = info.topics.iter().map(|t| t.name.as_str()).collect();
        for from in remaps.unused(&names) {
            tracing::warn!("remap: {from} is not a topic of {}", path.display());
        }
        Ok(Replay {
            bag_start_ns: info.time_range.map_or(0, |(start, _)| start),
            path,
            reader,
            plans,
            machine_left_out,
            allow_machine_topics: p.allow_machine_topics,
            rate,
            looping: p.r#loop,
            start_offset,
            start_paused: p.start_paused,
            wait_for_subscribers,
            linger,
            clock_period,
        })
    }

    /// The selected topics (those of unknown type included, marked).
    pub fn topics(&self) -> &[TopicPlan] {
        &self.plans
    }

    /// Machine topics left out because `topics` does not name them, with their messages.
    pub fn machine_topics_left_out(&self) -> &[(String, u64)] {
        &self.machine_left_out
    }

    /// Messages of the played topics in the bag (before the start offset is applied).
    pub fn messages(&self) -> u64 {
        self.plans
            .iter()
            .filter(|p| p.known)
            .map(|p| p.messages)
            .sum()
    }

    /// Plays the bag on `node` until its end (or, with `loop`, until shutdown), calling
    /// `observer` after every published message and on every pause or resume. Serves
    /// `~/set_paused` (`std_srvs/srv/SetBool`: `data: true` pauses) while it runs. Shutdown of
    /// `node` stops it cleanly (the summary says so).
    ///
    /// # Errors
    /// A publisher or the service cannot be created; the bag turns out unreadable partway
    /// ([`DataError`]). A message that fails to publish is logged and counted, not an error.
    pub async fn run(
        self,
        node: &CellNode,
        mut observer: impl FnMut(&Progress),
    ) -> anyhow::Result<ReplaySummary> {
        let Replay {
            path,
            reader,
            plans,
            machine_left_out,
            allow_machine_topics,
            bag_start_ns,
            rate,
            looping,
            start_offset,
            start_paused,
            wait_for_subscribers,
            linger,
            clock_period,
        } = self;
        let total_messages: u64 = plans.iter().filter(|p| p.known).map(|p| p.messages).sum();
        let unknown_type: u64 = plans.iter().filter(|p| !p.known).map(|p| p.messages).sum();

        // One publisher per published name; `route[i]` is plan i's.
        let mut publishers: Vec<Box<dyn Republish>> = Vec::new();
        let mut by_output: HashMap<String, usize> = HashMap::new();
        let mut route: Vec<Option<usize>> = Vec::new();
        for plan in &plans {
            if !plan.known {
                route.push(None);
                continue;
            }
            let index = match by_output.get(&plan.output) {
                Some(&i) => i,
                None => {
                    let publisher = publisher_for(node, &plan.output, &plan.ros_type, plan.qos)
                        .ok_or_else(|| anyhow!("{}: type {} not known", plan.topic, plan.ros_type))?
                        .map_err(|e| {
                            NodeParamError(format!("{} (from {}): {e:#}", plan.output, plan.topic))
                        })?;
                    publishers.push(publisher);
                    by_output.insert(plan.output.clone(), publishers.len() - 1);
                    publishers.len() - 1
                }
            };
            route.push(Some(index));
        }
        let topics = publishers.len();
        let machine_outputs: Vec<&str> = plans
            .iter()
            .zip(&route)
            .filter(|(plan, route)| is_machine_type(&plan.ros_type) && route.is_some())
            .filter_map(|(_, route)| route.map(|i| publishers[i].topic()))
            .collect();
        if !machine_outputs.is_empty() {
            if allow_machine_topics {
                tracing::warn!(
                    "playing machine topics {} (allow_machine_topics): a machine bridge on \
                     domain {} will act on them",
                    machine_outputs.join(", "),
                    node.domain_id()
                );
            } else if let Some(bridge) = find_bridge(node, &machine_outputs).await {
                return Err(NodeParamError(format!(
                    "refusing to play machine topics {} onto ROS domain {}: a machine bridge \
                     or another reader of machine messages runs there ({bridge}) and would act on them; pass --allow-machine-topics \
                     (parameter allow_machine_topics) to play them anyway",
                    machine_outputs.join(", "),
                    node.domain_id()
                ))
                .into());
            }
        }
        let mut time_source = match clock_period {
            Some(period) => Some(TimeSource::new(
                node,
                period,
                bag_start_ns.saturating_add(start_offset.as_nanos() as u64),
            )?),
            None => None,
        };

        // Pause/resume arrive from the service as requests the loop below answers, so the
        // answer comes after the clock has changed.
        let (control_tx, mut control_rx) = mpsc::channel::<Control>(8);
        let server = node.service_server::<SetBoolRequest, SetBoolResponse>("~/set_paused")?;
        let service_name = server.name().to_owned();
        let service_stop = StopOnDrop(Shutdown::new());
        let stop = service_stop.0.clone();
        let service = tokio::spawn(async move {
            server
                .serve(&stop, move |request: SetBoolRequest| {
                    let control_tx = control_tx.clone();
                    async move {
                        let ended = || SetBoolResponse {
                            success: false,
                            message: "the replay has ended".into(),
                        };
                        let (reply, answer) = oneshot::channel();
                        let control = Control {
                            paused: request.data,
                            reply,
                        };
                        if control_tx.send(control).await.is_err() {
                            return ended();
                        }
                        match answer.await {
                            Ok(message) => SetBoolResponse {
                                success: true,
                                message,
                            },
                            Err(_) => ended(),
                        }
                    }
                })
                .await;
        });

        // The reader thread.
        let stats = Arc::new(ReadStats::default());
        let (feed_tx, mut feed_rx) = mpsc::channel::<Feed>(1024);
        {
            let index: HashMap<String, usize> = plans
                .iter()
                .enumerate()
                .map(|(i, p)| (p.topic.clone(), i))
                .collect();
            let decoders: Vec<Option<Decoder>> =
                plans.iter().map(|p| decoder_for(&p.ros_type)).collect();
            let job = ReadJob {
                reader,
                index,
                decoders,
                timeline: Timeline::new(bag_start_ns, start_offset),
                looping,
                budget: Arc::new(Budget::new(READ_AHEAD_BYTES)),
                stats: stats.clone(),
                tx: feed_tx,
            };
            std::thread::Builder::new()
                .name("bag reader".into())
                .spawn(move || job.run())
                .map_err(|e| anyhow!("starting the bag reader thread: {e}"))?;
        }

        let shutdown = node.shutdown().clone();
        if !wait_for_subscribers.is_zero() {
            let waits = publishers
                .iter()
                .map(|p| p.wait_for_subscribers(wait_for_subscribers));
            tokio::select! {
                matched = futures::future::join_all(waits) => {
                    let missing: Vec<&str> = publishers
                        .iter()
                        .zip(&matched)
                        .filter(|(_, m)| !**m)
                        .map(|(p, _)| p.topic())
                        .collect();
                    if missing.is_empty() {
                        // Discovery is symmetric but not simultaneous: let the readers match
                        // this node's writers too, or a reliable reader may lose the first ones.
                        tokio::time::sleep(SUBSCRIBER_SETTLE.min(wait_for_subscribers)).await;
                    } else {
                        tracing::info!(
                            "no subscriber after {:.1} s on {}; playing anyway",
                            wait_for_subscribers.as_secs_f64(),
                            missing.join(", ")
                        );
                    }
                }
                _ = shutdown.requested() => {}
            }
        }
        tracing::info!(
            "playing {} ({} topics, {} messages) at ×{rate}{}{}; pause with {service_name}",
            path.display(),
            topics,
            total_messages,
            if looping { ", looping" } else { "" },
            if start_paused { ", paused" } else { "" },
        );

        let t0 = tokio::time::Instant::now();
        let now = || t0.elapsed();
        let mut clock = ReplayClock::new(rate, now(), start_paused).map_err(NodeParamError)?;
        let mut progress = Progress {
            published: 0,
            total: total_messages,
            all_published: 0,
            pass: 0,
            position: Duration::ZERO,
            paused: start_paused,
            scheduled_at: None,
        };
        let mut failed = 0u64;
        let mut stopped = false;
        let mut first_at: Option<tokio::time::Instant> = None;
        let mut last_at = t0;
        let mut outcome: anyhow::Result<()> = Ok(());
        'replay: loop {
            // The next message, answering pause requests meanwhile.
            let item = loop {
                tokio::select! {
                    biased;
                    _ = shutdown.requested() => {
                        stopped = true;
                        break 'replay;
                    }
                    Some(c) = control_rx.recv() => {
                        apply(&mut clock, c, now());
                        show_clock(&clock, now(), &mut progress, &mut observer);
                    }
                    () = TimeSource::tick(&mut time_source) => {
                        TimeSource::publish(&mut time_source, clock.position(now())).await;
                    }
                    feed = feed_rx.recv() => match feed {
                        None => break 'replay,
                        Some(Feed::Failed(e)) => {
                            outcome = Err(DataError(format!("bag: {e}")).into());
                            break 'replay;
                        }
                        Some(Feed::Item(item)) => break item,
                    },
                }
            };
            if let Some(source) = &mut time_source {
                source.place(&item);
            }
            if item.pass != progress.pass {
                // A new pass: its messages are those left after the start offset.
                progress.pass = item.pass;
                progress.published = 0;
                progress.total =
                    total_messages.saturating_sub(stats.before_offset.load(Ordering::Relaxed));
                clock.restart(now());
                if item.pass > 1 {
                    tracing::info!("pass {} from the start", item.pass);
                }
            }
            // Wait until it is due, answering pause requests meanwhile.
            let due = loop {
                let due = clock.due(item.offset);
                let wait = async {
                    match due {
                        Some(d) => tokio::time::sleep_until(t0 + d).await,
                        None => std::future::pending().await,
                    }
                };
                tokio::select! {
                    biased;
                    _ = shutdown.requested() => {
                        stopped = true;
                        break 'replay;
                    }
                    Some(c) = control_rx.recv() => {
                        apply(&mut clock, c, now());
                        show_clock(&clock, now(), &mut progress, &mut observer);
                    }
                    () = TimeSource::tick(&mut time_source) => {
                        TimeSource::publish(&mut time_source, clock.position(now())).await;
                    }
                    _ = wait => break due.unwrap_or_default(),
                }
            };
            let Some(publisher) = route[item.topic].map(|i| &publishers[i]) else {
                continue;
            };
            first_at.get_or_insert_with(tokio::time::Instant::now);
            match publisher.publish(item.message).await {
                Ok(()) => {
                    progress.published += 1;
                    progress.all_published += 1;
                }
                Err(e) => {
                    failed += 1;
                    tracing::warn!("{e:#}");
                }
            }
            last_at = tokio::time::Instant::now();
            progress.position = item.offset;
            progress.scheduled_at = Some((t0 + due).into_std());
            observer(&progress);
        }
        drop(feed_rx); // ends the reader thread

        if outcome.is_ok() && !stopped && !linger.is_zero() {
            let end = tokio::time::sleep(linger);
            tokio::pin!(end);
            loop {
                tokio::select! {
                    _ = &mut end => break,
                    _ = shutdown.requested() => break,
                    Some(c) = control_rx.recv() => {
                        let _ = c.reply.send("the replay has finished".into());
                    }
                }
            }
        }
        // The server holds a clone of the node: let it go before the caller drops the node,
        // or the node outlives its graph spinner when the runtime shuts down.
        drop(service_stop);
        let _ = service.await;
        outcome?;
        Ok(ReplaySummary {
            published: progress.all_published,
            failed,
            undecodable: stats.undecodable.load(Ordering::Relaxed),
            unknown_type,
            before_offset: stats.before_offset.load(Ordering::Relaxed),
            machine_left_out,
            passes: progress.pass,
            topics,
            elapsed: first_at.map_or(Duration::ZERO, |f| last_at.saturating_duration_since(f)),
            stopped,
            rate,
        })
    }
}

/// Looks for a machine bridge for up to [`BRIDGE_DISCOVERY`] (ending early once one is
/// seen): a reader of a [`MACHINE_TYPES`] type on any topic or service (`machine_bridge`
/// always has its `machine_command` topic and service and its `execute_program` action), or of
/// `outputs`, the topics the replay would publish machine messages on. The replay itself
/// reads none of these. Returns what it found, in words.
async fn find_bridge(node: &CellNode, outputs: &[&str]) -> Option<String> {
    let deadline = tokio::time::Instant::now() + BRIDGE_DISCOVERY;
    loop {
        let found: Vec<String> = node
            .discovered_readers()
            .into_iter()
            .filter(|r| {
                is_machine_type(&r.ros_type)
                    || outputs.iter().any(|o| r.dds_topic == format!("rt{o}"))
            })
            .map(|r| format!("a reader of {} on {}", r.ros_type, r.dds_topic))
            .collect();
        if !found.is_empty() {
            return Some(found.join(", "));
        }
        if tokio::time::Instant::now() >= deadline || node.shutdown().is_triggered() {
            return None;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// The fastest `/clock` a replay publishes (rosbag2 sets no limit; beyond this the ticks would
/// crowd out the messages).
const MAX_CLOCK_HZ: f64 = 1000.0;

/// The replay as a ROS time source: the bag's time on `/clock` (module docs).
struct TimeSource {
    publisher: Publisher<Clock>,
    ticks: tokio::time::Interval,
    /// The log time at bag offset 0 of the current pass (the first message kept; before it,
    /// the bag's start plus the start offset).
    origin_ns: u64,
    pass: u32,
}

impl TimeSource {
    fn new(node: &CellNode, period: Duration, origin_ns: u64) -> anyhow::Result<Self> {
        let mut ticks = tokio::time::interval(period);
        ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        Ok(TimeSource {
            publisher: Publisher::new(node, cell_runtime::clock::CLOCK_TOPIC, QosPreset::Clock)?,
            ticks,
            origin_ns,
            pass: 0,
        })
    }

    /// Takes the origin of a new pass from its first message.
    fn place(&mut self, item: &Item) {
        if item.pass != self.pass {
            self.pass = item.pass;
            let offset_ns = u64::try_from(item.offset.as_nanos()).unwrap_or(u64::MAX);
            self.origin_ns = item.log_time_ns.saturating_sub(offset_ns);
        }
    }

    /// The next tick; never, without a time source.
    async fn tick(source: &mut Option<Self>) {
        match source {
            Some(s) => {
                s.ticks.tick().await;
            }
            None => std::future::pending().await,
        }
    }

    /// Publishes the bag time at replay `position`.
    async fn publish(source: &mut Option<Self>, position: Duration) {
        let Some(s) = source else { return };
        let ns = s
            .origin_ns
            .saturating_add(u64::try_from(position.as_nanos()).unwrap_or(u64::MAX));
        let clock = Time::from_system_time(std::time::UNIX_EPOCH + Duration::from_nanos(ns));
        if let Err(e) = s.publisher.publish(Clock { clock }).await {
            tracing::debug!("/clock: {e:#}");
        }
    }
}

/// How long the readers get to match this node after it has matched them.
const SUBSCRIBER_SETTLE: Duration = Duration::from_millis(500);

/// Decoded messages the reader thread may hold ahead of the clock (bytes of CDR).
const READ_AHEAD_BYTES: usize = 64 << 20;

/// A pause or resume request and where to send the answer.
struct Control {
    paused: bool,
    reply: oneshot::Sender<String>,
}

/// Applies a pause/resume request at `now` and answers it with what happened.
fn apply(clock: &mut ReplayClock, control: Control, now: Duration) {
    let changed = clock.set_paused(control.paused, now);
    let t = clock.position(now).as_secs_f64();
    let message = match (control.paused, changed) {
        (true, true) => format!("paused at t={t:.2} s"),
        (true, false) => format!("already paused at t={t:.2} s"),
        (false, true) => format!("resumed at t={t:.2} s"),
        (false, false) => format!("already playing, t={t:.2} s"),
    };
    if changed {
        tracing::info!("{message}");
    }
    let _ = control.reply.send(message);
}

/// Tells the observer the clock changed (paused or resumed) between messages.
fn show_clock(
    clock: &ReplayClock,
    now: Duration,
    progress: &mut Progress,
    observer: &mut impl FnMut(&Progress),
) {
    progress.paused = clock.is_paused();
    progress.position = clock.position(now);
    progress.scheduled_at = None;
    observer(progress);
}

/// Triggers its signal when dropped (stops the service however `run` ends).
struct StopOnDrop(Shutdown);

impl Drop for StopOnDrop {
    fn drop(&mut self) {
        self.0.trigger();
    }
}

/// Decodes CDR as one type, boxed for the trip to the publisher.
type Decoder = fn(&[u8]) -> Result<Box<dyn Any + Send>, CdrError>;

fn decode_any<T: RosMessage>(bytes: &[u8]) -> Result<Box<dyn Any + Send>, CdrError> {
    Ok(Box::new(T::decode(bytes)?))
}

type BoxFuture<'a, T> = Pin<Box<dyn Future<Output = T> + Send + 'a>>;

/// A [`Publisher`] of whatever type one topic carries.
trait Republish: Send + Sync {
    fn topic(&self) -> &str;
    fn publish(&self, message: Box<dyn Any + Send>) -> BoxFuture<'_, anyhow::Result<()>>;
    fn wait_for_subscribers(&self, timeout: Duration) -> BoxFuture<'_, bool>;
}

impl<T: RosMessage> Republish for Publisher<T> {
    fn topic(&self) -> &str {
        Publisher::topic(self)
    }

    fn publish(&self, message: Box<dyn Any + Send>) -> BoxFuture<'_, anyhow::Result<()>> {
        Box::pin(async move {
            let message = message
                .downcast::<T>()
                .map_err(|_| anyhow!("{}: not a {}", self.topic(), T::ROS_NAME))?;
            Publisher::publish(self, *message).await
        })
    }

    fn wait_for_subscribers(&self, timeout: Duration) -> BoxFuture<'_, bool> {
        Box::pin(Publisher::wait_for_subscribers(self, 1, timeout))
    }
}

/// The decoder and publisher for every type of [`cell_msgs::for_each_message!`].
macro_rules! known_types {
    ($($ty:ty => $name:literal),* $(,)?) => {
        fn decoder_for(ros_type: &str) -> Option<Decoder> {
            match ros_type {
                $($name => Some(decode_any::<$ty> as Decoder),)*
                _ => None,
            }
        }

        fn publisher_for(
            node: &CellNode,
            topic: &str,
            ros_type: &str,
            qos: QosPreset,
        ) -> Option<anyhow::Result<Box<dyn Republish>>> {
            match ros_type {
                $($name => Some(
                    node.publisher::<$ty>(topic, qos).map(|p| Box::new(p) as Box<dyn Republish>)
                ),)*
                _ => None,
            }
        }
    };
}
cell_msgs::for_each_message!(known_types);

/// A decoded message on its way to the publisher.
struct Item {
    pass: u32,
    offset: Duration,
    log_time_ns: u64,
    topic: usize,
    message: Box<dyn Any + Send>,
    _budget: Permit,
}

/// What the reader thread sends.
enum Feed {
    Item(Item),
    /// The bag could not be read further (the error names the file).
    Failed(String),
}

#[derive(Default)]
struct ReadStats {
    before_offset: AtomicU64,
    undecodable: AtomicU64,
}

/// The reader thread's work: every pass over the bag, filtered, placed and decoded.
struct ReadJob {
    reader: BagReader,
    index: HashMap<String, usize>,
    decoders: Vec<Option<Decoder>>,
    timeline: Timeline,
    looping: bool,
    budget: Arc<Budget>,
    stats: Arc<ReadStats>,
    tx: mpsc::Sender<Feed>,
}

impl ReadJob {
    fn run(mut self) {
        let mut warned: HashSet<usize> = HashSet::new();
        for pass in 1u32.. {
            self.timeline.rewind();
            let mut sent = 0u64;
            for m in self.reader.messages() {
                let m = match m {
                    Ok(m) => m,
                    Err(e) => {
                        let _ = self.tx.blocking_send(Feed::Failed(e.to_string()));
                        return;
                    }
                };
                let Some(&topic) = self.index.get(&*m.topic) else {
                    continue;
                };
                let Some(decode) = self.decoders[topic] else {
                    continue;
                };
                let Some(offset) = self.timeline.place(m.log_time_ns) else {
                    if pass == 1 {
                        self.stats.before_offset.fetch_add(1, Ordering::Relaxed);
                    }
                    continue;
                };
                let message = match decode(&m.data) {
                    Ok(message) => message,
                    Err(e) => {
                        if warned.insert(topic) {
                            tracing::warn!("{}: skipping undecodable messages: {e}", m.topic);
                        }
                        self.stats.undecodable.fetch_add(1, Ordering::Relaxed);
                        continue;
                    }
                };
                let item = Item {
                    pass,
                    offset,
                    log_time_ns: m.log_time_ns,
                    topic,
                    message,
                    _budget: self.budget.acquire(m.data.len()),
                };
                if self.tx.blocking_send(Feed::Item(item)).is_err() {
                    return; // the replay ended
                }
                sent += 1;
            }
            // A pass with nothing to play would loop for ever without pause.
            if !self.looping || sent == 0 {
                return;
            }
        }
    }
}

/// Bytes of messages in flight between the reader thread and the publisher.
struct Budget {
    limit: usize,
    used: Mutex<usize>,
    freed: Condvar,
}

/// A share of a [`Budget`], given back when dropped.
struct Permit {
    budget: Arc<Budget>,
    bytes: usize,
}

impl Budget {
    fn new(limit: usize) -> Self {
        Budget {
            limit,
            used: Mutex::new(0),
            freed: Condvar::new(),
        }
    }

    /// Blocks until `bytes` fit (one message larger than the whole budget goes alone).
    fn acquire(self: &Arc<Self>, bytes: usize) -> Permit {
        let mut used = self.used.lock().unwrap_or_else(|p| p.into_inner());
        while *used > 0 && *used + bytes > self.limit {
            used = self.freed.wait(used).unwrap_or_else(|p| p.into_inner());
        }
        *used += bytes;
        Permit {
            budget: self.clone(),
            bytes,
        }
    }
}

impl Drop for Permit {
    fn drop(&mut self) {
        let mut used = self.budget.used.lock().unwrap_or_else(|p| p.into_inner());
        *used -= self.bytes;
        self.budget.freed.notify_all();
    }
}

/// Plays the bag, logging progress every `progress_every_s`, and a summary at the end.
///
/// # Errors
/// See [`Replay::open`] and [`Replay::run`].
pub async fn run(node: CellNode, p: ReplayerParams) -> anyhow::Result<()> {
    let replay = Replay::open(&p)?;
    let every = Duration::from_secs_f64(p.progress_every_s);
    let mut last_log = std::time::Instant::now();
    let summary = replay
        .run(&node, |pr| {
            if pr.scheduled_at.is_some() && last_log.elapsed() >= every {
                last_log = std::time::Instant::now();
                tracing::info!(
                    "replayed {}/{} messages, t={:.1} s{}",
                    pr.published,
                    pr.total,
                    pr.position.as_secs_f64(),
                    if pr.pass > 1 {
                        format!(" (pass {})", pr.pass)
                    } else {
                        String::new()
                    }
                );
            }
        })
        .await?;
    tracing::info!("{summary}");
    Ok(())
}

/// The `replayer` binary (also `cell node replayer`).
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("replayer", argv, run)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_bag::QosProfile;

    #[test]
    fn the_shipped_params_file_parses_and_matches_the_defaults() {
        let mut sources = cell_runtime::params::ParamSources::default();
        let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/replayer.yaml");
        sources
            .merge_file(std::path::Path::new(file), "/", "replayer")
            .unwrap();
        let p: ReplayerParams = sources.parse().unwrap();
        assert_eq!(p, ReplayerParams::default());
    }

    #[test]
    fn remaps_parse_apply_and_name_bad_entries() {
        let r = Remaps::parse(&["/a:=/b".into(), "c:=renamed".into()]).unwrap();
        assert_eq!(r.apply("/a"), ("/b", Some(0)));
        assert_eq!(r.apply("/c"), ("renamed", Some(1)));
        assert_eq!(r.apply("/x"), ("/x", None));
        assert_eq!(r.unused(&["/a", "/x"]), ["/c"]);
        for (bad, i) in [("nope", 1), (":=/b", 1), ("/a:=", 1), ("/a b:=/c", 1)] {
            let e = Remaps::parse(&["/ok:=/fine".into(), bad.into()])
                .unwrap_err()
                .0;
            assert!(e.starts_with(&format!("remap[{i}]: ")), "{e}");
            assert!(e.contains("expected FROM:=TO"), "{e}");
        }
    }

    #[test]
    fn recorded_qos_maps_back_to_the_presets() {
        let yaml = |p: &[QosProfile]| cell_bag::qos::to_yaml(p);
        let plan = QosProfile::reliable_transient_local(16);
        let status = QosProfile::reliable_volatile(32);
        let stream = QosProfile::best_effort(1);
        assert_eq!(preset_for(&yaml(&[plan])), (QosPreset::Plan, None));
        assert_eq!(preset_for(&yaml(&[status])), (QosPreset::Status, None));
        assert_eq!(preset_for(&yaml(&[stream])), (QosPreset::Stream, None));
        // Several publishers: only what all of them offered.
        assert_eq!(preset_for(&yaml(&[plan, status])).0, QosPreset::Status);
        assert_eq!(preset_for(&yaml(&[plan, stream])).0, QosPreset::Stream);
        // Nothing usable recorded: Status, with a note.
        let (preset, note) = preset_for("");
        assert_eq!((preset, note.is_some()), (QosPreset::Status, true));
        let (preset, note) = preset_for("- nope");
        assert_eq!((preset, note.is_some()), (QosPreset::Status, true));
        let unknown = yaml(&[plan]).replace("reliability: 1", "reliability: 0");
        assert_eq!(preset_for(&unknown).0, QosPreset::Status);
    }

    #[test]
    fn every_known_type_has_a_decoder_and_others_none() {
        let bytes =
            cell_msgs::to_cdr(&cell_msgs::std_msgs::StringMsg { data: "hi".into() }).unwrap();
        let decoded = decoder_for("std_msgs/msg/String").unwrap()(&bytes).unwrap();
        let decoded = decoded
            .downcast::<cell_msgs::std_msgs::StringMsg>()
            .unwrap();
        assert_eq!(decoded.data, "hi");
        assert!(decoder_for("cell_msgs/msg/HeatMap").is_some());
        assert!(decoder_for("rcl_interfaces/msg/Log").is_none());
    }

    #[test]
    fn bad_parameters_and_bags_are_named_with_their_exit_class() {
        let dir = tempfile::tempdir().unwrap();
        let bag = dir.path().join("b");
        let mut w = cell_bag::BagWriter::create(&bag, Default::default()).unwrap();
        w.add_topic("/a", "std_msgs/msg/String", &[]).unwrap();
        w.write("/a", &cell_msgs::std_msgs::StringMsg::default(), 1)
            .unwrap();
        w.finish().unwrap();
        let ok = ReplayerParams {
            bag: bag.display().to_string(),
            ..ReplayerParams::default()
        };
        let param_error = |p: ReplayerParams| -> String {
            let e = Replay::open(&p).err().expect("refused");
            e.downcast_ref::<NodeParamError>()
                .unwrap_or_else(|| panic!("not a NodeParamError: {e:#}"))
                .0
                .clone()
        };
        let missing = dir.path().join("nope");
        let e = param_error(ReplayerParams {
            bag: missing.display().to_string(),
            ..ok.clone()
        });
        assert!(
            e.starts_with("bag: ") && e.contains(&missing.display().to_string()),
            "{e}"
        );
        assert!(param_error(ReplayerParams::default()).starts_with("bag: "));
        for rate in [0.0, -2.0, f64::NAN] {
            let e = param_error(ReplayerParams { rate, ..ok.clone() });
            assert!(e.starts_with("rate: "), "{e}");
        }
        let e = param_error(ReplayerParams {
            topics: vec!["(".into()],
            ..ok.clone()
        });
        assert!(e.starts_with("topics[0]"), "{e}");
        let e = param_error(ReplayerParams {
            remap: vec!["/a=/b".into()],
            ..ok.clone()
        });
        assert!(e.starts_with("remap[0]"), "{e}");
        let e = param_error(ReplayerParams {
            start_offset_s: -1.0,
            ..ok.clone()
        });
        assert!(e.starts_with("start_offset_s"), "{e}");
        let e = param_error(ReplayerParams {
            topics: vec!["/b".into()],
            ..ok.clone()
        });
        assert!(e.starts_with("topics/exclude") && e.contains("/a"), "{e}");

        // An unfinished bag: a data error naming the file.
        let mcap = std::fs::read_dir(&bag)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| p.extension().is_some_and(|x| x == "mcap"))
            .unwrap();
        let bytes = std::fs::read(&mcap).unwrap();
        std::fs::write(&mcap, &bytes[..bytes.len() - 20]).unwrap();
        let e = Replay::open(&ok).err().expect("refused");
        let data = e.downcast_ref::<DataError>().expect("a DataError");
        assert!(data.0.contains(&mcap.display().to_string()), "{}", data.0);
        assert!(data.0.contains("repair"), "{}", data.0);
    }

    #[test]
    fn machine_topics_are_left_out_unless_named() {
        let dir = tempfile::tempdir().unwrap();
        let bag = dir.path().join("m");
        let mut w = cell_bag::BagWriter::create(&bag, Default::default()).unwrap();
        w.write(
            "/cell/machine_program",
            &cell_msgs::MachineProgram::default(),
            1,
        )
        .unwrap();
        w.write(
            "/cell/machine_command",
            &cell_msgs::MachineCommand::default(),
            2,
        )
        .unwrap();
        w.write(
            "/cell/machine_command",
            &cell_msgs::MachineCommand::default(),
            3,
        )
        .unwrap();
        w.write("/cell/note", &cell_msgs::std_msgs::StringMsg::default(), 4)
            .unwrap();
        w.finish().unwrap();
        let all = ReplayerParams {
            bag: bag.display().to_string(),
            ..ReplayerParams::default()
        };
        let played =
            |r: &Replay| -> Vec<String> { r.topics().iter().map(|t| t.topic.clone()).collect() };
        // Every topic matches `.*`, but the machine topics are not named: left out.
        let r = Replay::open(&all).unwrap();
        assert_eq!(played(&r), ["/cell/note"]);
        assert_eq!(
            r.machine_topics_left_out(),
            [
                ("/cell/machine_program".to_owned(), 1),
                ("/cell/machine_command".to_owned(), 2)
            ]
        );
        assert_eq!(r.messages(), 1);
        // Named: played; a pattern matching it is not a name.
        let named = ReplayerParams {
            topics: vec![".*".into(), "/cell/machine_program".into()],
            ..all.clone()
        };
        let r = Replay::open(&named).unwrap();
        assert_eq!(played(&r), ["/cell/machine_program", "/cell/note"]);
        assert_eq!(
            r.machine_topics_left_out(),
            [("/cell/machine_command".to_owned(), 2)]
        );
        // Only machine topics selected and none named: refused, naming them.
        let only = ReplayerParams {
            topics: vec!["/cell/machine_.*".into()],
            ..all.clone()
        };
        let e = Replay::open(&only).err().expect("refused");
        let e = e
            .downcast_ref::<NodeParamError>()
            .expect("a parameter error");
        assert!(
            e.0.starts_with("topics: every selected topic")
                && e.0.contains("/cell/machine_program (1 message)"),
            "{}",
            e.0
        );
        // The names are real: every one but the action's wire-level SendGoal is a known type.
        for t in MACHINE_TYPES {
            assert!(
                decoder_for(t).is_some() || t.ends_with("_SendGoal_Request"),
                "{t}"
            );
        }
    }

    #[test]
    fn the_summary_is_one_line_with_what_was_left_out() {
        let mut summary = ReplaySummary {
            published: 12,
            failed: 0,
            undecodable: 0,
            unknown_type: 0,
            before_offset: 0,
            machine_left_out: Vec::new(),
            passes: 1,
            topics: 1,
            elapsed: Duration::from_millis(2500),
            stopped: false,
            rate: 2.0,
        };
        assert_eq!(
            summary.to_string(),
            "replayed 12 messages on 1 topic in 2.5 s at ×2 (1 pass)"
        );
        summary.passes = 3;
        summary.stopped = true;
        summary.unknown_type = 4;
        summary.before_offset = 2;
        assert_eq!(
            summary.to_string(),
            "replayed 12 messages on 1 topic in 2.5 s at ×2 (3 passes), stopped early; \
             2 before the start offset; 4 of unknown types"
        );
        summary.machine_left_out = vec![("/m".into(), 1), ("/c".into(), 3)];
        assert!(summary
            .to_string()
            .ends_with("; left out machine topics /m (1 message), /c (3 messages)"));
    }

    #[test]
    fn the_budget_blocks_until_bytes_come_back() {
        let budget = Arc::new(Budget::new(10));
        let a = budget.acquire(6);
        let big = budget.clone();
        let waiter = std::thread::spawn(move || {
            let _b = big.acquire(6);
        });
        std::thread::sleep(Duration::from_millis(50));
        assert!(!waiter.is_finished(), "6 + 6 > 10 waits");
        drop(a);
        waiter.join().unwrap();
        // Larger than the whole budget: goes alone.
        drop(budget.acquire(100));
        assert_eq!(*budget.used.lock().unwrap(), 0);
    }
}
