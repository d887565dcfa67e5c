//! Which clock model the offset profile supports: one constant offset, a linear drift, or steps.
//!
//! **Criterion.** The Bayesian information criterion over the profile's usable windows with their
//! σ: BIC = χ²/ρ + k·ln(n/ρ), where ρ = window/step is how many windows see each stretch of the
//! mission (the windows overlap, so χ² and n are counted ρ times) and k the model's parameters
//! (constant 1, linear 2, one more mean and one change time per step). Each window's χ² is capped
//! at [`CHI2_CAP`] (3σ): one window spoiled by a position jump of the estimate (a localiser
//! correcting itself) cannot decide a model alone. The simplest model whose BIC is within
//! [`BIC_MARGIN`] ("very strong" evidence on the Kass–Raftery scale) of the lowest is chosen, in the
//! order constant, linear, piecewise — a drift is not called steps, nor a constant a drift, unless
//! the data insist — and only `constant` on a profile of fewer than [`MIN_INDEPENDENT_WINDOWS`]
//! independent windows.
//!
//! **Steps** are found by binary segmentation (the split of a stretch that lowers its χ² most, kept
//! while it lowers the BIC by [`BIC_MARGIN`]; at most [`MAX_STEPS`]); a segment spans at least two
//! independent windows, so a position jump, which spoils a window or two, is not a step; and the two
//! sides must differ by the step resolution, the drift's rule ([`SLOW_ERROR_FACTOR`]·z·σ of their
//! difference), unless the profile is a first look ([`Steps::Provisional`]). The change time is
//! then located on the data themselves, to a few seconds: on the positions when the pose fit made
//! the profile ([`crate::align::pose_fit::locate_change`]), else on the signals
//! ([`locate_change`]); two changes less than a window apart are one step (`piecewise_segments`).
//! Steps that go out and back (a segment returning to the offset two segments before it,
//! `steps_out_and_back`) are read as two basins of the fit, not a clock: the model is `constant`,
//! its σ covering both (`alternation_s`).
//!
//! **The signal searches' constant** (a clock model from the speed or curvature profile, not the
//! pose fit) keeps the whole mission's answer, one correlation over every sample, with σ the
//! larger of its own and the windows' mean's; where that answer lies beyond [`WHOLE_WINDOWS_Z`] σ
//! of the windows' mean, σ adds the distance ([`whole_against_windows_s`]): a correlation over a
//! whole mission with gaps can peak at a lag none of its stretches chooses (a 1 Hz ground reference
//! with outages, its speed search 251 ms off under σ 75 ms, its windows' mean 40 ms off).
//!
//! Sign of the drift: `drift_ppm` is positive when the estimate's clock runs fast, so its Δt falls
//! with time: Δt(t) = Δt(t_mid) − drift_ppm·10⁻⁶·(t − t_mid). The chosen model is applied to the
//! estimate's stamps from the report's numbers by [`crate::clock`].

use crate::align::offset_profile::{OffsetProfile, ProfileWindow, SIGMA_FLOOR_S};
use crate::align::time_offset::{Pair, SignalView};

/// A model must lower the BIC by this much to replace a simpler one.
pub const BIC_MARGIN: f64 = 10.0;
/// The largest χ² one window contributes.
pub const CHI2_CAP: f64 = 9.0;
/// The fewest independent windows (n/ρ) on which a model other than `constant` is chosen.
pub const MIN_INDEPENDENT_WINDOWS: f64 = 6.0;
/// The most steps looked for.
pub const MAX_STEPS: usize = 3;
/// The drift resolution is this many times the criterion's own threshold z·σ_drift. σ_drift comes
/// from the windows' scatter about their neighbours, which cannot see an error that wanders slowly
/// across the mission (a forward lever trading against Δt as the gait or the heading changes): to a
/// line fitted over a short mission it is a drift. On the constant clocks of 840 validation missions
/// (`trajdrift validate --missions 30`, seeds 1, 1000, 2000 and 3000) the measured drift reached 1.3
/// times z·σ_drift (1.7 with the estimate jumping), and two 3-minute missions were called drifting
/// at 115 and 122 ppm; of the 120 drifting missions (15–25 minutes, 40–150 ppm) one, a legged
/// mission at 44 ppm with windows of 9 ms, measured below twice it. A measured alternative, a floor
/// of the windows' median σ over the mission's span added to σ_drift, kept the same false alarms and
/// called twice as many 5-minute missions drifting with the wrong rate.
pub const SLOW_ERROR_FACTOR: f64 = 2.0;
/// A constant's σ covers the distance from the whole mission's answer to its own windows' mean
/// beyond this many of the mean's σ (see [`whole_against_windows_s`]).
pub const WHOLE_WINDOWS_Z: f64 = 2.0;

/// The clock model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OffsetModel {
    /// One offset for the whole mission.
    Constant,
    /// Δt changes linearly with time (the clocks run at different rates).
    Linear,
    /// Δt is constant per segment and steps between them (a recorder restart, an NTP correction).
    Piecewise,
}

impl OffsetModel {
    /// The name as on the command line and in reports.
    pub fn as_str(&self) -> &'static str {
        match self {
            OffsetModel::Constant => "constant",
            OffsetModel::Linear => "linear",
            OffsetModel::Piecewise => "piecewise",
        }
    }
}

/// `--offset-model`: a clock model to fit, or `Auto`: the model chosen from the offset profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelChoice {
    /// Chosen from the profile (BIC; constant unless the data refute it).
    Auto,
    /// This model, whatever the profile says.
    Fixed(OffsetModel),
}

