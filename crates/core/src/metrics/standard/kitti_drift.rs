//! KITTI segment drift, as the KITTI odometry devkit (`evaluate_odometry.cpp`) computes it: from every
//! 10th pose, for each length 100, 200 … 800 m of reference path, the first pose at least that far on;
//! the relative pose error of the segment `E = (P_a⁻¹P_b)⁻¹(Q_a⁻¹Q_b)`, its translation over the length
//! (t_err, %) and its rotation angle over the length (r_err, deg/100 m), averaged over all segments.

use serde::{Deserialize, Serialize};

use super::poses::Poses;
use crate::error::{Error, Result};

/// The devkit's segment lengths, metres.
pub const LENGTHS_M: [f64; 8] = [100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0];
/// The devkit's step between first frames.
pub const STEP: usize = 10;

/// Drift over the segments of one length.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentDrift {
    pub length_m: f64,
    pub segments: usize,
    /// Mean translation error over the length, percent.
    pub t_err_pct: f64,
    /// Mean rotation error over the length, degrees per 100 m.
    pub r_err_deg_per_100m: f64,
}

/// The devkit's summary: every segment of every length averaged, and per length.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KittiDrift {
    pub segments: usize,
    pub t_err_pct: f64,
    pub r_err_deg_per_100m: f64,
    pub per_length: Vec<SegmentDrift>,
}

/// KITTI drift of associated (same length, pose i with pose i) `reference` and `estimate`, both with
/// orientation. Fails when the reference is shorter than 100 m of path.
pub fn kitti_drift(reference: &Poses, estimate: &Poses) -> Result<KittiDrift> {
    if reference.rotations.is_none() || estimate.rotations.is_none() {
        return Err(super::rpe::needs_orientation("KITTI segment drift"));
    }
    let n = reference.len().min(estimate.len());
    let mut dist = Vec::with_capacity(n);
    dist.push(0.0);
    for i in 1..n {
        dist.push(dist[i - 1] + (reference.positions[i] - reference.positions[i - 1]).norm());
    }
    let mut per_length = Vec::new();
    let (mut all_t, mut all_r, mut count) = (0.0, 0.0, 0usize);
    for &len in &LENGTHS_M {
        let (mut t_sum, mut r_sum, mut k) = (0.0, 0.0, 0usize);
        for first in (0..n).step_by(STEP) {
            // The devkit's `lastFrameFromSegmentLength`: the first frame beyond first + len.
            let Some(last) = (first..n).find(|&j| dist[j] > dist[first] + len) else {
                continue;
            };
            let (rq, tq) = relative(reference, first, last);
            let (rp, tp) = relative(estimate, first, last);
            let rp_t = rp.transpose();
            let r_e = rp_t * rq;
            let t_e = rp_t * tq - rp_t * tp;
            let c = ((r_e.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
            t_sum += t_e.norm() / len;
            r_sum += c.acos() / len;
            k += 1;
        }
        if k > 0 {
            per_length.push(SegmentDrift {
                length_m: len,
                segments: k,
                t_err_pct: t_sum / k as f64 * 100.0,
                r_err_deg_per_100m: (r_sum / k as f64).to_degrees() * 100.0,
            });
            all_t += t_sum;
            all_r += r_sum;
            count += k;
        }
    }
    if count == 0 {
        return Err(Error::Metric(format!(
            "KITTI segment drift needs at least 100 m of reference path ({:.1} m here)",
            dist.last().copied().unwrap_or(0.0)
        )));
    }
    Ok(KittiDrift {
        segments: count,
        t_err_pct: all_t / count as f64 * 100.0,
        r_err_deg_per_100m: (all_r / count as f64).to_degrees() * 100.0,
        per_length,
    })
}

fn relative(p: &Poses, i: usize, j: usize) -> (nalgebra::Matrix3<f64>, nalgebra::Vector3<f64>) {
    let ri_t = p.rotation(i).transpose();
    (
        ri_t * p.rotation(j),
        ri_t * (p.positions[j] - p.positions[i]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::standard::poses::Rotations;
    use nalgebra::{Matrix3, Vector3};

    fn straight(n: usize, step: f64) -> Poses {
        Poses {
            stamps_s: None,
            positions: (0..n)
                .map(|i| Vector3::new(i as f64 * step, 0.0, 0.0))
                .collect(),
            rotations: Some(Rotations::Matrices(vec![Matrix3::identity(); n])),
        }
    }

    #[test]
    fn a_scale_error_is_its_percentage() {
        let r = straight(2000, 1.0);
        let e = straight(2000, 1.01);
        let d = kitti_drift(&r, &e).unwrap();
        assert!((d.t_err_pct - 1.0).abs() < 0.02, "{d:?}");
        assert!(d.r_err_deg_per_100m.abs() < 1e-9);
        assert_eq!(d.per_length.len(), 8);
        let short = kitti_drift(&straight(50, 1.0), &straight(50, 1.0)).unwrap_err();
        assert!(short.to_string().contains("at least 100 m"));
    }
}
