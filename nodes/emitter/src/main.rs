fn main() -> std::process::ExitCode {
    cell_emitter::node::main(std::env::args().skip(1).collect())
}
