//! The fitted lateral lever-arm correction of the Drift Error (beyond the paper: `--lever-correction fit`).
//!
//! Why: the paper's α = r_ref/r_est needs both radii per curvature segment, which are noisy, so its gate
//! rarely passes and it barely changes the DE. A *lateral* lever arm has a much simpler signature. Let the
//! estimate sensor sit at `d` metres to the LEFT of the reference point (body frame x forward, y left,
//! z up, as truth.json `lever_arms`). When the body moves along its heading ψ at speed v and turns at rate
//! ψ̇ (no sideslip), the estimate sensor moves at v − d·ψ̇, so over a window its path is
//!
//! L_est = s·(L_ref − d·Δψ)
//!
//! with Δψ the signed heading change over the window (counter-clockwise positive, seen from above) and s
//! the estimate's scale (1.02 = 2 % too long), valid while the turn radius stays above |d| everywhere
//! (otherwise the sensor moves backwards on part of the turn: rotation in place). A forward lever arm
//! changes the path only to second order (speed √(v² + (x·ψ̇)²)), so it is not modelled.
//!
//! The model is linear in (s, s·d): a least-squares fit over all windows gives both, with windows that
//! contain a rotation in place left out, then windows where the formula breaks (|d·Δψ| ≥ L_ref/2: mean
//! radius below 2|d|) or whose residual is an outlier (> 3 robust σ) dropped in a few refits. When the
//! windows turn too little to tell d apart from noise (standard error of d above
//! [`MAX_LEVER_STD_ERR_M`], e.g. a straight mission) d is 0 and s alone is fitted.
//!
//! The corrected window then has DE = |1 − L_est/(L_ref − d·Δψ)| (reported α = L_ref/(L_ref − d·Δψ), 1
//! where the formula breaks), so s itself stays in the DE: it is the drift being measured.
//!
//! Δψ comes from positions alone: the signed turning angle (in the horizontal xy plane) at each vertex of
//! the reference's ε-decimated polyline is split half to each adjacent chord, and a window's Δψ is the sum
//! over its chords. The sum telescopes to the heading change between the chords around the window's two
//! ends, so vertex noise does not accumulate (with 2 cm of noise and 1 m chords, about 0.04 rad), and each
//! turn is wrapped to (−π, π] on its own, so whole loops are counted. Chords shorter than ε/2 (forced
//! vertices at the boundaries of a rotation in place, the last vertex) are skipped: their direction is
//! noise and one wrong wrap would add 2π. Turns across a chord that counts zero length (inside a rotation
//! in place) are dropped, like the paths there.
//!
//! Hand-written: a two-unknown least squares with trimming is a few lines; no crate does this fit.

use super::decimate::DecimatedPath;
use crate::stats::median;

/// Above this standard error (metres) the lateral lever arm is not identifiable and is set to 0.
pub const MAX_LEVER_STD_ERR_M: f64 = 0.1;

/// Refits after dropping breaking or outlying windows.
const MAX_REFITS: usize = 6;

/// Cumulative heading change of a decimated reference polyline, per vertex.
#[derive(Debug, Clone)]
pub struct HeadingTrack {
    /// `prefix[k]`: heading change attributed to chords `0..k`, radians.
    prefix: Vec<f64>,
}

impl HeadingTrack {
    /// Builds the track of `path` (see the module doc for the rule). Chords shorter than `min_chord_m`
    /// horizontally (the short ones the decimation forces at excluded-interval boundaries and at the end,
    /// whose direction is noise) take no part: the turn is measured between the counted chords around
    /// them, unless a chord counting zero length lies in between.
    pub fn new(path: &DecimatedPath<'_>, min_chord_m: f64) -> Self {
        let m = path.t.len();
        let mut share = vec![0.0; m.saturating_sub(1)];
        // The previous usable chord: its index and horizontal direction.
        let mut prev: Option<(usize, f64, f64)> = None;
        for c in 0..m.saturating_sub(1) {
            if path.s[c + 1] <= path.s[c] {
                prev = None; // inside a rotation in place: no turn across it
                continue;
            }
            let v = path.p[c + 1] - path.p[c];
            if v.x.hypot(v.y) < min_chord_m.max(1e-9) {
                continue;
            }
            if let Some((pc, px, py)) = prev {
                let turn = (px * v.y - py * v.x).atan2(px * v.x + py * v.y);
                share[pc] += 0.5 * turn;
                share[c] += 0.5 * turn;
            }
            prev = Some((c, v.x, v.y));
        }
        let mut prefix = Vec::with_capacity(m);
        prefix.push(0.0);
        for x in share {
            prefix.push(prefix.last().copied().unwrap_or(0.0) + x);
        }
        HeadingTrack { prefix }
    }

    /// Signed heading change Δψ between vertices `start` and `end` (indices into the path), radians,
    /// counter-clockwise positive.
    pub fn change(&self, start: usize, end: usize) -> f64 {
        let n = self.prefix.len();
        if n == 0 {
            return 0.0;
        }
        self.prefix[end.min(n - 1)] - self.prefix[start.min(n - 1)]
    }
}

