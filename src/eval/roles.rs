//! Who plays which role in an evaluation: the reference and the estimates, as the user named them
//! (a topic or a text file each) or as a preset picks them in the recording. `eval`, every mission of
//! a `batch` and `ape`/`rpe`/`offset` resolve their roles here, the same way: what was named wins over
//! the preset, a preset's estimate absent from the recording is skipped with a note, and the preset's
//! `[parameters]` come back as the lowest layer.

use std::path::PathBuf;

use super::config::{EvalConfig, NamedInput};
use super::preset::Preset;
use crate::error::{Error, Result};
use crate::params::Parameters;

/// The resolved roles.
#[derive(Debug, Clone)]
pub struct Roles {
    pub reference: NamedInput,
    pub estimates: Vec<NamedInput>,
    /// What the user should read: the preset's estimates absent from the recording.
    pub notes: Vec<String>,
    /// The preset's `[parameters]` (empty without a preset): the lowest layer.
    pub preset_parameters: Parameters,
}

/// The reference and estimates in `recordings`: `reference`/`estimates` as named, the rest picked by
/// `preset`; without a preset, a missing reference is refused with `no_reference` (what to give, in the
/// words of the caller's interface).
pub fn resolve(
    recordings: &[PathBuf],
    reference: Option<NamedInput>,
    estimates: Vec<NamedInput>,
    preset: Option<&Preset>,
    no_reference: &str,
) -> Result<Roles> {
    let Some(p) = preset else {
        return Ok(Roles {
            reference: reference.ok_or_else(|| Error::InvalidArgument(no_reference.into()))?,
            estimates,
            notes: Vec::new(),
            preset_parameters: Parameters::default(),
        });
    };
    let s = p.select_in(recordings, reference, estimates)?;
    Ok(Roles {
        reference: s.reference,
        estimates: s.estimates,
        notes: s
            .skipped
            .iter()
            .map(|n| {
                format!(
                    "preset {}: estimate {n} is not in the recording, skipped",
                    p.name
                )
            })
            .collect(),
        preset_parameters: p.parameters.clone(),
    })
}

impl Roles {
    /// The request of these roles in `recordings` (the first is the recording, the others more files
    /// of the same mission), with `layers` over the preset's parameters, lowest first.
    pub fn config(self, recordings: &[PathBuf], layers: &[&Parameters]) -> EvalConfig {
        let mut c = EvalConfig::new(recordings.first().cloned(), self.reference, self.estimates);
        c.more_recordings = recordings.iter().skip(1).cloned().collect();
        c.params = Parameters::layered(
            std::iter::once(&self.preset_parameters).chain(layers.iter().copied()),
        );
        c
    }
}

/// The reference named on a command line: `--reference TOPIC` or `--reference-file FILE`.
pub fn named_reference(topic: Option<&str>, file: Option<&std::path::Path>) -> Option<NamedInput> {
    match (topic, file) {
        (Some(t), _) => Some(NamedInput::topic(t)),
        (None, Some(f)) => Some(NamedInput::file(&f.to_string_lossy())),
        (None, None) => None,
    }
}
