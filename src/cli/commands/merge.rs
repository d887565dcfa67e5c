//! `trajdrift merge`: the summary of a batch from the per-mission results of several folders (the
//! shards of a cluster run).

use anyhow::Result;

use trajdrift::batch::summary::{read_results, Summary};

use crate::cli::args::MergeArgs;

/// Runs the command; returns the batch's exit code (1 when a mission failed, else 3 when an offset was
/// weak).
pub fn run(a: MergeArgs) -> Result<u8> {
    let results = read_results(&a.dirs)?;
    let summary = Summary::build(&results);
    let out = a.out.clone().unwrap_or_else(|| a.dirs[0].clone());
    std::fs::create_dir_all(&out).map_err(|e| trajdrift::Error::Output {
        path: out.clone(),
        detail: e.to_string(),
    })?;
    summary.write(&out)?;
    if !a.quiet {
        crate::cli::emit(&summary.to_markdown())?;
    }
    for f in &summary.failed {
        eprintln!("error: mission {}: {}", f.mission, f.error);
    }
    Ok(summary.exit_code())
}
