//! The whole-mission fit: the parameters every window shares (the clock's θ and the lever D), by
//! Gauss–Newton on the windows' reduced equations summed ([`fit`], [`solve`], [`SharedFit`]), with
//! the error bar of the module doc (the delete-one-window jackknife, floored by the formal σ), and
//! [`coarse_start`], a search for a start when the one given lies outside the basin. Kept apart
//! from `window.rs` (which builds each window's equations) and `profile.rs` (which solves one
//! window at a time) because its unknowns are common to every window: each step sums them all.

use nalgebra::{DMatrix, DVector, Vector3};
use rayon::prelude::*;

use super::window::{Problem, Terms, Window};
use super::{ClockShape, PoseData, PoseFit, LEVER_PRIOR_M};

/// Gauss–Newton iterations at most. Most fits stop within ten; on a few legged missions Δt and a
/// forward lever trade places for tens of iterations before they settle (20 left 3 of 1200
/// validation missions unconverged, and their signal-search fallback 26–75 ms off with σ of
/// hundreds of ms). The cost is only paid where the fit needs it.
pub const MAX_ITERATIONS: usize = 60;
/// Gauss–Newton iterations at most of the lead search's fits from its minima
/// (`align::pose_model`). Along the valley where Δt trades with the lever, the damped steps of a
/// walking robot's fit can creep: on the second simulator's outages 61403 (10/10 Hz, the sensor
/// 0.24 m ahead and 0.17 m above the reference's point) the fit from the truth's minimum moved
/// 0.05 ms an iteration with the vertical lever and stopped unconverged after 60, 0.7 ms from the
/// truth; it was dropped and the fit a lead away (614 ms off, σ 4 ms) stood. On the narrow
/// Jacobian it converges in 164. The lead search runs on walking robots only, and only an
/// unconverged fit (or a jackknife refit of one of its windows) pays for the iterations
/// (docs/evidence.md, "A creeping fit given time").
pub const LEAD_MAX_ITERATIONS: usize = 240;
/// The largest change of an offset parameter in one iteration, seconds.
pub(super) const MAX_STEP_S: f64 = 0.1;
/// A window whose residual RMS exceeds this many times the median window's is left out (what the
/// jump finder missed: a jump too small to find, an estimate that goes astray for a while).
pub(super) const OUTLIER_RMS_FACTOR: f64 = 4.0;
/// The scale of the clock column handed to the profile's windows is kept within these, the secant
/// correction's range: it steps their Newton iterations. A whole fit across a clock step (its
/// constant a misfit, whose equations barely change with it) measured 0.38, and every window of
/// the profile, stepped 2.6 times too far by it, failed to converge.
const PROFILE_SCALE_RANGE: (f64, f64) = (1.0, 4.0);
/// The jackknife refits at most this many windows' delete-one fits in full (see
/// `SharedFit::jackknife`): the largest of the steps that leave the range their slope was measured
/// over. One influential window is what breaks the one step; where many are beyond that range the
/// fit is weak anyway, and each refit costs a whole fit. Refitting every such step moved no
/// second-simulator mission more than these three did (235 missions with any), and took a weak
/// near-straight drive's evaluation from 1.2 s to 7.9 s (403 refits); three, to 2.3 s.
pub(super) const MAX_JACKKNIFE_REFITS: usize = 3;

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
    span_step_s: (f64, f64),
) -> Option<f64> {
    coarse_minima(data, windows, start_s, span_step_s, 1)
        .first()
        .map(|m| m.offset_s)
}

/// A local minimum of [`coarse_minima`]'s scan.
#[derive(Debug, Clone, Copy)]
pub struct ScanMinimum {
    /// The candidate Δt, seconds.
    pub offset_s: f64,
    /// The residual per point there (the lever solved), m².
    pub cost_m2: f64,
    /// The lever settled there (estimate body frame), metres.
    pub lever_m: Vector3<f64>,
}

