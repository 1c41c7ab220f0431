fn main() -> std::process::ExitCode {
    slicer::main(std::env::args().skip(1).collect())
}
