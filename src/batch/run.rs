//! Runs the missions of a batch in parallel (a rayon pool of `--jobs` threads). Each mission streams its
//! recording like `eval`, so memory is bounded by the largest mission's samples times the jobs. A
//! failing mission is recorded with its error and the others go on. Results do not depend on `--jobs`:
//! every mission is computed alone and the summary is built in name order.

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;

use super::identity::{BatchLock, Fingerprint, RunRecord, RunStatus};
use super::manifest::{Manifest, MissionSpec};
use super::shard::Shard;
use super::summary::{MissionResult, Summary, Timing, MISSION_KIND};
use super::summary_files::{self, SUMMARY_STEM};
use crate::error::{Error, Result};
use crate::job::{self, JobEvent, JobOutputs, Pass};
use crate::output::{write_json, OutputGuard};

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
    /// Keep the result of a mission already done instead of running it again: only one that is `ok`,
    /// computed with the same parameters from the same inputs, with every output asked for present.
    pub skip_existing: bool,
    pub shard: Option<Shard>,
    /// Per-mission figures (`<mission>_figures/`, in this format) and/or `<mission>.html`.
    pub pictures: MissionPictures,
    /// The files the missions were found from (the manifest, or the folder of recordings): no output
    /// may be one of them or lie inside the folder.
    pub inputs: Vec<PathBuf>,
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

/// The largest per-mission result read back (a two-hour mission's result is a few megabytes).
pub const MAX_RESULT_BYTES: u64 = 256 << 20;

/// The result of `m` kept from an earlier run, when it can be reused: it parses, it is `ok`, it was
/// computed with the same parameters from the same inputs (its [`Fingerprint`] matches the mission as
/// it is now), and every output asked for now (annotated recording, figures, HTML page) is there.
fn previous(opts: &BatchOptions, m: &MissionSpec, now: &Fingerprint) -> Option<MissionResult> {
    let bytes = crate::sources::input::read_bounded(
        &result_path(&opts.out_dir, &m.name),
        MAX_RESULT_BYTES,
        "mission result",
    )
    .ok()?;
    let r: MissionResult = serde_json::from_slice(&bytes).ok()?;
    let same = r.fingerprint.as_ref() == Some(now) && now.inputs.is_some();
    let outputs = (!opts.annotate
        || r.annotated.is_some() && opts.out_dir.join(format!("{}.mcap", m.name)).is_file())
        && (opts.pictures.plot.is_none()
            || opts.out_dir.join(format!("{}_figures", m.name)).is_dir())
        && (!opts.pictures.html || opts.out_dir.join(format!("{}.html", m.name)).is_file());
    (r.kind == MISSION_KIND && r.status == "ok" && r.mission == m.name && same && outputs)
        .then_some(r)
}

/// Missions at once: `--jobs` (0: the number of cores), never more than the missions to run nor four
/// threads a core (more would only compete for the same cores and memory).
pub fn effective_jobs(requested: usize, missions: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let asked = if requested == 0 { cores } else { requested };
    asked.min(missions).min(4 * cores).max(1)
}

/// Runs the batch and writes every per-mission result, the run record and the summary into
/// `opts.out_dir`. Every output is claimed before any mission runs; the folder is locked for the run.
pub fn run_batch(
    manifest: &Manifest,
    opts: &BatchOptions,
    progress: BatchProgress<'_>,
) -> Result<BatchOutcome> {
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
    let mut guard = input_guard(manifest, opts);
    guard.claim_dir("--out", &opts.out_dir)?;
    std::fs::create_dir_all(&opts.out_dir).map_err(|e| Error::output(&opts.out_dir, &e))?;
    let _lock = BatchLock::acquire(&opts.out_dir, opts.shard)?;
    crate::output::remove_all_stale_temps(&opts.out_dir);
    let mut results = Vec::new();
    let mut skipped = Vec::new();
    let mut todo = Vec::new();
    for m in &selected {
        let now = Fingerprint::of(&m.config);
        match opts
            .skip_existing
            .then(|| previous(opts, m, &now))
            .flatten()
        {
            Some(r) => {
                skipped.push(m.name.clone());
                results.push(r);
            }
            None => todo.push((*m, now)),
        }
    }
    claim_outputs(&mut guard, &selected, opts)?;
    check_existing(&todo, opts)?;
    let all: Vec<(&str, &crate::eval::config::EvalConfig)> = manifest
        .missions
        .iter()
        .map(|m| (m.name.as_str(), &m.config))
        .collect();
    let selected_names: Vec<&str> = selected.iter().map(|m| m.name.as_str()).collect();
    let mut record = RunRecord::new(&all, opts.shard, &selected_names);
    let record_path = opts.out_dir.join(RunRecord::file_name(opts.shard));
    write_json(&record_path, &record)?;
    progress(BatchEvent::Planned {
        missions: todo.len(),
    });
    let jobs = effective_jobs(opts.jobs, todo.len());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::InvalidArgument(format!("--jobs {jobs}: {e}")))?;
    let ran: Vec<Result<MissionResult>> = pool.install(|| {
        todo.par_iter()
            .map(|(m, fingerprint)| run_mission(m, fingerprint, opts, progress))
            .collect()
    });
    for r in ran {
        results.push(r?);
    }
    results.sort_by(|a, b| a.mission.cmp(&b.mission));
    let summary = Summary::build(&results);
    match opts.shard {
        Some(shard) => summary_files::write(&summary, &opts.out_dir, &shard.summary_stem())?,
        None => summary_files::write(&summary, &opts.out_dir, SUMMARY_STEM)?,
    }
    record.status = RunStatus::Complete;
    write_json(&record_path, &record)?;
    Ok(BatchOutcome {
        results,
        skipped,
        summary,
    })
}