/// The `count` best local minima of [`coarse_start`]'s residual per point over its candidates
/// (see [`ScanMinimum`]), best first (a candidate at the search's
/// edge counts when it is not above its one neighbour; a candidate without points costs ∞). Along a
/// valley where Δt trades against the lever, a gait ripples the residual with its period, and a
/// grid coarser than the ripple can sample the truth's ripple above another's: several minima are
/// fitted, not one.
pub fn coarse_minima(
    data: &PoseData<'_>,
    windows: &[Window],
    start_s: f64,
    (span_s, step_s): (f64, f64),
    count: usize,
) -> Vec<ScanMinimum> {
    let problem = data.problem();
    let fit = SharedFit::new(&problem, windows, &ClockShape::Constant, true);
    let k = (span_s / step_s).round() as i64;
    let scan: Vec<ScanMinimum> = (-k..=k)
        .map(|i| {
            let theta = start_s + i as f64 * step_s;
            let (lever, terms) = lever_settled(&fit, theta);
            let (rss, n) = residual_sums(&terms);
            ScanMinimum {
                offset_s: theta,
                cost_m2: if n > 0 { rss / n as f64 } else { f64::INFINITY },
                lever_m: lever,
            }
        })
        .collect::<Vec<_>>();
    let cost = |i: usize| scan.get(i).map_or(f64::INFINITY, |c| c.cost_m2);
    let mut minima: Vec<ScanMinimum> = (0..scan.len())
        .filter(|&i| {
            let c = cost(i);
            c.is_finite() && c <= cost(i.wrapping_sub(1)) && c <= cost(i + 1)
        })
        .map(|i| scan[i])
        .collect();
    minima.sort_by(|a, b| a.cost_m2.total_cmp(&b.cost_m2));
    minima.truncate(count);
    minima
}

/// The lever settled at the constant Δt `offset_s` (Newton steps from none, [`COARSE_LEVER_STEPS`]
/// at most) and the windows' terms there, each window's similarity solved.
fn lever_settled(fit: &SharedFit<'_>, offset_s: f64) -> (Vector3<f64>, Vec<Option<Terms>>) {
    let theta = [offset_s];
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
    (lever, terms)
}

/// Each window's residual per point at the constant Δt `offset_s` with the lever settled there as
/// [`coarse_minima`] settles it, squared metres (`None` for a window without points): candidates
/// for Δt compared alike, whatever fit (or scan) proposed them: on their mean, and on their
/// differences window by window, which are independent where the candidates' shared residuals (the
/// gait, a wandering bias) are not.
pub fn residuals_at(data: &PoseData<'_>, windows: &[Window], offset_s: f64) -> Vec<Option<f64>> {
    let problem = data.problem();
    let fit = SharedFit::new(&problem, windows, &ClockShape::Constant, true);
    per_point(lever_settled(&fit, offset_s).1)
}

fn per_point(terms: Vec<Option<Terms>>) -> Vec<Option<f64>> {
    terms
        .into_iter()
        .map(|t| t.filter(|t| t.n > 0).map(|t| t.rss / t.n as f64))
        .collect()
}

/// Gauss–Newton with backtracking over the shared parameters, then the jackknife.
pub(super) fn solve(
    problem: &Problem<'_>,
    windows: &[Window],
    shape: &ClockShape,
    theta0: Vec<f64>,
    lever0: Vector3<f64>,
    with_lever: bool,
) -> Option<PoseFit> {
    let fit = SharedFit::new(problem, windows, shape, with_lever);
    let mut x = fit.start(theta0, lever0)?;
    let iterations = fit.gauss_newton(&mut x)?;
    fit.finish(x, iterations)
}

/// The fit of the parameters every window shares over `windows`: the clock `shape`'s `m` (first)
/// and, when `with_lever`, the lever's three (of `p` in all).
pub(super) struct SharedFit<'a> {
    pub(super) problem: &'a Problem<'a>,
    pub(super) windows: &'a [Window],
    pub(super) shape: &'a ClockShape,
    pub(super) with_lever: bool,
    pub(super) m: usize,
    pub(super) p: usize,
}

impl<'a> SharedFit<'a> {
    /// The fit of `shape` over `windows`, with the lever when `with_lever`.
    pub(super) fn new(
        problem: &'a Problem<'a>,
        windows: &'a [Window],
        shape: &'a ClockShape,
        with_lever: bool,
    ) -> Self {
        let m = shape.len();
        SharedFit {
            problem,
            windows,
            shape,
            with_lever,
            m,
            p: m + if with_lever { 3 } else { 0 },
        }
    }
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
    damping: Damping,
}

