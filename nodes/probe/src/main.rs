fn main() -> std::process::ExitCode {
    probe::main(std::env::args().skip(1).collect())
}
