fn main() -> std::process::ExitCode {
    cell_probe::main(std::env::args().skip(1).collect())
}
