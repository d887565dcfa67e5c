//! The clock offset Δt between an estimate and its reference (step 2 of the paper).
//!
//! Both trajectories are turned into a frame-independent signal — the curvature signature κ of eq. (1)
//! (`curvature`, the paper's method) or the windowed speed (`speed`, the baseline) — which is resampled
//! by linear interpolation onto a common grid (grid points at multiples of δt of each clock). The lag
//! k in [−k_max, k_max] that maximises the masked normalised cross-correlation (eq. 2) of the two
//! grids gives Δt = k·δt, with the convention κ_est(t) ≈ κ_ref(t + Δt): the estimate's stamps become
//! t_est + Δt on the reference clock.
//!
//! To keep buffers small on long missions the search runs in two stages: the whole ±max_offset on a
//! coarse grid with FFTs over blocks of the grid ([`crate::align::xcorr::masked_ncc_blocks`]; neither
//! grid is held whole, see [`crate::align::grid::LazyGrid`]), then every fine step (1 ms) in a window
//! of ±2 coarse steps around the coarse peak, with the sums of the fine grid formed from prefix sums
//! over runs of the sparser signal (`crate::align::fine_sums`: no full-length signal on the fine
//! grid), and finally a parabola through the best fine lag and its neighbours for a sub-step offset.
//! The signals themselves come from `crate::align::signals`, computed once per evaluation.
//!
//! Confidence (all on the coarse curve, which covers the whole search range). Let ρ be the peak NCC,
//! b the median NCC over the eligible lags (the level of an unrelated alignment) and P = ρ − b the
//! peak's prominence. The *main lobe* is the contiguous run of lags around the peak above b + P/2; the
//! exclusion zone is that run widened by its own width on each side, and at least ±1 s (lobes of κ
//! are ~1 s wide, those of speed 5–20 s). ρ₂ is the best NCC outside the exclusion zone and
//! separation s = (ρ − ρ₂)/P ∈ [0, 1] (1: nothing else rises, 0: a rival as high as the peak).
//!
//! confidence = s · min(1, P / 0.3) · min(1, overlap_fraction / 0.5)
//!
//! and the status is `ok` when confidence ≥ 0.5, ρ ≥ 0.3 and the peak is not at the edge of the
//! search range; `weak` otherwise. The thresholds were set on the five simulated missions (see
//! tests/it/time_offset.rs `offset_table`): with them no peak that is off by more than a second is `ok`
//! there. What they cannot see is a *biased* but clear peak: a sensor mounted a distance d ahead of
//! the other sees the same curvature d/v earlier (κ_front(t) ≈ κ_back(t + d/v) at speed v), so the
//! `curvature` offset is off by ≈ d/v with a perfect-looking peak (legged: 0.2 m at ~0.4 m/s gives
//! +0.5 s). Speed has no such first-order shift.

use std::sync::Arc;

use nalgebra::Vector3;

use crate::align::fine_sums::fine_sums;
use crate::align::grid::{GridBlocks, LazyGrid};
pub use crate::align::offset_params::{OffsetMethod, OffsetParams, COARSE_GRID_S};
use crate::align::offset_sigma::offset_sigma;
pub use crate::align::signals::{Intervals, Pair, Signal, SignalCache, SignalPair, SignalView};
use crate::align::xcorr::{masked_ncc_blocks, Centering};
use crate::error::{Error, Result};

/// Whether the estimate can be trusted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OffsetStatus {
    /// A clear, unique peak.
    Ok,
    /// A flat or ambiguous peak: do not trust the offset.
    Weak,
}

