//! The lead search (see `mod.rs`): fits along the forward lever's valley from a scan of Δt
//! over the lead a lever makes at a walk, judged on the referee's longer windows; the valley's σ
//! where the windows cannot tell two of them apart.

use nalgebra::Vector3;

use super::{
    walking, BeyondLever, LEAD_LEVER_M, LEAD_MINIMA, LEAD_SCAN_WINDOWS, LEAD_SIGNIFICANCE_T,
    LEAD_STEP_S, MAX_DISAGREEMENT_S, MAX_LEAD_S, MIN_POOLED_WINDOWS, REFEREE_MIN_WINDOWS,
    REFEREE_WINDOW_S, SAME_BASIN_S,
};
use crate::align::clock_model::OffsetModel;
use crate::align::pose_fit::{self, ClockShape, PoseData, PoseFit};

/// What the lead search found: the fits along the forward lever's valley (the near one among
/// them), judged over `windows` (the referee's, [`referee_windows`], less those holding a window
/// any of the fits left out as a jump).
pub(super) struct Lead {
    pub(super) windows: Vec<pose_fit::Window>,
    pub(super) fits: Vec<LeadFit>,
    /// The fits left out for their forward lever ([`within_lead_lever`]), judged on `windows`.
    pub(super) beyond: Vec<LeadFit>,
}

/// A fit along the valley: the residual per point at its Δt in every window of [`Lead::windows`]
/// (the lever settled there, [`pose_fit::residuals_at`]), and the scan's minimum it started from
/// (`None`: the near fit).
pub(super) struct LeadFit {
    pub(super) fit: PoseFit,
    pub(super) residuals: Vec<Option<f64>>,
    pub(super) from: Option<pose_fit::ScanMinimum>,
}

impl Lead {
    /// The fit with the least mean residual per point over the windows every fit has points in,
    /// when it is not in `near`'s basin.
    pub(super) fn far(&self, near: Option<&PoseFit>) -> Option<PoseFit> {
        let shared: Vec<bool> = (0..self.windows.len())
            .map(|k| self.fits.iter().all(|f| f.residuals[k].is_some()))
            .collect();
        let mean = |r: &[Option<f64>]| {
            let (sum, n) = r
                .iter()
                .zip(&shared)
                .filter_map(|(x, s)| x.filter(|_| *s))
                .fold((0.0, 0usize), |(a, n), x| (a + x, n + 1));
            let m = sum / n as f64;
            if m.is_finite() {
                m
            } else {
                f64::INFINITY
            }
        };
        let best = self
            .fits
            .iter()
            .min_by(|a, b| mean(&a.residuals).total_cmp(&mean(&b.residuals)))?;
        // In the near fit's basin, the best replaces it only where the referee finds it better
        // beyond the paired t (a fit made again on the referee's windows by the truth's minimum).
        let near_fit = self.fits.iter().find(|f| f.from.is_none());
        let beaten = |n: &LeadFit| {
            !std::ptr::eq(n, best) && paired_t(&n.residuals, &best.residuals) >= LEAD_SIGNIFICANCE_T
        };
        (!near.is_some_and(|n| same_basin(n, &best.fit)) || near_fit.is_some_and(beaten))
            .then(|| best.fit.clone())
    }

