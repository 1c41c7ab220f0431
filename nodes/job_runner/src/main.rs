fn main() -> std::process::ExitCode {
    job_runner::main(std::env::args().skip(1).collect())
}
