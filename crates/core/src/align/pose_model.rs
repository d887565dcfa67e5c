//! The clock model from the pose fit: the mission's Δt, its profile over windows and the model they
//! support, each with an error bar from the mission's own windows.
//!
//! 1. **Whole mission.** One Δt and the lever D fitted over every window ([`pose_fit::fit`]), from the
//!    offset the signal searches found; windows whose fit leaves a residual far above the others (a
//!    jump of the estimate inside them) are left out. Each window's scale is held to the mission's
//!    by the prior [`scale_prior_m`] chooses from the reference's speed (firm for a vehicle, loose
//!    for a robot that walks: [`walking`]).
//! 2. **Profile.** Each window's own Δt with D held ([`pose_fit::profile`]; searched ±3 s for a
//!    deeper root where the whole mission's constant is uncertain beyond 2 ms), its σ the window's
//!    least-squares error calibrated by the scatter of the windows about their neighbours, a factor
//!    and an excess every window shares ([`pose_fit::scatter_calibration`]): model-free for a
//!    constant clock and a linear drift alike.
//! 3. **Model.** [`crate::align::clock_model::choose_model`] over the profile: a drift or a step only
//!    when the windows' calibrated σ refute one constant (BIC margin), a step only with two windows
//!    of support on each side.
//! 4. **Final fit.** The chosen model's parameters (constant; offset and drift; one offset per
//!    segment) fitted again with D over every window; a drift below the resolution, or steps whose
//!    sides this fit does not tell apart ([`steps_resolved`]), become the constant. Their σ come
//!    from the mission's windows twice: the jackknife over the windows of that fit (D free; at
//!    least its formal σ, see [`crate::align::pose_fit`]), and the profile's windows for the same
//!    parameter (their calibrated σ combined and raised by their scatter about it, D held; the
//!    signal searches' 2 ms floor is not theirs; where fewer of them converged than the fit has
//!    windows, k of n, times √(k/n): k windows combined are the error bar of a k-window answer,
//!    [`windows_share`]). The windows hold D, so they cannot see what
//!    D's freedom adds to the offset's error (a forward lever fitted a few centimetres off moves
//!    every window alike); that share of the formal σ ([`pose_fit::PoseFit::lever_share_s`]) joins
//!    their part in quadrature (on the second simulator's 960 seen missions, scaled to equal
//!    medians, errors beyond 2.5σ 41 → 33; docs/evidence.md, "The lever's share of σ"). An
//!    offset's σ (the constant's, each segment's) is
//!    the mean of the two variances, at least the formal σ (over at least [`MIN_POOLED_WINDOWS`]
//!    windows and where the jackknife saw a spread; otherwise the larger): each alone is an
//!    estimate from 8–30 windows, noisy from mission to mission, and the larger of two noisy
//!    estimates is biased wide (taking it, the constant clocks' median |error|/σ was 0.595 against
//!    a Gaussian's 0.674 and 2σ covered 96 %; pooled, 0.674 and 95 %, and scaled to the same median
//!    fewer errors beyond 2.5σ: 30 of 1399 against 36; docs/evidence.md, "Two estimates of σ,
//!    pooled"). The line's σ (offset at t_mid and drift) stay the fit's, at least the windows':
//!    there the windows' line is the narrower (alone its median |error|/σ is 1.02), and pooling
//!    would take the declared drifts' 2σ coverage from 95 % to 93 %. The report's
//!    `time_offset.sigma_parts` gives the pieces and the rule ([`SigmaParts`]).
//! 5. **Tilings.** A constant's Δt and lever are the mean of the final fit and of three more on
//!    the same windows' cuts moved by a quarter, a half and three quarters of a window
//!    ([`TILINGS`], `over_tilings`): where the cuts fall chooses part of each window's slow errors,
//!    and on 1–2 Hz references that part moved Δt by 10–30 ms from one tiling to the next. The
//!    offset's σ loses, in quadrature, what the mean removes of the tilings' spread, at least the
//!    formal σ (`sigma_parts.cuts_s`; docs/evidence.md, "The windows' cuts, averaged"), where
//!    that removal is resolved from σ: what remains exceeds the removal's own noise (a spread
//!    from four fits is a variance from three degrees of freedom; [`Cuts::resolved_against`]).
//!    Not where the fit's σ is below [`TILINGS_FROM_SIGMA_S`]: there the mean moves Δt by less,
//!    and costs a long mission's evaluation half its time again.
//!
//! **The lead search.** The signal searches read a sensor ahead of the other as a clock offset of
//! lever/speed (at a walk, a 0.3 m lever is a second), and the fit from there stays in the long
//! valley where Δt trades against the forward lever, which only the gait's ripple of the speed and
//! the turns slope; a speed search can match a smooth walking speed at a wrong lag, confidently.
//! Where the windows chose one constant clock, or a step or a drift of their own (windows started a
//! lead away settle in the gait's basins, which read as either; not a model the user forced), and
//! [`LEAD_LEVER_M`] over the reference's mean speed while it moves (the lead, at most
//! [`MAX_LEAD_S`]) exceeds [`LEAD_REACH`] times [`MAX_DISAGREEMENT_S`] (the robot is
//! [`walking`]), Δt is scanned from the lead before the earliest confident search's answer to the
//! lead after the latest, the lever solved at each candidate ([`pose_fit::coarse_minima`]);
//! constant fits start from the scan's best minima (with the lever found there, else none; one that
//! leaves its minimum's basin is made again on [`pose_fit::NARROW_JACOBIAN_PERIODS`], as a gait's
//! bob can turn the default Jacobian negative;
//! where no fit could be made from the start, one whose forward lever exceeds [`LEAD_LEVER_M`]
//! beyond [`LEAD_SIGNIFICANCE_T`] of its σ traded Δt for a lever the search does not allow for, and
//! is dropped, said where it fits better ([`PoseClock::beyond_lever`]): a walking robot's fit 3.4 s
//! off with a lever of 0.86 m had won there; on the second simulator's 897 other walking missions
//! the reported fit's was 0.39 m at most) and compete with the near fit on their residual per point
//! over the **referee's windows**: [`REFEREE_WINDOW_S`] long (at most a sixth of the mission), each
//! fit's Δt held and the lever settled there ([`pose_fit::residuals_at`]). A 20 s window's own
//! heading and translation take an along-track shift of the path as it comes, so on the fits'
//! windows the valley is nearly flat; over 80 s the speed changes, and the truth's basin is the
//! deepest where on 20 s windows another was (the scan runs on the referee's windows too). A fit
//! the referee finds worse than the minimum it started from beyond [`LEAD_SIGNIFICANCE_T`] (it
//! climbed out of that basin), and a minimum by the near fit that it finds better than the near
//! fit, are fitted again on the referee's windows from the minimum (where a jump of the estimate
//! leaves the referee fewer than three windows, the fits' own windows judge). The best replaces the
//! near fit (in the near fit's basin only when better beyond the paired t) when the profile
//! measured from it chooses a constant clock too (only then: across a clock step the constant
//! trades its lever for Δt as well, and the other segment's basin fits better; a true drift
//! stays a drift, as on every drifting walking robot of `trajdrift validate`); where fewer than
//! three of that profile's windows converge on the default Jacobian, it is measured on the narrow
//! one, as the caller does where the default cannot make the near fit (a walking robot with receipt
//! stamps: not one of 44 windows converged from the right fit on the default, and the near fit,
//! worse by a paired t of 25, stayed 655 ms off; on the narrow one all 44 lay within 5 ms of it).
//! Where another fit (or the scan's minimum it started from, where that fits the windows better
//! than the fit that climbed from it) is not worse beyond [`LEAD_SIGNIFICANCE_T`] (a paired t over
//! the referee's windows' residuals: the windows are independent where the points are not), the
//! data cannot tell the two apart, and the constant's σ adds half their distance in quadrature
//! (`sigma_parts.valley_s`). Measured on a second simulator's missions (docs/evidence.md, "A second
//! simulator, and the lead search", "The valley refereed on longer windows").
//!
//! A constant clock whose drift the data cannot resolve could still hide one below the resolution:
//! when the profile's line measures a drift d beyond [`HIDDEN_DRIFT_Z`] of its σ_d (a drift the data
//! suggest without resolving it), the constant's σ adds the part of it beyond its noise,
//! √(d² − σ_d²)·(the windows' spread in time: the σ-weighted RMS distance of their times from
//! their mean), what such a drift moves Δt by over the mission in the RMS. Below 2σ_d the measured drift
//! is what a constant clock's windows show by chance (a third of them beyond 1σ_d): added from 1σ_d
//! on, it raised σ on 6 and 8 of 12 fresh draws of a ground and a legged mission on constant clocks,
//! by up to 2.5 times (docs/evidence.md, "The hidden drift, from 2σ").

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::align::clock_model::{
    choose_model, locate_change, windows_inside, windows_line_sigma_s, windows_offset_s,
    windows_offset_sigma_s, ClockModel, ClockSegment, OffsetModel, Steps,
};
use crate::align::offset_profile::{OffsetProfile, ProfileParams, ProfileWindow};
use crate::align::pose_fit::{self, ClockShape, PoseData, PoseFit, WindowSearch};
use crate::align::signals::SignalView;
use crate::align::time_offset::OffsetMethod;

