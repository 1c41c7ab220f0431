//! `cell bag info BAG`, `cell bag repair BAG` and `cell bag to-rerun BAG`: rosbag2 MCAP bags
//! without DDS, through [`cell_bag`]; `cell bag play BAG`: the bag republished over DDS, through
//! [`replayer`].
//!
//! - `info` prints topics, types, counts, duration, size and files, like `ros2 bag info`.
//! - `to-rerun` converts a bag into a Rerun recording (see [`crate::bag_rerun`]).
//! - `repair` restores a bag whose writer was killed: every file is cut after its last complete
//!   chunk and rewritten with a summary (the original kept as `*.orig`), and `metadata.yaml` is
//!   regenerated.
//! - `play` runs the replayer library on a node named `bag_play` with a progress bar: recorded
//!   timing (×`--rate`), recorded QoS, `--loop`, `--topics`/`--exclude`, `--remap`,
//!   `--start-offset`, `--paused` (resume with `/bag_play/set_paused`), `--clock [HZ]` (the
//!   bag's time on `/clock` for `use_sim_time` nodes); Ctrl-C stops cleanly. Machine topics
//!   (programs, machine commands, `execute_program` goals) are left out, with a line naming
//!   them, unless `--topics` names one; playing one onto a domain where a machine bridge runs
//!   needs `--allow-machine-topics` (see [`replayer`]).
//!
//! Exit status: 0 done; 64 a bad command line, a path that does not exist, or machine topics
//! refused because a machine bridge runs on the domain; 65 a bag that
//! cannot be read (truncated, corrupted, unfinished: the message names the file and offset, and
//! for an unfinished bag says to run `cell bag repair`).

use std::{path::PathBuf, process::ExitCode};

use cell_runtime::{CellNode, DataError, NodeParamError, NodeSetup, Shutdown};
use clap::Subcommand;
use replayer::{Replay, ReplayerParams};

/// `cell bag` subcommands.
#[derive(Subcommand, Debug)]
pub enum BagCommand {
    /// Topics, types, message counts, duration, size and files of a bag (a directory or one
    /// .mcap), like `ros2 bag info`.
    Info {
        /// The bag directory or .mcap file.
        bag: PathBuf,
    },
    /// Restore a bag whose recorder was killed: keep everything up to the last complete chunk,
    /// write the summary section and regenerate metadata.yaml (originals kept as *.orig).
    Repair {
        /// The bag directory or .mcap file.
        bag: PathBuf,
    },
    /// Republish a bag over DDS with its recorded timing and QoS, with a progress bar (node
    /// `bag_play`; pause and resume with its `/bag_play/set_paused` service, std_srvs/SetBool).
    /// Ctrl-C stops.
    Play(PlayArgs),
    /// Convert a bag into a Rerun recording drawn like the live nodes' (toolpaths, heat maps
    /// and exposure scalars, machine traces, programs; see `cellsuite::bag_rerun`), with a
    /// summary per topic. Messages of unknown types are counted and skipped.
    ToRerun(crate::bag_rerun::ToRerunArgs),
}

/// `cell bag play` options (the replayer node's parameters).
#[derive(clap::Args, Debug)]
pub struct PlayArgs {
    /// The bag directory or .mcap file (give it before the list options).
    pub bag: PathBuf,
    /// Speed factor (> 0): 2 plays twice as fast as recorded.
    #[arg(long, default_value_t = 1.0, value_name = "N")]
    pub rate: f64,
    /// Start over at the end, until Ctrl-C.
    #[arg(long = "loop")]
    pub looping: bool,
    /// Play only topics matching one of these regexes (whole name); default: all.
    #[arg(long, num_args = 1.., value_name = "RE")]
    pub topics: Vec<String>,
    /// Never play topics matching one of these regexes (default: /rosout, /parameter_events).
    #[arg(long, num_args = 1.., value_name = "RE")]
    pub exclude: Vec<String>,
    /// Publish a bag topic under another name.
    #[arg(long, num_args = 1.., value_name = "FROM:=TO")]
    pub remap: Vec<String>,
    /// Skip the first S seconds of the bag.
    #[arg(long, default_value_t = 0.0, value_name = "S")]
    pub start_offset: f64,
    /// Start paused (resume: `ros2 service call /bag_play/set_paused std_srvs/srv/SetBool
    /// "{data: false}"`).
    #[arg(long)]
    pub paused: bool,
    /// Wait up to S seconds for every topic to have a subscriber before the first message.
    #[arg(long, default_value_t = 1.0, value_name = "S")]
    pub wait_for_subscribers: f64,
    /// Keep the publishers up S seconds after the last message (retransmissions, late joiners).
    #[arg(long, default_value_t = 1.0, value_name = "S")]
    pub linger: f64,
    /// Publish the bag's time on /clock (rosgraph_msgs/msg/Clock) HZ times a second (default
    /// 40), for nodes started with use_sim_time:=true; frozen while paused.
    #[arg(long, value_name = "HZ", num_args = 0..=1, default_missing_value = "40")]
    pub clock: Option<f64>,
    /// DDS interfaces: all, loopback or ADDR[,ADDR…] (default: CELL_DDS_NETWORK, else by
    /// ROS_LOCALHOST_ONLY, else all).
    #[arg(long, value_name = "NETWORK")]
    pub dds_network: Option<String>,
    /// Play machine topics named in --topics (programs, machine commands, execute_program
    /// goals) even when a machine bridge runs on the domain: the machine will act on them.
    #[arg(long)]
    pub allow_machine_topics: bool,
}

