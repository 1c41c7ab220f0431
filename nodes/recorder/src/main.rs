fn main() -> std::process::ExitCode {
    recorder::main(std::env::args().skip(1).collect())
}