/// The result of the offset search.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct OffsetEstimate {
    /// The method used.
    pub method: OffsetMethod,
    /// Δt, seconds: t_est + Δt is on the reference clock.
    pub offset_s: f64,
    /// The peak NCC.
    pub correlation: f64,
    /// Confidence in [0, 1] (see the module doc).
    pub confidence: f64,
    /// `ok` or `weak`.
    pub status: OffsetStatus,
    /// Overlap at the peak over the defined points of the shorter signal (coarse grid).
    pub overlap_fraction: f64,
    /// ρ − ρ₂: how far the peak NCC stands above the best NCC outside its main lobe (0 when nothing
    /// lies outside the lobe).
    pub margin: f64,
    /// Δt of that best rival outside the main lobe, seconds.
    pub rival_offset_s: Option<f64>,
    /// Share of the two trajectories' time overlap (at the peak) where both signals are defined.
    pub defined_fraction: f64,
    /// Standard error of `offset_s`, seconds, from the residual of the aligned signals (see
    /// `crate::align::offset_sigma`); `None` on an overlap too short to tell.
    pub sigma_s: Option<f64>,
}

/// Lags whose overlap is below this share of the best overlap are not eligible for the peak: an NCC
/// over a sliver of the mission is meaningless.
const MIN_OVERLAP_SHARE: f64 = 0.5;
/// Prominence (peak NCC over the median) that counts as a fully clear peak.
const PROMINENCE_FULL: f64 = 0.3;
/// Overlap share that counts as full support.
const OVERLAP_FULL: f64 = 0.5;
/// The least confidence reported as `ok`.
const MIN_CONFIDENCE: f64 = 0.5;
/// The least peak NCC reported as `ok`.
const MIN_CORRELATION: f64 = 0.3;
/// Defined share of the overlap that counts as full support (κ is undefined while standing still or
/// slower than ε/Δt_max; a quarter of the mission still gives a usable signature).
const DEFINED_FULL: f64 = 0.25;
/// Least half-width of the main lobe excluded around the peak, curvature methods, seconds.
const MIN_LOBE_CURVATURE_S: f64 = 1.0;
/// Least half-width of the main lobe excluded around the peak, speed (its lobes are 5–20 s wide),
/// seconds.
const MIN_LOBE_SPEED_S: f64 = 3.0;
/// The descent from the peak counted as its main lobe stops this far out, seconds (the widest lobes
/// seen, those of speed, are 5–20 s wide).
const MAX_LOBE_S: f64 = 20.0;
/// Fine refinement window, in coarse steps on each side of the coarse peak.
const FINE_WINDOW_COARSE_STEPS: f64 = 2.0;
/// Estimates Δt such that t_est + Δt is on the reference clock. Times are seconds from a common
/// origin, increasing, each as long as its positions; `est_t` is on the estimate's clock.
pub fn estimate_time_offset(
    method: OffsetMethod,
    ref_t: &[f64],
    ref_p: &[Vector3<f64>],
    est_t: &[f64],
    est_p: &[Vector3<f64>],
    params: &OffsetParams,
) -> Result<OffsetEstimate> {
    estimate_time_offset_excluding(method, ref_t, ref_p, est_t, est_p, params, &[], &[])
}

/// [`estimate_time_offset`] with the signal samples stamped inside `ref_exclude` (reference clock)
/// or `est_exclude` (estimate clock) left out: intervals where the two signals are known not to
/// describe the same motion (a turn in place seen by one sensor only).
#[allow(clippy::too_many_arguments)]
pub fn estimate_time_offset_excluding(
    method: OffsetMethod,
    ref_t: &[f64],
    ref_p: &[Vector3<f64>],
    est_t: &[f64],
    est_p: &[Vector3<f64>],
    params: &OffsetParams,
    ref_exclude: &[(f64, f64)],
    est_exclude: &[(f64, f64)],
) -> Result<OffsetEstimate> {
    let cache = SignalCache::default();
    let pair = Pair::new((ref_t, ref_p), (est_t, est_p), &cache);
    estimate_time_offset_cached(method, &pair, params, (ref_exclude, est_exclude))
}

