//! The correlation curves of the offset search near its answer, recomputed for the figure: the report
//! keeps each method's peak, not the curve. Built from the search's own pieces (the signals of
//! [`Pair`], the coarse grid, `masked_ncc_blocks`), so the curve is the one the search's coarse stage
//! saw; the marked peak is the refined answer from the report.

use nalgebra::Vector3;

use crate::align::grid::LazyGrid;
use crate::align::time_offset::{OffsetMethod, OffsetParams, Pair, SignalCache};
use crate::align::xcorr::masked_ncc_blocks;

/// One method's NCC against the offset Δt (seconds).
#[derive(Debug, Clone)]
pub struct CorrelationCurve {
    pub method: OffsetMethod,
    pub points: Vec<(f64, f64)>,
    /// The method's refined answer (Δt, peak NCC), from the report.
    pub peak: Option<(f64, f64)>,
}

/// The NCC of `method` at Δt in `[center − half_width, center + half_width]` on the coarse grid.
/// Times are seconds from a common origin; `est_t` is on the estimate's own clock.
#[allow(clippy::too_many_arguments)]
pub fn correlation_curve(
    method: OffsetMethod,
    ref_t: &[f64],
    ref_p: &[Vector3<f64>],
    est_t: &[f64],
    est_p: &[Vector3<f64>],
    params: &OffsetParams,
    center_s: f64,
    half_width_s: f64,
) -> Vec<(f64, f64)> {
    let gap = params.max_gap_s.unwrap_or(params.curvature.dt_max_s);
    let cache = SignalCache::default();
    let pair = Pair::new((ref_t, ref_p), (est_t, est_p), &cache);
    let Ok((r, e)) = pair.signals(method, params) else {
        return Vec::new();
    };
    let h = params.coarse_grid_s;
    let e = LazyGrid::new(&e.t, &e.v, h, gap);
    let r = LazyGrid::new(&r.t, &r.v, h, gap);
    // Lag k pairs estimate grid point n with reference grid point n + k: Δt = k·h.
    let shift = e.first_index - r.first_index;
    let k0 = ((center_s - half_width_s) / h).floor() as i64;
    let k1 = ((center_s + half_width_s) / h).ceil() as i64;
    let ncc = masked_ncc_blocks(&e, &r, k0 + shift, k1 + shift, method.centering(params));
    (0..ncc.len())
        .filter(|&i| ncc.overlap[i] >= 3)
        .map(|i| ((ncc.lag(i) - shift) as f64 * h, ncc.ncc[i]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A figure-eight-ish path with speed changes; the estimate lags it by 0.4 s.
    fn path(dt: f64) -> (Vec<f64>, Vec<Vector3<f64>>) {
        (0..3000)
            .map(|i| {
                let t = i as f64 * 0.1;
                let u = t - dt;
                let a = 0.05 * u + 0.3 * (0.11 * u).sin();
                (t, Vector3::new(20.0 * a.sin(), 10.0 * (2.0 * a).sin(), 0.0))
            })
            .unzip()
    }

    #[test]
    fn the_curve_peaks_at_the_shift() {
        let (rt, rp) = path(0.0);
        let (et, ep) = path(0.0);
        let et: Vec<f64> = et.iter().map(|t| t - 0.4).collect();
        let params = OffsetParams::default();
        for m in [OffsetMethod::SignedCurvature, OffsetMethod::Speed] {
            let c = correlation_curve(m, &rt, &rp, &et, &ep, &params, 0.0, 3.0);
            let best = c.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
            assert!((best.0 - 0.4).abs() < 0.05, "{m:?}: peak at {}", best.0);
        }
    }
}
