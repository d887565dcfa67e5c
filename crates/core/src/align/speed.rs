//! The speed profile of a trajectory: the signal of the `speed` time-offset method (the baseline the
//! paper argues against — blind when the robot drives at constant speed).
//!
//! Finite differences of consecutive positions are far too noisy (2 cm of reference noise at 10 Hz is
//! 0.28 m/s of speed noise), so the speed is taken over a time window instead: for each sample i, the
//! chord from the first sample at or after t_i − w/2 to the last sample at or before t_i + w/2 gives
//! v = |p_k − p_j| / (t_k − t_j), stamped at the chord's mid-time (t_j + t_k)/2, where a chord-average
//! speed is centred whatever the sampling. Noise drops to ≈ √2·σ/w (0.014 m/s for 2 cm and the
//! default w = 2 s, which was the most accurate of 0.3–4 s on the simulated missions, see
//! tests/it/time_offset.rs `speed_variants`).
//! A chord is only used when it spans at least half the window and contains no gap between
//! consecutive samples longer than `max_gap_s` (Δt_max): no speed is ever made up across a GNSS
//! outage or a recording gap. Like κ, speed is the same in every frame (it is a distance over a time).
//!
//! White position noise makes a chord longer on average (|Δp + n|² = |Δp|² + 6σ² for σ per
//! coordinate), so a noisy trajectory looks faster than it is where it is slow: every start looks
//! earlier and every stop later, and the offset measured on a part of the mission that holds a start
//! (or a stop) moves — the clock drift between the first and the last third (which hold the mission's
//! start and its final stop) read hundreds of ppm on the shared missions. Given the noise σ, the
//! chord's squared length is debiased by 6σ² before its root is taken (clamped at 0); standing still
//! with 2 cm of noise, the mean 2 s speed drops from 0.023 to below 0.012 m/s (unit test below).

use nalgebra::Vector3;

/// One defined sample of the speed profile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedSample {
    /// The chord's mid-time, seconds.
    pub t: f64,
    /// Chord length over chord duration, m/s.
    pub speed: f64,
    /// Heading rate of the path over the chord, rad/s (counter-clockwise positive, horizontal plane):
    /// the turn between the chord's first and second halves over the time between their mid-points;
    /// 0 when a half is too short to have a heading. A sensor mounted a lateral distance d from
    /// another on the same body moves at v − ω·d (ω the yaw rate, which the path's heading rate is
    /// for a lateral lever): [`crate::align::time_offset`] uses it to take that difference out.
    pub yaw_rate: f64,
}

/// The windowed speed profile (see the module doc), debiased for white position noise of σ `noise_m`
/// per coordinate (0: no correction). `times` (seconds) must be non-decreasing and as
/// long as `positions`; non-finite samples are skipped. Samples are in increasing time, one per
/// distinct chord.
pub fn speed_profile(
    times: &[f64],
    positions: &[Vector3<f64>],
    window_s: f64,
    max_gap_s: f64,
    noise_m: f64,
) -> Vec<SpeedSample> {
    let mut out = Vec::new();
    speed_profile_each(times, positions, window_s, max_gap_s, noise_m, |s| {
        out.push(s)
    });
    out
}

/// [`speed_profile`], each sample handed to `out` as it is computed (the caller keeps what it needs,
/// not a copy of the whole profile).
pub fn speed_profile_each(
    times: &[f64],
    positions: &[Vector3<f64>],
    window_s: f64,
    max_gap_s: f64,
    noise_m: f64,
    mut out: impl FnMut(SpeedSample),
) {
    let bias = 6.0 * noise_m * noise_m;
    let len = times.len().min(positions.len());
    let finite = |i: usize| times[i].is_finite() && positions[i].iter().all(|v| v.is_finite());
    // The finite samples' indices, materialised only when some sample is not finite.
    let idx: Option<Vec<usize>> =
        (!(0..len).all(finite)).then(|| (0..len).filter(|&i| finite(i)).collect());
    let n = idx.as_ref().map_or(len, Vec::len);
    if n < 2 || window_s.is_nan() || window_s <= 0.0 {
        return;
    }
    let at = |k: usize| idx.as_ref().map_or(k, |v| v[k]);
    let t = |k: usize| times[at(k)];
    let p = |k: usize| positions[at(k)];
    // next_gap[k]: the first m ≥ k with t(m+1) − t(m) > max_gap_s (n − 1 when there is none). A
    // chord j..k is gap-free iff next_gap[j] ≥ k.
    let mut next_gap = vec![n - 1; n];
    for m in (0..n - 1).rev() {
        next_gap[m] = if t(m + 1) - t(m) > max_gap_s {
            m
        } else {
            next_gap[m + 1]
        };
    }
    let half = 0.5 * window_s;
    let (mut j, mut k) = (0usize, 0usize);
    let mut last: Option<(usize, usize)> = None;
    for i in 0..n {
        let ti = t(i);
        while t(j) < ti - half {
            j += 1;
        }
        k = k.max(i);
        while k + 1 < n && t(k + 1) <= ti + half {
            k += 1;
        }
        if last == Some((j, k)) {
            continue;
        }
        let span = t(k) - t(j);
        if k == j || span < half || next_gap[j] < k {
            continue;
        }
        last = Some((j, k));
        out(SpeedSample {
            t: 0.5 * (t(j) + t(k)),
            speed: ((p(k) - p(j)).norm_squared() - bias).max(0.0).sqrt() / span,
            yaw_rate: heading_rate(&t, &p, j, i, k, noise_m),
        });
    }
}

