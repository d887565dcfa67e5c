//! One window's problem: the estimate's poses interpolated at the reference's times under a clock
//! and a lever ([`Problem::points`]), the window's similarity and heading drift fitted to them
//! ([`WindowPoints`], [`Nuisance`]) and eliminated from its normal equations ([`Terms`],
//! [`NormalSums`]). Both fits build on it: the whole mission's (`shared.rs`) sums these equations,
//! the profile (`profile.rs`) solves them one window at a time; nothing here steps the clock or
//! the lever. Also here: how the mission is cut into windows ([`windows`]), and
//! [`locate_change`], which fits the same similarities to the two sides of a clock change.

use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, Vector3};

use crate::stats::{median_step, stamp_jitter_s};

use super::sampler::{At, Sampler, Taps};
use super::{ClockShape, PoseData, DRIFT_PRIOR_M2S2, MIN_WINDOW_SAMPLES, PROBE_JITTERS, WINDOW_S};

/// The half-step h of the instrument's central differences: one of the estimate's periods, at
/// least 50 ms (a difference over shorter times is mostly the estimate's noise: 3 mm of noise over
/// ±10 ms is 0.2 m/s) and at most 0.25 s, seconds. One period, not more: a difference over ±h sees
/// motion at f in proportion to sin(2πfh)/(2πfh), and a legged robot's gait (2–5 Hz) is the
/// sharpest timing signal it has; over two periods of a 10 Hz estimate that response is 0.2 at
/// 2 Hz and negative at 3.5 Hz, and the fit lost the gait. When h is a whole number of periods
/// the samples the difference shares with its point do not correlate their noise (see
/// `sampler.rs`); between 20 and 80 Hz the 50 ms floor is not always one (25–30 Hz: 1.25–1.5
/// periods; 50 Hz: 2.5), and the instrument's noise then correlates a little with the point's
/// (the test there shows it at half a period); the validation's 50 Hz missions include it, its
/// rates probe no further.
const STENCIL_MIN_S: f64 = 0.05;
const STENCIL_MAX_S: f64 = 0.25;
/// A window's search compares its residual on every ⌊n/SEARCH_POINTS⌋-th of its n reference
/// samples (this many to twice as many; all of a window of fewer), and the root it finds is then
/// refined on all of them. A stretch between jumps counts [`MIN_SEGMENT_SAMPLES`] of those taken.
const SEARCH_POINTS: usize = 32;

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
pub(super) struct Terms {
    pub(super) n: usize,
    pub(super) rss: f64,
    /// The estimating equations g = Σ v·e over the shared parameters, v the instrument (∂model/∂θ
    /// from central differences over ±h, whose noise is uncorrelated with the point's own although
    /// they share samples where h is a whole number of periods: see [`STENCIL_MIN_S`]); h = Σ v·v
    /// (the formal σ's middle); j = Σ v·w with w the same derivative over two of the estimate's
    /// periods more (`PoseFitParams::jacobian_periods`; one where the fit cannot be made with
    /// two), mostly other samples than v's (the cubics at the ends share one or two; the long
    /// interpolation's more, which can slow the steps but does not move the root g = 0): the Newton
    /// Jacobian of g, nearly free of the bias Σ v·v takes from v's noise, which steps the
    /// fits (the error bar measures the clock columns instead: `SharedFit::jacobians`). The
    /// window's similarity and drift eliminated (Schur complement).
    pub(super) h: DMatrix<f64>,
    pub(super) j: DMatrix<f64>,
    pub(super) g: DVector<f64>,
    /// Σ (p_ref − p̄_ref)·R(u − ū) and Σ|u − ū|²: the window's scale evidence.
    pub(super) tr: f64,
    pub(super) s_uu: f64,
    /// Σ|p_ref − p̄_ref|²: what the window's motion explains.
    pub(super) s_rr: f64,
    /// The stretches between the estimate's jumps the window's points fall in, each with its own
    /// similarity and drift (1 without a jump).
    pub(super) segments: usize,
}

/// A stretch of a window between two of the estimate's jumps holds at least this many reference
/// samples to be fitted (its similarity and drift are 8 parameters); fewer are left out.
const MIN_SEGMENT_SAMPLES: usize = 6;

