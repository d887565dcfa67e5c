//! The Drift Error (step 3 of the paper): how much longer or shorter the estimate's path is than the
//! reference's over windows of w metres of reference path.
//!
//! Per window, DE = |1 − α·Δs_est/Δs_ref|, with both path lengths measured on ε-decimated polylines
//! (`super::decimate`) over the same time span, α the lever-arm correction ([`super::lever`]), and the
//! paths inside rotations in place (`super::rotation_in_place`) left out of both. Path lengths and
//! angles do not depend on the frame, so the estimate needs no spatial alignment; it must be on the
//! reference's clock (shift it by the time offset first).

use nalgebra::Vector3;

use super::decimate::DecimatedPath;
use super::lever::{segment_alpha, CurvatureTrack, LeverCorrection};
use super::lever_fit::{fit_alpha, fit_scale_and_lever, FitSample, HeadingTrack, LeverFit};
use super::rotation_in_place::{rotations_in_place, RotationInPlaceParams};
use super::windows::{gaps, path_windows, PathWindow};
use crate::align::curvature::{curvature_signature, CurvatureParams};
use crate::error::{Error, Result};
use crate::stats::{summarize, Summary};

/// The parameters of the Drift Error.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DriftParams {
    /// w: window length in metres of reference path.
    pub window_m: f64,
    /// β: overlap of consecutive windows, a fraction in [0, 1).
    pub overlap: f64,
    /// ε of the path decimation, metres. Default 1 m: a chord of length L with position noise σ on
    /// both ends is too long by about 2σ²/L (two perpendicular axes), so with a GNSS-grade reference
    /// (σ = 2 cm) ε = 0.3 m inflates the reference by ~0.5 % and ε = 1 m by ~0.1 %. Larger ε shortens
    /// tight turns (a chord of ε on radius r is short of its arc by ε²/(24r²)), equally for both sensors
    /// when they sit on nearly the same radius.
    pub path_eps_m: f64,
    /// Δt_max: a reference or estimate gap longer than this drops the window, seconds.
    pub dt_max_s: f64,
    /// Lever-arm correction.
    pub lever_correction: LeverCorrection,
    /// a: the expected lever arm between the sensors, metres.
    pub lever_arm_m: f64,
    /// Curvature (eq. 1) parameters for the radii of the lever-arm correction (default ε_min 0.5 m).
    pub curvature: CurvatureParams,
}

impl DriftParams {
    /// The rotation-in-place detector's parameters: a standstill lasts at least Δt_max (the paper's
    /// "no ε-chord within Δt_max"), inside a ball of [`STILL_RADIUS_M`].
    pub fn rotation_in_place(&self) -> RotationInPlaceParams {
        RotationInPlaceParams {
            still_radius_m: STILL_RADIUS_M,
            min_still_s: self.dt_max_s,
        }
    }
}

/// Radius within which the reference counts as standing still, metres: well above GNSS-RTK or
/// motion-capture noise (≤ 3 cm), well below any lever arm worth correcting for.
pub const STILL_RADIUS_M: f64 = 0.15;

impl Default for DriftParams {
    fn default() -> Self {
        DriftParams {
            window_m: 5.0,
            overlap: 0.0,
            path_eps_m: 1.0,
            dt_max_s: 2.0,
            lever_correction: LeverCorrection::Fit,
            lever_arm_m: 0.1,
            curvature: CurvatureParams {
                eps_m: 0.5,
                ..CurvatureParams::default()
            },
        }
    }
}

/// One window's Drift Error.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DriftWindow {
    /// Start of the window, seconds (reference clock, same origin as the inputs).
    pub t_start: f64,
    /// End of the window, seconds.
    pub t_end: f64,
    /// Δs_ref: the reference's decimated path length, metres.
    pub ref_length_m: f64,
    /// Δs_est: the estimate's decimated path length, uncorrected, metres.
    pub est_length_m: f64,
    /// α: corrected / uncorrected estimate length (1 without correction).
    pub alpha: f64,
    /// DE = |1 − α·Δs_est/Δs_ref|.
    pub de: f64,
}

