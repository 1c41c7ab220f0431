fn main() -> std::process::ExitCode {
    cell_replayer::main(std::env::args().skip(1).collect())
}