/// Least σ of a window or of the headline Δt from the pose fit, seconds (the fit is continuous in
/// Δt; this only keeps a degenerate window from claiming infinite precision).
pub const POSE_SIGMA_FLOOR_S: f64 = 1e-4;
/// The pose fit's Δt may differ from the signal search's by this much at most, seconds: farther, the
/// fit went to another basin and is not used (only the lead search looks farther, and judges the
/// basins it finds on every window).
pub const MAX_DISAGREEMENT_S: f64 = 0.3;
/// The largest forward lever between the two sensors the lead search allows for, metres (it runs
/// on walking robots only, whose sensors sit on one body; the signal searches' disagreement is read
/// as a lever up to [`crate::align::auto_offset::MAX_LEVER_M`], a vehicle's antenna included).
pub const LEAD_LEVER_M: f64 = 0.5;
/// The lead at most, seconds (a lever of 0.5 m at 0.2 m/s).
pub const MAX_LEAD_S: f64 = 2.5;
/// The lead search's step, seconds (a step rate up to 2.6 Hz, its bob at twice that, ripples the
/// valley every 0.19–0.38 s). At 0.1 s the fit from the scan's minimum by the truth, 0.04–0.07 s
/// from it, slid into another basin on walking missions of a second simulator, which were then
/// read 0.2–0.5 s off (docs/evidence.md, "The lead search, finer").
pub const LEAD_STEP_S: f64 = 0.05;
/// Two fits, or a fit and a scan's minimum, within this of each other lie in one basin, seconds.
pub const SAME_BASIN_S: f64 = 0.1;
/// The lead search fits from this many of its best minima at most (outside the near fit's basin;
/// six moved no mission of the second simulator's 256 walking ones by more than 0.03 ms).
pub const LEAD_MINIMA: usize = 3;
/// A fit along the valley is told from another when the windows' residuals, paired, differ by at
/// least this many of their standard errors (a t statistic); nearer, σ covers both (see the module
/// doc).
pub const LEAD_SIGNIFICANCE_T: f64 = 2.0;
/// Other confident searches' answers farther than this from the applied one are not scanned
/// about, seconds (twice the largest lead: a search that far off found something else).
pub const MAX_ANSWER_SPREAD_S: f64 = 2.0 * MAX_LEAD_S;
/// The lead search's scan looks at this many of the referee's windows at most (evenly spread:
/// 1200 s of a long mission).
pub const LEAD_SCAN_WINDOWS: usize = 15;
/// The lead search's referee compares Δt along the valley on windows this long, seconds (at least
/// the fit's, at most the mission's span over [`REFEREE_MIN_WINDOWS`]). A window's similarity
/// (its own heading, scale and translation) takes an along-track shift of the path as it comes:
/// on a straight or a steadily curving stretch the shift is a rotation and a translation. What
/// tells Δt from a forward lever is the speed changing, and within 20 s it barely does; over 80 s
/// the truth's basin fits best where on 20 s windows another did (docs/evidence.md, "The valley
/// refereed on longer windows").
pub const REFEREE_WINDOW_S: f64 = 80.0;
/// The referee's windows are at most the mission's span over this many (its paired t needs some).
pub const REFEREE_MIN_WINDOWS: usize = 6;
/// The lead search runs where the lead can exceed this many times [`MAX_DISAGREEMENT_S`] (below
/// 0.83 m/s: walking robots; a vehicle's speed search, immune to a forward lever, starts the fit
/// near enough, and the search would cost a long mission's evaluation a fifth more).
pub const LEAD_REACH: f64 = 2.0;
/// The step of the coarse search for a start when the fit from the signal search's answer does not
/// converge, seconds (the fit converged from 34–100 ms off where it stalled from 64–218 ms).
pub const COARSE_STEP_S: f64 = 0.025;
/// Each window of the profile searches this far around its start when its own refinement fails (a
/// clock step), or for a deeper root (see `Mission::window_search`), seconds.
pub const WINDOW_SEARCH_S: f64 = 3.0;
/// An offset's σ pools the jackknife with the windows only over at least this many windows (the
/// jackknife's own least); over fewer, and where the jackknife saw no spread at all, it is the
/// larger of the two.
pub const MIN_POOLED_WINDOWS: usize = 3;
/// A drift below the resolution enters the constant's σ only when the profile's line measures it
/// beyond this many of its σ (see the module doc).
pub const HIDDEN_DRIFT_Z: f64 = 2.0;
/// A clock step the windows chose is kept only where the final fit tells its two sides apart by
/// more than this many σ of their difference (see [`steps_resolved`]).
pub const STEP_RESOLUTION_Z: f64 = 3.0;
/// Every profile window is searched for a deeper root unless the whole mission's constant has a σ
/// within this, seconds (see `Mission::window_search`).
pub const DEEP_SEARCH_SIGMA_S: f64 = 0.002;
/// A constant clock's Δt and lever are the mean over this many tilings of the mission's windows,
/// each shifted by a further 1/`TILINGS` of a window (see `over_tilings` and the module doc).
pub const TILINGS: usize = 4;
/// A tiling's fit joins the mean only within this many of the first tiling's σ of it (farther, it
/// went to another basin).
pub const TILING_REACH_SIGMA: f64 = 3.0;
/// A constant whose fit's σ (the jackknife's, at least the formal) is below this is not averaged
/// over tilings, seconds: the tilings' Δt spread by about one tiling's σ, so the mean would move
/// it by a fraction of a millisecond, while three more fits of a two-hour mission on a 10 Hz
/// reference (σ 0.2 ms) made its evaluation take 1.67 times as long (docs/evidence.md, "The
/// windows' cuts, averaged").
pub const TILINGS_FROM_SIGMA_S: f64 = 1e-3;

/// How the headline σ combined the jackknife with the windows (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SigmaCombination {
    /// An offset (constant, a segment): the mean of the two variances (the windows' with the
    /// lever's share), at least the formal σ.
    Pooled,
    /// The larger of the fit's σ (the jackknife, at least the formal) and the windows': the line's
    /// rule, and an offset's over fewer than three windows, without windows, or where the jackknife
    /// saw no spread.
    Larger,
}

/// What the headline σ was made of, seconds: the report's `sigma_parts`, so that a user (and the
/// validation) can see which piece carries it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SigmaParts {
    /// The final fit's jackknife over windows, the lever free.
    pub jackknife_s: f64,
    /// The final fit's formal σ (what white residuals would give; 0 when it could not be formed).
    pub formal_s: f64,
    /// The profile's windows for the same parameter, the lever held (their calibrated σ combined
    /// and raised by their scatter about it; when pooled, times √([`windows_share`]) where the
    /// profile kept fewer windows than the fit has); `None` without a window inside an offset's
    /// span, or fewer than two for the line.
    pub windows_s: Option<f64>,
    /// The part of the fit's formal σ that the lever's freedom adds ([`PoseFit::lever_share_s`]),
    /// which the windows, the lever held, cannot see: added to their part in quadrature before
    /// pooling (0 when not pooled).
    #[serde(default)]
    pub lever_s: f64,
    /// A drift below the resolution the constant could hide, added in quadrature (0 otherwise).
    pub hidden_drift_s: f64,
    /// Half the distance to a fit along the forward lever's valley that the windows do not find
    /// worse (the lead search, see the module doc), added in quadrature (0 otherwise).
    #[serde(default)]
    pub valley_s: f64,
    /// Half the spread of windows that stepped out and back between two basins, read as one
    /// constant clock ([`crate::align::clock_model::ClockModel::alternation_s`]), added in
    /// quadrature (0 otherwise).
    #[serde(default)]
    pub basins_s: f64,
    /// The part of one tiling's σ that the mean over [`TILINGS`] tilings of the windows removes
    /// (their Δt's spread, see `over_tilings`), taken away in quadrature, never below the formal σ
    /// (0 otherwise: not a constant, one tiling, or a spread not resolved from σ,
    /// [`Cuts::resolved_against`]).
    #[serde(default)]
    pub cuts_s: f64,
    pub combined: SigmaCombination,
}

