//! Where the reference stands still: the intervals a curvature comparison must leave out.
//!
//! A robot that turns in place keeps its reference point still while a sensor mounted beside it
//! sweeps an arc. The sensor's signed curvature then has a spike the reference's has not (the
//! reference's chords reach across the stand to the path before and after it, with a turn of their
//! own), and on the shared legged mission with six spins this alone moved the signed-curvature
//! offset by +0.43 s — read by `auto` as the lead of a lever arm that is not there. Leaving out the
//! stands (± the time to travel one curvature chord) brought it back to +13 ms
//! (`auto_table` in tests/it/time_offset_auto.rs prints both in the
//! reason; `turns_in_place_do_not_fake_a_lever_arm` asserts that no lever arm is suspected).

use nalgebra::Vector3;

use crate::align::auto_params::reference_noise;
use crate::align::speed::speed_profile;

/// Below this 2 s chord speed the reference is standing still, m/s.
pub const STILL_SPEED_MPS: f64 = 0.05;
/// Stands closer than this are merged, seconds.
const MERGE_S: f64 = 1.0;

/// The intervals (seconds, the trajectory's clock) where the 2 s chord speed, debiased for the
/// trajectory's own noise, stays below [`STILL_SPEED_MPS`], each widened by `margin_s` on both sides.
pub fn still_intervals(
    times: &[f64],
    positions: &[Vector3<f64>],
    max_gap_s: f64,
    margin_s: f64,
) -> Vec<(f64, f64)> {
    let noise = reference_noise(times, positions).unwrap_or(0.0);
    let mut out: Vec<(f64, f64)> = Vec::new();
    for s in speed_profile(times, positions, 2.0, max_gap_s, noise) {
        if s.speed >= STILL_SPEED_MPS {
            continue;
        }
        match out.last_mut() {
            Some(last) if s.t - last.1 < MERGE_S => last.1 = s.t,
            _ => out.push((s.t, s.t)),
        }
    }
    out.into_iter()
        .map(|(a, b)| (a - margin_s, b + margin_s))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stop_between_two_drives_is_found() {
        // 1 m/s for 10 s, still for 10 s, 1 m/s for 10 s, at 10 Hz.
        let t: Vec<f64> = (0..300).map(|i| i as f64 * 0.1).collect();
        let p: Vec<Vector3<f64>> = t
            .iter()
            .map(|&t| {
                let x = if t < 10.0 {
                    t
                } else if t < 20.0 {
                    10.0
                } else {
                    t - 10.0
                };
                Vector3::new(x, 0.0, 0.0)
            })
            .collect();
        let s = still_intervals(&t, &p, 2.0, 0.5);
        assert_eq!(s.len(), 1, "{s:?}");
        assert!(
            s[0].0 > 9.0 && s[0].0 < 11.0 && s[0].1 > 19.0 && s[0].1 < 21.0,
            "{s:?}"
        );
    }
}
