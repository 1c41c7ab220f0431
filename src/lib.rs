//! The `cell` command.
//!
//! - `cell launch FILE [NAME:=VALUE …]` starts the nodes of a ROS 2 YAML launch file and
//!   supervises them (see [`cell_launch`]).
//! - `cell demo` runs the demo cell from `launch_scripts/demo.launch.yaml` (embedded in the
//!   binary, so it works from any directory): a hot-wire wing planned, emitted and streamed to
//!   the GRBL simulator, then a sheet nest sequenced, emitted and run on a GRBL laser simulator,
//!   a WAAM part sliced and run on the RWS simulator, and a G-Wing section's first layers
//!   printed on the Marlin simulator; the programs, the bag, `cell.rrd` and `bag.rrd` in
//!   `demo-out/`.
//! - `cell node EXEC [ARGS…]` runs one of the nodes built into `cell`, exactly as its own binary
//!   would. Launch files fall back to this, so `cargo run -- demo` needs no other binaries.
//! - `cell hotwire --airfoil NAME|FILE --chord MM --out DIR [--profile NAME]` plans one hot-wire
//!   cut on the spot (no DDS) and writes `trajectory.csv`, `report.json`, `toolpath.json`,
//!   `exposure.svg` and, with `--profile`, the machine program (see [`hotwire`]).
//! - `cell emit --toolpath FILE --profile NAME --out FILE` turns a toolpath file into a machine
//!   program on the spot (see [`emit`]).
//! - `cell sheet --layout FILE.dxf|json --out DIR [--policy …]` sequences the cut of a nested
//!   sheet on the spot (no DDS) and writes `plan.json`, `program.ngc` and `report.json` (see
//!   [`sheet`]).
//! - `cell wing --config FILE --out DIR` designs a G-Wing wing and writes one extrusion
//!   program per printable section and `report.json` (see [`wing`]).
//! - `cell slice --stl FILE --process waam|FILE.yaml --out DIR [--layer-height MM]` slices a
//!   part for WAAM on the spot (no DDS) and writes `layers.json`, the RAPID program,
//!   `report.json` and `stock.stl` (see [`mod@slice`]).
//! - `cell stream --controller ID|FILE --program FILE…` runs a program file on one controller
//!   with a progress bar, through the machine bridge's controller code, without DDS (see
//!   [`stream`]).
//! - `cell machine status|hold|resume|abort|override [--machine ID]` talks to a running
//!   `machine_bridge` node over DDS: its status topic and its command service (see [`machine`]).
//! - `cell bag info BAG`, `cell bag repair BAG`, `cell bag to-rerun BAG --out FILE.rrd`:
//!   rosbag2 MCAP bags (see [`bag`] and, for the Rerun conversion, [`bag_rerun`]); `cell bag
//!   play BAG` republishes one over DDS with its recorded timing.

pub mod bag;
pub mod bag_rerun;
pub mod emit;
pub mod exit;
pub mod hotwire;
pub mod machine;
pub mod rrd;
pub mod sheet;
pub mod sim_process;
pub mod slice;
pub mod stream;
pub mod wing;

use std::{path::PathBuf, process::ExitCode};

use cell_launch::{
    default_resolver, supervise, LaunchFile, Program, StopOthersWhen, SupervisorOptions,
};
use clap::{Parser, Subcommand};

/// The demo cell's launch file, as shipped in `launch_scripts/`.
pub const DEMO_LAUNCH: &str = include_str!("../launch_scripts/demo.launch.yaml");

/// A node `cell` can run itself: its exec name and its `main`.
type BuiltinMain = fn(Vec<String>) -> ExitCode;

