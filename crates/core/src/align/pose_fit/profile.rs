//! The offset profile: each window's own Δt with the lever held ([`profile`], [`WindowSolver`]),
//! its least-squares σ ([`formal_sigma`]) and the calibration that brings those σ to the windows'
//! scatter about their neighbours, a factor and an excess ([`scatter_calibration`]). Kept apart
//! from the whole-mission fit (`shared.rs`) because it solves one window at a time (a Newton on one
//! offset, and a search for a deeper root); both build on the windows' equations of `window.rs`.

use nalgebra::Vector3;
use rayon::prelude::*;

use super::shared::{MAX_ITERATIONS, MAX_STEP_S, OUTLIER_RMS_FACTOR};
use super::window::{Problem, Terms, Window};
use super::{ClockShape, PoseData, CLIP_CHI2};

/// E[χ²₁ | χ²₁ ≤ 16]: what the clipped mean of unit normals' squares comes to.
const CLIPPED_MEAN: f64 = 0.9989;
/// The median of χ²₁.
const CHI2_1_MEDIAN: f64 = 0.4549;
/// How much lower (in χ² of the window's own noise) a profile window's residual must be at the root
/// its search finds than at the root nearest its start for the search's to be taken (5σ).
const SEARCH_CHI2: f64 = 25.0;
/// The spacing of a window's search over offsets, seconds.
const SEARCH_STEP_S: f64 = 0.05;

/// Δt on one window, with its σ (the window's least-squares error, not yet scaled).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowOffset {
    pub t: f64,
    pub offset_s: f64,
    /// σ̂_k·√H_k/(c·J_k), seconds (see `formal_sigma`).
    pub formal_sigma_s: f64,
    /// The window's residual RMS, metres.
    pub rms_m: f64,
    /// The share of the reference's motion in the window the fit explains, 1 − RSS/Σ|p − p̄|².
    pub quality: f64,
}

impl WindowOffset {
    /// Window `w`'s offset `offset_s`, with its reduced equations `t` there (`c`: the scale of the
    /// clock column, [`super::PoseFit::jacobian_scale`]); `None` when the window has no formal σ.
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
    /// The scale c of the Jacobian's clock column: the whole fit's
    /// [`super::PoseFit::jacobian_scale`].
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
    /// [`solve`](super::shared::solve)): its root and the equations there; `None` when there is
    /// none (H or J not positive, or the step left exceeds the window's own error).
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
/// form, c the whole fit's measured scale of the clock column; σ̂² the residual per degree of
/// freedom: 3 per point less the 8 of each stretch's similarity and drift and the offset).
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
    let terms: Vec<f64> = neighbour_terms(w)
        .into_iter()
        .map(|(e2, v, _)| e2 / v)
        .collect();
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

/// The windows' calibration (module doc): σ_k² = (`factor`·s_k)² + `extra_s`², s_k a window's
/// least-squares error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowScatter {
    /// f ≥ 1: residuals correlated within a window.
    pub factor: f64,
    /// τ ≥ 0, seconds: the error every window has beyond what its residuals show.
    pub extra_s: f64,
}

impl WindowScatter {
    /// The calibrated σ of a window whose least-squares error is `formal_s`.
    pub fn sigma_s(&self, formal_s: f64) -> f64 {
        (self.factor * formal_s).hypot(self.extra_s)
    }
}