impl ModelChoice {
    /// The model forced, if any.
    pub fn forced(self) -> Option<OffsetModel> {
        match self {
            ModelChoice::Auto => None,
            ModelChoice::Fixed(m) => Some(m),
        }
    }
}

/// One segment of constant offset, absolute seconds on the reference clock (the inputs' origin).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ClockSegment {
    pub t_start: f64,
    pub t_end: f64,
    pub offset_s: f64,
    pub sigma_s: f64,
}

/// The chosen model and its parameters.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClockModel {
    pub model: OffsetModel,
    /// Headline Δt, seconds: constant — the whole mission's; linear — at `t_mid`; piecewise — the
    /// longest segment's.
    pub offset_s: f64,
    /// Its standard error, seconds.
    pub sigma_s: f64,
    /// Linear: the time Δt = `offset_s`, reference clock, seconds.
    pub t_mid: f64,
    /// The linear fit's drift, ppm (positive: the estimate's clock runs fast), and its σ — always
    /// measured when the profile has two usable windows; applied only when `model` is linear.
    pub drift_ppm: Option<f64>,
    pub drift_sigma_ppm: Option<f64>,
    /// The smallest drift declared on this profile, ppm: [`SLOW_ERROR_FACTOR`]·z·σ_drift with
    /// z = √(BIC margin + ln n) (what a linear model must gain to be chosen). Below it the model is
    /// constant whatever the BIC says (the pose fit's constant then adds to its σ a drift measured
    /// beyond 2σ_drift: `align::pose_model`).
    pub drift_resolution_ppm: Option<f64>,
    /// The segments (piecewise; empty otherwise).
    pub segments: Vec<ClockSegment>,
    /// BIC of constant, linear and piecewise (NaN when not computed).
    pub bic: [f64; 3],
    /// Why this model, in one sentence.
    pub reason: String,
    /// The criterion's verdict the reason ends with.
    #[serde(skip)]
    pub criterion: String,
    /// The spread of the offsets the windows alternate between where they step out and back
    /// (`steps_out_and_back`: two basins of a fit, read as `constant`), seconds; 0 otherwise.
    #[serde(skip)]
    pub alternation_s: f64,
}

impl ClockModel {
    /// A piecewise model's headline: its longest segment's offset and σ. Returns that segment's
    /// index (`None` without segments, the headline then unchanged).
    pub fn headline_from_longest_segment(&mut self) -> Option<usize> {
        let (k, offset_s, sigma_s) = self
            .segments
            .iter()
            .enumerate()
            .max_by(|(_, a), (_, b)| (a.t_end - a.t_start).total_cmp(&(b.t_end - b.t_start)))
            .map(|(k, s)| (k, s.offset_s, s.sigma_s))?;
        self.offset_s = offset_s;
        self.sigma_s = sigma_s;
        Some(k)
    }

    /// Writes `reason` from the model's numbers and its criterion.
    pub fn describe(&mut self) {
        let why = &self.criterion;
        self.reason = match self.model {
            OffsetModel::Constant => format!(
                "constant {:+.4} ± {:.4} s: {why}",
                self.offset_s, self.sigma_s
            ),
            OffsetModel::Linear => format!(
                "linear drift {:+.1} ± {:.1} ppm: {why}",
                self.drift_ppm.unwrap_or(f64::NAN),
                self.drift_sigma_ppm.unwrap_or(f64::NAN)
            ),
            OffsetModel::Piecewise => {
                let steps: Vec<String> = self
                    .segments
                    .windows(2)
                    .map(|s| {
                        format!(
                            "{:+.3} → {:+.3} s at {:.0} s after the reference's start",
                            s[0].offset_s, s[1].offset_s, s[1].t_start
                        )
                    })
                    .collect();
                format!("piecewise, {}: {why}", steps.join(", "))
            }
        };
    }

    /// A constant model with no profile behind it (too short a mission, or forced without one).
    pub fn constant(offset_s: f64, sigma_s: f64, reason: String) -> ClockModel {
        ClockModel {
            model: OffsetModel::Constant,
            offset_s,
            sigma_s,
            t_mid: 0.0,
            drift_ppm: None,
            drift_sigma_ppm: None,
            drift_resolution_ppm: None,
            segments: Vec::new(),
            bic: [f64::NAN; 3],
            reason,
            criterion: String::new(),
            alternation_s: 0.0,
        }
    }
}

/// A fit of one model over windows.
#[derive(Debug, Clone, Copy)]
struct Fit {
    chi2: f64,
    a: f64,
    b: f64,
    sigma_a: f64,
    sigma_b: f64,
}

