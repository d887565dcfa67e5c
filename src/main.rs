//! The `trajdrift` binary: parse arguments, dispatch, print. All logic lives in the library.

mod cli;

use clap::Parser;

fn main() -> std::process::ExitCode {
    cli::run(cli::args::Cli::parse())
}
