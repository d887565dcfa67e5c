//! The offset profile: Δt(t) over sliding windows of the mission, each with an honest σ.
//!
//! The signal of the applied method (speed or signed curvature) is computed once per trajectory
//! ([`crate::align::signals::Pair`]); each window then correlates a slice of the two
//! signals — the reference's cut to the window, the estimate's (already shifted by the whole
//! mission's Δt₀) reaching [`SEARCH_S`] past it on both sides — over ±[`SEARCH_S`] around Δt₀. No
//! re-run of the whole pipeline per window.
//!
//! **Window and step.** From the data: the window is a tenth of the overlap, clamped to
//! [[`MIN_WINDOW_S`], [`MAX_WINDOW_S`]] (long enough to hold several starts, stops and turns; short
//! enough that a 20-minute mission has ten), the step half of it; both can be given.
//!
//! **σ per window.** The residual σ of `crate::align::offset_sigma` sees the residual's size but
//! not the noise that moved the peak, nor a shape difference between two sensors' signals: on real
//! data it is ~100× too small. It is kept only as the windows' *relative* weight, and only upwards
//! (a window's σ is at least the median window's: a small residual is no proof); its scale comes
//! from the data: the second differences Δ_{i−2} − 2Δ_i + Δ_{i+2} of non-overlapping windows are
//! free of any constant and of any linear drift, and under honest σ_i each divided by
//! √(σ²_{i−2} + 4σ²_i + σ²_{i+2}) is a unit normal. The scale f² is the median of their squares
//! over the median of χ²₁ (0.455): robust to the few second differences a step makes. f ≥ 1 (the
//! residual is never taken as too large), and each σ is at least [`SIGMA_FLOOR_S`] (the fine grid
//! and the method's own bias of a few ms). tests/it/time_offset_profile.rs `coverage_table` shows the
//! coverage of 2σ over simulated missions.

pub use crate::stats::median;
use rayon::prelude::*;

use crate::align::time_offset::{search_signals, OffsetMethod, OffsetParams, SignalView};

/// Residual offset searched in each window around the whole mission's Δt₀, seconds.
pub const SEARCH_S: f64 = 3.0;
/// Least window, seconds.
pub const MIN_WINDOW_S: f64 = 20.0;
/// Largest window chosen from the data, seconds.
pub const MAX_WINDOW_S: f64 = 120.0;
/// Least σ of a window or of the headline Δt, seconds.
pub const SIGMA_FLOOR_S: f64 = 0.002;
/// Median of the χ² distribution with one degree of freedom.
const CHI2_1_MEDIAN: f64 = 0.4549;
/// Fine grid of the windows' searches, seconds (their parabola resolves a fraction of it).
const PROFILE_GRID_S: f64 = 0.002;
/// A window's peak this close to the edge of its search range is not used, seconds.
const EDGE_S: f64 = 0.1;
/// The least peak NCC of a window that is used.
const MIN_WINDOW_CORRELATION: f64 = 0.3;

/// Window and step of the profile (`None`: from the data).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct ProfileParams {
    pub window_s: Option<f64>,
    pub step_s: Option<f64>,
}

/// Δt on one window.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ProfileWindow {
    /// The window's centre, seconds on the reference clock (the inputs' origin).
    pub t: f64,
    /// Δt on the window, seconds.
    pub offset_s: f64,
    /// Its standard error, seconds (see the module doc).
    pub sigma_s: f64,
    /// The window's peak NCC.
    pub correlation: f64,
    /// Whether the window's peak is usable (clear, NCC ≥ 0.3): unusable windows are reported, not fitted.
    pub usable: bool,
}

/// The offset profile of one estimate.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct OffsetProfile {
    pub method: OffsetMethod,
    pub window_s: f64,
    pub step_s: f64,
    /// Scale applied to the residual σ (see the module doc), ≥ 1 (the pose fit's windows also carry
    /// an excess added in quadrature, see `pose_fit::scatter_calibration`; this is its factor).
    pub sigma_scale: f64,
    pub windows: Vec<ProfileWindow>,
}

impl OffsetProfile {
    /// The usable windows.
    pub fn usable(&self) -> Vec<ProfileWindow> {
        self.windows.iter().copied().filter(|w| w.usable).collect()
    }

    /// How many windows one window overlaps (window / step, ≥ 1): the factor by which a fit over all
    /// windows counts each stretch of the mission.
    pub fn redundancy(&self) -> f64 {
        (self.window_s / self.step_s).max(1.0)
    }
}

/// The window and step for an overlap of `span_s` seconds.
pub fn window_and_step(span_s: f64, p: &ProfileParams) -> (f64, f64) {
    let w = p
        .window_s
        .unwrap_or_else(|| (span_s / 10.0).clamp(MIN_WINDOW_S, MAX_WINDOW_S));
    let s = p.step_s.unwrap_or(0.5 * w);
    (w, s)
}