/// The σ of one offset over `profile`'s usable windows wholly inside `span` (reference seconds):
/// their calibrated σ combined, each stretch of the mission counted once, raised by their scatter
/// about that offset where it exceeds their σ (the Birge ratio, as the drift's σ and a step's
/// sides), without the signal searches' floor; `None` without such a window.
///
/// ```
/// use trajdrift_core::align::clock_model::{windows_line_sigma_s, windows_offset_sigma_s};
/// use trajdrift_core::align::offset_profile::{OffsetProfile, ProfileWindow};
/// use trajdrift_core::align::time_offset::OffsetMethod;
/// // Four disjoint 20 s windows, each Δt ± 2 ms.
/// let window = |t: f64| ProfileWindow {
///     t,
///     offset_s: 0.1,
///     sigma_s: 0.002,
///     correlation: 1.0,
///     usable: true,
/// };
/// let mut profile = OffsetProfile {
///     method: OffsetMethod::Pose,
///     window_s: 20.0,
///     step_s: 20.0,
///     sigma_scale: 1.0,
///     windows: [10.0, 30.0, 50.0, 70.0].map(window).to_vec(),
/// };
/// let all = (f64::NEG_INFINITY, f64::INFINITY);
/// let close = |a: Option<f64>, b: f64| (a.unwrap() - b).abs() < 1e-12;
/// assert!(close(windows_offset_sigma_s(&profile, all), 0.001)); // 2 ms / √4
/// // A segment from 0 to 45 s holds the first two wholly (the third straddles 45 s).
/// assert!(close(windows_offset_sigma_s(&profile, (0.0, 45.0)), 0.002 / 2f64.sqrt()));
/// assert_eq!(windows_offset_sigma_s(&profile, (0.0, 15.0)), None);
/// // The line's offset at the windows' centre is as sure as their mean.
/// assert!(close(windows_line_sigma_s(&profile, 40.0), 0.001));
/// // Windows every 10 s overlap by half: each stretch counts once, the σ is not halved again.
/// profile.step_s = 10.0;
/// profile.windows = (0..7).map(|k| window(10.0 + 10.0 * k as f64)).collect();
/// assert!(close(windows_offset_sigma_s(&profile, all), 0.002 * (2.0 / 7.0f64).sqrt()));
/// ```
pub fn windows_offset_sigma_s(profile: &OffsetProfile, span: (f64, f64)) -> Option<f64> {
    windows_offset_s(profile, span).map(|(_, sigma)| sigma)
}

/// How many of `profile`'s usable windows lie wholly inside `span` (reference seconds): those
/// [`windows_offset_s`] combines.
pub fn windows_inside(profile: &OffsetProfile, span: (f64, f64)) -> usize {
    inside(&profile.usable(), span, 0.5 * profile.window_s).len()
}

/// The weighted mean of `profile`'s usable windows wholly inside `span` (reference seconds) and its
/// σ ([`windows_offset_sigma_s`]); `None` without such a window.
pub fn windows_offset_s(profile: &OffsetProfile, span: (f64, f64)) -> Option<(f64, f64)> {
    let w = inside(&profile.usable(), span, 0.5 * profile.window_s);
    fit(&w, 0.0, false, profile.redundancy()).map(|c| (c.a, c.sigma_a * c.birge(w.len(), 1)))
}

/// How far the whole mission's answer `whole_s` lies from the weighted mean of `profile`'s usable
/// windows beyond the mean's σ, seconds: √(d² − σ²) where the distance d exceeds
/// [`WHOLE_WINDOWS_Z`]·σ, else 0. Both measure the one offset of a constant clock on the same data,
/// the whole answer in one correlation, the mean window by window; where they disagree the
/// correlation over the whole mission found a peak its own stretches do not (a smooth speed matched
/// at a wrong lag across a reference with gaps), and a σ that leaves out the distance claims more
/// than either knows. Added in quadrature to the signal searches' constant.
///
/// ```
/// use trajdrift_core::align::clock_model::whole_against_windows_s;
/// use trajdrift_core::align::offset_profile::{OffsetProfile, ProfileWindow};
/// use trajdrift_core::align::time_offset::OffsetMethod;
/// let window = |t: f64, offset_s: f64| ProfileWindow {
///     t, offset_s, sigma_s: 0.002, correlation: 0.9, usable: true,
/// };
/// let profile = OffsetProfile {
///     method: OffsetMethod::Curvature,
///     window_s: 20.0,
///     step_s: 20.0,
///     sigma_scale: 1.0,
///     windows: (0..4).map(|k| window(10.0 + 20.0 * k as f64, 0.1)).collect(),
/// };
/// // The windows' mean is 0.1 s with σ 1 ms (2 ms / √4).
/// assert_eq!(whole_against_windows_s(0.1015, &profile), 0.0); // within 2σ
/// let excess = whole_against_windows_s(0.105, &profile); // 5σ away
/// assert!((excess - (0.005f64.powi(2) - 0.001f64.powi(2)).sqrt()).abs() < 1e-12);
/// ```
pub fn whole_against_windows_s(whole_s: f64, profile: &OffsetProfile) -> f64 {
    match windows_offset_s(profile, (f64::NEG_INFINITY, f64::INFINITY)) {
        Some((mean, sigma)) if (whole_s - mean).abs() > WHOLE_WINDOWS_Z * sigma => {
            ((whole_s - mean).powi(2) - sigma * sigma).sqrt()
        }
        _ => 0.0,
    }
}

/// The σ at `t_mid` of the line through `profile`'s usable windows (as
/// [`windows_offset_sigma_s`], the scatter taken about the line); `None` with fewer than two.
pub fn windows_line_sigma_s(profile: &OffsetProfile, t_mid: f64) -> Option<f64> {
    let w = profile.usable();
    fit(&w, t_mid, true, profile.redundancy()).map(|l| l.sigma_a * l.birge(w.len(), 2))
}

/// The windows of `w` (each `half` a window either side of its centre) wholly inside `span`: those
/// straddling a change of the clock mix both offsets.
fn inside(w: &[ProfileWindow], (lo, hi): (f64, f64), half: f64) -> Vec<ProfileWindow> {
    w.iter()
        .copied()
        .filter(|p| p.t - half >= lo - 1e-9 && p.t + half <= hi + 1e-9)
        .collect()
}

