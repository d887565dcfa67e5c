//! `trajdrift batch`: evaluate the missions of a manifest (or a folder of recordings) in parallel.

use anyhow::{anyhow, Result};

use trajdrift::batch::manifest::{FolderRequest, Manifest};
use trajdrift::batch::run::{run_batch, BatchOptions, BatchOutcome, MissionPictures};
use trajdrift::batch::shard::Shard;

use trajdrift::report::escape::escape;

use crate::cli::args::{BatchArgs, PlotFormatArg};
use crate::cli::batch_progress::BatchBars;

/// `batch --audit`: every mission audited; the summary lists each mission's clock domains and the
/// sources out of line.
fn run_audit(a: &BatchArgs) -> Result<u8> {
    use trajdrift::audit::discover::SourceRequest;
    use trajdrift::batch::audit::{from_manifest, missions_in, run_audit_batch};
    if a.annotate || a.plot || a.shard.is_some() || a.skip_existing {
        return Err(trajdrift::Error::InvalidArgument(
            "--audit runs with --out, --jobs, --html, --reference, --estimate, --preset and the evaluation parameters; not with --annotate, --plot, --shard or --skip-existing".into(),
        )
        .into());
    }
    let missions = if a.input.is_dir() {
        let request = SourceRequest {
            reference: a.reference.clone(),
            sources: a.estimate.clone(),
            preset: a.preset.clone(),
        };
        missions_in(&a.input, &request, &a.params.0)?
    } else {
        from_manifest(&Manifest::from_toml(&a.input, &a.params.0)?)
    };
    let bars = BatchBars::new(a.quiet);
    let summary = run_audit_batch(&missions, &a.out, a.jobs.unwrap_or(0), a.html, &|e| {
        bars.event(e)
    });
    bars.finish();
    let summary = summary.map_err(|e| anyhow!(e))?;
    for m in &summary.missions {
        if let Some(e) = &m.error {
            eprintln!("error: mission {}: {}", m.mission, e);
        }
    }
    if !a.quiet {
        crate::cli::emit(&summary.to_markdown())?;
        eprintln!(
            "{} missions audited, {} failed; results in {}",
            summary.missions.len(),
            summary
                .missions
                .iter()
                .filter(|m| m.status != trajdrift::batch::audit::MissionStatus::Ok)
                .count(),
            a.out.display()
        );
    }
    Ok(summary.exit_code())
}

/// Runs the command; returns the exit code, as `eval`'s: 1 when a mission failed, else 3 when a mission
/// finished with a warning (the summary says which), else 0.
pub fn run(a: BatchArgs) -> Result<u8> {
    if a.audit {
        return run_audit(&a);
    }
    let manifest = manifest_from_args(&a)?;
    let opts = options_from_args(&a)?;
    let bars = BatchBars::new(a.quiet);
    let outcome = run_batch(&manifest, &opts, &|e| bars.event(e));
    bars.finish();
    let outcome = outcome.map_err(|e| anyhow!(e))?;
    report(&a, &outcome)?;
    Ok(outcome.summary.exit_code())
}

/// The missions: a folder of recordings with `--reference`/`--estimate` or `--preset`, or a
/// manifest (which names them per mission).
fn manifest_from_args(a: &BatchArgs) -> Result<Manifest> {
    if a.input.is_dir() {
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
        return Ok(Manifest::from_dir(&a.input, &request)?);
    }
    if a.reference.is_some() || !a.estimate.is_empty() || a.preset.is_some() {
        return Err(trajdrift::Error::InvalidArgument(
            "--reference/--estimate/--preset are for a folder of recordings; a manifest names them per mission".into(),
        )
        .into());
    }
    Ok(Manifest::from_toml(&a.input, &a.params.0)?)
}

/// How to run: the output folder, jobs, shard, annotated recordings and pictures.
fn options_from_args(a: &BatchArgs) -> Result<BatchOptions> {
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
    Ok(BatchOptions {
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
        // The manifest or folder, and a preset file.
        inputs: std::iter::once(a.input.clone())
            .chain(
                a.preset
                    .iter()
                    .map(std::path::PathBuf::from)
                    .filter(|p| p.is_file()),
            )
            .collect(),
    })
}

/// Each failed mission and each warning on stderr; the summary table and one line on stdout.
fn report(a: &BatchArgs, outcome: &BatchOutcome) -> Result<()> {
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
    Ok(())
}
