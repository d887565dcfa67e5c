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
//! and R̂ are interpolated linearly between the estimate's samples (gaps longer than the largest gap
//! are not bridged). Where the estimate jumps ([`crate::align::jumps`]: a localiser correcting
//! itself), each side of the jump within a window has its own similarity and drift (the sides share
//! only θ and D), and the points whose interpolation would reach across the jump are left out. A
//! window's scale is held to the mission's by a prior worth [`SCALE_PRIOR_M`] of spread per sample, so a window that stands or turns in place (whose positions barely spread)
//! keeps the mission's scale and still pins D: its reference stands still while ê sweeps the lever's
//! arc. The similarity of each window has a closed form (Umeyama: an SVD of the 3×3 cross-covariance);
//! θ and D are found by Gauss–Newton on the normal equations reduced by each window's similarity
//! (the Schur complement of the full system), from the offset `auto` found.
//!
//! **What it cannot see.** At constant speed a sensor D_x ahead is, to first order, the same sensor
//! D_x/v later: Δt and a forward lever are then inseparable. The fit says so: [`PoseFit::inseparable`]
//! compares Δt's error with the lever fitted and with it held (the variance inflation); the lever and
//! Δt are told apart by speed changes, stops, turns in place and the second-order chord-versus-arc
//! difference of curves.
//!
//! **Error bar: the spread of independent windows.** The windows do not overlap, and the noise of one
//! (reference noise, the estimate's drift and jitter, the gait, a model error) is nearly independent
//! of the next's. The standard error of every fitted parameter is the delete-one-window jackknife of
//! the whole fit, lever included: each window left out in turn (one Newton step of the reduced normal
//! equations from the full solution), variance (K−1)/K·Σ(θ₋ₖ − θ̄)². It assumes nothing about the
//! residual — not whiteness, not its size — only that windows err independently; it is honest for the
//! same reason a bootstrap is, and it includes the lever's uncertainty, which moves every window
//! alike. What no spread can show is an error common to every window of the mission (a latency the
//! recorder adds to every stamp is, by definition, part of the offset). With the 8–30 windows of a
//! mission the jackknife's variance is itself uncertain (by 25–50 %), and where it falls short the
//! error is several of its σ; so each parameter's σ is at least its formal one, J⁻¹·σ̂²H·J⁻ᵀ with σ̂²
//! the residual per degree of freedom — what the residuals would give were they white, the least the
//! noise allows (on white noise it is the spread of the answers: a test draws the noise 40 times). On
//! the validation's 1399 constant clocks this halved the errors beyond 3σ (39 → 20) and moved no Δt
//! (docs/evidence.md).
//!
//! Each window's own Δt (the offset profile, [`profile`]) comes from the same fit with D held and one
//! θ per window, refined from the clock's value at the window and, where the mission's constant is
//! uncertain beyond 2 ms ([`WindowSearch::Every`], see `align::pose_model`), searched within ±3 s
//! for a deeper root (`WindowSolver::deeper`): a window started on the wrong side of a clock step,
//! or in a first look without a lever, can settle at a root of its own a few hundred milliseconds
//! off, as sharp as the right one.
//!
//! A window's σ is its least-squares error σ̂_k/√H_k (σ̂_k² = its residual per degree of freedom)
//! times one factor f for the mission, from the windows' scatter about the line through their
//! neighbours: e_k = Δt_k − (interpolation of Δt_{k−1} and Δt_{k+1} at t_k) is free of any constant
//! and any linear drift, so under honest σ each e_k/σ(e_k) is a unit normal; f² is the mean of those
//! squares with the ones beyond 4σ set aside ([`CLIP_CHI2`]: a step, which spoils two, does not
//! decide it). This is what makes a drift or a step, judged against the windows' σ, a claim the
//! data support (see [`crate::align::clock_model`]).

use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, UnitQuaternion, Vector3};
use rayon::prelude::*;

/// Length of a window, seconds (a window holds at least [`MIN_WINDOW_SAMPLES`] reference samples:
/// longer at low reference rates).
pub const WINDOW_S: f64 = 20.0;
/// The fewest reference samples in a window.
pub const MIN_WINDOW_SAMPLES: usize = 20;
/// A window's scale follows its own data only as far as its positions spread more than this per
/// sample, metres (the prior's weight is n·SCALE_PRIOR_M²).
pub const SCALE_PRIOR_M: f64 = 1.0;
/// A window's heading drift rate follows its own data only as far as they determine it better than
/// this prior: σ 10⁻³ rad/s (0.06°/s) against 2 cm of noise per sample (weight n·(0.02/10⁻³)² m²s²).
pub const DRIFT_PRIOR_M2S2: f64 = 400.0;
/// Prior σ of each lever component, metres (keeps a lever the data cannot see at 0).
pub const LEVER_PRIOR_M: f64 = 1.0;
/// A window's squared scatter beyond this many (squared) σ of the current factor is set aside when
/// the profile's scale factor is estimated (4σ).
pub const CLIP_CHI2: f64 = 16.0;
/// E[χ²₁ | χ²₁ ≤ 16]: what the clipped mean of unit normals' squares comes to.
const CLIPPED_MEAN: f64 = 0.9989;
/// The median of χ²₁.
const CHI2_1_MEDIAN: f64 = 0.4549;
/// The half-step h of the instrument's central differences: two of the estimate's periods (the
/// samples it interpolates are not those of the point) and at least 50 ms (a difference over
/// shorter times is mostly the estimate's noise: 3 mm of noise over ±10 ms is 0.2 m/s), at most
/// 0.25 s, seconds.
const STENCIL_MIN_S: f64 = 0.05;
const STENCIL_MAX_S: f64 = 0.25;
/// Gauss–Newton iterations at most. Most fits stop within ten; on a few legged missions Δt and a
/// forward lever trade places for tens of iterations before they settle (20 left 3 of 1200
/// validation missions unconverged, and their signal-search fallback 26–75 ms off with σ of
/// hundreds of ms). The cost is only paid where the fit needs it.
const MAX_ITERATIONS: usize = 60;
/// The largest change of an offset parameter in one iteration, seconds.
const MAX_STEP_S: f64 = 0.1;
/// A window whose residual RMS exceeds this many times the median window's is left out (what the
/// jump finder missed: a jump too small to find, an estimate that goes astray for a while).
const OUTLIER_RMS_FACTOR: f64 = 4.0;
/// How much lower (in χ² of the window's own noise) a profile window's residual must be at the root
/// its search finds than at the root nearest its start for the search's to be taken (5σ).
const SEARCH_CHI2: f64 = 25.0;
/// A window's search compares its residual on every ⌊n/SEARCH_POINTS⌋-th of its n reference
/// samples (this many to twice as many; all of a window of fewer), and the root it finds is then
/// refined on all of them. A stretch between jumps counts [`MIN_SEGMENT_SAMPLES`] of those taken.
const SEARCH_POINTS: usize = 32;
/// The spacing of a window's search over offsets, seconds.
const SEARCH_STEP_S: f64 = 0.05;
/// The variance inflation of Δt by the lever above which the two are called inseparable.
pub const INSEPARABLE_VIF: f64 = 25.0;

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

/// The estimate's position and attitude at one time (linear interpolation).
#[derive(Clone, Copy)]
struct At {
    p: Vector3<f64>,
    r: Matrix3<f64>,
}

/// Linear interpolation of the estimate's poses.
struct Sampler<'a> {
    track: PoseTrack<'a>,
    /// The track's orientations as rotation matrices, converted once (each point of every
    /// iteration interpolates five poses, ten conversions otherwise).
    rotations: Vec<Matrix3<f64>>,
    gap: f64,
}

impl Sampler<'_> {
    /// The pose at `t` (estimate clock); `None` outside the track or across a gap longer than the
    /// largest gap. `hint`: the index found last (rising queries walk from it).
    fn at(&self, t: f64, hint: &mut usize) -> Option<At> {
        let ts = self.track.t;
        let n = ts.len();
        let mut j = (*hint).min(n);
        while j < n && ts[j] < t {
            j += 1;
        }
        while j > 0 && ts[j - 1] >= t {
            j -= 1;
        }
        *hint = j;
        if j == 0 || j >= n {
            return None;
        }
        let (a, b) = (j - 1, j);
        let span = ts[b] - ts[a];
        if span > self.gap || span <= 0.0 {
            return None;
        }
        let f = (t - ts[a]) / span;
        let (ra, rb) = (self.rotations[a], self.rotations[b]);
        Some(At {
            p: self.track.p[a] + (self.track.p[b] - self.track.p[a]) * f,
            r: ra + (rb - ra) * f,
        })
    }

    /// The stretch of the track between jumps that `[t − reach, t + reach]` (estimate clock) lies
    /// in, `None` when a jump falls within it (its interpolation would mix the two frames).
    fn segment(&self, t: f64, reach: f64) -> Option<usize> {
        let jumps = self.track.jumps;
        let k = jumps.partition_point(|&(_, after)| after <= t - reach);
        match jumps.get(k) {
            Some(&(before, _)) if before < t + reach => None,
            _ => Some(k),
        }
    }
}

/// A window: reference samples `range`, its centre time.
#[derive(Debug, Clone)]
pub struct Window {
    pub range: std::ops::Range<usize>,
    pub t_start: f64,
    pub t_end: f64,
}

impl Window {
    /// The window's centre, reference clock.
    pub fn t(&self) -> f64 {
        0.5 * (self.t_start + self.t_end)
    }
}

/// The reduced normal equations of one window (its similarity eliminated), at the current parameters.
#[derive(Debug, Clone)]
struct Terms {
    n: usize,
    rss: f64,
    /// The estimating equations g = Σ v·e over the shared parameters, v the instrument (∂model/∂θ
    /// from central differences over ±h, which interpolate other samples of the estimate than the
    /// point itself: the residual's own noise does not enter them); h = Σ v·v; j = Σ v·w with w the
    /// same derivative over two of the estimate's periods more (samples independent of v's again):
    /// the Newton Jacobian of g, free of the bias Σ v·v takes from v's noise. The window's similarity and drift eliminated (Schur
    /// complement).
    h: DMatrix<f64>,
    j: DMatrix<f64>,
    g: DVector<f64>,
    /// Σ (p_ref − p̄_ref)·R(u − ū) and Σ|u − ū|²: the window's scale evidence.
    tr: f64,
    s_uu: f64,
    /// Σ|p_ref − p̄_ref|²: what the window's motion explains.
    s_rr: f64,
    /// The stretches between the estimate's jumps the window's points fall in, each with its own
    /// similarity and drift (1 without a jump).
    segments: usize,
}

