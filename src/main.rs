//! The `cell` binary; see [`cell_cli`].

fn main() -> std::process::ExitCode {
    cell_cli::main(std::env::args().collect())
}
