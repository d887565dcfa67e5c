//! Loads the reference and the estimates of an evaluation: one streaming pass over the recording for
//! every requested topic, TUM files read directly.

use std::path::Path;

use crate::error::{Error, Result};
use crate::eval::config::{EvalConfig, LeverSpec, NamedInput, TrajectoryInput};
use crate::sources::text::{read_text_audited, TextOptions};
use crate::sources::tf_chain::parse_chain_topic;
use crate::sources::{ExtractOptions, Extraction, Progress, Warning};
use crate::trajectory::rows::RowAudit;
use crate::trajectory::Trajectory;

/// A trajectory with what the report says about its origin.
#[derive(Debug, Clone)]
pub struct Loaded {
    pub name: String,
    /// Topic or file.
    pub label: String,
    pub type_name: String,
    pub trajectory: Trajectory,
    pub dropped_samples: u64,
    /// Rows read, dropped per reason, stamps going back.
    pub rows: RowAudit,
    pub geodetic_origin: Option<[f64; 3]>,
    /// Its lever arm (`--reference-lever` / `--estimate-lever`), `tf-static:` ones resolved.
    pub lever_m: Option<[f64; 3]>,
}

impl Loaded {
    /// The same input holding `trajectory` instead (its stamps mapped, its samples thinned).
    pub fn with_trajectory(&self, trajectory: Trajectory) -> Loaded {
        Loaded {
            name: self.name.clone(),
            label: self.label.clone(),
            type_name: self.type_name.clone(),
            trajectory,
            dropped_samples: self.dropped_samples,
            rows: self.rows,
            geodetic_origin: self.geodetic_origin,
            lever_m: self.lever_m,
        }
    }
}

/// Everything an evaluation reads.
#[derive(Debug, Clone)]
pub struct Inputs {
    pub reference: Loaded,
    pub estimates: Vec<Loaded>,
    pub warnings: Vec<Warning>,
    /// The input reported in `input.path` and its size.
    pub path: String,
    pub bytes: u64,
}

impl Inputs {
    /// The estimates by name, with their trajectories (what the figures are drawn from, with the
    /// reference's [`Loaded::trajectory`]).
    pub fn named_estimates(&self) -> Vec<(&str, &Trajectory)> {
        self.estimates
            .iter()
            .map(|e| (e.name.as_str(), &e.trajectory))
            .collect()
    }
}

/// The estimate topics whose orientations nothing in this evaluation reads: the default Drift Error,
/// APE (translation part) and RPE point distance need positions only, and RPE's translation part and
/// KITTI drift need the reference's orientation too, so a reference without one (PointStamped,
/// NavSatFix: the usual GNSS, prism or total station) makes the estimate's useless. Kept for levers
/// (moved through the body frame), the aligned export and the annotated recording, the pose fit of
/// `--offset-method auto` (see [`crate::align::pose_fit`]), and whenever the reference's type is
/// unknown before the pass. Half of what a 200 Hz odometry costs in memory.
fn positions_only(config: &EvalConfig, source: &dyn crate::sources::Source) -> Vec<String> {
    let pose_fit = config.pose_fit();
    let needed_elsewhere = config.keep_orientations
        || pose_fit
        || config.export_aligned.is_some()
        || config.reference_lever.is_some()
        || !config.estimate_levers.is_empty();
    let reference_oriented = match &config.reference.input {
        TrajectoryInput::Topic(t) => source
            .indexed_type(t)
            .and_then(|ty| crate::decode::message_kind(&ty))
            .is_none_or(|k| k.has_orientation()),
        TrajectoryInput::TumFile(_) => true,
    };
    let read_by_metrics =
        (config.params.metric_set().rpe || config.params.metric_set().kitti) && reference_oriented;
    if needed_elsewhere || read_by_metrics {
        return Vec::new();
    }
    config
        .estimates
        .iter()
        .filter_map(|e| match &e.input {
            TrajectoryInput::Topic(t) if *t != topic_name(&config.reference.input) => {
                Some(t.clone())
            }
            _ => None,
        })
        .collect()
}

