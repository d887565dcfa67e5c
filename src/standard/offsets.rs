//! `trajdrift offset`: every way of finding the clock offset side by side on one estimate — none,
//! spatial (Umeyama SE(3) + a search of the Δt minimising the APE, what a user of evo would do by
//! hand), speed, curvature, signed curvature and auto (eval's combination) — each with its Δt, its
//! quality, its status, the time it took, and the APE the estimate gets once shifted by it.

use std::time::Instant;

use serde::Serialize;

use crate::align::auto_offset::auto_time_offset;
use crate::align::time_offset::{estimate_time_offset, OffsetMethod, OffsetStatus};
use crate::error::{Error, Result};
use crate::eval::config::EvalConfig;
use crate::metrics::standard::{
    evaluate_with_offset, Alignment, Metric, Pipeline, PoseRelation, SyncMethod,
};
use crate::trajectory::Trajectory;

/// One method's answer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OffsetRow {
    pub method: String,
    /// Δt, seconds (t_est + Δt = reference clock); `None` when the method failed.
    pub offset_s: Option<f64>,
    /// The method's own quality: peak NCC for the correlation methods, the APE RMSE (m) for spatial.
    pub quality: Option<f64>,
    /// `ok`, `weak`, `failed` or `-` (none).
    pub status: String,
    pub time_ms: f64,
    /// APE (SE(3), translation part) RMSE of the estimate shifted by Δt, m.
    pub ape_rmse_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// The APE pipeline used to judge an offset: SE(3) alignment, interpolation, `t_max_diff` wide enough
/// for sensors not sampled in phase.
fn ape_pipeline(reference: &Trajectory, estimate: &Trajectory) -> Pipeline {
    let period = |t: &Trajectory| {
        let mut d: Vec<i64> = t.stamps_ns.windows(2).map(|w| w[1] - w[0]).collect();
        d.sort_unstable();
        d.get(d.len() / 2).map_or(0.0, |&x| x as f64 * 1e-9)
    };
    Pipeline {
        alignment: Alignment::Se3,
        sync: SyncMethod::Interpolation,
        t_max_diff_s: period(reference).max(period(estimate)).max(0.01),
        ..Pipeline::default()
    }
}

/// APE RMSE of `estimate` shifted by `dt`, or `None` when it cannot be computed.
pub fn ape_rmse_at(
    reference: &Trajectory,
    estimate: &Trajectory,
    dt: f64,
    p: &Pipeline,
) -> Option<f64> {
    evaluate_with_offset(
        reference,
        estimate,
        dt,
        Metric::Ape,
        PoseRelation::TransPart,
        p,
    )
    .ok()
    .map(|r| r.stats.rmse)
}

/// The Δt in `[-range, range]` minimising the APE RMSE: a scan at 0.1 s, then 0.01 s and 0.001 s around
/// the best.
pub fn spatial_offset(
    reference: &Trajectory,
    estimate: &Trajectory,
    range_s: f64,
) -> Result<(f64, f64)> {
    let p = ape_pipeline(reference, estimate);
    let mut best: Option<(f64, f64)> = None;
    let scan = |from: f64, to: f64, step: f64, best: &mut Option<(f64, f64)>| {
        let n = ((to - from) / step).round() as i64;
        for k in 0..=n {
            let dt = from + k as f64 * step;
            if let Some(r) = ape_rmse_at(reference, estimate, dt, &p) {
                if best.is_none_or(|b| r < b.1) {
                    *best = Some((dt, r));
                }
            }
        }
    };
    scan(-range_s, range_s, 0.1, &mut best);
    for step in [0.01, 0.001] {
        if let Some((c, _)) = best {
            scan(c - 10.0 * step, c + 10.0 * step, step, &mut best);
        }
    }
    best.ok_or_else(|| {
        Error::Metric(format!(
            "no shift within ±{range_s} s gives associated pairs for the APE"
        ))
    })
}

/// Runs every method on the first estimate of `config`.
pub fn compare_offset_methods(config: &EvalConfig, spatial_range_s: f64) -> Result<Vec<OffsetRow>> {
    let inputs = crate::eval::inputs::load(config, &|_| {})?;
    let reference = &inputs.reference.trajectory;
    let estimate = &inputs
        .estimates
        .first()
        .ok_or_else(|| Error::InvalidArgument("give an estimate".into()))?
        .trajectory;
    // Every method needs a few samples on each side; fewer are refused by name, not measured.
    for (what, t) in [
        (&inputs.reference.label, reference),
        (&inputs.estimates[0].label, estimate),
    ] {
        if t.len() < 3 {
            return Err(Error::TooFewSamples {
                what: what.clone(),
                n: t.len(),
                need: 3,
            });
        }
    }
    let t0 = reference.stamps_ns.first().copied().unwrap_or(0);
    let (ref_t, est_t) = (reference.times_s(t0), estimate.times_s(t0));
    let auto = config.measure(&ref_t, &reference.positions);
    let params = config.resolved(&auto).offset_params();
    let p = ape_pipeline(reference, estimate);
    let row = |method: &str, found: Result<(f64, Option<f64>, String)>, ms: f64| match found {
        Ok((dt, quality, status)) => OffsetRow {
            method: method.into(),
            offset_s: Some(dt),
            quality,
            status,
            time_ms: ms,
            ape_rmse_m: ape_rmse_at(reference, estimate, dt, &p),
            error: None,
        },
        Err(e) => OffsetRow {
            method: method.into(),
            offset_s: None,
            quality: None,
            status: "failed".into(),
            time_ms: ms,
            ape_rmse_m: None,
            error: Some(e.to_string()),
        },
    };
    let status = |s: OffsetStatus| match s {
        OffsetStatus::Ok => "ok".to_string(),
        OffsetStatus::Weak => "weak".to_string(),
    };
    let mut rows = vec![row("none", Ok((0.0, None, "-".into())), 0.0)];
    let start = Instant::now();
    let spatial = spatial_offset(reference, estimate, spatial_range_s)
        .map(|(dt, rmse)| (dt, Some(rmse), "ok".to_string()));
    rows.push(row("spatial", spatial, start.elapsed().as_secs_f64() * 1e3));
    for m in [
        OffsetMethod::Speed,
        OffsetMethod::Curvature,
        OffsetMethod::SignedCurvature,
    ] {
        let start = Instant::now();
        let r = estimate_time_offset(
            m,
            &ref_t,
            &reference.positions,
            &est_t,
            &estimate.positions,
            &params,
        )
        .map(|o| (o.offset_s, Some(o.correlation), status(o.status)));
        rows.push(row(m.as_str(), r, start.elapsed().as_secs_f64() * 1e3));
    }
    let start = Instant::now();
    let r = auto_time_offset(
        &ref_t,
        &reference.positions,
        &est_t,
        &estimate.positions,
        &params,
    )
    .map(|a| {
        (
            a.estimate.offset_s,
            Some(a.estimate.correlation),
            status(a.estimate.status),
        )
    });
    rows.push(row("auto", r, start.elapsed().as_secs_f64() * 1e3));
    Ok(rows)
}