/// Weighted least squares of y = a + b·(t − t0) (`linear`) or y = a, with capped χ².
fn fit(w: &[ProfileWindow], t0: f64, linear: bool, rho: f64) -> Option<Fit> {
    let (mut s, mut st, mut stt, mut sy, mut sty) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for p in w {
        let q = 1.0 / p.sigma_s.powi(2);
        let t = p.t - t0;
        s += q;
        st += q * t;
        stt += q * t * t;
        sy += q * p.offset_s;
        sty += q * t * p.offset_s;
    }
    if w.is_empty() || s <= 0.0 {
        return None;
    }
    let (a, b, var_a, var_b) = if linear {
        let det = s * stt - st * st;
        if w.len() < 2 || det <= 0.0 {
            return None;
        }
        (
            (stt * sy - st * sty) / det,
            (s * sty - st * sy) / det,
            stt / det,
            s / det,
        )
    } else {
        (sy / s, 0.0, 1.0 / s, 0.0)
    };
    let chi2 = w
        .iter()
        .map(|p| {
            ((p.offset_s - a - b * (p.t - t0)) / p.sigma_s)
                .powi(2)
                .min(CHI2_CAP)
        })
        .sum();
    Some(Fit {
        chi2,
        a,
        b,
        sigma_a: (var_a * rho).sqrt(),
        sigma_b: (var_b * rho).sqrt(),
    })
}

/// z = √(BIC margin + ln n) over `n_eff` independent windows: how many σ a drift or a step must
/// reach to lower the BIC by [`BIC_MARGIN`].
fn criterion_z(n_eff: f64) -> f64 {
    (BIC_MARGIN + n_eff.max(1.0).ln()).sqrt()
}

impl Fit {
    /// σ of the constant, raised by the windows' scatter about it where that exceeds their σ (the
    /// Birge ratio over `len` windows).
    fn scattered_sigma_a(&self, len: usize) -> f64 {
        self.sigma_a * self.birge(len, 1)
    }

    /// The Birge ratio √(χ²/dof) over `len` windows and `k` parameters, at least 1: how much the
    /// windows scatter about the fit beyond their σ. χ² and dof are both taken over every window, as
    /// the drift's σ always took them; with overlapping windows (ρ > 1) the independent dof are
    /// n/ρ − k, fewer than (n − k)/ρ, so the ratio comes out a little low there (the pose fit's
    /// profile is disjoint unless `--offset-step` asks otherwise).
    fn birge(&self, len: usize, k: usize) -> f64 {
        let dof = (len as f64 - k as f64).max(1.0);
        (self.chi2 / dof).sqrt().max(1.0)
    }
}

/// Splits of `w` into constant stretches by binary segmentation; returns the split indices (a split
/// at i: windows ..i and i.. differ). A split is a step only when its two sides' offsets differ by
/// the step resolution, [`SLOW_ERROR_FACTOR`]·z·σ of the difference (each side's σ raised by its
/// own windows' scatter): the same rule as a drift's, for the same reason — an error that wanders
/// slowly across the mission (a forward lever trading against Δt as the gait or the path changes)
/// moves neighbouring windows together, which their σ cannot show. On the validation's
/// position-jump missions (seeds 1000, 2000, 3000), once the jumps no longer spoiled the windows,
/// the BIC alone called three constant clocks stepping by 5, 23 and 60 ms; the steps of the step
/// missions are 0.1–1 s. A [`Steps::Provisional`] profile proposes steps on the BIC alone.
fn segment(w: &[ProfileWindow], min_len: usize, rho: f64, n_eff: f64, steps: Steps) -> Vec<usize> {
    let mut splits: Vec<usize> = Vec::new();
    let penalty = 2.0 * n_eff.max(1.0).ln();
    let floor = match steps {
        Steps::Provisional => 0.0,
        Steps::Resolved => SLOW_ERROR_FACTOR * criterion_z(n_eff),
    };
    for _ in 0..MAX_STEPS {
        let mut bounds = vec![0];
        bounds.extend(&splits);
        bounds.push(w.len());
        let mut best: Option<(f64, usize)> = None;
        for k in 0..bounds.len() - 1 {
            let (lo, hi) = (bounds[k], bounds[k + 1]);
            let Some(whole) = fit(&w[lo..hi], 0.0, false, rho) else {
                continue;
            };
            for i in lo + min_len..=hi.saturating_sub(min_len) {
                let (Some(l), Some(r)) = (
                    fit(&w[lo..i], 0.0, false, rho),
                    fit(&w[i..hi], 0.0, false, rho),
                ) else {
                    continue;
                };
                let gain = (whole.chi2 - l.chi2 - r.chi2) / rho;
                let sigma = l
                    .scattered_sigma_a(i - lo)
                    .hypot(r.scattered_sigma_a(hi - i));
                if (l.a - r.a).abs() < floor * sigma {
                    continue;
                }
                if best.is_none_or(|(g, _)| gain > g) {
                    best = Some((gain, i));
                }
            }
        }
        match best {
            Some((gain, i)) if gain - penalty >= BIC_MARGIN => {
                splits.push(i);
                splits.sort_unstable();
            }
            _ => break,
        }
    }
    splits
}

