//! The inputs of `trajdrift ape`/`rpe`: evo's positional forms (`tum REF EST`, `kitti REF EST`,
//! `euroc GT.csv EST`, `bag BAG REF EST`, `bag2 DIR REF EST`, `mcap FILE REF EST`) mapped onto
//! trajdrift's own readers (the text readers and [`crate::eval::inputs::load`], so TF chains and presets
//! work too), each with the stamp conversion evo's reader for that form uses.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::eval::config::{EvalConfig, NamedInput};
use crate::metrics::standard::poses::{Poses, Rotations, StampSeconds};
use crate::sources::euroc::read_euroc;
use crate::sources::kitti::read_kitti_matrices;
use crate::sources::text::{detect_format, TextFormat};
use crate::sources::tum::read_tum_rows_compact;
use crate::sources::{Progress, Warning};

/// evo's format word.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EvoFormat {
    Tum,
    Kitti,
    Euroc,
    Bag,
    Bag2,
    Mcap,
}

impl EvoFormat {
    /// Parses the first positional argument, if it is a format word.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "tum" => EvoFormat::Tum,
            "kitti" => EvoFormat::Kitti,
            "euroc" => EvoFormat::Euroc,
            "bag" => EvoFormat::Bag,
            "bag2" => EvoFormat::Bag2,
            "mcap" => EvoFormat::Mcap,
            _ => return None,
        })
    }
}

/// Where the two trajectories come from.
#[derive(Debug, Clone, PartialEq)]
pub enum MetricInputs {
    /// Two text files in one of evo's text forms.
    Text {
        format: EvoFormat,
        reference: PathBuf,
        estimate: PathBuf,
    },
    /// trajdrift's own inputs (a recording with topics or TF chains, text files, presets), and evo's
    /// `bag`/`bag2`/`mcap` forms: read like `eval` reads them.
    Eval(Box<EvalConfig>),
}

/// Two trajectories ready for the metric, and what to call them.
#[derive(Debug, Clone)]
pub struct LoadedPair {
    pub reference: Poses,
    pub estimate: Poses,
    pub reference_label: String,
    pub estimate_label: String,
    /// What the read warns of (a recording cut short), as [`crate::eval::inputs::Inputs::warnings`].
    pub warnings: Vec<Warning>,
}

impl MetricInputs {
    /// Builds the inputs from evo's positional form `FORMAT ARG...`.
    pub fn from_evo(format: EvoFormat, args: &[String]) -> Result<Self> {
        let want = match format {
            EvoFormat::Bag | EvoFormat::Bag2 | EvoFormat::Mcap => 3,
            _ => 2,
        };
        if args.len() != want {
            return Err(Error::InvalidArgument(format!(
                "{format:?} takes {want} arguments ({}), got {}",
                match want {
                    3 => "RECORDING REF_TOPIC EST_TOPIC",
                    _ => "REF_FILE EST_FILE",
                },
                args.len()
            )));
        }
        if want == 2 {
            return Ok(MetricInputs::Text {
                format,
                reference: PathBuf::from(&args[0]),
                estimate: PathBuf::from(&args[1]),
            });
        }
        let rec = PathBuf::from(&args[0]);
        let c = EvalConfig::new(
            Some(rec),
            NamedInput::topic(&args[1]),
            vec![NamedInput::topic(&args[2])],
        );
        Ok(MetricInputs::Eval(Box::new(c)))
    }

    /// Every file these inputs read (outputs are checked against them).
    pub fn input_paths(&self) -> Vec<PathBuf> {
        match self {
            MetricInputs::Text {
                reference,
                estimate,
                ..
            } => vec![reference.clone(), estimate.clone()],
            MetricInputs::Eval(c) => c.input_paths(),
        }
    }

    /// Reads both trajectories.
    pub fn load(&self, progress: Progress<'_>) -> Result<LoadedPair> {
        self.load_with(progress, true)
    }

    /// [`MetricInputs::load`]; TUM text files skip their orientation columns unless `orientation`
    /// (see [`crate::metrics::standard::needs_orientation`]).
    pub fn load_with(&self, progress: Progress<'_>, orientation: bool) -> Result<LoadedPair> {
        match self {
            MetricInputs::Text {
                format,
                reference,
                estimate,
            } => load_text(*format, reference, estimate, orientation),
            MetricInputs::Eval(c) => {
                let inputs = crate::eval::inputs::load(c, progress)?;
                let est = inputs.estimates.first().ok_or_else(|| {
                    Error::InvalidArgument(
                        "give an estimate (--estimate TOPIC or --estimate-file FILE)".into(),
                    )
                })?;
                let conv = Some(StampSeconds::SecPlusNanos);
                let (reference_label, estimate_label) = (inputs.reference.label, est.label.clone());
                let estimate = inputs
                    .estimates
                    .into_iter()
                    .next()
                    .map(|e| e.trajectory)
                    .unwrap_or_default();
                Ok(LoadedPair {
                    reference: Poses::from_trajectory(inputs.reference.trajectory, conv),
                    estimate: Poses::from_trajectory(estimate, conv),
                    reference_label,
                    estimate_label,
                    warnings: inputs.warnings,
                })
            }
        }
    }

