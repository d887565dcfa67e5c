//! The standard error of a time offset, from the data that gave it.
//!
//! A correlation peak says where the two signals agree best, not how well that place is pinned down.
//! Whether a drift of the clocks shows between the first and the last third of a mission depends on
//! exactly that: on a few minutes of driving the thirds' offsets scatter by tens of milliseconds, on
//! two hours by a few. So every offset gets a standard error, computed from its own residual.
//!
//! Linearising y(t) = a·x(t − δ) + r(t) around the peak (x the reference signal, y the estimate's,
//! both on the grid, shifted by the estimate), the least-squares shift is
//! δ̂ = −Σ x′·r / (a·Σ x′²), so var δ̂ = var(Σ x′·r) / (a·Σ x′²)². The residual r is not white: it
//! carries the speed window's smoothing and the systematic differences between two sensors (a
//! lateral lever arm changes the speed in every turn). Its variance is therefore taken by batch
//! means — var(Σ x′·r) ≈ Σ_b (Σ_{k∈b} x′_k·r_k)² over blocks of [`BLOCK_S`] seconds, longer than the
//! residual's correlation — which holds for any residual that decorrelates within a block. Either
//! signal may be the noisy one, so the slope is taken from each in turn and the larger error kept.
//!
//! What the residual cannot show is noise that has already moved the peak (at the peak it is no
//! longer in the residual): [`crate::align::offset_profile`] scales it by the scatter of the profile.

use crate::align::grid::resample;
use crate::align::xcorr::Centering;

/// Length of the blocks of the batch-means variance, seconds: longer than the speed window and than a
/// turn (the residual's correlation time), short enough for a third of a few-minute mission to hold
/// several.
pub const BLOCK_S: f64 = 10.0;
/// The fewest blocks the variance is taken from.
pub const MIN_BLOCKS: usize = 3;

/// The standard error of `offset_s`, seconds, for the signals `reference` and `estimate` (times,
/// values) compared on a grid of `step` with gaps longer than `max_gap_s` left undefined. `None` when
/// the overlap holds fewer than [`MIN_BLOCKS`] blocks or a signal is flat.
pub fn offset_sigma(
    (ref_t, ref_v): (&[f64], &[f64]),
    (est_t, est_v): (&[f64], &[f64]),
    offset_s: f64,
    step: f64,
    max_gap_s: f64,
    centering: Centering,
) -> Option<f64> {
    let x = resample(ref_t, ref_v, step, max_gap_s);
    let y = {
        // Dropped once resampled (a second copy of the estimate's times).
        let shifted: Vec<f64> = est_t.iter().map(|t| t + offset_s).collect();
        resample(&shifted, est_v, step, max_gap_s)
    };
    let lo = x.first_index.max(y.first_index);
    let hi = (x.first_index + x.len() as i64).min(y.first_index + y.len() as i64);
    let defined = |s: &crate::align::grid::RegularSignal, n: i64| {
        let i = n - s.first_index;
        (0..s.len() as i64).contains(&i) && s.mask[i as usize] > 0.5
    };
    let value =
        |s: &crate::align::grid::RegularSignal, n: i64| s.values[(n - s.first_index) as usize];
    // Grid points where both signals and both central differences are defined.
    let points: Vec<GridPoint> = (lo + 1..hi - 1)
        .filter(|&n| (n - 1..=n + 1).all(|m| defined(&x, m) && defined(&y, m)))
        .map(|n| GridPoint {
            n,
            x: value(&x, n),
            y: value(&y, n),
            dx: (value(&x, n + 1) - value(&x, n - 1)) / (2.0 * step),
            dy: (value(&y, n + 1) - value(&y, n - 1)) / (2.0 * step),
        })
        .collect();
    let block = (BLOCK_S / step).round().max(1.0) as i64;
    if points.len() < 3 || (points[points.len() - 1].n - points[0].n) < MIN_BLOCKS as i64 * block {
        return None;
    }
    // Either signal may carry the noise (a GNSS reference is usually the noisier, an odometry
    // estimate the smoother): the slope is taken from one, the residual against the other, both
    // ways, and the larger error kept.
    let a = one_way(&points, |p| (p.x, p.y, p.dx), centering, block);
    let b = one_way(&points, |p| (p.y, p.x, p.dy), centering, block);
    match (a, b) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    }
}

