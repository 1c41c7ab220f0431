fn main() -> std::process::ExitCode {
    monitor::main(std::env::args().skip(1).collect())
}
