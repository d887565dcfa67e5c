//! The clock model from the pose fit: the mission's Δt, its profile over windows and the model they
//! support, each with an error bar from the mission's own windows.
//!
//! 1. **Whole mission.** One Δt and the lever D fitted over every window ([`pose_fit::fit`]), from the
//!    offset the signal searches found; windows whose fit leaves a residual far above the others (a
//!    jump of the estimate inside them) are left out.
//! 2. **Profile.** Each window's own Δt with D held ([`pose_fit::profile`]), its σ the window's
//!    least-squares error scaled by the scatter of the windows about their neighbours
//!    ([`pose_fit::scatter_factor`]): model-free for a constant clock and a linear drift alike.
//! 3. **Model.** [`crate::align::clock_model::choose_model`] over the profile: a drift or a step only
//!    when the windows' calibrated σ refute one constant (BIC margin), a step only with two windows
//!    of support on each side.
//! 4. **Final fit.** The chosen model's parameters (constant; offset and drift; one offset per
//!    segment) fitted again with D over every window, and their σ the jackknife over windows (see
//!    [`crate::align::pose_fit`]).
//!
//! A constant clock whose drift the data cannot resolve could still hide one below the resolution:
//! the constant's σ then adds the part of the measured drift beyond its own noise,
//! √(max(0, d² − σ_d²))·(the windows' spread in time), so that 2σ covers the Δt the drift would give
//! anywhere in the mission; on a constant clock this term is usually zero.

use nalgebra::Vector3;

use crate::align::clock_model::{choose_model, ClockModel, ClockSegment, OffsetModel};
use crate::align::offset_profile::{OffsetProfile, ProfileParams, ProfileWindow};
use crate::align::pose_fit::{self, ClockShape, PoseData, PoseFit};
use crate::align::signals::SignalView;
use crate::align::time_offset::OffsetMethod;

/// Least σ of a window or of the headline Δt from the pose fit, seconds (the fit is continuous in
/// Δt; this only keeps a degenerate window from claiming infinite precision).
pub const POSE_SIGMA_FLOOR_S: f64 = 1e-4;
/// The pose fit's Δt may differ from the signal search's by this much at most, seconds: farther, the
/// fit went to another basin and is not used.
pub const MAX_DISAGREEMENT_S: f64 = 0.3;
/// Each window of the profile searches this far around the whole mission's Δt when its own
/// refinement fails (a clock step), seconds.
pub const WINDOW_SEARCH_S: f64 = 3.0;

/// The clock model found by the pose fit.
#[derive(Debug, Clone)]
pub struct PoseClock {
    pub profile: OffsetProfile,
    pub model: ClockModel,
    /// The final fit (the chosen model's parameters, the lever, the windows used).
    pub fit: PoseFit,
    /// The whole-mission constant fit's Δt and σ (what step 1 found).
    pub whole: (f64, f64),
    /// Windows left out of the whole-mission fit (their residual far above the others').
    pub outlier_windows: usize,
}