/// [`estimate_time_offset_excluding`] with the signals taken from (or put into) `pair`'s cache.
pub fn estimate_time_offset_cached(
    method: OffsetMethod,
    pair: &Pair<'_>,
    params: &OffsetParams,
    (ref_exclude, est_exclude): (Intervals<'_>, Intervals<'_>),
) -> Result<OffsetEstimate> {
    check_params(params)?;
    if matches!(method, OffsetMethod::Auto | OffsetMethod::Pose) {
        // `auto` is decided above the search (crate::align::auto_offset), and the pose fit refines
        // its answer (crate::align::pose_fit), never inside it.
        return Err(Error::InvalidArgument(format!(
            "time offset: `{}` is not a signal search; call auto_time_offset",
            method.as_str()
        )));
    }
    let gap = params.max_gap_s.unwrap_or(params.curvature.dt_max_s);
    let (r, e) = pair.signals(method, params)?;
    let (r, e) = (without(&r, ref_exclude), without(&e, est_exclude));
    let (r, e) = (r.as_ref(), e.as_ref());
    let ((rt, rv, rw), (et, ev, ew)) = (
        (&r.t[..], &r.v[..], &r.yaw_rate[..]),
        (&e.t[..], &e.v[..], &e.yaw_rate[..]),
    );
    let first = search_signals(method, (rt, rv), (et, ev), params)?;
    if method != OffsetMethod::Speed {
        return Ok(first);
    }
    // A lateral lever arm: the estimate's sensor moves at v − ω·d in every turn. Its d is measured at
    // the first answer and taken out of the estimate's speed before a second search.
    match lateral_lever_from_speed((rt, rv, rw), (et, ev), first.offset_s, gap) {
        Some(lever) if lever.abs() >= MIN_SPEED_LEVER_M => {
            // The lever moves Δt by tens of ms: rather than a second search (whose fine peak can
            // jump between neighbouring lags on a change in the last digits), the Gauss–Newton
            // shift of the corrected speed against the reference, continuous in the data.
            let corrected: Vec<f64> = ev.iter().zip(ew).map(|(v, w)| v + lever * w).collect();
            let mut offset = first.offset_s;
            for _ in 0..GAUSS_NEWTON_STEPS {
                match gauss_newton_shift((rt, rv), (et, &corrected), offset, gap) {
                    Some(d) if d.abs() <= REFINE_S => offset += d,
                    _ => return Ok(first),
                }
            }
            let centering = method.centering(params);
            let h = params.coarse_grid_s;
            Ok(OffsetEstimate {
                offset_s: offset,
                sigma_s: offset_sigma((rt, rv), (et, &corrected), offset, h, gap, centering),
                ..first
            })
        }
        _ => Ok(first),
    }
}

/// Both trajectories' signals for `method`, and the lateral lever arm (metres) to take out of the
/// estimate's speed, measured at `offset_s` (what [`estimate_time_offset`] found): the offset profile
/// correlates windows of these. Taken from `pair`'s cache when the search computed them.
pub fn prepared_signals(
    method: OffsetMethod,
    pair: &Pair<'_>,
    params: &OffsetParams,
    offset_s: f64,
) -> Result<(SignalPair, Option<f64>)> {
    check_params(params)?;
    let (r, e) = pair.signals(method, params)?;
    let mut lever = None;
    if method == OffsetMethod::Speed {
        let gap = params.max_gap_s.unwrap_or(params.curvature.dt_max_s);
        lever = lateral_lever_from_speed((&r.t, &r.v, &r.yaw_rate), (&e.t, &e.v), offset_s, gap)
            .filter(|l| l.abs() >= MIN_SPEED_LEVER_M);
    }
    Ok(((r, e), lever))
}

/// The search of one method over two signals already computed (times, values), `est` on the
/// estimate's clock.
pub fn search_signals(
    method: OffsetMethod,
    reference: (&[f64], &[f64]),
    estimate: (&[f64], &[f64]),
    params: &OffsetParams,
) -> Result<OffsetEstimate> {
    check_params(params)?;
    for (s, what) in [(reference, "reference"), (estimate, "estimate")] {
        if s.0.len() < 3 {
            return Err(Error::TooFewSamples {
                what: format!("{what} {} signal", method.as_str()),
                n: s.0.len(),
                need: 3,
            });
        }
    }
    let gap = params.max_gap_s.unwrap_or(params.curvature.dt_max_s);
    search(
        method,
        reference,
        estimate,
        params,
        method.centering(params),
        gap,
    )
}

