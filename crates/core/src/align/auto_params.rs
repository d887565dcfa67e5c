//! Automatic parameters from the data: ε of the curvature signature, ε of path lengths and the Δt_max
//! of the curvature signature, chosen from the reference's own high-frequency noise and the robot's
//! speed instead of a platform table.
//!
//! Why: the paper's rule ε_min ≈ 3σ fails on white reference noise. κ of eq. (1) is a turning angle
//! over a chord of ε, and the angle's noise is ~σ/ε, so κ's noise grows like σ/ε²: at σ = 2 cm,
//! ε = 0.1 m gives a κ noise of several 1/m, far above any real curvature (0.05–0.5 1/m), and the
//! correlation peak lands 0.1–30 s off. A chord of length L with noise σ on both ends is also too long
//! by ≈ 2σ²/L, i.e. a relative 2σ²/L², which biases the Drift Error's path lengths.
//!
//! * σ: the robust spread of the third differences of consecutive, evenly spaced reference samples
//!   (p₃ − 3p₂ + 3p₁ − p₀ has variance 20σ² for white noise and removes position, speed and
//!   acceleration exactly; the motion left, jerk·δt³, is negligible at sensor rates):
//!   σ = median|d₃| / 0.6745 / √20, pooled over x, y, z.
//! * curvature ε = √(σ / κ_noise) with κ_noise = 0.005 1/m (σ/ε² below that), in [0.1, 5] m:
//!   2 m at σ = 2 cm, 0.45 m at 1 mm.
//! * path ε = σ·√(2 / 0.0008) = 50σ (relative inflation 2σ²/ε² ≤ 0.08 %), in [0.1, w_min/5] m: 1 m at
//!   σ = 2 cm, where the Drift Error medians of the shared missions were within 0.5 pp of the truth.
//! * curvature Δt_max = 1.5·ε/v_slow, v_slow the 10th percentile of the reference's speed while moving,
//!   in [Δt_max given, 30] s: a chord of ε must be covered within Δt_max in the slow parts too (10 s
//!   for a legged robot at 0.3 m/s with ε = 2 m), or κ is undefined exactly where a legged robot walks.

use nalgebra::Vector3;

use crate::align::speed::speed_profile;

/// κ noise level σ/ε² the curvature ε is chosen for, 1/m.
pub const KAPPA_NOISE_PER_M: f64 = 0.005;
/// Relative path-length inflation 2σ²/ε² the path ε is chosen for.
pub const PATH_INFLATION: f64 = 0.0008;
/// Bounds of the automatic curvature ε, metres.
pub const CURVATURE_EPS_RANGE_M: [f64; 2] = [0.1, 5.0];
/// Smallest automatic path ε, metres (the largest is a fifth of the smallest window).
pub const PATH_EPS_MIN_M: f64 = 0.1;
/// Largest automatic curvature Δt_max, seconds.
pub const DT_MAX_CAP_S: f64 = 30.0;
/// Speed above which the robot counts as moving, m/s (well above the 2 s windowed speed's noise).
pub const MOVING_SPEED_MPS: f64 = 0.1;

/// What the automatic parameters were chosen from, and what they are.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct AutoParams {
    /// σ of the reference's white position noise, metres (`None`: too few evenly spaced samples).
    pub reference_noise_m: Option<f64>,
    /// Mean speed of the reference while moving, m/s.
    pub mean_speed_mps: Option<f64>,
    /// 10th percentile of the reference's speed while moving, m/s.
    pub slow_speed_mps: Option<f64>,
    /// ε of the curvature signature, metres.
    pub curvature_eps_m: f64,
    /// ε of path lengths, metres.
    pub path_eps_m: f64,
    /// Δt_max of the curvature signature, seconds.
    pub curvature_dt_max_s: f64,
}

/// σ of the white noise of `positions` (see the module doc); `None` with fewer than 10 usable
/// quadruples of evenly spaced samples.
pub fn reference_noise(times: &[f64], positions: &[Vector3<f64>]) -> Option<f64> {
    let n = times.len().min(positions.len());
    if n < 4 {
        return None;
    }
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let typical = steps[steps.len() / 2];
    if typical.is_nan() || typical <= 0.0 {
        return None;
    }
    let even = |dt: f64| (dt - typical).abs() <= 0.2 * typical;
    let mut d3: Vec<f64> = Vec::with_capacity(3 * n);
    for i in 3..n {
        if !(even(times[i] - times[i - 1])
            && even(times[i - 1] - times[i - 2])
            && even(times[i - 2] - times[i - 3]))
        {
            continue;
        }
        let d = positions[i] - 3.0 * positions[i - 1] + 3.0 * positions[i - 2] - positions[i - 3];
        d3.extend(d.iter().filter(|v| v.is_finite()).map(|v| v.abs()));
    }
    if d3.len() < 30 {
        return None;
    }
    let mid = d3.len() / 2;
    let (_, median, _) = d3.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*median / 0.6745 / 20f64.sqrt())
}