/// The Levenberg–Marquardt damping λ (relative: λ times the diagonal of H is added to the Newton
/// Jacobian's) and how it moves: after a rejected trial step λ grows by ν, ν doubling with each
/// rejection in a row (2, 4, 8, …); after a taken step λ falls to a third and ν is 2 again
/// (Nielsen's rule, in Madsen, Nielsen and Tingleff, "Methods for non-linear least squares
/// problems", 2004, with its fall held at a third).
///
/// **Why not ten times after a rejection.** A fit creeping along a curved valley (Δt trading with
/// a lever) has every other iteration's first trial rejected: ×10 and ÷3, then ÷3 again at the
/// next iteration, left λ 10/9 higher after each such pair of iterations, and λ climbed without
/// end while steps were taken — from 4·10⁻⁶ to 6 in 60 iterations on a vehicle whose fit then
/// stopped unconverged, to 1500 in seven on one whose fit stopped on steps too small to move.
/// With ×2 the pair leaves λ at 2/9 of itself, so it settles where the steps are taken; ten
/// rejections in a row still reach 2⁵⁵ (docs/evidence.md, "The damping that ratcheted").
#[derive(Debug, Clone, Copy)]
struct Damping {
    lambda: f64,
    growth: f64,
}

impl Damping {
    fn new(lambda: f64) -> Damping {
        Damping {
            lambda,
            growth: 2.0,
        }
    }

    /// After a rejected trial step.
    fn rejected(&mut self) {
        self.lambda *= self.growth;
        self.growth *= 2.0;
    }

    /// After a taken step.
    fn taken(&mut self) {
        self.lambda = (self.lambda / 3.0).max(1e-6);
        self.growth = 2.0;
    }
}

