//! Runs the missions of a batch in parallel (a rayon pool of `--jobs` threads). Each mission streams its
//! recording like `eval`, so memory is bounded by the largest mission's samples times the jobs. A
//! failing mission is recorded with its error and the others go on. Results do not depend on `--jobs`:
//! every mission is computed alone and the summary is built in name order.

use crate::plot::Trajectories;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;

use super::manifest::{Manifest, MissionSpec};
use super::shard::Shard;
use super::summary::{MissionResult, Summary, Timing, MISSION_KIND};
use crate::annotate::annotate;
use crate::error::{Error, Result};
use crate::eval::evaluate_with_inputs;
use crate::output::{write_output, OutputGuard};

/// How to run a batch.
#[derive(Debug, Clone)]
pub struct BatchOptions {
    /// Where `<mission>.json`, `<mission>.mcap` and the summary go.
    pub out_dir: PathBuf,
    /// Missions at once (0 = the number of cores).
    pub jobs: usize,
    /// Also write `<mission>.mcap`, the annotated recording.
    pub annotate: bool,
    /// Replace existing annotated recordings.
    pub force: bool,
    /// Keep the result of a mission already done (its JSON says `ok`, and its `.mcap` exists with
    /// `--annotate`) instead of running it again.
    pub skip_existing: bool,
    pub shard: Option<Shard>,
    /// Per-mission figures (`<mission>_figures/`, in this format) and/or `<mission>.html`.
    pub pictures: MissionPictures,
}

/// What pictures each mission gets (`batch --plot [--plot-format F] --html`).
#[derive(Debug, Clone, Copy, Default)]
pub struct MissionPictures {
    pub plot: Option<crate::plot::PlotFormat>,
    pub html: bool,
}

impl MissionPictures {
    fn outputs(&self, out_dir: &Path, mission: &str) -> crate::plot::PictureOutputs {
        crate::plot::PictureOutputs {
            plot_dir: self
                .plot
                .map(|_| out_dir.join(format!("{mission}_figures"))),
            format: self.plot,
            html: self.html.then(|| out_dir.join(format!("{mission}.html"))),
        }
    }
}