/// A lateral lever arm below this (metres) is left in the speed (it moves Δt by well under 5 ms).
const MIN_SPEED_LEVER_M: f64 = 0.05;
/// The offset at which a lateral lever is measured is rounded to this, seconds.
const LEVER_GRID_S: f64 = 0.01;
/// The largest step of the lever-corrected refinement, seconds.
const REFINE_S: f64 = 0.5;
/// Gauss–Newton steps of the lever-corrected refinement.
const GAUSS_NEWTON_STEPS: usize = 3;

/// One Gauss–Newton step δ of e(t) ≈ g·r(t + offset + δ) + c over the estimate's samples (r′ by
/// central differences of the interpolated reference): δ = Σ r′·(e − g·r − c) / (g·Σ r′²), g and c
/// from the least squares of e on r at `offset`. `None` when the signals do not determine it.
fn gauss_newton_shift(
    (rt, rv): (&[f64], &[f64]),
    (et, ev): (&[f64], &[f64]),
    offset: f64,
    gap: f64,
) -> Option<f64> {
    let h = 0.05;
    // One pass of raw sums over the points (e, r, r′) rather than the points kept (three values a
    // sample of a 200 Hz estimate are 35 MB on a 2-hour mission); the centred sums follow from them.
    // Three cursors (t − h, t, t + h): the estimate's times rise, so each walks the reference once.
    let cursors = [0usize; 3].map(std::cell::Cell::new);
    let at = |t: f64, c: usize| -> Option<f64> {
        let i = count_below(rt, t, &cursors[c]);
        if i == 0 || i >= rt.len() || rt[i] - rt[i - 1] > gap {
            return None;
        }
        let f = (t - rt[i - 1]) / (rt[i] - rt[i - 1]);
        Some(rv[i - 1] + f * (rv[i] - rv[i - 1]))
    };
    let mut n = 0usize;
    let [mut se, mut sr, mut srr, mut ser, mut sd, mut sdd, mut sde, mut sdr] = [0.0f64; 8];
    for (&t, &e) in et.iter().zip(ev) {
        let t = t + offset;
        if let (Some(r), Some(up), Some(down)) = (at(t, 1), at(t + h, 2), at(t - h, 0)) {
            let d = (up - down) / (2.0 * h);
            n += 1;
            se += e;
            sr += r;
            srr += r * r;
            ser += e * r;
            sd += d;
            sdd += d * d;
            sde += d * e;
            sdr += d * r;
        }
    }
    if n < 10 {
        return None;
    }
    let nf = n as f64;
    let (me, mr) = (se / nf, sr / nf);
    let srr = srr - nf * mr * mr;
    let ser = ser - nf * me * mr;
    let g = ser / srr;
    if !(srr > 0.0 && sdd > 0.0 && g.abs() > 1e-6) {
        return None;
    }
    // Σ r′·((e − ē) − g·(r − r̄)).
    let num = (sde - me * sd) - g * (sdr - mr * sd);
    let d = num / (g * sdd);
    d.is_finite().then_some(d)
}

/// The largest lateral lever arm taken out of the speed, metres.
const MAX_SPEED_LEVER_M: f64 = 3.0;

