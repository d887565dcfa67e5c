//! The estimate's pose at any time: cubic interpolation through the four samples around it, or
//! through twelve for a slow estimate against a sparser reference.
//!
//! **Why cubic.** The pose fit compares each reference sample with the estimate's pose at the
//! same instant, so the estimate is interpolated at the reference's times. A legged robot's body
//! rolls and sways at its gait (1.5–2.5 Hz) and pitches and bobs at twice that; an estimate
//! published at 10 Hz has 2–6 samples per period of that motion. A straight line between two
//! samples then misses the motion between them, and misses it with a phase error: the line at a
//! fraction f of the way from one sample to the next lags or leads the motion by a part of the
//! period that depends on f. Where the two sensors' rates are commensurate (a 5 Hz reference and
//! a 10 Hz estimate) f is the same at every reference sample, the error does not average out, and
//! the gait — the sharpest timing signal a walking robot has — pulls Δt by tens of milliseconds.
//! The cubic through four samples (Lagrange's, on their actual times) follows a 2 Hz sway sampled
//! at 10 Hz to a few per cent and is exact for any cubic motion; it costs a few more products.
//!
//! **A slow estimate against a sparser reference: twelve samples.** At 10 Hz a gait that bobs and
//! pitches at 3.5–5 Hz lies near the estimate's Nyquist frequency, where the cubic errs in phase by
//! 7 ms at 3.6 Hz and 14 ms at 4.2 Hz; the error is the same at every reference sample where the
//! rates are commensurate, so it pulls Δt. Where the reference is at least as dense, the fit
//! averages that band out of both sides (`AVERAGE_BELOW_HZ`); where it is sparser (1–5 Hz against
//! 10 Hz) nothing can be averaged, and the estimate is interpolated by Lagrange's polynomial through
//! the [`LONG_TAPS`] samples around the time (six each side), whose response stays near one and
//! in phase much closer to the Nyquist frequency (a sinc's, to which it tends with its length):
//! at 10 Hz its worst phase error over the fractions of a step is 0.4 ms at 3 Hz, 1.9 ms at 3.6 Hz
//! and 7.9 ms at 4.2 Hz, where the cubic's is 3.5, 7.0 and 14.6 ms (what lies closer still to the
//! Nyquist frequency neither follows). Its twelve samples must be evenly spaced to within [`LONG_STEP_RATIO`] (a long polynomial
//! through uneven steps swings); otherwise the cubic, as elsewhere. On the second simulator's
//! walking robots with a 10 Hz estimate and a 1–5 Hz reference (15 missions drawn after the
//! choice) the median error went from 4.7 to 2.3 ms and 2σ covered 87 % instead of 80 %
//! (docs/evidence.md, "A slow estimate against a sparser reference: twelve samples").
//!
//! **Where it falls back.** The four samples must lie in one stretch of the estimate (no jump
//! between them: [`crate::align::jumps`]), within the largest gap interpolated across, and be
//! nearly evenly spaced (each outer step within a factor [`MAX_STEP_RATIO`] of the middle one: a
//! cubic through very uneven steps overshoots). Otherwise the pose is the straight line between the
//! two samples around it, as before near a gap or a jump.
//!
//! **The noise it shares.** The fit's instrument (a central difference of these interpolations
//! one estimate period either side, see `window.rs`) uses some of the samples the point itself
//! does. For any interpolation that is the same at every sample (a kernel shifted by one period),
//! the shared samples enter the difference's two ends with the same weights they enter the point
//! with, so the covariance of the instrument's noise with the point's cancels: Σ wᵢ·wᵢ₋₁ on one
//! side, the same sum on the other; the long interpolation's twelve weights as the cubic's four. A
//! test checks both on evenly sampled white noise.

use nalgebra::{Matrix3, Vector3};

use super::PoseTrack;

