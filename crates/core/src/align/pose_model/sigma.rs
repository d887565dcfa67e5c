//! The σ of step 4 (see `mod.rs`): each parameter's error bar from the final fit's jackknife
//! and the profile's windows, with a hidden drift, the valley, two basins and the tilings' cuts,
//! and what it was made of ([`SigmaParts`]); whether a piecewise fit resolves its steps.

use super::tilings::Cuts;
use super::{
    SigmaCombination, SigmaParts, HIDDEN_DRIFT_Z, MIN_POOLED_WINDOWS, POSE_SIGMA_FLOOR_S,
    STEP_RESOLUTION_Z,
};
use crate::align::clock_model::{
    windows_inside, windows_line_sigma_s, windows_offset_sigma_s, ClockModel, ClockSegment,
    OffsetModel,
};
use crate::align::offset_profile::OffsetProfile;
use crate::align::pose_fit::PoseFit;

/// Whether a piecewise fit tells some two neighbouring segments apart: their offsets differ by more
/// than [`STEP_RESOLUTION_Z`] σ of the difference (from the fit's covariance, at least
/// [`POSE_SIGMA_FLOOR_S`] on each side). True for a fit of one segment.
pub fn steps_resolved(fit: &PoseFit) -> bool {
    let c = &fit.covariance;
    let floor = 2.0 * POSE_SIGMA_FLOOR_S * POSE_SIGMA_FLOOR_S;
    let steps = fit.theta.len().saturating_sub(1);
    steps == 0
        || (0..steps).any(|k| {
            let var = c[(k, k)] + c[(k + 1, k + 1)] - 2.0 * c[(k, k + 1)];
            (fit.theta[k + 1] - fit.theta[k]).abs() > STEP_RESOLUTION_Z * var.max(floor).sqrt()
        })
}

