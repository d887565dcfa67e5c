//! Clock drift: the offset on the first and the last third of the overlap, how well each is known,
//! and the drift they imply when the difference is larger than its error.
//!
//! A single Δt is the whole story only when both clocks tick at the same rate. On a 2-hour mission a
//! 10 ppm drift moves Δt by 72 ms from start to end, so the offset is measured again on the first
//! and the last third of the overlap (the reference cut to it, the estimate a little wider). Each
//! third is searched around the whole mission's Δt (the estimate is shifted by it first, then a
//! residual within ±[`THIRD_SEARCH_S`] is found with the same method), and the measured drift is
//! the rate error of the estimate's clock between the thirds' mid-times,
//! −(Δt_last − Δt_first)/(t_last − t_first), in parts per million: positive when the estimate's clock
//! runs fast (t_est = t0 + (t − t0)·(1 + ppm·10⁻⁶) − Δt₀, the simulator's model), so that Δt shrinks
//! with time.
//!
//! **How well a third's Δt is known.** A third of a few minutes holds a handful of starts, stops and
//! turns, and the noise of the reference near each of them moves its Δt by milliseconds; a lateral
//! lever arm moves it further (the two sensors' speeds differ in every turn). Two errors are
//! combined: the residual's ([`crate::align::offset_sigma`], which sees the lever arm's systematic
//! difference) and the noise's, measured by injection — the third is aligned again
//! [`INJECTIONS`] times with fresh white noise of each trajectory's own measured σ added, and the
//! spread of the answers is how much noise of that size moves it (the residual cannot see this: at
//! the correlation peak the noise that moved the peak is no longer in the residual). On the shared
//! missions the thirds' errors then fall within 2.5σ (tests/time_offset_auto.rs `thirds_table`).
//!
//! **What is reported.** `measured_ppm` and its `sigma_ppm` always; `drift_ppm` is the measured drift
//! when it exceeds [`SIGNIFICANCE`]·σ, and 0 otherwise: a constant offset is kept unless the data
//! show it does not fit, the usual rule of a model choice (and what a user applies: no one corrects a
//! drift of 200 ± 100 ppm). The smallest drift a mission resolves is `resolution_ppm` =
//! [`SIGNIFICANCE`]·σ: hundreds of ppm on a few minutes, a few ppm on hours.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

use crate::align::auto_params::reference_noise;
use crate::align::time_offset::{estimate_time_offset, OffsetMethod, OffsetParams};

/// Residual offset searched on each third around the whole mission's Δt, seconds.
pub const THIRD_SEARCH_S: f64 = 2.0;
/// Noise injections per third.
pub const INJECTIONS: usize = 16;
/// The fine grid of the injected runs, seconds.
pub const INJECTION_GRID_S: f64 = 0.005;
/// A drift is reported when it exceeds this many standard errors.
pub const SIGNIFICANCE: f64 = 3.0;