/// A stretch of a window between two of the estimate's jumps holds at least this many reference
/// samples to be fitted (its similarity and drift are 8 parameters); fewer are left out.
const MIN_SEGMENT_SAMPLES: usize = 6;

/// The problem: reference samples, the estimate's poses, the windows.
struct Problem<'a> {
    ref_t: &'a [f64],
    ref_p: &'a [Vector3<f64>],
    sampler: Sampler<'a>,
    /// The half-steps of the central differences for ∂u/∂Δt, seconds (see [`Terms`]): the
    /// instrument's, and the Jacobian's (two of the estimate's periods more: other samples again).
    h: f64,
    hw: f64,
}

/// One point of a window: reference position, the estimate's position ê, u = ê − R̂·D, ∂u/∂Δt
/// over ±h (the instrument) and over ±h_w (for the Newton Jacobian), R̂, time.
#[derive(Clone)]
struct Pt {
    r: Vector3<f64>,
    e: Vector3<f64>,
    u: Vector3<f64>,
    du: Vector3<f64>,
    dw: Vector3<f64>,
    rhat: Matrix3<f64>,
    t: f64,
    /// The stretch of the estimate between jumps the point's stencil lies in.
    seg: usize,
}

impl Terms {
    /// The residual's degrees of freedom before the shared parameters: three per point, less each
    /// stretch's similarity and drift (8).
    fn dof(&self) -> f64 {
        (3 * self.n) as f64 - 8.0 * self.segments as f64
    }

    /// The window's residual RMS, metres.
    fn rms_m(&self) -> f64 {
        (self.rss / self.n as f64).sqrt()
    }

    /// The equations of two stretches of one window fitted apart (their nuisances their own).
    fn plus(self, o: Terms) -> Terms {
        Terms {
            n: self.n + o.n,
            rss: self.rss + o.rss,
            h: self.h + o.h,
            j: self.j + o.j,
            g: self.g + o.g,
            tr: self.tr + o.tr,
            s_uu: self.s_uu + o.s_uu,
            s_rr: self.s_rr + o.s_rr,
            segments: self.segments + o.segments,
        }
    }
}

/// The reduced normal equations of the points `pts` under one similarity and drift (a window, or
/// a stretch of one between jumps; see [`Problem::terms`]).
fn segment_terms(pts: Vec<Pt>, shape: &ClockShape, with_lever: bool, s_bar: f64) -> Option<Terms> {
    let m = shape.len();
    let p = m + if with_lever { 3 } else { 0 };
    let n = pts.len();
    let win = WindowPoints::new(pts);
    let nuisance = win.nuisance(s_bar);
    let mut sums = NormalSums::zeros(p);
    let mut shared = SharedColumns::new(m, with_lever);
    for (q, dw) in win.pts.iter().zip(&nuisance.drift) {
        let (e, cols) = nuisance.residual(&win, q, dw);
        shared.fill(q, &nuisance, shape);
        sums.add(&e, &cols, &shared.v, &shared.x);
    }
    let rss = sums.rss;
    let (h, j, g) = sums.reduce(&nuisance, win.nf, s_bar)?;
    Some(Terms {
        n,
        rss,
        h,
        j,
        g,
        tr: nuisance.tr,
        s_uu: nuisance.s_uu,
        s_rr: win.s_rr,
        segments: 1,
    })
}

/// `pts` (in time order) cut into the stretches of the estimate between jumps they fall in, those of
/// fewer than [`MIN_SEGMENT_SAMPLES`] points left out (their similarity and drift are 8 parameters).
fn stretches(pts: Vec<Pt>) -> Vec<Vec<Pt>> {
    let mut out: Vec<Vec<Pt>> = Vec::new();
    let mut rest = pts.into_iter().peekable();
    while let Some(first) = rest.next() {
        let mut run = vec![first];
        while let Some(q) = rest.next_if(|q| q.seg == run[0].seg) {
            run.push(q);
        }
        if run.len() >= MIN_SEGMENT_SAMPLES {
            out.push(run);
        }
    }
    out
}

impl Problem<'_> {
    /// The reduced normal equations of window `w` for the clock `shape`/`theta` (its parameters
    /// first) and, when `with_lever`, the lever D (the last three); `d` is the lever used either way.
    /// `s_bar`: the mission's scale (the prior's centre).
    fn terms(
        &self,
        w: &Window,
        shape: &ClockShape,
        theta: &[f64],
        d: &Vector3<f64>,
        with_lever: bool,
        s_bar: f64,
    ) -> Option<Terms> {
        let pts = self.points(w, shape, theta, d);
        if pts.len() < MIN_WINDOW_SAMPLES {
            return None;
        }
        if pts.first().map(|q| q.seg) == pts.last().map(|q| q.seg) {
            return segment_terms(pts, shape, with_lever, s_bar);
        }
        // A jump of the estimate within the window: each stretch between jumps its own similarity
        // and drift, their reduced equations summed (the stretches share only θ and D).
        let mut total: Option<Terms> = None;
        for run in stretches(pts) {
            let Some(t) = segment_terms(run, shape, with_lever, s_bar) else {
                continue;
            };
            total = Some(match total {
                None => t,
                Some(sum) => sum.plus(t),
            });
        }
        total.filter(|t| t.n >= MIN_WINDOW_SAMPLES)
    }

    /// Window `w`'s residual at the constant offset `offset_s` with the lever `d`: the mean squared
    /// residual per point once each stretch's similarity is fitted (scale held about `s_bar`; no
    /// heading drift), metres², on [`SEARCH_POINTS`] to twice as many of its samples. What a search over
    /// offsets compares: one interpolation per point instead of [`Problem::points`]'s five, and no
    /// normal equations. `None` with fewer than [`MIN_WINDOW_SAMPLES`] points.
    fn mean_square_m2(
        &self,
        w: &Window,
        offset_s: f64,
        d: &Vector3<f64>,
        s_bar: f64,
    ) -> Option<f64> {
        let stride = (w.range.len() / SEARCH_POINTS).max(1);
        let mut pts: Vec<Pt> = Vec::with_capacity(w.range.len().div_ceil(stride));
        let mut hint: Option<usize> = None;
        for i in w.range.clone().step_by(stride) {
            let t = self.ref_t[i];
            let te = t - offset_s;
            let hint = hint
                .get_or_insert_with(|| self.sampler.track.t.partition_point(|&x| x < te - self.hw));
            let (Some(seg), Some(a)) =
                (self.sampler.segment(te, self.hw), self.sampler.at(te, hint))
            else {
                continue;
            };
            pts.push(Pt {
                r: self.ref_p[i],
                e: a.p,
                u: a.p - a.r * d,
                du: Vector3::zeros(),
                dw: Vector3::zeros(),
                rhat: a.r,
                t,
                seg,
            });
        }
        let (mut rss, mut n) = (0.0, 0usize);
        for run in stretches(pts) {
            let win = WindowPoints::new(run);
            rss += win.similarity_rss(s_bar);
            n += win.pts.len();
        }
        (n >= MIN_WINDOW_SAMPLES).then(|| rss / n as f64)
    }

    /// The points of window `w` (see [`Pt`]) for the clock `shape`/`theta` and the lever `d`: the
    /// reference samples whose time on the estimate's clock, and the stencils of the central
    /// differences around it, fall where the estimate's poses can be interpolated.
    fn points(&self, w: &Window, shape: &ClockShape, theta: &[f64], d: &Vector3<f64>) -> Vec<Pt> {
        let mut pts: Vec<Pt> = Vec::with_capacity(w.range.len());
        let mut hints = [0usize; 5];
        let (h, hw) = (self.h, self.hw);
        for i in w.range.clone() {
            let t = self.ref_t[i];
            let te = t - shape.value(theta, t);
            // The hints of the first query of the window by bisection, the rest walk.
            if pts.is_empty() {
                hints = [self.sampler.track.t.partition_point(|&x| x < te - hw); 5];
            }
            let Some(seg) = self.sampler.segment(te, hw) else {
                continue;
            };
            let mut at = |k: usize, dt: f64| self.sampler.at(te + dt, &mut hints[k]);
            let (Some(a), Some(m1), Some(p1), Some(m2), Some(p2)) =
                (at(0, 0.0), at(1, -h), at(2, h), at(3, -hw), at(4, hw))
            else {
                continue;
            };
            let u = |x: &At| x.p - x.r * d;
            pts.push(Pt {
                r: self.ref_p[i],
                e: a.p,
                u: u(&a),
                // u(t − Δt) moves by −u̇ per second of Δt.
                du: (u(&m1) - u(&p1)) / (2.0 * h),
                dw: (u(&m2) - u(&p2)) / (2.0 * hw),
                rhat: a.r,
                t,
                seg,
            });
        }
        pts
    }
}

/// A window's points and their centroids: what its similarity and drift are fitted to.
struct WindowPoints {
    pts: Vec<Pt>,
    /// The number of points (the priors' weights grow with it).
    nf: f64,
    /// The centroids of the reference positions (r̄) and of u (ū), metres, and of the times (t̄),
    /// seconds.
    rbar_m: Vector3<f64>,
    ubar_m: Vector3<f64>,
    tbar_s: f64,
    /// Σ|p_ref − p̄_ref|²: what the window's motion explains (see [`Terms`]).
    s_rr: f64,
}

impl WindowPoints {
    /// The centroids of `pts`.
    fn new(pts: Vec<Pt>) -> WindowPoints {
        let nf = pts.len() as f64;
        let rbar_m = pts.iter().map(|q| q.r).sum::<Vector3<f64>>() / nf;
        let ubar_m = pts.iter().map(|q| q.u).sum::<Vector3<f64>>() / nf;
        let tbar_s = pts.iter().map(|q| q.t).sum::<f64>() / nf;
        let s_rr: f64 = pts.iter().map(|q| (q.r - rbar_m).norm_squared()).sum();
        WindowPoints {
            pts,
            nf,
            rbar_m,
            ubar_m,
            tbar_s,
            s_rr,
        }
    }

    /// The scale given Σ r̃·R·ũ (`tr`) and Σ|ũ|² (`s_uu`), held about the mission's `s_bar` by its
    /// prior (weight n·[`SCALE_PRIOR_M`]²).
    fn scale_of(&self, tr: f64, s_uu: f64, s_bar: f64) -> f64 {
        let lambda = self.scale_prior_m2();
        ((tr + lambda * s_bar) / (s_uu + lambda)).max(1e-3)
    }

