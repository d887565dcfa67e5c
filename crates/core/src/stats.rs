//! Summary statistics of a metric's per-window (or per-pose) values, in the style evo prints them, so
//! that a number from trajdrift can be put next to one from evo without a footnote.
//!
//! Quantiles use linear interpolation between closest ranks (numpy's default `method="linear"`), and
//! `std` is the population standard deviation (numpy's default `ddof=0`, which evo uses). Hand-written:
//! ten lines of arithmetic do not justify a statistics crate.

/// The statistics of a set of values.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Summary {
    /// Root mean square.
    pub rmse: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// 50 % quantile.
    pub median: f64,
    /// Population standard deviation.
    pub std: f64,
    /// 25 % quantile.
    pub q1: f64,
    /// 75 % quantile.
    pub q3: f64,
    /// 95 % quantile.
    pub p95: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Number of values.
    pub n: usize,
}

/// Summarizes `values`, ignoring non-finite ones. `None` when no finite value is left.
///
/// ```
/// use trajdrift_core::stats::summarize;
/// let s = summarize(&[1.0, 2.0, 3.0, 4.0]).unwrap();
/// assert_eq!(s.median, 2.5);
/// assert_eq!(s.q1, 1.75); // numpy.quantile([1, 2, 3, 4], 0.25)
/// ```
pub fn summarize(values: &[f64]) -> Option<Summary> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    // Unstable and on every core: values equal under `total_cmp` are the same bits, so the order (and
    // every statistic below) is the one a stable sort gives; a million APE values sort in a third of the time.
    rayon::slice::ParallelSliceMut::par_sort_unstable_by(v.as_mut_slice(), f64::total_cmp);
    let n = v.len();
    let nf = n as f64;
    let mean = v.iter().sum::<f64>() / nf;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / nf;
    let rmse = (v.iter().map(|x| x * x).sum::<f64>() / nf).sqrt();
    Some(Summary {
        rmse,
        mean,
        median: quantile_sorted(&v, 0.5),
        std: var.sqrt(),
        q1: quantile_sorted(&v, 0.25),
        q3: quantile_sorted(&v, 0.75),
        p95: quantile_sorted(&v, 0.95),
        min: v[0],
        max: v[n - 1],
        n,
    })
}

/// The median of `v`: the middle value, or the mean of the two middle ones (`None` when empty).
///
/// ```
/// use trajdrift_core::stats::median;
/// assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
/// assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
/// assert_eq!(median(&[]), None);
/// ```
pub fn median(v: &[f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    Some(if s.len() % 2 == 1 {
        s[m]
    } else {
        0.5 * (s[m - 1] + s[m])
    })
}

/// The median step between consecutive times `t`, by selection (the upper of the two middle steps
/// for an even count: the element a full sort puts at the middle index, in linear time); `None`
/// with fewer than two times. A series' typical sampling period, which gaps and jitter barely move.
///
/// ```
/// use trajdrift_core::stats::median_step;
/// assert_eq!(median_step(&[0.0, 0.25, 0.5, 1.5, 1.75]), Some(0.25));
/// assert_eq!(median_step(&[0.0, 1.0, 3.0]), Some(2.0));
/// assert_eq!(median_step(&[5.0]), None);
/// ```
pub fn median_step(t: &[f64]) -> Option<f64> {
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if steps.is_empty() {
        return None;
    }
    let mid = steps.len() / 2;
    Some(*steps.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// How far the stamps `t` of a stream sampled every `period` seconds stray from an even grid,
/// seconds: the σ of each stamp's own error, estimated robustly from the consecutive steps (each
/// step's error is the difference of two stamps' errors, σ·√2; 1.4826 × their median absolute
/// deviation from `period` estimates that σ for normal errors, and 0.73 of the mean latency for
/// exponential ones, stamps taken at receipt). A dropped sample, a step of two periods, moves the
/// median no more than any other outlier. 0 with fewer than two times.
///
/// ```
/// use trajdrift_core::stats::stamp_jitter_s;
/// let even: Vec<f64> = (0..100).map(|i| i as f64 * 0.02).collect();
/// assert!(stamp_jitter_s(&even, 0.02) < 1e-12);
/// // Every other stamp 4 ms late: each step is 4 ms off; σ of a stamp 4·1.4826/√2 ≈ 4.2 ms.
/// let late: Vec<f64> = (0..100).map(|i| i as f64 * 0.02 + if i % 2 == 1 { 0.004 } else { 0.0 }).collect();
/// assert!((stamp_jitter_s(&late, 0.02) - 0.004 * 1.4826 / 2f64.sqrt()).abs() < 1e-9);
/// assert_eq!(stamp_jitter_s(&[1.0], 0.02), 0.0);
/// ```
pub fn stamp_jitter_s(t: &[f64], period: f64) -> f64 {
    let mut dev: Vec<f64> = t.windows(2).map(|w| (w[1] - w[0] - period).abs()).collect();
    if dev.is_empty() {
        return 0.0;
    }
    let mid = dev.len() / 2;
    1.4826 * *dev.select_nth_unstable_by(mid, f64::total_cmp).1 / std::f64::consts::SQRT_2
}

/// The `q` quantile (0 ≤ q ≤ 1) of sorted, non-empty `v`, linear between closest ranks (numpy default).
pub fn quantile_sorted(v: &[f64], q: f64) -> f64 {
    let h = (v.len() - 1) as f64 * q.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    v[lo] + (h - lo as f64) * (v[hi] - v[lo])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_numpy() {
        // numpy: x = [3, 1, 4, 1, 5, 9, 2, 6]; np.quantile(x, [.25, .5, .75, .95]) = 1.75, 3.5, 5.25, 7.95
        let s = summarize(&[3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0, 6.0]).unwrap();
        assert!((s.q1 - 1.75).abs() < 1e-12);
        assert!((s.median - 3.5).abs() < 1e-12);
        assert!((s.q3 - 5.25).abs() < 1e-12);
        assert!((s.p95 - 7.95).abs() < 1e-12);
        assert!((s.mean - 3.875).abs() < 1e-12);
        // np.std(x) = 2.5708704751503917, sqrt(mean(x²)) = sqrt(173/8)
        assert!((s.std - 2.5708704751503917).abs() < 1e-12);
        assert!((s.rmse - (173.0f64 / 8.0).sqrt()).abs() < 1e-12);
        assert_eq!((s.min, s.max, s.n), (1.0, 9.0, 8));
    }

    #[test]
    fn empty_and_non_finite() {
        assert!(summarize(&[]).is_none());
        assert!(summarize(&[f64::NAN]).is_none());
        let s = summarize(&[f64::NAN, 2.0]).unwrap();
        assert_eq!((s.median, s.n), (2.0, 1));
    }
}
