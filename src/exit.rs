//! How the one-shot commands end: one `error: …` line on stderr and the exit status that says
//! whose fault it was (sysexits: 64 the command line, 65 the input data, 1 anything else).

use std::process::ExitCode;

/// A bad command line: prints the message, exit status 64.
pub fn usage(message: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(cell_runtime::EXIT_USAGE)
}

/// Input data that cannot be used (the message names the file): exit status 65.
pub fn bad_data(message: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(cell_runtime::EXIT_DATA)
}

/// Anything else (an output that cannot be written): exit status 1.
pub fn failure(message: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::FAILURE
}