/// The clock model found by the pose fit.
#[derive(Debug, Clone)]
pub struct PoseClock {
    pub profile: OffsetProfile,
    pub model: ClockModel,
    /// The final fit (the chosen model's parameters, the lever, the windows used); `None` when it did
    /// not converge and the model's parameters are the windows'.
    pub fit: Option<PoseFit>,
    /// The lever used and its σ (estimate body frame, metres).
    pub lever: (Vector3<f64>, Option<Vector3<f64>>),
    /// The final fit's first clock parameter (the constant; the line's offset at t_mid; the first
    /// segment's offset) and its σ as the model reports it.
    pub first_offset: (f64, f64),
    /// Windows left out of the whole-mission fit (their residual far above the others').
    pub outlier_windows: usize,
    /// What the headline σ was made of; `None` when the model's parameters are the windows'.
    pub sigma_parts: Option<SigmaParts>,
    /// When the lead search's constant replaced what the windows chose from the start.
    pub replaced: Option<Replaced>,
    /// A fit the lead search left out for its forward lever that fits the referee's windows
    /// better than the one reported (its forward lever beyond [`LEAD_LEVER_M`], see
    /// [`BeyondLever`]).
    pub beyond_lever: Option<BeyondLever>,
}

/// A lead-search fit left out because its forward lever exceeds [`LEAD_LEVER_M`] beyond
/// [`LEAD_SIGNIFICANCE_T`] of its σ, that fits the referee's windows better than the reported fit
/// ([`PoseClock::beyond_lever`]): right only on a robot whose sensors sit that far apart along its
/// travel, where the user gives the levers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeyondLever {
    /// Its Δt, seconds.
    pub offset_s: f64,
    /// Its forward lever and that lever's σ, metres.
    pub forward_m: f64,
    pub forward_sigma_m: f64,
}

/// What the lead search's constant replaced ([`PoseClock::replaced`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Replaced {
    /// The model the windows chose from the start.
    pub model: OffsetModel,
    /// Its first clock parameter, seconds.
    pub first_s: f64,
    /// The windows from the lead search's constant were measured on the narrow Jacobian
    /// ([`pose_fit::NARROW_JACOBIAN_PERIODS`]): on the default one fewer than three converged.
    pub narrow_windows: bool,
}

/// The speed signals of the pair (reference, estimate), asked for only when a step's time is not
/// found on the positions (so computed only then, when the caller has not computed them already).
pub type Signals<'a> = &'a dyn Fn() -> Option<(SignalView<'a>, SignalView<'a>)>;

/// The clock model of the mission in `data` from the pose fit, starting at `start_s` (the signal
/// searches' answer; the other confident searches' answers `other_answers_s` widen the lead
/// search); `None` when the fit cannot be made (too few windows, no convergence, or an answer
/// farther than [`MAX_DISAGREEMENT_S`] from the start that the lead search did not find).
///
/// The Newton Jacobian is `data.params.jacobian_periods` wide; a caller whose fit cannot be made
/// may try [`pose_fit::NARROW_JACOBIAN_PERIODS`] (a gait the default's differences answer with
/// the wrong sign sends Newton away from the truth), and says so.
pub fn pose_clock_model(
    data: &PoseData<'_>,
    start_s: f64,
    other_answers_s: &[f64],
    profile_params: &ProfileParams,
    signals: Signals<'_>,
    forced: Option<OffsetModel>,
) -> Option<PoseClock> {
    // The reference's mean speed while it moves (a robot that stands half the mission still walks).
    let moving_speed_mps =
        crate::align::auto_params::moving_speed(data.ref_t, data.ref_p, data.params.max_gap_s)
            .map(|(v, _)| v);
    let data = PoseData {
        params: pose_fit::PoseFitParams {
            window_s: profile_params.window_s.or(data.params.window_s),
            scale_prior_m: scale_prior_m(moving_speed_mps),
            ..data.params
        },
        ..*data
    };
    let narrow_data = narrowed(&data);
    let windows = data.windows();
    if windows.len() < 3 {
        return None;
    }
    let mut mission = Mission {
        data: &data,
        // The profile's windows: the fits' own (disjoint), or every `--offset-step` seconds.
        profile_windows: data.profile_windows(profile_params.step_s),
        whole: whole_mission_fit(&data, &windows, start_s),
        windows,
        signals,
        forced,
    };
    let mut chosen = mission.choose(start_s)?;
    // The lead search, where the windows chose one constant clock, or a step or a drift of their
    // own (`lead_searched`): across a true clock step the constant trades its lever for Δt as
    // well, and the other segment's basin fits better, so a far constant replaces the chosen model
    // only when the profile measured from it chooses a constant too (a true step or drift stays).
    // A drift the final fit leaves below the resolution (`resolved`) becomes a constant after
    // this.
    // The near fit: the whole mission's, or without one the chosen constant's.
    let near = mission.whole.clone().or_else(|| chosen.fit.clone());
    let lead = lead_searched(chosen.model.model, mission.forced)
        .then(|| {
            let answers: Vec<f64> = std::iter::once(start_s)
                .chain(other_answers_s.iter().copied())
                .filter(|a| a.is_finite() && (a - start_s).abs() <= MAX_ANSWER_SPREAD_S)
                .collect();
            lead_search(
                &data,
                &mission.windows,
                &answers,
                near.as_ref(),
                moving_speed_mps?,
            )
        })
        .flatten();
    let mut replaced = None;
    if let Some(far) = lead.as_ref().and_then(|l| l.far(near.as_ref())) {
        let other = Mission {
            whole: Some(far),
            windows: mission.windows.clone(),
            profile_windows: mission.profile_windows.clone(),
            ..mission
        };
        // Where the default Jacobian leaves the profile from the far fit fewer than three
        // windows, it is measured on the narrow one (the caller's fallback for the near fit).
        let (other, c, narrow_windows) = match other.choose(start_s) {
            Some(c) => (other, Some(c), false),
            None => {
                let other = Mission {
                    data: &narrow_data,
                    ..other
                };
                let c = other.choose(start_s);
                (other, c, true)
            }
        };
        if let Some(c) = c.filter(|c| c.model.model == OffsetModel::Constant) {
            let first_s = chosen
                .fit
                .as_ref()
                .map_or(chosen.model.offset_s, |f| f.theta[0]);
            replaced = Some(Replaced {
                model: chosen.model.model,
                first_s,
                narrow_windows,
            });
            (mission, chosen) = (other, c);
        }
    }
    // Without a converged fit of the chosen model, its parameters stay those of the windows.
    let Some(last) = chosen.fit else {
        return mission
            .without_fit(chosen.profile, chosen.model, chosen.lever_m)
            .map(|pc| PoseClock { replaced, ..pc });
    };
    let (profile, mut model) = (chosen.profile, chosen.model);
    let last = mission.resolved(&mut model, last);
    let (last, cuts) = match model.model {
        OffsetModel::Constant => over_tilings(mission.data, last),
        _ => (last, Cuts::NONE),
    };
    let valley_s = match (&lead, model.model) {
        (Some(lead), OffsetModel::Constant) => lead.valley_s(&data, &last),
        _ => 0.0,
    };
    let beyond_lever = match (&lead, model.model) {
        (Some(lead), OffsetModel::Constant) => lead.beyond_lever(&data, &last),
        _ => None,
    };
    let sigma_parts = set_parameters(&mut model, &last, &profile, valley_s, cuts);
    model.describe();
    // θ₀'s σ as reported: the headline's, or the first segment's.
    let first_sigma_s = match model.model {
        OffsetModel::Piecewise => model.segments.first().map_or(model.sigma_s, |s| s.sigma_s),
        _ => model.sigma_s,
    };
    Some(PoseClock {
        profile,
        model,
        sigma_parts,
        outlier_windows: last.outliers.len(),
        first_offset: (last.theta[0], first_sigma_s),
        lever: (last.lever_m, last.lever_sigma_m),
        fit: Some(last),
        replaced,
        beyond_lever,
    })
}

/// Step 1: one Δt and the lever over every window from `start_s`, or, when that does not converge,
/// from the best of a coarse search within [`MAX_DISAGREEMENT_S`] of it
/// ([`pose_fit::coarse_start`], every [`COARSE_STEP_S`]); `None` when neither converges or the fit
/// lands farther than [`MAX_DISAGREEMENT_S`] from the start (another basin).
fn whole_mission_fit(
    data: &PoseData<'_>,
    windows: &[pose_fit::Window],
    start_s: f64,
) -> Option<PoseFit> {
    let from = |theta: f64| {
        pose_fit::fit(
            data,
            windows,
            ClockShape::Constant,
            vec![theta],
            Vector3::zeros(),
            true,
        )
        .filter(|w| w.converged && (w.theta[0] - start_s).abs() <= MAX_DISAGREEMENT_S)
    };
    from(start_s).or_else(|| {
        let coarse =
            pose_fit::coarse_start(data, windows, start_s, (MAX_DISAGREEMENT_S, COARSE_STEP_S))?;
        ((coarse - start_s).abs() >= COARSE_STEP_S)
            .then(|| from(coarse))
            .flatten()
    })
}