/// What a running batch reports, for a progress display.
#[derive(Debug, Clone, Copy)]
pub enum BatchEvent<'a> {
    /// The batch will run `missions` missions (after shard and skip).
    Planned { missions: usize },
    /// A mission started; `bytes` is what it will read in all (two passes with `--annotate`).
    Started { mission: &'a str, bytes: u64 },
    /// Bytes read so far by a mission.
    Read { mission: &'a str, bytes: u64 },
    /// A mission ended.
    Finished { mission: &'a str, ok: bool },
}

/// Receives [`BatchEvent`]s from every worker thread.
pub type BatchProgress<'a> = &'a (dyn Fn(BatchEvent<'_>) + Sync);

/// What a batch did.
#[derive(Debug, Clone)]
pub struct BatchOutcome {
    /// Every mission of the run (shard) in name order, including those kept by `skip_existing`.
    pub results: Vec<MissionResult>,
    /// Missions kept from an earlier run.
    pub skipped: Vec<String>,
    pub summary: Summary,
}

/// The result file of a mission.
pub fn result_path(out_dir: &Path, mission: &str) -> PathBuf {
    out_dir.join(format!("{mission}.json"))
}

fn previous(opts: &BatchOptions, m: &MissionSpec) -> Option<MissionResult> {
    let text = std::fs::read(result_path(&opts.out_dir, &m.name)).ok()?;
    let r: MissionResult = serde_json::from_slice(&text).ok()?;
    let mcap_ok = !opts.annotate || opts.out_dir.join(format!("{}.mcap", m.name)).exists();
    (r.kind == MISSION_KIND && r.status == "ok" && r.mission == m.name && mcap_ok).then_some(r)
}

/// Runs the batch and writes every per-mission result and the summary into `opts.out_dir`.
pub fn run_batch(
    manifest: &Manifest,
    opts: &BatchOptions,
    progress: BatchProgress<'_>,
) -> Result<BatchOutcome> {
    std::fs::create_dir_all(&opts.out_dir).map_err(|e| Error::Output {
        path: opts.out_dir.clone(),
        detail: e.to_string(),
    })?;
    let names: Vec<&str> = manifest.missions.iter().map(|m| m.name.as_str()).collect();
    let keep = opts
        .shard
        .map_or_else(|| vec![true; names.len()], |s| s.select(&names));
    let selected: Vec<&MissionSpec> = manifest
        .missions
        .iter()
        .zip(keep)
        .filter_map(|(m, k)| k.then_some(m))
        .collect();
    let mut results = Vec::new();
    let mut skipped = Vec::new();
    let mut todo = Vec::new();
    for m in selected {
        match opts.skip_existing.then(|| previous(opts, m)).flatten() {
            Some(r) => {
                skipped.push(m.name.clone());
                results.push(r);
            }
            None => todo.push(m),
        }
    }
    check_outputs(&todo, opts)?;
    progress(BatchEvent::Planned {
        missions: todo.len(),
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.jobs)
        .build()
        .map_err(|e| Error::InvalidArgument(format!("--jobs {}: {e}", opts.jobs)))?;
    let ran: Vec<Result<MissionResult>> = pool.install(|| {
        todo.par_iter()
            .map(|m| run_mission(m, opts, progress))
            .collect()
    });
    for r in ran {
        results.push(r?);
    }
    results.sort_by(|a, b| a.mission.cmp(&b.mission));
    let summary = Summary::build(&results);
    match opts.shard {
        Some(shard) => summary.write_as(&opts.out_dir, &shard.summary_stem())?,
        None => summary.write(&opts.out_dir)?,
    }
    Ok(BatchOutcome {
        results,
        skipped,
        summary,
    })
}

/// Refuses the batch (a usage error) when an output it would write is one of a mission's inputs:
/// `<mission>.json`, `<mission>.mcap`, the summaries, or an `--export-aligned` file.
fn check_outputs(todo: &[&MissionSpec], opts: &BatchOptions) -> Result<()> {
    let all = OutputGuard::new(todo.iter().flat_map(|m| m.config.input_paths()));
    for name in ["summary.json", "summary.csv", "summary.md"] {
        all.check("--out", &opts.out_dir.join(name))?;
    }
    for m in todo {
        all.check("--out", &result_path(&opts.out_dir, &m.name))?;
        if opts.annotate {
            all.check("--annotate", &opts.out_dir.join(format!("{}.mcap", m.name)))?;
        }
        m.config.check_outputs()?;
    }
    Ok(())
}

/// Runs one mission and writes `<mission>.json`; only a failure to write that file is an `Err`.
fn run_mission(
    m: &MissionSpec,
    opts: &BatchOptions,
    progress: BatchProgress<'_>,
) -> Result<MissionResult> {
    let start = Instant::now();
    let size: u64 = m
        .config
        .recordings()
        .iter()
        .map(|p| crate::sources::open::input_size(p))
        .sum();
    let passes = if opts.annotate { 2 } else { 1 };
    progress(BatchEvent::Started {
        mission: &m.name,
        bytes: size * passes,
    });
    let mcap_name = format!("{}.mcap", m.name);
    let outcome = (|| -> Result<_> {
        // The annotated recording's aligned poses carry the estimate's orientation.
        let config = crate::eval::config::EvalConfig {
            keep_orientations: opts.annotate,
            ..m.config.clone()
        };
        let (report, inputs) = evaluate_with_inputs(&config, &|b| {
            progress(BatchEvent::Read {
                mission: &m.name,
                bytes: b,
            })
        })?;
        let estimates = inputs.named_estimates();
        let trajectories = Trajectories {
            reference: &inputs.reference.trajectory,
            estimates: &estimates,
        };
        opts.pictures
            .outputs(&opts.out_dir, &m.name)
            .write(&report, trajectories)?;
        if opts.annotate {
            annotate(
                &m.config,
                &report,
                &inputs,
                &opts.out_dir.join(&mcap_name),
                opts.force,
                &|b| {
                    progress(BatchEvent::Read {
                        mission: &m.name,
                        bytes: size + b,
                    })
                },
            )?;
        }
        Ok(report)
    })();
    progress(BatchEvent::Finished {
        mission: &m.name,
        ok: outcome.is_ok(),
    });
    let recording = m
        .config
        .recording
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    let (status, error, report) = match outcome {
        Ok(r) => ("ok", None, Some(r)),
        Err(e) => ("failed", Some(e.to_string()), None),
    };
    let result = MissionResult {
        kind: MISSION_KIND.into(),
        mission: m.name.clone(),
        recording,
        status: status.into(),
        error,
        annotated: (opts.annotate && report.is_some()).then_some(mcap_name),
        report,
        timing: Timing {
            seconds: start.elapsed().as_secs_f64(),
        },
    };
    let path = result_path(&opts.out_dir, &m.name);
    let mut bytes = serde_json::to_vec_pretty(&result).map_err(|e| Error::Output {
        path: path.clone(),
        detail: e.to_string(),
    })?;
    bytes.push(b'\n');
    write_output(&path, &bytes)?;
    Ok(result)
}