impl SharedFit<'_> {
    /// The windows' reduced equations at the clock `theta`, the lever `d` and the mission's scale
    /// `s_bar`.
    pub(super) fn eval(&self, theta: &[f64], d: &Vector3<f64>, s_bar: f64) -> Vec<Option<Terms>> {
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
            damping: Damping::new(1e-3),
        })
    }

    /// Gauss–Newton on the estimating equations from `x`, at most [`MAX_ITERATIONS`] steps, until a
    /// step is small or no damping makes one acceptable: the number of iterations; `None` when the
    /// summed equations cannot be solved.
    fn gauss_newton(&self, x: &mut Iterate) -> Option<usize> {
        let (m, p) = (self.m, self.p);
        let mut iterations = 0;
        let mut previous: Option<DVector<f64>> = None;
        for it in 0..self.problem.max_iterations() {
            iterations = it + 1;
            if it < 3 {
                self.rescale(x);
            }
            let l = lever_weight(&x.terms);
            let (Some(mut step), g0, scales) =
                self.normal(&x.terms, &x.lever_m, l, x.jacobian_scale, x.damping.lambda)
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
            if let (Some(s), ..) =
                self.normal(&x.terms, &x.lever_m, l, x.jacobian_scale, x.damping.lambda)
            {
                *step = s;
            }
        }
    }

    /// Takes `step` (shortened to [`MAX_STEP_S`] on the clock) when it keeps every window and
    /// lowers the merit of the estimating equations below `before` (the instrument is not the
    /// cost's exact gradient, so the steps solve g = 0 rather than descend a cost); otherwise more
    /// damping ([`Damping`]) and a new step, ten tries at most. Whether a step was taken (`step` is
    /// then the one taken).
    fn backtrack(
        &self,
        x: &mut Iterate,
        step: &mut DVector<f64>,
        l: f64,
        scales: &DVector<f64>,
        before: f64,
    ) -> bool {
        const TRIES: usize = 10;
        let (m, c) = (self.m, x.jacobian_scale);
        for tried in 1..=TRIES {
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
                x.damping.taken();
                return true;
            }
            x.damping.rejected();
            if tried == TRIES {
                break;
            }
            match self.normal(&x.terms, &x.lever_m, l, c, x.damping.lambda) {
                (Some(s), ..) => *step = s,
                _ => return false,
            }
        }
        false
    }

    /// The reduced equations summed over the windows with the lever's prior (weight `l`, centred
    /// on 0, at the lever `d`) added, the Jacobian's clock columns scaled by the secant correction
    /// `c`: (H, J, g).
    pub(super) fn summed(
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
        self.add_lever_prior(&mut h, l);
        self.add_lever_prior(&mut j, l);
        if self.with_lever {
            for k in 0..3 {
                g[m + k] += l * d[k];
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

    /// Each window's Jacobian of its estimating equations at (`theta`, `d`, `scale`), `terms`
    /// there, and their sum with the lever's prior (weight `l`). The clock columns are measured:
    /// the window's equations' change over θ_i ± δ (δ moving Δt by half the instrument's half-step
    /// at most within the window, [`Self::probe_step`]); one-sided where a shift changes the
    /// window's points on one side only, and the analytic column scaled by the iteration's secant
    /// correction `c` where it changes them on both. The lever's columns are the analytic ones
    /// (no time derivative in them).
    ///
    /// Why measured (for the error bar, and the scale handed to the profile's windows; the
    /// iteration, and whether it converged, keep the analytic J, which steers it well): J's clock
    /// columns are a derivative over a wider stencil than the instrument's, and the secant
    /// correction that makes up for it only grows. Where the estimate's stamps jitter (taken at
    /// receipt: a 200 Hz estimate whose stamps wander by more than its period) the steps undo each
    /// other from noise and c climbed to 2–4 where the equations' slope was 1.2–1.4 times J, and
    /// σ came out short by that factor (receipt-stamp missions whose Δt scattered by 4 ms over
    /// fresh noise reported 1–2 ms). Below 40 Hz J misses a gait the instrument follows: J − J_k
    /// went near-singular in the jackknife, and a formal floor on J was tens of milliseconds on
    /// legged missions whose Δt was within 1 ms. The measured slope has neither fault at any rate;
    /// and where one constant is fitted across a clock step, it says how little the equations pin
    /// it (σ of seconds where J claimed 45 ms). docs/evidence.md, "The slope, measured".
    pub(super) fn jacobians(
        &self,
        (theta, d, scale): (&[f64], &Vector3<f64>, f64),
        terms: &[Option<Terms>],
        l: f64,
        c: f64,
    ) -> Jacobians {
        let m = self.m;
        let own: Vec<Option<DMatrix<f64>>> = self
            .windows
            .par_iter()
            .zip(terms)
            .map(|(w, t)| {
                let t = t.as_ref()?;
                let mut j = t.j.clone();
                for i in 0..m {
                    let Some(step) = self.probe_step(w, i, self.problem.probe_s()) else {
                        continue; // Δt in this window does not depend on θ_i.
                    };
                    let at = |sign: f64| {
                        let mut shifted = theta.to_vec();
                        shifted[i] += sign * step;
                        self.problem
                            .terms(w, self.shape, &shifted, d, self.with_lever, scale)
                            // The same points, or the difference is a point's whole term.
                            .filter(|s| s.n == t.n && s.segments == t.segments)
                    };
                    let column = match (at(1.0), at(-1.0)) {
                        (Some(a), Some(b)) => (&a.g - &b.g) / (2.0 * step),
                        (Some(a), None) => (&a.g - &t.g) / step,
                        (None, Some(b)) => (&t.g - &b.g) / step,
                        (None, None) => j.column(i) * c,
                    };
                    j.set_column(i, &column);
                }
                Some(j)
            })
            .collect();
        let mut whole = own
            .iter()
            .flatten()
            .fold(DMatrix::zeros(self.p, self.p), |a, j| a + j);
        self.add_lever_prior(&mut whole, l);
        Jacobians { own, whole }
    }

    /// The shift of clock parameter `i` that moves Δt by `half_width_s` at most within window `w`
    /// (a linear drift's slope by that over the window's farthest end from the mid); `None` when
    /// Δt in the window does not depend on θ_i (another segment's offset). The slopes are measured
    /// over the problem's probe: half the instrument's half-step (25 ms at 20 Hz and above, 50 ms
    /// at 10 Hz, 125 ms below 4 Hz), wider where the estimate's stamps jitter
    /// ([`super::PROBE_JITTERS`]): over less than an estimate's period the equations are rough —
    /// the instrument's change with Δt is the interpolated track's local slope, mostly the
    /// estimate's noise at
    /// 100–200 Hz, and against the reference's noise in the residual it flattened the slope
    /// measured over ±2 ms to a quarter of its value over ±10 ms or more (σ 0.35 s on a turn in
    /// place whose Δt was within 0.1 ms, in a trial); a gait at 2–3.5 Hz keeps 90 % of its slope
    /// over ±25 ms.
    fn probe_step(&self, w: &Window, i: usize, half_width_s: f64) -> Option<f64> {
        let mut phi = vec![0.0; self.m];
        let mut reach = 0.0f64;
        for t in [w.t_start, w.t_end] {
            self.shape.basis(t, &mut phi);
            reach = reach.max(phi[i].abs());
        }
        (reach > 0.0).then(|| half_width_s / reach)
    }

    /// The lever's prior (weight `l`, on the lever's diagonal) added to a summed Jacobian or H.
    fn add_lever_prior(&self, a: &mut DMatrix<f64>, l: f64) {
        if self.with_lever {
            for k in self.m..self.p {
                a[(k, k)] += l;
            }
        }
    }

    /// The formal covariance S⁻¹·σ̂²H·S⁻ᵀ of the summed equations (S the Jacobian `jac`, H the
    /// summed Σ v·v with the lever's prior), σ̂² the residual per degree of freedom (white
    /// residuals assumed).
    pub(super) fn formal_covariance(
        &self,
        terms: &[Option<Terms>],
        jac: &Jacobians,
        h: &DMatrix<f64>,
    ) -> Option<DMatrix<f64>> {
        let (rss, _) = residual_sums(terms);
        let dof = terms.iter().flatten().map(Terms::dof).sum::<f64>() - self.p as f64;
        if dof <= 0.0 {
            return None;
        }
        let si = jac.whole.clone().try_inverse()?;
        Some(&si * h * si.transpose() * (rss / dof))
    }

    /// The delete-one-window jackknife at the solution `x` (see the module doc): each window left
    /// out by one step (S − S_k)⁻¹·g_k of the summed equations less its own, S the Jacobian of
    /// [`Self::jacobians`]; the covariance (K−1)/K·Σ(δ₋ₖ − δ̄)(δ₋ₖ − δ̄)ᵀ of those steps.
    /// `None` when fewer than three windows could be left out.
    ///
    /// A step is a linear prediction from slopes measured over ± [`Self::probe_step`]; where it
    /// moves a clock parameter beyond half the instrument's half-step (an evenly stamped
    /// estimate's probe), it extrapolates, and where the window's measured slopes
    /// carry much of S along some direction, S − S_k is near-singular and the step runs away
    /// (while the fit without the window may hardly move). That window's fit without it is then
    /// made in full (Gauss–Newton from `x`; the
    /// [`MAX_JACKKNIFE_REFITS`] largest such steps). On a vehicle with receipt stamps (reference
    /// 2 Hz, estimate 20 Hz, Δt within 6 ms) one step was 3.9 s and σ 2.7 s; made in full, the
    /// three largest steps (3.9 s, 229 ms, 139 ms) were 15, 14 and 21 ms, and σ 108 ms (the formal
    /// σ is 79 ms) (docs/evidence.md, "The jackknife's runaway step, refitted").
    fn jackknife(&self, x: &Iterate, jac: &Jacobians) -> Option<DMatrix<f64>> {
        let p = self.p;
        let mut deltas: Vec<(usize, DVector<f64>)> = x
            .terms
            .iter()
            .zip(&jac.own)
            .enumerate()
            .filter_map(|(k, (t, own))| {
                let (t, own) = (t.as_ref()?, own.as_ref()?);
                Some((k, (&jac.whole - own).lu().solve(&t.g)?))
            })
            .collect();
        if deltas.len() < 3 {
            return None;
        }
        // How far beyond half the instrument's half-step each step moves a clock parameter (> 1:
        // beyond). Not the probe where a jittered estimate's is wider: its slopes, measured over a
        // wider shift for their noise, do not make a longer step linear (a window where a vehicle
        // nearly stops ran away as before; the test of the runaway window).
        let linear_s = 0.5 * self.problem.half_step_s();
        let reach = |k: usize, d: &DVector<f64>| {
            (0..self.m)
                .filter_map(|i| Some(d[i].abs() / self.probe_step(&self.windows[k], i, linear_s)?))
                .fold(0.0, f64::max)
        };
        let mut beyond: Vec<(usize, f64)> = deltas
            .iter()
            .enumerate()
            .map(|(at, (k, d))| (at, reach(*k, d)))
            .filter(|(_, r)| *r > 1.0)
            .collect();
        beyond.sort_by(|a, b| b.1.total_cmp(&a.1));
        beyond.truncate(MAX_JACKKNIFE_REFITS);
        let refits: Vec<(usize, DVector<f64>)> = beyond
            .par_iter()
            .filter_map(|(at, _)| Some((*at, self.refit_without(x, deltas[*at].0)?)))
            .collect();
        for (at, d) in refits {
            deltas[at].1 = d;
        }
        let deltas: Vec<DVector<f64>> = deltas.into_iter().map(|(_, d)| d).collect();
        let kf = deltas.len() as f64;
        let mean = deltas.iter().fold(DVector::zeros(p), |a, d| a + d) / kf;
        let mut cov = DMatrix::<f64>::zeros(p, p);
        for dlt in &deltas {
            let c = dlt - &mean;
            cov += &c * c.transpose();
        }
        cov *= (kf - 1.0) / kf;
        Some(cov)
    }

    /// The change of the shared parameters from `x` when window `k` is left out, by Gauss–Newton
    /// from `x` over the others; `None` when that fit cannot be made.
    fn refit_without(&self, x: &Iterate, k: usize) -> Option<DVector<f64>> {
        let mut others = self.windows.to_vec();
        others.remove(k);
        let fit = SharedFit::new(self.problem, &others, self.shape, self.with_lever);
        let mut y = fit.start(x.theta.clone(), x.lever_m)?;
        fit.gauss_newton(&mut y)?;
        let mut d = DVector::zeros(self.p);
        for i in 0..self.m {
            d[i] = y.theta[i] - x.theta[i];
        }
        if self.with_lever {
            for i in 0..3 {
                d[self.m + i] = y.lever_m[i] - x.lever_m[i];
            }
        }
        Some(d)
    }

    /// The scale of the clock columns for the profile's windows: the Jacobian of
    /// [`Self::jacobians`] over the analytic one (`analytic`, summed) along a shift of the whole
    /// clock, within [`PROFILE_SCALE_RANGE`]; the iteration's `c` unless both are positive.
    fn profile_scale(&self, jac: &Jacobians, analytic: &DMatrix<f64>, c: f64) -> f64 {
        let m = self.m;
        let u = self.shape.uniform_shift();
        let along = |a: &DMatrix<f64>| -> f64 {
            (0..m)
                .map(|r| u[r] * (0..m).map(|k| a[(r, k)] * u[k]).sum::<f64>())
                .sum()
        };
        let (num, den) = (along(&jac.whole), along(analytic));
        if num > 0.0 && den > 0.0 {
            (num / den).clamp(PROFILE_SCALE_RANGE.0, PROFILE_SCALE_RANGE.1)
        } else {
            c
        }
    }

    /// The fit at the solution `x`: the standard errors (the jackknife's, at least the formal
    /// ones), whether it converged (the Newton step left is small beside them), the variance
    /// inflation of Δt by the lever.
    fn finish(&self, x: Iterate, iterations: usize) -> Option<PoseFit> {
        let (m, p, with_lever) = (self.m, self.p, self.with_lever);
        let d = x.lever_m;
        let l = lever_weight(&x.terms);
        let jac = self.jacobians((&x.theta, &d, x.scale), &x.terms, l, x.jacobian_scale);
        // The summed equations once: H and the analytic J for the error bar, and the Newton step
        // left as the iteration steps (J's clock columns scaled by c, not the error bar's slope).
        let (h, analytic, g) = self.summed(&x.terms, &d, l, 1.0);
        let mut j_c = analytic.clone();
        scale_clock_columns(&mut j_c, m, x.jacobian_scale);
        let remaining = j_c.lu().solve(&g).map(|step| -step);
        let used: Vec<(&Window, &Terms)> = self
            .windows
            .iter()
            .zip(&x.terms)
            .filter_map(|(w, t)| t.as_ref().map(|t| (w, t)))
            .collect();
        let mut cov = self.jackknife(&x, &jac)?;
        let theta_jackknife_sigma: Vec<f64> = (0..m).map(|k| cov[(k, k)].max(0.0).sqrt()).collect();
        let mut theta_formal_sigma = vec![0.0; m];
        // The formal σ is the floor (see the module doc): each parameter's variance raised to it,
        // the jackknife's correlations kept.
        if let Some(formal) = self.formal_covariance(&x.terms, &jac, &h) {
            for (k, s) in theta_formal_sigma.iter_mut().enumerate() {
                *s = formal[(k, k)].max(0.0).sqrt();
            }
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
        // The step is the iteration's (its Jacobian), σ the error bar's: a constant fitted across
        // a clock step, which the equations barely pin (σ of seconds), counts as converged, so that
        // the profile starts from its lever (judged on the measured slope it did not, and the
        // profile lost the step).
        let converged = remaining.is_some_and(|step| {
            (0..m).all(|k| step[k].abs() <= sig(k).max(1e-4))
                && (!with_lever || (m..p).all(|k| step[k].abs() <= sig(k).max(1e-3)))
        });
        let variance_inflation = if with_lever {
            // Var(θₖ) with D free over Var(θₖ) with D held (the other θ free in both), from the
            // normal equations: (H⁻¹)ₖₖ over ((H_θθ)⁻¹)ₖₖ.
            let held = h.view((0, 0), (m, m)).clone_owned().try_inverse();
            match (h.clone().try_inverse(), held) {
                (Some(free), Some(held)) => (0..m)
                    .map(|k| (free[(k, k)] / held[(k, k)]).max(1.0))
                    .collect(),
                _ => vec![f64::INFINITY; m],
            }
        } else {
            vec![1.0; m]
        };
        Some(PoseFit {
            shape: self.shape.clone(),
            theta: x.theta,
            lever_m: d,
            theta_sigma: (0..m).map(sig).collect(),
            theta_jackknife_sigma,
            theta_formal_sigma,
            lever_sigma_m: with_lever.then(|| Vector3::new(sig(m), sig(m + 1), sig(m + 2))),
            covariance: cov,
            variance_inflation,
            windows: used.iter().map(|(w, _)| (*w).clone()).collect(),
            outliers: Vec::new(),
            rms_m: used.iter().map(|(_, t)| t.rms_m()).collect(),
            scale: x.scale,
            jacobian_scale: self.profile_scale(&jac, &analytic, x.jacobian_scale),
            iterations,
            converged: converged && used.len() >= 3,
        })
    }
}

/// The lever prior's weight: the windows' residual variance per coordinate over the prior's
/// variance [`LEVER_PRIOR_M`]².
pub(super) fn lever_weight(terms: &[Option<Terms>]) -> f64 {
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

/// Each window's Jacobian of its estimating equations (`None` where the window has none) and
/// their sum with the lever's prior: what the error bar linearises the fit with.
pub(super) struct Jacobians {
    own: Vec<Option<DMatrix<f64>>>,
    whole: DMatrix<f64>,
}

/// The Jacobian's `m` clock columns of `j` scaled by the secant correction `c`.
fn scale_clock_columns(j: &mut DMatrix<f64>, m: usize, c: f64) {
    for k in 0..m {
        j.column_mut(k).scale_mut(c);
    }
}

#[cfg(test)]
mod tests {
    use super::Damping;

    /// A fit whose every other step is taken only after one rejection: the damping settles
    /// instead of climbing (ten times after a rejection left it 10/9 higher after each pair).
    #[test]
    fn a_step_taken_after_one_rejection_leaves_less_damping() {
        let mut d = Damping::new(1e-2);
        for _ in 0..30 {
            d.rejected();
            d.taken();
            d.taken();
        }
        assert!(d.lambda <= 1e-2, "{d:?}");
        let mut once = Damping::new(1.0);
        once.rejected();
        once.taken();
        assert!(once.lambda < 1.0, "{once:?}");
    }

    /// Rejections in a row grow the damping ever faster: ten reach 2⁵⁵, and a taken step starts
    /// the growth again at two.
    #[test]
    fn rejections_in_a_row_grow_the_damping_ever_faster() {
        let mut d = Damping::new(1.0);
        for _ in 0..10 {
            d.rejected();
        }
        assert_eq!(d.lambda, 2f64.powi(55));
        d.taken();
        d.rejected();
        assert_eq!(d.lambda, 2f64.powi(55) / 3.0 * 2.0);
    }
}