/// Mean and 10th percentile of the reference's 2 s windowed speed while moving (above
/// [`MOVING_SPEED_MPS`]); `None` when it never moves.
pub fn moving_speed(
    times: &[f64],
    positions: &[Vector3<f64>],
    max_gap_s: f64,
) -> Option<(f64, f64)> {
    let mut v: Vec<f64> = speed_profile(times, positions, 2.0, max_gap_s, 0.0)
        .into_iter()
        .map(|s| s.speed)
        .filter(|v| v.is_finite() && *v > MOVING_SPEED_MPS)
        .collect();
    if v.is_empty() {
        return None;
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    v.sort_by(f64::total_cmp);
    Some((mean, v[v.len() / 10]))
}

/// The automatic parameters for a reference (see the module doc). `min_window_m` is the smallest
/// Drift Error window; `base_dt_max_s` the Δt_max used elsewhere (the floor of the curvature one).
pub fn auto_params(
    times: &[f64],
    positions: &[Vector3<f64>],
    min_window_m: f64,
    base_dt_max_s: f64,
) -> AutoParams {
    let sigma = reference_noise(times, positions);
    let motion = moving_speed(times, positions, base_dt_max_s);
    let s = sigma.unwrap_or(0.0);
    let [c_lo, c_hi] = CURVATURE_EPS_RANGE_M;
    let curvature_eps_m = (s / KAPPA_NOISE_PER_M).sqrt().clamp(c_lo, c_hi);
    let path_hi = (min_window_m / 5.0).max(PATH_EPS_MIN_M);
    let path_eps_m = (s * (2.0 / PATH_INFLATION).sqrt()).clamp(PATH_EPS_MIN_M, path_hi);
    let curvature_dt_max_s = match motion {
        Some((_, slow)) => {
            (1.5 * curvature_eps_m / slow).clamp(base_dt_max_s, DT_MAX_CAP_S.max(base_dt_max_s))
        }
        None => base_dt_max_s,
    };
    AutoParams {
        reference_noise_m: sigma,
        mean_speed_mps: motion.map(|m| m.0),
        slow_speed_mps: motion.map(|m| m.1),
        curvature_eps_m,
        path_eps_m,
        curvature_dt_max_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    fn noisy_circle(sigma: f64, rate: f64) -> (Vec<f64>, Vec<Vector3<f64>>) {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let g = Normal::new(0.0, sigma.max(1e-300)).unwrap();
        (0..3000)
            .map(|i| {
                let t = i as f64 / rate;
                let a = 0.1 * t;
                let p = Vector3::new(10.0 * a.cos(), 10.0 * a.sin(), 0.0)
                    + Vector3::new(g.sample(&mut rng), g.sample(&mut rng), g.sample(&mut rng));
                (t, p)
            })
            .unzip()
    }

    #[test]
    fn noise_is_recovered_through_the_motion() {
        for sigma in [0.005, 0.02, 0.1] {
            let (t, p) = noisy_circle(sigma, 10.0);
            let s = reference_noise(&t, &p).unwrap();
            assert!((s / sigma - 1.0).abs() < 0.1, "σ {sigma}: got {s}");
        }
    }

    #[test]
    fn two_cm_at_ten_hz_gives_the_measured_values() {
        let (t, p) = noisy_circle(0.02, 10.0);
        let a = auto_params(&t, &p, 5.0, 2.0);
        assert!((a.curvature_eps_m - 2.0).abs() < 0.15, "{a:?}");
        assert!((a.path_eps_m - 1.0).abs() < 0.1, "{a:?}");
        assert!((a.mean_speed_mps.unwrap() - 1.0).abs() < 0.05, "{a:?}");
        // 1 m/s: a 2 m chord takes 2 s; Δt_max leaves room (1.5×).
        assert!((a.curvature_dt_max_s - 3.0).abs() < 0.3, "{a:?}");
    }

    #[test]
    fn a_clean_reference_gets_the_smallest_eps() {
        let (t, p) = noisy_circle(0.0, 10.0);
        let a = auto_params(&t, &p, 5.0, 2.0);
        assert_eq!(a.curvature_eps_m, 0.1);
        assert_eq!(a.path_eps_m, 0.1);
    }
}
