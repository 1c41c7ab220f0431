fn main() -> std::process::ExitCode {
    cell_runner::main(std::env::args().skip(1).collect())
}