/// Whether the steps found at `splits` go out and back: some segment's offset within a quarter of
/// the step before it of the offset two segments earlier (A → B → A). A clock that steps does not
/// come back to within milliseconds of where it was; a fit with two basins does, window after
/// window: on walking robots of the second simulator whose sensor led the reference's point by
/// 0.8 s at their walking speed, the profile's windows settled in two basins 0.43–0.55 s apart
/// (the forward lever trading against Δt), alternating three to six times, and the BIC called
/// them steps (clock alarms on constant clocks). `pieces`: the segments' fits in time order
/// ([`Fits::pieces`]). Returns the spread of the segments' offsets.
fn steps_out_and_back(pieces: &[Fit]) -> Option<f64> {
    let a: Vec<f64> = pieces.iter().map(|f| f.a).collect();
    let back = a
        .windows(3)
        .any(|s| (s[2] - s[0]).abs() < 0.25 * (s[1] - s[0]).abs());
    let (lo, hi) = a
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        });
    back.then_some(hi - lo)
}

/// How the steps of a profile are judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Steps {
    /// On the BIC alone: the profile is a first look, to be measured again under the model it
    /// proposes (its windows beyond a large step were searched from the wrong offset and scatter;
    /// a step of 0.8 s came out of one as 0.36 s, 4.5σ).
    Provisional,
    /// On the BIC and the step resolution (see `segment`).
    Resolved,
}

/// Where a clock changes from Δt₁ to Δt₂ between two reference times: `locate((Δt₁, Δt₂), (lo, hi))`
/// on the data themselves ([`locate_change`] on signals, [`crate::align::pose_fit::locate_change`] on
/// positions); `None` when they cannot tell.
pub type Locate<'a> = dyn Fn((f64, f64), (f64, f64)) -> Option<f64> + 'a;

/// Chooses the model from `profile` (see the module doc). `whole` is the whole mission's Δt and its
/// standard error (calibrated); `locate` finds a change time between two windows (`None`: halfway
/// between them). `forced`: the model to fit whatever the criterion says.
pub fn choose_model(
    profile: &OffsetProfile,
    whole: (f64, f64),
    locate: Option<&Locate<'_>>,
    forced: Option<OffsetModel>,
    steps: Steps,
) -> ClockModel {
    let w = profile.usable();
    let rho = profile.redundancy();
    let n_eff = w.len() as f64 / rho;
    let whole_sigma = whole.1;
    let Some(c) = fit(&w, 0.0, false, rho) else {
        return ClockModel::constant(
            whole.0,
            whole_sigma,
            "constant: the offset profile has no usable window".into(),
        );
    };
    let t_mid = 0.5 * (w[0].t + w[w.len() - 1].t);
    let min_len = (2.0 * rho).ceil() as usize;
    let splits = segment(&w, min_len, rho, n_eff, steps);
    let fits = Fits {
        constant: c,
        linear: fit(&w, t_mid, true, rho),
        windows: &w,
        splits: &splits,
    };
    let criterion = Criterion {
        bic: fits.bics(rho, n_eff),
        n_windows: w.len(),
        n_eff,
        window_s: profile.window_s,
    };
    let drift = fits.drift_ppm();
    let z = criterion_z(n_eff);
    let resolution = drift.map(|d| SLOW_ERROR_FACTOR * z * d.1);
    let chosen = match (forced, criterion.choice(), drift, resolution) {
        (Some(f), ..) => f,
        // A drift below the resolution is not declared.
        (None, OffsetModel::Linear, Some((d, _)), Some(r)) if d.abs() < r => OffsetModel::Constant,
        (None, c, ..) => c,
    };
    // Steps out and back are two basins of the fit, not a clock: constant, σ covering both.
    let alternation = match (forced, chosen) {
        (None, OffsetModel::Piecewise) => steps_out_and_back(&fits.pieces(rho)),
        _ => None,
    };
    let chosen = if alternation.is_some() {
        OffsetModel::Constant
    } else {
        chosen
    };
    let alternation_s = alternation.unwrap_or(0.0);
    let mut model = ClockModel {
        model: chosen,
        offset_s: whole.0,
        sigma_s: whole_sigma.max(c.sigma_a).max(0.5 * alternation_s),
        t_mid,
        drift_ppm: drift.map(|d| d.0),
        drift_sigma_ppm: drift.map(|d| d.1),
        drift_resolution_ppm: resolution,
        segments: Vec::new(),
        bic: criterion.bic,
        reason: String::new(),
        criterion: criterion.verdict(forced.is_some()),
        alternation_s,
    };
    if alternation.is_some() {
        model.criterion = format!(
            "{}; but the windows step out and back between offsets {alternation_s:.3} s apart: two basins of the fit (on a walking robot, a forward lever trading against Δt), not a clock, and σ covers both",
            model.criterion
        );
    }
    if let (None, OffsetModel::Linear, Some((d, _)), Some(r)) =
        (forced, criterion.choice(), drift, resolution)
    {
        if chosen == OffsetModel::Constant {
            model.criterion = format!(
                "{}; the drift {d:+.1} ppm is below the resolution {r:.1} ppm",
                model.criterion
            );
        }
    }
    fill(&mut model, &fits, profile, locate);
    model.describe();
    model
}

/// The criterion over a profile (see the module doc): the BIC of the constant, linear and piecewise
/// models over its `n_windows` usable windows of `window_s` seconds, `n_eff` of them independent.
struct Criterion {
    bic: [f64; 3],
    n_windows: usize,
    n_eff: f64,
    window_s: f64,
}

