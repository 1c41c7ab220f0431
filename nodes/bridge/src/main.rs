fn main() -> std::process::ExitCode {
    cell_bridge::node::main(std::env::args().skip(1).collect())
}
