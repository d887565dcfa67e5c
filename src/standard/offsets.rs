//! `trajdrift offset`: every way of finding the clock offset side by side on one estimate — none,
//! spatial (Umeyama SE(3) + a search of the Δt minimising the APE, what a user of evo would do by
//! hand), speed, curvature, signed curvature and auto (eval's combination) — each with its Δt, its
//! quality, its status, the time it took, and the APE the estimate gets once shifted by it.

use std::time::Instant;

use serde::Serialize;

use crate::align::auto_offset::auto_time_offset;
use crate::align::time_offset::{estimate_time_offset, OffsetMethod, OffsetStatus};
use crate::diag::{Warning, WarningCode};
use crate::error::{Error, Result};
use crate::eval::config::EvalConfig;
use crate::metrics::standard::{
    evaluate_with_offset, Alignment, Metric, Pipeline, PoseRelation, SyncMethod,
};
use crate::trajectory::Trajectory;

/// A way of finding the offset, as `trajdrift offset` lists them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum OffsetWay {
    /// No offset (the baseline).
    None,
    /// The Δt minimising the APE after an SE(3) alignment (what an evo user does by hand).
    Spatial,
    Speed,
    Curvature,
    SignedCurvature,
    /// eval's combination.
    Auto,
    /// `auto`'s answer refined by the pose fit.
    Pose,
}

impl OffsetWay {
    /// As written in the table and the JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            OffsetWay::None => "none",
            OffsetWay::Spatial => "spatial",
            OffsetWay::Speed => "speed",
            OffsetWay::Curvature => "curvature",
            OffsetWay::SignedCurvature => "signed-curvature",
            OffsetWay::Auto => "auto",
            OffsetWay::Pose => "pose",
        }
    }
}

impl std::fmt::Display for OffsetWay {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

impl From<OffsetMethod> for OffsetWay {
    fn from(m: OffsetMethod) -> Self {
        match m {
            OffsetMethod::Speed => OffsetWay::Speed,
            OffsetMethod::Curvature => OffsetWay::Curvature,
            OffsetMethod::SignedCurvature => OffsetWay::SignedCurvature,
            OffsetMethod::Auto => OffsetWay::Auto,
            OffsetMethod::Pose => OffsetWay::Pose,
        }
    }
}

/// How a way fared: a search's own status, `failed`, or `-` for `none` (nothing searched).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum RowStatus {
    #[serde(rename = "ok")]
    Ok,
    #[serde(rename = "weak")]
    Weak,
    #[serde(rename = "failed")]
    Failed,
    #[serde(rename = "-")]
    NotSearched,
}

impl RowStatus {
    /// As written in the table and the JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            RowStatus::Ok => "ok",
            RowStatus::Weak => "weak",
            RowStatus::Failed => "failed",
            RowStatus::NotSearched => "-",
        }
    }
}

impl std::fmt::Display for RowStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

impl From<OffsetStatus> for RowStatus {
    fn from(s: OffsetStatus) -> Self {
        match s {
            OffsetStatus::Ok => RowStatus::Ok,
            OffsetStatus::Weak => RowStatus::Weak,
        }
    }
}

/// One method's answer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OffsetRow {
    pub method: OffsetWay,
    /// Δt, seconds (t_est + Δt = reference clock); `None` when the method failed.
    pub offset_s: Option<f64>,
    /// The method's own quality: peak NCC for the correlation methods, the APE RMSE (m) for spatial.
    pub quality: Option<f64>,
    pub status: RowStatus,
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

/// Runs every method on the first estimate of `config`. Returns the rows and the warnings the user must
/// see: the read's (a recording cut short) and, as `eval` warns of a weak offset, one when no method's
/// answer is `ok`.
pub fn compare_offset_methods(
    config: &EvalConfig,
    spatial_range_s: f64,
) -> Result<(Vec<OffsetRow>, Vec<Warning>)> {
    let inputs = crate::eval::inputs::load(config, &|_| {})?;
    let (reference, estimate) = pair_of(&inputs)?;
    let t0 = reference.stamps_ns.first().copied().unwrap_or(0);
    let (ref_t, est_t) = (reference.times_s(t0), estimate.times_s(t0));
    let auto = config.measure(&ref_t, &reference.positions);
    let params = config.resolved(&auto).offset_params();
    let p = ape_pipeline(reference, estimate);
    let row = |method: OffsetWay, found: Result<(f64, Option<f64>, RowStatus)>, start: Instant| {
        let time_ms = start.elapsed().as_secs_f64() * 1e3;
        match found {
            Ok((dt, quality, status)) => OffsetRow {
                method,
                offset_s: Some(dt),
                quality,
                status,
                time_ms,
                ape_rmse_m: ape_rmse_at(reference, estimate, dt, &p),
                error: None,
            },
            Err(e) => OffsetRow {
                method,
                offset_s: None,
                quality: None,
                status: RowStatus::Failed,
                time_ms,
                ape_rmse_m: None,
                error: Some(e.to_string()),
            },
        }
    };
    let mut rows = vec![OffsetRow {
        time_ms: 0.0,
        ..row(
            OffsetWay::None,
            Ok((0.0, None, RowStatus::NotSearched)),
            Instant::now(),
        )
    }];
    let start = Instant::now();
    let spatial = spatial_offset(reference, estimate, spatial_range_s)
        .map(|(dt, rmse)| (dt, Some(rmse), RowStatus::Ok));
    rows.push(row(OffsetWay::Spatial, spatial, start));
    let (r, e) = (
        (&ref_t[..], &reference.positions[..]),
        (&est_t[..], &estimate.positions[..]),
    );
    for m in [
        OffsetMethod::Speed,
        OffsetMethod::Curvature,
        OffsetMethod::SignedCurvature,
    ] {
        let start = Instant::now();
        let found = estimate_time_offset(m, r.0, r.1, e.0, e.1, &params)
            .map(|o| (o.offset_s, Some(o.correlation), o.status.into()));
        rows.push(row(m.into(), found, start));
    }
    let start = Instant::now();
    let found = auto_time_offset(r.0, r.1, e.0, e.1, &params).map(|a| {
        (
            a.estimate.offset_s,
            Some(a.estimate.correlation),
            a.estimate.status.into(),
        )
    });
    rows.push(row(OffsetWay::Auto, found, start));
    let mut warnings = inputs.warnings.clone();
    if !rows.iter().any(|r| r.status == RowStatus::Ok) {
        warnings.push(Warning {
            code: WarningCode::WeakTimeOffset,
            message: format!(
                "{}: no method found a confident time offset (each one is weak or failed, see its row). Check the overlap or give --time-offset",
                inputs.estimates[0].label
            ),
        });
    }
    Ok((rows, warnings))
}

/// The reference and the first estimate; every method needs a few samples on each side, fewer are
/// refused by name, not measured.
fn pair_of(inputs: &crate::eval::inputs::Inputs) -> Result<(&Trajectory, &Trajectory)> {
    let estimate = inputs
        .estimates
        .first()
        .ok_or_else(|| Error::InvalidArgument("give an estimate".into()))?;
    for t in [&inputs.reference, estimate] {
        if t.trajectory.len() < 3 {
            return Err(Error::TooFewSamples {
                what: t.label.clone(),
                n: t.trajectory.len(),
                need: 3,
            });
        }
    }
    Ok((&inputs.reference.trajectory, &estimate.trajectory))
}