impl Criterion {
    /// Whether the profile has independent windows enough to refute the constant.
    fn enough(&self) -> bool {
        self.n_eff >= MIN_INDEPENDENT_WINDOWS
    }

    /// The simplest model whose BIC is within [`BIC_MARGIN`] of the lowest, in the order constant,
    /// linear, piecewise; the constant on too few independent windows.
    fn choice(&self) -> OffsetModel {
        let [bic_c, bic_l, bic_p] = self.bic;
        let best = bic_c.min(bic_l).min(bic_p);
        if !self.enough() || bic_c <= best + BIC_MARGIN {
            OffsetModel::Constant
        } else if bic_l <= best + BIC_MARGIN {
            OffsetModel::Linear
        } else {
            OffsetModel::Piecewise
        }
    }

    /// The verdict a model's reason ends with (`forced`: the model came from `--offset-model`).
    fn verdict(&self, forced: bool) -> String {
        let [bic_c, bic_l, bic_p] = self.bic;
        if forced {
            "forced with --offset-model".to_string()
        } else if !self.enough() {
            format!(
                "{:.1} independent windows of {:.0} s are too few to refute it",
                self.n_eff, self.window_s
            )
        } else {
            format!(
                "BIC constant {bic_c:.1}, linear {bic_l:.1}, piecewise {bic_p:.1} over {} windows of {:.0} s (a more complex model must be {BIC_MARGIN:.0} lower)",
                self.n_windows,
                self.window_s
            )
        }
    }
}

/// The fits behind a model choice.
struct Fits<'a> {
    constant: Fit,
    linear: Option<Fit>,
    windows: &'a [ProfileWindow],
    splits: &'a [usize],
}

impl Fits<'_> {
    /// BIC = χ²/ρ + k·ln(n/ρ) of the constant, linear and piecewise models (`rho`: ρ, `n_eff`: n/ρ);
    /// ∞ for a linear model that could not be fitted and for steps when none was found.
    fn bics(&self, rho: f64, n_eff: f64) -> [f64; 3] {
        let bic = |chi2: f64, k: f64| chi2 / rho + k * n_eff.max(1.0).ln();
        let pieces = self.pieces(rho);
        let bic_c = bic(self.constant.chi2, 1.0);
        let bic_l = self.linear.map_or(f64::INFINITY, |l| bic(l.chi2, 2.0));
        let bic_p = if self.splits.is_empty() {
            f64::INFINITY
        } else {
            bic(
                pieces.iter().map(|p| p.chi2).sum(),
                (2 * self.splits.len() + 1) as f64,
            )
        };
        [bic_c, bic_l, bic_p]
    }

    /// The constant fits of the stretches between the splits, in time order (`rho`: ρ).
    fn pieces(&self, rho: f64) -> Vec<Fit> {
        let w = self.windows;
        bounds(self.splits, w.len())
            .windows(2)
            .filter_map(|b| fit(&w[b[0]..b[1]], 0.0, false, rho))
            .collect()
    }

    /// The linear fit's drift and its σ, ppm (positive: the estimate's clock runs fast): the σ from
    /// the windows' σ, raised by the scatter about the line where it exceeds them.
    fn drift_ppm(&self) -> Option<(f64, f64)> {
        self.linear
            .map(|l| (-l.b * 1e6, l.sigma_b * 1e6 * l.birge(self.windows.len(), 2)))
    }
}

/// Sets the chosen model's parameters.
fn fill(
    model: &mut ClockModel,
    f: &Fits<'_>,
    profile: &OffsetProfile,
    locate: Option<&Locate<'_>>,
) {
    match model.model {
        OffsetModel::Constant => {}
        OffsetModel::Linear => {
            let l = f.linear.unwrap_or(f.constant);
            model.offset_s = l.a;
            model.sigma_s = l.sigma_a.max(SIGMA_FLOOR_S);
            model.drift_ppm = Some(-l.b * 1e6);
        }
        OffsetModel::Piecewise => {
            model.segments = piecewise_segments(f.windows, f.splits, profile, locate);
            model.headline_from_longest_segment();
        }
    }
}

fn bounds(splits: &[usize], n: usize) -> Vec<usize> {
    let mut b = vec![0];
    b.extend(splits);
    b.push(n);
    b
}