/// The lateral lever arm d (metres, estimate sensor to the left of the reference's positive) that
/// best explains the estimate's speed at `offset_s` as a·(v_ref − ω_ref·d) + c, by least squares over
/// the estimate's samples; `None` when the turns do not determine it or it is implausible.
fn lateral_lever_from_speed(
    (rt, rv, rw): (&[f64], &[f64], &[f64]),
    (et, ev): (&[f64], &[f64]),
    offset_s: f64,
    gap: f64,
) -> Option<f64> {
    // Normal equations of ev = a·rv + b·rw + c.
    // At a whole number of 10 ms: d does not move with the last digits of the offset (a rigid
    // transform of the estimate changes those, and nothing else may).
    let offset_s = (offset_s / LEVER_GRID_S).round() * LEVER_GRID_S;
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    let mut y = nalgebra::Vector3::<f64>::zeros();
    let cursor = std::cell::Cell::new(0);
    for (&te, &v) in et.iter().zip(ev) {
        let t = te + offset_s;
        let i = count_below(rt, t, &cursor);
        if i == 0 || i >= rt.len() || rt[i] - rt[i - 1] > gap {
            continue;
        }
        let f = (t - rt[i - 1]) / (rt[i] - rt[i - 1]);
        let x = nalgebra::Vector3::new(
            rv[i - 1] + f * (rv[i] - rv[i - 1]),
            rw[i - 1] + f * (rw[i] - rw[i - 1]),
            1.0,
        );
        m += x * x.transpose();
        y += x * v;
    }
    let sol = m.try_inverse()? * y;
    let (a, b) = (sol[0], sol[1]);
    if a.abs() < 0.1 || !b.is_finite() {
        return None;
    }
    let d = -b / a;
    // Rounded (1 cm, 0.1 % of gain): the correction must not move with the last digits of the
    // signals, which differ between frames by the noise estimate's rounding.
    let (d, a) = ((d * 100.0).round() / 100.0, (a * 1000.0).round() / 1000.0);
    (d.abs() <= MAX_SPEED_LEVER_M).then_some(d * a)
}

/// The number of times in `t` (non-decreasing) below `x`, as `t.partition_point(|&v| v < x)`, walked
/// from the previous answer in `hint`: rising queries cost the walk, not a bisection each.
fn count_below(t: &[f64], x: f64, hint: &std::cell::Cell<usize>) -> usize {
    let mut i = hint.get().min(t.len());
    while i < t.len() && t[i] < x {
        i += 1;
    }
    while i > 0 && t[i - 1] >= x {
        i -= 1;
    }
    hint.set(i);
    i
}

/// The two-stage search (see the module doc) over two signals already computed.
fn search(
    method: OffsetMethod,
    (rt, rv): (&[f64], &[f64]),
    (et, ev): (&[f64], &[f64]),
    params: &OffsetParams,
    centering: Centering,
    gap: f64,
) -> Result<OffsetEstimate> {
    let no_overlap = || Error::NoOverlap {
        estimate: format!("estimate {} signal", method.as_str()),
        est_start: et[0],
        est_end: et[et.len() - 1],
        ref_start: rt[0],
        ref_end: rt[rt.len() - 1],
        offset: params.max_offset_s,
    };
    let coarse =
        coarse_peak(method, (rt, rv), (et, ev), params, centering, gap).ok_or_else(no_overlap)?;
    let (offset, peak) = fine_peak((rt, rv), (et, ev), params, centering, gap, coarse.offset_s)
        .ok_or_else(no_overlap)?;
    let confidence = coarse.confidence();
    let h = params.coarse_grid_s;
    let sigma_s = offset_sigma((rt, rv), (et, ev), offset, h, gap, centering);
    let status = if confidence >= MIN_CONFIDENCE && peak >= MIN_CORRELATION && !coarse.at_edge {
        OffsetStatus::Ok
    } else {
        OffsetStatus::Weak
    };
    Ok(OffsetEstimate {
        method,
        offset_s: offset,
        correlation: peak,
        confidence,
        status,
        overlap_fraction: coarse.overlap_fraction,
        margin: coarse.lobe.margin,
        rival_offset_s: coarse.rival_offset_s,
        defined_fraction: coarse.defined_fraction,
        sigma_s,
    })
}

