fn main() -> std::process::ExitCode {
    cell_sequencer::node::main(std::env::args().skip(1).collect())
}
