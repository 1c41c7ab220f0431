fn main() -> std::process::ExitCode {
    cell_recorder::main(std::env::args().skip(1).collect())
}