/// Nodes built into `cell`, by the exec name launch files use.
pub const BUILTIN_NODES: &[(&str, BuiltinMain)] = &[
    ("probe", probe::main),
    ("monitor", monitor::main),
    ("planner", planner::main),
    ("sequencer", sequencer::main),
    ("slicer", slicer::main),
    ("emitter", emitter::main),
    ("machine_bridge", machine_bridge::main),
    ("job_runner", job_runner::main),
    ("recorder", recorder::main),
    ("replayer", replayer::main),
];

#[derive(Parser, Debug)]
#[command(
    name = "cell",
    version,
    about = "cellsuite: plan, program, stream and watch a thermal manufacturing cell"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Start the nodes of a ROS 2 YAML launch file and supervise them.
    Launch {
        /// The launch file (`launch: - node: {pkg, exec, name, namespace, param, remap}`).
        file: PathBuf,
        /// Launch arguments, `NAME:=VALUE`, overriding the file's `arg` defaults.
        #[arg(value_name = "NAME:=VALUE")]
        args: Vec<String>,
    },
    /// Run the demo cell: a hot-wire wing planned, emitted for the 4-axis GRBL cutter and
    /// streamed to the in-repo GRBL simulator, then a sheet nest sequenced and cut on a GRBL
    /// laser simulator, a WAAM part sliced and run on the RWS simulator, and the first layers
    /// of a G-Wing section printed on the Marlin simulator (`wing_layers:=N`), with a summary
    /// table at the end. Writes the
    /// programs, the bag of every topic, `cell.rrd` (every node's Rerun log in one recording)
    /// and `bag.rrd` (the bag drawn) to --out, and lists them last.
    Demo {
        /// Output directory: the programs, the bag (`bag/`, drawn into `bag.rrd`),
        /// `rrd/<node>.rrd` and the merged `cell.rrd`.
        #[arg(long, default_value = "demo-out")]
        out: PathBuf,
        /// Rerun output for every node: `save` (into --out, merged into cell.rrd), `off`,
        /// `save:DIR` (one .rrd per node in DIR) or `connect:HOST:PORT`.
        #[arg(long, default_value = "save")]
        rerun: String,
        /// Use this launch file instead of the built-in demo (e.g.
        /// launch_scripts/probe.launch.yaml, the wiring check).
        #[arg(long)]
        file: Option<PathBuf>,
        /// The node whose exit ends the run (the others are then stopped).
        #[arg(long, default_value = "job_runner")]
        until: String,
        /// Further launch arguments, `NAME:=VALUE` (e.g. `iterations:=2000`).
        #[arg(value_name = "NAME:=VALUE")]
        args: Vec<String>,
    },
    /// Plan one hot-wire cut without DDS: write DIR/trajectory.csv, DIR/report.json,
    /// DIR/toolpath.json, DIR/exposure.svg (the paths and the exposure per panel before and
    /// after) and, with --profile, the machine program (DIR/program.ngc).
    Hotwire(Box<hotwire::HotwireArgs>),
    /// Turn a toolpath file (JSON, e.g. from `cell hotwire`) into a machine program without
    /// DDS. Exit status: 64 bad arguments or profile, 65 a toolpath the emitter refuses (no
    /// file is written), 1 the output cannot be written.
    Emit(emit::EmitArgs),
    /// Sequence the cut of a nested sheet (DXF or JSON layout) without DDS: write
    /// DIR/plan.json, DIR/program.ngc and DIR/report.json. Exit status: 64 bad arguments or
    /// profile, 65 a bad layout (named file and entity or field), 1 the output cannot be
    /// written.
    Sheet(sheet::SheetArgs),
    /// Design a wing for material extrusion (G-Wing: lifting line, spars, sections) from a spec
    /// such as config/wings/gwing-table2.yaml and write one program per printable section
    /// (Marlin by default) and DIR/report.json (mass, build time). Exit status: 64 bad
    /// arguments or profile, 65 a bad spec (named file and field), 1 the output cannot be
    /// written.
    Wing(wing::WingArgs),
    /// Slice a part (STL) for wire-arc additive manufacturing without DDS, with a progress bar
    /// per layer: write DIR/layers.json, the RAPID program (DIR/WAAM_<job>.mod and .pgf),
    /// DIR/report.json (layers, contours, deposited volume, times, cost breakdown) and
    /// DIR/stock.stl. Exit status: 64 bad arguments or profile, 65 a bad mesh or process file
    /// (named), 1 the output cannot be written.
    Slice(slice::SliceArgs),
    /// Run a program file on one controller (GRBL, Marlin or ABB RWS) without DDS, with a
    /// progress bar; Ctrl-C aborts with a safe stop. `--controller grbl-sim` (or `marlin-sim`)
    /// starts the in-repo simulator. Exit status: 0 ran to its end, 1 stopped (alarm, bad
    /// line, link lost, aborted), 64 bad arguments or controller file, 65 a program the
    /// controller refuses.
    Stream(stream::StreamArgs),
    /// Watch or stop a running machine_bridge node (its machine_status topic and its
    /// machine_command service) without the ROS 2 command line: `cell machine status
    /// [--follow]`, `cell machine hold|resume|abort [--machine ID]`, `cell machine override
    /// --feed|--spindle PCT`. Reach a bridge in a namespace with `--ros-args -r __ns:=/cell`
    /// last on the line; the domain is ROS_DOMAIN_ID's. Exit status: 0 done, 1 the bridge
    /// refused or has no such controller, 64 bad arguments, 69 no bridge found or no answer
    /// within --timeout.
    #[command(subcommand)]
    Machine(machine::MachineAction),
    /// Inspect, repair, convert or play a rosbag2 MCAP bag: `cell bag info BAG`, `cell bag
    /// repair BAG`, `cell bag to-rerun BAG --out FILE.rrd`, `cell bag play BAG`. Exit status: 64
    /// bad arguments, no such path or an output that cannot be written, 65 a bag that cannot be
    /// read.
    #[command(subcommand)]
    Bag(bag::BagCommand),
    /// Run a node built into `cell` (as launch files do when no separate binary is installed).
    Node {
        /// The node's exec name.
        exec: String,
        /// The node's arguments, `--ros-args …` included.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

/// Finds a launch file's exec: a node built into this binary first (always the same build as
/// `cell` itself), then a program beside `cell` or on `$PATH`.
pub fn resolve_exec(pkg: &str, exec: &str) -> Option<Program> {
    if BUILTIN_NODES.iter().any(|(name, _)| *name == exec) {
        if let Ok(me) = std::env::current_exe() {
            return Some(Program {
                program: me,
                leading_args: vec!["node".into(), exec.into()],
            });
        }
    }
    default_resolver(pkg, exec)
}

/// Runs `cell` with `argv` (program name included) and returns its exit status.
pub fn main(argv: Vec<String>) -> ExitCode {
    let cli = match Cli::try_parse_from(argv) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(cell_runtime::EXIT_USAGE)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    match cli.command {
        Command::Node { exec, args } => {
            match BUILTIN_NODES.iter().find(|(name, _)| *name == exec) {
                Some((_, node_main)) => node_main(args),
                None => {
                    let known: Vec<_> = BUILTIN_NODES.iter().map(|(n, _)| *n).collect();
                    eprintln!(
                        "error: cell node: no built-in node {exec:?} (built in: {})",
                        known.join(", ")
                    );
                    ExitCode::from(cell_runtime::EXIT_USAGE)
                }
            }
        }
        Command::Hotwire(args) => hotwire::run(*args),
        Command::Emit(args) => emit::run(args),
        Command::Sheet(args) => sheet::run(args),
        Command::Wing(args) => wing::run(args),
        Command::Slice(args) => slice::run(args),
        Command::Stream(args) => stream::run(args),
        Command::Machine(action) => machine::run(action),
        Command::Bag(command) => bag::run(command),
        Command::Launch { file, args } => run_launch(LaunchSource::File(file), args, None),
        Command::Demo {
            out,
            rerun,
            file,
            until,
            mut args,
        } => {
            let rrd_dir = out.join("rrd");
            let rerun = match rerun.split_once(':') {
                _ if rerun == "save" => {
                    format!("save:{}", rrd_dir.join("{node}.rrd").display())
                }
                Some(("save", dir)) => {
                    format!("save:{}", PathBuf::from(dir).join("{node}.rrd").display())
                }
                _ => rerun,
            };
            let merge = rerun.starts_with(&format!("save:{}", rrd_dir.display()));
            if let Err(e) = std::fs::create_dir_all(&out) {
                eprintln!("error: --out {}: {e}", out.display());
                return ExitCode::from(cell_runtime::EXIT_USAGE);
            }
            // The recorder starts a fresh bag; the last run's is kept one run longer.
            let bag = out.join("bag");
            if bag.exists() {
                let previous = out.join("bag.previous");
                let _ = std::fs::remove_dir_all(&previous);
                if let Err(e) = std::fs::rename(&bag, &previous) {
                    eprintln!(
                        "error: cannot move the last bag aside to {}: {e}",
                        previous.display()
                    );
                    return ExitCode::from(1);
                }
            }
            args.insert(0, format!("rerun:={rerun}"));
            let source = match file {
                Some(path) => LaunchSource::File(path),
                None => {
                    args.insert(1, format!("out:={}", out.display()));
                    LaunchSource::Embedded
                }
            };
            let status = run_launch(source, args, Some(StopOthersWhen::Node(until)));
            let mut outputs = DemoOutputs::default();
            if merge {
                let cell_rrd = out.join("cell.rrd");
                match rrd::merge_dir(&rrd_dir, &cell_rrd) {
                    Ok(n) => outputs.rows.push((
                        "rerun",
                        format!(
                            "{} ({n} Rerun messages from every node)",
                            cell_rrd.display()
                        ),
                    )),
                    Err(e) => eprintln!("error: {}: {e:#}", cell_rrd.display()),
                }
            }
            // The recorder has finished the bag by now (it stops with the other nodes).
            if bag.exists() {
                outputs.add_bag(&bag, &out.join("bag.rrd"), &out);
            }
            print!("{outputs}");
            status
        }
    }
}

/// The table `cell demo` prints last: what it wrote, one row per file.
#[derive(Debug, Default)]
struct DemoOutputs {
    /// (kind, description) rows.
    rows: Vec<(&'static str, String)>,
}

impl DemoOutputs {
    /// Adds the bag (from its summary), its conversion to `bag_rrd` and the program files the
    /// bag's `MachineProgram`s name that the emitter wrote into `out`. A bag that cannot be
    /// read or converted is reported as an error line; the run's status stays the nodes'.
    fn add_bag(&mut self, bag: &std::path::Path, bag_rrd: &std::path::Path, out: &std::path::Path) {
        match cell_bag::BagInfo::open(bag) {
            // First: the bag is the run's record; the rest is drawn from it or beside it.
            Ok(info) => self.rows.insert(
                0,
                (
                    "bag",
                    format!(
                        "{}: {} topics, {} messages, {} (`cell bag info {0}`)",
                        bag.display(),
                        info.topics.len(),
                        info.message_count,
                        cell_bag::reader::human_size(info.size)
                    ),
                ),
            ),
            Err(e) => {
                eprintln!("error: {e}");
                return;
            }
        }
        let options = bag_rerun::ConvertOptions {
            // Not the nodes' run id: the bag's entities would merge into theirs in a viewer.
            recording_id: format!("cell-{}-bag", std::process::id()),
            progress: false,
        };
        match bag_rerun::convert(bag, bag_rrd, &options) {
            Ok(report) => {
                self.rows.push((
                    "rerun",
                    format!(
                        "{} (the bag drawn: {} messages converted, {} skipped)",
                        bag_rrd.display(),
                        report.converted(),
                        report.skipped()
                    ),
                ));
                for program in &report.programs {
                    let path = out.join(&program.file);
                    if path.is_file() {
                        self.rows.push((
                            "program",
                            format!(
                                "{} (job {}, {} lines)",
                                path.display(),
                                program.job_id,
                                program.lines
                            ),
                        ));
                    }
                }
            }
            Err(e) => eprintln!("error: {}: {e}", bag_rrd.display()),
        }
    }
}

impl std::fmt::Display for DemoOutputs {
    /// `cell: outputs` and a table in the style of job_runner's summary.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.rows.is_empty() {
            return Ok(());
        }
        writeln!(f, "cell: outputs")?;
        writeln!(f, "| output  | file |")?;
        writeln!(f, "|---------|------|")?;
        for (kind, text) in &self.rows {
            writeln!(f, "| {kind:<7} | {text} |")?;
        }
        Ok(())
    }
}

