//! The evaluation job: load the trajectories, find each estimate's clock offset, compute its Drift
//! Error at every window size, and assemble the report. Estimates are evaluated in parallel (rayon).

pub mod config;
pub mod export;
pub mod extrinsics;
pub mod inputs;
pub mod layer_check;
mod offset;
pub mod parameters;
pub mod preset;
pub mod roles;
pub mod sweep;

use rayon::prelude::*;

use crate::align::auto_params::AutoParams;
use crate::clock::ClockCorrection;
use crate::diag::Warning;
use crate::error::{Error, Result};
use crate::metrics::drift_error::{drift_error_windows, DriftErrorResult, DriftWindow};
use crate::report::json::{
    AutoParameters, DriftErrorReport, EstimateReport, ExtrinsicsReport, Input, Parameters, Report,
    Tool, TopicReport, SCHEMA_VERSION,
};
use crate::sources::Progress;
use config::EvalConfig;
use inputs::{load, Inputs, Loaded};
use offset::{given_offset, relabel, searched_offset};

/// The crop's bounds (`--t-start`, `--t-end`), ns since the epoch; `None`: open.
type CropNs = (Option<i64>, Option<i64>);

/// The longest time span of the loaded trajectories, seconds (what the offset search grids).
fn data_span_s(inputs: &Inputs) -> f64 {
    std::iter::once(&inputs.reference)
        .chain(&inputs.estimates)
        .filter_map(|t| t.trajectory.span_ns())
        .map(|(a, b)| (b as f64 - a as f64) * 1e-9)
        .fold(0.0, f64::max)
}

/// Runs the whole evaluation. Warnings the user must see (a weak offset, a truncated recording) are in
/// `Report::warnings`; the CLI exits with code 3 when there is any.
pub fn evaluate(config: &EvalConfig, progress: Progress<'_>) -> Result<Report> {
    evaluate_with_inputs(config, progress).map(|(report, _)| report)
}

/// Like [`evaluate`], and also returns the loaded trajectories (the reference cropped like the
/// evaluation), for consumers that need more than the report (the annotated MCAP's curvature channels).
pub fn evaluate_with_inputs(
    config: &EvalConfig,
    progress: Progress<'_>,
) -> Result<(Report, Inputs)> {
    config.validate()?;
    config.check_outputs()?;
    let inputs = load(config, progress)?;
    evaluate_loaded(config, inputs)
}

/// The evaluation of inputs already read with [`load`] for `config` (a sweep reads the recording once
/// and evaluates it at many parameter values; none of those change what is read): the inputs made
/// ready ([`crop_inputs`]), each estimate evaluated ([`evaluate_estimates`]), the report assembled
/// ([`assemble_report`]).
pub fn evaluate_loaded(config: &EvalConfig, mut inputs: Inputs) -> Result<(Report, Inputs)> {
    config.validate()?;
    let levers = extrinsics::apply_levers(&inputs.reference, &mut inputs.estimates)?;
    let (t0_ns, crop_ns) = crop_inputs(config, &mut inputs)?;
    // `--platform auto`: ε and the curvature Δt_max from the reference's own noise and speed.
    let reference = &inputs.reference.trajectory;
    let auto = config.measure(&reference.times_s(t0_ns), &reference.positions);
    let auto_names = config.auto_parameter_names();
    let resolved = config.resolved(&auto);
    let config = &resolved;
    let evaluated = evaluate_estimates(config, &inputs, t0_ns, crop_ns, levers)?;
    let report = assemble_report(config, &inputs, &auto, auto_names, crop_ns, evaluated);
    Ok((report, inputs))
}