/// The turn from chord j→m to chord m→k over the time between their mid-points, rad/s; 0 when
/// either half is shorter than a few noise σ (no heading) or the three samples do not span time.
fn heading_rate(
    t: &dyn Fn(usize) -> f64,
    p: &dyn Fn(usize) -> Vector3<f64>,
    j: usize,
    m: usize,
    k: usize,
    noise_m: f64,
) -> f64 {
    let (a, b) = (p(m) - p(j), p(k) - p(m));
    let min_len = (5.0 * noise_m).max(1e-3);
    let dt = 0.5 * (t(k) - t(j));
    if m <= j || m >= k || a.xy().norm() < min_len || b.xy().norm() < min_len || dt <= 0.0 {
        return 0.0;
    }
    let turn = (a.x * b.y - a.y * b.x).atan2(a.x * b.x + a.y * b.y);
    turn / dt
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_speed_and_gaps() {
        // 1.5 m/s along x at 10 Hz, with a 5 s hole in the middle.
        let t: Vec<f64> = (0..400)
            .map(|i| i as f64 * 0.1)
            .filter(|&t| !(15.0..20.0).contains(&t))
            .collect();
        let p: Vec<Vector3<f64>> = t.iter().map(|&t| Vector3::new(1.5 * t, 0.0, 0.0)).collect();
        let v = speed_profile(&t, &p, 1.0, 2.0, 0.0);
        assert!(v.len() > 300);
        assert!(v.iter().all(|s| (s.speed - 1.5).abs() < 1e-9));
        assert!(v.windows(2).all(|w| w[0].t < w[1].t));
        // No chord crosses the hole.
        assert!(v.iter().all(|s| s.t < 14.9 || s.t > 20.0));
    }

    /// Standing still with 2 cm of white noise per coordinate at 10 Hz: the raw 2 s chord speed
    /// averages E|n₁ − n₂|/2 s = 1.596·√2·σ/2 ≈ 0.023 m/s; debiased it is at most half that, and at
    /// 1 m/s the correction changes the speed by less than 1 mm/s.
    #[test]
    fn noise_is_debiased() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let sigma = 0.02;
        let n = Normal::new(0.0, sigma).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let t: Vec<f64> = (0..6000).map(|i| i as f64 * 0.1).collect();
        let mut noisy = |x: f64| {
            Vector3::new(
                x + n.sample(&mut rng),
                n.sample(&mut rng),
                n.sample(&mut rng),
            )
        };
        let still: Vec<Vector3<f64>> = t.iter().map(|_| noisy(0.0)).collect();
        let mean = |v: Vec<SpeedSample>| v.iter().map(|s| s.speed).sum::<f64>() / v.len() as f64;
        let raw = mean(speed_profile(&t, &still, 2.0, 2.0, 0.0));
        let debiased = mean(speed_profile(&t, &still, 2.0, 2.0, sigma));
        assert!((raw - 0.0226).abs() < 0.002, "raw {raw}");
        assert!(debiased < 0.5 * raw, "debiased {debiased}");
        let moving: Vec<Vector3<f64>> = t.iter().map(|&t| noisy(t)).collect();
        let (a, b) = (
            mean(speed_profile(&t, &moving, 2.0, 2.0, 0.0)),
            mean(speed_profile(&t, &moving, 2.0, 2.0, sigma)),
        );
        assert!((a - b).abs() < 1e-3, "{a} vs {b}");
    }
}