/// The Drift Error of an estimate for one window length.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DriftErrorResult {
    /// w, metres.
    pub window_m: f64,
    /// The lever-arm correction applied.
    pub lever_correction: LeverCorrection,
    /// The kept windows, in time order.
    pub windows: Vec<DriftWindow>,
    /// Windows dropped for crossing a reference or estimate gap longer than Δt_max.
    pub dropped_windows: usize,
    /// Fraction of the reference's samples skipped by the ε-decimation.
    pub discarded_fraction: f64,
    /// Fraction of the estimate's samples skipped by the ε-decimation.
    pub discarded_fraction_estimate: f64,
    /// Statistics of the windows' DE; `None` without windows.
    pub stats: Option<Summary>,
    /// Rotations in place left out of both paths, `[t_start, t_end]` seconds.
    pub excluded_intervals: Vec<[f64; 2]>,
    /// The fitted scale and lateral lever arm ([`LeverCorrection::Fit`] only).
    pub lever_fit: Option<LeverFit>,
}

/// The Drift Error for `params.window_m`. Times are seconds relative to a common origin, increasing;
/// `est_t` is already shifted onto the reference clock. Positions may be in unrelated frames.
pub fn drift_error(
    ref_t: &[f64],
    ref_p: &[Vector3<f64>],
    est_t: &[f64],
    est_p: &[Vector3<f64>],
    params: &DriftParams,
) -> Result<DriftErrorResult> {
    let mut all = drift_error_windows(ref_t, ref_p, est_t, est_p, params, &[params.window_m])?;
    all.pop()
        .ok_or_else(|| Error::InvalidArgument("no window length given".into()))
}

/// The Drift Error for several window lengths (`params.window_m` is ignored), sharing the decimation,
/// the curvature signatures and the rotation-in-place detection. One result per entry of `windows_m`.
pub fn drift_error_windows(
    ref_t: &[f64],
    ref_p: &[Vector3<f64>],
    est_t: &[f64],
    est_p: &[Vector3<f64>],
    params: &DriftParams,
    windows_m: &[f64],
) -> Result<Vec<DriftErrorResult>> {
    check_input("reference", ref_t, ref_p)?;
    check_input("estimate", est_t, est_p)?;
    check_params(params)?;
    let (r0, r1) = (ref_t[0], ref_t[ref_t.len() - 1]);
    let (e0, e1) = (est_t[0], est_t[est_t.len() - 1]);
    if e1 <= r0 || e0 >= r1 {
        return Err(Error::NoOverlap {
            estimate: "estimate".into(),
            est_start: e0,
            est_end: e1,
            ref_start: r0,
            ref_end: r1,
            offset: 0.0,
        });
    }

    let excluded = rotations_in_place(ref_t, ref_p, est_t, est_p, &params.rotation_in_place());
    let ref_path = DecimatedPath::new(ref_t, ref_p, params.path_eps_m, &excluded);
    let est_path = DecimatedPath::new(est_t, est_p, params.path_eps_m, &excluded);

    // No window may cross a gap of either trajectory; all lie inside the estimate's span.
    let mut blocked = gaps(ref_t, params.dt_max_s);
    blocked.extend(gaps(est_t, params.dt_max_s));
    blocked.sort_by(|a, b| a[0].total_cmp(&b[0]));

    let tracks = match params.lever_correction {
        LeverCorrection::Paper => Some((
            CurvatureTrack::new(
                &curvature_signature(ref_t, ref_p, &params.curvature),
                params.curvature.dt_max_s,
            ),
            CurvatureTrack::new(
                &curvature_signature(est_t, est_p, &params.curvature),
                params.curvature.dt_max_s,
            ),
        )),
        LeverCorrection::None | LeverCorrection::Fit => None,
    };
    let headings = (params.lever_correction == LeverCorrection::Fit)
        .then(|| HeadingTrack::new(&ref_path, 0.5 * params.path_eps_m));

    windows_m
        .iter()
        .map(|&w| {
            let layout = path_windows(&ref_path, w, params.overlap, [e0, e1], &blocked)?;
            let mut windows: Vec<DriftWindow> = layout
                .windows
                .iter()
                .map(|win| window_de(win, &ref_path, &est_path, tracks.as_ref(), params))
                .collect();
            let lever_fit = headings
                .as_ref()
                .and_then(|h| apply_lever_fit(&mut windows, &layout.windows, h, &excluded));
            let des: Vec<f64> = windows.iter().map(|w| w.de).collect();
            Ok(DriftErrorResult {
                window_m: w,
                lever_correction: params.lever_correction,
                stats: summarize(&des),
                windows,
                dropped_windows: layout.dropped,
                discarded_fraction: ref_path.discarded_fraction(),
                discarded_fraction_estimate: est_path.discarded_fraction(),
                excluded_intervals: excluded.clone(),
                lever_fit,
            })
        })
        .collect()
}

