//! `eval --annotate OUT.mcap`: the input recording streamed into a new MCAP with the results beside the
//! data, so Foxglove or RViz show the aligned estimate, its Drift Error windows and the curvature
//! signatures on the recording's own timeline.
//!
//! [`copy`] is the record-by-record copy pass, [`channels`] the new channels and their messages,
//! [`metadata`] the `trajdrift` metadata record and report attachment, [`input_info`] the ids and
//! compression read from the input's summary. The output is written beside OUT and renamed when complete.

pub mod any_input;
pub mod channels;
pub mod copy;
pub mod input_info;
pub mod metadata;
pub mod stamps;

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::align::curvature::{curvature_signature, CurvatureSample};
use crate::clock::ClockCorrection;
use crate::decode::message_kind;
use crate::error::{Error, Result};
use crate::eval::config::{EvalConfig, TrajectoryInput};
use crate::eval::inputs::Inputs;
use crate::output::{OutputFile, OutputGuard};
use crate::report::json::{EstimateReport, Report};
use crate::sources::Progress;
use crate::trajectory::Trajectory;
use channels::{
    AlignedSource, Annotator, Counts, CurvatureMessage, DriftErrorMessage, EstimatePlan, Plan,
};
use copy::{copy_with, CopyOutcome};
use input_info::{read_input_info, InputInfo};

/// What an annotate run wrote.
#[derive(Debug, Clone)]
pub struct AnnotateOutcome {
    pub path: PathBuf,
    pub copy: CopyOutcome,
    /// Messages written per new topic.
    pub counts: Counts,
}

/// Checks that `out` may be written for `input`: not the input itself (by path, symlink or inode:
/// [`OutputGuard`]), and not existing unless `force`.
pub fn check_output(input: &Path, out: &Path, force: bool) -> Result<()> {
    OutputGuard::new([input]).check("--annotate", out)?;
    if out.exists() && !force {
        return Err(Error::InvalidArgument(format!(
            "{}: exists; pass --force to replace it",
            out.display()
        )));
    }
    Ok(())
}

/// Checks before the evaluation runs that `--annotate out` can be written for `config`'s inputs: not
/// over any input, not existing unless `force`, and every recording one trajdrift can copy (opened
/// here, so a wrong path fails now rather than after the evaluation).
pub fn check_annotate(config: &EvalConfig, out: &Path, force: bool) -> Result<()> {
    let recordings = config.recordings();
    for input in recordings.iter().chain(text_inputs(config).iter()) {
        check_output(input, out, force)?;
        if input.is_dir() && out.starts_with(input) {
            return Err(Error::InvalidArgument(format!(
                "{}: --annotate would write inside the input folder {}; choose another output file",
                out.display(),
                input.display()
            )));
        }
    }
    let ours = channel_topics(config)?;
    if recordings.is_empty() {
        check_output(Path::new(""), out, force)?;
    } else {
        let source = crate::sources::open_all(&recordings)?;
        if let Some(t) = source
            .topics()?
            .into_iter()
            .find(|t| ours.contains(&t.topic))
        {
            return Err(Error::InvalidArgument(format!(
                "--annotate: the recording already holds the channel {} (an annotated copy?); annotate the original recording",
                crate::report::escape::escape(&t.topic)
            )));
        }
    }
    Ok(())
}

/// The channels the annotated copy adds (`/trajdrift/reference/curvature`, and per estimate
/// `/trajdrift/<name>/aligned`, `drift_error`, `curvature`), refused when two coincide: an estimate
/// named `reference` would double the reference's curvature channel.
pub fn channel_topics(config: &EvalConfig) -> Result<Vec<String>> {
    let mut topics = vec![channels::topic("reference", "curvature")];
    for e in &config.estimates {
        for what in ["aligned", "drift_error", "curvature"] {
            let t = channels::topic(&e.name, what);
            if topics.contains(&t) {
                return Err(Error::InvalidArgument(format!(
                    "--annotate: estimate `{}` would write the channel {t}, which another channel of the annotated recording takes; name it with --estimate NAME=TOPIC",
                    crate::report::escape::escape(&e.name),
                    t = crate::report::escape::escape(&t)
                )));
            }
            topics.push(t);
        }
    }
    Ok(topics)
}

