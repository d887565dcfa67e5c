//! The evaluation job: load the trajectories, find each estimate's clock offset, compute its Drift
//! Error at every window size, and assemble the report. Estimates are evaluated in parallel (rayon).

pub mod config;
pub mod extrinsics;
pub mod inputs;

use rayon::prelude::*;

use crate::align::time_offset::{estimate_time_offset, OffsetEstimate, OffsetMethod, OffsetStatus};
use crate::error::{Error, Result};
use crate::metrics::drift_error::{drift_error_windows, DriftErrorResult};
use crate::report::json::{
    DriftErrorReport, EstimateReport, Input, OffsetMethodReport, Parameters, Report,
    TimeOffsetReport, Tool, TopicReport, WindowReport, SCHEMA_VERSION,
};
use crate::sources::{Progress, Warning};
use config::EvalConfig;
use inputs::{load, Loaded};

/// Every method the offset search runs (the applied one is `EvalConfig::offset_method`).
pub const OFFSET_METHODS: [OffsetMethod; 2] = [OffsetMethod::Curvature, OffsetMethod::Speed];

/// Runs the whole evaluation. Warnings the user must see (a weak offset, a truncated recording) are in
/// `Report::warnings`; the CLI exits with code 3 when there is any.
pub fn evaluate(config: &EvalConfig, progress: Progress<'_>) -> Result<Report> {
    config.validate()?;
    let mut inputs = load(config, progress)?;
    let levers = extrinsics::apply_levers(config, &mut inputs.estimates)?;
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
    let (crop_start, crop_end) = (crop(config.t_start), crop(config.t_end));
    reference.trajectory.crop(crop_start, crop_end);
    require_samples(&inputs.path, reference)?;
    let reference = &inputs.reference;
    for e in &inputs.estimates {
        require_samples(&inputs.path, e)?;
    }

    let results: Vec<Result<(EstimateReport, Vec<Warning>)>> = inputs
        .estimates
        .par_iter()
        .map(|est| evaluate_estimate(config, reference, est, t0_ns, (crop_start, crop_end)))
        .collect();
    let mut estimates = Vec::with_capacity(results.len());
    let mut warnings = inputs.warnings.clone();
    for r in results {
        let (e, w) = r?;
        estimates.push(e);
        warnings.extend(w);
    }
    for (e, x) in estimates.iter_mut().zip(levers) {
        e.extrinsics = x;
    }
    let to_s = |ns: Option<i64>| ns.map(|t| t as f64 * 1e-9);
    Ok(Report {
        schema_version: SCHEMA_VERSION,
        tool: Tool::default(),
        input: Input {
            path: inputs.path.clone(),
            bytes: inputs.bytes,
        },
        parameters: Parameters {
            platform: config.platform.as_str().into(),
            curvature_eps_m: config.curvature_eps(),
            path_eps_m: config.path_eps(),
            theta_max_rad: config.theta_max_rad,
            dt_max_s: config.dt_max_s,
            windows_m: config.windows_m.clone(),
            overlap: config.overlap,
            lever_arm_m: config.lever_arm_m,
            lever_correction: config.lever_correction.as_str().into(),
            max_offset_s: config.max_offset_s,
            grid_s: config.grid_s,
            offset_method: config.offset_method.as_str().into(),
            time_offset_s: config.time_offset_s,
            stamp: match config.stamp {
                crate::sources::StampSource::Header => "header".into(),
                crate::sources::StampSource::Log => "log".into(),
            },
            origin: config.origin,
            t_start: to_s(crop_start),
            t_end: to_s(crop_end),
        },
        reference: TopicReport {
            topic: reference.label.clone(),
            type_name: reference.type_name.clone(),
            samples: reference.trajectory.len(),
            geodetic_origin: reference.geodetic_origin,
            dropped_samples: reference.dropped_samples,
        },
        estimates,
        warnings,
    })
}

fn require_samples(path: &str, t: &Loaded) -> Result<()> {
    if t.trajectory.len() < 3 {
        return Err(Error::TooFewSamples {
            what: format!("{path}: {}", t.label),
            n: t.trajectory.len(),
            need: 3,
        });
    }
    Ok(())
}

fn status_str(s: OffsetStatus) -> &'static str {
    match s {
        OffsetStatus::Ok => "ok",
        OffsetStatus::Weak => "weak",
    }
}

fn method_report(method: OffsetMethod, r: &Result<OffsetEstimate>) -> OffsetMethodReport {
    match r {
        Ok(o) => OffsetMethodReport {
            method: method.as_str().into(),
            offset_s: Some(o.offset_s),
            correlation: Some(o.correlation),
            confidence: Some(o.confidence),
            status: status_str(o.status).into(),
            error: None,
        },
        Err(e) => OffsetMethodReport {
            method: method.as_str().into(),
            offset_s: None,
            correlation: None,
            confidence: None,
            status: "failed".into(),
            error: Some(e.to_string()),
        },
    }
}

