fn main() -> std::process::ExitCode {
    machine_bridge::main(std::env::args().skip(1).collect())
}
