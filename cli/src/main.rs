//! The `ilopt` binary: see `ilopt --help` and the README.
fn main() -> std::process::ExitCode {
    ilopt_cli::main()
}