impl PlayArgs {
    /// The replayer parameters these options stand for.
    pub fn params(&self) -> ReplayerParams {
        let defaults = ReplayerParams::default();
        ReplayerParams {
            bag: self.bag.display().to_string(),
            rate: self.rate,
            r#loop: self.looping,
            topics: if self.topics.is_empty() {
                defaults.topics
            } else {
                self.topics.clone()
            },
            exclude: if self.exclude.is_empty() {
                defaults.exclude
            } else {
                self.exclude.clone()
            },
            remap: self.remap.clone(),
            start_offset_s: self.start_offset,
            start_paused: self.paused,
            wait_for_subscribers_s: self.wait_for_subscribers,
            linger_s: self.linger,
            clock_hz: self.clock.unwrap_or(0.0),
            allow_machine_topics: self.allow_machine_topics,
            ..defaults
        }
    }
}

/// The exit status for a replay error: 64 a bad option or path, 65 an unreadable bag, else 1.
fn exit_code(e: &anyhow::Error) -> ExitCode {
    if e.downcast_ref::<NodeParamError>().is_some() {
        ExitCode::from(cell_runtime::EXIT_USAGE)
    } else if e.downcast_ref::<DataError>().is_some() {
        ExitCode::from(cell_runtime::EXIT_DATA)
    } else {
        ExitCode::FAILURE
    }
}

/// `cell bag play`: see the [module docs](self).
fn play(args: &PlayArgs) -> ExitCode {
    // Warnings only by default: the bar shows progress and pauses (RUST_LOG=info for more).
    cell_runtime::logging::init(Some("warn"));
    let fail = |e: anyhow::Error| {
        eprintln!("error: cell bag play: {e:#}");
        exit_code(&e)
    };
    // Checked before any DDS comes up.
    let replay = match Replay::open(&args.params()) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let left_out = replay.machine_topics_left_out();
    if !left_out.is_empty() {
        let names: Vec<&str> = left_out.iter().map(|(t, _)| t.as_str()).collect();
        eprintln!(
            "cell bag play: left out machine topics {} (they would drive a machine); name one \
             with --topics to play it",
            names.join(", ")
        );
    }
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => return fail(anyhow::anyhow!("cannot start the async runtime: {e}")),
    };
    let mut participant = None;
    let result = runtime.block_on(async {
        let user: Vec<String> = match &args.dds_network {
            Some(n) => vec!["--dds-network".into(), n.clone()],
            None => Vec::new(),
        };
        let mut setup =
            NodeSetup::from_args("bag_play", user).map_err(|e| NodeParamError(format!("{e:#}")))?;
        setup.shutdown = Shutdown::new().with_os_signals();
        let node = CellNode::new(setup)?;
        participant = Some(node.participant_guard());
        let bar = indicatif::ProgressBar::new(replay.messages());
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} [{bar:40}] {pos}/{len} messages, {msg} ({elapsed})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar.enable_steady_tick(std::time::Duration::from_millis(200));
        let summary = replay
            .run(&node, |p| {
                bar.set_length(p.total);
                bar.set_position(p.published);
                bar.set_message(format!(
                    "t={:.1} s{}{}",
                    p.position.as_secs_f64(),
                    if p.pass > 1 {
                        format!(", pass {}", p.pass)
                    } else {
                        String::new()
                    },
                    if p.paused {
                        ", PAUSED (/bag_play/set_paused)"
                    } else {
                        ""
                    },
                ));
            })
            .await;
        bar.finish_and_clear();
        summary
    });
    // The runtime drops the graph spinner; only then may the DDS participant go.
    drop(runtime);
    drop(participant);
    match result {
        Ok(summary) => {
            println!("cell bag play: {summary}");
            ExitCode::SUCCESS
        }
        Err(e) => fail(e),
    }
}

/// Runs a `cell bag` subcommand.
pub fn run(command: BagCommand) -> ExitCode {
    let bag = match &command {
        BagCommand::Info { bag } | BagCommand::Repair { bag } => bag,
        // The replayer names the parameter and the path itself.
        BagCommand::Play(args) => return play(args),
        BagCommand::ToRerun(args) => &args.bag,
    };
    if !bag.exists() {
        eprintln!(
            "error: {}: no such bag (a directory or .mcap file)",
            bag.display()
        );
        return ExitCode::from(cell_runtime::EXIT_USAGE);
    }
    let result = match &command {
        BagCommand::Play(args) => return play(args),
        BagCommand::ToRerun(args) => return crate::bag_rerun::run(args),
        BagCommand::Info { bag } => cell_bag::BagInfo::open(bag).map(|info| print!("{info}")),
        BagCommand::Repair { bag } => cell_bag::repair(bag).map(|report| {
            let mut repaired = 0;
            for f in report.repaired() {
                repaired += 1;
                println!(
                    "repaired {}: {} messages kept, {} bytes dropped{}",
                    f.path.display(),
                    f.messages,
                    f.dropped_bytes,
                    f.stopped
                        .as_ref()
                        .map(|(offset, why)| format!(" (cut at offset {offset}: {why})"))
                        .unwrap_or_default()
                );
            }
            if repaired == 0 {
                println!(
                    "{}: every file is complete; nothing to repair",
                    report.dir.display()
                );
            }
            println!("wrote {}", report.metadata.display());
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(cell_runtime::EXIT_DATA)
        }
    }
}