/// The coarse stage's answer: the peak of the NCC over the whole search range, coarse grid.
struct CoarsePeak {
    /// Δt at the peak, seconds.
    offset_s: f64,
    /// Overlap at the peak over the defined points of the shorter signal.
    overlap_fraction: f64,
    /// Share of the two trajectories' time overlap (at the peak) where both signals are defined.
    defined_fraction: f64,
    /// The peak against the rest of the curve.
    lobe: Lobe,
    /// Δt of the best rival outside the main lobe, seconds.
    rival_offset_s: Option<f64>,
    /// Whether the peak is at an end of the search range.
    at_edge: bool,
}

impl CoarsePeak {
    /// The confidence in [0, 1] (see the module doc): the separation, times the prominence, the
    /// overlap and the defined share, each over what counts as full.
    fn confidence(&self) -> f64 {
        (self.lobe.separation
            * (self.lobe.prominence / PROMINENCE_FULL).clamp(0.0, 1.0)
            * (self.overlap_fraction / OVERLAP_FULL).clamp(0.0, 1.0)
            * (self.defined_fraction / DEFINED_FULL).clamp(0.0, 1.0))
        .clamp(0.0, 1.0)
    }
}

/// The coarse stage: the NCC of every lag within ±`max_offset_s` on the coarse grid, both grids
/// read a block at a time (never held whole), and its peak among the lags whose overlap is at least
/// [`MIN_OVERLAP_SHARE`] of the best. `None` when the signals do not overlap.
fn coarse_peak(
    method: OffsetMethod,
    (rt, rv): (&[f64], &[f64]),
    (et, ev): (&[f64], &[f64]),
    params: &OffsetParams,
    centering: Centering,
    gap: f64,
) -> Option<CoarsePeak> {
    // Lag k pairs est grid point n with ref grid point n + k, i.e. Δt = k·h.
    let h = params.coarse_grid_s;
    let e = LazyGrid::new(et, ev, h, gap);
    let r = LazyGrid::new(rt, rv, h, gap);
    let (e_def, r_def) = (e.defined_count(), r.defined_count());
    if e_def < 3 || r_def < 3 {
        return None;
    }
    let k_max = (params.max_offset_s / h).floor() as i64;
    let shift = e.first_index - r.first_index; // array lag = k + shift
    let coarse = masked_ncc_blocks(&e, &r, -k_max + shift, k_max + shift, centering);
    let best_overlap = coarse.overlap.iter().copied().max().unwrap_or(0);
    if best_overlap < 3 {
        return None;
    }
    let min_overlap = ((MIN_OVERLAP_SHARE * best_overlap as f64).ceil() as usize).max(3);
    let eligible: Vec<usize> = (0..coarse.len())
        .filter(|&i| coarse.overlap[i] >= min_overlap)
        .collect();
    let &i_peak = eligible
        .iter()
        .max_by(|&&x, &&y| coarse.ncc[x].total_cmp(&coarse.ncc[y]))?;
    let offset_s = (coarse.lag(i_peak) - shift) as f64 * h;
    let overlap_fraction = coarse.overlap[i_peak] as f64 / e_def.min(r_def) as f64;
    // Share of the time both trajectories overlap (at the peak) where both signals are defined.
    let span =
        (rt[rt.len() - 1].min(et[et.len() - 1] + offset_s) - rt[0].max(et[0] + offset_s)).max(h);
    let defined_fraction = (coarse.overlap[i_peak] as f64 * h / span).clamp(0.0, 1.0);
    let min_lobe_s = match method {
        OffsetMethod::Speed => MIN_LOBE_SPEED_S.max(params.speed_window_s),
        _ => MIN_LOBE_CURVATURE_S,
    };
    let lobe = peak_separation(&coarse.ncc, &eligible, i_peak, h, min_lobe_s);
    Some(CoarsePeak {
        offset_s,
        overlap_fraction,
        defined_fraction,
        rival_offset_s: lobe.rival.map(|i| (coarse.lag(i) - shift) as f64 * h),
        lobe,
        at_edge: i_peak == 0 || i_peak + 1 == coarse.len(),
    })
}

