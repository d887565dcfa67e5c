//! `trajdrift audit`: the clock map of a whole mission.

use anyhow::Result;

use trajdrift::audit::discover::SourceRequest;
use trajdrift::audit::{audit, AuditConfig};
use trajdrift::output::OutputGuard;

use crate::cli::args::{AuditArgs, SourceArgs};
use crate::cli::progress::ReadProgress;
use crate::cli::{EXIT_OK, EXIT_WARNING};

/// The library's request from the source flags.
pub fn request(a: &SourceArgs) -> SourceRequest {
    SourceRequest {
        reference: a.reference.clone(),
        sources: a.source.clone(),
        preset: a.preset.clone(),
    }
}

/// Refuses outputs over an input (a recording, a file of a mission folder, or inside that folder, a
/// preset file).
pub fn guard(recordings: &[std::path::PathBuf], sources: &SourceArgs) -> Result<OutputGuard> {
    let files = trajdrift::audit::discover::expand_files(recordings)?;
    let mut guard = OutputGuard::new(recordings.iter().chain(&files));
    if let Some(p) = preset_file(sources) {
        guard.add(p);
    }
    Ok(guard)
}

/// `--preset` when it names a file (not a built-in preset).
pub fn preset_file(a: &SourceArgs) -> Option<&std::path::Path> {
    a.preset
        .as_deref()
        .map(std::path::Path::new)
        .filter(|p| p.is_file())
}

/// Runs the command; returns the exit code.
pub fn run(a: AuditArgs) -> Result<u8> {
    let mut guard = guard(&a.recording, &a.sources)?;
    for (flag, out) in [("--json", &a.json), ("--html", &a.html)] {
        if let Some(out) = out {
            guard.claim(flag, out)?;
        }
    }
    let config = AuditConfig {
        recordings: a.recording.clone(),
        request: request(&a.sources),
        params: a.params.0.clone(),
    };
    let total: u64 = a
        .recording
        .iter()
        .map(|p| trajdrift::sources::open::input_size(p))
        .sum();
    let progress = ReadProgress::new(total, a.quiet);
    let outcome = audit(&config, &|b| progress.update(b));
    progress.finish();
    let outcome = outcome?;
    if !a.quiet {
        for n in &outcome.notes {
            eprintln!("note: {}", trajdrift::report::escape::escape(n));
        }
    }
    let report = &outcome.report;
    if let Some(path) = &a.html {
        guard.write(
            "--html",
            path,
            trajdrift::audit::html::render(report)?.as_bytes(),
        )?;
        if !a.quiet {
            eprintln!("wrote {}", path.display());
        }
    }
    let json_to_stdout = a.json.as_deref().is_some_and(|p| p.as_os_str() == "-");
    if let Some(path) = &a.json {
        trajdrift::output::write_json(path, report)?;
    }
    let table = !a.quiet && !json_to_stdout;
    if table {
        crate::cli::emit(&trajdrift::audit::table::render(report))?;
    }
    if !(table && std::io::IsTerminal::is_terminal(&std::io::stdout())) {
        for w in &report.warnings {
            crate::cli::warn(w);
        }
    }
    Ok(if report.warnings.is_empty() {
        EXIT_OK
    } else {
        EXIT_WARNING
    })
}
