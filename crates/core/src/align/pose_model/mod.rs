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
//!
//! **Where each step lives.** `model.rs`: [`pose_clock_model`], step 1 and the order of the rest;
//! `mission.rs`: steps 2 to 4 (the profile, the model chosen from it, its fit, a drift or a step
//! the fit does not resolve taken back); `profile.rs`: the profile's windows kept and calibrated;
//! `sigma.rs`: the σ of step 4 and what it is made of ([`SigmaParts`]); `tilings.rs`: step 5;
//! `lead.rs`: the lead search; `tests.rs`: their unit tests. The constants and the result's types
//! are here.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::align::clock_model::{ClockModel, OffsetModel};
use crate::align::offset_profile::OffsetProfile;
use crate::align::pose_fit::{self, PoseFit};
use crate::align::signals::SignalView;

mod lead;
mod mission;
mod model;
mod profile;
mod sigma;
#[cfg(test)]
mod tests;
mod tilings;

pub use model::pose_clock_model;
pub use profile::{MAX_SIGMA_RATIO, MIN_WINDOW_QUALITY, NEIGHBOUR_OUTLIER};
pub use sigma::{steps_resolved, windows_share};
pub use tilings::Cuts;

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