fn evaluate_estimate(
    config: &EvalConfig,
    reference: &Loaded,
    est: &Loaded,
    t0_ns: i64,
    crop: (Option<i64>, Option<i64>),
) -> Result<(EstimateReport, Vec<Warning>)> {
    let ref_t = reference.trajectory.times_s(t0_ns);
    let ref_p = &reference.trajectory.positions;
    let est_t = est.trajectory.times_s(t0_ns);
    let est_p = &est.trajectory.positions;
    let mut warnings = Vec::new();

    let time_offset = match config.time_offset_s {
        Some(dt) => TimeOffsetReport {
            method: "given".into(),
            offset_s: dt,
            applied_s: dt,
            correlation: None,
            confidence: None,
            status: "given".into(),
            methods: Vec::new(),
        },
        None => {
            let params = config.offset_params();
            let runs: Vec<(OffsetMethod, Result<OffsetEstimate>)> = OFFSET_METHODS
                .par_iter()
                .map(|&m| {
                    (
                        m,
                        estimate_time_offset(m, &ref_t, ref_p, &est_t, est_p, &params),
                    )
                })
                .collect();
            let chosen = runs
                .iter()
                .find(|(m, _)| *m == config.offset_method)
                .map(|(_, r)| r);
            let methods = runs.iter().map(|(m, r)| method_report(*m, r)).collect();
            match chosen {
                Some(Ok(o)) if o.status == OffsetStatus::Ok => TimeOffsetReport {
                    method: o.method.as_str().into(),
                    offset_s: o.offset_s,
                    applied_s: o.offset_s,
                    correlation: Some(o.correlation),
                    confidence: Some(o.confidence),
                    status: "ok".into(),
                    methods,
                },
                Some(Err(e @ Error::NoOverlap { .. })) => {
                    return Err(clone_no_overlap(e, &est.label))
                }
                other => {
                    let (offset_s, correlation, confidence) = match other {
                        Some(Ok(o)) => (o.offset_s, Some(o.correlation), Some(o.confidence)),
                        _ => (0.0, None, None),
                    };
                    warnings.push(Warning {
                        code: "weak_time_offset".into(),
                        message: format!(
                            "{}: the {} time-offset peak is weak (best {:+.3} s); Drift Error computed at 0 s. Check the overlap, try --offset-method speed or give --time-offset",
                            est.name,
                            config.offset_method.as_str(),
                            offset_s
                        ),
                    });
                    TimeOffsetReport {
                        method: config.offset_method.as_str().into(),
                        offset_s,
                        applied_s: 0.0,
                        correlation,
                        confidence,
                        status: "weak".into(),
                        methods,
                    }
                }
            }
        }
    };

    // Shift onto the reference clock and crop like the reference.
    let applied_ns = (time_offset.applied_s * 1e9).round() as i64;
    let mut aligned = est.trajectory.shifted(applied_ns);
    aligned.crop(crop.0, crop.1);
    let aligned_t = aligned.times_s(t0_ns);
    if aligned.len() < 3 {
        let (r0, r1) = (
            ref_t.first().copied().unwrap_or(0.0),
            ref_t.last().copied().unwrap_or(0.0),
        );
        return Err(Error::NoOverlap {
            estimate: est.label.clone(),
            est_start: est_t.first().copied().unwrap_or(0.0),
            est_end: est_t.last().copied().unwrap_or(0.0),
            ref_start: r0,
            ref_end: r1,
            offset: time_offset.applied_s,
        });
    }
    let t0_s = t0_ns as f64 * 1e-9;
    let params = config.drift_params(config.windows_m[0]);
    let drift = drift_error_windows(
        &ref_t,
        ref_p,
        &aligned_t,
        &aligned.positions,
        &params,
        &config.windows_m,
    )
    .map_err(|e| relabel(e, &est.label))?
    .iter()
    .map(|r| drift_report(r, t0_s))
    .collect();
    Ok((
        EstimateReport {
            name: est.name.clone(),
            topic: est.label.clone(),
            type_name: est.type_name.clone(),
            samples: est.trajectory.len(),
            dropped_samples: est.dropped_samples,
            time_offset,
            drift_error: drift,
            extrinsics: None,
        },
        warnings,
    ))
}

/// Names the estimate in an overlap error raised deep in the maths.
fn relabel(e: Error, label: &str) -> Error {
    match e {
        Error::NoOverlap { .. } => clone_no_overlap(&e, label),
        Error::TooFewSamples { n, need, what } => Error::TooFewSamples {
            what: format!("{label}: {what}"),
            n,
            need,
        },
        other => other,
    }
}

fn clone_no_overlap(e: &Error, label: &str) -> Error {
    match e {
        Error::NoOverlap {
            est_start,
            est_end,
            ref_start,
            ref_end,
            offset,
            ..
        } => Error::NoOverlap {
            estimate: label.to_string(),
            est_start: *est_start,
            est_end: *est_end,
            ref_start: *ref_start,
            ref_end: *ref_end,
            offset: *offset,
        },
        _ => Error::InvalidArgument(e.to_string()),
    }
}

fn drift_report(r: &DriftErrorResult, t0_s: f64) -> DriftErrorReport {
    let s = r.stats.as_ref();
    DriftErrorReport {
        window_m: r.window_m,
        lever_correction: r.lever_correction.as_str().into(),
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
            .map(|w| WindowReport {
                t_start: w.t_start + t0_s,
                t_end: w.t_end + t0_s,
                ref_length_m: w.ref_length_m,
                est_length_m: w.est_length_m,
                alpha: w.alpha,
                de: w.de,
            })
            .collect(),
    }
}