/// Step 4: `model`'s parameters and their σ from its fit `last` (σ at least
/// [`POSE_SIGMA_FLOOR_S`]). An offset's σ (the constant's, each segment's) pools the fit's
/// jackknife with what the profile's windows give for it (their calibrated σ combined and raised by
/// their scatter, scaled to the fit's windows by [`windows_share`], with the share of σ the fitted
/// lever adds, which they hold): the mean of the two
/// variances, at least the formal σ. The line's σ are the
/// fit's, at least the windows' (see `mod.rs`). The constant's σ also adds a drift the
/// profile measures beyond [`HIDDEN_DRIFT_Z`] of its σ, and `valley_s` (the lead search's: half
/// the distance to a fit the windows cannot tell from it), both in quadrature; the piecewise
/// model's headline is its longest segment's. Returns what the headline σ was made of.
pub(super) fn set_parameters(
    model: &mut ClockModel,
    last: &PoseFit,
    profile: &OffsetProfile,
    valley_s: f64,
    cuts: Cuts,
) -> Option<SigmaParts> {
    let sigma = |k: usize, floor_s: Option<f64>| {
        let s = last.theta_sigma[k].max(POSE_SIGMA_FLOOR_S);
        floor_s.map_or(s, |f| s.max(f))
    };
    let parts = |k: usize, windows_s: Option<f64>, combined: SigmaCombination| SigmaParts {
        jackknife_s: last.theta_jackknife_sigma[k],
        formal_s: last.theta_formal_sigma[k],
        windows_s,
        lever_s: 0.0,
        hidden_drift_s: 0.0,
        valley_s: 0.0,
        basins_s: 0.0,
        cuts_s: 0.0,
        combined,
    };
    // An offset over the windows inside `span`: its σ and what it was made of.
    let offset_sigma = |k: usize, span: (f64, f64)| {
        let windows_s = windows_offset_sigma_s(profile, span);
        let jackknife = last.theta_jackknife_sigma[k];
        let inside = windows_inside(profile, span);
        match windows_s {
            Some(w) if jackknife > 0.0 && inside >= MIN_POOLED_WINDOWS => {
                let lever_s = last.lever_share_s(k);
                // k windows combined estimate a k-window answer's error; the fit's is over n.
                let fitted = last
                    .windows
                    .iter()
                    .filter(|x| (span.0..=span.1).contains(&x.t()))
                    .count();
                let w = w * windows_share(inside, fitted).sqrt();
                let windows_s = Some(w);
                let windows_var = w * w + lever_s * lever_s;
                let s = ((jackknife * jackknife + windows_var) / 2.0)
                    .sqrt()
                    .max(last.theta_formal_sigma[k])
                    .max(POSE_SIGMA_FLOOR_S);
                let parts = SigmaParts {
                    lever_s,
                    ..parts(k, windows_s, SigmaCombination::Pooled)
                };
                (s, parts)
            }
            _ => (
                sigma(k, windows_s),
                parts(k, windows_s, SigmaCombination::Larger),
            ),
        }
    };
    match model.model {
        OffsetModel::Constant => {
            model.offset_s = last.theta[0];
            // A drift below the resolution that the constant could hide (see `mod.rs`).
            let hidden = match (model.drift_ppm, model.drift_sigma_ppm) {
                (Some(d), Some(s)) if d.abs() > HIDDEN_DRIFT_Z * s => {
                    let excess = (d * d - s * s).sqrt() * 1e-6;
                    excess * time_spread(profile)
                }
                _ => 0.0,
            };
            let (sigma_s, parts) = offset_sigma(0, (f64::NEG_INFINITY, f64::INFINITY));
            // The mean over tilings keeps less of what the cuts choose (`over_tilings`), where
            // the tilings' spread is resolved from σ (`Cuts::resolved_against`).
            let cuts_s = if cuts.resolved_against(sigma_s) {
                cuts.removed_s
            } else {
                0.0
            };
            let sigma_s = (sigma_s * sigma_s - cuts_s * cuts_s)
                .max(0.0)
                .sqrt()
                .max(last.theta_formal_sigma[0])
                .max(POSE_SIGMA_FLOOR_S)
                .min(sigma_s);
            // Windows in two basins (see `clock_model::steps_out_and_back`): σ covers both.
            let basins_s = 0.5 * model.alternation_s;
            model.sigma_s =
                (sigma_s * sigma_s + hidden * hidden + valley_s * valley_s + basins_s * basins_s)
                    .sqrt();
            Some(SigmaParts {
                hidden_drift_s: hidden,
                valley_s,
                basins_s,
                cuts_s,
                ..parts
            })
        }
        OffsetModel::Linear => {
            // `choose_model` left the drift's σ from the profile's line.
            model.offset_s = last.theta[0];
            let floor = windows_line_sigma_s(profile, model.t_mid);
            model.sigma_s = sigma(0, floor);
            model.drift_ppm = Some(-last.theta[1] * 1e6);
            let drift_floor = model
                .drift_sigma_ppm
                .filter(|s| s.is_finite())
                .map_or(0.0, |s| s * 1e-6);
            model.drift_sigma_ppm = Some(last.theta_sigma[1].max(drift_floor) * 1e6);
            Some(parts(0, floor, SigmaCombination::Larger))
        }
        OffsetModel::Piecewise => {
            let mut each = Vec::with_capacity(model.segments.len());
            for (k, s) in model.segments.iter_mut().enumerate() {
                let (sigma_s, parts) = offset_sigma(k, (s.t_start, s.t_end));
                *s = ClockSegment {
                    offset_s: last.theta[k],
                    sigma_s,
                    ..*s
                };
                each.push(parts);
            }
            // What the headline's σ was made of: its segment's.
            let k = model.headline_from_longest_segment()?;
            each.into_iter().nth(k)
        }
    }
}

/// The share of the final fit's `fitted` windows that the profile's `inside` windows make (at
/// most 1; 1 where the fit's windows are not known). The profile's windows combined estimate the
/// error of an answer over those windows alone; the fit's answer is over all of its windows, each
/// about as informative (the same length, the same data), so its error is the windows' σ times
/// √(share). Where the profile keeps every window the share is 1 and nothing changes; where few of
/// them converged (a walking robot's profile measured on the narrow Jacobian: 3 of 30), the
/// windows' combined σ would otherwise be an error bar for a 3-window answer.
///
/// ```
/// # use trajdrift_core::align::pose_model::windows_share;
/// assert_eq!(windows_share(30, 30), 1.0);
/// assert_eq!(windows_share(3, 30), 0.1);
/// assert_eq!(windows_share(5, 4), 1.0); // a profile window straddling two of the fit's
/// assert_eq!(windows_share(5, 0), 1.0); // the fit's windows unknown
/// ```
pub fn windows_share(inside: usize, fitted: usize) -> f64 {
    if fitted > inside {
        inside as f64 / fitted as f64
    } else {
        1.0
    }
}

/// The weighted standard deviation of the usable windows' times, seconds.
fn time_spread(p: &OffsetProfile) -> f64 {
    let w = p.usable();
    let (mut s, mut st, mut stt) = (0.0, 0.0, 0.0);
    for x in &w {
        let q = 1.0 / (x.sigma_s * x.sigma_s);
        s += q;
        st += q * x.t;
        stt += q * x.t * x.t;
    }
    if s <= 0.0 {
        return 0.0;
    }
    let m = st / s;
    (stt / s - m * m).max(0.0).sqrt()
}