    /// The scale prior's weight λ = n·[`SCALE_PRIOR_M`]², m².
    fn scale_prior_m2(&self) -> f64 {
        self.nf * SCALE_PRIOR_M * SCALE_PRIOR_M
    }

    /// Σ|p_ref − r̄ − s·R·(u − ū)|² under the similarity alone (no heading drift): the residual a
    /// search over offsets compares.
    fn similarity_rss(&self, s_bar: f64) -> f64 {
        let (rot, tr, s_uu) = self.similarity(&|i| self.pts[i].u - self.ubar_m);
        let s = self.scale_of(tr, s_uu, s_bar);
        self.pts
            .iter()
            .map(|q| (s * (rot * (q.u - self.ubar_m)) + self.rbar_m - q.r).norm_squared())
            .sum()
    }

    /// The similarity of the centred points ũ_i = `at(i)` to the centred reference positions r̃:
    /// the rotation R maximising Σ r̃·R·ũ (Umeyama), that Σ r̃·R·ũ and Σ|ũ|² (the scale's evidence).
    fn similarity(&self, at: &dyn Fn(usize) -> Vector3<f64>) -> (Matrix3<f64>, f64, f64) {
        let mut cov = Matrix3::zeros();
        let mut s_uu = 0.0;
        for (i, q) in self.pts.iter().enumerate() {
            let du = at(i);
            cov += (q.r - self.rbar_m) * du.transpose();
            s_uu += du.norm_squared();
        }
        let rot = rotation_of(&cov);
        (rot, (rot.transpose() * cov).trace(), s_uu)
    }

    /// The basis w_i of a heading drift about `up` (centred): a heading drifting at b rad/s moves
    /// the points by b·w_i, w_i = ∫(τ − t̄)·up × dê over the window's own increments.
    fn drift_basis(&self, up: &Vector3<f64>) -> Vec<Vector3<f64>> {
        let pts = &self.pts;
        let mut drift = Vec::with_capacity(pts.len());
        let mut acc = Vector3::zeros();
        drift.push(acc);
        for k in 1..pts.len() {
            let mid = 0.5 * (pts[k - 1].t + pts[k].t) - self.tbar_s;
            acc += up.cross(&(pts[k].e - pts[k - 1].e)) * mid;
            drift.push(acc);
        }
        let dbar = drift.iter().sum::<Vector3<f64>>() / self.nf;
        for w in &mut drift {
            *w -= dbar;
        }
        drift
    }

    /// The window's nuisance (see [`Nuisance`]): the similarity of the centred points, then twice
    /// the drift rate given the similarity and the similarity given the rate (when the window's
    /// increments give the drift a basis). The scale is held to the mission's `s_bar` by its prior.
    fn nuisance(&self, s_bar: f64) -> Nuisance {
        let nf = self.nf;
        let lambda = self.scale_prior_m2();
        let scale_of = |tr: f64, s_uu: f64| self.scale_of(tr, s_uu, s_bar);
        let (mut rot, mut tr, mut s_uu) = self.similarity(&|i| self.pts[i].u - self.ubar_m);
        // The estimate's heading drifting within the window at a rate b about its vertical: its
        // positions carry b·∫(τ − t̄)·ẑ × dê (integrated over the window's own increments), which
        // no rotation of the whole window removes.
        let drift = self.drift_basis(&(rot.transpose() * Vector3::z()));
        let d_ww: f64 = drift.iter().map(|w| w.norm_squared()).sum();
        let mut b = 0.0;
        let mut s = scale_of(tr, s_uu);
        if d_ww > 0.0 {
            for _ in 0..2 {
                // b given the similarity, then the similarity given b.
                let num: f64 = self
                    .pts
                    .iter()
                    .zip(&drift)
                    .map(|(q, w)| {
                        (rot * w).dot(&(s * (rot * (q.u - self.ubar_m)) - (q.r - self.rbar_m)))
                    })
                    .sum();
                b = num / (s * (d_ww + nf * DRIFT_PRIOR_M2S2 / (s * s)));
                (rot, tr, s_uu) = self.similarity(&|i| self.pts[i].u - self.ubar_m - drift[i] * b);
                s = scale_of(tr, s_uu);
            }
        }
        Nuisance {
            rot,
            scale: s,
            rate_rad_s: b,
            drift,
            tr,
            s_uu,
            lambda_m2: lambda,
        }
    }
}

/// A window's nuisance, fitted to its points: its similarity (rotation, scale; the translation is
/// the centroids') and its heading drift rate b, p_ref − r̄ ≈ s·R·(u − ū − b·w).
struct Nuisance {
    rot: Matrix3<f64>,
    scale: f64,
    /// b, rad/s.
    rate_rad_s: f64,
    /// The drift's basis w_i, one per point ([`WindowPoints::drift_basis`]).
    drift: Vec<Vector3<f64>>,
    /// Σ r̃·R·ũ and Σ|ũ|² of the last similarity (the window's scale evidence, see [`Terms`]).
    tr: f64,
    s_uu: f64,
    /// The scale prior's weight λ = n·[`SCALE_PRIOR_M`]², m².
    lambda_m2: f64,
}

impl Nuisance {
    /// Point `q`'s residual e (the model less the reference, metres) and the model's derivatives by
    /// the nuisance: translation (3), rotation (3, δω applied on the left), scale (1), heading drift
    /// rate (1). `dw`: the point's drift basis.
    fn residual(
        &self,
        win: &WindowPoints,
        q: &Pt,
        dw: &Vector3<f64>,
    ) -> (Vector3<f64>, [Vector3<f64>; 8]) {
        let (rot, s, b) = (self.rot, self.scale, self.rate_rad_s);
        let wv = s * (rot * (q.u - win.ubar_m - dw * b));
        let e = wv + win.rbar_m - q.r;
        let cols: [Vector3<f64>; 8] = [
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
            Vector3::x().cross(&wv),
            Vector3::y().cross(&wv),
            Vector3::z().cross(&wv),
            wv / s,
            -(rot * dw) * s,
        ];
        (e, cols)
    }
}

/// One point's columns of the shared parameters (the clock's, then the lever's when fitted): `v`
/// the instrument's (∂u/∂Δt over ±h), `x` the Jacobian's (over ±h_w); `phi` holds the clock's
/// basis. Refilled point after point.
struct SharedColumns {
    phi: Vec<f64>,
    v: Vec<Vector3<f64>>,
    x: Vec<Vector3<f64>>,
    with_lever: bool,
}

impl SharedColumns {
    /// Room for `m` clock parameters and, when `with_lever`, the lever's three.
    fn new(m: usize, with_lever: bool) -> SharedColumns {
        let p = m + if with_lever { 3 } else { 0 };
        SharedColumns {
            phi: vec![0.0; m],
            v: vec![Vector3::zeros(); p],
            x: vec![Vector3::zeros(); p],
            with_lever,
        }
    }

    /// The columns of point `q` under the window's `nuisance`: the clock's basis φ(t) times s·R·∂u/∂Δt,
    /// and −s·R·R̂ for the lever (u = ê − R̂·D).
    fn fill(&mut self, q: &Pt, nuisance: &Nuisance, shape: &ClockShape) {
        let (rot, s) = (nuisance.rot, nuisance.scale);
        let m = self.phi.len();
        shape.basis(q.t, &mut self.phi);
        let sdu = s * (rot * q.du);
        let sdw = s * (rot * q.dw);
        for (k, f) in self.phi.iter().enumerate() {
            self.v[k] = sdu * *f;
            self.x[k] = sdw * *f;
        }
        if self.with_lever {
            let sr = s * (rot * q.rhat);
            for c in 0..3 {
                self.v[m + c] = -sr.column(c).into_owned();
                self.x[m + c] = self.v[m + c];
            }
        }
    }
}

/// The sums of a window's normal equations over its points, the nuisance N (8 columns) against
/// itself, the shared parameters' instrument V and Jacobian X and the residual e (NᵀN, NᵀV, NᵀX,
/// Nᵀe), the instrument against the same (VᵀV, VᵀX, Vᵀe), and the residual sum of squares.
struct NormalSums {
    ntn: SMatrix<f64, 8, 8>,
    nte: SMatrix<f64, 8, 1>,
    /// NᵀV, NᵀX (8 × p) and VᵀV, VᵀX (p × p), row-major: one point adds to each entry in turn, so
    /// the entries a point touches lie next to each other (each entry's sum is the same sum, in the
    /// same order, as in a matrix type's storage; only the memory walk differs).
    ntv: Vec<f64>,
    ntx: Vec<f64>,
    vtv: Vec<f64>,
    vtx: Vec<f64>,
    vte: Vec<f64>,
    p: usize,
    rss: f64,
}

impl NormalSums {
    /// Empty sums for `p` shared parameters.
    fn zeros(p: usize) -> NormalSums {
        NormalSums {
            ntn: SMatrix::<f64, 8, 8>::zeros(),
            nte: SMatrix::<f64, 8, 1>::zeros(),
            ntv: vec![0.0; 8 * p],
            ntx: vec![0.0; 8 * p],
            vtv: vec![0.0; p * p],
            vtx: vec![0.0; p * p],
            vte: vec![0.0; p],
            p,
            rss: 0.0,
        }
    }

    /// Adds one point: its residual `e`, nuisance columns `cols` and shared columns `v` and `x`
    /// (of the symmetric NᵀN and VᵀV the upper triangles only).
    fn add(
        &mut self,
        e: &Vector3<f64>,
        cols: &[Vector3<f64>; 8],
        v: &[Vector3<f64>],
        x: &[Vector3<f64>],
    ) {
        let p = self.p;
        self.rss += e.norm_squared();
        for a in 0..8 {
            let ca = &cols[a];
            self.nte[a] += ca.dot(e);
            for (b, cb) in cols.iter().enumerate().skip(a) {
                self.ntn[(a, b)] += ca.dot(cb);
            }
            let rows = self.ntv[a * p..(a + 1) * p]
                .iter_mut()
                .zip(&mut self.ntx[a * p..(a + 1) * p]);
            for ((sv, sx), (vb, xb)) in rows.zip(v.iter().zip(x)) {
                *sv += ca.dot(vb);
                *sx += ca.dot(xb);
            }
        }
        for (a, va) in v.iter().enumerate() {
            self.vte[a] += va.dot(e);
            let (vtv, vtx) = (
                &mut self.vtv[a * p..(a + 1) * p],
                &mut self.vtx[a * p..(a + 1) * p],
            );
            for (b, (vb, xb)) in v.iter().zip(x).enumerate() {
                if b >= a {
                    vtv[b] += va.dot(vb);
                }
                vtx[b] += va.dot(xb);
            }
        }
    }

