fn main() -> std::process::ExitCode {
    planner::main(std::env::args().skip(1).collect())
}