    /// Half the largest distance from `reported`'s Δt to a fit the windows do not find worse beyond
    /// [`LEAD_SIGNIFICANCE_T`], seconds: how far along the valley the data leave Δt undecided (0
    /// when every other fit is worse).
    ///
    /// Where the scan's minimum a fit started from fits the windows better than the fit (and lies
    /// outside `reported`'s basin), the minimum stands for it: a fit need not end where the
    /// residual is least (its estimating equations weigh the points by the instrument, see
    /// `pose_fit`), and where the gait's ripple is as deep as the valley is shallow (a 1 Hz
    /// reference of a walking robot) a fit climbed 80 ms up the ripple from the minimum by the
    /// truth to a residual a fifth higher; the minimum itself fits the windows as well as the fit
    /// 0.4 s off that was reported, under a σ of 11 ms. The minimum is weighed as the scan found
    /// it (at its Δt, the lever settled there, as every candidate). Only the fitted minima: the
    /// scan's others, weighed too, are more chances for a worse one to pass the test (one mission
    /// right within 1 ms went from σ 5 ms to 336 ms; docs/evidence.md).
    pub(super) fn valley_s(&self, data: &PoseData<'_>, reported: &PoseFit) -> f64 {
        let at = |offset_s: f64| pose_fit::residuals_at(data, &self.windows, offset_s);
        let residuals = at(reported.theta[0]);
        let at_minimum = |m: &pose_fit::ScanMinimum| at(m.offset_s);
        let candidates = self.candidates(reported.theta[0], at_minimum);
        undecided_reach_s(reported.theta[0], &residuals, candidates)
    }

    /// The fit left out for its forward lever that fits the windows best, where it fits them better
    /// than `reported` (a negative paired t): what the bound decided.
    pub(super) fn beyond_lever(
        &self,
        data: &PoseData<'_>,
        reported: &PoseFit,
    ) -> Option<BeyondLever> {
        if self.beyond.is_empty() {
            return None;
        }
        self.beyond_against(&pose_fit::residuals_at(
            data,
            &self.windows,
            reported.theta[0],
        ))
    }

    /// [`Lead::beyond_lever`] against the reported fit's windows' `residuals`.
    pub(super) fn beyond_against(&self, residuals: &[Option<f64>]) -> Option<BeyondLever> {
        self.beyond
            .iter()
            .map(|b| (b, paired_t(&b.residuals, residuals)))
            .filter(|(_, t)| *t < 0.0)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(b, _)| BeyondLever {
                offset_s: b.fit.theta[0],
                forward_m: b.fit.lever_m.x,
                forward_sigma_m: b.fit.lever_sigma_m.map_or(f64::NAN, |s| s.x),
            })
    }

    /// The valley's candidates against a fit at `at_s`: each fit's Δt and residuals, or the
    /// minimum it started from (its residuals `at_minimum`) where that lies outside `at_s`'s basin
    /// and fits the windows better than the fit.
    pub(super) fn candidates<'l>(
        &'l self,
        at_s: f64,
        at_minimum: impl Fn(&pose_fit::ScanMinimum) -> Vec<Option<f64>> + 'l,
    ) -> impl Iterator<Item = (f64, Vec<Option<f64>>)> + 'l {
        self.fits.iter().map(move |f| {
            let fitted = (f.fit.theta[0], f.residuals.clone());
            f.from
                .filter(|m| (m.offset_s - at_s).abs() > SAME_BASIN_S)
                .map(|m| (m.offset_s, at_minimum(&m)))
                .filter(|(_, r)| paired_t(r, &f.residuals) < 0.0)
                .unwrap_or(fitted)
        })
    }
}

/// Half the largest distance from `at_s` (its windows' residuals `residuals`) to a candidate Δt
/// outside its basin whose windows' residuals are not worse beyond [`LEAD_SIGNIFICANCE_T`],
/// seconds (0 when every candidate is worse or in the basin).
///
/// ```text
/// at 0.10 s; candidates 0.15 s (same basin), 0.50 s (as good), 0.90 s (worse in every window)
///   → (0.50 − 0.10) / 2 = 0.20 s
/// ```
pub(super) fn undecided_reach_s(
    at_s: f64,
    residuals: &[Option<f64>],
    candidates: impl IntoIterator<Item = (f64, Vec<Option<f64>>)>,
) -> f64 {
    candidates
        .into_iter()
        .filter(|(t, r)| {
            (t - at_s).abs() > SAME_BASIN_S && paired_t(r, residuals) < LEAD_SIGNIFICANCE_T
        })
        .map(|(t, _)| (t - at_s).abs() / 2.0)
        .fold(0.0, f64::max)
}