    /// The evaluation request that finds the time offset (`--time-offset auto`) on the same inputs.
    pub fn offset_config(&self) -> Result<EvalConfig> {
        match self {
            MetricInputs::Eval(c) => Ok((**c).clone()),
            MetricInputs::Text { format: EvoFormat::Kitti, .. } => Err(Error::InvalidArgument(
                "--time-offset auto needs stamped trajectories; KITTI pose files are paired by index (give --kitti-times with the native form --reference-file/--estimate-file)".into(),
            )),
            MetricInputs::Text {
                reference,
                estimate,
                ..
            } => Ok(EvalConfig::new(
                None,
                NamedInput::file(&reference.to_string_lossy()),
                vec![NamedInput::file(&estimate.to_string_lossy())],
            )),
        }
    }
}

/// Reads evo's text forms after checking the files are in that format. Rows are kept as written
/// (evo neither sorts nor drops repeated stamps) and KITTI rotations as written (not re-orthonormalised).
fn load_text(
    format: EvoFormat,
    reference: &Path,
    estimate: &Path,
    orientation: bool,
) -> Result<LoadedPair> {
    let tum = |path: &Path| -> Result<Poses> {
        check_format(path, TextFormat::Tum, format)?;
        let (rows, orientations) = read_tum_rows_compact(path, orientation)?;
        Ok(Poses::from_tum(rows, orientations))
    };
    let kitti = |path: &Path| -> Result<Poses> {
        check_format(path, TextFormat::Kitti, format)?;
        let rows = read_kitti_matrices(path)?;
        Ok(Poses {
            stamps_s: None,
            positions: rows.iter().map(|r| r.1).collect(),
            rotations: Some(Rotations::Matrices(rows.iter().map(|r| r.0).collect())),
        })
    };
    let euroc = |path: &Path| -> Result<Poses> {
        check_format(path, TextFormat::Euroc, format)?;
        Ok(Poses::from_trajectory(
            read_euroc(path)?,
            Some(StampSeconds::NanosOverE9),
        ))
    };
    // The two files are read at once (one per core).
    let (reference_poses, estimate_poses) = match format {
        EvoFormat::Tum => rayon::join(|| tum(reference), || tum(estimate)),
        EvoFormat::Kitti => rayon::join(|| kitti(reference), || kitti(estimate)),
        EvoFormat::Euroc => rayon::join(|| euroc(reference), || tum(estimate)),
        _ => unreachable!("recording forms are read through eval inputs"),
    };
    // Rows not finite are dropped, as every reader of the project drops them (evo's own rows stay
    // in file order).
    let (reference_poses, estimate_poses) = (reference_poses?.usable(), estimate_poses?.usable());
    Ok(LoadedPair {
        reference: reference_poses,
        estimate: estimate_poses,
        reference_label: reference.display().to_string(),
        estimate_label: estimate.display().to_string(),
        warnings: Vec::new(),
    })
}

/// A one-line error when a file is not in the format the command line names.
fn check_format(path: &Path, want: TextFormat, form: EvoFormat) -> Result<()> {
    let Ok(found) = detect_format(path) else {
        return Ok(()); // the reader names the problem with its line
    };
    if found == want {
        return Ok(());
    }
    let describe = |f: TextFormat| match f {
        TextFormat::Tum => "TUM (t x y z qx qy qz qw)",
        TextFormat::Kitti => "KITTI (12 values a row)",
        TextFormat::Euroc => "EuRoC ground truth CSV",
        TextFormat::Csv => "CSV with a header",
    };
    let hint = match found {
        TextFormat::Tum => "tum",
        TextFormat::Kitti => "kitti",
        TextFormat::Euroc => "euroc (as the reference)",
        TextFormat::Csv => "the native form: --reference-file/--estimate-file with --csv",
    };
    Err(Error::InvalidArgument(format!(
        "{}: the `{}` form expects {}, but the file looks like {}; use {hint}",
        path.display(),
        format!("{form:?}").to_lowercase(),
        describe(want),
        describe(found)
    )))
}