/// The clock model of the mission in `data` from the pose fit, starting at `start_s` (the signal
/// searches' answer); `None` when the fit cannot be made (too few windows, no convergence, or an
/// answer farther than [`MAX_DISAGREEMENT_S`] from the start).
pub fn pose_clock_model(
    data: &PoseData<'_>,
    start_s: f64,
    profile_params: &ProfileParams,
    signals: Option<(SignalView<'_>, SignalView<'_>)>,
    forced: Option<OffsetModel>,
) -> Option<PoseClock> {
    let data = PoseData {
        params: pose_fit::PoseFitParams {
            window_s: profile_params.window_s.or(data.params.window_s),
            ..data.params
        },
        ..*data
    };
    let windows = data.windows();
    if windows.len() < 3 {
        return None;
    }
    let whole = pose_fit::fit(
        &data,
        &windows,
        ClockShape::Constant,
        vec![start_s],
        Vector3::zeros(),
        true,
    )?;
    if std::env::var("POSE_DEBUG").is_ok() {
        eprintln!(
            "whole: theta {:?} ± {:?} lever {:?} converged {} iterations {} windows {} outliers {} vif {:.1} rms {:?}",
            whole.theta, whole.theta_sigma, whole.lever_m, whole.converged, whole.iterations, whole.windows.len(), whole.outliers.len(), whole.variance_inflation, whole.rms_m
        );
    }
    if !whole.converged || (whole.theta[0] - start_s).abs() > MAX_DISAGREEMENT_S {
        return None;
    }
    let offset0 = whole.theta[0];
    let raw = pose_fit::profile(
        &data,
        &windows,
        whole.lever_m,
        whole.scale,
        &|_| offset0,
        WINDOW_SEARCH_S,
    );
    let raw = consistent_windows(raw);
    if raw.len() < 3 {
        return None;
    }
    let f = pose_fit::scatter_factor(
        &raw.iter()
            .map(|w| (w.t, w.offset_s, w.formal_sigma_s))
            .collect::<Vec<_>>(),
    )
    // The formal σ assumes independent residuals; real ones are correlated (gait, drift, slow GNSS
    // errors), so the windows scatter at least as much as it says: a factor below 1 is chance
    // (few windows), not evidence.
    .max(1.0);
    if std::env::var("POSE_DEBUG").is_ok() {
        eprintln!("scatter factor {f:.2}");
        for w in &raw {
            eprintln!(
                "  raw t {:7.1} offset {:+.5} formal {:.5} rms {:.4} q {:.4}",
                w.t, w.offset_s, w.formal_sigma_s, w.rms_m, w.quality
            );
        }
    }
    let window_s = windows[0].t_end - windows[0].t_start;
    let profile = OffsetProfile {
        method: OffsetMethod::Pose,
        window_s,
        step_s: window_s,
        sigma_scale: f,
        windows: raw
            .iter()
            .map(|w| ProfileWindow {
                t: w.t,
                offset_s: w.offset_s,
                sigma_s: (w.formal_sigma_s * f).max(POSE_SIGMA_FLOOR_S),
                correlation: w.quality,
                usable: true,
            })
            .collect(),
    };
    let whole_sigma = whole.theta_sigma[0].max(POSE_SIGMA_FLOOR_S);
    let mut model = choose_model(&profile, (offset0, whole_sigma), signals, forced);
    // The final fit of the chosen model, lever included, σ by the jackknife over windows.
    let (shape, theta0) = match model.model {
        OffsetModel::Constant => (ClockShape::Constant, vec![offset0]),
        OffsetModel::Linear => (
            ClockShape::Linear { t_mid: model.t_mid },
            vec![model.offset_s, -model.drift_ppm.unwrap_or(0.0) * 1e-6],
        ),
        OffsetModel::Piecewise => (
            ClockShape::Piecewise {
                changes: model.segments.iter().skip(1).map(|s| s.t_start).collect(),
            },
            model.segments.iter().map(|s| s.offset_s).collect(),
        ),
    };
    let last = if model.model == OffsetModel::Constant {
        whole.clone()
    } else {
        pose_fit::fit(&data, &windows, shape, theta0, whole.lever_m, true)?
    };
    let sigma = |k: usize| last.theta_sigma[k].max(POSE_SIGMA_FLOOR_S);
    match model.model {
        OffsetModel::Constant => {
            model.offset_s = last.theta[0];
            // A drift below the resolution that the constant could hide (see the module doc).
            let hidden = match (model.drift_ppm, model.drift_sigma_ppm) {
                (Some(d), Some(s)) => {
                    let excess = ((d * d - s * s).max(0.0)).sqrt() * 1e-6;
                    excess * time_spread(&profile)
                }
                _ => 0.0,
            };
            model.sigma_s = (sigma(0).powi(2) + hidden * hidden).sqrt();
        }
        OffsetModel::Linear => {
            model.offset_s = last.theta[0];
            model.sigma_s = sigma(0);
            model.drift_ppm = Some(-last.theta[1] * 1e6);
            model.drift_sigma_ppm = Some(last.theta_sigma[1] * 1e6);
        }
        OffsetModel::Piecewise => {
            for (k, s) in model.segments.iter_mut().enumerate() {
                *s = ClockSegment {
                    offset_s: last.theta[k],
                    sigma_s: sigma(k),
                    ..*s
                };
            }
            if let Some(s) = model
                .segments
                .iter()
                .max_by(|a, b| (a.t_end - a.t_start).total_cmp(&(b.t_end - b.t_start)))
            {
                model.offset_s = s.offset_s;
                model.sigma_s = s.sigma_s;
            }
        }
    }
    model.describe();
    Some(PoseClock {
        profile,
        model,
        outlier_windows: whole.outliers.len(),
        whole: (offset0, whole_sigma),
        fit: last,
    })
}

/// A window's fit must explain this share of its reference's motion (1 − RSS/Σ|p − p̄|²): below it,
/// the reference barely moved (a stop, a turn in place) and the window says nothing about timing.
pub const MIN_WINDOW_QUALITY: f64 = 0.5;
/// A window farther from the median of its neighbours than this many times the windows' typical
/// distance (in units of their σ) is left out of the profile.
pub const NEIGHBOUR_OUTLIER: f64 = 8.0;

/// The profile's windows without those that say nothing (see [`MIN_WINDOW_QUALITY`]) or contradict
/// their neighbours grossly (a wrong root of a weak window): each window against the median of the
/// seven around it, in units of its own σ; the typical such distance (median) sets the scale.
fn consistent_windows(raw: Vec<pose_fit::WindowOffset>) -> Vec<pose_fit::WindowOffset> {
    let w: Vec<pose_fit::WindowOffset> = raw
        .into_iter()
        .filter(|w| w.quality >= MIN_WINDOW_QUALITY)
        .collect();
    if w.len() < 5 {
        return w;
    }
    let distance: Vec<f64> = (0..w.len())
        .map(|k| {
            let lo = k.saturating_sub(3);
            let hi = (k + 4).min(w.len());
            let around: Vec<f64> = w[lo..hi].iter().map(|x| x.offset_s).collect();
            let m = crate::align::offset_profile::median(&around).unwrap_or(w[k].offset_s);
            (w[k].offset_s - m).abs() / w[k].formal_sigma_s
        })
        .collect();
    let typical = crate::align::offset_profile::median(&distance)
        .unwrap_or(1.0)
        .max(1.0);
    w.into_iter()
        .zip(distance)
        .filter(|(_, d)| *d <= NEIGHBOUR_OUTLIER * typical)
        .map(|(w, _)| w)
        .collect()
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