    /// The reduced equations (H, J and g of [`Terms`]): the symmetric sums completed, the priors of
    /// the window's `nuisance` (its scale about the mission's `s_bar`, its drift rate about 0; `nf`
    /// points) and a ridge added, then the nuisance eliminated (the Schur complement). `None` when
    /// the nuisance's block cannot be inverted.
    fn reduce(
        mut self,
        nuisance: &Nuisance,
        nf: f64,
        s_bar: f64,
    ) -> Option<(DMatrix<f64>, DMatrix<f64>, DVector<f64>)> {
        let p = self.p;
        for a in 0..8 {
            for b in 0..a {
                self.ntn[(a, b)] = self.ntn[(b, a)];
            }
        }
        for a in 0..p {
            for b in 0..a {
                self.vtv[a * p + b] = self.vtv[b * p + a];
            }
        }
        // The priors: residuals √λ·(s − s̄) and √λ_b·b.
        let lambda = nuisance.lambda_m2;
        self.ntn[(6, 6)] += lambda;
        self.nte[6] += lambda * (nuisance.scale - s_bar);
        self.ntn[(7, 7)] += nf * DRIFT_PRIOR_M2S2;
        self.nte[7] += nf * DRIFT_PRIOR_M2S2 * nuisance.rate_rad_s;
        // A rotation or a drift the window does not determine (its points on a line, standing)
        // stays put.
        let ridge = 1e-9 * (0..8).map(|a| self.ntn[(a, a)]).fold(0.0, f64::max);
        for a in 0..8 {
            self.ntn[(a, a)] += ridge;
        }
        let inv = self.ntn.try_inverse()?;
        let ntn_inv = DMatrix::from_fn(8, 8, |a, b| inv[(a, b)]);
        let ntv = DMatrix::from_row_slice(8, p, &self.ntv);
        let ntx = DMatrix::from_row_slice(8, p, &self.ntx);
        let vtv = DMatrix::from_row_slice(p, p, &self.vtv);
        let vtx = DMatrix::from_row_slice(p, p, &self.vtx);
        let xv = &ntn_inv * &ntv;
        let h = &vtv - ntv.transpose() * &xv;
        let j = &vtx - xv.transpose() * &ntx;
        let nte_d = DVector::from_fn(8, |a, _| self.nte[a]);
        let g = DVector::from_column_slice(&self.vte) - xv.transpose() * nte_d;
        Some((h, j, g))
    }
}

/// The rotation R maximising tr(Rᵀ·cov) (Kabsch: cov = Σ (r − r̄)(u − ū)ᵀ), identity when cov
/// holds nothing.
fn rotation_of(cov: &Matrix3<f64>) -> Matrix3<f64> {
    if cov.norm() <= 0.0 || !cov.iter().all(|v| v.is_finite()) {
        return Matrix3::identity();
    }
    let svd = cov.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Matrix3::identity();
    };
    let sign = (u * vt).determinant().signum();
    u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, sign)) * vt
}

/// Cuts the reference's span into windows of [`WINDOW_S`] (or longer, to hold
/// [`MIN_WINDOW_SAMPLES`] at the reference's median rate).
pub fn windows(ref_t: &[f64], window_s: Option<f64>) -> Vec<Window> {
    let n = ref_t.len();
    if n < MIN_WINDOW_SAMPLES {
        return Vec::new();
    }
    let mut steps: Vec<f64> = ref_t.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = steps.len() / 2;
    let period = *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
    let len = window_s.unwrap_or(WINDOW_S.max(1.5 * MIN_WINDOW_SAMPLES as f64 * period));
    let (a, b) = (ref_t[0], ref_t[n - 1]);
    let count = ((b - a) / len).floor().max(1.0) as usize;
    // The windows share the span evenly (no sliver at the end).
    let len = (b - a) / count as f64;
    (0..count)
        .map(|k| {
            let (lo, hi) = (a + k as f64 * len, a + (k + 1) as f64 * len);
            let start = ref_t.partition_point(|&t| t < lo);
            let end = if k + 1 == count {
                n
            } else {
                ref_t.partition_point(|&t| t < hi)
            };
            Window {
                range: start..end,
                t_start: lo,
                t_end: hi,
            }
        })
        .collect()
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
    pub lever_sigma_m: Option<Vector3<f64>>,
    /// The covariance of (θ, D): the jackknife's, each variance raised to at least the formal one.
    pub covariance: DMatrix<f64>,
    /// Δt's error with the lever fitted over Δt's error with it held, squared (θ₀; 1 without lever).
    pub variance_inflation: f64,
    /// The windows used, and the ones left out as outliers (their residual RMS).
    pub windows: Vec<Window>,
    pub outliers: Vec<Window>,
    /// Residual RMS per used window, metres.
    pub rms_m: Vec<f64>,
    /// The mission's scale (estimate distances over reference distances, ≈ 1 + scale error).
    pub scale: f64,
    /// The secant correction of the Jacobian's clock columns (see `solve`); the profile's windows
    /// use it too.
    pub jacobian_scale: f64,
    pub iterations: usize,
    pub converged: bool,
}

impl PoseFit {
    /// Whether Δt and the lever are too entangled to tell apart (constant speed, no turns in place):
    /// Δt's variance grows by more than [`INSEPARABLE_VIF`] when the lever is fitted.
    pub fn inseparable(&self) -> bool {
        self.variance_inflation > INSEPARABLE_VIF
    }
}

/// Settings of a fit.
#[derive(Debug, Clone, Copy)]
pub struct PoseFitParams {
    /// The largest gap of the estimate interpolated across, seconds.
    pub max_gap_s: f64,
    /// The window length (`None`: [`WINDOW_S`], longer at low reference rates).
    pub window_s: Option<f64>,
}

/// The reference, the estimate's poses and the settings of one mission's fits.
pub struct PoseData<'a> {
    pub ref_t: &'a [f64],
    pub ref_p: &'a [Vector3<f64>],
    pub estimate: PoseTrack<'a>,
    pub params: PoseFitParams,
}

impl<'a> PoseData<'a> {
    fn problem(&self) -> Problem<'a> {
        let mut steps: Vec<f64> = self.estimate.t.windows(2).map(|w| w[1] - w[0]).collect();
        let period = if steps.is_empty() {
            0.01
        } else {
            let mid = steps.len() / 2;
            *steps.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        Problem {
            ref_t: self.ref_t,
            ref_p: self.ref_p,
            sampler: Sampler {
                track: self.estimate,
                rotations: self
                    .estimate
                    .q
                    .iter()
                    .map(|q| q.to_rotation_matrix().into_inner())
                    .collect(),
                gap: self.params.max_gap_s,
            },
            h: (2.0 * period).clamp(STENCIL_MIN_S, STENCIL_MAX_S),
            hw: (2.0 * period).clamp(STENCIL_MIN_S, STENCIL_MAX_S) + 2.0 * period,
        }
    }

