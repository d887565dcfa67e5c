//! Step 5 (see `mod.rs`): a constant's Δt and lever the mean over tilings of the windows,
//! and what that mean removes from one tiling's σ.

use nalgebra::Vector3;

use super::{POSE_SIGMA_FLOOR_S, TILINGS, TILINGS_FROM_SIGMA_S, TILING_REACH_SIGMA};
use crate::align::pose_fit::{self, ClockShape, PoseData, PoseFit};

/// The constant `last` (fitted on the mission's windows) with its Δt and lever the mean over
/// [`TILINGS`] tilings of the windows (`last`'s, and each one's cuts shifted by k/`TILINGS` of a
/// window, fitted from `last`); a tiling's fit that does not converge or lands farther than
/// [`TILING_REACH_SIGMA`] of `last`'s σ from it is left out; `last` alone where its σ is below
/// [`TILINGS_FROM_SIGMA_S`]. Everything else (the jackknife, the
/// windows used) stays `last`'s. Also returns the part of one tiling's σ that the mean removes,
/// seconds: s·√(1 − 1/n), s the standard deviation of the n tilings' Δt (0 for one).
///
/// Why: each window holds its own similarity, and which stretch of the slow errors (the estimate's
/// heading wandering, the reference's bias) and of the speed changes a window holds depends on
/// where the cuts fall; on a 1–2 Hz reference the same mission's Δt moved by 10–30 ms from one
/// tiling to the next. Each tiling's error is a part they share (the reference's white noise: the
/// same samples) and a part the cuts choose, of variance s² when the tilings err apart; the mean
/// keeps 1/n of the latter, so the constant's σ (one tiling's) loses s²·(1 − 1/n) in quadrature,
/// never below the formal σ (`set_parameters`). Measured in docs/evidence.md ("The windows' cuts,
/// averaged").
pub(super) fn over_tilings(data: &PoseData<'_>, last: PoseFit) -> (PoseFit, Cuts) {
    if last.theta_sigma[0] < TILINGS_FROM_SIGMA_S {
        return (last, Cuts::NONE);
    }
    let reach_s = TILING_REACH_SIGMA * last.theta_sigma[0].max(POSE_SIGMA_FLOOR_S);
    let with_lever = last.lever_sigma_m.is_some();
    let fits: Vec<(f64, Vector3<f64>)> = (1..TILINGS)
        .filter_map(|k| {
            let windows = data.tiling(k as f64 / TILINGS as f64);
            pose_fit::fit(
                data,
                &windows,
                ClockShape::Constant,
                last.theta.clone(),
                last.lever_m,
                with_lever,
            )
        })
        .filter(|f| f.converged && (f.theta[0] - last.theta[0]).abs() <= reach_s)
        .map(|f| (f.theta[0], f.lever_m))
        .chain([(last.theta[0], last.lever_m)])
        .collect();
    let n = fits.len() as f64;
    let mut mean = last;
    mean.theta[0] = fits.iter().map(|f| f.0).sum::<f64>() / n;
    mean.lever_m = fits.iter().map(|f| f.1).sum::<Vector3<f64>>() / n;
    let removed_s = if fits.len() > 1 {
        let var = fits
            .iter()
            .map(|f| (f.0 - mean.theta[0]).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        (var * (1.0 - 1.0 / n)).sqrt()
    } else {
        0.0
    };
    let tilings = fits.len();
    (mean, Cuts { removed_s, tilings })
}

/// What the mean over tilings removes from one tiling's σ (`over_tilings`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cuts {
    /// s·√(1 − 1/n), s the standard deviation of the n tilings' Δt, seconds.
    pub removed_s: f64,
    /// n: the tilings whose fits joined the mean.
    pub tilings: usize,
}

impl Cuts {
    /// One tiling: nothing removed.
    pub const NONE: Cuts = Cuts {
        removed_s: 0.0,
        tilings: 1,
    };

    /// Whether the removal is resolved against `sigma_s`, the σ of one tiling's Δt: what would
    /// remain of its variance exceeds the removal's own noise (one standard deviation of a
    /// variance from n − 1 degrees of freedom, √(2/(n − 1)) of it; with four tilings, a removal
    /// up to 0.74 of σ). Beyond that the tilings' spread is as large as σ itself, which says
    /// rather that σ came out small than that the mean is nearly exact: where it was taken anyway,
    /// 2σ covered 89 % of 223 missions of a second simulator, 97 % without it (docs/evidence.md,
    /// "The tilings' spread, resolved or not").
    ///
    /// ```
    /// # use trajdrift_core::align::pose_model::Cuts;
    /// let cuts = |removed_s: f64| Cuts { removed_s, tilings: 4 };
    /// assert!(cuts(0.7).resolved_against(1.0));
    /// assert!(!cuts(0.75).resolved_against(1.0));
    /// assert!(!cuts(1.2).resolved_against(1.0));
    /// assert!(!Cuts::NONE.resolved_against(1.0));
    /// ```
    pub fn resolved_against(&self, sigma_s: f64) -> bool {
        if self.tilings < 2 || self.removed_s <= 0.0 {
            return false;
        }
        let removed2 = self.removed_s * self.removed_s;
        let noise = (2.0 / (self.tilings - 1) as f64).sqrt() * removed2;
        sigma_s * sigma_s - removed2 > noise
    }
}
