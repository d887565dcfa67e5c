//! `trajdrift merge`: the summary of a batch from the per-mission results of several folders (the
//! shards of a cluster run), checked first: an incomplete or inconsistent set is said by name and
//! exits 1, unless `--allow-partial`.

use anyhow::Result;

use trajdrift::batch::merge::read_set;
use trajdrift::batch::summary::Summary;
use trajdrift::batch::summary_files::{self, SUMMARY_STEM};
use trajdrift::output::OutputGuard;
use trajdrift::report::escape::escape;

use crate::cli::args::MergeArgs;

/// Runs the command; returns the batch's exit code (1 when the set is incomplete or a mission failed,
/// else 3 when a mission finished with a warning or the summary is partial).
pub fn run(a: MergeArgs) -> Result<u8> {
    let set = read_set(&a.dirs)?;
    for p in &set.skipped {
        if !a.quiet {
            eprintln!(
                "note: {}: not a trajdrift result, skipped",
                escape(&p.display().to_string())
            );
        }
    }
    for p in &set.problems {
        eprintln!("error: merge: {}", escape(p));
    }
    if !set.problems.is_empty() && !a.allow_partial {
        eprintln!(
            "error: merge: the set is incomplete or inconsistent ({} problem{}); nothing written (pass --allow-partial to merge it anyway, marked partial)",
            set.problems.len(),
            if set.problems.len() == 1 { "" } else { "s" }
        );
        return Ok(1);
    }
    let mut summary = Summary::build(&set.results);
    summary.partial = !set.problems.is_empty();
    summary.problems = set.problems.clone();
    let out = a.out.clone().unwrap_or_else(|| a.dirs[0].clone());
    // The summary never replaces a file it was built from.
    let mut guard = OutputGuard::new(&set.files);
    guard.claim_dir("--out", &out)?;
    for path in summary_files::paths(&out, SUMMARY_STEM) {
        guard.claim("the summary", &path)?;
    }
    std::fs::create_dir_all(&out).map_err(|e| trajdrift::Error::output(&out, &e))?;
    summary_files::write(&summary, &out, SUMMARY_STEM)?;
    if !a.quiet {
        crate::cli::emit(&summary.to_markdown())?;
    }
    for f in &summary.failed {
        eprintln!(
            "error: mission {}: {}",
            escape(&f.mission),
            escape(&f.error)
        );
    }
    Ok(summary.exit_code())
}