    /// The windows of this mission.
    pub fn windows(&self) -> Vec<Window> {
        windows(self.ref_t, self.params.window_s)
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

/// How many times the change time and the two sides' similarities are refined in turn.
const LOCATE_ROUNDS: usize = 3;

/// The reference time τ in [lo, hi] at which the clock changes from Δt₁ to Δt₂ (`d`), located on
/// the positions: τ minimises Σ_{t<τ} |e₁(t)|² + Σ_{t≥τ} |e₂(t)|², e_k the residual of the reference
/// sample at t against the estimate at t − Δt_k (less its `lever_m`) mapped by a similarity fitted
/// to the points on side k of τ, half a window beyond [lo, hi] included (scale held about `s_bar`
/// like the windows'); τ and the two similarities in turn, from the middle. The positions see a step
/// where speed signals cannot (a walking robot's speed hardly changes): the estimate is displaced
/// by its velocity times the step, which no similarity of a side removes. `None` with fewer than
/// [`MIN_WINDOW_SAMPLES`] points on a side.
pub fn locate_change(
    data: &PoseData<'_>,
    lever_m: &Vector3<f64>,
    s_bar: f64,
    d: (f64, f64),
    (lo, hi): (f64, f64),
) -> Option<f64> {
    let problem = data.problem();
    let pad = 0.5 * data.params.window_s.unwrap_or(WINDOW_S);
    let stretch = Window {
        range: data.ref_t.partition_point(|&t| t < lo - pad)
            ..data.ref_t.partition_point(|&t| t <= hi + pad),
        t_start: lo - pad,
        t_end: hi + pad,
    };
    // Each reference sample under both clocks (the samples where either cannot be interpolated
    // dropped).
    let under = |dt: f64| problem.points(&stretch, &ClockShape::Constant, &[dt], lever_m);
    let (p1, p2) = (under(d.0), under(d.1));
    let mut both: Vec<(Pt, Pt)> = Vec::with_capacity(p1.len());
    let mut later = p2.into_iter().peekable();
    for a in p1 {
        while later.next_if(|b| b.t < a.t).is_some() {}
        if let Some(b) = later.next_if(|b| b.t == a.t) {
            both.push((a, b));
        }
    }
    let mut tau = 0.5 * (lo + hi);
    let mut located = None;
    for _ in 0..LOCATE_ROUNDS {
        let side = |before: bool| {
            let pts: Vec<Pt> = both
                .iter()
                .filter(|(a, _)| (a.t < tau) == before)
                .map(|(a, b)| if before { a.clone() } else { b.clone() })
                .collect();
            (pts.len() >= MIN_WINDOW_SAMPLES).then(|| {
                let w = WindowPoints::new(pts);
                let n = w.nuisance(s_bar);
                (w, n)
            })
        };
        let (Some((w1, n1)), Some((w2, n2))) = (side(true), side(false)) else {
            return located;
        };
        let err = |w: &WindowPoints, n: &Nuisance, q: &Pt| {
            (n.scale * (n.rot * (q.u - w.ubar_m)) + w.rbar_m - q.r).norm_squared()
        };
        // (time, cost before, cost after) of every sample in [lo, hi]: the split of least cost.
        let costs: Vec<(f64, f64, f64)> = both
            .iter()
            .filter(|(a, _)| a.t >= lo && a.t <= hi)
            .map(|(a, b)| (a.t, err(&w1, &n1, a), err(&w2, &n2, b)))
            .collect();
        let split = crate::align::clock_model::least_cost_split(&costs)?;
        located = Some(split);
        if split == tau {
            break;
        }
        tau = split;
    }
    located
}

/// Fits the clock `shape` (from `theta0`) and, when `with_lever`, the lever (from `lever0`) over
/// `windows`; windows whose residual RMS is an outlier are left out and the fit repeated.
pub fn fit(
    data: &PoseData<'_>,
    windows: &[Window],
    shape: ClockShape,
    theta0: Vec<f64>,
    lever0: Vector3<f64>,
    with_lever: bool,
) -> Option<PoseFit> {
    let problem = data.problem();
    // Windows whose residual at the start is an outlier already (a jump of the estimate in them)
    // are left out before the first fit, so that they cannot drag it.
    let at_start: Vec<Option<f64>> = windows
        .par_iter()
        .map(|w| {
            problem
                .terms(w, &shape, &theta0, &lever0, false, 1.0)
                .map(|t| t.rms_m())
        })
        .collect();
    let mut rms: Vec<f64> = at_start.iter().flatten().copied().collect();
    rms.sort_by(f64::total_cmp);
    let median = rms.get(rms.len() / 2).copied().unwrap_or(f64::INFINITY);
    let (mut kept, mut outliers): (Vec<Window>, Vec<Window>) = (Vec::new(), Vec::new());
    for (w, r) in windows.iter().zip(&at_start) {
        match r {
            Some(r) if *r > OUTLIER_RMS_FACTOR * median => outliers.push(w.clone()),
            _ => kept.push(w.clone()),
        }
    }
    if kept.len() < 3 {
        kept = windows.to_vec();
        outliers.clear();
    }
    let (mut theta, mut lever) = (theta0, lever0);
    for _round in 0..3 {
        let mut f = solve(&problem, &kept, &shape, theta.clone(), lever, with_lever)?;
        let mut rms = f.rms_m.clone();
        rms.sort_by(f64::total_cmp);
        let median = rms[rms.len() / 2];
        type Scored = Vec<(Window, f64)>;
        let (bad, good): (Scored, Scored) = f
            .windows
            .iter()
            .cloned()
            .zip(f.rms_m.iter().copied())
            .partition(|(_, r)| *r > OUTLIER_RMS_FACTOR * median);
        if bad.is_empty() || good.len() < 3 {
            f.outliers = outliers;
            return Some(f);
        }
        outliers.extend(bad.into_iter().map(|(w, _)| w));
        kept = good.into_iter().map(|(w, _)| w).collect();
        theta = f.theta;
        lever = f.lever_m;
    }
    let mut f = solve(&problem, &kept, &shape, theta, lever, with_lever)?;
    f.outliers = outliers;
    Some(f)
}

/// Newton steps of the lever at each candidate of [`coarse_start`] at most: the windows' similarities
/// move with the lever, so one step from none leaves it far off where the robot turns in place.
const COARSE_LEVER_STEPS: usize = 6;
/// A lever step below this ends [`coarse_start`]'s lever iterations, metres.
const COARSE_LEVER_TOLERANCE_M: f64 = 1e-3;

/// The offset among `start_s` ± `span_s` (every `step_s`) at which the windows fit best, the lever
/// solved at each candidate (Newton steps from none until it settles, six at
/// most), by the residual per point: a start for [`fit`] when the one it was given lies outside
/// the basin (the estimating equations have no root between there and the truth: on two
/// validation missions the fit stalled 111 ms off, or ran away, from a start 218 and 64 ms off, and
/// converged from within 100 and 34 ms). With a single lever step the residual of a robot turning
/// in place fell steadily away from the truth (the lever left at half its length), and the best
/// candidate was the search's edge, 0.36 s off; settled, it is 11 ms off and the fit converges.
/// `None` when no candidate has windows.
pub fn coarse_start(
    data: &PoseData<'_>,
    windows: &[Window],
    start_s: f64,
    (span_s, step_s): (f64, f64),
) -> Option<f64> {
    let problem = data.problem();
    let shape = ClockShape::Constant;
    let fit = SharedFit {
        problem: &problem,
        windows,
        shape: &shape,
        with_lever: true,
        m: 1,
        p: 4,
    };
    let k = (span_s / step_s).round() as i64;
    (-k..=k)
        .filter_map(|i| {
            let theta = [start_s + i as f64 * step_s];
            let mut lever = Vector3::zeros();
            let mut terms = fit.eval(&theta, &lever, 1.0);
            for _ in 0..COARSE_LEVER_STEPS {
                let (_, j, g) = fit.summed(&terms, &lever, lever_weight(&terms), 1.0);
                let Some(step) = j
                    .view((1, 1), (3, 3))
                    .into_owned()
                    .lu()
                    .solve(&g.rows(1, 3).into_owned())
                else {
                    break;
                };
                let step = Vector3::new(step[0], step[1], step[2]);
                lever -= step;
                terms = fit.eval(&theta, &lever, 1.0);
                if step.norm() < COARSE_LEVER_TOLERANCE_M {
                    break;
                }
            }
            let (rss, n) = residual_sums(&terms);
            (n > 0).then(|| (theta[0], rss / n as f64))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|best| best.0)
}

/// Gauss–Newton with backtracking over the shared parameters, then the jackknife.
fn solve(
    problem: &Problem<'_>,
    windows: &[Window],
    shape: &ClockShape,
    theta0: Vec<f64>,
    lever0: Vector3<f64>,
    with_lever: bool,
) -> Option<PoseFit> {
    let m = shape.len();
    let fit = SharedFit {
        problem,
        windows,
        shape,
        with_lever,
        m,
        p: m + if with_lever { 3 } else { 0 },
    };
    let mut x = fit.start(theta0, lever0)?;
    let iterations = fit.gauss_newton(&mut x)?;
    fit.finish(x, iterations)
}

/// The fit of the parameters every window shares over `windows`: the clock `shape`'s `m` (first)
/// and, when `with_lever`, the lever's three (of `p` in all).
struct SharedFit<'a> {
    problem: &'a Problem<'a>,
    windows: &'a [Window],
    shape: &'a ClockShape,
    with_lever: bool,
    m: usize,
    p: usize,
}

/// Gauss–Newton's iterate: the shared parameters, the windows' reduced equations at them, and what
/// steers the steps.
struct Iterate {
    /// The clock's parameters θ (seconds; a linear slope in s/s).
    theta: Vec<f64>,
    /// The lever D, estimate body frame.
    lever_m: Vector3<f64>,
    /// Each window's reduced equations at θ, D and the mission's scale (`None`: too few points).
    terms: Vec<Option<Terms>>,
    /// The mission's scale s̄, the centre of the windows' scale priors.
    scale: f64,
    /// The secant correction c of the Jacobian's clock columns.
    jacobian_scale: f64,
    /// The Levenberg–Marquardt damping λ.
    damping: f64,
}

impl SharedFit<'_> {
    /// The windows' reduced equations at the clock `theta`, the lever `d` and the mission's scale
    /// `s_bar`.
    fn eval(&self, theta: &[f64], d: &Vector3<f64>, s_bar: f64) -> Vec<Option<Terms>> {
        self.windows
            .par_iter()
            .map(|w| {
                self.problem
                    .terms(w, self.shape, theta, d, self.with_lever, s_bar)
            })
            .collect()
    }

    /// The iterate at the start (the mission's scale 1); `None` with fewer than three windows.
    fn start(&self, theta0: Vec<f64>, lever0: Vector3<f64>) -> Option<Iterate> {
        let s_bar = 1.0;
        let terms = self.eval(&theta0, &lever0, s_bar);
        if terms.iter().flatten().count() < 3 {
            return None;
        }
        Some(Iterate {
            theta: theta0,
            lever_m: lever0,
            terms,
            scale: s_bar,
            jacobian_scale: 1.0,
            damping: 1e-3,
        })
    }

    /// Gauss–Newton on the estimating equations from `x`, at most [`MAX_ITERATIONS`] steps, until a
    /// step is small or no damping makes one acceptable: the number of iterations; `None` when the
    /// summed equations cannot be solved.
    fn gauss_newton(&self, x: &mut Iterate) -> Option<usize> {
        let (m, p) = (self.m, self.p);
        let mut iterations = 0;
        let mut previous: Option<DVector<f64>> = None;
        for it in 0..MAX_ITERATIONS {
            iterations = it + 1;
            if it < 3 {
                self.rescale(x);
            }
            let l = lever_weight(&x.terms);
            let (Some(mut step), g0, scales) =
                self.normal(&x.terms, &x.lever_m, l, x.jacobian_scale, x.damping)
            else {
                return None;
            };
            // The secant correction, once the lever has settled.
            if let (true, Some(last)) = (it >= 2, &previous) {
                self.secant_correction(x, &mut step, last, l);
            }
            let before = merit(&g0, &scales);
            let accepted = self.backtrack(x, &mut step, l, &scales, before);
            let small = (0..m).all(|k| step[k].abs() < 2e-6)
                && (!self.with_lever || (m..p).all(|k| step[k].abs() < 2e-5));
            if !accepted || small {
                break;
            }
            previous = Some(step);
        }
        Some(iterations)
    }

    /// The mission's scale from the windows' evidence (Σ tr over Σ s_uu), the windows' equations
    /// then re-evaluated with it, so that every step compares like with like. Done in the first
    /// iterations only.
    fn rescale(&self, x: &mut Iterate) {
        let (tr, suu) = x
            .terms
            .iter()
            .flatten()
            .fold((0.0, 0.0), |(a, b), t| (a + t.tr, b + t.s_uu));
        if suu > 0.0 && tr > 0.0 && (tr / suu - x.scale).abs() > 1e-6 {
            x.scale = tr / suu;
            x.terms = self.eval(&x.theta, &x.lever_m, x.scale);
        }
    }

    /// The secant correction c of the Jacobian's clock columns, which are a derivative over a
    /// wider stencil and miss part of the fast motion (a gait) the residual follows: a clock
    /// `step` that undoes part of the `last` (ρ < 0, its projection on it) means the Jacobian was
    /// too small, so c grows by 1 − ρ (within [1, 4]) and `step` is solved again with it.
    fn secant_correction(
        &self,
        x: &mut Iterate,
        step: &mut DVector<f64>,
        last: &DVector<f64>,
        l: f64,
    ) {
        let m = self.m;
        let (new, old) = (step.rows(0, m), last.rows(0, m));
        let norm = old.dot(&old);
        let rho = new.dot(&old) / norm;
        if norm.sqrt() > 1e-5 && rho < 0.0 {
            x.jacobian_scale = (x.jacobian_scale * (1.0 - rho)).clamp(1.0, 4.0);
            if let (Some(s), ..) = self.normal(&x.terms, &x.lever_m, l, x.jacobian_scale, x.damping)
            {
                *step = s;
            }
        }
    }

    /// Takes `step` (shortened to [`MAX_STEP_S`] on the clock) when it keeps every window and
    /// lowers the merit of the estimating equations below `before` (the instrument is not the
    /// cost's exact gradient, so the steps solve g = 0 rather than descend a cost); otherwise ten
    /// times more damping and a new step, ten tries at most. Whether a step was taken (`step` is
    /// then the one taken); the damping falls after a success.
    fn backtrack(
        &self,
        x: &mut Iterate,
        step: &mut DVector<f64>,
        l: f64,
        scales: &DVector<f64>,
        before: f64,
    ) -> bool {
        let (m, c) = (self.m, x.jacobian_scale);
        for _ in 0..10 {
            let largest = (0..m).map(|k| step[k].abs()).fold(0.0, f64::max);
            let a = if largest > MAX_STEP_S {
                MAX_STEP_S / largest
            } else {
                1.0
            };
            let t2: Vec<f64> = (0..m).map(|k| x.theta[k] + a * step[k]).collect();
            let d2 = if self.with_lever {
                x.lever_m + Vector3::new(step[m], step[m + 1], step[m + 2]) * a
            } else {
                x.lever_m
            };
            let terms2 = self.eval(&t2, &d2, x.scale);
            if terms2.iter().flatten().count() == x.terms.iter().flatten().count()
                && merit(&self.normal(&terms2, &d2, l, c, 0.0).1, scales) < before
            {
                x.theta = t2;
                x.lever_m = d2;
                x.terms = terms2;
                *step *= a;
                x.damping = (x.damping / 3.0).max(1e-6);
                return true;
            }
            x.damping *= 10.0;
            match self.normal(&x.terms, &x.lever_m, l, c, x.damping) {
                (Some(s), ..) => *step = s,
                _ => return false,
            }
        }
        false
    }

    /// The reduced equations summed over the windows with the lever's prior (weight `l`, centred
    /// on 0, at the lever `d`) added, the Jacobian's clock columns scaled by the secant correction
    /// `c`: (H, J, g).
    fn summed(
        &self,
        terms: &[Option<Terms>],
        d: &Vector3<f64>,
        l: f64,
        c: f64,
    ) -> (DMatrix<f64>, DMatrix<f64>, DVector<f64>) {
        let (m, p) = (self.m, self.p);
        let (mut h, mut j, mut g) = (
            DMatrix::<f64>::zeros(p, p),
            DMatrix::<f64>::zeros(p, p),
            DVector::<f64>::zeros(p),
        );
        for t in terms.iter().flatten() {
            h += &t.h;
            j += &t.j;
            g += &t.g;
        }
        if self.with_lever {
            for c in 0..3 {
                h[(m + c, m + c)] += l;
                j[(m + c, m + c)] += l;
                g[m + c] += l * d[c];
            }
        }
        scale_clock_columns(&mut j, m, c);
        (h, j, g)
    }

    /// The damped Newton step −(J + λ·diag(H))⁻¹·g of the summed equations (see [`Self::summed`];
    /// Levenberg–Marquardt: more λ after a failed step), the gradient g and the merit's scales
    /// diag(H).
    fn normal(
        &self,
        terms: &[Option<Terms>],
        d: &Vector3<f64>,
        l: f64,
        c: f64,
        lambda: f64,
    ) -> (Option<DVector<f64>>, DVector<f64>, DVector<f64>) {
        let (h, mut j, g) = self.summed(terms, d, l, c);
        for k in 0..self.p {
            j[(k, k)] += lambda * h[(k, k)];
        }
        let step = j.lu().solve(&g).map(|x| -x);
        (step, g, h.diagonal())
    }

    /// The formal covariance J⁻¹·σ̂²H·J⁻ᵀ of the summed equations, σ̂² the residual per degree of
    /// freedom (white residuals assumed).
    fn formal_covariance(
        &self,
        terms: &[Option<Terms>],
        d: &Vector3<f64>,
        l: f64,
        c: f64,
    ) -> Option<DMatrix<f64>> {
        let (h, j, _) = self.summed(terms, d, l, c);
        let (rss, _) = residual_sums(terms);
        let dof = terms.iter().flatten().map(Terms::dof).sum::<f64>() - self.p as f64;
        if dof <= 0.0 {
            return None;
        }
        let ji = j.try_inverse()?;
        Some(&ji * h * ji.transpose() * (rss / dof))
    }

    /// The delete-one-window jackknife at the solution (see the module doc): each window left out
    /// by one Newton step of the summed equations less its own; the covariance
    /// (K−1)/K·Σ(δ₋ₖ − δ̄)(δ₋ₖ − δ̄)ᵀ of those steps, and the summed H (for the variance
    /// inflation). `None` when fewer than three windows could be left out.
    fn jackknife(
        &self,
        terms: &[Option<Terms>],
        d: &Vector3<f64>,
        l: f64,
        c: f64,
    ) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        let (m, p) = (self.m, self.p);
        let (h, j, _) = self.summed(terms, d, l, c);
        let deltas: Vec<DVector<f64>> = terms
            .iter()
            .flatten()
            .filter_map(|t| {
                let mut tj = t.j.clone();
                scale_clock_columns(&mut tj, m, c);
                (&j - tj).lu().solve(&t.g)
            })
            .collect();
        if deltas.len() < 3 {
            return None;
        }
        let kf = deltas.len() as f64;
        let mean = deltas.iter().fold(DVector::zeros(p), |a, d| a + d) / kf;
        let mut cov = DMatrix::<f64>::zeros(p, p);
        for dlt in &deltas {
            let c = dlt - &mean;
            cov += &c * c.transpose();
        }
        cov *= (kf - 1.0) / kf;
        Some((cov, h))
    }

