//! evo's pose filters applied before association (`--downsample N`, `--motion_filter DISTANCE
//! ANGLE_DEGREES`): the same indices evo keeps, so that the metric sees the same poses.

use super::poses::{rotation_angle, Poses};
use crate::error::{Error, Result};

/// evo's `downsample`: `np.linspace(0, n − 1, num, dtype=int)`, nothing when `n ≤ num`.
///
/// ```
/// use trajdrift_core::metrics::standard::filters::downsample_ids;
/// assert_eq!(downsample_ids(10, 4), vec![0, 3, 6, 9]);
/// assert_eq!(downsample_ids(3, 5), vec![0, 1, 2]);
/// ```
pub fn downsample_ids(n: usize, num: usize) -> Vec<u32> {
    if n <= num || num == 0 {
        return (0..n as u32).collect();
    }
    if num == 1 {
        return vec![0];
    }
    let step = (n - 1) as f64 / (num - 1) as f64;
    let mut ids: Vec<u32> = (0..num).map(|k| (k as f64 * step) as u32).collect();
    ids[num - 1] = (n - 1) as u32;
    ids
}

/// evo's `filter_by_motion` with the angle in degrees: keep the first pose, then each pose whose
/// accumulated path length since the last kept one reaches `distance_m`, or whose rotation from
/// the last kept one reaches `angle_deg`.
pub fn motion_filter_ids(p: &Poses, distance_m: f64, angle_deg: f64) -> Result<Vec<u32>> {
    if p.len() < 2 {
        return Err(Error::Metric(
            "--motion_filter: poses must contain at least two poses".into(),
        ));
    }
    if distance_m < 0.0 || angle_deg < 0.0 {
        return Err(Error::Metric(format!(
            "--motion_filter {distance_m} {angle_deg}: the thresholds must be >= 0"
        )));
    }
    let angle = angle_deg.to_radians();
    let mut acc = Vec::with_capacity(p.len());
    let mut sum = 0.0;
    for (i, x) in p.positions.iter().enumerate() {
        if i > 0 {
            sum += (x - p.positions[i - 1]).norm();
        }
        acc.push(sum);
    }
    let (mut ids, mut prev_angle, mut prev_dist) = (vec![0u32], 0usize, 0.0);
    for (i, &d) in acc.iter().enumerate().skip(1) {
        let keep = d - prev_dist >= distance_m
            || rotation_angle(&(p.rotation(prev_angle).transpose() * p.rotation(i))) >= angle;
        if keep {
            ids.push(i as u32);
            prev_angle = i;
            prev_dist = d;
        }
    }
    Ok(ids)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn motion_filter_keeps_every_metre() {
        let p = Poses {
            stamps_s: Some((0..11).map(|i| i as f64).collect()),
            positions: (0..11)
                .map(|i| Vector3::new(0.5 * i as f64, 0.0, 0.0))
                .collect(),
            rotations: None,
        };
        assert_eq!(
            motion_filter_ids(&p, 1.0, 90.0).unwrap(),
            vec![0, 2, 4, 6, 8, 10]
        );
    }
}
