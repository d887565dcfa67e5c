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
//! are not bridged). A window's scale is held to the mission's by a prior worth [`SCALE_PRIOR_M`] of
//! spread per sample, so a window that stands or turns in place (whose positions barely spread)
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
//! recorder adds to every stamp is, by definition, part of the offset).
//!
//! Each window's own Δt (the offset profile, [`profile`]) comes from the same fit with D held and one
//! θ per window. Its σ is the window's least-squares error σ̂_k/√H_k (σ̂_k² = its residual per degree
//! of freedom) times one factor f for the mission, from the windows' scatter about the line through
//! their neighbours: e_k = Δt_k − (interpolation of Δt_{k−1} and Δt_{k+1} at t_k) is free of any
//! constant and any linear drift, so under honest σ each e_k/σ(e_k) is a unit normal; f² is the
//! mean of those squares with the ones beyond 4σ set aside ([`CLIP_CHI2`]: a step, which spoils
//! two, does not decide it). This is what makes a drift or a step, judged against the windows' σ, a claim the
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
/// A window whose residual RMS exceeds this many times the median window's is left out (a jump of
/// the estimate inside it: a localiser correcting itself is not a clock event).
const OUTLIER_RMS_FACTOR: f64 = 4.0;
/// The variance inflation of Δt by the lever above which the two are called inseparable.
pub const INSEPARABLE_VIF: f64 = 25.0;