    /// The fit at the solution `x`: the standard errors (the jackknife's, at least the formal
    /// ones), whether it converged (the Newton step left is small beside them), the variance
    /// inflation of Δt by the lever.
    fn finish(&self, x: Iterate, iterations: usize) -> Option<PoseFit> {
        let (m, p, with_lever) = (self.m, self.p, self.with_lever);
        let (d, c) = (x.lever_m, x.jacobian_scale);
        let l = lever_weight(&x.terms);
        let remaining = self.normal(&x.terms, &d, l, c, 0.0).0;
        let used: Vec<(&Window, &Terms)> = self
            .windows
            .iter()
            .zip(&x.terms)
            .filter_map(|(w, t)| t.as_ref().map(|t| (w, t)))
            .collect();
        let (mut cov, h) = self.jackknife(&x.terms, &d, l, c)?;
        // The formal σ is the floor (see the module doc): each parameter's variance raised to it,
        // the jackknife's correlations kept.
        if let Some(formal) = self.formal_covariance(&x.terms, &d, l, c) {
            let raise: Vec<f64> = (0..p)
                .map(|k| {
                    let (jack, floor) = (cov[(k, k)], formal[(k, k)]);
                    if jack > 0.0 && floor > jack {
                        (floor / jack).sqrt()
                    } else {
                        1.0
                    }
                })
                .collect();
            for a in 0..p {
                for b in 0..p {
                    cov[(a, b)] *= raise[a] * raise[b];
                }
                // A jackknife that saw no spread at all (a parameter no window moves).
                if cov[(a, a)] <= 0.0 {
                    cov[(a, a)] = formal[(a, a)].max(0.0);
                }
            }
        }
        let sig = |i: usize| cov[(i, i)].max(0.0).sqrt();
        // Converged: the Newton step left is within the parameters' own uncertainty (the
        // estimating equations are as rough as their noise at that scale; the σ floored, which
        // moved no validation mission's convergence). Half a σ was the rule
        // while a jump of the estimate could bend a fit; with jumps given their own frames, one σ
        // took a 1 Hz-reference mission's σ from 447 to 7 ms and located a step 0.01 s off instead of
        // 43 s (docs/evidence.md).
        let converged = remaining.is_some_and(|step| {
            (0..m).all(|k| step[k].abs() <= sig(k).max(1e-4))
                && (!with_lever || (m..p).all(|k| step[k].abs() <= sig(k).max(1e-3)))
        });
        let variance_inflation = if with_lever {
            // Var(θ₀) with D free over Var(θ₀) with D held, from the normal equations.
            h.clone()
                .try_inverse()
                .map_or(f64::INFINITY, |inv| inv[(0, 0)] * h[(0, 0)])
        } else {
            1.0
        };
        Some(PoseFit {
            shape: self.shape.clone(),
            theta: x.theta,
            lever_m: d,
            theta_sigma: (0..m).map(sig).collect(),
            lever_sigma_m: with_lever.then(|| Vector3::new(sig(m), sig(m + 1), sig(m + 2))),
            covariance: cov,
            variance_inflation,
            windows: used.iter().map(|(w, _)| (*w).clone()).collect(),
            outliers: Vec::new(),
            rms_m: used.iter().map(|(_, t)| t.rms_m()).collect(),
            scale: x.scale,
            jacobian_scale: c,
            iterations,
            converged: converged && used.len() >= 3,
        })
    }
}

/// The lever prior's weight: the windows' residual variance per coordinate over the prior's
/// variance [`LEVER_PRIOR_M`]².
fn lever_weight(terms: &[Option<Terms>]) -> f64 {
    let (rss, n) = residual_sums(terms);
    rss / (3.0 * n.max(1) as f64) / (LEVER_PRIOR_M * LEVER_PRIOR_M)
}

/// The residual sum of squares and the points of the windows' `terms`.
fn residual_sums(terms: &[Option<Terms>]) -> (f64, usize) {
    terms
        .iter()
        .flatten()
        .fold((0.0, 0usize), |(r, n), t| (r + t.rss, n + t.n))
}

/// The merit of the estimating equations: Σ g_k²/H_kk with the current iterate's `scales` (the
/// Newton direction descends it).
fn merit(g: &DVector<f64>, scales: &DVector<f64>) -> f64 {
    g.iter()
        .zip(scales.iter())
        .map(|(g, h)| if *h > 0.0 { g * g / h } else { 0.0 })
        .sum::<f64>()
}