/// The topic of an input ("" for a file).
fn topic_name(input: &TrajectoryInput) -> String {
    match input {
        TrajectoryInput::Topic(t) => t.clone(),
        TrajectoryInput::TumFile(_) => String::new(),
    }
}

/// Reads every input of `config`.
pub fn load(config: &EvalConfig, progress: Progress<'_>) -> Result<Inputs> {
    let all: Vec<&NamedInput> = std::iter::once(&config.reference)
        .chain(&config.estimates)
        .collect();
    let topics: Vec<String> = all
        .iter()
        .filter_map(|i| match &i.input {
            TrajectoryInput::Topic(t) => Some(t.clone()),
            TrajectoryInput::TumFile(_) => None,
        })
        .collect();
    // Each input's lever as given, and the /tf_static look-ups the `tf-static:` ones need.
    let specs: Vec<Option<&LeverSpec>> = all
        .iter()
        .enumerate()
        .map(|(i, input)| match i {
            0 => config.reference_lever.as_ref(),
            _ => config.estimate_lever(&input.name),
        })
        .collect();
    let mut lookups: Vec<(String, String)> = Vec::new();
    for (input, spec) in all.iter().zip(&specs) {
        if let Some(l) = static_lookup(config, input, *spec)? {
            if !lookups.contains(&l) {
                lookups.push(l);
            }
        }
    }
    let (extraction, path, bytes) = extract(config, &topics, &lookups, progress)?;
    let mut loaded = Vec::with_capacity(all.len());
    for &input in &all {
        loaded.push(loaded_input(config, input, extraction.as_ref())?);
    }
    for ((l, input), spec) in loaded.iter_mut().zip(&all).zip(&specs) {
        l.lever_m = lever_of(config, input, *spec, extraction.as_ref())?;
    }
    let reference = loaded.remove(0);
    Ok(Inputs {
        reference,
        estimates: loaded,
        warnings: extraction.map(|e| e.warnings).unwrap_or_default(),
        path,
        bytes,
    })
}

/// One pass over the recording for the requested topics and `/tf_static` look-ups (none when
/// every input is a text file); with the input's path and size for the report.
fn extract(
    config: &EvalConfig,
    topics: &[String],
    lookups: &[(String, String)],
    progress: Progress<'_>,
) -> Result<(Option<Extraction>, String, u64)> {
    match &config.recording {
        Some(rec) => {
            let source = crate::sources::open_all(&config.recordings())?;
            let extraction = if !topics.is_empty() {
                let mut unique = topics.to_vec();
                unique.dedup();
                let options = ExtractOptions {
                    stamp: config.params.stamp(),
                    origin: config.params.origin,
                    static_lookups: lookups.to_vec(),
                    positions_only: positions_only(config, source.as_ref()),
                };
                Some(source.extract(&unique, &options, progress)?)
            } else if !lookups.is_empty() {
                let options = ExtractOptions {
                    static_lookups: lookups.to_vec(),
                    ..ExtractOptions::default()
                };
                Some(source.extract(&[], &options, progress)?)
            } else {
                None
            };
            Ok((extraction, rec.display().to_string(), source.size_bytes()))
        }
        None => {
            let p = match &config.reference.input {
                TrajectoryInput::TumFile(p) => p.clone(),
                TrajectoryInput::Topic(_) => {
                    return Err(Error::InvalidArgument(
                        "a topic was given but no RECORDING".into(),
                    ));
                }
            };
            let bytes = std::fs::metadata(&p).map_err(|e| Error::io(&p, e))?.len();
            Ok((None, p.display().to_string(), bytes))
        }
    }
}

/// One input: read from its text file, or taken from the recording's extraction.
fn loaded_input(
    config: &EvalConfig,
    input: &NamedInput,
    extraction: Option<&Extraction>,
) -> Result<Loaded> {
    Ok(match &input.input {
        TrajectoryInput::TumFile(p) => load_tum(&input.name, p, &config.text)?,
        TrajectoryInput::Topic(t) => {
            let ex = extraction
                .and_then(|e| e.topics.iter().find(|x| &x.topic == t))
                .ok_or_else(|| Error::InvalidArgument(format!("topic {t} was not extracted")))?;
            Loaded {
                name: input.name.clone(),
                label: t.clone(),
                type_name: ex.type_name.clone(),
                trajectory: ex.trajectory.clone(),
                dropped_samples: ex.invalid_dropped + ex.duplicate_stamps,
                rows: ex.rows,
                geodetic_origin: ex.geodetic_origin,
                lever_m: None,
            }
        }
    })
}