/// The estimate's poses: times on its own clock (seconds from the common origin), positions and
/// orientations (body to its frame).
#[derive(Clone, Copy)]
pub struct PoseTrack<'a> {
    pub t: &'a [f64],
    pub p: &'a [Vector3<f64>],
    pub q: &'a [UnitQuaternion<f64>],
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
        let (ra, rb) = (
            self.track.q[a].to_rotation_matrix().into_inner(),
            self.track.q[b].to_rotation_matrix().into_inner(),
        );
        Some(At {
            p: self.track.p[a] + (self.track.p[b] - self.track.p[a]) * f,
            r: ra + (rb - ra) * f,
        })
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
}

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
struct Pt {
    r: Vector3<f64>,
    e: Vector3<f64>,
    u: Vector3<f64>,
    du: Vector3<f64>,
    dw: Vector3<f64>,
    rhat: Matrix3<f64>,
    t: f64,
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
        let m = shape.len();
        let p = m + if with_lever { 3 } else { 0 };
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
            });
        }
        let n = pts.len();
        if n < MIN_WINDOW_SAMPLES {
            return None;
        }
        let nf = n as f64;
        let rbar = pts.iter().map(|q| q.r).sum::<Vector3<f64>>() / nf;
        let ubar = pts.iter().map(|q| q.u).sum::<Vector3<f64>>() / nf;
        let tbar = pts.iter().map(|q| q.t).sum::<f64>() / nf;
        let s_rr: f64 = pts.iter().map(|q| (q.r - rbar).norm_squared()).sum();
        // The similarity (rotation, Σ r̃·R·ũ, Σ|ũ|²) of centred points ũ_i = `at(i)`.
        let similarity = |at: &dyn Fn(usize) -> Vector3<f64>| {
            let mut cov = Matrix3::zeros();
            let mut s_uu = 0.0;
            for (i, q) in pts.iter().enumerate() {
                let du = at(i);
                cov += (q.r - rbar) * du.transpose();
                s_uu += du.norm_squared();
            }
            let rot = rotation_of(&cov);
            ((rot), (rot.transpose() * cov).trace(), s_uu)
        };
        let lambda = nf * SCALE_PRIOR_M * SCALE_PRIOR_M;
        let scale_of = |tr: f64, s_uu: f64| ((tr + lambda * s_bar) / (s_uu + lambda)).max(1e-3);
        let (mut rot, mut tr, mut s_uu) = similarity(&|i| pts[i].u - ubar);
        // The estimate's heading drifting within the window at a rate b about its vertical: its
        // positions carry b·∫(τ − t̄)·ẑ × dê (integrated over the window's own increments), which
        // no rotation of the whole window removes.
        let up = rot.transpose() * Vector3::z();
        let mut drift = Vec::with_capacity(n);
        let mut acc = Vector3::zeros();
        drift.push(acc);
        for k in 1..n {
            let mid = 0.5 * (pts[k - 1].t + pts[k].t) - tbar;
            acc += up.cross(&(pts[k].e - pts[k - 1].e)) * mid;
            drift.push(acc);
        }
        let dbar = drift.iter().sum::<Vector3<f64>>() / nf;
        for w in &mut drift {
            *w -= dbar;
        }
        let d_ww: f64 = drift.iter().map(|w| w.norm_squared()).sum();
        let mut b = 0.0;
        let mut s = scale_of(tr, s_uu);
        if d_ww > 0.0 {
            for _ in 0..2 {
                // b given the similarity, then the similarity given b.
                let num: f64 = pts
                    .iter()
                    .zip(&drift)
                    .map(|(q, w)| (rot * w).dot(&(s * (rot * (q.u - ubar)) - (q.r - rbar))))
                    .sum();
                b = num / (s * (d_ww + nf * DRIFT_PRIOR_M2S2 / (s * s)));
                (rot, tr, s_uu) = similarity(&|i| pts[i].u - ubar - drift[i] * b);
                s = scale_of(tr, s_uu);
            }
        }
        // Nuisance: translation (3), rotation (3, δω applied on the left), scale (1), heading drift
        // rate (1).
        let mut ntn = SMatrix::<f64, 8, 8>::zeros();
        let mut ntv = DMatrix::<f64>::zeros(8, p);
        let mut nte = SMatrix::<f64, 8, 1>::zeros();
        let mut ntx = DMatrix::<f64>::zeros(8, p);
        let mut vtv = DMatrix::<f64>::zeros(p, p);
        let mut vtx = DMatrix::<f64>::zeros(p, p);
        let mut vte = DVector::<f64>::zeros(p);
        let mut rss = 0.0;
        let mut phi = vec![0.0; m];
        let mut v = vec![Vector3::zeros(); p];
        let mut x = vec![Vector3::zeros(); p];
        for (q, dw) in pts.iter().zip(&drift) {
            let wv = s * (rot * (q.u - ubar - dw * b));
            let e = wv + rbar - q.r;
            rss += e.norm_squared();
            // Columns of ∂model/∂nuisance.
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
            shape.basis(q.t, &mut phi);
            let sdu = s * (rot * q.du);
            let sdw = s * (rot * q.dw);
            for (k, f) in phi.iter().enumerate() {
                v[k] = sdu * *f;
                x[k] = sdw * *f;
            }
            if with_lever {
                let sr = s * (rot * q.rhat);
                for c in 0..3 {
                    v[m + c] = -sr.column(c).into_owned();
                    x[m + c] = v[m + c];
                }
            }
            for a in 0..8 {
                nte[a] += cols[a].dot(&e);
                for b in a..8 {
                    ntn[(a, b)] += cols[a].dot(&cols[b]);
                }
                for b in 0..p {
                    ntv[(a, b)] += cols[a].dot(&v[b]);
                    ntx[(a, b)] += cols[a].dot(&x[b]);
                }
            }
            for (a, va) in v.iter().enumerate() {
                vte[a] += va.dot(&e);
                for b in 0..p {
                    if b >= a {
                        vtv[(a, b)] += va.dot(&v[b]);
                    }
                    vtx[(a, b)] += va.dot(&x[b]);
                }
            }
        }
        for a in 0..8 {
            for b in 0..a {
                ntn[(a, b)] = ntn[(b, a)];
            }
        }
        for a in 0..p {
            for b in 0..a {
                vtv[(a, b)] = vtv[(b, a)];
            }
        }
        // The priors: residuals √λ·(s − s̄) and √λ_b·b.
        ntn[(6, 6)] += lambda;
        nte[6] += lambda * (s - s_bar);
        ntn[(7, 7)] += nf * DRIFT_PRIOR_M2S2;
        nte[7] += nf * DRIFT_PRIOR_M2S2 * b;
        // A rotation or a drift the window does not determine (its points on a line, standing)
        // stays put.
        let ridge = 1e-9 * (0..8).map(|a| ntn[(a, a)]).fold(0.0, f64::max);
        for a in 0..8 {
            ntn[(a, a)] += ridge;
        }
        let inv = ntn.try_inverse()?;
        let ntn_inv = DMatrix::from_fn(8, 8, |a, b| inv[(a, b)]);
        let xv = &ntn_inv * &ntv;
        let h = &vtv - ntv.transpose() * &xv;
        let j = &vtx - xv.transpose() * &ntx;
        let nte_d = DVector::from_fn(8, |a, _| nte[a]);
        let g = &vte - xv.transpose() * nte_d;
        Some(Terms {
            n,
            rss,
            h,
            j,
            g,
            tr,
            s_uu,
            s_rr,
        })
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
    /// Jackknife standard errors of θ and of D (D's when fitted).
    pub theta_sigma: Vec<f64>,
    pub lever_sigma_m: Option<Vector3<f64>>,
    /// The jackknife covariance of (θ, D).
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
                .map(|t| (t.rss / t.n as f64).sqrt())
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
    let p = m + if with_lever { 3 } else { 0 };
    let eval = |theta: &[f64], d: &Vector3<f64>, s_bar: f64| -> Vec<Option<Terms>> {
        windows
            .par_iter()
            .map(|w| problem.terms(w, shape, theta, d, with_lever, s_bar))
            .collect()
    };
    let (mut theta, mut d) = (theta0, lever0);
    let mut s_bar = 1.0;
    let mut terms = eval(&theta, &d, s_bar);
    if terms.iter().flatten().count() < 3 {
        return None;
    }
    let mut converged = false;
    let mut iterations = 0;
    let lever_weight = |terms: &[Option<Terms>]| {
        let (rss, n) = terms
            .iter()
            .flatten()
            .fold((0.0, 0usize), |(r, n), t| (r + t.rss, n + t.n));
        rss / (3.0 * n.max(1) as f64) / (LEVER_PRIOR_M * LEVER_PRIOR_M)
    };
    // The reduced equations summed over the windows, the lever's prior (weight `l`) added: the
    // Newton step −J⁻¹·g, the gradient and the scales of the merit.
    let normal = |terms: &[Option<Terms>], d: &Vector3<f64>, l: f64, c: f64, lambda: f64| {
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
        if with_lever {
            for c in 0..3 {
                h[(m + c, m + c)] += l;
                j[(m + c, m + c)] += l;
                g[m + c] += l * d[c];
            }
        }
        for k in 0..m {
            j.column_mut(k).scale_mut(c);
        }
        // Levenberg–Marquardt: λ·diag(H) added, more of it after a failed step.
        for k in 0..p {
            j[(k, k)] += lambda * h[(k, k)];
        }
        let step = j.lu().solve(&g).map(|x| -x);
        (step, g, h.diagonal())
    };
    // The merit of the estimating equations: Σ g_k²/H_kk with the current iterate's scales (the
    // Newton direction descends it).
    let merit = |g: &DVector<f64>, scales: &DVector<f64>| {
        g.iter()
            .zip(scales.iter())
            .map(|(g, h)| if *h > 0.0 { g * g / h } else { 0.0 })
            .sum::<f64>()
    };
    // The Jacobian's clock columns are a derivative over a wider stencil, which misses part of the
    // fast motion (a gait) the residual follows: scaled by `c`, a secant correction learnt from
    // successive steps (a step undone by the next one means the Jacobian was too small).
    let mut c = 1.0;
    let mut lambda = 1e-3;
    let mut previous: Option<DVector<f64>> = None;
    for it in 0..MAX_ITERATIONS {
        iterations = it + 1;
        // The mission's scale from the windows' evidence, in the first iterations (the windows'
        // equations then re-evaluated with it, so that every step compares like with like).
        if it < 3 {
            let (tr, suu) = terms
                .iter()
                .flatten()
                .fold((0.0, 0.0), |(a, b), t| (a + t.tr, b + t.s_uu));
            if suu > 0.0 && tr > 0.0 && (tr / suu - s_bar).abs() > 1e-6 {
                s_bar = tr / suu;
                terms = eval(&theta, &d, s_bar);
            }
        }
        let l = lever_weight(&terms);
        let (Some(mut step), g0, scales) = normal(&terms, &d, l, c, lambda) else {
            return None;
        };
        // The secant correction, once the lever has settled, from a step that undoes part of the
        // last (the Jacobian was too small).
        if let (true, Some(last)) = (it >= 2, &previous) {
            let (new, old) = (step.rows(0, m), last.rows(0, m));
            let norm = old.dot(&old);
            let rho = new.dot(&old) / norm;
            if norm.sqrt() > 1e-5 && rho < 0.0 {
                c = (c * (1.0 - rho)).clamp(1.0, 4.0);
                if let (Some(s), ..) = normal(&terms, &d, l, c, lambda) {
                    step = s;
                }
            }
        }
        let before = merit(&g0, &scales);
        // The instrument is not the cost's exact gradient, so the steps solve the estimating
        // equations g = 0: a step is kept when it lowers their merit; otherwise more damping.
        let mut accepted = false;
        for _ in 0..10 {
            let largest = (0..m).map(|k| step[k].abs()).fold(0.0, f64::max);
            let a = if largest > MAX_STEP_S {
                MAX_STEP_S / largest
            } else {
                1.0
            };
            let t2: Vec<f64> = (0..m).map(|k| theta[k] + a * step[k]).collect();
            let d2 = if with_lever {
                d + Vector3::new(step[m], step[m + 1], step[m + 2]) * a
            } else {
                d
            };
            let terms2 = eval(&t2, &d2, s_bar);
            if terms2.iter().flatten().count() == terms.iter().flatten().count()
                && merit(&normal(&terms2, &d2, l, c, 0.0).1, &scales) < before
            {
                theta = t2;
                d = d2;
                terms = terms2;
                accepted = true;
                step *= a;
                lambda = (lambda / 3.0).max(1e-6);
                break;
            }
            lambda *= 10.0;
            match normal(&terms, &d, l, c, lambda) {
                (Some(s), ..) => step = s,
                _ => break,
            }
        }
        let small = (0..m).all(|k| step[k].abs() < 2e-6)
            && (!with_lever || (m..p).all(|k| step[k].abs() < 2e-5));
        if !accepted || small {
            break;
        }
        previous = Some(step);
    }
    let l = lever_weight(&terms);
    let remaining = normal(&terms, &d, l, c, 0.0).0;
    // The jackknife over windows: each left out by one Newton step of the reduced equations.
    let used: Vec<(&Window, &Terms)> = windows
        .iter()
        .zip(&terms)
        .filter_map(|(w, t)| t.as_ref().map(|t| (w, t)))
        .collect();
    let k = used.len();
    let (mut h, mut j) = (DMatrix::<f64>::zeros(p, p), DMatrix::<f64>::zeros(p, p));
    for (_, t) in &used {
        h += &t.h;
        j += &t.j;
    }
    if with_lever {
        for c in 0..3 {
            h[(m + c, m + c)] += l;
            j[(m + c, m + c)] += l;
        }
    }
    for k in 0..m {
        j.column_mut(k).scale_mut(c);
    }
    let deltas: Vec<DVector<f64>> = used
        .iter()
        .filter_map(|(_, t)| {
            let mut tj = t.j.clone();
            for k in 0..m {
                tj.column_mut(k).scale_mut(c);
            }
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
    let sig = |i: usize| cov[(i, i)].max(0.0).sqrt();
    // Converged: the Newton step left is small beside the parameters' own uncertainty (the
    // estimating equations are as rough as their noise at that scale).
    if let Some(step) = remaining {
        converged = (0..m).all(|k| step[k].abs() <= (0.5 * sig(k)).max(1e-4))
            && (!with_lever || (m..p).all(|k| step[k].abs() <= (0.5 * sig(k)).max(1e-3)));
    }
    let variance_inflation = if with_lever {
        // Var(θ₀) with D free over Var(θ₀) with D held, from the normal equations.
        h.clone()
            .try_inverse()
            .map_or(f64::INFINITY, |inv| inv[(0, 0)] * h[(0, 0)])
    } else {
        1.0
    };
    Some(PoseFit {
        shape: shape.clone(),
        theta,
        lever_m: d,
        theta_sigma: (0..m).map(sig).collect(),
        lever_sigma_m: with_lever.then(|| Vector3::new(sig(m), sig(m + 1), sig(m + 2))),
        covariance: cov,
        variance_inflation,
        windows: used.iter().map(|(w, _)| (*w).clone()).collect(),
        outliers: Vec::new(),
        rms_m: used
            .iter()
            .map(|(_, t)| (t.rss / t.n as f64).sqrt())
            .collect(),
        scale: s_bar,
        jacobian_scale: c,
        iterations,
        converged: converged && k >= 3,
    })
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

/// Each window's own Δt with the lever `lever` held, started from `start(t)` (a window that fails
/// from there is searched ±`search_s` first). Windows that do not converge are left out.
pub fn profile(
    data: &PoseData<'_>,
    windows: &[Window],
    lever: Vector3<f64>,
    (scale, c): (f64, f64),
    start: &(dyn Fn(f64) -> f64 + Sync),
    search_s: f64,
) -> Vec<WindowOffset> {
    let problem = data.problem();
    let shape = ClockShape::Constant;
    let one = |w: &Window, theta0: f64| -> Option<(f64, Terms)> {
        let mut theta = theta0;
        let mut terms = problem.terms(w, &shape, &[theta], &lever, false, scale)?;
        // The merit g²/H of the estimating equation, the Newton step −g/J (see `solve`).
        let merit = |t: &Terms| t.g[0] * t.g[0] / t.h[(0, 0)];
        for _ in 0..MAX_ITERATIONS {
            if terms.h[(0, 0)] <= 0.0 || terms.j[(0, 0)] <= 0.0 {
                return None;
            }
            let step = (-terms.g[0] / (c * terms.j[(0, 0)])).clamp(-MAX_STEP_S, MAX_STEP_S);
            let before = merit(&terms);
            let mut a = 1.0;
            let mut next = None;
            for _ in 0..8 {
                if let Some(t2) =
                    problem.terms(w, &shape, &[theta + a * step], &lever, false, scale)
                {
                    if t2.n == terms.n && t2.h[(0, 0)] > 0.0 && merit(&t2) < before {
                        next = Some((theta + a * step, t2));
                        break;
                    }
                }
                a *= 0.5;
            }
            let Some((th, t2)) = next else { break };
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
    };
    let raw: Vec<Option<(f64, Terms)>> = windows.par_iter().map(|w| one(w, start(w.t()))).collect();
    let mut rms: Vec<f64> = raw
        .iter()
        .flatten()
        .map(|(_, t)| (t.rss / t.n as f64).sqrt())
        .collect();
    if rms.is_empty() {
        return Vec::new();
    }
    rms.sort_by(f64::total_cmp);
    let median = rms[rms.len() / 2];
    windows
        .par_iter()
        .zip(raw)
        .filter_map(|(w, r)| {
            let fits =
                |r: &(f64, Terms)| (r.1.rss / r.1.n as f64).sqrt() <= OUTLIER_RMS_FACTOR * median;
            let r = match r {
                Some(r) if fits(&r) => r,
                _ => {
                    // A window the start left in another basin (a clock step): searched first.
                    let t0 = start(w.t());
                    let steps = (search_s / 0.05).round() as i64;
                    let best = (-steps..=steps)
                        .filter_map(|k| {
                            let th = t0 + k as f64 * 0.05;
                            problem
                                .terms(w, &shape, &[th], &lever, false, scale)
                                .map(|t| (th, t.rss))
                        })
                        .min_by(|a, b| a.1.total_cmp(&b.1))?;
                    let r = one(w, best.0)?;
                    if !fits(&r) {
                        return None;
                    }
                    r
                }
            };
            let (theta, t) = r;
            Some(WindowOffset {
                t: w.t(),
                offset_s: theta,
                formal_sigma_s: formal_sigma(&t, c)?,
                rms_m: (t.rss / t.n as f64).sqrt(),
                quality: if t.s_rr > 0.0 {
                    (1.0 - t.rss / t.s_rr).clamp(0.0, 1.0)
                } else {
                    0.0
                },
            })
        })
        .collect()
}

/// A window's least-squares error of its one offset, seconds: σ̂·√H/(c·J) (the instrumental-variable
/// form, c the whole fit's secant correction; σ̂² the residual per degree of freedom: 3 per point less the 8 of the similarity and drift
/// and the offset).
fn formal_sigma(t: &Terms, c: f64) -> Option<f64> {
    let dof = (3 * t.n) as f64 - 9.0;
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

    /// A body driving curves with speed changes; the estimate 0.3 m ahead and 0.2 m above its
    /// reference point, in a rotated frame with a 2 % scale error and a known offset: the fit
    /// recovers the offset to well under a millisecond and the horizontal lever to a centimetre.
    #[test]
    fn recovers_offset_and_lever_on_a_noise_free_mission() {
        let dt_true = 0.137;
        let lever = Vector3::new(0.3, 0.0, 0.2);
        let body = |t: f64| {
            let v = 1.0 + 0.5 * (0.21 * t).sin();
            let yaw = 0.8 * (0.05 * t).sin() + 0.3 * (0.13 * t).cos();
            (v, yaw)
        };
        // Integrate the body at 1 kHz.
        let n = 120_000;
        let mut pos = Vec::with_capacity(n);
        let mut yaws = Vec::with_capacity(n);
        let mut p = Vector3::zeros();
        for i in 0..n {
            let t = i as f64 * 0.001;
            let (v, yaw) = body(t);
            pos.push(p);
            yaws.push(yaw);
            p += Vector3::new(yaw.cos(), yaw.sin(), 0.0) * v * 0.001;
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
            et.push(t_true - dt_true);
            ep.push(frame * ((p + r * lever) * 1.02) + Vector3::new(5.0, -3.0, 1.0));
            eq.push(frame * r);
        }
        let data = PoseData {
            ref_t: &ref_t,
            ref_p: &ref_p,
            estimate: PoseTrack {
                t: &et,
                p: &ep,
                q: &eq,
            },
            params: PoseFitParams {
                max_gap_s: 1.0,
                window_s: None,
            },
        };
        let w = data.windows();
        let f = fit(
            &data,
            &w,
            ClockShape::Constant,
            vec![0.1],
            Vector3::zeros(),
            true,
        )
        .unwrap();
        assert!((f.theta[0] - dt_true).abs() < 5e-4, "{:?}", f.theta);
        // The horizontal lever, scaled like the estimate; the vertical one is invisible without tilt
        // (the prior keeps it at 0).
        let want = Vector3::new(lever.x, lever.y, 0.0) * 1.02;
        assert!((f.lever_m - want).norm() < 0.01, "{:?}", f.lever_m);
        assert!(f.converged);
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