/// Whether a robot whose mean speed while it moves is `moving_speed_mps` walks: a forward lever of
/// [`LEAD_LEVER_M`] then leads by more than [`LEAD_REACH`] × [`MAX_DISAGREEMENT_S`] (below
/// 0.83 m/s).
/// The lead search runs there, and the windows' scale prior is the walking one.
pub fn walking(moving_speed_mps: f64) -> bool {
    LEAD_LEVER_M / moving_speed_mps > LEAD_REACH * MAX_DISAGREEMENT_S
}

/// The windows' scale prior for a reference whose mean speed while it moves is `moving_speed_mps`
/// (`None`: it hardly moves), metres of spread per sample.
///
/// **Why two.** A window's free scale absorbs a speed that changes steadily within it: along the
/// track ê(t − Δt) is then a scaled copy of ê(t), and Δt rests on what the speed does beyond a
/// line. On a near-straight drive that is little, and the forward lever takes the rest. Odometry's
/// scale error changes slowly (a wheel's radius, a lidar's near-unit scale), so a vehicle's windows
/// are held to the mission's scale ([`pose_fit::VEHICLE_SCALE_PRIOR_M`]: a 20 s window at 1 m/s
/// spreads 5.8 m per sample, its scale then the mission's). On the second simulator's
/// missions a prior of 10 m took ground missions' median error from 7.5 to 2.8 ms and near-straight
/// ones' from 10.7 to 2.0 ms (8.9 → 3.1 and 7.8 → 2.1 ms on seed sets drawn to check the choice;
/// docs/evidence.md, "A vehicle's window scales held"); 30 m took the vehicles' median over 476
/// missions from 3.2 to 2.8 ms, and above 10 ms from 62 to 48 (docs/evidence.md, "A vehicle's
/// window scales held firmer"). A walking robot ([`walking`]) keeps
/// [`pose_fit::SCALE_PRIOR_M`]: the firmer prior moved its missions between the gait's near-equal
/// basins, both ways, and four of them read a false clock step.
///
/// ```
/// use trajdrift_core::align::pose_fit::{SCALE_PRIOR_M, VEHICLE_SCALE_PRIOR_M};
/// use trajdrift_core::align::pose_model::scale_prior_m;
/// assert_eq!(scale_prior_m(Some(1.5)), VEHICLE_SCALE_PRIOR_M);
/// assert_eq!(scale_prior_m(Some(0.4)), SCALE_PRIOR_M);
/// assert_eq!(scale_prior_m(None), SCALE_PRIOR_M);
/// ```
pub fn scale_prior_m(moving_speed_mps: Option<f64>) -> f64 {
    if moving_speed_mps.is_some_and(|v| !walking(v)) {
        pose_fit::VEHICLE_SCALE_PRIOR_M
    } else {
        pose_fit::SCALE_PRIOR_M
    }
}

/// What the lead search found: the fits along the forward lever's valley (the near one among
/// them), judged over `windows` (the referee's, [`referee_windows`], less those holding a window
/// any of the fits left out as a jump).
struct Lead {
    windows: Vec<pose_fit::Window>,
    fits: Vec<LeadFit>,
    /// The fits left out for their forward lever ([`within_lead_lever`]), judged on `windows`.
    beyond: Vec<LeadFit>,
}

/// A fit along the valley: the residual per point at its Δt in every window of [`Lead::windows`]
/// (the lever settled there, [`pose_fit::residuals_at`]), and the scan's minimum it started from
/// (`None`: the near fit).
struct LeadFit {
    fit: PoseFit,
    residuals: Vec<Option<f64>>,
    from: Option<pose_fit::ScanMinimum>,
}

