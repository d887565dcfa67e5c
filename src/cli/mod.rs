//! The command-line edge: argument definitions, one handler per command, progress display and exit
//! codes. Results go to stdout, diagnostics to stderr.

pub mod args;
pub mod batch_progress;
pub mod commands;
pub mod progress;

use std::process::ExitCode;

/// Everything went fine.
pub const EXIT_OK: u8 = 0;
/// The command failed (bad input, I/O error).
pub const EXIT_FAILURE: u8 = 1;
/// The command line or a parameter value is wrong.
pub const EXIT_USAGE: u8 = 2;
/// The command finished, but with a warning the user must see (weak offset, truncated recording).
pub const EXIT_WARNING: u8 = 3;

/// Parses the command line (clap exits with code 2 and its message on a usage error).
pub fn parse() -> args::Cli {
    use clap::Parser;
    args::Cli::parse()
}

/// Dispatches a parsed command line and maps the outcome to an exit code.
pub fn run(cli: args::Cli) -> ExitCode {
    let result = match cli.command {
        args::Command::Eval(a) => commands::eval::run(*a),
        args::Command::Topics(a) => commands::topics::run(a),
        args::Command::Simulate(a) => commands::simulate::run(a),
        args::Command::Batch(a) => commands::batch::run(*a),
        args::Command::Merge(a) => commands::merge::run(a),
        args::Command::Export(a) => commands::export::run(a),
        args::Command::Sweep(a) => commands::sweep::run(*a),
        args::Command::Ape(a) => commands::ape::run(*a),
        args::Command::Rpe(a) => commands::rpe::run(*a),
        args::Command::Offset(a) => commands::offset::run(*a),
    };
    match result {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            eprintln!("error: {e:#}");
            let usage = matches!(
                e.downcast_ref::<trajdrift::Error>(),
                Some(trajdrift::Error::InvalidArgument(_))
            );
            ExitCode::from(if usage { EXIT_USAGE } else { EXIT_FAILURE })
        }
    }
}
