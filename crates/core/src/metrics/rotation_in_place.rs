//! Detecting rotations in place, which the Drift Error must exclude.
//!
//! When a robot turns on the spot about (or near) its reference sensor, the reference travels ~0 m while
//! an estimate sensor at a lever arm l from the axis sweeps an arc of l·|angle|. The lever-arm correction
//! cannot fix this (r_ref ≈ 0, so α = r_ref/r_est ≈ 0 is meaningless), and the window containing the
//! spin would report a huge DE that says nothing about drift. So such intervals are found and both
//! trajectories' paths inside them are left out.
//!
//! Detection: a *standstill* of the reference is a run of consecutive reference samples that all stay
//! within `still_radius_m` of the run's running centroid (no motion beyond noise) for at least
//! `min_still_s` (the paper's Δt_max: no ε-chord within Δt_max), not crossing a sampling gap longer than
//! `min_still_s`. A reference rotating about a point within `still_radius_m` of it (radius ~0) is a
//! standstill too. The standstill is a rotation in place when, over the same time span, the estimate
//! (already on the reference clock) travels more than `still_radius_m` further than the reference, both
//! paths measured on polylines decimated with ε = `still_radius_m` (so that the reference's noise inside
//! its ball counts ~0, while the slow approach into the stop counts on both sides). Plain stops, where both
//! stand still, are not reported (both paths are ~0 there anyway).

use nalgebra::Vector3;

use super::decimate::{interpolate_position, DecimatedPath};

/// Parameters of the rotation-in-place detector.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RotationInPlaceParams {
    /// Radius of the ball the reference must stay in to stand still, metres (above its noise).
    pub still_radius_m: f64,
    /// Shortest standstill, seconds (the paper's Δt_max).
    pub min_still_s: f64,
}

impl Default for RotationInPlaceParams {
    fn default() -> Self {
        RotationInPlaceParams {
            still_radius_m: 0.15,
            min_still_s: 2.0,
        }
    }
}

/// The samples of a trajectory inside `[t0, t1]`, with the positions interpolated at both ends.
fn slice_between(
    times: &[f64],
    positions: &[Vector3<f64>],
    t0: f64,
    t1: f64,
) -> (Vec<f64>, Vec<Vector3<f64>>) {
    let i0 = times.partition_point(|&x| x <= t0);
    let i1 = times.partition_point(|&x| x < t1).max(i0);
    let mut t = Vec::with_capacity(i1 - i0 + 2);
    let mut p = Vec::with_capacity(i1 - i0 + 2);
    t.push(t0);
    p.push(interpolate_position(times, positions, t0));
    t.extend_from_slice(&times[i0..i1]);
    p.extend_from_slice(&positions[i0..i1]);
    t.push(t1);
    p.push(interpolate_position(times, positions, t1));
    (t, p)
}

/// Standstill intervals `[t_start, t_end]` of a trajectory (seconds), in time order.
pub fn standstills(
    times: &[f64],
    positions: &[Vector3<f64>],
    params: &RotationInPlaceParams,
) -> Vec<[f64; 2]> {
    let n = times.len().min(positions.len());
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        let mut centroid = positions[i];
        let mut count = 1.0;
        let mut j = i + 1;
        while j < n
            && times[j] - times[j - 1] <= params.min_still_s
            && (positions[j] - centroid).norm() < params.still_radius_m
        {
            count += 1.0;
            centroid += (positions[j] - centroid) / count;
            j += 1;
        }
        if times[j - 1] - times[i] >= params.min_still_s {
            out.push([times[i], times[j - 1]]);
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// The rotations in place: reference standstills during which the estimate sweeps an arc. Both inputs
/// are on the same clock (the estimate already shifted); returns sorted, disjoint `[t_start, t_end]`.
pub fn rotations_in_place(
    ref_t: &[f64],
    ref_p: &[Vector3<f64>],
    est_t: &[f64],
    est_p: &[Vector3<f64>],
    params: &RotationInPlaceParams,
) -> Vec<[f64; 2]> {
    let n_est = est_t.len().min(est_p.len());
    if n_est == 0 {
        return Vec::new();
    }
    let (est_t, est_p) = (&est_t[..n_est], &est_p[..n_est]);
    let eps = params.still_radius_m;
    standstills(ref_t, ref_p, params)
        .into_iter()
        .filter(|&[t0, t1]| {
            if t1 < est_t[0] || t0 > est_t[n_est - 1] {
                return false;
            }
            let (et, ep) = slice_between(est_t, est_p, t0, t1);
            let (rt, rp) = slice_between(ref_t, ref_p, t0, t1);
            let est_len = DecimatedPath::new(&et, &ep, eps, &[]).length_between(t0, t1);
            let ref_len = DecimatedPath::new(&rt, &rp, eps, &[]).length_between(t0, t1);
            est_len - ref_len > eps
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spin_is_found_and_plain_stop_is_not() {
        // Drive 5 s along x, stop 5 s, spin 5 s about the reference (estimate 0.5 m to the left), drive on.
        let mut rt = vec![];
        let mut rp = vec![];
        let mut et = vec![];
        let mut ep = vec![];
        let mut heading = 0.0f64;
        let mut x = 0.0;
        for i in 0..=250 {
            let t = i as f64 * 0.1;
            if !(5.0..20.0).contains(&t) {
                x += 0.1;
            }
            if (10.0..15.0).contains(&t) {
                heading += std::f64::consts::PI / 50.0;
            }
            let p = Vector3::new(x, 0.0, 0.0);
            let lever = Vector3::new(-0.5 * heading.sin(), 0.5 * heading.cos(), 0.0);
            rt.push(t);
            rp.push(p);
            et.push(t);
            ep.push(p + lever);
        }
        let still = standstills(&rt, &rp, &RotationInPlaceParams::default());
        assert_eq!(still.len(), 1);
        let rip = rotations_in_place(&rt, &rp, &et, &ep, &RotationInPlaceParams::default());
        assert_eq!(rip.len(), 1);
        assert!(rip[0][0] <= 10.0 && rip[0][1] >= 15.0, "{rip:?}");
        // Without the spin nothing is reported.
        let rip = rotations_in_place(&rt, &rp, &rt, &rp, &RotationInPlaceParams::default());
        assert!(rip.is_empty());
    }
}