/// The Jacobian's `m` clock columns of `j` scaled by the secant correction `c`.
fn scale_clock_columns(j: &mut DMatrix<f64>, m: usize, c: f64) {
    for k in 0..m {
        j.column_mut(k).scale_mut(c);
    }
}

/// Δt on one window, with its σ (the window's least-squares error, not yet scaled).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowOffset {
    pub t: f64,
    pub offset_s: f64,
    /// σ̂_k/√H_k, seconds.
    pub formal_sigma_s: f64,
    /// The window's residual RMS, metres.
    pub rms_m: f64,
    /// The share of the reference's motion in the window the fit explains, 1 − RSS/Σ|p − p̄|².
    pub quality: f64,
}

impl WindowOffset {
    /// Window `w`'s offset `offset_s`, with its reduced equations `t` there (`c`: the whole fit's
    /// secant correction); `None` when the window has no formal σ.
    fn of(w: &Window, offset_s: f64, t: &Terms, c: f64) -> Option<WindowOffset> {
        Some(WindowOffset {
            t: w.t(),
            offset_s,
            formal_sigma_s: formal_sigma(t, c)?,
            rms_m: t.rms_m(),
            quality: if t.s_rr > 0.0 {
                (1.0 - t.rss / t.s_rr).clamp(0.0, 1.0)
            } else {
                0.0
            },
        })
    }
}

/// Which profile windows are searched beyond their refinement from the start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WindowSearch {
    /// Only a window that fails from its start or leaves a residual far above the others'.
    Failed,
    /// Every window as well, for a deeper root than the one it settled at
    /// (`WindowSolver::deeper`).
    Every,
}

/// Each window's own Δt with the lever `lever` held, started from `start(t)` and searched as
/// `search` says, within ±`search_s` of its start. Windows that do not converge are left out.
pub fn profile(
    data: &PoseData<'_>,
    windows: &[Window],
    lever: Vector3<f64>,
    (scale, c): (f64, f64),
    start: &(dyn Fn(f64) -> f64 + Sync),
    (search, search_s): (WindowSearch, f64),
) -> Vec<WindowOffset> {
    let solver = WindowSolver {
        problem: data.problem(),
        lever_m: lever,
        scale,
        jacobian_scale: c,
    };
    let raw: Vec<Option<(f64, Terms)>> = windows
        .par_iter()
        .map(|w| {
            let t0 = start(w.t());
            let refined = solver.refine(w, t0)?;
            Some(match search {
                WindowSearch::Failed => refined,
                WindowSearch::Every => solver.deeper(w, refined, t0, search_s),
            })
        })
        .collect();
    let mut rms: Vec<f64> = raw.iter().flatten().map(|(_, t)| t.rms_m()).collect();
    if rms.is_empty() {
        return Vec::new();
    }
    rms.sort_by(f64::total_cmp);
    let median = rms[rms.len() / 2];
    windows
        .par_iter()
        .zip(raw)
        .filter_map(|(w, r)| {
            let fits = |r: &(f64, Terms)| r.1.rms_m() <= OUTLIER_RMS_FACTOR * median;
            let (theta, t) = match r {
                Some(r) if fits(&r) => r,
                // A window the start left in another basin (a clock step): searched first.
                _ => solver.search(w, start(w.t()), search_s).filter(fits)?,
            };
            WindowOffset::of(w, theta, &t, c)
        })
        .collect()
}

/// The fit of one window's own Δt (one constant) with the lever held: the profile's.
struct WindowSolver<'a> {
    problem: Problem<'a>,
    /// The lever held, estimate body frame.
    lever_m: Vector3<f64>,
    /// The mission's scale (the centre of the window's scale prior).
    scale: f64,
    /// The whole fit's secant correction c of the Jacobian (see [`SharedFit::secant_correction`]).
    jacobian_scale: f64,
}

impl WindowSolver<'_> {
    /// Window `w`'s reduced equations at the offset `offset_s`.
    fn terms(&self, w: &Window, offset_s: f64) -> Option<Terms> {
        self.problem.terms(
            w,
            &ClockShape::Constant,
            &[offset_s],
            &self.lever_m,
            false,
            self.scale,
        )
    }

    /// Newton on window `w`'s estimating equation from `offset0_s` (the step −g/(c·J), see
    /// [`solve`]): its root and the equations there; `None` when there is none (H or J not
    /// positive, or the step left exceeds the window's own error).
    fn refine(&self, w: &Window, offset0_s: f64) -> Option<(f64, Terms)> {
        let c = self.jacobian_scale;
        let mut theta = offset0_s;
        let mut terms = self.terms(w, theta)?;
        for _ in 0..MAX_ITERATIONS {
            if terms.h[(0, 0)] <= 0.0 || terms.j[(0, 0)] <= 0.0 {
                return None;
            }
            let step = (-terms.g[0] / (c * terms.j[(0, 0)])).clamp(-MAX_STEP_S, MAX_STEP_S);
            let Some((a, th, t2)) = self.halving(w, theta, step, &terms) else {
                break;
            };
            theta = th;
            terms = t2;
            if (a * step).abs() < 2e-6 {
                break;
            }
        }
        // Not a root of the window's equation (the step left exceeds the window's own error, within
        // which its estimating equation is as rough as its noise): no answer.
        let formal = formal_sigma(&terms, c)?;
        if (terms.g[0] / (c * terms.j[(0, 0)])).abs() > formal.max(1e-4) {
            return None;
        }
        Some((theta, terms))
    }

    /// The first of `step`, its half, its quarter… (eight tries) from `theta` that keeps the
    /// window's points and lowers the merit g²/H of its estimating equation (`terms` at `theta`):
    /// the fraction taken, the new offset and the equations there.
    fn halving(
        &self,
        w: &Window,
        theta: f64,
        step: f64,
        terms: &Terms,
    ) -> Option<(f64, f64, Terms)> {
        let merit = |t: &Terms| t.g[0] * t.g[0] / t.h[(0, 0)];
        let before = merit(terms);
        let mut a = 1.0;
        for _ in 0..8 {
            if let Some(t2) = self.terms(w, theta + a * step) {
                if t2.n == terms.n && t2.h[(0, 0)] > 0.0 && merit(&t2) < before {
                    return Some((a, theta + a * step, t2));
                }
            }
            a *= 0.5;
        }
        None
    }

    /// `refined` (window `w`'s root nearest the start `t0_s`), or the root of the least residual
    /// within ±`search_s` of the start when that lies in another basin and its residual is lower by
    /// more than [`SEARCH_CHI2`] of the window's own noise. A start on the wrong side of a clock
    /// step, or a first look without a lever, can leave a window at a root of its own a few hundred
    /// milliseconds off, as sharp as the right one (σ of 3 ms) and no outlier by its residual; the
    /// window then hides the step, or a constant that is not the clock's.
    fn deeper(&self, w: &Window, refined: (f64, Terms), t0_s: f64, search_s: f64) -> (f64, Terms) {
        let dof = refined.1.dof() - 1.0;
        if dof <= 0.0 {
            return refined;
        }
        let Some(best_s) = self.search_start(w, t0_s, search_s) else {
            return refined;
        };
        if (best_s - refined.0).abs() <= SEARCH_STEP_S {
            return refined;
        }
        // Per point, on as many stretches and nearly as many points: a root that leaves some of
        // the window's samples uninterpolated, or splits it at a jump (each stretch its own
        // similarity soaking up residual), is not deeper for that.
        let mean_square_m2 = |t: &Terms| t.rss / t.n as f64;
        let noise_m2 = refined.1.rss / dof;
        match self.refine(w, best_s) {
            Some(s)
                if s.1.segments == refined.1.segments
                    && 10 * s.1.n >= 9 * refined.1.n
                    && (mean_square_m2(&refined.1) - mean_square_m2(&s.1)) * refined.1.n as f64
                        > SEARCH_CHI2 * noise_m2 =>
            {
                s
            }
            _ => refined,
        }
    }

    /// Window `w`'s offset searched every [`SEARCH_STEP_S`] within ±`search_s` of `t0_s` (the least
    /// residual), then refined: for a window the start left in another basin (a clock step).
    fn search(&self, w: &Window, t0_s: f64, search_s: f64) -> Option<(f64, Terms)> {
        self.refine(w, self.search_start(w, t0_s, search_s)?)
    }

    /// The offset of least residual every [`SEARCH_STEP_S`] within ±`search_s` of `t0_s`.
    fn search_start(&self, w: &Window, t0_s: f64, search_s: f64) -> Option<f64> {
        if !search_s.is_finite() {
            return None;
        }
        let steps = (search_s / SEARCH_STEP_S).round() as i64;
        (-steps..=steps)
            .filter_map(|k| {
                let th = t0_s + k as f64 * SEARCH_STEP_S;
                self.problem
                    .mean_square_m2(w, th, &self.lever_m, self.scale)
                    .map(|ms| (th, ms))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|best| best.0)
    }
}

/// A window's least-squares error of its one offset, seconds: σ̂·√H/(c·J) (the instrumental-variable
/// form, c the whole fit's secant correction; σ̂² the residual per degree of freedom: 3 per point
/// less the 8 of each stretch's similarity and drift and the offset).
fn formal_sigma(t: &Terms, c: f64) -> Option<f64> {
    let dof = t.dof() - 1.0;
    let (h, j) = (t.h[(0, 0)], c * t.j[(0, 0)]);
    if dof <= 0.0 || h <= 0.0 || j <= 0.0 {
        return None;
    }
    Some((t.rss / dof * h).sqrt() / j)
}