/// The segments of a piecewise model: change times located on the data (`locate`) between the windows
/// on either side of each split, each segment's Δt the weighted mean of the windows wholly inside it.
///
/// Two changes less than a window apart are one step seen from both sides of the window that
/// straddles it (its Δt between the two, a split either side of it): the segment between them
/// holds no window of its own, so its windows join the side whose Δt is nearer theirs and the
/// change is located again. On the validation's step missions this turned a 3-second segment 87 ms
/// off into one step located 1 s from the truth and changed nothing else (docs/evidence.md).
fn piecewise_segments(
    w: &[ProfileWindow],
    splits: &[usize],
    profile: &OffsetProfile,
    locate: Option<&Locate<'_>>,
) -> Vec<ClockSegment> {
    let half = 0.5 * profile.window_s;
    let rho = profile.redundancy();
    let mut splits = splits.to_vec();
    let (b, means, changes) = loop {
        let b = bounds(&splits, w.len());
        let means: Vec<f64> = b
            .windows(2)
            .map(|x| fit(&w[x[0]..x[1]], 0.0, false, rho).map_or(f64::NAN, |f| f.a))
            .collect();
        let changes: Vec<f64> = splits
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                let (lo, hi) = (w[i - 1].t - half, w[i].t + half);
                locate
                    .and_then(|l| l((means[k], means[k + 1]), (lo, hi)))
                    .unwrap_or(0.5 * (w[i - 1].t + w[i].t))
            })
            .collect();
        // Segment k lies between changes k − 1 and k.
        match (1..changes.len()).find(|&k| changes[k] - changes[k - 1] < profile.window_s) {
            Some(k) => {
                let nearer_first =
                    (means[k] - means[k - 1]).abs() <= (means[k] - means[k + 1]).abs();
                splits.remove(if nearer_first { k - 1 } else { k });
            }
            None => break (b, means, changes),
        }
    };
    let mut edges = vec![w[0].t - half];
    edges.extend(&changes);
    edges.push(w[w.len() - 1].t + half);
    edges
        .windows(2)
        .enumerate()
        .map(|(k, x)| {
            let f = fit(&inside(w, (x[0], x[1]), half), 0.0, false, rho).or_else(|| {
                let lo = b[k];
                let hi = b[k + 1];
                fit(&w[lo..hi], 0.0, false, rho)
            });
            ClockSegment {
                t_start: x[0],
                t_end: x[1],
                offset_s: f.map_or(means[k], |f| f.a),
                sigma_s: f.map_or(SIGMA_FLOOR_S, |f| f.sigma_a.max(SIGMA_FLOOR_S)),
            }
        })
        .collect()
}

/// The reference time τ in [lo, hi] at which the estimate's signal stops matching the reference at
/// Δt₁ and starts matching it at Δt₂: the τ minimising Σ_{t<τ} (z_e − z_r(t + Δt₁))² +
/// Σ_{t≥τ} (z_e − z_r(t + Δt₂))² over the estimate's samples (z: each signal standardised).
pub fn locate_change(
    (r, e): (SignalView<'_>, SignalView<'_>),
    (d1, d2): (f64, f64),
    (lo, hi): (f64, f64),
) -> Option<f64> {
    let stats = |s: &SignalView<'_>| {
        let n = s.t.len() as f64;
        let m = (0..s.t.len()).map(|i| s.value(i)).sum::<f64>() / n;
        let var = (0..s.t.len())
            .map(|i| (s.value(i) - m).powi(2))
            .sum::<f64>()
            / n;
        (m, var.sqrt().max(1e-12))
    };
    let ((mr, sr), (me, se)) = (stats(&r), stats(&e));
    let at = |t: f64| -> Option<f64> {
        let i = r.t.partition_point(|&x| x < t);
        if i == 0 || i >= r.t.len() || r.t[i] - r.t[i - 1] > 1.0 {
            return None;
        }
        let f = (t - r.t[i - 1]) / (r.t[i] - r.t[i - 1]);
        let (v0, v1) = (r.value(i - 1), r.value(i));
        Some((v0 + f * (v1 - v0) - mr) / sr)
    };
    // (reference time, cost before, cost after) per estimate sample in the stretch.
    let mut pts: Vec<(f64, f64, f64)> = Vec::new();
    for (i, &t) in e.t.iter().enumerate() {
        let v = e.value(i);
        let tr = t + d1;
        if tr < lo || tr > hi {
            continue;
        }
        let z = (v - me) / se;
        if let (Some(a), Some(b)) = (at(t + d1), at(t + d2)) {
            pts.push((tr, (z - a).powi(2), (z - b).powi(2)));
        }
    }
    if pts.len() < 10 {
        return None;
    }
    least_cost_split(&pts)
}

/// Given (time, cost before, cost after) of each sample in time order, the time τ minimising
/// Σ_{t ≤ τ} before + Σ_{t > τ} after (τ the first sample's time when every sample is better after);
/// `None` without samples.
pub fn least_cost_split(pts: &[(f64, f64, f64)]) -> Option<f64> {
    let first = pts.first()?;
    let mut after: f64 = pts.iter().map(|p| p.2).sum();
    let mut before = 0.0;
    let mut best = (after, first.0);
    for p in pts {
        before += p.1;
        after -= p.2;
        if before + after < best.0 {
            best = (before + after, p.0);
        }
    }
    Some(best.1)
}

/// The offset profile of `whole.method` around the whole mission's answer and the model chosen from
/// it (`forced`: the model to fit). The signals are computed once; the windows correlate slices.
#[allow(clippy::too_many_arguments)]
pub fn clock_model(
    ref_t: &[f64],
    ref_p: &[nalgebra::Vector3<f64>],
    est_t: &[f64],
    est_p: &[nalgebra::Vector3<f64>],
    params: &crate::align::time_offset::OffsetParams,
    whole: &crate::align::time_offset::OffsetEstimate,
    profile: &crate::align::offset_profile::ProfileParams,
    forced: Option<OffsetModel>,
) -> crate::error::Result<(OffsetProfile, ClockModel)> {
    let cache = crate::align::time_offset::SignalCache::default();
    let pair = Pair::new((ref_t, ref_p), (est_t, est_p), &cache);
    clock_model_of(&pair, params, whole, profile, forced)
}

