fn main() -> std::process::ExitCode {
    cell_monitor::main(std::env::args().skip(1).collect())
}
