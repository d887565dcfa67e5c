//! `trajdrift batch`: evaluate the missions of a manifest (or a folder of recordings) in parallel.

use anyhow::{anyhow, Result};

use trajdrift::batch::manifest::{FolderRequest, Manifest};
use trajdrift::batch::run::{run_batch, BatchOptions, MissionPictures};
use trajdrift::batch::shard::Shard;

use trajdrift::report::escape::escape;

use crate::cli::args::{BatchArgs, PlotFormatArg};
use crate::cli::batch_progress::BatchBars;

/// Runs the command; returns the exit code, as `eval`'s: 1 when a mission failed, else 3 when a mission
/// finished with a warning (the summary says which), else 0.
pub fn run(a: BatchArgs) -> Result<u8> {
    let manifest = if a.input.is_dir() {
        if a.reference.is_none() && a.preset.is_none() {
            return Err(trajdrift::Error::InvalidArgument(format!(
                "{}: a folder needs --reference TOPIC and --estimate TOPIC, or --preset NAME",
                a.input.display()
            ))
            .into());
        }
        if a.estimate.is_empty() && a.preset.is_none() {
            return Err(trajdrift::Error::InvalidArgument(format!(
                "{}: a folder needs --estimate TOPIC (repeatable)",
                a.input.display()
            ))
            .into());
        }
        let request = FolderRequest {
            reference: a.reference.clone(),
            estimates: a.estimate.clone(),
            preset: a.preset.clone(),
            parameters: a.params.0.clone(),
        };
        Manifest::from_dir(&a.input, &request)?
    } else {
        if a.reference.is_some() || !a.estimate.is_empty() || a.preset.is_some() {
            return Err(trajdrift::Error::InvalidArgument(
                "--reference/--estimate/--preset are for a folder of recordings; a manifest names them per mission".into(),
            )
            .into());
        }
        Manifest::from_toml(&a.input, &a.params.0)?
    };
    let shard = match a.shard.as_deref() {
        Some(spec) => Some(Shard::resolve(spec, a.shards, &|v| std::env::var(v).ok())?),
        None if a.shards.is_some() => {
            return Err(trajdrift::Error::InvalidArgument(
                "--shards N goes with --shard auto".into(),
            )
            .into())
        }
        None => None,
    };
    let opts = BatchOptions {
        out_dir: a.out.clone(),
        jobs: a.jobs.unwrap_or(0),
        annotate: a.annotate,
        force: a.force,
        skip_existing: a.skip_existing,
        shard,
        pictures: MissionPictures {
            plot: a.plot.then_some(match a.plot_format {
                PlotFormatArg::Svg => trajdrift::plot::PlotFormat::Svg,
                PlotFormatArg::Png => trajdrift::plot::PlotFormat::Png,
            }),
            html: a.html,
        },
        inputs: vec![a.input.clone()],
    };
    let bars = BatchBars::new(a.quiet);
    let outcome = run_batch(&manifest, &opts, &|e| bars.event(e));
    bars.finish();
    let outcome = outcome.map_err(|e| anyhow!(e))?;
    let s = &outcome.summary;
    for f in &s.failed {
        eprintln!(
            "error: mission {}: {}",
            escape(&f.mission),
            escape(&f.error)
        );
    }
    for w in &s.warned {
        for r in outcome.results.iter().filter(|r| r.mission == w.mission) {
            for warning in r.report.iter().flat_map(|r| &r.warnings) {
                crate::cli::warn(&trajdrift::diag::Warning {
                    code: warning.code,
                    message: format!("mission {}: {}", w.mission, warning.message),
                });
            }
        }
    }
    if !a.quiet {
        crate::cli::emit(&s.to_markdown())?;
        eprintln!(
            "{} missions ({} kept from an earlier run), {} failed; results in {}",
            s.missions,
            outcome.skipped.len(),
            s.failed.len(),
            a.out.display()
        );
    }
    Ok(s.exit_code())
}
