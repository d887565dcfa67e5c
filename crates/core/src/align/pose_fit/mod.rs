//! The pose fit: the clock offset from the positions themselves, with the estimate's lever arm
//! fitted alongside, and an error bar taken from the spread of the mission's own windows.
//!
//! **Why.** Speed and curvature compare one number per instant. A walking robot's speed hardly
//! changes, and a sensor mounted ahead of the reference point sees every curve early, so those
//! signals leave tens of milliseconds on legged missions. The positions carry more: where the robot
//! is, not only how fast it goes or how sharply it turns. When the estimate has an orientation R̂ (its
//! body's attitude), the reference point it corresponds to is the estimate's position less its lever,
//! ê − R̂·D, whatever the robot does — turning in place, rolling with its gait, tilting on a slope.
//!
//! **Model.** The reference clock's time t of the reference sample p_ref(t) meets the estimate at
//! t − Δt(t) of its own clock. The mission is cut into windows of [`WINDOW_S`] seconds (at least
//! [`MIN_WINDOW_SAMPLES`] reference samples each); in window k
//!
//! p_ref(t) ≈ s_k·R_k·(ê(t − Δt(t)) − R̂(t − Δt(t))·D) + T_k,
//!
//! with the window's own similarity (rotation R_k ∈ SO(3), scale s_k, translation T_k: the estimate's
//! frame, its drift and its scale error, which odometry accumulates slowly) and, shared by every
//! window, the lever D (the estimate's sensor relative to the reference's point, in the estimate's
//! body frame) and the clock Δt(t) = Σ θ_m·φ_m(t) (constant, linear or piecewise, [`ClockShape`]). ê
//! and R̂ are interpolated by the cubic through the four samples around each time, which follows a
//! gait's sway sampled at 10 Hz where a straight line would shift its phase (`sampler.rs`; the line
//! beside a jump or a gap; gaps longer than the largest gap are not bridged). What lies near a slow
//! estimate's Nyquist frequency the cubic does not follow: at estimate rates up to
//! [`AVERAGE_BELOW_HZ`], against a reference at least as dense, the reference's samples and their
//! predictions are averaged over two of the estimate's periods before they are compared, which
//! takes that band out of both sides alike; against a sparser reference, which nothing can average,
//! the estimate is interpolated through twelve samples instead of four, which follow that band
//! much further in phase (`sampler.rs`).
//! Where the estimate jumps ([`crate::align::jumps`]: a localiser correcting itself), each side of
//! the jump within a window has its own similarity and drift (the sides share only θ and D), and
//! the points whose interpolation would reach across the jump are left out. A window's scale is
//! held to the mission's by a prior worth [`PoseFitParams::scale_prior_m`] of spread per sample
//! ([`SCALE_PRIOR_M`] for a robot that walks, [`VEHICLE_SCALE_PRIOR_M`] for a vehicle, whose free
//! window scale would absorb a speed changing steadily within the window and leave Δt to the lever
//! on straight stretches: `align::pose_model::scale_prior_m`), so a window that stands or turns in
//! place (whose positions barely spread) keeps the mission's scale and still pins D: its reference
//! stands still while ê sweeps the lever's arc. The similarity of each window has a closed form
//! (Umeyama: an SVD of the 3×3 cross-covariance); θ and D are found by Gauss–Newton on the normal
//! equations reduced by each window's similarity (the Schur complement of the full system), from
//! the offset `auto` found.
//!
//! **What it cannot see.** At constant speed a sensor D_x ahead is, to first order, the same sensor
//! D_x/v later: Δt and a forward lever are then inseparable. The fit says so: [`PoseFit::inseparable`]
//! compares Δt's error with the lever fitted and with it held (the variance inflation); the lever and
//! Δt are told apart by speed changes, stops, turns in place and the second-order chord-versus-arc
//! difference of curves. Nor does it follow an estimate whose heading wanders at periods near a
//! window's length (10–40 s): the window's rotation and drift rate take up what is slower, and what
//! is left bends the estimate's path within the window, which a vehicle's Δt follows (on the second
//! simulator, +36.8 ms where the walk's content slower than 40 s alone gives +5.5 ms). The windows
//! then disagree and the jackknife widens σ; a bend, knots or a looser rate in the window's
//! nuisance did not take it out (docs/evidence.md, "The heading walk by period").
//!
//! **Error bar: the spread of independent windows.** The windows do not overlap, and the noise of one
//! (reference noise, the estimate's drift and jitter, the gait, a model error) is nearly independent
//! of the next's. The standard error of every fitted parameter is the delete-one-window jackknife of
//! the whole fit, lever included: each window left out in turn (one Newton step of the reduced normal
//! equations from the full solution, with the Jacobian S of the estimating equations measured at the
//! solution: their change over a shift of the clock, see `SharedFit::jacobians`, a shift of at
//! least [`PROBE_JITTERS`] times the estimate's stamp jitter; where that step would move the clock
//! beyond half the instrument's half-step, the fit without the window is made in full, see
//! `SharedFit::jackknife`), variance
//! (K−1)/K·Σ(θ₋ₖ − θ̄)². It assumes nothing about the
//! residual — not whiteness, not its size — only that windows err independently; it is honest for the
//! same reason a bootstrap is, and it includes the lever's uncertainty, which moves every window
//! alike. What no spread can show is an error common to every window of the mission (a latency the
//! recorder adds to every stamp is, by definition, part of the offset). With the 8–30 windows of a
//! mission the jackknife's variance is itself uncertain (by 25–50 %), and where it falls short the
//! error is several of its σ; so each parameter's σ is at least its formal one, S⁻¹·σ̂²H·S⁻ᵀ with σ̂²
//! the residual per degree of freedom — what the residuals would give were they white, the least the
//! noise allows (on white noise it is the spread of the answers: a test draws the noise 40 times). On
//! the validation's 1399 constant clocks this halved the errors beyond 3σ (39 → 20) and moved no Δt
//! (docs/evidence.md).
//!
//! Each window's own Δt (the offset profile, [`profile`](fn@profile)) comes from the same fit with D held and one
//! θ per window, refined from the clock's value at the window and, where the mission's constant is
//! uncertain beyond 2 ms ([`WindowSearch::Every`], see `align::pose_model`), searched within ±3 s
//! for a deeper root (`WindowSolver::deeper`): a window started on the wrong side of a clock step,
//! or in a first look without a lever, can settle at a root of its own a few hundred milliseconds
//! off, as sharp as the right one.
//!
//! A window's σ is its least-squares error s_k (`formal_sigma`: σ̂_k·√H_k/(c·J_k), the
//! instrumental-variable form, σ̂_k² its residual per degree of freedom) calibrated by the windows'
//! scatter about the line through their neighbours:
//! e_k = Δt_k − (interpolation of Δt_{k−1} and Δt_{k+1} at t_k) is free of any constant and any
//! linear drift. Two things make the windows scatter beyond s_k, and one factor cannot model both:
//! residuals correlated within a window (every s_k too small by the same factor f), and errors the
//! residuals do not show at all — a gait aliased by the estimate's rate, receipt-time jitter along
//! the track — which are about the same size in every window however sharp its geometry, and
//! independent from one window to the next (an excess τ; an error common to neighbours cancels in
//! e_k and is left to the floors of [`crate::align::pose_model`]). So σ_k² = (f·s_k)² + τ² (a
//! random-effects model, as in a meta-analysis of studies each with an extra spread of one size),
//! f ≥ 1 and τ ≥ 0 fitted by weighted least squares of e_k² on its expectation, the terms beyond 4σ
//! set aside ([`CLIP_CHI2`]: a step, which spoils two, does not decide it); see
//! [`scatter_calibration`]. With f alone the sharpest windows
//! were too sure: on the validation's windows sharper than their mission's median, 2σ covered 87 %
//! (the others 95 %); with τ, 92 % and 94 % (docs/evidence.md). This is what makes a drift or a step,
//! judged against the windows' σ, a claim the data support (see [`crate::align::clock_model`]).