/// The inputs made ready for the evaluation: the reference cropped to `--t-start`/`--t-end`
/// (seconds from its first stamp, or absolute from 1e8 s on), every trajectory checked for enough
/// samples, and a search's size checked against the data's span. Returns the time origin (the
/// reference's first stamp before the crop) and the crop's bounds, ns.
fn crop_inputs(config: &EvalConfig, inputs: &mut Inputs) -> Result<(i64, CropNs)> {
    let reference = &mut inputs.reference;
    let t0_ns = reference.trajectory.stamps_ns.first().copied().unwrap_or(0);
    let crop = |v: Option<f64>| {
        v.map(|s| {
            if s.abs() < 1e8 {
                t0_ns + (s * 1e9).round() as i64
            } else {
                (s * 1e9).round() as i64
            }
        })
    };
    let (crop_start, crop_end) = (crop(config.params.t_start), crop(config.params.t_end));
    reference.trajectory.crop(crop_start, crop_end);
    require_samples(&inputs.path, reference)?;
    for e in &inputs.estimates {
        require_samples(&inputs.path, e)?;
    }
    if config.params.time_offset.is_none() {
        check_search_size(config, inputs)?;
    }
    Ok((t0_ns, (crop_start, crop_end)))
}

/// The offset search's size over the data's span against the budgets
/// ([`crate::params::check_search_size`]). A refusal names the input of the longest span and, when
/// one gap between its samples makes most of that span (a bad stamp), the gap and its samples.
pub(crate) fn check_search_size(config: &EvalConfig, inputs: &Inputs) -> Result<()> {
    let span_s = data_span_s(inputs);
    crate::params::check_search_size(
        config.params.max_offset_s(),
        config.params.grid_s(),
        &config.params.offset_profile(),
        span_s,
    )
    .map_err(|e| {
        let longest = std::iter::once(&inputs.reference)
            .chain(&inputs.estimates)
            .max_by_key(|t| t.trajectory.span_ns().map_or(0, |(a, b)| b.saturating_sub(a)));
        let Some(t) = longest else { return e };
        let stamps = &t.trajectory.stamps_ns;
        let gap = stamps
            .windows(2)
            .enumerate()
            .max_by_key(|(_, w)| w[1].saturating_sub(w[0]));
        match gap {
            Some((i, w)) if (w[1] as f64 - w[0] as f64) * 1e-9 > 0.5 * span_s => {
                Error::InvalidArgument(format!(
                    "{}: a gap of {:.0} s between samples {} and {} (stamps {:.3} s and {:.3} s): {e}",
                    t.label,
                    (w[1] as f64 - w[0] as f64) * 1e-9,
                    i + 1,
                    i + 2,
                    w[0] as f64 * 1e-9,
                    w[1] as f64 * 1e-9,
                ))
            }
            _ => Error::InvalidArgument(format!("{}: {e}", t.label)),
        }
    })
}

/// Every estimate evaluated against the reference (in parallel), its extrinsics from `levers`
/// attached: the estimates' reports and their warnings, in input order (the first failure in that
/// order is the error).
fn evaluate_estimates(
    config: &EvalConfig,
    inputs: &Inputs,
    t0_ns: i64,
    crop_ns: CropNs,
    levers: Vec<Option<ExtrinsicsReport>>,
) -> Result<(Vec<EstimateReport>, Vec<Warning>)> {
    let results: Vec<Result<(EstimateReport, Vec<Warning>)>> = inputs
        .estimates
        .par_iter()
        .map(|est| {
            evaluate_estimate(
                config,
                &inputs.reference,
                est,
                t0_ns,
                crop_ns,
                inputs.estimates.len(),
            )
        })
        .collect();
    let mut estimates = Vec::with_capacity(results.len());
    let mut warnings = Vec::new();
    for r in results {
        let (e, w) = r?;
        estimates.push(e);
        warnings.extend(w);
    }
    for (e, x) in estimates.iter_mut().zip(levers) {
        e.extrinsics = x;
    }
    Ok((estimates, warnings))
}