/// The profile of `method` over the signals `r` and `e` (the estimate's on its own clock) around the
/// whole mission's `offset_s`: the windows correlate slices of them.
pub fn offset_profile(
    method: OffsetMethod,
    (r, e): (SignalView<'_>, SignalView<'_>),
    params: &OffsetParams,
    offset_s: f64,
    profile: &ProfileParams,
) -> OffsetProfile {
    // Shifted by a whole number of coarse steps (the grid's phase does not move with the last
    // digits of Δt₀); the windows' answers are relative to that.
    let offset_s = (offset_s / params.coarse_grid_s).round() * params.coarse_grid_s;
    let (a, b) = (
        r.t[0].max(e.t[0] + offset_s),
        r.t[r.t.len() - 1].min(e.t[e.t.len() - 1] + offset_s),
    );
    let (window_s, step_s) = window_and_step(b - a, profile);
    let p = OffsetParams {
        max_offset_s: SEARCH_S.min(params.max_offset_s),
        grid_s: params.grid_s.max(PROFILE_GRID_S).min(params.coarse_grid_s),
        ..*params
    };
    let n = if b - a < window_s {
        usize::from(b - a > 0.5 * window_s)
    } else {
        ((b - a - window_s) / step_s).floor() as usize + 1
    };
    let window_s = window_s.min(b - a);
    // Each window's answer, σ still the residual's (NaN when it has none).
    // The windows are independent: searched in parallel (rayon keeps their order).
    let raw: Vec<ProfileWindow> = (0..n)
        .into_par_iter()
        .filter_map(|k| {
            let lo = a + k as f64 * step_s;
            one_window(method, (r, e), &p, (lo, lo + window_s), offset_s)
        })
        .collect();
    let residual: Vec<f64> = raw
        .iter()
        .map(|w| w.sigma_s)
        .filter(|s| s.is_finite() && *s > 0.0)
        .collect();
    let typical = median(&residual).unwrap_or(SIGMA_FLOOR_S);
    // The residual σ may raise a window above the typical one, never lower it: a window whose
    // residual looks small is not thereby more trustworthy than its peers.
    let windows: Vec<ProfileWindow> = raw
        .into_iter()
        .map(|w| ProfileWindow {
            sigma_s: if w.sigma_s.is_finite() {
                w.sigma_s.max(typical)
            } else {
                typical
            },
            ..w
        })
        .collect();
    let stride = ((window_s / step_s).ceil() as usize).max(1);
    let sigma_scale = sigma_scale(&windows, stride);
    let windows = windows
        .into_iter()
        .map(|w| ProfileWindow {
            sigma_s: (w.sigma_s * sigma_scale).max(SIGMA_FLOOR_S),
            ..w
        })
        .collect();
    OffsetProfile {
        method,
        window_s,
        step_s,
        sigma_scale,
        windows,
    }
}

/// The search on the window [lo, hi] of the reference clock: the reference's signal cut to it, the
/// estimate's (shifted by Δt₀, a window's worth at a time) reaching past it by the search range and
/// the speed window.
fn one_window(
    method: OffsetMethod,
    (r, e): (SignalView<'_>, SignalView<'_>),
    p: &OffsetParams,
    (lo, hi): (f64, f64),
    offset_s: f64,
) -> Option<ProfileWindow> {
    let margin = SEARCH_S + p.speed_window_s;
    let ri = range(r.t, lo, hi);
    // The estimate's samples whose shifted times fall in the stretch (the same sums as a shifted
    // copy of every time would give).
    let (elo, ehi) = (lo - margin, hi + margin);
    let ei =
        e.t.partition_point(|&x| x + offset_s < elo)..e.t.partition_point(|&x| x + offset_s <= ehi);
    let shifted: Vec<f64> = e.t[ei.clone()].iter().map(|t| t + offset_s).collect();
    let o = search_signals(
        method,
        (&r.t[ri.clone()], &r.values(ri)),
        (&shifted, &e.values(ei)),
        p,
    )
    .ok()?;
    // The short search range leaves no rival outside the main lobe, so the status (which asks for
    // one) says nothing here: a clear NCC off the search's edge is what counts.
    let usable = o.correlation >= MIN_WINDOW_CORRELATION
        && o.offset_s.abs() < p.max_offset_s - EDGE_S
        && o.overlap_fraction >= 0.5;
    Some(ProfileWindow {
        t: 0.5 * (lo + hi),
        offset_s: offset_s + o.offset_s,
        sigma_s: o.sigma_s.unwrap_or(f64::NAN),
        correlation: o.correlation,
        usable,
    })
}

/// f of the module doc: from the second differences of usable windows `stride` apart (the nearest
/// that do not overlap). 1 when there are too few.
pub fn sigma_scale(windows: &[ProfileWindow], stride: usize) -> f64 {
    let u: Vec<&ProfileWindow> = windows.iter().filter(|w| w.usable).collect();
    let mut chi2 = Vec::new();
    for i in stride..u.len().saturating_sub(stride) {
        let (p, c, n) = (u[i - stride], u[i], u[i + stride]);
        let d = p.offset_s - 2.0 * c.offset_s + n.offset_s;
        let v = p.sigma_s.powi(2) + 4.0 * c.sigma_s.powi(2) + n.sigma_s.powi(2);
        if v > 0.0 {
            chi2.push(d * d / v);
        }
    }
    if chi2.len() < 3 {
        return 1.0;
    }
    median(&chi2).map_or(1.0, |m| (m / CHI2_1_MEDIAN).sqrt().max(1.0))
}

/// Indices of the sorted `t` inside [lo, hi].
pub fn range(t: &[f64], lo: f64, hi: f64) -> std::ops::Range<usize> {
    t.partition_point(|&x| x < lo)..t.partition_point(|&x| x <= hi)
}
