//! `cell stream`: run a program file on one controller from the command line, without DDS,
//! through the same controller code the `machine_bridge` node uses.
//!
//! `--controller` is an id under `config/controllers` (`grbl-sim` starts the in-repo simulator)
//! or a controller YAML file. `--program` is one G-code file (`.ngc`, `.nc`, `.gcode`, …) or,
//! for an ABB controller, the RAPID modules and the `.pgf` the emitter wrote. A progress bar
//! follows the acknowledged lines; Ctrl-C (SIGINT) or SIGTERM aborts with a safe stop (hold,
//! reset, heat off) and the command exits only once the controller has reported the heat off,
//! or the message says why that could not be confirmed.
//!
//! Exit status: 0 the program ran to its end; 1 it stopped (alarm, rejected line, link lost,
//! aborted; the message names the line and, after a drop, the `--start-line` to resume from);
//! 64 a bad command line or controller file; 65 a program the controller refuses (wrong
//! dialect, a line GRBL cannot take) or that cannot be read.

use std::{path::PathBuf, process::ExitCode, time::Duration};

use cell_bridge::config::ControllerSpec;
use cell_bridge::controller::Controller;
use cell_msgs::{ExecuteProgramResult as R, MachineCommand, MachineProgram, ProgramFile};
use clap::Args;

/// `cell stream` options.
#[derive(Args, Debug)]
pub struct StreamArgs {
    /// Controller: an id under config/controllers (grbl-sim, grbl-xyuv, abb-irb2600-waam, …) or
    /// a controller YAML file.
    #[arg(long, value_name = "ID|FILE")]
    pub controller: String,
    /// Program files: one G-code file, or a RAPID program's modules and its .pgf.
    #[arg(long, value_name = "FILE", num_args = 1.., required = true)]
    pub program: Vec<PathBuf>,
    /// Original line number to start from (resuming after a stop); default: the first line.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub start_line: u32,
    /// How long to wait for the controller to answer before giving up (s).
    #[arg(long, value_name = "S", default_value_t = 30.0)]
    pub connect_timeout: f64,
}

fn exit(code: u8, message: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(code)
}

/// Reads the files into a program: RAPID when any file is a `.mod`, `.modx` or `.pgf`; else
/// G-code in `gcode_dialect` (the controller's: `grbl` or `marlin`).
fn read_program(paths: &[PathBuf], gcode_dialect: &str) -> Result<MachineProgram, String> {
    let mut files = Vec::new();
    for p in paths {
        let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| format!("{}: not a file name", p.display()))?;
        files.push(ProgramFile { name, text });
    }
    let is_rapid = |f: &ProgramFile| {
        let n = f.name.to_ascii_lowercase();
        n.ends_with(".mod") || n.ends_with(".modx") || n.ends_with(".pgf")
    };
    let rapid = files.iter().any(is_rapid);
    if !rapid && files.len() != 1 {
        return Err(format!("a G-code program is one file; got {}", files.len()));
    }
    let job_id = paths[0]
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(MachineProgram {
        job_id,
        dialect: if rapid { "rapid" } else { gcode_dialect }.into(),
        line_count: files.iter().map(|f| f.text.lines().count() as u32).sum(),
        files,
        ..MachineProgram::default()
    })
}

/// Runs `cell stream`.
pub fn run(args: StreamArgs) -> ExitCode {
    cell_runtime::logging::init(Some("warn"));
    let spec = match ControllerSpec::resolve(&args.controller) {
        Ok(s) => s,
        Err(e) => return exit(cell_runtime::EXIT_USAGE, e),
    };
    let dialect = match &spec {
        ControllerSpec::Marlin(_) => "marlin",
        _ => "grbl",
    };
    let program = match read_program(&args.program, dialect) {
        Ok(p) => p,
        Err(e) => return exit(cell_runtime::EXIT_DATA, e),
    };
    if !(args.connect_timeout.is_finite() && args.connect_timeout > 0.0) {
        return exit(cell_runtime::EXIT_USAGE, "--connect-timeout must be > 0");
    }
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => return exit(1, format!("cannot start the async runtime: {e}")),
    };
    runtime.block_on(stream(spec, program, &args))
}

