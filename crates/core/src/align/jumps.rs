//! Where the estimate jumps: a localiser correcting itself (a loop closure, a map re-localisation)
//! moves the estimate's position by decimetres to metres from one sample to the next.
//!
//! **Why.** The pose fit maps each window of the estimate onto the reference by one similarity. A
//! jump inside a window cannot be mapped away: the fit bends Δt (and the lever) to spread the jump's
//! residual, and a jump near a window's edge spoils it too little for the window to be set aside as
//! an outlier. On the validation's position-jump missions this left errors of tens to hundreds of
//! milliseconds. A jump is not a clock event; it is a new frame. Found here, the pose fit gives each
//! side of a jump its own similarity ([`crate::align::pose_fit`]).
//!
//! **How.** Between samples k−1 and k the estimate moves by Δ_k. Its neighbours predict that move,
//! by their velocities, dt_k·(v_{k−1} + v_{k+1})/2, and by the sample count, (Δ_{k−1} + Δ_{k+1})/2
//! (a sensor samples evenly whatever its stamps say); the anomaly is the distance between the move
//! and each prediction (a second difference, metres). Smooth motion leaves it at the noise's and
//! the acceleration's level (a legged gait at 10 Hz: centimetres); a jump J leaves |J| on its move
//! and half of it on either neighbour. Stamps taken at receipt jitter by milliseconds, which the
//! velocities divide by (on the validation's receipt-stamp missions the velocities alone called
//! dozens of jumps); a dropped sample fools the count instead; a jump is anomalous both ways. A jump
//! also persists: the three moves around it carry it whole over what the moves beyond them predict,
//! while two samples swapped by receipt stamps (a sorted stream whose latencies exceed its period)
//! or one wild sample add nothing over three moves. Each way's threshold is the larger of
//! [`MIN_JUMP_M`], [`JUMP_FACTOR`] times the track's median anomaly and [`TAIL_FACTOR`] times its
//! 98th percentile; a move jumps when it exceeds both and at least half of its anomaly persists.
//! Jumping moves closer than one judgement spans are one event, whose span runs from the sample
//! before the first to the sample after the last: a jump's neighbours, two corrections in quick
//! succession, or a stretch of stamps repeated by a clock stepping back (two stretches of the path
//! interleaved), which the pose fit must not split into pieces. Moves near a gap longer than
//! `max_gap_s` are not judged (nothing predicts them).

use nalgebra::Vector3;

/// The smallest move called a jump, metres: above a vehicle's acceleration over one sample at 10 Hz
/// (3 m/s² × 0.1² s² = 3 cm) and a walking gait's, below the localiser corrections that spoil a
/// window (the validation's position jumps are 0.3–2 m).
pub const MIN_JUMP_M: f64 = 0.1;
/// A jump's anomaly is at least this many times the track's median anomaly.
pub const JUMP_FACTOR: f64 = 10.0;
/// ... and at least this many times the track's [`TAIL_QUANTILE`] anomaly: an irregular stream
/// (stamps taken at receipt, reordered and dropped samples: a few percent of its moves off by a
/// sample) has a tail the median does not see. A jump is three anomalous moves; a quantile that
/// jumps could reach would need one every fifty samples.
pub const TAIL_FACTOR: f64 = 2.0;
pub const TAIL_QUANTILE: f64 = 0.98;
/// The moves judged on either side of a move (its neighbour, then two more for the persistence).
const REACH: usize = 3;

