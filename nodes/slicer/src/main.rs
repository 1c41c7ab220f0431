fn main() -> std::process::ExitCode {
    cell_slicer::node::main(std::env::args().skip(1).collect())
}