async fn stream(spec: ControllerSpec, program: MachineProgram, args: &StreamArgs) -> ExitCode {
    let controller = match Controller::start(spec).await {
        Ok(c) => c,
        Err(e) => return exit(1, e),
    };
    let timeout = Duration::from_secs_f64(args.connect_timeout);
    let connected = match &controller {
        Controller::Grbl(g) => Some(g.wait_connected(timeout).await),
        Controller::Marlin(m) => Some(m.wait_connected(timeout).await),
        Controller::Rws(_) => None,
    };
    if connected == Some(false) {
        let why = controller.status().alarm;
        return exit(
            1,
            format!("{}: no answer within {timeout:?}: {why}", controller.id()),
        );
    }
    let bar = indicatif::ProgressBar::new(100);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {prefix} [{bar:40}] {pos:>3}% line {msg} ({elapsed})",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_prefix(format!("{} {}", controller.id(), program.job_id));
    let run = controller.execute(&program, args.start_line);
    tokio::pin!(run);
    let mut tick = tokio::time::interval(Duration::from_millis(100));
    let mut aborting = false;
    let mut stop_signal = std::pin::pin!(stop_signal());
    let outcome = loop {
        tokio::select! {
            outcome = &mut run => break outcome,
            _ = tick.tick() => {
                let s = controller.status();
                bar.set_position(controller.percent_done().round() as u64);
                bar.set_message(format!("{}/{}", s.acked_line, s.total_lines));
            }
            name = &mut stop_signal, if !aborting => {
                aborting = true;
                // `suspend`, not `println`: the lines must show when stderr is not a terminal
                // (the bar is hidden then, and its `println` with it).
                bar.suspend(|| eprintln!("{name}: aborting (hold, reset, heat off)"));
                let abort = MachineCommand { machine_id: controller.id().into(), command: MachineCommand::COMMAND_ABORT, value: 0 };
                match controller.command(&abort).await {
                    Ok(m) | Err(m) => bar.suspend(|| eprintln!("{m}")),
                }
            }
        }
    };
    bar.finish_and_clear();
    if outcome.success {
        println!("cell stream: {}", outcome.message);
        return ExitCode::SUCCESS;
    }
    let code = if outcome.outcome == R::OUTCOME_REFUSED {
        cell_runtime::EXIT_DATA
    } else {
        1
    };
    let mut message = outcome.message;
    if outcome.outcome == R::OUTCOME_LINK_LOST && outcome.last_acked_line > 0 {
        message.push_str(&format!(
            " (cell stream … --start-line {})",
            outcome.last_acked_line + 1
        ));
    }
    exit(code, message)
}

/// The first SIGINT (Ctrl-C) or SIGTERM; its name.
async fn stop_signal() -> &'static str {
    use tokio::signal::unix::{signal, SignalKind};
    match signal(SignalKind::terminate()) {
        Ok(mut term) => tokio::select! {
            _ = tokio::signal::ctrl_c() => "Ctrl-C",
            _ = term.recv() => "SIGTERM",
        },
        Err(_) => {
            let _ = tokio::signal::ctrl_c().await;
            "Ctrl-C"
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn programs_are_gcode_or_rapid_by_their_files() {
        let dir = tempfile::tempdir().unwrap();
        let w = |name: &str, text: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            p
        };
        let g = w("wing.ngc", "G21\nG0 X1\n");
        let p = read_program(std::slice::from_ref(&g), "grbl").unwrap();
        assert_eq!(
            (p.dialect.as_str(), p.job_id.as_str(), p.line_count),
            ("grbl", "wing", 2)
        );
        let p = read_program(std::slice::from_ref(&g), "marlin").unwrap();
        assert_eq!(
            p.dialect, "marlin",
            "a G-code file takes the controller's dialect"
        );
        let m = w("Main.mod", "MODULE Main\nENDMODULE\n");
        let f = w("Main.pgf", "<Program/>\n");
        let p = read_program(&[m, f], "grbl").unwrap();
        assert_eq!(p.dialect, "rapid");
        assert_eq!(p.files.len(), 2);
        let e = read_program(&[g.clone(), g], "grbl").unwrap_err();
        assert!(e.contains("one file"), "{e}");
        let e = read_program(&[dir.path().join("nope.ngc")], "grbl").unwrap_err();
        assert!(e.contains("nope.ngc"), "{e}");
    }
}
