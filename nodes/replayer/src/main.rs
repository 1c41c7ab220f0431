fn main() -> std::process::ExitCode {
    replayer::main(std::env::args().skip(1).collect())
}