/// Every input of the batch: each mission's files and folders, and the manifest or folder it came from.
fn input_guard(manifest: &Manifest, opts: &BatchOptions) -> OutputGuard {
    let mut guard = OutputGuard::new(manifest.missions.iter().flat_map(|m| {
        let mut v = m.config.input_paths();
        v.extend(m.config.more_recordings.iter().cloned());
        v
    }));
    for p in &opts.inputs {
        guard.add(p);
    }
    guard
}

/// Claims, before any mission runs, every file this run writes into `--out`: each mission's result
/// (and annotated recording, figures, HTML page), the summaries and the run record. Refused (exit 2)
/// when one is an input or when two of them are one file — a mission named `summary` would take the
/// summary's name, two estimates mapping to one figure name would overwrite each other.
fn claim_outputs(
    guard: &mut OutputGuard,
    selected: &[&MissionSpec],
    opts: &BatchOptions,
) -> Result<()> {
    let stem = opts
        .shard
        .map_or_else(|| SUMMARY_STEM.to_string(), |s| s.summary_stem());
    for path in summary_files::paths(&opts.out_dir, &stem) {
        guard.claim("the batch summary", &path)?;
    }
    guard.claim(
        "the run record",
        &opts.out_dir.join(RunRecord::file_name(opts.shard)),
    )?;
    for m in selected {
        let who = format!("mission `{}`", m.name);
        guard.claim(&who, &result_path(&opts.out_dir, &m.name))?;
        if opts.annotate {
            guard.claim(&who, &opts.out_dir.join(format!("{}.mcap", m.name)))?;
            crate::annotate::channel_topics(&m.config)
                .map_err(|e| Error::InvalidArgument(format!("mission {}: {e}", m.name)))?;
        }
        let names: Vec<&str> = m.config.estimates.iter().map(|e| e.name.as_str()).collect();
        opts.pictures
            .outputs(&opts.out_dir, &m.name)
            .claim(guard, &names)
            .map_err(|e| match e {
                Error::InvalidArgument(msg) => {
                    Error::InvalidArgument(format!("mission {}: {msg}", m.name))
                }
                e => e,
            })?;
        m.config.claim_outputs(guard)?;
    }
    Ok(())
}

/// Refuses (exit 2, before any work) a run that would replace an existing annotated recording without
/// `--force`: the mission would fail after its evaluation and its good result turn into a failure.
fn check_existing(todo: &[(&MissionSpec, Fingerprint)], opts: &BatchOptions) -> Result<()> {
    if !opts.annotate || opts.force {
        return Ok(());
    }
    let existing: Vec<String> = todo
        .iter()
        .map(|(m, _)| opts.out_dir.join(format!("{}.mcap", m.name)))
        .filter(|p| p.exists())
        .map(|p| p.display().to_string())
        .collect();
    if existing.is_empty() {
        return Ok(());
    }
    Err(Error::InvalidArgument(format!(
        "{} exist{}; pass --force to replace {}, or --skip-existing to keep the missions already done",
        existing.join(", "),
        if existing.len() == 1 { "s" } else { "" },
        if existing.len() == 1 { "it" } else { "them" }
    )))
}

/// Runs one mission and writes `<mission>.json`; only a failure to write that file is an `Err`.
fn run_mission(
    m: &MissionSpec,
    fingerprint: &Fingerprint,
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
    let outputs = JobOutputs {
        annotate: opts.annotate.then(|| opts.out_dir.join(&mcap_name)),
        force: opts.force,
        pictures: opts.pictures.outputs(&opts.out_dir, &m.name),
    };
    let outcome = job::run(&m.config, &outputs, &|event| {
        if let JobEvent::Read { pass, bytes } = event {
            // The annotation pass reads the recording a second time: its bytes come after the first's.
            let before = if pass == Pass::Annotate { size } else { 0 };
            progress(BatchEvent::Read {
                mission: &m.name,
                bytes: before + bytes,
            })
        }
    })
    .map(|done| done.report);
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
        fingerprint: Some(fingerprint.clone()),
        report,
        timing: Timing {
            seconds: start.elapsed().as_secs_f64(),
        },
    };
    write_json(&result_path(&opts.out_dir, &m.name), &result)?;
    Ok(result)
}