/// One window as the fit sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitSample {
    /// L_ref, metres.
    pub ref_length_m: f64,
    /// L_est, metres (uncorrected).
    pub est_length_m: f64,
    /// Δψ of the reference over the window, radians.
    pub heading_change_rad: f64,
    /// False for windows the fit must not use (a rotation in place inside).
    pub usable: bool,
}

/// The fitted model L_est = s·(L_ref − d·Δψ).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LeverFit {
    /// s: the estimate's path scale (1.02 = 2 % too long).
    pub scale: f64,
    /// d: lateral lever arm, metres; > 0 = the estimate sensor LEFT of the reference point (x forward,
    /// y left, z up). 0 when not identifiable.
    pub lateral_lever_m: f64,
    /// Standard error of d, metres (`None` when d was not fitted).
    pub lateral_lever_std_err_m: Option<f64>,
    /// Windows the final fit used.
    pub windows_used: usize,
}

/// True when L_ref − d·Δψ is a valid model of the window (mean radius at least 2|d|).
pub fn formula_holds(ref_length_m: f64, heading_change_rad: f64, lever_m: f64) -> bool {
    ref_length_m > 0.0 && (lever_m * heading_change_rad).abs() < 0.5 * ref_length_m
}

/// α of a window under the fitted lever: L_ref/(L_ref − d·Δψ), or 1 where the formula breaks.
///
/// ```
/// use trajdrift_core::metrics::lever_fit::fit_alpha;
/// // A 5 m window turning a quarter circle left, estimate 0.5 m to the left: its path is shorter.
/// let a = fit_alpha(5.0, std::f64::consts::FRAC_PI_2, 0.5);
/// assert!((a - 5.0 / (5.0 - 0.5 * std::f64::consts::FRAC_PI_2)).abs() < 1e-12);
/// assert_eq!(fit_alpha(1.0, 6.3, 0.5), 1.0); // radius below 2|d|: no correction
/// ```
pub fn fit_alpha(ref_length_m: f64, heading_change_rad: f64, lever_m: f64) -> f64 {
    if formula_holds(ref_length_m, heading_change_rad, lever_m) {
        ref_length_m / (ref_length_m - lever_m * heading_change_rad)
    } else {
        1.0
    }
}

/// Least squares of L_est = a·L_ref − b·Δψ over `used`; (a, b, residual variance, (NᵀN)⁻¹_bb).
fn solve(samples: &[FitSample], used: &[bool]) -> Option<(f64, f64, f64, f64)> {
    let (mut sll, mut slp, mut spp, mut sly, mut spy, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0usize);
    for (x, _) in samples.iter().zip(used).filter(|(_, &u)| u) {
        let (l, p, y) = (x.ref_length_m, -x.heading_change_rad, x.est_length_m);
        sll += l * l;
        slp += l * p;
        spp += p * p;
        sly += l * y;
        spy += p * y;
        n += 1;
    }
    let det = sll * spp - slp * slp;
    if n < 3 || det.is_nan() || det <= 1e-12 * sll * spp.max(1e-12) {
        return None;
    }
    let a = (spp * sly - slp * spy) / det;
    let b = (sll * spy - slp * sly) / det;
    let rss: f64 = samples
        .iter()
        .zip(used)
        .filter(|(_, &u)| u)
        .map(|(x, _)| (x.est_length_m - a * x.ref_length_m + b * x.heading_change_rad).powi(2))
        .sum();
    Some((a, b, rss / (n - 2) as f64, sll / det))
}

/// Scale alone (d = 0): L_est = s·L_ref.
fn scale_only(samples: &[FitSample], used: &[bool]) -> Option<(f64, usize)> {
    let (mut sll, mut sly, mut n) = (0.0, 0.0, 0usize);
    for (x, _) in samples.iter().zip(used).filter(|(_, &u)| u) {
        sll += x.ref_length_m * x.ref_length_m;
        sly += x.ref_length_m * x.est_length_m;
        n += 1;
    }
    (sll > 0.0).then(|| (sly / sll, n))
}

