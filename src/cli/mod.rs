//! The command-line edge: argument definitions, one handler per command, progress display and exit
//! codes. Results go to stdout, diagnostics to stderr.

pub mod allocator;
pub mod args;
pub mod batch_progress;
pub mod commands;
pub mod evo_args;
pub mod evo_config;
pub mod evo_log;
pub mod progress;

use trajdrift::error::ExitStatus;
use trajdrift::report::escape::escape_line;

/// Everything went fine.
pub const EXIT_OK: u8 = ExitStatus::Ok as u8;
/// The command finished, but with a warning the user must see (weak offset, truncated recording).
pub const EXIT_WARNING: u8 = ExitStatus::Warning as u8;

/// Runs the command line `args` (the program name first) and returns its exit code: what the
/// `trajdrift` binary does, callable in process (the Python package's `trajdrift` command). A usage
/// error prints clap's message and returns 2; `--help` and `--version` print and return 0.
pub fn main_with_args(args: Vec<std::ffi::OsString>) -> u8 {
    use clap::Parser;
    match args::Cli::try_parse_from(evo_config::expand(args)) {
        Ok(cli) => run(cli),
        Err(e) if e.use_stderr() => {
            eprintln!("{}", usage_error_line(&e.render().to_string()));
            e.exit_code().clamp(0, 255) as u8
        }
        Err(e) => {
            let _ = e.print();
            e.exit_code().clamp(0, 255) as u8
        }
    }
}

/// clap's usage error (`error: …`, its tips and the arguments it lists, a blank line, the usage,
/// "For more information…") as the one line every error of the project is: the message, what clap
/// listed or suggested after it, and the command whose `--help` says more.
fn usage_error_line(rendered: &str) -> String {
    let mut parts: Vec<&str> = Vec::new();
    let mut command = "trajdrift".to_string();
    for line in rendered.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if let Some(usage) = line.strip_prefix("Usage: ") {
            let words: Vec<&str> = usage
                .split_whitespace()
                .take_while(|w| !w.starts_with(['[', '<', '-']))
                .collect();
            if !words.is_empty() {
                command = words.join(" ");
            }
        } else if !line.starts_with("For more information") {
            parts.push(line);
        }
    }
    let mut text = parts
        .first()
        .copied()
        .unwrap_or("error: invalid usage")
        .to_string();
    for (i, p) in parts.iter().enumerate().skip(1) {
        text.push_str(if i == 1 && text.ends_with(':') {
            " "
        } else {
            "; "
        });
        text.push_str(p);
    }
    format!("{text}; see `{command} --help`")
}

/// Dispatches a parsed command line and maps the outcome to an exit code.
pub fn run(cli: args::Cli) -> u8 {
    let result = match cli.command {
        args::Command::Eval(a) => commands::eval::run(*a),
        args::Command::Topics(a) => commands::topics::run(a),
        args::Command::Audit(a) => commands::audit::run(*a),
        args::Command::Restamp(a) => commands::restamp::run(*a),
        args::Command::Simulate(a) => commands::simulate::run(a),
        args::Command::Batch(a) => commands::batch::run(*a),
        args::Command::Merge(a) => commands::merge::run(a),
        args::Command::Export(a) => commands::export::run(a),
        args::Command::Sweep(a) => commands::sweep::run(*a),
        args::Command::Ape(a) => commands::ape::run(*a),
        args::Command::Rpe(a) => commands::rpe::run(*a),
        args::Command::Offset(a) => commands::offset::run(*a),
        args::Command::Man(a) => commands::man::run(a),
        args::Command::Completions(a) => commands::completions::run(a),
        args::Command::Res(a) => commands::res::run(*a),
        args::Command::Traj(a) => commands::traj::run(*a),
        args::Command::Validate(a) => commands::validate::run(*a),
    };
    match result {
        Ok(code) => code,
        Err(e) if is_broken_pipe(&e) => EXIT_OK,
        Err(e) => {
            eprintln!("error: {}", message(&e));
            exit_status(&e).code()
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
pub fn warn(w: &trajdrift::diag::Warning) {
    eprintln!("{}", escape_line(&warning_line(w)));
}

/// A warning as its one line, `warning [code]: message`, not yet escaped (for [`warn`] and evo's log).
pub fn warning_line(w: &trajdrift::diag::Warning) -> String {
    format!("warning [{}]: {}", w.code, w.message)
}

/// The exit code of a command that finished: [`EXIT_WARNING`] when it has a warning the user must
/// see (a recording cut short, a weak offset), else [`EXIT_OK`].
pub fn exit_code(warnings: &[trajdrift::diag::Warning]) -> u8 {
    ExitStatus::from_warnings(!warnings.is_empty()).code()
}