/// Whether the lead search runs on a mission whose windows chose `model` (`forced`: the user's
/// model, if any): on a constant clock, and on a step or a drift the windows chose themselves — a
/// walking robot's windows started a lead away from the truth settle in the gait's basins along
/// the valley, a second apart, and read as a step, or, basin by basin along the mission, as a
/// drift (a 20 Hz walking robot whose speed search matched a lag 0.9 s off read −1521 ppm); a
/// constant from the search replaces it only when the profile measured from there chooses a
/// constant too (a true step stays a step, a true drift a drift).
pub(super) fn lead_searched(model: OffsetModel, forced: Option<OffsetModel>) -> bool {
    match model {
        OffsetModel::Constant => true,
        OffsetModel::Piecewise | OffsetModel::Linear => forced.is_none(),
    }
}

/// `data` with the narrow Jacobian, [`pose_fit::NARROW_JACOBIAN_PERIODS`].
pub(super) fn narrowed<'d>(data: &PoseData<'d>) -> PoseData<'d> {
    PoseData {
        params: pose_fit::PoseFitParams {
            jacobian_periods: pose_fit::NARROW_JACOBIAN_PERIODS,
            ..data.params
        },
        ..*data
    }
}

/// `data` with the lead search's iterations, [`pose_fit::LEAD_MAX_ITERATIONS`].
fn patient<'d>(data: &PoseData<'d>) -> PoseData<'d> {
    PoseData {
        params: pose_fit::PoseFitParams {
            max_iterations: pose_fit::LEAD_MAX_ITERATIONS,
            ..data.params
        },
        ..*data
    }
}

/// The lead search's referee's windows: [`REFEREE_WINDOW_S`] long, at least as long as the fit's
/// `windows`, at most the mission's span over [`REFEREE_MIN_WINDOWS`].
fn referee_windows(data: &PoseData<'_>, windows: &[pose_fit::Window]) -> Vec<pose_fit::Window> {
    let fit_s = windows
        .iter()
        .map(|w| w.t_end - w.t_start)
        .fold(0.0, f64::max);
    let span_s = match (data.ref_t.first(), data.ref_t.last()) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    };
    pose_fit::windows(data.ref_t, Some(referee_length_s(fit_s, span_s)))
}

/// The referee's window length for fit windows `fit_s` long over a mission spanning `span_s`:
/// [`REFEREE_WINDOW_S`], at most `span_s` over [`REFEREE_MIN_WINDOWS`], at least `fit_s`, seconds.
///
/// ```text
/// fit 20 s:  span 900 s → 80 s;  span 300 s → 50 s;  span 90 s → 20 s
/// ```
pub(super) fn referee_length_s(fit_s: f64, span_s: f64) -> f64 {
    (span_s / REFEREE_MIN_WINDOWS as f64)
        .min(REFEREE_WINDOW_S)
        .max(fit_s)
}

/// Two constant fits in one basin: their Δt within [`SAME_BASIN_S`].
fn same_basin(a: &PoseFit, b: &PoseFit) -> bool {
    (a.theta[0] - b.theta[0]).abs() <= SAME_BASIN_S
}