use nalgebra::{DMatrix, UnitQuaternion, Vector3};

mod profile;
mod sampler;
mod shared;
#[cfg(test)]
mod tests;
mod window;

pub use profile::{
    profile, scatter_calibration, scatter_factor, WindowOffset, WindowScatter, WindowSearch,
};
pub use shared::{
    coarse_minima, coarse_start, fit, residuals_at, ScanMinimum, LEAD_MAX_ITERATIONS,
    MAX_ITERATIONS,
};
pub use window::{locate_change, tiling, windows, Window};

/// Length of a window, seconds (a window holds at least [`MIN_WINDOW_SAMPLES`] reference samples:
/// longer at low reference rates).
pub const WINDOW_S: f64 = 20.0;
/// The Newton Jacobian's differences reach this many of the estimate's periods beyond the
/// instrument's (mostly other samples than its, so nearly free of the bias its own noise gives
/// Σ v·v; see `window.rs`).
pub const JACOBIAN_PERIODS: f64 = 2.0;
/// The Jacobian's reach where the fit cannot be made with [`JACOBIAN_PERIODS`]: over ±(h + 2
/// periods) a 20 Hz estimate's differences answer a gait's 3.3–6.7 Hz bob and pitch with the
/// wrong sign, the Jacobian turns negative in the windows, and Newton steps away from the truth
/// (one period answers them with the right sign; everywhere it moved other missions between
/// basins: docs/evidence.md, "The Jacobian's stencil, narrower: tried, reverted").
pub const NARROW_JACOBIAN_PERIODS: f64 = 1.0;
/// The default of [`PoseFitParams::average_below_hz`], Hz: an estimate published at this rate or
/// below, against a reference sampled at least as densely, is compared on the reference's samples
/// averaged over two of the estimate's periods.
///
/// **Why.** A walking robot's body moves at its step frequency and at twice it (bob, pitch, the
/// surge of its speed): up to 5–6 Hz. An estimate at 10 Hz has its Nyquist frequency there, and no
/// interpolation of its samples follows motion so near it (the cubic of `sampler.rs` is within a
/// few per cent at 0.2 of the rate, not at 0.45; a quintic moved the answers by 1–2 ms, not the
/// tens of milliseconds they were off). The reference, at 10–20 Hz, does see that motion. The
/// misfit is then a signal at the gait's harmonic, alike in every window (commensurate rates put
/// every reference sample at the same fraction of the estimate's period), which the fit takes up
/// in a vertical lever that trades with Δt, and which no spread of windows shows: on a walking
/// robot of the second simulator at 10/10 Hz, Δt 31 ms off under σ 3 ms and the lever's height
/// 12 cm off; with the true lever given, 2 ms.
///
/// **How.** The model p_ref ≈ s·R·(ê − R̂·D) + T is linear in the points once the window's
/// similarity is fixed, so the mean of k consecutive reference samples meets the mean of their k
/// predictions under the same similarity, clock and lever: averaging both sides alike changes no
/// parameter, only the band the fit weighs. Two samples one of the estimate's periods apart
/// average with gain |cos(π·f/f_e)| at frequency f (more samples over the same span have their
/// zero at the same place): nothing at the estimate's Nyquist, 0.31 at 0.4·f_e, 0.81 at 0.2·f_e (a
/// 2 Hz sway at 10 Hz). The band the estimate cannot represent leaves both sides; the gait's
/// fundamental stays. Where the reference is sparser than the estimate it already aliases the gait
/// and nothing is averaged; at these rates the estimate is then interpolated through twelve samples
/// (`sampler::LONG_TAPS`). At 20 Hz and above the gait lies where the cubic follows it and the
/// mean only costs resolution (walking robots at 20/20 Hz: median error 0.46 → 0.63 ms), so it is
/// not taken there. The instruments of neighbours in a block share a few of the estimate's samples
/// with their points (see `window.rs`), a bias of order σ_e²/(2h·v²) with σ_e the estimate's noise
/// per sample: 0.1 ms at 2 mm and 0.4 m/s. Measured: docs/evidence.md, "The reference averaged
/// over two of a slow estimate's periods".
pub const AVERAGE_BELOW_HZ: f64 = 15.0;
/// The fewest reference samples in a window.
pub const MIN_WINDOW_SAMPLES: usize = 20;
/// A window's scale follows its own data only as far as its positions spread more than this per
/// sample, metres (the prior's weight is n·P²): P for a robot that walks, stands or turns in place
/// (its windows spread a few metres; see `align::pose_model::scale_prior_m`).
pub const SCALE_PRIOR_M: f64 = 1.0;
/// P for a vehicle, metres (see `align::pose_model::scale_prior_m`): a window spreading less than
/// this per sample (a 20 s window at up to about 5 m/s) keeps mostly the mission's scale.
pub const VEHICLE_SCALE_PRIOR_M: f64 = 30.0;
/// A window's heading drift rate follows its own data only as far as they determine it better than
/// this prior: σ 10⁻³ rad/s (0.06°/s) against 2 cm of noise per sample (weight n·(0.02/10⁻³)² m²s²).
pub const DRIFT_PRIOR_M2S2: f64 = 400.0;
/// Prior σ of each lever component, metres (keeps a lever the data cannot see at 0).
pub const LEVER_PRIOR_M: f64 = 1.0;
/// A window's squared scatter beyond this many times its current expectation is set aside when the
/// profile's windows are calibrated (4σ).
pub const CLIP_CHI2: f64 = 16.0;
/// The variance inflation of Δt by the lever above which the two are called inseparable.
pub const INSEPARABLE_VIF: f64 = 25.0;
/// The error bar measures the equations' slope in Δt over a shift of at least this many times the
/// estimate's stamp jitter ([`crate::stats::stamp_jitter_s`]). Stamps taken at receipt stray by
/// milliseconds; a shift of Δt moves the reference's points across samples whose stamps are that
/// far off, and over a shift of a few jitters the slope measured is the jitter's as much as the
/// path's. On a vehicle, whose Δt and forward lever are nearly one direction of the equations
/// (told apart by slow speed changes only), that noise decides how far they are told apart: a
/// mission with a 50 Hz estimate whose stamps jitter by 4.6 ms reported σ 309 ms over ±25 ms,
/// 33 ms over ±69 ms (19 ms with its stamps at their mean latency). Evenly stamped streams (jitter
/// 0) keep half the instrument's half-step, which a gait's slope needs. On the second simulator's
/// 128 receipt-stamp missions 2σ covered 92 % instead of 89 % (walking robots 89 % instead of
/// 82 %); the project's 200 kept their errors (one moved by 0.07 ms) and 2σ's cover, 94 %
/// (docs/evidence.md, "The slope measured over the stamps' jitter").
pub const PROBE_JITTERS: f64 = 15.0;