/// [`clock_model`] over the signals of `pair` (those the whole-mission search computed).
pub fn clock_model_of(
    pair: &Pair<'_>,
    params: &crate::align::time_offset::OffsetParams,
    whole: &crate::align::time_offset::OffsetEstimate,
    profile: &crate::align::offset_profile::ProfileParams,
    forced: Option<OffsetModel>,
) -> crate::error::Result<(OffsetProfile, ClockModel)> {
    let ((r, e), lever) =
        crate::align::time_offset::prepared_signals(whole.method, pair, params, whole.offset_s)?;
    let e = match lever {
        Some(d) => SignalView::with_lever(&e, d),
        None => SignalView::of(&e),
    };
    let r = SignalView::of(&r);
    let p = crate::align::offset_profile::offset_profile(
        whole.method,
        (r, e),
        params,
        whole.offset_s,
        profile,
    );
    let whole_sigma = whole
        .sigma_s
        .map_or(SIGMA_FLOOR_S, |s| s * p.sigma_scale)
        .max(SIGMA_FLOOR_S);
    let locate = |d: (f64, f64), span: (f64, f64)| locate_change((r, e), d, span);
    let mut m = choose_model(
        &p,
        (whole.offset_s, whole_sigma),
        Some(&locate),
        forced,
        Steps::Resolved,
    );
    if m.model == OffsetModel::Constant {
        let excess = whole_against_windows_s(m.offset_s, &p);
        if excess > 0.0 {
            m.sigma_s = m.sigma_s.hypot(excess);
            m.criterion = format!(
                "{}; σ adds {:.4} s for the whole mission's answer's distance from its windows' mean",
                m.criterion, excess
            );
            m.describe();
        }
    }
    Ok((p, m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::align::time_offset::OffsetMethod;

    /// A pose profile of disjoint 20 s windows, Δt `offset(k)` ± 3 ms in window k, with a jitter of
    /// ±1 ms that repeats every three windows.
    fn profile(n: usize, offset: impl Fn(usize) -> f64) -> OffsetProfile {
        OffsetProfile {
            method: OffsetMethod::Pose,
            window_s: 20.0,
            step_s: 20.0,
            sigma_scale: 1.0,
            windows: (0..n)
                .map(|k| ProfileWindow {
                    t: 10.0 + 20.0 * k as f64,
                    offset_s: offset(k) + 1e-3 * (k % 3) as f64 - 1e-3,
                    sigma_s: 0.003,
                    correlation: 1.0,
                    usable: true,
                })
                .collect(),
        }
    }

    /// Windows in two basins 0.55 s apart, out and back (A → B → A): constant, not a step, with σ
    /// covering both basins; the same windows stepping once stay a step.
    #[test]
    fn steps_out_and_back_are_two_basins_not_a_clock() {
        let basins = profile(30, |k| if (10..20).contains(&k) { 1.63 } else { 1.08 });
        let m = choose_model(&basins, (1.08, 0.005), None, None, Steps::Resolved);
        assert_eq!(m.model, OffsetModel::Constant, "{}", m.reason);
        assert!((m.alternation_s - 0.55).abs() < 0.01, "{}", m.alternation_s);
        assert!(m.sigma_s >= 0.27, "{}", m.reason);
        assert!(m.reason.contains("out and back"), "{}", m.reason);
        let step = profile(30, |k| if k >= 15 { 1.63 } else { 1.08 });
        let m = choose_model(&step, (1.08, 0.005), None, None, Steps::Resolved);
        assert_eq!(m.model, OffsetModel::Piecewise, "{}", m.reason);
        assert_eq!(m.alternation_s, 0.0);
        // Forced, the steps stand.
        let m = choose_model(
            &basins,
            (1.08, 0.005),
            None,
            Some(OffsetModel::Piecewise),
            Steps::Resolved,
        );
        assert_eq!(m.model, OffsetModel::Piecewise, "{}", m.reason);
    }

    /// A step inside window 15 (300–320 s), its Δt between the two sides', split at windows 15
    /// and 17: the two changes land within a window of each other (the data place the change at
    /// 310 s wherever they are asked), so the segment between them holds no window of its own. One
    /// step at 310 s, each side the Δt of the windows wholly on it.
    #[test]
    fn a_step_seen_from_both_sides_of_a_straddling_window_is_one_step() {
        let p = profile(30, |k| match k {
            0..15 => -0.90,
            15 => -0.49,
            _ => -0.17,
        });
        let asked = std::cell::RefCell::new(Vec::new());
        let locate = |_: (f64, f64), (lo, hi): (f64, f64)| {
            asked.borrow_mut().push((lo, hi));
            Some(310.0_f64.clamp(lo, hi))
        };
        let segments = piecewise_segments(&p.usable(), &[15, 17], &p, Some(&locate));
        assert_eq!(segments.len(), 2, "{segments:?}");
        assert_eq!(segments[0].t_end, 310.0);
        assert!((segments[0].offset_s + 0.90).abs() < 2e-3, "{segments:?}");
        assert!((segments[1].offset_s + 0.17).abs() < 2e-3, "{segments:?}");
        // First both changes, then the one left.
        assert_eq!(
            *asked.borrow(),
            [(280.0, 320.0), (320.0, 360.0), (280.0, 320.0)]
        );
        // Changes a window apart or more stay two steps.
        let p = profile(30, |k| match k {
            0..15 => -0.90,
            15..17 => -0.49,
            _ => -0.17,
        });
        let locate = |_: (f64, f64), (lo, hi): (f64, f64)| Some(0.5 * (lo + hi));
        let segments = piecewise_segments(&p.usable(), &[15, 17], &p, Some(&locate));
        assert_eq!(segments.len(), 3, "{segments:?}");
    }
}
