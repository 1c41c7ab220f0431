fn main() -> std::process::ExitCode {
    cell_planner::node::main(std::env::args().skip(1).collect())
}