/// The estimate's poses: times on its own clock (seconds from the common origin), positions and
/// orientations (body to its frame), and where it jumps ([`crate::align::jumps::jumps`] of `t` and
/// `p`: found once per track, the fits ask many times).
#[derive(Clone, Copy)]
pub struct PoseTrack<'a> {
    pub t: &'a [f64],
    pub p: &'a [Vector3<f64>],
    pub q: &'a [UnitQuaternion<f64>],
    pub jumps: &'a [(f64, f64)],
}

/// The shape of Δt(t) = Σ θ_m·φ_m(t), t on the reference clock.
#[derive(Debug, Clone, PartialEq)]
pub enum ClockShape {
    /// θ₀.
    Constant,
    /// θ₀ + θ₁·(t − t_mid).
    Linear { t_mid: f64 },
    /// θ_m on the m-th stretch between the change times (sorted).
    Piecewise { changes: Vec<f64> },
}

impl ClockShape {
    /// The number of parameters.
    pub fn len(&self) -> usize {
        match self {
            ClockShape::Constant => 1,
            ClockShape::Linear { .. } => 2,
            ClockShape::Piecewise { changes } => changes.len() + 1,
        }
    }

    /// Never empty (a shape has at least one parameter).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The parameters' change that shifts Δt(t) by one second everywhere.
    pub(super) fn uniform_shift(&self) -> Vec<f64> {
        match self {
            ClockShape::Constant => vec![1.0],
            ClockShape::Linear { .. } => vec![1.0, 0.0],
            ClockShape::Piecewise { changes } => vec![1.0; changes.len() + 1],
        }
    }

