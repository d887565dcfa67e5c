//! The profile's windows (see `mod.rs`, step 2): those that say nothing or contradict their
//! neighbours left out, the rest's σ calibrated by their scatter.

use super::POSE_SIGMA_FLOOR_S;
use crate::align::offset_profile::{OffsetProfile, ProfileWindow};
use crate::align::pose_fit;
use crate::align::time_offset::OffsetMethod;

/// The profile of the windows' offsets, their σ calibrated by the windows' scatter
/// ([`pose_fit::scatter_calibration`]); `None` with fewer than three windows.
pub(super) fn calibrated_profile(
    raw: Vec<pose_fit::WindowOffset>,
    windows: &[pose_fit::Window],
) -> Option<OffsetProfile> {
    if raw.len() < 3 {
        return None;
    }
    let window_s = windows[0].t_end - windows[0].t_start;
    let step_s = windows
        .get(1)
        .map_or(window_s, |w| (w.t_start - windows[0].t_start).min(window_s));
    // The calibration from windows that do not overlap (every window of a disjoint profile; one
    // a window's length apart of an overlapping one): overlapping neighbours share samples and
    // would scatter less than their σ says.
    let mut independent: Vec<(f64, f64, f64)> = Vec::new();
    for w in &raw {
        if independent
            .last()
            .is_none_or(|last| w.t - last.0 >= 0.999 * window_s)
        {
            independent.push((w.t, w.offset_s, w.formal_sigma_s));
        }
    }
    // The formal σ assumes independent residuals; real ones are correlated (gait, drift, slow GNSS
    // errors), so the windows scatter at least as much as it says: a factor below 1 is chance (few
    // windows), not evidence (the calibration keeps f ≥ 1).
    let scatter = pose_fit::scatter_calibration(&independent);
    // A window whose σ is many times the typical one weighs nothing in any fit and pins nothing:
    // left out of the profile.
    let sigmas: Vec<f64> = raw.iter().map(|w| w.formal_sigma_s).collect();
    let typical = crate::align::offset_profile::median(&sigmas).unwrap_or(f64::INFINITY);
    Some(OffsetProfile {
        method: OffsetMethod::Pose,
        window_s,
        step_s,
        sigma_scale: scatter.factor,
        windows: raw
            .iter()
            .filter(|w| w.formal_sigma_s <= MAX_SIGMA_RATIO * typical)
            .map(|w| ProfileWindow {
                t: w.t,
                offset_s: w.offset_s,
                sigma_s: scatter.sigma_s(w.formal_sigma_s).max(POSE_SIGMA_FLOOR_S),
                correlation: w.quality,
                usable: true,
            })
            .collect(),
    })
}

/// A window whose σ exceeds the median window's this many times is left out of the profile (its
/// weight in any fit is under 1 %).
pub const MAX_SIGMA_RATIO: f64 = 10.0;
/// A window's fit must explain this share of its reference's motion (1 − RSS/Σ|p − p̄|²): below it,
/// the reference barely moved (a stop, a turn in place) and the window says nothing about timing.
pub const MIN_WINDOW_QUALITY: f64 = 0.5;
/// A window farther from the median of its neighbours than this many times the windows' typical
/// distance (in units of their σ) is left out of the profile.
pub const NEIGHBOUR_OUTLIER: f64 = 8.0;

/// The profile's windows without those that say nothing (see [`MIN_WINDOW_QUALITY`]) or contradict
/// their neighbours grossly (a wrong root of a weak window): each window against the median of the
/// seven around it, in units of its own σ; the typical such distance (median) sets the scale.
pub(super) fn consistent_windows(raw: Vec<pose_fit::WindowOffset>) -> Vec<pose_fit::WindowOffset> {
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