/// The text files among the inputs (never to be overwritten either).
fn text_inputs(config: &EvalConfig) -> Vec<PathBuf> {
    std::iter::once(&config.reference)
        .chain(&config.estimates)
        .filter_map(|i| match &i.input {
            TrajectoryInput::TumFile(p) => Some(p.clone()),
            TrajectoryInput::Topic(_) => None,
        })
        .collect()
}

/// The one input that is copied record by record (keeping its ids, attachments and metadata): a
/// single MCAP file.
fn single_mcap(recordings: &[PathBuf]) -> Option<&Path> {
    match recordings {
        [one] if !one.is_dir() && crate::sources::mcap::McapSource::open(one).is_ok() => {
            Some(one.as_path())
        }
        _ => None,
    }
}

/// Writes the annotated copy of the evaluated inputs to `out`: every input message (of one MCAP file,
/// a ROS 1 bag, a rosbag2 folder or a mission of several) plus the trajdrift channels; with text
/// inputs only, the trajdrift channels alone. `report` and `inputs` come from
/// [`crate::eval::evaluate_with_inputs`] with `config`.
pub fn annotate(
    config: &EvalConfig,
    report: &Report,
    inputs: &Inputs,
    out: &Path,
    force: bool,
    progress: Progress<'_>,
) -> Result<AnnotateOutcome> {
    check_annotate(config, out, force)?;
    let recordings = config.recordings();
    let plan = plan(config, report, inputs);
    let mcap_input = single_mcap(&recordings);
    let recording = match (mcap_input, recordings.is_empty()) {
        (None, false) => Some(
            crate::sources::open::open_recording(&recordings[0]).and_then(
                |first| match recordings.len() {
                    1 => Ok(first),
                    _ => {
                        let mut parts = vec![first];
                        for p in &recordings[1..] {
                            parts.push(crate::sources::open::open_recording(p)?);
                        }
                        Ok(Box::new(crate::sources::mission::Mission::new(
                            &recordings[0],
                            parts,
                        )?) as crate::sources::mission::Part)
                    }
                },
            )?,
        ),
        _ => None,
    };
    let (info, profile) = match (mcap_input, &recording) {
        (Some(path), _) => (read_input_info(path), String::new()),
        (None, Some(rec)) => {
            let (channels, _) = rec.channel_counts()?;
            let info = InputInfo {
                schema_ids: (1..=u16::try_from(channels.len()).unwrap_or(u16::MAX)).collect(),
                channel_ids: channels.iter().map(|c| c.id).collect(),
                compression: None,
            };
            (info, any_input::profile(&channels).to_string())
        }
        (None, None) => (InputInfo::default(), String::new()),
    };
    let schema_ids = InputInfo::free_ids(&info.schema_ids, 3);
    let channel_ids = InputInfo::free_ids(&info.channel_ids, 1 + 3 * plan.estimates.len());
    let mut annotator = Annotator::new(out.to_path_buf(), plan, &schema_ids, &channel_ids)?;
    let options = mcap::WriteOptions::new()
        .compression(info.output_compression())
        .library(concat!("trajdrift ", env!("CARGO_PKG_VERSION")));
    let copy = write_atomically(out, |file| match mcap_input {
        Some(path) => copy_with(path, file, out, options, &mut annotator, progress),
        None => any_input::copy_recording(
            recording
                .as_deref()
                .map_or(any_input::CopyInput::Nothing, |r| {
                    any_input::CopyInput::One(r as &dyn crate::sources::recording::Recording)
                }),
            file,
            out,
            options,
            &profile,
            &mut annotator,
            progress,
        ),
    })?;
    Ok(AnnotateOutcome {
        path: out.to_path_buf(),
        copy,
        counts: annotator.counts(),
    })
}