/// The problem: reference samples, the estimate's poses, the windows.
pub(super) struct Problem<'a> {
    ref_t: &'a [f64],
    ref_p: &'a [Vector3<f64>],
    sampler: Sampler<'a>,
    /// The half-steps of the central differences for ∂u/∂Δt, seconds (see [`Terms`]): the
    /// instrument's, and the Jacobian's (`jacobian_periods` of the estimate's periods more: mostly
    /// other samples).
    h: f64,
    hw: f64,
    /// The windows' scale prior, metres of spread per sample
    /// ([`super::PoseFitParams::scale_prior_m`]).
    scale_prior_m: f64,
    /// The reference samples averaged into one point by [`Problem::averaged`] (1: none), and the
    /// reference's median period, seconds.
    block: usize,
    ref_period_s: f64,
    /// The half-width over which the error bar measures the equations' slope in Δt, seconds: half
    /// the instrument's half-step, or [`PROBE_JITTERS`] times the estimate's stamp jitter where
    /// that is wider ([`Problem::probe_s`]).
    probe_s: f64,
    /// Gauss–Newton iterations at most ([`super::PoseFitParams::max_iterations`]).
    max_iterations: usize,
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
    pub(super) fn dof(&self) -> f64 {
        (3 * self.n) as f64 - 8.0 * self.segments as f64
    }

    /// The window's residual RMS, metres.
    pub(super) fn rms_m(&self) -> f64 {
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
fn segment_terms(
    pts: Vec<Pt>,
    shape: &ClockShape,
    with_lever: bool,
    (s_bar, prior_m): (f64, f64),
) -> Option<Terms> {
    let m = shape.len();
    let p = m + if with_lever { 3 } else { 0 };
    let n = pts.len();
    let win = WindowPoints::new(pts, prior_m);
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
    /// Gauss–Newton iterations at most of a fit of the shared parameters.
    pub(super) fn max_iterations(&self) -> usize {
        self.max_iterations
    }

    /// The reduced normal equations of window `w` for the clock `shape`/`theta` (its parameters
    /// first) and, when `with_lever`, the lever D (the last three); `d` is the lever used either way.
    /// `s_bar`: the mission's scale (the prior's centre).
    pub(super) fn terms(
        &self,
        w: &Window,
        shape: &ClockShape,
        theta: &[f64],
        d: &Vector3<f64>,
        with_lever: bool,
        s_bar: f64,
    ) -> Option<Terms> {
        let pts = self.averaged(self.points(w, shape, theta, d));
        if pts.len() < MIN_WINDOW_SAMPLES {
            return None;
        }
        if pts.first().map(|q| q.seg) == pts.last().map(|q| q.seg) {
            return segment_terms(pts, shape, with_lever, (s_bar, self.scale_prior_m));
        }
        // A jump of the estimate within the window: each stretch between jumps its own similarity
        // and drift, their reduced equations summed (the stretches share only θ and D).
        let mut total: Option<Terms> = None;
        for run in stretches(pts) {
            let Some(t) = segment_terms(run, shape, with_lever, (s_bar, self.scale_prior_m)) else {
                continue;
            };
            total = Some(match total {
                None => t,
                Some(sum) => sum.plus(t),
            });
        }
        total.filter(|t| t.n >= MIN_WINDOW_SAMPLES)
    }

    /// `pts` (in time order) averaged over blocks of `block` consecutive reference samples: the
    /// band the estimate cannot represent taken out of both sides of the model alike (see
    /// [`super::AVERAGE_BELOW_HZ`]). A block holds samples of one stretch between jumps, none
    /// dropped between them (a gap, a point the estimate could not be interpolated at); samples
    /// that make no whole block are left out. Unchanged when the block is one sample, or when the
    /// window could not keep [`MIN_WINDOW_SAMPLES`] blocks (a short window, a very slow estimate
    /// against a dense reference): such a window is compared point by point.
    fn averaged(&self, pts: Vec<Pt>) -> Vec<Pt> {
        let k = self.block;
        if k < 2 || pts.len() < k * MIN_WINDOW_SAMPLES {
            return pts;
        }
        let kf = k as f64;
        // k consecutive samples span k − 1 periods; half a period more allows for jittered stamps.
        let span_s = (kf - 0.5) * self.ref_period_s;
        let mean_v =
            |g: &[Pt], f: fn(&Pt) -> Vector3<f64>| g.iter().map(f).sum::<Vector3<f64>>() / kf;
        let mut out: Vec<Pt> = Vec::with_capacity(pts.len() / k + 1);
        let mut i = 0;
        while i + k <= pts.len() {
            let g = &pts[i..i + k];
            if g.iter().all(|q| q.seg == g[0].seg) && g[k - 1].t - g[0].t <= span_s {
                out.push(Pt {
                    r: mean_v(g, |q| q.r),
                    e: mean_v(g, |q| q.e),
                    u: mean_v(g, |q| q.u),
                    du: mean_v(g, |q| q.du),
                    dw: mean_v(g, |q| q.dw),
                    rhat: g.iter().map(|q| q.rhat).sum::<Matrix3<f64>>() / kf,
                    t: g.iter().map(|q| q.t).sum::<f64>() / kf,
                    seg: g[0].seg,
                });
                i += k;
            } else {
                i += 1;
            }
        }
        out
    }

    /// The instrument's half-step h, seconds (see [`STENCIL_MIN_S`]).
    pub(super) fn half_step_s(&self) -> f64 {
        self.h
    }

    /// The half-width of the shift of Δt over which the error bar measures the equations' slope,
    /// seconds: half the instrument's half-step (25 ms at 20 Hz and above, 50 ms at 10 Hz, 125 ms
    /// below 4 Hz), widened to [`PROBE_JITTERS`] times the estimate's stamp jitter where that is
    /// more (see [`PROBE_JITTERS`]).
    pub(super) fn probe_s(&self) -> f64 {
        self.probe_s
    }

    /// Window `w`'s residual at the constant offset `offset_s` with the lever `d`: the mean squared
    /// residual per point once each stretch's similarity is fitted (scale held about `s_bar`; no
    /// heading drift), metres², on [`SEARCH_POINTS`] to twice as many of its samples. What a search over
    /// offsets compares: one interpolation per point instead of [`Problem::points`]'s five, and no
    /// normal equations. `None` with fewer than [`MIN_WINDOW_SAMPLES`] points.
    pub(super) fn mean_square_m2(
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
            let win = WindowPoints::new(run, self.scale_prior_m);
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
    /// The scale prior, metres of spread per sample ([`super::PoseFitParams::scale_prior_m`]).
    scale_prior_m: f64,
}

impl WindowPoints {
    /// The centroids of `pts`; the scale held by a prior of `scale_prior_m`.
    fn new(pts: Vec<Pt>, scale_prior_m: f64) -> WindowPoints {
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
            scale_prior_m,
        }
    }

    /// The scale given Σ r̃·R·ũ (`tr`) and Σ|ũ|² (`s_uu`), held about the mission's `s_bar` by its
    /// prior (weight n·P², P the window's `scale_prior_m`).
    fn scale_of(&self, tr: f64, s_uu: f64, s_bar: f64) -> f64 {
        let lambda = self.scale_prior_m2();
        ((tr + lambda * s_bar) / (s_uu + lambda)).max(1e-3)
    }

    /// The scale prior's weight λ = n·P², m².
    fn scale_prior_m2(&self) -> f64 {
        self.nf * self.scale_prior_m * self.scale_prior_m
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
    /// The scale prior's weight λ = n·P², m².
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
        // The translation's columns are the unit vectors: their dot products are the other
        // columns' components (the same sums, bit for bit, without the products by 0 and 1).
        for a in 0..3 {
            self.nte[a] += e[a];
            for (b, cb) in cols.iter().enumerate().skip(a) {
                self.ntn[(a, b)] += cb[a];
            }
            let rows = self.ntv[a * p..(a + 1) * p]
                .iter_mut()
                .zip(&mut self.ntx[a * p..(a + 1) * p]);
            for ((sv, sx), (vb, xb)) in rows.zip(v.iter().zip(x)) {
                *sv += vb[a];
                *sx += xb[a];
            }
        }
        for a in 3..8 {
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
    tiling(ref_t, window_s, 0.0)
}

/// The windows of [`windows`] with every cut moved later by `phase` (a fraction of a window in
/// [0, 1)); the first and the last window take what is left at the ends, each between half a
/// window and one and a half (`phase` 0: [`windows`]).
///
/// ```
/// use trajdrift_core::align::pose_fit::{tiling, windows};
/// let t: Vec<f64> = (0..=1000).map(|k| 0.1 * k as f64).collect(); // 100 s at 10 Hz
/// let cuts = |w: &[trajdrift_core::align::pose_fit::Window]| -> Vec<f64> {
///     w.iter().map(|w| w.t_start).collect()
/// };
/// assert_eq!(cuts(&windows(&t, Some(20.0))), [0.0, 20.0, 40.0, 60.0, 80.0]);
/// assert_eq!(cuts(&tiling(&t, Some(20.0), 0.25)), [0.0, 25.0, 45.0, 65.0, 85.0]);
/// assert_eq!(cuts(&tiling(&t, Some(20.0), 0.75)), [0.0, 15.0, 35.0, 55.0, 75.0]);
/// ```
pub fn tiling(ref_t: &[f64], window_s: Option<f64>, phase: f64) -> Vec<Window> {
    let n = ref_t.len();
    if n < MIN_WINDOW_SAMPLES {
        return Vec::new();
    }
    let period = median_step(ref_t).unwrap_or(0.0);
    let len = window_s.unwrap_or(WINDOW_S.max(1.5 * MIN_WINDOW_SAMPLES as f64 * period));
    let (a, b) = (ref_t[0], ref_t[n - 1]);
    let count = ((b - a) / len).floor().max(1.0) as usize;
    // The windows share the span evenly (no sliver at the end).
    let len = (b - a) / count as f64;
    // The cuts a + (k + phase)·len, less those within half a window of either end.
    let inner = (0..=count)
        .map(|k| a + (k as f64 + phase) * len)
        .filter(|&c| c - a >= 0.5 * len - 1e-9 && b - c >= 0.5 * len - 1e-9 && c > a && c < b);
    let cuts: Vec<f64> = std::iter::once(a).chain(inner).chain([b]).collect();
    let count = cuts.len() - 1;
    (0..count)
        .map(|k| {
            let (lo, hi) = (cuts[k], cuts[k + 1]);
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

// The mission's problem, built here beside the types it fills (`PoseData` itself is in `mod.rs`).
impl<'a> PoseData<'a> {
    pub(super) fn problem(&self) -> Problem<'a> {
        let period = median_step(self.estimate.t).unwrap_or(0.01);
        let ref_period_s = median_step(self.ref_t).unwrap_or(f64::INFINITY);
        // Two of the estimate's periods of reference samples, where the estimate is slow enough
        // for a gait to reach its Nyquist band and the reference samples it more densely.
        let slow = period * self.params.average_below_hz >= 1.0;
        let block = if slow && ref_period_s > 0.0 {
            (2.0 * period / ref_period_s).round().clamp(1.0, 1e6) as usize
        } else {
            1
        };
        // Where a slow estimate's reference is sparser, nothing is averaged: the long
        // interpolation follows the band near the estimate's Nyquist frequency instead.
        let taps = if slow && block == 1 {
            Taps::Long
        } else {
            Taps::Cubic
        };
        let h = period.clamp(STENCIL_MIN_S, STENCIL_MAX_S);
        let probe_s = (0.5 * h).max(PROBE_JITTERS * stamp_jitter_s(self.estimate.t, period));
        Problem {
            ref_t: self.ref_t,
            ref_p: self.ref_p,
            sampler: Sampler::new(self.estimate, self.params.max_gap_s, taps),
            h,
            hw: h + self.params.jacobian_periods * period,
            probe_s,
            scale_prior_m: self.params.scale_prior_m,
            block,
            ref_period_s,
            max_iterations: self.params.max_iterations,
        }
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
                let w = WindowPoints::new(pts, problem.scale_prior_m);
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The slow twin of [`NormalSums::add`]: every entry a dot product of two whole columns.
    fn add_by_dots(
        sums: &mut NormalSums,
        e: &Vector3<f64>,
        cols: &[Vector3<f64>; 8],
        v: &[Vector3<f64>],
        x: &[Vector3<f64>],
    ) {
        let p = sums.p;
        sums.rss += e.norm_squared();
        for a in 0..8 {
            sums.nte[a] += cols[a].dot(e);
            for b in a..8 {
                sums.ntn[(a, b)] += cols[a].dot(&cols[b]);
            }
            for b in 0..p {
                sums.ntv[a * p + b] += cols[a].dot(&v[b]);
                sums.ntx[a * p + b] += cols[a].dot(&x[b]);
            }
        }
        for a in 0..p {
            sums.vte[a] += v[a].dot(e);
            for b in 0..p {
                if b >= a {
                    sums.vtv[a * p + b] += v[a].dot(&v[b]);
                }
                sums.vtx[a * p + b] += v[a].dot(&x[b]);
            }
        }
    }

    /// The translation's rows taken as components give the dot products' sums bit for bit.
    #[test]
    fn the_sums_by_components_are_the_sums_by_dot_products() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut vec3 = || {
            Vector3::new(
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
            )
        };
        let p = 4;
        let (mut fast, mut slow) = (NormalSums::zeros(p), NormalSums::zeros(p));
        for _ in 0..200 {
            let e = vec3();
            let wv = vec3();
            let cols = [
                Vector3::x(),
                Vector3::y(),
                Vector3::z(),
                Vector3::x().cross(&wv),
                Vector3::y().cross(&wv),
                Vector3::z().cross(&wv),
                wv,
                vec3(),
            ];
            let v: Vec<Vector3<f64>> = (0..p).map(|_| vec3()).collect();
            let x: Vec<Vector3<f64>> = (0..p).map(|_| vec3()).collect();
            fast.add(&e, &cols, &v, &x);
            add_by_dots(&mut slow, &e, &cols, &v, &x);
        }
        assert_eq!(fast.rss.to_bits(), slow.rss.to_bits());
        for (a, b) in fast.ntn.iter().zip(slow.ntn.iter()) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        for (a, b) in fast.nte.iter().zip(slow.nte.iter()) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        for (f, s) in [
            (&fast.ntv, &slow.ntv),
            (&fast.ntx, &slow.ntx),
            (&fast.vtv, &slow.vtv),
            (&fast.vtx, &slow.vtx),
            (&fast.vte, &slow.vte),
        ] {
            let bits = |w: &Vec<f64>| w.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(f), bits(s));
        }
    }
}