/// One window's Drift Error: the two path lengths over its time span, the estimate's corrected per
/// curvature segment by the paper's α when `tracks` (reference, estimate) are given.
fn window_de(
    win: &PathWindow,
    ref_path: &DecimatedPath,
    est_path: &DecimatedPath,
    tracks: Option<&(CurvatureTrack, CurvatureTrack)>,
    params: &DriftParams,
) -> DriftWindow {
    let ref_len = ref_path.s[win.end] - ref_path.s[win.start];
    let est_raw = est_path.length_between(win.t_start, win.t_end);
    let est_corr = match tracks {
        None => est_raw,
        Some((kr, ke)) => (win.start..win.end)
            .map(|a| {
                let (ta, tb) = (ref_path.t[a], ref_path.t[a + 1]);
                let alpha = segment_alpha(
                    kr.mean_between(ta, tb),
                    ke.mean_between(ta, tb),
                    params.lever_arm_m,
                );
                alpha * est_path.length_between(ta, tb)
            })
            .sum(),
    };
    DriftWindow {
        t_start: win.t_start,
        t_end: win.t_end,
        ref_length_m: ref_len,
        est_length_m: est_raw,
        alpha: if est_raw > 0.0 {
            est_corr / est_raw
        } else {
            1.0
        },
        de: (1.0 - est_corr / ref_len).abs(),
    }
}

/// The fitted lever correction (`--lever-correction fit`): the scale and lateral lever fitted over
/// all `windows` (their heading changes from `headings`; rotations in place, `excluded`, left out),
/// then each window's α and DE from the fit. `None` when the fit fails (the windows keep their
/// uncorrected DE).
fn apply_lever_fit(
    windows: &mut [DriftWindow],
    layout: &[PathWindow],
    headings: &HeadingTrack,
    excluded: &[[f64; 2]],
) -> Option<LeverFit> {
    let dpsi: Vec<f64> = layout
        .iter()
        .map(|win| headings.change(win.start, win.end))
        .collect();
    let samples: Vec<FitSample> = windows
        .iter()
        .zip(&dpsi)
        .map(|(w, &psi)| FitSample {
            ref_length_m: w.ref_length_m,
            est_length_m: w.est_length_m,
            heading_change_rad: psi,
            usable: !excluded
                .iter()
                .any(|iv| iv[0] < w.t_end && iv[1] > w.t_start),
        })
        .collect();
    let fit = fit_scale_and_lever(&samples)?;
    for (w, &psi) in windows.iter_mut().zip(&dpsi) {
        w.alpha = fit_alpha(w.ref_length_m, psi, fit.lateral_lever_m);
        w.de = (1.0 - w.alpha * w.est_length_m / w.ref_length_m).abs();
    }
    Some(fit)
}

fn check_input(what: &str, t: &[f64], p: &[Vector3<f64>]) -> Result<()> {
    if t.len() != p.len() {
        return Err(Error::InvalidArgument(format!(
            "{what}: {} stamps but {} positions",
            t.len(),
            p.len()
        )));
    }
    if t.len() < 3 {
        return Err(Error::TooFewSamples {
            what: what.into(),
            n: t.len(),
            need: 3,
        });
    }
    if t.iter().any(|x| !x.is_finite()) || t.windows(2).any(|w| w[1] <= w[0]) {
        return Err(Error::InvalidArgument(format!(
            "{what}: stamps must be finite and strictly increasing; sort and deduplicate the trajectory first"
        )));
    }
    if p.iter().any(|v| !v.iter().all(|x| x.is_finite())) {
        return Err(Error::InvalidArgument(format!(
            "{what}: positions must be finite"
        )));
    }
    Ok(())
}

fn check_params(p: &DriftParams) -> Result<()> {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !(p.path_eps_m.is_finite() && p.path_eps_m >= 0.0) {
        return Err(Error::InvalidArgument(format!(
            "path ε {} m: must be a non-negative number of metres",
            p.path_eps_m
        )));
    }
    if !positive(p.dt_max_s) {
        return Err(Error::InvalidArgument(format!(
            "Δt_max {} s: must be a positive number of seconds",
            p.dt_max_s
        )));
    }
    if !(p.lever_arm_m.is_finite() && p.lever_arm_m >= 0.0) {
        return Err(Error::InvalidArgument(format!(
            "lever arm {} m: must be a non-negative number of metres",
            p.lever_arm_m
        )));
    }
    Ok(())
}