/// f of the module doc: the factor that makes the windows' σ match their scatter about the line
/// through their neighbours, from a clipped mean: terms beyond [`CLIP_CHI2`] (4σ) of the current
/// factor are set aside (a step spoils two, a window in another basin three) and the mean of the
/// others, over what the clip leaves of a unit normal's square, gives the next factor; started from
/// the median (robust), iterated to its fixed point. 1 with fewer than three terms.
pub fn scatter_factor(w: &[(f64, f64, f64)]) -> f64 {
    // (t, offset, σ) in time order.
    let mut terms: Vec<f64> = Vec::new();
    for k in 1..w.len().saturating_sub(1) {
        let (t0, d0, s0) = w[k - 1];
        let (t1, d1, s1) = w[k];
        let (t2, d2, s2) = w[k + 1];
        if t2 <= t0 {
            continue;
        }
        let a = (t2 - t1) / (t2 - t0);
        let b = (t1 - t0) / (t2 - t0);
        let e = d1 - (a * d0 + b * d2);
        let v = s1 * s1 + a * a * s0 * s0 + b * b * s2 * s2;
        if v > 0.0 {
            terms.push(e * e / v);
        }
    }
    if terms.len() < 3 {
        return 1.0;
    }
    let mut sorted = terms.clone();
    sorted.sort_by(f64::total_cmp);
    let mut f2 = (sorted[sorted.len() / 2] / CHI2_1_MEDIAN).max(1e-12);
    for _ in 0..50 {
        let kept: Vec<f64> = terms
            .iter()
            .copied()
            .filter(|c| *c <= CLIP_CHI2 * f2)
            .collect();
        if kept.is_empty() {
            break;
        }
        let next = kept.iter().sum::<f64>() / kept.len() as f64 / CLIPPED_MEAN;
        if (next - f2).abs() <= 1e-9 * f2 {
            f2 = next;
            break;
        }
        f2 = next;
    }
    f2.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A simulated mission: the reference 10 Hz over 110 s, the estimate at 20 Hz stamped on its own
    /// clock (`dt_at(t)` late, t true time), its sensor `lever` from the reference point, in a
    /// rotated frame with a 2 % scale error; the body drives curves at `speed(t)`.
    #[derive(Clone)]
    struct Sim {
        ref_t: Vec<f64>,
        ref_p: Vec<Vector3<f64>>,
        t: Vec<f64>,
        p: Vec<Vector3<f64>>,
        q: Vec<UnitQuaternion<f64>>,
        jumps: Vec<(f64, f64)>,
    }

    impl Sim {
        fn new(dt_at: &dyn Fn(f64) -> f64, speed: &dyn Fn(f64) -> f64, lever: Vector3<f64>) -> Sim {
            let yaw_at = |t: f64| 0.8 * (0.05 * t).sin() + 0.3 * (0.13 * t).cos();
            // Integrate the body at 1 kHz.
            let n = 120_000;
            let mut pos = Vec::with_capacity(n);
            let mut yaws = Vec::with_capacity(n);
            let mut p = Vector3::zeros();
            for i in 0..n {
                let t = i as f64 * 0.001;
                let yaw = yaw_at(t);
                pos.push(p);
                yaws.push(yaw);
                p += Vector3::new(yaw.cos(), yaw.sin(), 0.0) * speed(t) * 0.001;
            }
            let at = |t: f64| {
                let i = ((t * 1000.0) as usize).min(n - 1);
                (pos[i], yaws[i])
            };
            let ref_t: Vec<f64> = (0..1100).map(|i| 1.0 + i as f64 * 0.1).collect();
            let ref_p: Vec<Vector3<f64>> = ref_t.iter().map(|&t| at(t).0).collect();
            let frame = UnitQuaternion::from_euler_angles(0.0, 0.0, 1.1);
            let (mut et, mut ep, mut eq) = (Vec::new(), Vec::new(), Vec::new());
            for i in 0..2300 {
                let t_true = 0.5 + i as f64 * 0.05;
                let (p, yaw) = at(t_true);
                let r = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
                et.push(t_true - dt_at(t_true));
                ep.push(frame * ((p + r * lever) * 1.02) + Vector3::new(5.0, -3.0, 1.0));
                eq.push(frame * r);
            }
            let jumps = crate::align::jumps::jumps(&et, &ep, 1.0);
            Sim {
                ref_t,
                ref_p,
                t: et,
                p: ep,
                q: eq,
                jumps,
            }
        }

        /// The estimate moved by `by` from `at_s` on (its clock): a localiser correcting itself.
        fn jumped(mut self, at_s: f64, by: Vector3<f64>) -> Sim {
            for (t, p) in self.t.iter().zip(&mut self.p) {
                if *t >= at_s {
                    *p += by;
                }
            }
            self.jumps = crate::align::jumps::jumps(&self.t, &self.p, 1.0);
            self
        }

        fn data(&self) -> PoseData<'_> {
            PoseData {
                ref_t: &self.ref_t,
                ref_p: &self.ref_p,
                estimate: PoseTrack {
                    t: &self.t,
                    p: &self.p,
                    q: &self.q,
                    jumps: &self.jumps,
                },
                params: PoseFitParams {
                    max_gap_s: 1.0,
                    window_s: None,
                },
            }
        }
    }

    /// One offset and the lever over the windows `w`, from `start_s` and no lever.
    fn constant_from(data: &PoseData<'_>, w: &[Window], start_s: f64) -> PoseFit {
        let shape = ClockShape::Constant;
        fit(data, w, shape, vec![start_s], Vector3::zeros(), true).unwrap()
    }

    /// A body driving curves with speed changes; the estimate 0.3 m ahead and 0.2 m above its
    /// reference point, in a rotated frame with a 2 % scale error and a known offset: the fit
    /// recovers the offset to well under a millisecond and the horizontal lever to a centimetre.
    #[test]
    fn recovers_offset_and_lever_on_a_noise_free_mission() {
        let dt_true = 0.137;
        let lever = Vector3::new(0.3, 0.0, 0.2);
        let sim = Sim::new(&|_| dt_true, &|t| 1.0 + 0.5 * (0.21 * t).sin(), lever);
        let data = sim.data();
        let w = data.windows();
        let f = constant_from(&data, &w, 0.1);
        assert!((f.theta[0] - dt_true).abs() < 5e-4, "{:?}", f.theta);
        // The horizontal lever, scaled like the estimate; the vertical one is invisible without tilt
        // (the prior keeps it at 0).
        let want = Vector3::new(lever.x, lever.y, 0.0) * 1.02;
        assert!((f.lever_m - want).norm() < 0.01, "{:?}", f.lever_m);
        assert!(f.converged);
    }

    /// Two position jumps of the estimate inside windows (0.8 m and 0.4 m) are two new frames, not
    /// clock events: the offset stays within half a millisecond and the windows holding them are
    /// fitted.
    #[test]
    fn a_jump_of_the_estimate_does_not_move_the_offset() {
        let dt_true = 0.137;
        let lever = Vector3::new(0.3, 0.0, 0.2);
        let sim = Sim::new(&|_| dt_true, &|t| 1.0 + 0.5 * (0.21 * t).sin(), lever)
            .jumped(31.03, Vector3::new(0.6, -0.5, 0.1))
            .jumped(79.51, Vector3::new(-0.3, 0.25, 0.0));
        assert_eq!(sim.jumps.len(), 2, "{:?}", sim.jumps);
        let data = sim.data();
        let w = data.windows();
        let f = constant_from(&data, &w, 0.1);
        assert!((f.theta[0] - dt_true).abs() < 5e-4, "{:?}", f.theta);
        // The windows holding the jumps are fitted, not set aside (noise-free, the residuals are
        // nanometres everywhere, so which window counts as an outlier is numerical noise).
        for jump_s in [31.03 + dt_true, 79.51 + dt_true] {
            assert!(f
                .windows
                .iter()
                .any(|w| w.t_start < jump_s && jump_s < w.t_end));
        }
        assert!(f.converged);
    }

    /// White noise on the reference, drawn again and again: the formal σ of Δt is the spread of its
    /// answers; the σ the fit reports (the jackknife over five windows, floored by the formal σ) is
    /// never below it and at most two thirds above it.
    #[test]
    fn the_sigma_of_the_offset_is_the_spread_of_its_answers() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let dt_true = 0.137;
        let lever = Vector3::new(0.3, 0.0, 0.2);
        let clean = Sim::new(&|_| dt_true, &|t| 1.0 + 0.5 * (0.21 * t).sin(), lever);
        let noise = Normal::new(0.0, 0.03).unwrap();
        let (mut errors2, mut sigmas2, mut formal2) = (0.0, 0.0, 0.0);
        for seed in 0..40 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let mut sim = clean.clone();
            for p in &mut sim.ref_p {
                *p += Vector3::from_fn(|_, _| noise.sample(&mut rng));
            }
            let data = sim.data();
            let w = data.windows();
            let f = constant_from(&data, &w, 0.1);
            let problem = data.problem();
            let shared = SharedFit {
                problem: &problem,
                windows: &f.windows,
                shape: &ClockShape::Constant,
                with_lever: true,
                m: 1,
                p: 4,
            };
            let terms = shared.eval(&f.theta, &f.lever_m, f.scale);
            let l = lever_weight(&terms);
            let formal = shared
                .formal_covariance(&terms, &f.lever_m, l, f.jacobian_scale)
                .unwrap();
            assert!(f.theta_sigma[0] >= 0.999 * formal[(0, 0)].sqrt());
            errors2 += (f.theta[0] - dt_true).powi(2);
            sigmas2 += f.theta_sigma[0].powi(2);
            formal2 += formal[(0, 0)];
        }
        // White residuals: the formal σ is the spread itself; the reported one (the jackknife of
        // five windows where it is larger) somewhat above it.
        let formal = (errors2 / formal2).sqrt();
        assert!(
            (0.75..1.33).contains(&formal),
            "RMS error / RMS formal σ {formal}"
        );
        let reported = (errors2 / sigmas2).sqrt();
        assert!(
            (0.6..1.0).contains(&reported),
            "RMS error / RMS σ {reported}"
        );
    }

    /// At a constant walking speed a clock step leaves the speed signals nothing to locate it by;
    /// the positions do: the change time is found to a fraction of a second.
    #[test]
    fn locates_a_step_at_constant_speed() {
        let lever = Vector3::new(0.3, 0.0, 0.2);
        let dt = |t: f64| if t < 60.0 { 0.437 } else { 0.137 };
        let sim = Sim::new(&dt, &|_| 0.5, lever);
        let located = locate_change(
            &sim.data(),
            &(lever * 1.02),
            1.02,
            (0.437, 0.137),
            (40.0, 80.0),
        )
        .unwrap();
        assert!((located - 60.0).abs() < 0.5, "{located}");
    }

    #[test]
    fn scatter_factor_of_honest_sigmas_is_near_one() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let n = Normal::new(0.0, 1.0).unwrap();
        let w: Vec<(f64, f64, f64)> = (0..4000)
            .map(|k| {
                (
                    k as f64 * 20.0,
                    0.3 + 1e-5 * k as f64 + 0.004 * n.sample(&mut rng),
                    0.004,
                )
            })
            .collect();
        let f = scatter_factor(&w);
        assert!((f - 1.0).abs() < 0.05, "{f}");
        let w3: Vec<(f64, f64, f64)> = w.iter().map(|&(t, d, s)| (t, d, s / 3.0)).collect();
        assert!((scatter_factor(&w3) - 3.0).abs() < 0.15);
    }
}
