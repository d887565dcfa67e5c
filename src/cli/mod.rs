//! The command-line edge: argument definitions, one handler per command, progress display and exit
//! codes. Results go to stdout, diagnostics to stderr.

pub mod args;
pub mod batch_progress;
pub mod commands;
pub mod progress;

use std::process::ExitCode;

use trajdrift::error::ExitStatus;
use trajdrift::report::escape::escape_line;

/// Everything went fine.
pub const EXIT_OK: u8 = ExitStatus::Ok as u8;
/// The command finished, but with a warning the user must see (weak offset, truncated recording).
pub const EXIT_WARNING: u8 = ExitStatus::Warning as u8;

/// Parses the command line, and records which `eval` flags were given (not defaults), so a preset's
/// parameters stay under them.
pub fn parse() -> args::Cli {
    use clap::parser::ValueSource;
    use clap::{CommandFactory, FromArgMatches};
    let matches = args::Cli::command().get_matches();
    let mut cli = args::Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    if let (args::Command::Eval(a), Some(("eval", m))) = (&mut cli.command, matches.subcommand()) {
        a.given = m
            .ids()
            .filter(|id| m.value_source(id.as_str()) == Some(ValueSource::CommandLine))
            .map(|id| id.to_string())
            .collect();
    }
    cli
}

/// Dispatches a parsed command line and maps the outcome to an exit code.
pub fn run(cli: args::Cli) -> ExitCode {
    let result = match cli.command {
        args::Command::Eval(a) => commands::eval::run(*a),
        args::Command::Topics(a) => commands::topics::run(a),
        args::Command::Simulate(a) => commands::simulate::run(a),
        args::Command::Batch(a) => commands::batch::run(a),
        args::Command::Merge(a) => commands::merge::run(a),
        args::Command::Export(a) => commands::export::run(a),
    };
    match result {
        Ok(code) => ExitCode::from(code),
        Err(e) if is_broken_pipe(&e) => ExitCode::from(EXIT_OK),
        Err(e) => {
            eprintln!("error: {}", message(&e));
            ExitCode::from(exit_status(&e).code())
        }
    }
}

/// The library's exit status for an error (the one exit-code type); a failure when the error did not
/// come from the library.
pub fn exit_status(e: &anyhow::Error) -> ExitStatus {
    e.chain()
        .find_map(|c| c.downcast_ref::<trajdrift::Error>())
        .map_or(ExitStatus::Failure, trajdrift::Error::exit_status)
}

/// A closed standard output (`trajdrift topics … | head`): not an error, the reader has what it wanted.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<trajdrift::Error>()
            .is_some_and(trajdrift::Error::is_broken_pipe)
            || c.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// The error chain on one line, each cause said once (a cause already in the message before it is
/// skipped), control characters from file names escaped.
pub fn message(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if !line.contains(&text) {
            if !line.is_empty() {
                line.push_str(": ");
            }
            line.push_str(&text);
        }
    }
    escape_line(&line)
}

/// Writes `text` to standard output; a closed pipe comes back as an error the dispatch ends quietly on.
pub fn emit(text: &str) -> trajdrift::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|_| out.flush())
        .map_err(|cause| trajdrift::Error::Stdout { cause })
}

/// Prints a warning line to stderr, names from files escaped.
pub fn warn(code: &str, message: &str) {
    eprintln!("warning [{code}]: {}", escape_line(message));
}
