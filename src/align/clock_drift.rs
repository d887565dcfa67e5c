//! Clock drift: the offset on the first and the last third of the overlap, and the drift they imply.
//!
//! A single Δt is the whole story only when both clocks tick at the same rate. On a 2-hour mission a
//! 10 ppm drift moves Δt by 72 ms from start to end, so the offset is measured again on the first
//! and the last third of the overlap (the reference cut to it, the estimate a little wider). Each
//! third is searched around the whole mission's Δt (the
//! estimate is shifted by it first, then a residual within ±[`THIRD_SEARCH_S`] is found with the
//! same method), and the drift is the rate error of the estimate's clock between the thirds'
//! mid-times, −(Δt_last − Δt_first)/(t_last − t_first), in parts per million: positive when the
//! estimate's clock runs fast (t_est = t0 + (t − t0)·(1 + ppm·10⁻⁶) − Δt₀, the simulator's model), so
//! that Δt shrinks with time.

use nalgebra::Vector3;

use crate::align::time_offset::{estimate_time_offset, OffsetMethod, OffsetParams};

/// Scatter of one third's Δt measured on the simulated missions of 2–6 minutes, seconds (errors of
/// 10–50 ms per third with speed, see tests/time_offset_auto.rs `thirds_table`): the drift is only
/// resolved to about 2·this/(time between the thirds), hundreds of ppm on a few minutes, ~10 ppm
/// on two hours.
pub const THIRD_SCATTER_S: f64 = 0.03;
/// Residual offset searched on each third around the whole mission's Δt, seconds.
pub const THIRD_SEARCH_S: f64 = 2.0;

/// The offset on the first and the last third of the overlap.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ClockDrift {
    /// Δt on the first third, seconds.
    pub first_third_s: f64,
    /// Δt on the last third, seconds.
    pub last_third_s: f64,
    /// Mid-times of the two thirds, seconds on the reference clock (same origin as the inputs).
    pub first_mid_s: f64,
    pub last_mid_s: f64,
    /// −(Δt_last − Δt_first)/(t_last − t_first), parts per million (positive: the estimate's clock
    /// runs fast).
    pub drift_ppm: f64,
    /// The smallest drift this mission resolves, 2·[`THIRD_SCATTER_S`]/(t_last − t_first), ppm: a
    /// `drift_ppm` below it is not evidence of drift.
    pub resolution_ppm: f64,
}

/// Measures Δt on the first and last thirds of the overlap with `method`, around `offset_s` (the
/// whole mission's answer). `None` when either third has no answer (too short, no signal).
pub fn clock_drift(
    method: OffsetMethod,
    ref_t: &[f64],
    ref_p: &[Vector3<f64>],
    est_t: &[f64],
    est_p: &[Vector3<f64>],
    params: &OffsetParams,
    offset_s: f64,
) -> Option<ClockDrift> {
    let (r0, r1) = (*ref_t.first()?, *ref_t.last()?);
    let (e0, e1) = (*est_t.first()? + offset_s, *est_t.last()? + offset_s);
    let (a, b) = (r0.max(e0), r1.min(e1));
    if b - a < 6.0 * THIRD_SEARCH_S {
        return None;
    }
    let third = (b - a) / 3.0;
    let shifted: Vec<f64> = est_t.iter().map(|t| t + offset_s).collect();
    let p = OffsetParams {
        max_offset_s: THIRD_SEARCH_S.min(params.max_offset_s),
        ..*params
    };
    let on = |lo: f64, hi: f64| -> Option<f64> {
        // Only the reference is cut to the third: the estimate reaches past it on both sides, so
        // every lag searched sees a whole third of both signals (no edge effects on one side only).
        let margin = 2.0 * THIRD_SEARCH_S + params.speed_window_s;
        let (ri, ei) = (
            range(ref_t, lo, hi),
            range(&shifted, lo - margin, hi + margin),
        );
        let r = estimate_time_offset(
            method,
            &ref_t[ri.clone()],
            &ref_p[ri],
            &shifted[ei.clone()],
            &est_p[ei],
            &p,
        )
        .ok()?;
        Some(offset_s + r.offset_s)
    };
    let first = on(a, a + third)?;
    let last = on(b - third, b)?;
    let (m0, m1) = (a + 0.5 * third, b - 0.5 * third);
    Some(ClockDrift {
        first_third_s: first,
        last_third_s: last,
        first_mid_s: m0,
        last_mid_s: m1,
        drift_ppm: -(last - first) / (m1 - m0) * 1e6,
        resolution_ppm: 2.0 * THIRD_SCATTER_S / (m1 - m0) * 1e6,
    })
}

/// Indices of the sorted `t` inside [lo, hi].
fn range(t: &[f64], lo: f64, hi: f64) -> std::ops::Range<usize> {
    t.partition_point(|&x| x < lo)..t.partition_point(|&x| x <= hi)
}