/// The largest ratio between an outer step of the four samples and the middle one for a cubic.
pub const MAX_STEP_RATIO: f64 = 2.0;
/// The samples of the long interpolation (see the module doc), half each side of the time.
pub const LONG_TAPS: usize = 12;
/// The largest ratio between any step of the long interpolation's samples and the middle one.
pub const LONG_STEP_RATIO: f64 = 1.5;

/// The samples of an interpolation: the cubic's four, or [`LONG_TAPS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Taps {
    Cubic,
    Long,
}

/// The estimate's position and attitude at one time.
#[derive(Clone, Copy)]
pub(super) struct At {
    pub(super) p: Vector3<f64>,
    pub(super) r: Matrix3<f64>,
}

/// The estimate's poses, interpolated.
pub(super) struct Sampler<'a> {
    pub(super) track: PoseTrack<'a>,
    /// The track's orientations as rotation matrices, converted once (each point of every
    /// iteration interpolates five poses, ten conversions otherwise).
    rotations: Vec<Matrix3<f64>>,
    /// `joined[i]`: samples i and i + 1 lie in one stretch (no jump between them) within the
    /// largest gap; the cubic needs its three steps joined.
    joined: Vec<bool>,
    gap: f64,
    taps: Taps,
}

impl<'a> Sampler<'a> {
    /// The sampler of `track`, bridging gaps up to `gap` seconds, through `taps` samples where
    /// they allow (the cubic and the line otherwise).
    pub(super) fn new(track: PoseTrack<'a>, gap: f64, taps: Taps) -> Sampler<'a> {
        let ts = track.t;
        // Jumps that begin in [tᵢ, tᵢ₊₁) or end in (tᵢ, tᵢ₊₁] separate the two samples.
        let begun = |t: f64| track.jumps.partition_point(|&(before, _)| before < t);
        let ended = |t: f64| track.jumps.partition_point(|&(_, after)| after <= t);
        let joined = ts
            .windows(2)
            .map(|w| {
                let span = w[1] - w[0];
                span > 0.0
                    && span <= gap
                    && begun(w[0]) == begun(w[1])
                    && ended(w[0]) == ended(w[1])
            })
            .collect();
        Sampler {
            track,
            rotations: track
                .q
                .iter()
                .map(|q| q.to_rotation_matrix().into_inner())
                .collect(),
            joined,
            gap,
            taps,
        }
    }

    /// The pose at `t` (estimate clock); `None` outside the track or across a gap longer than the
    /// largest gap. `hint`: the index found last (rising queries walk from it).
    pub(super) fn at(&self, t: f64, hint: &mut usize) -> Option<At> {
        let ts = self.track.t;
        let n = ts.len();
        let mut j = (*hint).min(n);
        while j < n && ts[j] < t {
            j += 1;
        }
        while j > 0 && ts[j - 1] >= t {
            j -= 1;
        }
        *hint = j;
        if j == 0 || j >= n {
            return None;
        }
        let (a, b) = (j - 1, j);
        let span = ts[b] - ts[a];
        if span > self.gap || span <= 0.0 {
            return None;
        }
        if self.taps == Taps::Long {
            if let Some(at) = self.through::<LONG_TAPS>(t, a, LONG_STEP_RATIO) {
                return Some(at);
            }
        }
        if let Some(at) = self.through::<4>(t, a, MAX_STEP_RATIO) {
            return Some(at);
        }
        let f = (t - ts[a]) / span;
        let (ra, rb) = (self.rotations[a], self.rotations[b]);
        Some(At {
            p: self.track.p[a] + (self.track.p[b] - self.track.p[a]) * f,
            r: ra + (rb - ra) * f,
        })
    }

    /// The pose at `t` (between samples a and a + 1) by Lagrange's polynomial through the N
    /// samples around it, N/2 each side (the cubic's four, or [`LONG_TAPS`]); `None` unless they
    /// lie in one stretch and every step is within `ratio` of the middle one (for the cubic: its
    /// two outer steps; see the module doc).
    fn through<const N: usize>(&self, t: f64, a: usize, ratio: f64) -> Option<At> {
        let half = N / 2;
        if a + 1 < half || a + half >= self.track.t.len() {
            return None;
        }
        let k = a + 1 - half;
        if !self.joined[k..k + N - 1].iter().all(|&j| j) {
            return None;
        }
        let x: [f64; N] = std::array::from_fn(|i| self.track.t[k + i]);
        let mid = x[half] - x[half - 1];
        let even = x.windows(2).all(|s| {
            let step = s[1] - s[0];
            step <= ratio * mid && step * ratio >= mid
        });
        if !even {
            return None;
        }
        let w = lagrange_weights(&x, t);
        let (p, r) = (self.track.p, &self.rotations);
        let mut at = At {
            p: p[k] * w[0],
            r: r[k] * w[0],
        };
        for i in 1..N {
            at.p += p[k + i] * w[i];
            at.r += r[k + i] * w[i];
        }
        Some(at)
    }

    /// The stretch of the track between jumps that `[t − reach, t + reach]` (estimate clock) lies
    /// in, `None` when a jump falls within it (its interpolation would mix the two frames).
    pub(super) fn segment(&self, t: f64, reach: f64) -> Option<usize> {
        let jumps = self.track.jumps;
        let k = jumps.partition_point(|&(_, after)| after <= t - reach);
        match jumps.get(k) {
            Some(&(before, _)) if before < t + reach => None,
            _ => Some(k),
        }
    }
}

/// The weights of the polynomial through the values at the N distinct times `x`, at `t`: the
/// value is Σ wᵢ·yᵢ (exact for any polynomial of degree below N:
/// `the_weights_reproduce_a_cubic_at_uneven_times`).
fn lagrange_weights<const N: usize>(x: &[f64; N], t: f64) -> [f64; N] {
    std::array::from_fn(|i| {
        (0..N)
            .filter(|&m| m != i)
            .map(|m| (t - x[m]) / (x[i] - x[m]))
            .product()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    fn track<'a>(
        t: &'a [f64],
        p: &'a [Vector3<f64>],
        q: &'a [UnitQuaternion<f64>],
        jumps: &'a [(f64, f64)],
    ) -> PoseTrack<'a> {
        PoseTrack { t, p, q, jumps }
    }

    #[test]
    fn the_weights_reproduce_a_cubic_at_uneven_times() {
        let x = [0.0, 0.1, 0.25, 0.3];
        let y = |t: f64| 1.0 - 2.0 * t + 3.0 * t * t - 4.0 * t * t * t;
        for t in [0.1, 0.13, 0.2, 0.25] {
            let w = lagrange_weights(&x, t);
            let v: f64 = (0..4).map(|i| w[i] * y(x[i])).sum();
            assert!((v - y(t)).abs() < 1e-12, "{t}: {v} vs {}", y(t));
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }

    /// A 2 Hz sway sampled at 10 Hz: the cubic follows it to a few per cent of its amplitude, the
    /// straight line (its slow twin, the fallback) misses by a fifth; at the samples both are exact.
    #[test]
    fn a_gait_sampled_at_ten_hertz_is_followed() {
        let t: Vec<f64> = (0..100).map(|i| 0.013 + i as f64 * 0.1).collect();
        let sway = |t: f64| (std::f64::consts::TAU * 2.0 * t).sin();
        let p: Vec<Vector3<f64>> = t.iter().map(|&t| Vector3::new(sway(t), 0.0, 0.0)).collect();
        let q = vec![UnitQuaternion::identity(); t.len()];
        let s = Sampler::new(track(&t, &p, &q, &[]), 1.0, Taps::Cubic);
        let (mut worst_cubic, mut worst_line) = (0.0f64, 0.0f64);
        let mut hint = 0;
        for k in 0..800 {
            let x = 0.5 + k as f64 * 0.01;
            let at = s.at(x, &mut hint).unwrap();
            worst_cubic = worst_cubic.max((at.p.x - sway(x)).abs());
            let j = t.partition_point(|&v| v < x);
            let f = (x - t[j - 1]) / (t[j] - t[j - 1]);
            let line = p[j - 1].x + (p[j].x - p[j - 1].x) * f;
            worst_line = worst_line.max((line - sway(x)).abs());
        }
        assert!(worst_cubic < 0.07, "cubic {worst_cubic}");
        assert!(worst_line > 0.15, "line {worst_line}");
        let at = s.at(t[40], &mut hint).unwrap();
        assert!((at.p.x - p[40].x).abs() < 1e-12);
    }

    /// A bob sampled at 10 Hz towards the estimate's Nyquist frequency (where a walking robot's
    /// gait pitches): the long interpolation follows it in phase to within 0.4 ms at 3 Hz, 1.9 ms
    /// at 3.6 Hz and 7.9 ms at 4.2 Hz, where the cubic (its slow twin here, and the fallback) lags
    /// or leads by 3.5, 7.0 and 14.6 ms (the module doc's figures). The phase error at each
    /// fraction of a step is the time shift that matches the interpolation to the bob, the worst
    /// over the fractions.
    #[test]
    fn a_bob_near_the_nyquist_frequency_is_followed_by_the_long_interpolation() {
        let t: Vec<f64> = (0..200).map(|i| 0.013 + i as f64 * 0.1).collect();
        let q = vec![UnitQuaternion::identity(); t.len()];
        let phase_error_s = |f_hz: f64, taps: Taps| {
            let w = |t: f64| std::f64::consts::TAU * f_hz * t;
            let p: Vec<Vector3<f64>> = t
                .iter()
                .map(|&t| Vector3::new(w(t).sin(), 0.0, 0.0))
                .collect();
            let s = Sampler::new(track(&t, &p, &q, &[]), 1.0, taps);
            let mut worst = 0.0f64;
            for k in 1..10 {
                let f = k as f64 / 10.0;
                let (mut in_phase, mut quadrature) = (0.0, 0.0);
                let mut hint = 0;
                for &ti in &t[20..180] {
                    let x = ti + f * 0.1;
                    let v = s.at(x, &mut hint).unwrap().p.x;
                    in_phase += v * w(x).sin();
                    quadrature += v * w(x).cos();
                }
                let tau = (quadrature / in_phase).atan() / (std::f64::consts::TAU * f_hz);
                worst = worst.max(tau.abs());
            }
            worst
        };
        // (frequency, the long interpolation's worst, the cubic's), seconds, to 0.05 ms.
        for (f_hz, long_s, cubic_s) in [
            (3.0, 0.0004, 0.0035),
            (3.6, 0.0019, 0.0070),
            (4.2, 0.0079, 0.0146),
        ] {
            let long = phase_error_s(f_hz, Taps::Long);
            let cubic = phase_error_s(f_hz, Taps::Cubic);
            assert!((long - long_s).abs() < 5e-5, "{f_hz} Hz: long {long}");
            assert!((cubic - cubic_s).abs() < 5e-5, "{f_hz} Hz: cubic {cubic}");
        }
    }

    /// A track of x = t² sampled at `t` with `jumps`, bridging gaps up to `gap`: at each `(x, a)`
    /// of `lines` the pose is the line between samples a and a + 1, at each x of `cubics` the cubic
    /// (exact on t²), and at each x of `none` there is none.
    fn check_t_squared(
        t: &[f64],
        jumps: &[(f64, f64)],
        gap: f64,
        lines: &[(f64, usize)],
        cubics: &[f64],
        none: &[f64],
    ) {
        let p: Vec<Vector3<f64>> = t.iter().map(|&t| Vector3::new(t * t, 0.0, 0.0)).collect();
        let q = vec![UnitQuaternion::identity(); t.len()];
        let s = Sampler::new(track(t, &p, &q, jumps), gap, Taps::Cubic);
        let mut hint = 0;
        for &(x, a) in lines {
            let f = (x - t[a]) / (t[a + 1] - t[a]);
            let line = p[a].x + (p[a + 1].x - p[a].x) * f;
            let got = s.at(x, &mut hint).unwrap().p.x;
            assert!(
                (got - line).abs() < 1e-12,
                "{x}: {got} is not the line's {line}"
            );
        }
        for &x in cubics {
            let got = s.at(x, &mut hint).unwrap().p.x;
            assert!(
                (got - x * x).abs() < 1e-12,
                "{x}: {got} is not the cubic's {}",
                x * x
            );
        }
        for &x in none {
            assert!(s.at(x, &mut hint).is_none(), "{x}");
        }
    }

    /// Across a jump of the estimate (between two samples, or spanning several), a gap, or very
    /// uneven steps, the pose is the straight line between its two samples.
    #[test]
    fn falls_back_to_the_line_near_a_jump_a_gap_or_uneven_steps() {
        // A jump between 0.3 and 0.4: the four samples around 0.25 reach across it, those around
        // 0.45 too; a 1.4 s gap (bridged: within 1.5 s) and uneven steps (0.05 then 0.45). Inside
        // one stretch of even steps (0.15): the cubic.
        check_t_squared(
            &[0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 1.9, 2.0, 2.1, 2.15, 2.6, 2.7],
            &[(0.3, 0.4)],
            1.5,
            &[(0.25, 2), (0.45, 4), (1.95, 6), (2.12, 8), (2.3, 9)],
            &[0.15],
            &[],
        );
        // Even steps, a jump spanning samples 2 to 4 (samples 0–3 hold its start, 0.2 → 0.3, and
        // samples 3–6 its end, 0.3 → 0.4), and a gap of 0.18 s beyond the 0.15 s bridged (its
        // ratio to 0.1 s passes): the line beside the gap, nothing across it, the cubic clear of
        // both.
        check_t_squared(
            &[0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.88, 0.98, 1.08],
            &[(0.2, 0.4)],
            0.15,
            &[(0.15, 1), (0.45, 4), (0.65, 6)],
            &[0.55],
            &[0.8],
        );
    }

    /// The noise the instrument shares with its point: white noise on evenly spaced samples, the
    /// central difference one period either side of a point uncorrelated with the point's own
    /// interpolated noise, at any fraction of the way between two samples, by the cubic and by the
    /// long interpolation.
    #[test]
    fn a_difference_one_period_either_side_shares_no_noise_with_its_point() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let n = 20_000;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.1).collect();
        let p: Vec<Vector3<f64>> = (0..n)
            .map(|_| Vector3::new(noise.sample(&mut rng), 0.0, 0.0))
            .collect();
        let q = vec![UnitQuaternion::identity(); n];
        let correlation = |taps: Taps, f: f64, h: f64| {
            let s = Sampler::new(track(&t, &p, &q, &[]), 1.0, taps);
            let (mut sum_ve, mut sum_vv, mut sum_ee) = (0.0, 0.0, 0.0);
            let mut hints = [0usize; 3];
            for &ti in &t[5..n - 5] {
                let x = ti + f * 0.1;
                let e = s.at(x, &mut hints[0]).unwrap().p.x;
                let v = s.at(x - h, &mut hints[1]).unwrap().p.x
                    - s.at(x + h, &mut hints[2]).unwrap().p.x;
                sum_ve += v * e;
                sum_vv += v * v;
                sum_ee += e * e;
            }
            sum_ve / (sum_vv * sum_ee).sqrt()
        };
        for taps in [Taps::Cubic, Taps::Long] {
            for f in [0.1, 0.3, 0.5, 0.8] {
                // On an even grid, one period either side, Σ e·v telescopes to the ends of the
                // run: nothing is left of the noise the two share, whatever the kernel.
                let c = correlation(taps, f, 0.1);
                assert!(c.abs() < 1e-3, "{taps:?}, f {f}: correlation {c}");
            }
        }
        // Half a period either side the kernel is not shifted by whole samples: correlated.
        let c = correlation(Taps::Cubic, 0.3, 0.05);
        assert!(c.abs() > 0.1, "half a period: correlation {c}");
    }
}
