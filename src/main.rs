//! The `cell` binary; see [`cellsuite`].

fn main() -> std::process::ExitCode {
    cellsuite::main(std::env::args().collect())
}