    /// φ(t) into `out` (length [`Self::len`]).
    fn basis(&self, t: f64, out: &mut [f64]) {
        match self {
            ClockShape::Constant => out[0] = 1.0,
            ClockShape::Linear { t_mid } => {
                out[0] = 1.0;
                out[1] = t - t_mid;
            }
            ClockShape::Piecewise { changes } => {
                out.iter_mut().for_each(|v| *v = 0.0);
                out[changes.partition_point(|&c| c <= t)] = 1.0;
            }
        }
    }

    /// Δt(t) for parameters θ.
    pub fn value(&self, theta: &[f64], t: f64) -> f64 {
        match self {
            ClockShape::Constant => theta[0],
            ClockShape::Linear { t_mid } => theta[0] + theta[1] * (t - t_mid),
            ClockShape::Piecewise { changes } => theta[changes.partition_point(|&c| c <= t)],
        }
    }
}

/// The result of a fit of the shared parameters.
#[derive(Debug, Clone)]
pub struct PoseFit {
    pub shape: ClockShape,
    /// The clock's parameters θ (seconds; a linear slope in s/s).
    pub theta: Vec<f64>,
    /// The lever D, estimate body frame, metres (zero when not fitted).
    pub lever_m: Vector3<f64>,
    /// Standard errors of θ and of D (D's when fitted): the jackknife's, at least the formal ones.
    pub theta_sigma: Vec<f64>,
    /// θ's jackknife standard errors (before the formal floor); `theta_sigma[k]` is the larger of
    /// this and `theta_formal_sigma[k]` (the formal one where the jackknife saw no spread).
    pub theta_jackknife_sigma: Vec<f64>,
    /// θ's formal standard errors (0 where the formal covariance could not be formed).
    pub theta_formal_sigma: Vec<f64>,
    pub lever_sigma_m: Option<Vector3<f64>>,
    /// The covariance of (θ, D): the jackknife's, each variance raised to at least the formal one.
    pub covariance: DMatrix<f64>,
    /// Each clock parameter's error with the lever fitted over its error with the lever held,
    /// squared (from the normal equations; 1 without lever).
    pub variance_inflation: Vec<f64>,
    /// The windows used, and the ones left out as outliers (their residual RMS).
    pub windows: Vec<Window>,
    pub outliers: Vec<Window>,
    /// Residual RMS per used window, metres.
    pub rms_m: Vec<f64>,
    /// The mission's scale (estimate distances over reference distances, ≈ 1 + scale error).
    pub scale: f64,
    /// The scale of the analytic Jacobian's clock columns the profile's windows use: the measured
    /// slope of the estimating equations over the analytic one along a shift of the whole clock
    /// (see `SharedFit::jacobians`; the iteration's secant correction where it cannot be measured).
    pub jacobian_scale: f64,
    pub iterations: usize,
    pub converged: bool,
}

