//! The `trajdrift` binary: parse arguments, dispatch, print. All logic lives in the library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::run(cli::parse())
}
