//! Loads the reference and the estimates of an evaluation: one streaming pass over the recording for
//! every requested topic, TUM files read directly.

use std::path::Path;

use crate::error::{Error, Result};
use crate::eval::config::{EvalConfig, NamedInput, TrajectoryInput};
use crate::sources::text::{read_text, TextOptions};
use crate::sources::{ExtractOptions, Progress, Warning};
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
    pub geodetic_origin: Option<[f64; 3]>,
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
    let mut extraction = None;
    let (path, bytes) = match &config.recording {
        Some(rec) => {
            let source = crate::sources::open(rec)?;
            if !topics.is_empty() {
                let mut unique = topics.clone();
                unique.dedup();
                let options = ExtractOptions {
                    stamp: config.stamp,
                    origin: config.origin,
                };
                extraction = Some(source.extract(&unique, &options, progress)?);
            }
            (rec.display().to_string(), source.size_bytes())
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
            (p.display().to_string(), bytes)
        }
    };
    let mut loaded = Vec::with_capacity(all.len());
    for input in all {
        loaded.push(match &input.input {
            TrajectoryInput::TumFile(p) => load_tum(&input.name, p, &config.text)?,
            TrajectoryInput::Topic(t) => {
                let ex = extraction
                    .as_ref()
                    .and_then(|e| e.topics.iter().find(|x| &x.topic == t))
                    .ok_or_else(|| {
                        Error::InvalidArgument(format!("topic {t} was not extracted"))
                    })?;
                Loaded {
                    name: input.name.clone(),
                    label: t.clone(),
                    type_name: ex.type_name.clone(),
                    trajectory: ex.trajectory.clone(),
                    dropped_samples: ex.invalid_dropped + ex.duplicate_stamps,
                    geodetic_origin: ex.geodetic_origin,
                }
            }
        });
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

fn load_tum(name: &str, path: &Path, text: &TextOptions) -> Result<Loaded> {
    let (trajectory, format) = read_text(path, text)?;
    Ok(Loaded {
        name: name.to_string(),
        label: path.display().to_string(),
        type_name: format.as_str().into(),
        trajectory,
        dropped_samples: 0,
        geodetic_origin: None,
    })
}