enum LaunchSource {
    File(PathBuf),
    Embedded,
}

fn run_launch(source: LaunchSource, args: Vec<String>, stop: Option<StopOthersWhen>) -> ExitCode {
    cell_runtime::logging::init(None);
    let fail = |e: &dyn std::fmt::Display| {
        eprintln!("error: {e}");
        ExitCode::from(cell_runtime::EXIT_USAGE)
    };
    let mut pairs = Vec::new();
    for a in &args {
        match cell_launch::parse_launch_arg(a) {
            Ok(pair) => pairs.push(pair),
            Err(e) => return fail(&e),
        }
    }
    let file = match &source {
        LaunchSource::File(path) => LaunchFile::load(path, &pairs),
        LaunchSource::Embedded => {
            LaunchFile::parse(DEMO_LAUNCH, "launch_scripts/demo.launch.yaml", &pairs)
        }
    };
    if let (LaunchSource::Embedded, Ok(f)) = (&source, &file) {
        if let Some(iterations) = f.args.iter().find(|a| a.name == "iterations") {
            println!(
                "cell demo: planning with {} PSO iterations per wing section, reduced so the demo \
                 takes a minute or two on two cores (seed 000 runs 8000: add iterations:=8000)",
                iterations.value
            );
        }
    }
    let plan = match file.and_then(|f| f.plan(resolve_exec)) {
        Ok(plan) => plan,
        Err(e) => return fail(&e),
    };
    // One id for every node's Rerun recording, so a viewer shows the run as one.
    let run_id = format!("cell-{}", std::process::id());
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => return fail(&format!("cannot start the async runtime: {e}")),
    };
    let options = SupervisorOptions {
        stop_others_when: stop,
        ..Default::default()
    };
    let plan: Vec<_> = plan
        .into_iter()
        .map(|mut node| {
            node.env.push(("CELL_RUN_ID".into(), run_id.clone()));
            node
        })
        .collect();
    let started = std::time::Instant::now();
    match runtime.block_on(supervise(plan, options)) {
        Ok(summary) => {
            let nodes: Vec<String> = summary
                .nodes
                .iter()
                .map(|n| {
                    let status = n.status.map_or("unknown".to_string(), |s| s.to_string());
                    format!(
                        "{} ({status}, {:.1} s{})",
                        n.label,
                        n.runtime.as_secs_f64(),
                        if n.stopped { ", stopped" } else { "" }
                    )
                })
                .collect();
            let verdict = if summary.is_success() { "ok" } else { "FAILED" };
            println!(
                "cell: {verdict} after {:.1} s: {}",
                started.elapsed().as_secs_f64(),
                nodes.join(", ")
            );
            if let cell_launch::Outcome::Failed { message, .. } = &summary.outcome {
                eprintln!("error: {message}");
            }
            ExitCode::from(summary.exit_code().clamp(0, 255) as u8)
        }
        Err(e) => fail(&e),
    }
}