/// An input's lever: as given, or the translation of the `/tf_static` transform its
/// `tf-static:` spec names.
fn lever_of(
    config: &EvalConfig,
    input: &NamedInput,
    spec: Option<&LeverSpec>,
    extraction: Option<&Extraction>,
) -> Result<Option<[f64; 3]>> {
    Ok(match spec {
        None => None,
        Some(LeverSpec::Offset(v)) => Some(*v),
        Some(spec) => {
            let (from, to) = static_lookup(config, input, Some(spec))?.unwrap_or_default();
            let found = extraction
                .and_then(|e| {
                    e.static_transforms
                        .iter()
                        .find(|s| s.from == from && s.to == to)
                })
                .map(|s| s.pose.clone())
                .unwrap_or_else(|| Err("no look-up was made".into()));
            let pose = found.map_err(|detail| Error::TfChain {
                path: config.recording.clone().unwrap_or_default(),
                topic: format!("{} {}", lever_flag(config, input), spec.describe()),
                detail,
            })?;
            let t = pose.translation.vector;
            Some([t.x, t.y, t.z])
        }
    })
}

fn lever_flag(config: &EvalConfig, input: &NamedInput) -> &'static str {
    if std::ptr::eq(input, &config.reference) {
        "--reference-lever"
    } else {
        "--estimate-lever"
    }
}

/// The body frame of the evaluation, for `tf-static:FRAME` levers written without BODY: the CHILD
/// frame of the `/tf:PARENT:CHILD` inputs when there are some and they all name the same one (levers
/// are positions relative to one common body point, in one body frame). `None` otherwise.
fn common_body_frame(config: &EvalConfig) -> Option<String> {
    let mut children = std::iter::once(&config.reference)
        .chain(&config.estimates)
        .filter_map(|i| match &i.input {
            TrajectoryInput::Topic(t) => parse_chain_topic(t).and_then(|r| r.ok()).map(|r| r.child),
            TrajectoryInput::TumFile(_) => None,
        });
    let first = children.next()?;
    children.all(|c| c == first).then_some(first)
}

/// The (BODY, FRAME) look-up a `tf-static:` lever of `input` needs: BODY as written, else the
/// evaluation's body frame ([`common_body_frame`]); an error when neither names it or there is no
/// recording.
fn static_lookup(
    config: &EvalConfig,
    input: &NamedInput,
    spec: Option<&LeverSpec>,
) -> Result<Option<(String, String)>> {
    let Some(LeverSpec::TfStatic { body, frame }) = spec else {
        return Ok(None);
    };
    let flag = lever_flag(config, input);
    if config.recording.is_none() {
        return Err(Error::InvalidArgument(format!(
            "{flag} {}: a tf-static: lever is read from the recording's /tf_static; pass the RECORDING",
            spec.map(LeverSpec::describe).unwrap_or_default()
        )));
    }
    let Some(body) = body.clone().or_else(|| common_body_frame(config)) else {
        return Err(Error::InvalidArgument(format!(
            "{flag} tf-static:{frame}: the body frame is unknown (only /tf:PARENT:CHILD inputs name it, as CHILD, and they must agree); write tf-static:BODY:{frame}, e.g. tf-static:base_link:{frame}"
        )));
    };
    Ok(Some((body, frame.clone())))
}

fn load_tum(name: &str, path: &Path, text: &TextOptions) -> Result<Loaded> {
    let (trajectory, format, rows) = read_text_audited(path, text)?;
    Ok(Loaded {
        name: name.to_string(),
        label: path.display().to_string(),
        type_name: format.as_str().into(),
        trajectory,
        dropped_samples: rows.dropped(),
        rows,
        geodetic_origin: None,
        lever_m: None,
    })
}
