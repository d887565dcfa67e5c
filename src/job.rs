//! One evaluation job, as `eval` runs it and as `batch` runs each mission: evaluate the request, then
//! write the annotated recording and the figures asked for. The order, the passes over the recording
//! and the outputs are defined here once; the command line and the batch only say what to write and
//! how to show progress.

use std::path::PathBuf;

use crate::annotate::{annotate, check_annotate, AnnotateOutcome};
use crate::error::Result;
use crate::eval::config::EvalConfig;
use crate::eval::evaluate_with_inputs;
use crate::plot::{PictureOutputs, Trajectories};
use crate::report::json::Report;

/// What a job writes beside its report.
#[derive(Debug, Clone, Default)]
pub struct JobOutputs {
    /// `--annotate OUT.mcap`: the recording with the results added.
    pub annotate: Option<PathBuf>,
    /// Replace an existing annotated recording.
    pub force: bool,
    /// Figures and the HTML page.
    pub pictures: PictureOutputs,
}

/// A pass over the recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pass {
    /// Reading the trajectories for the evaluation.
    Evaluate,
    /// Copying the recording into the annotated one.
    Annotate,
}

/// What a job tells its caller while it runs.
#[derive(Debug, Clone, Copy)]
pub enum JobEvent {
    /// Bytes read so far in a pass.
    Read { pass: Pass, bytes: u64 },
    /// A pass ended.
    PassDone,
}

/// What a job did.
#[derive(Debug)]
pub struct JobDone {
    pub report: Report,
    /// The annotated recording, when asked for.
    pub annotated: Option<AnnotateOutcome>,
    /// The figures and HTML page written.
    pub pictures: Vec<PathBuf>,
}

/// Whether `outputs` can be written for `config`: refused before any pass (an existing annotated
/// recording without `force`, or one over an input).
pub fn check(config: &EvalConfig, outputs: &JobOutputs) -> Result<()> {
    match &outputs.annotate {
        Some(out) => check_annotate(config, out, outputs.force),
        None => Ok(()),
    }
}

/// The request `config` as the job runs it: the annotated recording's aligned poses carry the
/// estimate's orientation, so it keeps them.
pub fn config_for(config: &EvalConfig, outputs: &JobOutputs) -> EvalConfig {
    EvalConfig {
        keep_orientations: config.keep_orientations || outputs.annotate.is_some(),
        ..config.clone()
    }
}

/// Runs `config` and writes `outputs`: the evaluation pass, then the annotated recording (a second
/// pass), then the figures. `progress` hears every pass.
pub fn run(
    config: &EvalConfig,
    outputs: &JobOutputs,
    progress: &(dyn Fn(JobEvent) + Sync),
) -> Result<JobDone> {
    check(config, outputs)?;
    let config = config_for(config, outputs);
    let evaluated = evaluate_with_inputs(&config, &|bytes| {
        progress(JobEvent::Read {
            pass: Pass::Evaluate,
            bytes,
        })
    });
    progress(JobEvent::PassDone);
    let (report, inputs) = evaluated?;
    let annotated = match &outputs.annotate {
        Some(out) => {
            let done = annotate(&config, &report, &inputs, out, outputs.force, &|bytes| {
                progress(JobEvent::Read {
                    pass: Pass::Annotate,
                    bytes,
                })
            });
            progress(JobEvent::PassDone);
            Some(done?)
        }
        None => None,
    };
    let estimates = inputs.named_estimates();
    let pictures = outputs.pictures.write(
        &report,
        Trajectories {
            reference: &inputs.reference.trajectory,
            estimates: &estimates,
        },
    )?;
    Ok(JobDone {
        report,
        annotated,
        pictures,
    })
}
