//! `trajdrift restamp`: a copy of a mission with each clock domain moved onto the reference's clock.

use anyhow::{anyhow, Result};

use trajdrift::audit::report::{AuditReport, AUDIT_KIND};
use trajdrift::audit::restamp::{check_output, restamp};
use trajdrift::audit::restamp_plan::{missing_topics, parse_domain, plan};
use trajdrift::audit::{audit, AuditConfig};
use trajdrift::diag::WarningCode;

use crate::cli::args::RestampArgs;
use crate::cli::progress::ReadProgress;
use crate::cli::EXIT_WARNING;

/// Reads an audit written by `trajdrift audit --json`.
fn read_audit(path: &std::path::Path) -> Result<AuditReport> {
    let bytes = std::fs::read(path).map_err(|e| trajdrift::Error::io(path, e))?;
    let value: serde_json::Value = serde_json::from_slice(&bytes).map_err(|e| {
        anyhow!(
            "--audit {}: not JSON ({e}); give the file `trajdrift audit --json` wrote",
            path.display()
        )
    })?;
    if value.get("kind").and_then(|k| k.as_str()) != Some(AUDIT_KIND) {
        return Err(anyhow!(
            "--audit {}: not a trajdrift audit (no \"kind\": \"{AUDIT_KIND}\"); give the file `trajdrift audit --json` wrote",
            path.display()
        ));
    }
    serde_json::from_value(value).map_err(|e| {
        anyhow!(
            "--audit {}: an audit of another layout ({e}); audit the recording again",
            path.display()
        )
    })
}

/// Runs the command; returns the exit code.
pub fn run(a: RestampArgs) -> Result<u8> {
    // The --audit file and a preset file are inputs too.
    let others: Vec<&std::path::Path> = a
        .audit
        .iter()
        .map(|p| p.as_path())
        .chain(crate::cli::commands::audit::preset_file(&a.sources))
        .collect();
    check_output(&a.recording, &others, &a.out, a.force)?;
    let domains = a
        .domain
        .iter()
        .map(|d| parse_domain(d))
        .collect::<trajdrift::Result<Vec<_>>>()?;
    let total: u64 = a
        .recording
        .iter()
        .map(|p| trajdrift::sources::open::input_size(p))
        .sum();
    let report = match &a.audit {
        Some(path) => read_audit(path)?,
        None => {
            let config = AuditConfig {
                recordings: a.recording.clone(),
                request: crate::cli::commands::audit::request(&a.sources),
                params: a.params.0.clone(),
            };
            let progress = ReadProgress::new(total, a.quiet);
            let outcome = audit(&config, &|b| progress.update(b));
            progress.finish();
            let outcome = outcome?;
            if !a.quiet {
                for n in &outcome.notes {
                    eprintln!("note: {}", trajdrift::report::escape::escape(n));
                }
            }
            outcome.report
        }
    };
    let files = trajdrift::audit::discover::expand_files(&a.recording)?;
    if let Some(path) = &a.audit {
        let missing = missing_topics(&report, &files)?;
        if !missing.is_empty() {
            return Err(trajdrift::Error::InvalidArgument(format!(
                "--audit {}: an audit of another recording (its sources {} are not in the RECORDING); give the audit of this recording, or leave --audit out to audit it now",
                path.display(),
                trajdrift::report::escape::escape(&missing.join(", "))
            ))
            .into());
        }
    }
    let plan = plan(&report, &files, &domains)?;
    let progress = ReadProgress::new(total, a.quiet);
    let done = restamp(&a.recording, &report, &plan, &a.out, a.force, &|b| {
        progress.update(b)
    });
    progress.finish();
    let done = done?;
    let left_alone = plan.notes.iter().any(|n| n.contains("no confident clock"));
    for n in &plan.notes {
        eprintln!("note: {}", trajdrift::report::escape::escape(n));
    }
    if !a.quiet {
        let t0 = report.sources.first().map_or(0.0, |r| r.coverage.t_start);
        for d in &plan.domains {
            eprintln!(
                "domain {}: {} messages moved by {} ({})",
                trajdrift::report::escape::escape(&d.name),
                done.moved.get(&d.name).copied().unwrap_or(0),
                trajdrift::audit::table::describe_clock(&d.clock, t0),
                trajdrift::report::escape::escape(&d.sources.join(", "))
            );
        }
        eprintln!(
            "wrote {} ({} messages, {} moved, the audit attached)",
            done.path.display(),
            done.copy.messages,
            done.moved.values().sum::<u64>()
        );
    }
    // The copy has what the audit read: a recording cut short is said, as the audit said it.
    let truncated: Vec<_> = report
        .warnings
        .iter()
        .filter(|w| w.code == WarningCode::TruncatedRecording)
        .cloned()
        .collect();
    for w in &truncated {
        crate::cli::warn(w);
    }
    Ok(if left_alone {
        EXIT_WARNING
    } else {
        crate::cli::exit_code(&truncated)
    })
}