/// One grid point where both signals are defined: index, values, central differences.
struct GridPoint {
    n: i64,
    x: f64,
    y: f64,
    dx: f64,
    dy: f64,
}

/// The standard error with the slope taken from the first signal `pick` returns (value, other
/// value, slope of the first).
fn one_way(
    points: &[GridPoint],
    pick: fn(&GridPoint) -> (f64, f64, f64),
    centering: Centering,
    block: i64,
) -> Option<f64> {
    let count = points.len() as f64;
    let (mx, my) = match centering {
        Centering::MeanRemoved => (
            points.iter().map(|p| pick(p).0).sum::<f64>() / count,
            points.iter().map(|p| pick(p).1).sum::<f64>() / count,
        ),
        Centering::Raw => (0.0, 0.0),
    };
    let sxx: f64 = points.iter().map(|p| (pick(p).0 - mx).powi(2)).sum();
    let sxy: f64 = points
        .iter()
        .map(|p| (pick(p).0 - mx) * (pick(p).1 - my))
        .sum();
    let sdd: f64 = points.iter().map(|p| pick(p).2.powi(2)).sum();
    if !(sxx > 0.0 && sdd > 0.0) {
        return None;
    }
    let gain = sxy / sxx;
    // Batch means of z = x′·r over consecutive blocks of the grid.
    let first = points[0].n;
    let mut sums: Vec<f64> = Vec::new();
    for p in points {
        let (xv, yv, d) = pick(p);
        let b = ((p.n - first) / block) as usize;
        if sums.len() <= b {
            sums.resize(b + 1, 0.0);
        }
        sums[b] += d * ((yv - my) - gain * (xv - mx));
    }
    let var_sum: f64 = sums.iter().map(|s| s * s).sum();
    let sigma = var_sum.sqrt() / (gain.abs() * sdd);
    sigma.is_finite().then_some(sigma)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A noisy copy of a smooth signal: the standard error matches the scatter of the offsets the
    /// linearised least squares would give, within a factor of two.
    #[test]
    fn white_noise_gives_the_textbook_error() {
        // x(t) = sin(0.7 t) + 0.5 sin(1.9 t), y = x + white noise σ_n, dense samples.
        let h = 0.01;
        let t: Vec<f64> = (0..20_000).map(|i| i as f64 * h).collect();
        let x: Vec<f64> = t
            .iter()
            .map(|&t| (0.7 * t).sin() + 0.5 * (1.9 * t).sin())
            .collect();
        let sigma_n = 0.1;
        // Deterministic pseudo-noise (LCG), uniform with the right variance.
        let mut s = 12345u64;
        let y: Vec<f64> = x
            .iter()
            .map(|&v| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                v + u * sigma_n * 12f64.sqrt()
            })
            .collect();
        let got = offset_sigma((&t, &x), (&t, &y), 0.0, h, 1.0, Centering::MeanRemoved).unwrap();
        // Textbook: σ_δ = σ_n / √(Σ x′²).
        let sdd: f64 = t
            .iter()
            .map(|&t| (0.7 * (0.7 * t).cos() + 0.95 * (1.9 * t).cos()).powi(2))
            .sum();
        let want = sigma_n / sdd.sqrt();
        assert!(got > 0.5 * want && got < 2.0 * want, "{got} vs {want}");
    }

    #[test]
    fn too_short_has_no_error() {
        let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
        let x: Vec<f64> = t.iter().map(|t| t.sin()).collect();
        assert!(offset_sigma((&t, &x), (&t, &x), 0.0, 0.02, 1.0, Centering::Raw).is_none());
    }
}