/// The report of an evaluation: the input, the parameters used, the reference, the estimates, and
/// the warnings (the inputs' first, then the estimates').
fn assemble_report(
    config: &EvalConfig,
    inputs: &Inputs,
    auto: &AutoParams,
    auto_names: Vec<String>,
    crop_ns: CropNs,
    (estimates, estimate_warnings): (Vec<EstimateReport>, Vec<Warning>),
) -> Report {
    let mut warnings = inputs.warnings.clone();
    warnings.extend(estimate_warnings);
    let reference = &inputs.reference;
    Report {
        schema_version: SCHEMA_VERSION,
        tool: Tool::default(),
        input: Input {
            path: inputs.path.clone(),
            bytes: inputs.bytes,
        },
        parameters: parameters_report(config, auto, auto_names, crop_ns),
        reference: TopicReport {
            topic: reference.label.clone(),
            type_name: reference.type_name.clone(),
            samples: reference.trajectory.len(),
            geodetic_origin: reference.geodetic_origin,
            dropped_samples: reference.dropped_samples,
            rows: reference.rows,
        },
        estimates,
        warnings,
    }
}

/// The report's parameters: every value the evaluation used (the resolved ones: `auto` measured),
/// the crop in seconds, and what `--platform auto` measured and by which rules.
fn parameters_report(
    config: &EvalConfig,
    auto: &AutoParams,
    auto_names: Vec<String>,
    (crop_start, crop_end): CropNs,
) -> Parameters {
    let to_s = |ns: Option<i64>| ns.map(|t| t as f64 * 1e-9);
    Parameters {
        platform: config.params.platform(),
        curvature_eps_m: config.params.curvature_eps_m(),
        path_eps_m: config.params.path_eps_m(),
        theta_max_rad: config.params.theta_max_rad(),
        dt_max_s: config.params.dt_max_s(),
        windows_m: config.params.windows_m().clone(),
        overlap: config.params.overlap(),
        lever_arm_m: config.params.lever_arm_m(),
        lever_correction: config.params.lever_correction(),
        max_offset_s: config.params.max_offset_s(),
        grid_s: config.params.grid_s(),
        offset_method: config.params.offset_method(),
        time_offset_s: config.params.time_offset,
        stamp: config.params.stamp(),
        origin: config.params.origin,
        t_start: to_s(crop_start),
        t_end: to_s(crop_end),
        curvature_dt_max_s: config.curvature_dt_max_s,
        reference_noise_m: auto.reference_noise_m,
        auto: (!auto_names.is_empty()).then(|| AutoParameters {
            chosen: auto_names,
            reference_noise_m: auto.reference_noise_m,
            mean_speed_mps: auto.mean_speed_mps,
            slow_speed_mps: auto.slow_speed_mps,
            rules: "curvature_eps = sqrt(sigma / 0.005 m^-1) in [0.1, 5] m; path_eps = 50 sigma in [0.1, min window / 5] m; curvature_dt_max = 1.5 curvature_eps / slow speed in [dt_max, 30] s".into(),
        }),
    }
}

fn require_samples(path: &str, t: &Loaded) -> Result<()> {
    if t.trajectory.len() < 3 {
        // A text trajectory's label is its file, named once; a topic is named with its recording.
        let what = if std::path::Path::new(&t.label).is_file() {
            t.label.clone()
        } else {
            format!("{path}: {}", t.label)
        };
        return Err(Error::TooFewSamples {
            what,
            n: t.trajectory.len(),
            need: 3,
        });
    }
    Ok(())
}