/// Writes `out` through `write` with the one file writer ([`OutputFile`]: a regular file through a
/// temporary file beside it, synced and renamed when complete, removed on failure; a device written
/// through).
fn write_atomically(
    out: &Path,
    write: impl FnOnce(
        std::io::BufWriter<std::fs::File>,
    ) -> Result<(CopyOutcome, std::io::BufWriter<std::fs::File>)>,
) -> Result<CopyOutcome> {
    let out_err = |e: std::io::Error| Error::output(out, &e);
    let mut target = OutputFile::create(out)?;
    let file = target.file().try_clone().map_err(out_err)?;
    let (outcome, mut sink) = write(std::io::BufWriter::new(file))?;
    sink.flush().map_err(out_err)?;
    drop(sink);
    target.commit()?;
    Ok(outcome)
}

fn curvature_messages(traj: &Trajectory, config: &EvalConfig) -> Vec<(u64, CurvatureMessage)> {
    let t0 = traj.stamps_ns.first().copied().unwrap_or(0);
    let sig: Vec<CurvatureSample> = curvature_signature(
        &traj.times_s(t0),
        &traj.positions,
        &config.curvature_params(),
    );
    sig.iter()
        .filter_map(|s| {
            let stamp = *traj.stamps_ns.get(s.index)?;
            Some((
                u64::try_from(stamp).ok()?,
                CurvatureMessage {
                    t: stamp as f64 * 1e-9,
                    curvature: s.curvature,
                    signed_curvature: s.signed_curvature(),
                    turn_rad: s.turn_rad,
                },
            ))
        })
        .collect()
}

/// What to add, from the evaluation's results.
fn plan(config: &EvalConfig, report: &Report, inputs: &Inputs) -> Plan {
    let estimates = inputs
        .estimates
        .iter()
        .filter_map(|est| {
            let r = report.estimates.iter().find(|r| r.name == est.name)?;
            let shift = ClockCorrection::from_report(&r.time_offset);
            let aligned = shift.apply(&est.trajectory);
            let topic = config.estimates.iter().find_map(|e| match &e.input {
                TrajectoryInput::Topic(t) if e.name == est.name => Some(t.clone()),
                _ => None,
            });
            Some(EstimatePlan {
                name: est.name.clone(),
                shift,
                curvature: curvature_messages(&aligned, config),
                drift_error: drift_error_messages(r),
                aligned: match topic {
                    // A TF chain (`/tf:PARENT:CHILD`) has no message of its own to patch: it is
                    // written as PoseStamped from its samples, like a TUM file.
                    Some(t)
                        if message_kind(&est.type_name).is_some()
                            && crate::sources::tf_chain::parse_chain_topic(&t).is_none() =>
                    {
                        AlignedSource::PatchTopic(t)
                    }
                    _ => AlignedSource::Generate(aligned),
                },
            })
        })
        .collect();
    Plan {
        reference_curvature: curvature_messages(&inputs.reference.trajectory, config),
        estimates,
        report: report.clone(),
        stamp: config.params.stamp(),
    }
}

/// One message per Drift Error window, at the window's end.
fn drift_error_messages(r: &EstimateReport) -> Vec<(u64, DriftErrorMessage)> {
    r.drift_error
        .iter()
        .flat_map(|d| {
            d.per_window.iter().map(move |w| {
                (
                    (w.t_end * 1e9).round().max(0.0) as u64,
                    DriftErrorMessage {
                        window_m: d.window_m,
                        t_start: w.t_start,
                        t_end: w.t_end,
                        ref_length_m: w.ref_length_m,
                        est_length_m: w.est_length_m,
                        alpha: w.alpha,
                        de: w.de,
                    },
                )
            })
        })
        .collect()
}
