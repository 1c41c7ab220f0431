fn main() -> std::process::ExitCode {
    sequencer::main(std::env::args().skip(1).collect())
}