impl PoseFit {
    /// Whether Δt and the lever are too entangled to tell apart (constant speed, no turns in place):
    /// Δt's variance grows by more than [`INSEPARABLE_VIF`] when the lever is fitted.
    pub fn inseparable(&self) -> bool {
        self.variance_inflation[0] > INSEPARABLE_VIF
    }

    /// The part of θₖ's formal σ that the lever's freedom adds, seconds: what a fit with the lever
    /// held cannot see, √(formal² · (1 − 1/inflation)) (0 without a formal σ or a lever; all of
    /// it where the inflation is infinite).
    pub fn lever_share_s(&self, k: usize) -> f64 {
        let kept = 1.0 / self.variance_inflation[k];
        self.theta_formal_sigma[k] * (1.0 - kept).max(0.0).sqrt()
    }
}

/// Settings of a fit.
#[derive(Debug, Clone, Copy)]
pub struct PoseFitParams {
    /// The largest gap of the estimate interpolated across, seconds.
    pub max_gap_s: f64,
    /// The window length (`None`: [`WINDOW_S`], longer at low reference rates).
    pub window_s: Option<f64>,
    /// The windows' scale prior P, metres of spread per sample ([`SCALE_PRIOR_M`] or
    /// [`VEHICLE_SCALE_PRIOR_M`]: `align::pose_model::scale_prior_m` chooses by the reference's
    /// speed).
    pub scale_prior_m: f64,
    /// How many of the estimate's periods wider than the instrument's the Newton Jacobian's
    /// central differences reach ([`JACOBIAN_PERIODS`]; the evaluation tries
    /// [`NARROW_JACOBIAN_PERIODS`] where the fit cannot be made with it).
    pub jacobian_periods: f64,
    /// At estimate rates up to this, against a reference at least as dense, the reference's
    /// samples and their predictions are averaged over two of the estimate's periods
    /// ([`AVERAGE_BELOW_HZ`]; 0 never).
    pub average_below_hz: f64,
    /// Gauss–Newton iterations at most of a fit of the shared parameters ([`MAX_ITERATIONS`];
    /// the lead search's fits from its minima take [`LEAD_MAX_ITERATIONS`]).
    pub max_iterations: usize,
}

