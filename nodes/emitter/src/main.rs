fn main() -> std::process::ExitCode {
    emitter::main(std::env::args().skip(1).collect())
}