/// The offset on the first and the last third of the overlap, and the drift they imply.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ClockDrift {
    /// Δt on the first third, seconds.
    pub first_third_s: f64,
    /// Δt on the last third, seconds.
    pub last_third_s: f64,
    /// Standard errors of the two thirds' Δt, seconds.
    pub first_sigma_s: f64,
    pub last_sigma_s: f64,
    /// Mid-times of the two thirds, seconds on the reference clock (same origin as the inputs).
    pub first_mid_s: f64,
    pub last_mid_s: f64,
    /// −(Δt_last − Δt_first)/(t_last − t_first), parts per million (positive: the estimate's clock
    /// runs fast).
    pub measured_ppm: f64,
    /// Standard error of `measured_ppm`.
    pub sigma_ppm: f64,
    /// `measured_ppm` when it exceeds [`SIGNIFICANCE`]·`sigma_ppm`, else 0 (no evidence of drift).
    pub drift_ppm: f64,
    /// Whether the drift is significant.
    pub significant: bool,
    /// The smallest drift this mission resolves, [`SIGNIFICANCE`]·`sigma_ppm`.
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
    let ref_noise = reference_noise(ref_t, ref_p).unwrap_or(0.0);
    let est_noise = reference_noise(est_t, est_p).unwrap_or(0.0);
    let on = |lo: f64, hi: f64, seed: u64| -> Option<(f64, f64)> {
        // Only the reference is cut to the third: the estimate reaches past it on both sides, so
        // every lag searched sees a whole third of both signals (no edge effects on one side only).
        let margin = 2.0 * THIRD_SEARCH_S + params.speed_window_s;
        let (ri, ei) = (
            range(ref_t, lo, hi),
            range(&shifted, lo - margin, hi + margin),
        );
        let (rt, rp, et, ep) = (
            &ref_t[ri.clone()],
            &ref_p[ri],
            &shifted[ei.clone()],
            &est_p[ei],
        );
        let r = estimate_time_offset(method, rt, rp, et, ep, &p).ok()?;
        let spread = injected_spread(
            method,
            (rt, rp, ref_noise),
            (et, ep, est_noise),
            &p,
            r.offset_s,
            seed,
        );
        let sigma = (r.sigma_s.unwrap_or(0.0).powi(2) + spread.powi(2)).sqrt();
        Some((offset_s + r.offset_s, sigma))
    };
    let (first, s1) = on(a, a + third, 1)?;
    let (last, s2) = on(b - third, b, 2)?;
    let (m0, m1) = (a + 0.5 * third, b - 0.5 * third);
    let measured_ppm = -(last - first) / (m1 - m0) * 1e6;
    let sigma_ppm = (s1 * s1 + s2 * s2).sqrt() / (m1 - m0) * 1e6;
    let significant = measured_ppm.abs() > SIGNIFICANCE * sigma_ppm;
    Some(ClockDrift {
        first_third_s: first,
        last_third_s: last,
        first_sigma_s: s1,
        last_sigma_s: s2,
        first_mid_s: m0,
        last_mid_s: m1,
        measured_ppm,
        sigma_ppm,
        drift_ppm: if significant { measured_ppm } else { 0.0 },
        significant,
        resolution_ppm: SIGNIFICANCE * sigma_ppm,
    })
}

/// The RMS change of the answer when white noise of each trajectory's σ is added to its positions,
/// over [`INJECTIONS`] draws (seeded: the report is reproducible); answers that fail are skipped.
fn injected_spread(
    method: OffsetMethod,
    reference: (&[f64], &[Vector3<f64>], f64),
    estimate: (&[f64], &[Vector3<f64>], f64),
    params: &OffsetParams,
    base_s: f64,
    seed: u64,
) -> f64 {
    let noisy =
        |p: &[Vector3<f64>], sigma: f64, rng: &mut rand_chacha::ChaCha8Rng| match Normal::new(
            0.0, sigma,
        ) {
            Ok(n) if sigma > 0.0 => p
                .iter()
                .map(|q| q + Vector3::new(n.sample(rng), n.sample(rng), n.sample(rng)))
                .collect(),
            _ => p.to_vec(),
        };
    // Noise moves the answer by milliseconds: a coarser fine grid (its parabolic refinement still
    // resolves a fraction of a step) keeps the injections cheap on hour-long thirds.
    let injected = OffsetParams {
        grid_s: params
            .grid_s
            .max(INJECTION_GRID_S)
            .min(params.coarse_grid_s),
        ..*params
    };
    let deviations: Vec<f64> = (0..INJECTIONS as u64)
        .into_par_iter()
        .filter_map(|k| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed * 1000 + k);
            let rp = noisy(reference.1, reference.2, &mut rng);
            let ep = noisy(estimate.1, estimate.2, &mut rng);
            estimate_time_offset(method, reference.0, &rp, estimate.0, &ep, &injected)
                .ok()
                .map(|o| o.offset_s - base_s)
        })
        .collect();
    if deviations.is_empty() {
        return 0.0;
    }
    (deviations.iter().map(|d| d * d).sum::<f64>() / deviations.len() as f64).sqrt()
}

/// Indices of the sorted `t` inside [lo, hi].
fn range(t: &[f64], lo: f64, hi: f64) -> std::ops::Range<usize> {
    t.partition_point(|&x| x < lo)..t.partition_point(|&x| x <= hi)
}