/// The fine stage: every fine step (`grid_s`) within ±[`FINE_WINDOW_COARSE_STEPS`] coarse steps of
/// the coarse peak `coarse_offset_s`, the best NCC among the lags whose overlap is at least
/// [`MIN_OVERLAP_SHARE`] of the best, refined between the steps ([`parabola_peak`]): Δt and the
/// peak NCC. `None` when no lag overlaps.
fn fine_peak(
    (rt, rv): (&[f64], &[f64]),
    (et, ev): (&[f64], &[f64]),
    params: &OffsetParams,
    centering: Centering,
    gap: f64,
    coarse_offset_s: f64,
) -> Option<(f64, f64)> {
    let h = params.coarse_grid_s;
    let hf = params.grid_s;
    let lo = ((coarse_offset_s - FINE_WINDOW_COARSE_STEPS * h) / hf).round() as i64;
    let hi = ((coarse_offset_s + FINE_WINDOW_COARSE_STEPS * h) / hf).round() as i64;
    let kf_max = (params.max_offset_s / hf).floor() as i64;
    let (lo, hi) = (lo.max(-kf_max), hi.min(kf_max));
    let sums = fine_sums((et, ev), (rt, rv), hf, gap, lo, hi);
    let fine: Vec<f64> = sums.iter().map(|s| s.ncc(centering)).collect();
    let fine_min_overlap = sums.iter().map(|s| s.n).fold(0.0, f64::max) * MIN_OVERLAP_SHARE;
    let j = (0..fine.len())
        .filter(|&j| sums[j].n >= fine_min_overlap.max(3.0))
        .max_by(|&x, &y| fine[x].total_cmp(&fine[y]))?;
    Some(parabola_peak(&fine, j, (lo + j as i64) as f64 * hf, hf))
}

/// The sub-step peak of `ncc` around its best index `j` (at Δt `offset_s`, steps of `step_s`): the
/// vertex of the parabola through j and its neighbours when it opens downwards, at most half a step
/// away; Δt and the NCC there.
fn parabola_peak(ncc: &[f64], j: usize, offset_s: f64, step_s: f64) -> (f64, f64) {
    let (mut offset, mut peak) = (offset_s, ncc[j]);
    if j > 0 && j + 1 < ncc.len() {
        let (ym, y0, yp) = (ncc[j - 1], ncc[j], ncc[j + 1]);
        let denom = ym - 2.0 * y0 + yp;
        if denom < 0.0 {
            let d = (0.5 * (ym - yp) / denom).clamp(-0.5, 0.5);
            offset += d * step_s;
            peak = y0 - 0.25 * (ym - yp) * d;
        }
    }
    (offset, peak)
}

/// The samples of a signal outside every interval of `exclude` (the grid does not interpolate across
/// the hole when it is longer than the largest gap bridged); the signal itself when nothing is
/// excluded.
fn without<'s>(s: &'s Signal, exclude: &[(f64, f64)]) -> std::borrow::Cow<'s, Signal> {
    if exclude.is_empty() {
        return std::borrow::Cow::Borrowed(s);
    }
    let kept: Vec<usize> = (0..s.t.len())
        .filter(|&i| !exclude.iter().any(|&(a, b)| s.t[i] >= a && s.t[i] <= b))
        .collect();
    // The heading rates are empty for the curvature methods: they stay empty.
    let pick = |v: &[f64]| -> Vec<f64> {
        if v.is_empty() {
            Vec::new()
        } else {
            kept.iter().map(|&i| v[i]).collect()
        }
    };
    std::borrow::Cow::Owned(Signal {
        t: Arc::new(pick(&s.t)),
        v: pick(&s.v),
        yaw_rate: pick(&s.yaw_rate),
    })
}