impl PoseFitParams {
    /// The settings a mission's fits start from: the estimate's gaps up to `max_gap_s`
    /// interpolated, windows of the default length and the walking robot's scale prior.
    /// `align::pose_model::pose_clock_model` chooses the window and the prior for the mission in
    /// hand (the profile's window length, the reference's speed); a caller fitting directly keeps
    /// these.
    pub fn new(max_gap_s: f64) -> PoseFitParams {
        PoseFitParams {
            max_gap_s,
            window_s: None,
            scale_prior_m: SCALE_PRIOR_M,
            jacobian_periods: JACOBIAN_PERIODS,
            average_below_hz: AVERAGE_BELOW_HZ,
            max_iterations: MAX_ITERATIONS,
        }
    }
}

/// The reference, the estimate's poses and the settings of one mission's fits.
pub struct PoseData<'a> {
    pub ref_t: &'a [f64],
    pub ref_p: &'a [Vector3<f64>],
    pub estimate: PoseTrack<'a>,
    pub params: PoseFitParams,
}

impl<'a> PoseData<'a> {
    /// The windows of this mission.
    pub fn windows(&self) -> Vec<Window> {
        windows(self.ref_t, self.params.window_s)
    }

    /// The windows of this mission with every cut moved later by `phase` of a window ([`tiling`]).
    pub fn tiling(&self, phase: f64) -> Vec<Window> {
        tiling(self.ref_t, self.params.window_s, phase)
    }

    /// The profile's windows: those of [`Self::windows`] (disjoint), or with `step_s` shorter than
    /// their length, windows of the same length every `step_s` seconds (overlapping).
    pub fn profile_windows(&self, step_s: Option<f64>) -> Vec<Window> {
        let disjoint = self.windows();
        let (Some(step), Some(first), Some(last)) = (step_s, disjoint.first(), disjoint.last())
        else {
            return disjoint;
        };
        let len = first.t_end - first.t_start;
        if step >= len {
            return disjoint;
        }
        let (a, b) = (first.t_start, last.t_end);
        let count = ((b - a - len) / step).floor().max(0.0) as usize + 1;
        (0..count)
            .map(|k| {
                let (lo, hi) = (a + k as f64 * step, (a + k as f64 * step + len).min(b));
                Window {
                    range: self.ref_t.partition_point(|&t| t < lo)
                        ..self.ref_t.partition_point(|&t| t < hi),
                    t_start: lo,
                    t_end: hi,
                }
            })
            .collect()
    }
}