impl Lead {
    /// The fit with the least mean residual per point over the windows every fit has points in,
    /// when it is not in `near`'s basin.
    fn far(&self, near: Option<&PoseFit>) -> Option<PoseFit> {
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
    fn valley_s(&self, data: &PoseData<'_>, reported: &PoseFit) -> f64 {
        let at = |offset_s: f64| pose_fit::residuals_at(data, &self.windows, offset_s);
        let residuals = at(reported.theta[0]);
        let at_minimum = |m: &pose_fit::ScanMinimum| at(m.offset_s);
        let candidates = self.candidates(reported.theta[0], at_minimum);
        undecided_reach_s(reported.theta[0], &residuals, candidates)
    }

    /// The fit left out for its forward lever that fits the windows best, where it fits them better
    /// than `reported` (a negative paired t): what the bound decided.
    fn beyond_lever(&self, data: &PoseData<'_>, reported: &PoseFit) -> Option<BeyondLever> {
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
    fn beyond_against(&self, residuals: &[Option<f64>]) -> Option<BeyondLever> {
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
    fn candidates<'l>(
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
fn undecided_reach_s(
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
fn lead_searched(model: OffsetModel, forced: Option<OffsetModel>) -> bool {
    match model {
        OffsetModel::Constant => true,
        OffsetModel::Piecewise | OffsetModel::Linear => forced.is_none(),
    }
}

/// `data` with the narrow Jacobian, [`pose_fit::NARROW_JACOBIAN_PERIODS`].
fn narrowed<'d>(data: &PoseData<'d>) -> PoseData<'d> {
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
fn referee_length_s(fit_s: f64, span_s: f64) -> f64 {
    (span_s / REFEREE_MIN_WINDOWS as f64)
        .min(REFEREE_WINDOW_S)
        .max(fit_s)
}

/// Two constant fits in one basin: their Δt within [`SAME_BASIN_S`].
fn same_basin(a: &PoseFit, b: &PoseFit) -> bool {
    (a.theta[0] - b.theta[0]).abs() <= SAME_BASIN_S
}

/// The lead search (see the module doc): constant fits from the best minima of a scan of Δt over
/// the lead a forward lever can make at the reference's walking speed `moving_speed_mps` (its
/// mean while it moves) about the confident searches' answers `answers_s`, with the fit `near`
/// (the whole mission's, from the applied answer); `None` where the robot is not [`walking`] or
/// no answer is finite.
fn lead_search(
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
fn within_lead_lever(fit: &PoseFit) -> bool {
    let sigma_m = fit.lever_sigma_m.map_or(f64::INFINITY, |s| s.x);
    fit.lever_m.x.abs() - LEAD_SIGNIFICANCE_T * sigma_m <= LEAD_LEVER_M
}

/// The paired t statistic of `a` − `b` over the windows both have (negative: `a` fits better):
/// ±∞ when they differ by the same amount in every window, 0 (undecided) over fewer than two
/// windows, NaN (decided: not below any bound) when a residual is not finite.
fn paired_t(a: &[Option<f64>], b: &[Option<f64>]) -> f64 {
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

/// One mission's pose fits: the data, the windows of the fits and of the profile, the whole
/// mission's constant fit, and what the model choice takes besides the profile.
struct Mission<'a, 's> {
    data: &'a PoseData<'a>,
    windows: Vec<pose_fit::Window>,
    profile_windows: Vec<pose_fit::Window>,
    whole: Option<PoseFit>,
    signals: Signals<'s>,
    forced: Option<OffsetModel>,
}

/// A profile, the model chosen from it, and that model's fit.
struct Chosen {
    profile: OffsetProfile,
    model: ClockModel,
    /// The chosen model's clock shape.
    shape: ClockShape,
    /// The chosen model's fit with the lever over every window; `None` when it did not converge.
    fit: Option<PoseFit>,
    /// The lever the profile's windows held, estimate body frame.
    lever_m: Vector3<f64>,
}

impl Mission<'_, '_> {
    /// Steps 2 to 4: the profile, the model chosen from it and its fit. Measured from the whole
    /// mission's constant fit, or without one from `start_s` with no lever; measured again with
    /// the lever of the chosen model when that is not the constant, or when there was no constant
    /// fit.
    fn choose(&self, start_s: f64) -> Option<Chosen> {
        // Without a whole-mission constant fit (a step or a large drift spoils it), the profile
        // starts without a lever from the signal searches' answer, each window searching its own.
        let (mut lever, mut scale) = self
            .whole
            .as_ref()
            .map_or((Vector3::zeros(), (1.0, 1.0)), |w| {
                (w.lever_m, (w.scale, w.jacobian_scale))
            });
        let mut clock = (
            ClockShape::Constant,
            vec![self.whole.as_ref().map_or(start_s, |w| w.theta[0])],
        );
        let mut pass = 0;
        loop {
            pass += 1;
            // The first pass proposes steps on the BIC alone; the second, measured under them, judges.
            let steps = if pass == 1 {
                Steps::Provisional
            } else {
                Steps::Resolved
            };
            let chosen = self.pass(lever, scale, &clock, steps)?;
            // A model other than the constant was chosen on windows whose lever came from a
            // constant fit (or none): the profile is measured again with the lever of the chosen
            // model.
            if let (1, Some(l)) = (pass, &chosen.fit) {
                if chosen.model.model != OffsetModel::Constant || self.whole.is_none() {
                    lever = l.lever_m;
                    scale = (l.scale, l.jacobian_scale);
                    clock = (chosen.shape, l.theta.clone());
                    continue;
                }
            }
            // Steps proposed but not measured again (their fit did not converge): judged now, on
            // the same profile.
            if pass == 1 && chosen.model.model == OffsetModel::Piecewise {
                return Some(self.decide(
                    chosen.profile,
                    (lever, scale, clock.1[0]),
                    Steps::Resolved,
                ));
            }
            return Some(chosen);
        }
    }

    /// One pass: the profile with the lever `lever` held (the mission's scale and the scale of
    /// the clock column, `scale`: [`PoseFit::jacobian_scale`]), each window started from the clock
    /// `clock`, and what [`Self::decide`] makes of it. `None` with fewer than three windows in the profile.
    fn pass(
        &self,
        lever: Vector3<f64>,
        scale: (f64, f64),
        (shape, theta): &(ClockShape, Vec<f64>),
        steps: Steps,
    ) -> Option<Chosen> {
        let raw = pose_fit::profile(
            self.data,
            &self.profile_windows,
            lever,
            scale,
            &|t| shape.value(theta, t),
            (self.window_search(), WINDOW_SEARCH_S),
        );
        let profile = calibrated_profile(consistent_windows(raw), &self.profile_windows)?;
        Some(self.decide(profile, (lever, scale, theta[0]), steps))
    }

    /// How the profile's windows are searched: every window for a deeper root than the one it
    /// settled at, unless the whole mission's constant fit pins Δt within [`DEEP_SEARCH_SIGMA_S`]
    /// — windows that agree that well have none in another basin (a step or a first look without
    /// a lever leaves the constant's jackknife σ at 9–28 ms on the missions where a window hid
    /// one), and a long clean mission then pays nothing for the search.
    fn window_search(&self) -> WindowSearch {
        match &self.whole {
            Some(w) if w.theta_sigma[0] <= DEEP_SEARCH_SIGMA_S => WindowSearch::Failed,
            _ => WindowSearch::Every,
        }
    }

    /// The model chosen from `profile` (measured with `lever` held, at the mission's scale and
    /// the clock column's scale `scale`, its windows started from a clock whose first parameter is
    /// `clock_s`) and its parameters fitted with the lever over every window, σ by the jackknife
    /// over windows, at least the formal σ (the whole mission's fit when that is the constant).
    fn decide(
        &self,
        profile: OffsetProfile,
        (lever, scale, clock_s): (Vector3<f64>, (f64, f64), f64),
        steps: Steps,
    ) -> Chosen {
        let (offset0, whole_sigma) = match &self.whole {
            Some(w) => (w.theta[0], w.theta_sigma[0].max(POSE_SIGMA_FLOOR_S)),
            None => (clock_s, f64::INFINITY),
        };
        // A step's time on the positions, else on the speed signals.
        let locate = |d: (f64, f64), span: (f64, f64)| {
            pose_fit::locate_change(self.data, &lever, scale.0, d, span)
                .or_else(|| (self.signals)().and_then(|re| locate_change(re, d, span)))
        };
        let model = choose_model(
            &profile,
            (offset0, whole_sigma),
            Some(&locate),
            self.forced,
            steps,
        );
        let (next_shape, theta0) = shape_of(&model, offset0);
        let fit = match (&self.whole, model.model) {
            (Some(w), OffsetModel::Constant) => Some(w.clone()),
            _ => pose_fit::fit(
                self.data,
                &self.windows_of(&next_shape),
                next_shape.clone(),
                theta0,
                lever,
                true,
            )
            .filter(|f| f.converged),
        };
        Chosen {
            profile,
            model,
            shape: next_shape,
            fit,
            lever_m: lever,
        }
    }

    /// The windows a fit of `shape` uses: every one, less those holding a change of a piecewise
    /// clock (they mix two offsets).
    fn windows_of(&self, shape: &ClockShape) -> Vec<pose_fit::Window> {
        match shape {
            ClockShape::Piecewise { changes } => self
                .windows
                .iter()
                .filter(|w| !changes.iter().any(|&c| c > w.t_start && c < w.t_end))
                .cloned()
                .collect(),
            _ => self.windows.clone(),
        }
    }

    /// The clock when the chosen model's fit did not converge: its parameters are the windows'
    /// (a constant's the weighted mean of the `profile`), the lever the one they held. `None` when
    /// no lever was ever fitted (no whole-mission constant fit either).
    fn without_fit(
        &self,
        profile: OffsetProfile,
        mut model: ClockModel,
        lever_m: Vector3<f64>,
    ) -> Option<PoseClock> {
        // No lever was ever fitted (neither the whole mission's constant nor the chosen model
        // converged): the windows held it at zero, and a forward lever then reads as Δt (0.2 m at a
        // walk is half a second) with a σ that cannot show it. The signal searches' answer stands.
        self.whole.as_ref()?;
        if model.model == OffsetModel::Constant {
            if let Some((mean, sigma)) =
                windows_offset_s(&profile, (f64::NEG_INFINITY, f64::INFINITY))
            {
                model.offset_s = mean;
                model.sigma_s = sigma;
            }
        }
        model.describe();
        Some(PoseClock {
            outlier_windows: 0,
            sigma_parts: None,
            first_offset: (model.offset_s, model.sigma_s),
            fit: None,
            profile,
            model,
            lever: (lever_m, None),
            replaced: None,
            beyond_lever: None,
        })
    }

    /// The fit to report for `model`, whose fit is `last`: a drift is declared only when the fitted
    /// drift exceeds the resolution of the windows (the drift their calibrated σ can tell from a
    /// constant clock); below it the data do not refute the constant, whatever the windows' BIC
    /// said (receipt-stamp latencies or a gait tilt a few windows), and the model becomes the whole
    /// mission's constant. So too a step: kept only where the final fit tells some two neighbouring
    /// segments apart ([`steps_resolved`]); otherwise the model is the whole mission's constant, or
    /// where there was none (the fit from the signal searches' answer went to another basin) the
    /// constant fitted from the segments' mean with their lever (where that fit does not converge,
    /// the steps stand). A profile measured in another basin than the fit's (a walking robot's
    /// windows with the lever held, where Δt trades against it) can slope across the mission and
    /// propose a step whose two sides the fit then finds 6 ms apart under σ of 14–40 ms: not a
    /// clock event. Never when the model was forced.
    fn resolved(&self, model: &mut ClockModel, last: PoseFit) -> PoseFit {
        if let (None, OffsetModel::Piecewise) = (self.forced, model.model) {
            if !steps_resolved(&last) {
                let constant = self.whole.clone().or_else(|| {
                    let mean = last.theta.iter().sum::<f64>() / last.theta.len() as f64;
                    pose_fit::fit(
                        self.data,
                        &self.windows,
                        ClockShape::Constant,
                        vec![mean],
                        last.lever_m,
                        true,
                    )
                    .filter(|f| f.converged)
                });
                if let Some(w) = constant {
                    model.model = OffsetModel::Constant;
                    model.segments.clear();
                    model.criterion = format!(
                        "{}; the fit does not tell the segments apart (each step within {STEP_RESOLUTION_Z} σ)",
                        model.criterion
                    );
                    return w;
                }
            }
        }
        if self.forced.is_none() && model.model == OffsetModel::Linear {
            let fitted_ppm = -last.theta[1] * 1e6;
            if let (Some(resolution), Some(w)) = (model.drift_resolution_ppm, &self.whole) {
                if fitted_ppm.abs() < resolution {
                    model.model = OffsetModel::Constant;
                    model.criterion = format!(
                        "{}; the fitted drift {fitted_ppm:+.1} ppm is below the resolution {resolution:.1} ppm",
                        model.criterion
                    );
                    return w.clone();
                }
            }
        }
        last
    }
}

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
fn over_tilings(data: &PoseData<'_>, last: PoseFit) -> (PoseFit, Cuts) {
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
/// fit's, at least the windows' (see the module doc). The constant's σ also adds a drift the
/// profile measures beyond [`HIDDEN_DRIFT_Z`] of its σ, and `valley_s` (the lead search's: half
/// the distance to a fit the windows cannot tell from it), both in quadrature; the piecewise
/// model's headline is its longest segment's. Returns what the headline σ was made of.
fn set_parameters(
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
            // A drift below the resolution that the constant could hide (see the module doc).
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

/// The clock shape of `model` and its parameters to start from.
fn shape_of(model: &ClockModel, offset0: f64) -> (ClockShape, Vec<f64>) {
    match model.model {
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
    }
}

/// The profile of the windows' offsets, their σ calibrated by the windows' scatter
/// ([`pose_fit::scatter_calibration`]); `None` with fewer than three windows.
fn calibrated_profile(
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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// Four disjoint 20 s windows at 10, 30, 50, 70 s, each `offset(t)` ± 2 ms.
    fn profile(offset: impl Fn(f64) -> f64) -> OffsetProfile {
        OffsetProfile {
            method: OffsetMethod::Pose,
            window_s: 20.0,
            step_s: 20.0,
            sigma_scale: 1.0,
            windows: [10.0, 30.0, 50.0, 70.0]
                .map(|t| ProfileWindow {
                    t,
                    offset_s: offset(t),
                    sigma_s: 0.002,
                    correlation: 1.0,
                    usable: true,
                })
                .to_vec(),
        }
    }

    /// A converged final fit with parameters `theta` and their σ `sigma`.
    fn fit(shape: ClockShape, theta: Vec<f64>, sigma: Vec<f64>) -> PoseFit {
        let n = theta.len();
        PoseFit {
            shape,
            theta,
            lever_m: Vector3::zeros(),
            theta_jackknife_sigma: sigma.clone(),
            theta_formal_sigma: vec![0.0; n],
            theta_sigma: sigma,
            lever_sigma_m: None,
            covariance: DMatrix::zeros(n, n),
            variance_inflation: vec![1.0; n],
            windows: Vec::new(),
            outliers: Vec::new(),
            rms_m: Vec::new(),
            scale: 1.0,
            jacobian_scale: 1.0,
            iterations: 1,
            converged: true,
        }
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn a_step_is_resolved_only_beyond_three_sigma_of_the_difference_of_its_sides() {
        let two = |d: f64, var: f64, cov: f64| {
            let mut f = fit(
                ClockShape::Piecewise {
                    changes: vec![100.0],
                },
                vec![0.2, 0.2 + d],
                vec![var.sqrt(); 2],
            );
            f.covariance = DMatrix::from_row_slice(2, 2, &[var, cov, cov, var]);
            f
        };
        // 6 ms under σ 14 ms on each side, uncorrelated: not a step.
        assert!(!steps_resolved(&two(0.006, 0.014f64.powi(2), 0.0)));
        // 100 ms: a step.
        assert!(steps_resolved(&two(0.1, 0.014f64.powi(2), 0.0)));
        // Sides that share most of their error (the lever's, which moves both alike): with 96 % of
        // the variance shared the difference is known to 4.0 ms, and 6 ms is within 3σ of it;
        // with 98 %, to 2.8 ms, and 10 ms is beyond.
        assert!(!steps_resolved(&two(
            0.006,
            0.014f64.powi(2),
            0.96 * 0.014f64.powi(2)
        )));
        assert!(steps_resolved(&two(
            0.010,
            0.014f64.powi(2),
            0.98 * 0.014f64.powi(2)
        )));
        // One segment: nothing to resolve.
        let one = fit(ClockShape::Constant, vec![0.2], vec![0.01]);
        assert!(steps_resolved(&one));
    }

    #[test]
    fn a_profile_of_few_of_the_fits_windows_speaks_for_all_of_them() {
        let p = profile(|_| 0.1);
        let ms = |v: f64| v * 1e-3;
        let over = |n: usize| {
            let mut f = fit(ClockShape::Constant, vec![0.1], vec![ms(0.3)]);
            f.windows = (0..n)
                .map(|k| pose_fit::Window {
                    range: 0..0,
                    t_start: 20.0 * k as f64,
                    t_end: 20.0 * (k + 1) as f64,
                })
                .collect();
            f
        };
        // The fit over the profile's four windows of 20 s: they combine to 1 ms, as before.
        let mut m = ClockModel::constant(0.0, 0.0, String::new());
        let parts = set_parameters(&mut m, &over(4), &p, 0.0, Cuts::NONE).unwrap();
        assert!(close(parts.windows_s.unwrap(), ms(1.0)), "{parts:?}");
        // The fit over sixteen such windows, of which the profile kept four: their 1 ms is the
        // error of a four-window answer, the fit's over sixteen is √(4/16) of it; pooled with the
        // jackknife, √((0.3² + 0.5²)/2) ms.
        let mut m = ClockModel::constant(0.0, 0.0, String::new());
        let parts = set_parameters(&mut m, &over(16), &p, 0.0, Cuts::NONE).unwrap();
        assert!(close(parts.windows_s.unwrap(), ms(0.5)), "{parts:?}");
        assert!(close(m.sigma_s, ms(0.17f64.sqrt())), "{m:?}");
    }

    #[test]
    fn an_offsets_sigma_pools_the_jackknife_with_the_windows_at_least_the_formal() {
        let p = profile(|_| 0.1);
        let constant = || ClockModel::constant(0.0, 0.0, String::new());
        let ms = |v: f64| v * 1e-3;
        // The four windows combine to 2 ms / √4 = 1 ms: a jackknife of 0.3 ms is pooled with it,
        // √((0.3² + 1²)/2) ms.
        let mut m = constant();
        set_parameters(
            &mut m,
            &fit(ClockShape::Constant, vec![0.1], vec![ms(0.3)]),
            &p,
            0.0,
            Cuts::NONE,
        );
        assert!(
            close(m.offset_s, 0.1) && close(m.sigma_s, ms(0.545f64.sqrt())),
            "{m:?}"
        );
        // A jackknife wider than the windows is pooled the same way: √((5² + 1²)/2) ms.
        let mut m = constant();
        set_parameters(
            &mut m,
            &fit(ClockShape::Constant, vec![0.1], vec![ms(5.0)]),
            &p,
            0.0,
            Cuts::NONE,
        );
        assert!(close(m.sigma_s, ms(13f64.sqrt())), "{m:?}");
        // The formal σ stays the floor.
        let mut sure = fit(ClockShape::Constant, vec![0.1], vec![ms(2.0)]);
        sure.theta_jackknife_sigma = vec![ms(0.3)];
        sure.theta_formal_sigma = vec![ms(2.0)];
        let mut m = constant();
        let parts = set_parameters(&mut m, &sure, &p, 0.0, Cuts::NONE)
            .expect("a constant's σ has its parts");
        assert!(close(m.sigma_s, ms(2.0)), "{m:?}");
        // The report's `sigma_parts` say so.
        assert_eq!(parts.combined, SigmaCombination::Pooled);
        assert!(close(parts.jackknife_s, ms(0.3)) && close(parts.formal_s, ms(2.0)));
        assert!(close(parts.windows_s.unwrap(), ms(1.0)) && parts.hidden_drift_s == 0.0);
        // It is the jackknife that is pooled, not the fit's σ already raised to the formal one:
        // jackknife 0.3 ms, formal 0.5 ms, windows 1 ms give √((0.3² + 1²)/2) ms.
        let mut raised = fit(ClockShape::Constant, vec![0.1], vec![ms(0.5)]);
        raised.theta_jackknife_sigma = vec![ms(0.3)];
        raised.theta_formal_sigma = vec![ms(0.5)];
        let mut m = constant();
        set_parameters(&mut m, &raised, &p, 0.0, Cuts::NONE);
        assert!(close(m.sigma_s, ms(0.545f64.sqrt())), "{m:?}");
        // The mean over tilings removes the cuts' part in quadrature (√(0.545 − 0.2²) ms), never
        // below the formal σ (0.6 ms, with 0.45 ms removed).
        let cuts = |removed_s: f64| Cuts {
            removed_s,
            tilings: 4,
        };
        let mut m = constant();
        let parts = set_parameters(&mut m, &raised, &p, 0.0, cuts(ms(0.2))).unwrap();
        assert!(
            close(m.sigma_s, ms(0.505f64.sqrt())) && close(parts.cuts_s, ms(0.2)),
            "{m:?}"
        );
        let mut m = constant();
        let mut floored = raised.clone();
        floored.theta_formal_sigma = vec![ms(0.6)];
        set_parameters(&mut m, &floored, &p, 0.0, cuts(ms(0.45)));
        assert!(close(m.sigma_s, ms(0.6)), "{m:?}");
        // A spread of the tilings as large as σ itself is not removed: 0.7 ms of 0.74 ms.
        let mut m = constant();
        let parts = set_parameters(&mut m, &raised, &p, 0.0, cuts(ms(0.7))).unwrap();
        assert!(
            close(m.sigma_s, ms(0.545f64.sqrt())) && parts.cuts_s == 0.0,
            "{m:?}"
        );
        // A jackknife that saw no spread is no estimate: the larger of the fit's σ and the windows'.
        let mut flat = fit(ClockShape::Constant, vec![0.1], vec![ms(0.5)]);
        flat.theta_jackknife_sigma = vec![0.0];
        let mut m = constant();
        let parts = set_parameters(&mut m, &flat, &p, 0.0, Cuts::NONE).unwrap();
        assert!(close(m.sigma_s, ms(1.0)) && parts.combined == SigmaCombination::Larger);
        // Windows scattering ±4 ms about the offset with σ 2 ms: theirs grows by the Birge ratio
        // √(χ²/dof) = √(4·4/3) before the pooling.
        let scattered = profile(|t| {
            if t < 20.0 || (40.0..60.0).contains(&t) {
                0.104
            } else {
                0.096
            }
        });
        let mut m = constant();
        set_parameters(
            &mut m,
            &fit(ClockShape::Constant, vec![0.1], vec![ms(0.3)]),
            &scattered,
            0.0,
            Cuts::NONE,
        );
        let windows_s = ms(1.0) * (16.0f64 / 3.0).sqrt();
        let expected = ((ms(0.3).powi(2) + windows_s * windows_s) / 2.0).sqrt();
        assert!(close(m.sigma_s, expected), "{m:?}");
    }

    #[test]
    fn the_windows_part_carries_the_share_of_sigma_the_fitted_lever_adds() {
        let p = profile(|_| 0.1);
        let ms = |v: f64| v * 1e-3;
        // A fit whose formal σ of 2 ms is four times the variance it would have with the lever
        // held: the lever's freedom adds 2·√(1 − 1/4) = √3 ms, which the windows (1 ms, lever held)
        // cannot see. Pooled with the jackknife's 3 ms: √((3² + 1² + 3)/2) = √6.5 ms.
        let mut lever_free = fit(ClockShape::Constant, vec![0.1], vec![ms(3.0)]);
        lever_free.theta_formal_sigma = vec![ms(2.0)];
        lever_free.variance_inflation = vec![4.0];
        assert!(close(lever_free.lever_share_s(0), ms(3f64.sqrt())));
        let mut m = ClockModel::constant(0.0, 0.0, String::new());
        let parts = set_parameters(&mut m, &lever_free, &p, 0.0, Cuts::NONE).unwrap();
        assert!(close(m.sigma_s, ms(6.5f64.sqrt())), "{m:?}");
        assert!(close(parts.lever_s, ms(3f64.sqrt())));
        assert!(close(parts.windows_s.unwrap(), ms(1.0)));
        // Without a lever (inflation 1) nothing is added: √((3² + 1²)/2) ms.
        lever_free.variance_inflation = vec![1.0];
        let mut m = ClockModel::constant(0.0, 0.0, String::new());
        let parts = set_parameters(&mut m, &lever_free, &p, 0.0, Cuts::NONE).unwrap();
        assert!(
            close(m.sigma_s, ms(5f64.sqrt())) && parts.lever_s == 0.0,
            "{m:?}"
        );
    }

    #[test]
    fn a_segment_over_fewer_than_three_windows_keeps_the_larger() {
        // Two segments, 0–60 s (windows at 10, 30, 50 s) and 60–80 s (the window at 70 s).
        let p = profile(|_| 0.1);
        let segment = |t_start: f64, t_end: f64| ClockSegment {
            t_start,
            t_end,
            offset_s: 0.0,
            sigma_s: 0.0,
        };
        let mut m = ClockModel {
            model: OffsetModel::Piecewise,
            segments: vec![segment(0.0, 60.0), segment(60.0, 80.0)],
            ..ClockModel::constant(0.0, 0.0, String::new())
        };
        let shape = ClockShape::Piecewise {
            changes: vec![60.0],
        };
        let parts = set_parameters(
            &mut m,
            &fit(shape, vec![0.1, 0.2], vec![3e-4, 3e-4]),
            &p,
            0.0,
            Cuts::NONE,
        )
        .expect("the headline segment's parts");
        // Three windows of 2 ms: 2/√3 ms, pooled with the jackknife's 0.3 ms.
        let three_s = 0.002 / 3f64.sqrt();
        let pooled_s = ((3e-4f64.powi(2) + three_s * three_s) / 2.0).sqrt();
        assert!(close(m.segments[0].sigma_s, pooled_s), "{m:?}");
        assert_eq!(parts.combined, SigmaCombination::Pooled);
        assert!(
            close(m.sigma_s, pooled_s),
            "the longest segment is the headline"
        );
        // One window: its 2 ms, the larger.
        assert!(close(m.segments[1].sigma_s, 0.002), "{m:?}");
    }

    #[test]
    fn a_drift_below_the_resolution_widens_the_constant_only_beyond_twice_its_sigma() {
        // Four windows at 10–70 s: their times spread by √500 s about their mean (equal σ).
        let p = profile(|_| 0.1);
        let spread_s = 500f64.sqrt();
        let constant = |d: f64| ClockModel {
            drift_ppm: Some(d),
            drift_sigma_ppm: Some(10.0),
            ..ClockModel::constant(0.0, 0.0, String::new())
        };
        let fitted = fit(ClockShape::Constant, vec![0.1], vec![0.005]);
        // The jackknife's 5 ms pooled with the windows' 1 ms.
        let pooled_s = 13f64.sqrt() * 1e-3;
        // 15 ppm measured with σ 10 ppm: what a constant clock shows by chance; σ stays the pooled.
        let mut m = constant(15.0);
        set_parameters(&mut m, &fitted, &p, 0.0, Cuts::NONE);
        assert!(close(m.sigma_s, pooled_s), "{m:?}");
        // 30 ppm, 3σ: the part beyond its noise, √(30² − 10²) ppm, over the windows' spread.
        let mut m = constant(-30.0);
        set_parameters(&mut m, &fitted, &p, 0.0, Cuts::NONE);
        let hidden_s = 800f64.sqrt() * 1e-6 * spread_s;
        assert!(
            close(m.sigma_s, (pooled_s.powi(2) + hidden_s * hidden_s).sqrt()),
            "{m:?}"
        );
    }

    #[test]
    fn a_line_keeps_the_drifts_floor_and_states_it_in_ppm() {
        let p = profile(|t| 0.1 - 50e-6 * (t - 40.0));
        let mut m = ClockModel {
            model: OffsetModel::Linear,
            t_mid: 40.0,
            drift_ppm: Some(50.0),
            drift_sigma_ppm: Some(3.0),
            ..ClockModel::constant(0.1, 0.0, String::new())
        };
        let shape = ClockShape::Linear { t_mid: 40.0 };
        // θ₁ = −48·10⁻⁶ s/s is a clock running 48 ppm fast; its σ of 1 ppm is raised to the 3 ppm
        // `choose_model` left on the model, and the offset's 0.2 ms to the line's at t_mid (1 ms).
        set_parameters(
            &mut m,
            &fit(shape.clone(), vec![0.1, -48e-6], vec![2e-4, 1e-6]),
            &p,
            0.0,
            Cuts::NONE,
        );
        assert!(close(m.drift_ppm.unwrap(), 48.0));
        assert!(close(m.drift_sigma_ppm.unwrap(), 3.0));
        assert!(close(m.sigma_s, 0.001), "{m:?}");
        // A wider final fit stands.
        m.drift_sigma_ppm = Some(3.0);
        set_parameters(
            &mut m,
            &fit(shape, vec![0.1, -48e-6], vec![0.004, 5e-6]),
            &p,
            0.0,
            Cuts::NONE,
        );
        assert!(close(m.drift_sigma_ppm.unwrap(), 5.0) && close(m.sigma_s, 0.004));
    }

    #[test]
    fn the_lead_search_questions_a_constant_and_a_step_or_a_drift_of_the_windows_own_not_a_forced_model(
    ) {
        assert!(lead_searched(OffsetModel::Constant, None));
        assert!(lead_searched(OffsetModel::Piecewise, None));
        assert!(lead_searched(
            OffsetModel::Constant,
            Some(OffsetModel::Constant)
        ));
        assert!(!lead_searched(
            OffsetModel::Piecewise,
            Some(OffsetModel::Piecewise)
        ));
        assert!(lead_searched(OffsetModel::Linear, None));
        assert!(!lead_searched(
            OffsetModel::Linear,
            Some(OffsetModel::Linear)
        ));
    }

    #[test]
    fn a_lead_fit_needing_a_forward_lever_beyond_the_searchs_is_not_a_candidate() {
        let with_lever = |x: f64, sigma_x: Option<f64>| PoseFit {
            lever_m: Vector3::new(x, 0.3, -0.4),
            lever_sigma_m: sigma_x.map(|s| Vector3::new(s, 0.04, 0.4)),
            ..fit(ClockShape::Constant, vec![3.76], vec![0.04])
        };
        // A walking robot's fit 3.4 s off traded Δt for a forward lever of 0.86 ± 0.07 m.
        assert!(!within_lead_lever(&with_lever(-0.86, Some(0.07))));
        assert!(within_lead_lever(&with_lever(0.39, Some(0.01))));
        // Beyond the bound, but not by two of its σ: the data do not say it is.
        assert!(within_lead_lever(&with_lever(0.6, Some(0.1))));
        // Only the forward lever trades with Δt (the lateral and vertical ones do not count).
        assert!(within_lead_lever(&PoseFit {
            lever_m: Vector3::new(0.1, 0.9, 0.9),
            ..with_lever(0.1, Some(0.01))
        }));
        // Without a fitted lever's σ nothing rules the fit out.
        assert!(within_lead_lever(&with_lever(-0.86, None)));
    }

    #[test]
    fn a_long_lever_fit_left_out_is_told_where_it_fits_the_windows_better() {
        // Residuals of 20 windows: `level` each, ± `wobble` alternately.
        let shifted = |level: f64, wobble: f64| -> Vec<Option<f64>> {
            (0..20)
                .map(|k| Some(level + if k % 2 == 0 { wobble } else { -wobble }))
                .collect()
        };
        let long = |theta: f64, forward_m: f64| PoseFit {
            lever_m: Vector3::new(forward_m, 0.0, 0.0),
            lever_sigma_m: Some(Vector3::new(0.01, 0.01, 0.05)),
            ..fit(ClockShape::Constant, vec![theta], vec![1e-3])
        };
        let lead = |beyond: Vec<(PoseFit, Vec<Option<f64>>)>| Lead {
            windows: Vec::new(),
            fits: Vec::new(),
            beyond: beyond
                .into_iter()
                .map(|(fit, residuals)| LeadFit {
                    fit,
                    residuals,
                    from: None,
                })
                .collect(),
        };
        let reported = shifted(1.0, 0.01);
        // Worse than the reported fit in every window: nothing to tell.
        assert_eq!(
            lead(vec![(long(3.7, -0.86), shifted(1.2, 0.01))]).beyond_against(&reported),
            None
        );
        // Better: the best of those that are.
        let told = lead(vec![
            (long(3.7, -0.86), shifted(1.2, 0.01)),
            (long(-0.22, 0.71), shifted(0.9, 0.01)),
            (long(0.9, 0.66), shifted(0.99, 0.02)),
        ])
        .beyond_against(&reported);
        assert_eq!(
            told,
            Some(BeyondLever {
                offset_s: -0.22,
                forward_m: 0.71,
                forward_sigma_m: 0.01
            })
        );
        assert!(lead(Vec::new()).beyond_against(&reported).is_none());
    }

    #[test]
    fn fits_along_the_valley_the_windows_cannot_tell_apart_widen_sigma() {
        let at = |theta: f64| fit(ClockShape::Constant, vec![theta], vec![1e-3]);
        // Twenty windows' residuals per point (mm²) of one fit, a wobble of ±0.1 about 1.
        let base: Vec<Option<f64>> = (0..20)
            .map(|i| Some(1.0 + 0.1 * (i as f64 * 1.7).sin()))
            .collect();
        let shifted = |d: f64, wobble: f64| -> Vec<Option<f64>> {
            base.iter()
                .enumerate()
                .map(|(i, r)| r.map(|r| r + d + wobble * (i as f64 * 2.3).cos()))
                .collect()
        };
        // As good within the windows' scatter: undecided; worse in every window: decided.
        assert!(paired_t(&shifted(0.005, 0.1), &base).abs() < LEAD_SIGNIFICANCE_T);
        assert!(paired_t(&shifted(0.2, 0.01), &base) > 10.0);
        // The same excess in every window is decided, identical residuals are not, and a residual
        // that is not finite decides nothing below a bound.
        assert!(paired_t(&shifted(0.2, 0.0), &base) > 1e6);
        assert_eq!(paired_t(&base, &base), 0.0);
        let mut broken = base.clone();
        broken[3] = Some(f64::NAN);
        assert!(paired_t(&broken, &base).is_nan());
        // The far fit is the best on the windows every fit has, unless it is in the near basin
        // (the near fit: `from` none) and not better than the near fit beyond the paired t.
        let minimum = |offset_s: f64| pose_fit::ScanMinimum {
            offset_s,
            cost_m2: 1.0,
            lever_m: Vector3::zeros(),
        };
        let lead_of = |fits: Vec<(PoseFit, Vec<Option<f64>>, bool)>| Lead {
            windows: vec![
                pose_fit::Window {
                    range: 0..0,
                    t_start: 0.0,
                    t_end: 1.0
                };
                20
            ],
            fits: fits
                .into_iter()
                .map(|(fit, residuals, near)| LeadFit {
                    from: (!near).then(|| minimum(fit.theta[0])),
                    fit,
                    residuals,
                })
                .collect(),
            beyond: Vec::new(),
        };
        let lead = lead_of(vec![
            (at(0.43), shifted(0.005, 0.1), false),
            (at(0.9), shifted(0.2, 0.01), false),
            (at(0.05), shifted(-0.001, 0.1), true),
        ]);
        assert_eq!(lead.far(Some(&at(0.5))).map(|f| f.theta[0]), Some(0.05));
        assert!(lead.far(Some(&at(0.05))).is_none());
        // In the near fit's basin: a fit the referee finds better in every window replaces it,
        // one as good within the windows' scatter does not.
        let in_basin = |residuals: Vec<Option<f64>>| {
            lead_of(vec![
                (at(0.1), shifted(0.02, 0.001), true),
                (at(0.15), residuals, false),
            ])
            .far(Some(&at(0.1)))
            .map(|f| f.theta[0])
        };
        assert_eq!(in_basin(base.clone()), Some(0.15));
        assert_eq!(in_basin(shifted(0.019, 0.1)), None);
        // The referee's windows: 80 s, fewer on a short mission, never shorter than the fit's.
        assert_eq!(referee_length_s(20.0, 900.0), REFEREE_WINDOW_S);
        assert_eq!(referee_length_s(20.0, 300.0), 50.0);
        assert_eq!(referee_length_s(20.0, 90.0), 20.0);
        // The valley reaches to the farthest candidate as good, not to one in the basin or one
        // worse in every window.
        let reach = |c: Vec<(f64, Vec<Option<f64>>)>| undecided_reach_s(0.1, &base, c);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(
            reach(vec![
                (0.15, shifted(0.0, 0.1)),
                (0.5, shifted(0.005, 0.1)),
                (0.9, shifted(0.2, 0.01)),
            ]),
            0.2
        ));
        assert_eq!(reach(vec![(0.9, shifted(0.2, 0.01))]), 0.0);
        assert!(close(reach(vec![(-0.7, shifted(-0.01, 0.1))]), 0.4));
        // A fit that climbed from its minimum (0.5 s) to a worse residual (0.9 s): the minimum
        // stands for it where it fits better and lies outside the basin; else the fit does.
        let climbed = |from_s: f64| Lead {
            windows: Vec::new(),
            fits: vec![LeadFit {
                fit: at(0.9),
                residuals: shifted(0.2, 0.01),
                from: Some(pose_fit::ScanMinimum {
                    offset_s: from_s,
                    cost_m2: 1.0,
                    lever_m: Vector3::zeros(),
                }),
            }],
            beyond: Vec::new(),
        };
        let as_good = |_: &pose_fit::ScanMinimum| shifted(0.005, 0.1);
        let worse = |_: &pose_fit::ScanMinimum| shifted(0.3, 0.01);
        let lead = climbed(0.5);
        assert!(close(
            undecided_reach_s(0.1, &base, lead.candidates(0.1, as_good)),
            0.2
        ));
        assert_eq!(
            undecided_reach_s(0.1, &base, lead.candidates(0.1, worse)),
            0.0
        );
        let in_basin = climbed(0.15);
        let c: Vec<_> = in_basin.candidates(0.1, as_good).collect();
        assert_eq!(c[0].0, 0.9);
        // valley_s enters the constant's σ in quadrature and its parts.
        let p = profile(|_| 0.1);
        let mut m = ClockModel::constant(0.0, 0.0, String::new());
        let parts = set_parameters(
            &mut m,
            &fit(ClockShape::Constant, vec![0.1], vec![2e-3]),
            &p,
            0.215,
            Cuts::NONE,
        )
        .unwrap();
        assert!(m.sigma_s > 0.215 && m.sigma_s < 0.2151, "{m:?}");
        assert_eq!(parts.valley_s, 0.215);
        assert_eq!(parts.basins_s, 0.0);
    }

    #[test]
    fn windows_in_two_basins_widen_the_constants_sigma_by_half_their_spread_and_say_so() {
        let p = profile(|_| 0.1);
        let mut m = ClockModel {
            alternation_s: 0.5,
            ..ClockModel::constant(0.0, 0.0, String::new())
        };
        let parts = set_parameters(
            &mut m,
            &fit(ClockShape::Constant, vec![0.1], vec![2e-3]),
            &p,
            0.0,
            Cuts::NONE,
        )
        .unwrap();
        assert!(m.sigma_s > 0.25 && m.sigma_s < 0.2501, "{m:?}");
        assert_eq!((parts.basins_s, parts.valley_s), (0.25, 0.0));
    }
}