fn check_params(p: &OffsetParams) -> Result<()> {
    let positive = |v: f64, name: &str| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(Error::InvalidArgument(format!(
                "time offset: {name} must be a positive number of seconds, got {v}"
            )))
        }
    };
    positive(p.max_offset_s, "max offset")?;
    positive(p.grid_s, "grid step")?;
    positive(p.coarse_grid_s, "coarse grid step")?;
    positive(p.speed_window_s, "speed window")?;
    positive(p.curvature.dt_max_s, "dt_max")?;
    if let Some(g) = p.max_gap_s {
        positive(g, "max gap")?;
    }
    if p.grid_s > p.coarse_grid_s {
        return Err(Error::InvalidArgument(format!(
            "time offset: the grid step ({} s) must not exceed the coarse grid step ({} s)",
            p.grid_s, p.coarse_grid_s
        )));
    }
    Ok(())
}

/// The peak against the rest of the NCC curve (see the module doc).
struct Lobe {
    /// (ρ − ρ₂)/P in [0, 1].
    separation: f64,
    /// P = ρ − median.
    prominence: f64,
    /// ρ − ρ₂ (0 without a rival).
    margin: f64,
    /// Index of the best lag outside the main lobe.
    rival: Option<usize>,
}

/// Separation of the peak from its best rival outside the main lobe, and the peak's prominence over
/// the median (see the module doc). The main lobe is the union of (a) the run above half prominence
/// widened by its own width on each side and (b) the descent from the peak to the first real
/// minimum on each side (ripples below 5 % of P are walked through; at most 20 s), and is at least
/// ±`min_lobe_s`: the broad shoulders of a speed correlation are not rivals.
fn peak_separation(
    ncc: &[f64],
    eligible: &[usize],
    i_peak: usize,
    step: f64,
    min_lobe_s: f64,
) -> Lobe {
    let weak = |prominence: f64| Lobe {
        separation: 0.0,
        prominence,
        margin: 0.0,
        rival: None,
    };
    let mut vals: Vec<f64> = eligible.iter().map(|&i| ncc[i]).collect();
    vals.sort_by(f64::total_cmp);
    let median = vals[vals.len() / 2];
    let rho = ncc[i_peak];
    let prominence = rho - median;
    if prominence.is_nan() || prominence <= 0.0 {
        return weak(0.0);
    }
    let half = median + 0.5 * prominence;
    let (mut a, mut b) = (i_peak, i_peak);
    while a > 0 && ncc[a - 1] >= half {
        a -= 1;
    }
    while b + 1 < ncc.len() && ncc[b + 1] >= half {
        b += 1;
    }
    let width = (b - a + 1).max((min_lobe_s / step).ceil() as usize);
    let mut lo = a.saturating_sub(width);
    let mut hi = b + width;
    // The descent to the first minimum on each side, tracking the lowest value seen so far.
    let ripple = 0.05 * prominence;
    let reach = (MAX_LOBE_S / step).ceil() as usize;
    let (mut low, mut k) = (rho, i_peak);
    while k > 0 && i_peak - k < reach && ncc[k - 1] <= low + ripple {
        k -= 1;
        low = low.min(ncc[k]);
    }
    lo = lo.min(k);
    let (mut low, mut k) = (rho, i_peak);
    while k + 1 < ncc.len() && k - i_peak < reach && ncc[k + 1] <= low + ripple {
        k += 1;
        low = low.min(ncc[k]);
    }
    hi = hi.max(k);
    let rival = eligible
        .iter()
        .copied()
        .filter(|&i| i < lo || i > hi)
        .max_by(|&x, &y| ncc[x].total_cmp(&ncc[y]));
    let Some(r) = rival else {
        // Nothing outside the lobe to compare with: the peak is not shown to be unique.
        return weak(prominence);
    };
    Lobe {
        separation: ((rho - ncc[r]) / prominence).clamp(0.0, 1.0),
        prominence,
        margin: rho - ncc[r],
        rival: Some(r),
    }
}