/// f and τ of the module doc from the windows `w` (t, offset, least-squares σ; in time order, not
/// overlapping): each neighbour term e_k² has the expectation f²·v_k + c_k·τ² (v_k its variance from
/// the least-squares σ, c_k = 1 + a² + b² the share of τ² the interpolation carries); f² and τ² are
/// fitted by least squares weighted by the expectation's inverse square (a χ² term's variance is
/// twice its square), the terms beyond [`CLIP_CHI2`] times it set aside, from f = [`scatter_factor`]
/// and τ = 0 to the fixed point; a bound reached (f = 1 or τ = 0) refits the other alone, and so
/// does a system that cannot tell the two apart (every v_k in proportion to c_k: windows equally
/// sharp). f = [`scatter_factor`] (at least 1) and τ = 0 with fewer than three terms or an answer
/// that is not finite. With few windows τ comes out low more often than high (the validation's
/// missions hold 6–30); the final fit's jackknife, pooled with the windows, and its formal σ stand
/// behind it.
///
/// Windows whose errors are all the same size, whatever their own σ:
/// ```
/// use trajdrift_core::align::pose_fit::scatter_calibration;
/// // Offsets alternating ±2.45 ms about 0.1 s, so every e_k is ±4.9 ms, while the windows' own σ
/// // are 1 ms and 3 ms (two of each in turn): the sharp ones scatter far beyond their σ, the others
/// // less. No factor fits both; the fit puts f at its bound and the rest in τ.
/// let w: Vec<(f64, f64, f64)> = (0..40)
///     .map(|k| {
///         let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
///         (20.0 * k as f64, 0.1 + sign * 0.00245, if k % 4 < 2 { 0.001 } else { 0.003 })
///     })
///     .collect();
/// let c = scatter_calibration(&w);
/// assert_eq!(c.factor, 1.0);
/// assert!((c.extra_s - 0.0034).abs() < 0.0002, "{c:?}");
/// // The sharp windows widen most: from 1 to 3.6 ms, the others from 3 to 4.6 ms.
/// assert!(c.sigma_s(0.001) / 0.001 > 3.0 && c.sigma_s(0.003) / 0.003 < 1.6);
/// ```
pub fn scatter_calibration(w: &[(f64, f64, f64)]) -> WindowScatter {
    let terms = neighbour_terms(w);
    let factor_alone = WindowScatter {
        factor: scatter_factor(w).max(1.0),
        extra_s: 0.0,
    };
    if terms.len() < 3 {
        return factor_alone;
    }
    // f² and τ² (s²).
    let mut factor2 = factor_alone.factor.powi(2);
    let mut extra2_s2 = 0.0f64;
    for _ in 0..50 {
        // Weighted normal equations of y = e²/(clip's mean) on (v, c).
        let (mut svv, mut svc, mut scc, mut syv, mut syc) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for &(e2, v, c) in &terms {
            let expected = factor2 * v + c * extra2_s2;
            if e2 > CLIP_CHI2 * expected {
                continue;
            }
            let q = 1.0 / (expected * expected);
            let y = e2 / CLIPPED_MEAN;
            svv += q * v * v;
            svc += q * v * c;
            scc += q * c * c;
            syv += q * y * v;
            syc += q * y * c;
        }
        if svv <= 0.0 || scc <= 0.0 {
            break;
        }
        let det = svv * scc - svc * svc;
        let (mut next_f2, mut next_e2) = if det > 1e-9 * svv * scc {
            ((syv * scc - syc * svc) / det, (svv * syc - svc * syv) / det)
        } else {
            // v in proportion to c: the factor alone.
            (syv / svv, 0.0)
        };
        if next_f2 < 1.0 {
            next_f2 = 1.0;
            next_e2 = ((syc - svc) / scc).max(0.0);
        }
        if next_e2 < 0.0 {
            next_e2 = 0.0;
            next_f2 = (syv / svv).max(1.0);
        }
        // Settled to 10⁻⁹ relative (τ² to 10⁻⁹ of itself or of (1 µs)², whichever is larger).
        let settled = (next_f2 - factor2).abs() <= 1e-9 * factor2
            && (next_e2 - extra2_s2).abs() <= 1e-9 * (extra2_s2 + 1e-12);
        factor2 = next_f2;
        extra2_s2 = next_e2;
        if settled {
            break;
        }
    }
    let fitted = WindowScatter {
        factor: factor2.sqrt(),
        extra_s: extra2_s2.sqrt(),
    };
    if fitted.factor.is_finite() && fitted.extra_s.is_finite() {
        fitted
    } else {
        factor_alone
    }
}

/// The neighbour terms of `w` (module doc): (e_k², v_k, c_k) for each inner window whose three
/// windows are finite (a non-finite offset or σ would poison every sum).
fn neighbour_terms(w: &[(f64, f64, f64)]) -> Vec<(f64, f64, f64)> {
    let mut terms = Vec::new();
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
        if v > 0.0 && v.is_finite() && e.is_finite() {
            terms.push((e * e, v, 1.0 + a * a + b * b));
        }
    }
    terms
}