/// The lead search (see `mod.rs`): constant fits from the best minima of a scan of Δt over
/// the lead a forward lever can make at the reference's walking speed `moving_speed_mps` (its
/// mean while it moves) about the confident searches' answers `answers_s`, with the fit `near`
/// (the whole mission's, from the applied answer); `None` where the robot is not [`walking`] or
/// no answer is finite.
pub(super) fn lead_search(
    data: &PoseData<'_>,
    windows: &[pose_fit::Window],
    answers_s: &[f64],
    near: Option<&PoseFit>,
    moving_speed_mps: f64,
) -> Option<Lead> {
    // A sensor ahead of the other reads as a clock offset of lever/speed in the signal searches,
    // which at a walk lies beyond MAX_DISAGREEMENT_S; the positions with the lever fitted tell
    // the two apart only along a long, shallow valley the fit from there does not leave, rippled
    // by the gait. The lever solved at every candidate along it (over a sample of the windows on
    // long missions: the scan only finds basins), the fits from its best minima compete with the
    // near one on their residual over every window (the scan's own ranking is not trusted: its
    // grid samples the gait's ripples unevenly).
    if !walking(moving_speed_mps) {
        return None;
    }
    let lead_s = (LEAD_LEVER_M / moving_speed_mps).min(MAX_LEAD_S);
    // Over the lead about every answer: a speed search can match a smooth speed at a wrong lag
    // with confidence, and the curvature searches' answer then lies the lead from the truth.
    let (lo_s, hi_s) = answers_s
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), a| {
            (lo.min(*a), hi.max(*a))
        });
    if !(lo_s.is_finite() && hi_s.is_finite()) {
        return None;
    }
    let (lo_s, hi_s) = (lo_s - lead_s, hi_s + lead_s);
    let referee = referee_windows(data, windows);
    let stride = referee.len().div_ceil(LEAD_SCAN_WINDOWS).max(1);
    let sample: Vec<pose_fit::Window> = referee.iter().step_by(stride).cloned().collect();
    let minima = pose_fit::coarse_minima(
        data,
        &sample,
        (lo_s + hi_s) / 2.0,
        ((hi_s - lo_s) / 2.0, LEAD_STEP_S),
        LEAD_MINIMA + 1,
    );
    // The fit from each minimum, its lever the scan's there, or none when that does not converge
    // (a lever settled on a sample of the windows can start the fit outside the basin). Given
    // `LEAD_MAX_ITERATIONS`: along the valley a fit can creep toward its root.
    let narrow = patient(&narrowed(data));
    let data = &patient(data);
    let fit_on = |data: &PoseData<'_>, windows: &[pose_fit::Window], theta: f64, lever| {
        pose_fit::fit(
            data,
            windows,
            ClockShape::Constant,
            vec![theta],
            lever,
            true,
        )
        .filter(|f| {
            f.converged
                && f.theta[0] >= lo_s - MAX_DISAGREEMENT_S
                && f.theta[0] <= hi_s + MAX_DISAGREEMENT_S
        })
    };
    let fit_in = |data: &PoseData<'_>, theta: f64, lever| fit_on(data, windows, theta, lever);
    let far = minima
        .iter()
        .copied()
        .filter(|m| near.is_none_or(|n| (n.theta[0] - m.offset_s).abs() > SAME_BASIN_S))
        .take(LEAD_MINIMA)
        .filter_map(|m| {
            let from = |data: &PoseData<'_>| {
                fit_in(data, m.offset_s, m.lever_m)
                    .or_else(|| fit_in(data, m.offset_s, Vector3::zeros()))
            };
            // A fit that leaves its minimum's basin (or does not converge) on a walking robot
            // may have followed a Jacobian the gait turned negative: once more on the narrow one.
            let stays = |f: &PoseFit| (f.theta[0] - m.offset_s).abs() <= SAME_BASIN_S;
            match from(data) {
                Some(f) if stays(&f) => Some(f),
                other => from(&narrow).filter(stays).or(other),
            }
            .map(|f| (f, Some(m)))
        });
    // Where no fit could be made from the start, a fit that needs a longer forward lever than
    // the search allows for is no candidate (nothing else weighs against the lever it traded Δt
    // for); kept aside to say so where it fits the windows better than the one reported. Beside
    // a near fit, the referee judges every fit as it comes (on robots whose sensors sit farther
    // apart the near fit or a far one is often right).
    let admitted = |f: &PoseFit| near.is_some() || within_lead_lever(f);
    let (far, beyond): (Vec<_>, Vec<_>) = far.partition(|(f, _)| admitted(f));
    let fits: Vec<(PoseFit, Option<pose_fit::ScanMinimum>)> = far
        .into_iter()
        .chain(near.cloned().map(|f| (f, None)))
        .collect();
    // Windows a fit left out (a jump of the estimate) would weigh on every comparison; where that
    // leaves the referee too few, the fits' own windows judge.
    let left_out = |w: &pose_fit::Window| {
        fits.iter().any(|(f, _)| {
            f.outliers
                .iter()
                .any(|o| o.t_start < w.t_end && o.t_end > w.t_start)
        })
    };
    let mut kept: Vec<pose_fit::Window> = referee.into_iter().filter(|w| !left_out(w)).collect();
    if kept.len() < MIN_POOLED_WINDOWS {
        kept = windows.iter().filter(|w| !left_out(w)).cloned().collect();
    }
    // Where the referee finds a fit worse than the minimum it started from (it climbed out of the
    // basin the referee sees: the fit's windows are shorter), or a minimum within the near fit's
    // basin better than the near fit, the fit is made again on the referee's windows from there
    // and kept where it stays by the minimum.
    let at = |offset_s: f64| pose_fit::residuals_at(data, &kept, offset_s);
    let judged = |fit: PoseFit, from| LeadFit {
        residuals: at(fit.theta[0]),
        fit,
        from,
    };
    let worse = |f: &LeadFit, m: &pose_fit::ScanMinimum| {
        paired_t(&f.residuals, &at(m.offset_s)) >= LEAD_SIGNIFICANCE_T
    };
    let again = |m: &pose_fit::ScanMinimum| {
        fit_on(data, &kept, m.offset_s, m.lever_m)
            .filter(|f| (f.theta[0] - m.offset_s).abs() <= SAME_BASIN_S && admitted(f))
            .map(|f| judged(f, Some(*m)))
    };
    let mut fits: Vec<LeadFit> = fits
        .into_iter()
        .map(|(f, from)| {
            let f = judged(f, from);
            match from {
                Some(m) if worse(&f, &m) => again(&m).unwrap_or(f),
                _ => f,
            }
        })
        .collect();
    let near_minimum = fits.iter().find(|f| f.from.is_none()).and_then(|n| {
        minima
            .iter()
            .find(|m| (n.fit.theta[0] - m.offset_s).abs() <= SAME_BASIN_S)
            .filter(|m| worse(n, m))
    });
    fits.extend(near_minimum.and_then(again));
    let beyond = beyond
        .into_iter()
        .map(|(f, from)| judged(f, from))
        .collect();
    Some(Lead {
        windows: kept,
        fits,
        beyond,
    })
}