/// Fits s and d over the windows (see the module doc). `None` without any usable window.
pub fn fit_scale_and_lever(samples: &[FitSample]) -> Option<LeverFit> {
    let base: Vec<bool> = samples
        .iter()
        .map(|x| {
            x.usable
                && x.ref_length_m > 0.0
                && x.ref_length_m.is_finite()
                && x.est_length_m.is_finite()
                && x.heading_change_rad.is_finite()
        })
        .collect();
    let mut used = base.clone();
    let mut fitted = None;
    for _ in 0..MAX_REFITS {
        let Some((a, b, var, cbb)) = solve(samples, &used) else {
            break;
        };
        if a.is_nan() || a <= 0.0 {
            break;
        }
        let d = b / a;
        let se = var.max(0.0).sqrt() * cbb.max(0.0).sqrt() / a;
        fitted = Some((a, d, se, used.iter().filter(|&&u| u).count()));
        // Drop the windows where the formula breaks, and outliers beyond 3 robust σ.
        let resid: Vec<f64> = samples
            .iter()
            .map(|x| x.est_length_m - a * x.ref_length_m + b * x.heading_change_rad)
            .collect();
        let kept: Vec<f64> = resid
            .iter()
            .zip(&used)
            .filter(|(_, &u)| u)
            .map(|(r, _)| r.abs())
            .collect();
        let limit = 3.0 * 1.4826 * median(&kept).unwrap_or(0.0);
        let next: Vec<bool> = samples
            .iter()
            .zip(&base)
            .zip(&resid)
            .map(|((x, &ok), r)| {
                ok && formula_holds(x.ref_length_m, x.heading_change_rad, d)
                    && r.abs() <= limit.max(1e-9)
            })
            .collect();
        if next == used {
            break;
        }
        used = next;
    }
    match fitted {
        Some((s, d, se, n)) if se.is_finite() && se <= MAX_LEVER_STD_ERR_M => Some(LeverFit {
            scale: s,
            lateral_lever_m: d,
            lateral_lever_std_err_m: Some(se),
            windows_used: n,
        }),
        _ => scale_only(samples, &base).map(|(s, n)| LeverFit {
            scale: s,
            lateral_lever_m: 0.0,
            lateral_lever_std_err_m: None,
            windows_used: n,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use proptest::prelude::*;

    /// A circle of radius r, counter-clockwise, sampled every `step` radians.
    fn circle(r: f64, turns: f64, step: f64) -> (Vec<f64>, Vec<Vector3<f64>>) {
        let n = (turns * std::f64::consts::TAU / step) as usize;
        (0..=n)
            .map(|i| {
                let a = i as f64 * step;
                (i as f64, Vector3::new(r * a.cos(), r * a.sin(), 0.0))
            })
            .unzip()
    }

    #[test]
    fn heading_change_counts_whole_loops() {
        let (t, p) = circle(3.0, 2.0, 0.05);
        let path = DecimatedPath::new(&t, &p, 0.5, &[]);
        let h = HeadingTrack::new(&path, 0.25);
        let m = path.t.len();
        // Two loops minus half a chord's turn at each end.
        let total = h.change(0, m - 1);
        assert!((total - 2.0 * std::f64::consts::TAU).abs() < 0.3, "{total}");
        // Clockwise flips the sign.
        let q: Vec<_> = p.iter().map(|v| Vector3::new(v.x, -v.y, 0.0)).collect();
        let path = DecimatedPath::new(&t, &q, 0.5, &[]);
        let h2 = HeadingTrack::new(&path, 0.25);
        assert!((h2.change(0, m - 1) + total).abs() < 1e-9);
    }

    #[test]
    fn straight_windows_fall_back_to_scale_only() {
        let xs: Vec<FitSample> = (0..20)
            .map(|i| FitSample {
                ref_length_m: 5.0,
                est_length_m: 5.1 + 1e-3 * ((i * 7) % 5) as f64,
                heading_change_rad: 1e-3 * ((i * 3) % 4) as f64 - 1.5e-3,
                usable: true,
            })
            .collect();
        let f = fit_scale_and_lever(&xs).unwrap();
        assert_eq!(f.lateral_lever_m, 0.0);
        assert!((f.scale - 1.0208).abs() < 1e-3, "{f:?}");
        assert!(fit_scale_and_lever(&[]).is_none());
    }

    proptest! {
        #[test]
        fn recovers_scale_and_lever(s in 0.9f64..1.1, d in -1.0f64..1.0, seed in 0u64..1000) {
            // Windows of 5 m turning pseudo-randomly, a few broken by a rotation in place.
            let xs: Vec<FitSample> = (0..40u64)
                .map(|i| {
                    let psi = (((i * 7919 + seed) % 200) as f64 - 100.0) / 40.0;
                    let broken = i % 13 == 5;
                    FitSample {
                        ref_length_m: 5.0,
                        est_length_m: s * (5.0 - d * psi) + if broken { 3.0 } else { 0.0 },
                        heading_change_rad: psi,
                        usable: true,
                    }
                })
                .collect();
            let f = fit_scale_and_lever(&xs).unwrap();
            prop_assert!((f.scale - s).abs() < 1e-6, "{:?}", f);
            prop_assert!((f.lateral_lever_m - d).abs() < 1e-6, "{:?}", f);
            for x in xs.iter().filter(|x| x.est_length_m < 3.0 * 5.0) {
                let a = fit_alpha(x.ref_length_m, x.heading_change_rad, f.lateral_lever_m);
                if formula_holds(x.ref_length_m, x.heading_change_rad, d) && (x.est_length_m - s * (5.0 - d * x.heading_change_rad)).abs() < 1e-9 {
                    prop_assert!((a * x.est_length_m / x.ref_length_m - s).abs() < 1e-6);
                }
            }
        }
    }
}