/// The jumps of a track (times `t`, seconds, rising; positions `p`): for each, the times of the
/// samples before and after it (a jump over several moves: before the first, after the last).
/// Sorted, disjoint.
///
/// ```
/// use nalgebra::Vector3;
/// use trajdrift_core::align::jumps::jumps;
/// // 1 m/s along x at 10 Hz; the position jumps 0.5 m sideways between 5.0 s and 5.1 s.
/// let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.1).collect();
/// let p: Vec<Vector3<f64>> = t
///     .iter()
///     .map(|&t| Vector3::new(t, if t > 5.05 { 0.5 } else { 0.0 }, 0.0))
///     .collect();
/// let found = jumps(&t, &p, 1.0);
/// assert_eq!(found.len(), 1);
/// let (before, after) = found[0];
/// assert!(before <= 5.0 && after >= 5.1 && after - before < 0.5);
/// ```
pub fn jumps(t: &[f64], p: &[Vector3<f64>], max_gap_s: f64) -> Vec<(f64, f64)> {
    let n = t.len().min(p.len());
    if n < 2 * REACH + 2 {
        return Vec::new();
    }
    let judged = |k: usize| {
        let dt = t[k] - t[k - 1];
        dt > 0.0 && dt <= max_gap_s
    };
    let step = |k: usize| p[k] - p[k - 1];
    let velocity = |k: usize| step(k) / (t[k] - t[k - 1]);
    // The move k's anomaly (by the stamps, by the sample count), for the moves with REACH judged
    // moves on either side.
    let anomalies: Vec<Option<(f64, f64)>> = (0..n)
        .map(|k| {
            if k < REACH + 1 || k + REACH >= n || !(k - REACH..=k + REACH).all(judged) {
                return None;
            }
            let by_time = (velocity(k - 1) + velocity(k + 1)) * (0.5 * (t[k] - t[k - 1]));
            let by_count = (step(k - 1) + step(k + 1)) * 0.5;
            Some(((step(k) - by_time).norm(), (step(k) - by_count).norm()))
        })
        .collect();
    let threshold = |pick: fn(&(f64, f64)) -> f64| {
        let mut a: Vec<f64> = anomalies.iter().flatten().map(pick).collect();
        if a.is_empty() {
            return f64::INFINITY;
        }
        let mid = a.len() / 2;
        let median = *a.select_nth_unstable_by(mid, f64::total_cmp).1;
        let high = ((a.len() as f64 * TAIL_QUANTILE) as usize).min(a.len() - 1);
        let tail = *a.select_nth_unstable_by(high, f64::total_cmp).1;
        MIN_JUMP_M.max(JUMP_FACTOR * median).max(TAIL_FACTOR * tail)
    };
    let (by_time, by_count) = (threshold(|a| a.0), threshold(|a| a.1));
    let score: Vec<f64> = anomalies
        .iter()
        .map(|a| a.map_or(0.0, |(x, y)| (x / by_time).min(y / by_count)))
        .collect();
    // What persists of the move k's departure: the three moves around it less what the two moves
    // on either side of them predict (by the count), metres.
    let persists = |k: usize| {
        let (a, b) = (k - 2, k + 1);
        ((p[b] - p[a]) - (p[a] - p[a - 2] + p[b + 2] - p[b]) * 0.75).norm()
    };
    let jumping =
        |k: usize| score[k] > 1.0 && persists(k) >= 0.5 * anomalies[k].map_or(0.0, |a| a.1);
    // Anomalous moves closer than the moves one judgement spans are one event (a jump's neighbours,
    // two corrections in quick succession, a stretch of stamps repeated by a clock stepping back):
    // its span runs from before the first to after the last.
    let mut found: Vec<(usize, usize)> = Vec::new();
    for k in (REACH + 1..n - REACH).filter(|&k| jumping(k)) {
        match found.last_mut() {
            Some(last) if k - last.1 <= 2 * REACH => last.1 = k,
            _ => found.push((k, k)),
        }
    }
    found.into_iter().map(|(a, b)| (t[a - 1], t[b])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A walk along a circle of radius 5 m at `speed` m/s with a 2 Hz bob of `bob_m` (a gait),
    /// sampled at `rate_hz` for 60 s, jumping by `jump` at each of `at_s`.
    fn walk(
        rate_hz: f64,
        speed: f64,
        bob_m: f64,
        at_s: &[f64],
        jump: Vector3<f64>,
    ) -> (Vec<f64>, Vec<Vector3<f64>>) {
        let t: Vec<f64> = (0..(60.0 * rate_hz) as usize)
            .map(|i| i as f64 / rate_hz)
            .collect();
        let p = t
            .iter()
            .map(|&t| {
                let a = speed * t / 5.0;
                let bob = bob_m * (2.0 * std::f64::consts::TAU * t).sin();
                let jumped = at_s.iter().filter(|&&j| t >= j).count() as f64;
                Vector3::new(5.0 * a.cos() + bob, 5.0 * a.sin(), bob) + jump * jumped
            })
            .collect();
        (t, p)
    }

    #[test]
    fn a_smooth_gait_has_no_jump() {
        for rate in [10.0, 50.0, 200.0] {
            let (t, p) = walk(rate, 0.5, 0.02, &[], Vector3::zeros());
            assert!(jumps(&t, &p, 1.0).is_empty(), "{rate} Hz");
        }
    }

    #[test]
    fn stamps_taken_at_receipt_are_not_jumps() {
        let (t, p) = walk(100.0, 1.5, 0.02, &[], Vector3::zeros());
        // Each stamp late by 0–20 ms (a fixed pseudo-random sequence), kept rising.
        let mut late = 0.37f64;
        let mut last = f64::NEG_INFINITY;
        let t: Vec<f64> = t
            .iter()
            .map(|&t| {
                late = (late * 997.0 + 0.123).fract();
                last = (t + 0.02 * late).max(last + 1e-6);
                last
            })
            .collect();
        assert!(jumps(&t, &p, 1.0).is_empty());
    }

    #[test]
    fn swapped_samples_are_not_a_jump() {
        let (t, mut p) = walk(50.0, 3.0, 0.0, &[], Vector3::zeros());
        for k in (100..2900).step_by(100) {
            p.swap(k, k + 1);
        }
        assert!(jumps(&t, &p, 1.0).is_empty());
    }

    #[test]
    fn a_repeated_stretch_is_one_event() {
        // The clock steps back 0.2 s at 30 s: the sorted stamps interleave two stretches.
        let (t, p) = walk(50.0, 2.0, 0.0, &[], Vector3::zeros());
        let mut both: Vec<(f64, Vector3<f64>)> = t
            .iter()
            .zip(&p)
            .map(|(&t, &p)| (if t >= 30.0 { t - 0.2 + 0.003 } else { t }, p))
            .collect();
        both.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (t2, p2): (Vec<f64>, Vec<Vector3<f64>>) = both.into_iter().unzip();
        let found = jumps(&t2, &p2, 1.0);
        assert!(found.len() <= 1, "{found:?}");
        if let Some(&(before, after)) = found.first() {
            assert!(before >= 29.5 && after <= 30.5, "{found:?}");
        }
    }

    #[test]
    fn a_dropped_sample_is_not_a_jump() {
        let (t, p) = walk(10.0, 2.0, 0.0, &[], Vector3::zeros());
        let (t2, p2): (Vec<f64>, Vec<Vector3<f64>>) = t
            .into_iter()
            .zip(p)
            .enumerate()
            .filter(|(i, _)| *i != 300)
            .map(|(_, x)| x)
            .unzip();
        assert!(jumps(&t2, &p2, 1.0).is_empty());
    }

    #[test]
    fn a_gap_is_not_a_jump() {
        let (mut t, p) = walk(10.0, 1.0, 0.0, &[], Vector3::zeros());
        // Two seconds missing: the move across them is not judged.
        let (t2, p2): (Vec<f64>, Vec<Vector3<f64>>) = t
            .drain(..)
            .zip(p)
            .filter(|(t, _)| !(20.0..22.0).contains(t))
            .unzip();
        assert!(jumps(&t2, &p2, 0.5).is_empty());
    }

    proptest! {
        #[test]
        fn every_jump_is_found_once(
            rate in prop::sample::select(vec![10.0, 20.0, 100.0, 200.0]),
            size in 0.4f64..2.0,
            dir in 0.0f64..std::f64::consts::TAU,
            first in 5.0f64..25.0,
            second in 30.0f64..55.0,
        ) {
            let jump = Vector3::new(dir.cos(), dir.sin(), 0.2) * size;
            let (t, p) = walk(rate, 0.5, 0.02, &[first, second], jump);
            let found = jumps(&t, &p, 1.0);
            prop_assert_eq!(found.len(), 2);
            for (j, (a, b)) in [first, second].iter().zip(found) {
                prop_assert!(a < *j + 1e-9 && *j <= b + 1e-9, "{} not in ({}, {})", j, a, b);
            }
        }
    }
}