/// Whether a fit's forward lever is one the lead search allows for: not beyond [`LEAD_LEVER_M`]
/// by more than [`LEAD_SIGNIFICANCE_T`] of its σ (a fit without a lever, or without its σ, is).
/// The search scans only the lead such a lever makes; a fit along the valley that needs a longer
/// one, with no fit from the start to weigh it against, traded Δt for a lever beyond that premise
/// (where it fits the windows better than the fit reported, [`PoseClock::beyond_lever`] says so:
/// right only where the sensors sit that far apart).
///
/// ```text
/// forward 0.86 ± 0.07 m → no (0.86 − 2·0.07 > 0.5);  0.39 ± 0.01 m → yes;  0.6 ± 0.1 m → yes
/// ```
pub(super) fn within_lead_lever(fit: &PoseFit) -> bool {
    let sigma_m = fit.lever_sigma_m.map_or(f64::INFINITY, |s| s.x);
    fit.lever_m.x.abs() - LEAD_SIGNIFICANCE_T * sigma_m <= LEAD_LEVER_M
}

/// The paired t statistic of `a` − `b` over the windows both have (negative: `a` fits better):
/// ±∞ when they differ by the same amount in every window, 0 (undecided) over fewer than two
/// windows, NaN (decided: not below any bound) when a residual is not finite.
pub(super) fn paired_t(a: &[Option<f64>], b: &[Option<f64>]) -> f64 {
    let d: Vec<f64> = a
        .iter()
        .zip(b)
        .filter_map(|(a, b)| Some((*a)? - (*b)?))
        .collect();
    let k = d.len() as f64;
    if k < 2.0 {
        return 0.0;
    }
    let mean = d.iter().sum::<f64>() / k;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (k - 1.0);
    if var > 0.0 || !mean.is_finite() {
        mean / (var / k).sqrt()
    } else if mean == 0.0 {
        0.0
    } else {
        f64::INFINITY.copysign(mean)
    }
}
