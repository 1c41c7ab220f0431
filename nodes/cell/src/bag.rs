//! `cell bag info BAG`, `cell bag repair BAG` and `cell bag to-rerun BAG`: rosbag2 MCAP bags
//! without DDS, through [`cell_bag`].
//!
//! - `info` prints topics, types, counts, duration, size and files, like `ros2 bag info`.
//! - `to-rerun` converts a bag into a Rerun recording (see [`crate::bag_rerun`]).
//! - `repair` restores a bag whose writer was killed: every file is cut after its last complete
//!   chunk and rewritten with a summary (the original kept as `*.orig`), and `metadata.yaml` is
//!   regenerated.
//!
//! Exit status: 0 done; 64 a bad command line or a path that does not exist; 65 a bag that
//! cannot be read (truncated, corrupted, unfinished: the message names the file and offset, and
//! for an unfinished bag says to run `cell bag repair`).

use std::{path::PathBuf, process::ExitCode};

use clap::Subcommand;

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
    /// Convert a bag into a Rerun recording drawn like the live nodes' (toolpaths, heat maps
    /// and exposure scalars, machine traces, programs; see `cell_cli::bag_rerun`), with a
    /// summary per topic. Messages of unknown types are counted and skipped.
    ToRerun(crate::bag_rerun::ToRerunArgs),
}

/// Runs a `cell bag` subcommand.
pub fn run(command: BagCommand) -> ExitCode {
    let bag = match &command {
        BagCommand::Info { bag } | BagCommand::Repair { bag } => bag,
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