fn evaluate_estimate(
    config: &EvalConfig,
    reference: &Loaded,
    est: &Loaded,
    t0_ns: i64,
    crop: CropNs,
    n_estimates: usize,
) -> Result<(EstimateReport, Vec<Warning>)> {
    let ref_t = reference.trajectory.times_s(t0_ns);
    let est_t = est.trajectory.times_s(t0_ns);
    let (time_offset, warnings) = match config.params.time_offset {
        Some(dt) => (given_offset(dt), Vec::new()),
        None => searched_offset(
            config,
            (&ref_t, &reference.trajectory.positions),
            &est_t,
            est,
            t0_ns,
        )?,
    };
    // Shift onto the reference clock and crop like the reference.
    // The report's own clock model, to the nanosecond (see `clock`).
    let mut aligned = ClockCorrection::from_report(&time_offset).apply(&est.trajectory);
    aligned.crop(crop.0, crop.1);
    if aligned.len() < 3 {
        let first_last = |t: &[f64]| {
            (
                t.first().copied().unwrap_or(0.0),
                t.last().copied().unwrap_or(0.0),
            )
        };
        let ((est_start, est_end), (ref_start, ref_end)) = (first_last(&est_t), first_last(&ref_t));
        return Err(Error::NoOverlap {
            estimate: est.label.clone(),
            est_start,
            est_end,
            ref_start,
            ref_end,
            offset: time_offset.applied_s,
        });
    }
    let drift = drift_of(
        config,
        (&ref_t, &reference.trajectory.positions),
        &aligned,
        est,
        t0_ns,
    )?;
    if let Some(file) = &config.export_aligned {
        export::write_aligned(
            &export::aligned_path(file, &est.name, n_estimates),
            &aligned,
        )?;
    }
    // Last: the metrics take the aligned estimate whole (no copy of it).
    let standard_metrics = config.params.metric_set().any_standard().then(|| {
        crate::metrics::standard::in_eval::standard_metrics(
            &reference.trajectory,
            aligned,
            &config.params.metric_set(),
        )
    });
    Ok((
        EstimateReport {
            name: est.name.clone(),
            topic: est.label.clone(),
            type_name: est.type_name.clone(),
            samples: est.trajectory.len(),
            dropped_samples: est.dropped_samples,
            rows: est.rows,
            time_offset,
            drift_error: drift,
            extrinsics: None,
            standard_metrics,
        },
        warnings,
    ))
}

/// The Drift Error of the aligned estimate at every window size (none unless `de` is asked for).
fn drift_of(
    config: &EvalConfig,
    (ref_t, ref_p): (&[f64], &[nalgebra::Vector3<f64>]),
    aligned: &crate::trajectory::Trajectory,
    est: &Loaded,
    t0_ns: i64,
) -> Result<Vec<DriftErrorReport>> {
    if !config.params.metric_set().de {
        return Ok(Vec::new());
    }
    let t0_s = t0_ns as f64 * 1e-9;
    let params = config.drift_params(config.params.windows_m()[0]);
    let aligned_t = aligned.times_s(t0_ns);
    Ok(drift_error_windows(
        ref_t,
        ref_p,
        &aligned_t,
        &aligned.positions,
        &params,
        &config.params.windows_m(),
    )
    .map_err(|e| relabel(e, &est.label))?
    .iter()
    .map(|r| drift_report(r, t0_s))
    .collect())
}

fn drift_report(r: &DriftErrorResult, t0_s: f64) -> DriftErrorReport {
    let s = r.stats.as_ref();
    DriftErrorReport {
        window_m: r.window_m,
        lever_correction: r.lever_correction,
        windows: r.windows.len(),
        dropped_windows: r.dropped_windows,
        rmse: s.map(|s| s.rmse),
        mean: s.map(|s| s.mean),
        median: s.map(|s| s.median),
        std: s.map(|s| s.std),
        q1: s.map(|s| s.q1),
        q3: s.map(|s| s.q3),
        p95: s.map(|s| s.p95),
        min: s.map(|s| s.min),
        max: s.map(|s| s.max),
        discarded_fraction: r.discarded_fraction,
        excluded_intervals: r
            .excluded_intervals
            .iter()
            .map(|iv| [iv[0] + t0_s, iv[1] + t0_s])
            .collect(),
        per_window: r
            .windows
            .iter()
            .map(|w| DriftWindow {
                t_start: w.t_start + t0_s,
                t_end: w.t_end + t0_s,
                ..*w
            })
            .collect(),
        scale: r.lever_fit.map(|f| f.scale),
        lateral_lever_m: r.lever_fit.map(|f| f.lateral_lever_m),
    }
}
