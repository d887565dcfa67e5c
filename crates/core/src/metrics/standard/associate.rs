//! Association of two stamped trajectories, exactly as evo's `sync.associate_trajectories`: for each
//! stamp of the trajectory with fewer poses, the nearest stamp of the other within `max_diff`, no
//! uniqueness (two short stamps may take the same long one). The offset is added to the estimate's
//! stamps for the matching only; `Interpolation` then resamples the longer trajectory at the matched
//! stamps instead of snapping to its nearest pose.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion};

use super::poses::{Poses, Rotations};
use crate::error::{Error, Result};

/// evo's `--sync_method`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SyncMethod {
    /// Snap to the nearest pose (default).
    #[default]
    NearestTime,
    /// Interpolate the longer trajectory (linear positions, slerp rotations).
    Interpolation,
}

/// evo's `matching_time_indices` on sorted stamps (binary search): for each stamp of `a`, the index of
/// the nearest stamp of `b + offset_b` within `max_diff`, ties to the earlier one.
pub fn matching_time_indices(
    a: &[f64],
    b: &[f64],
    max_diff: f64,
    offset_b: f64,
) -> (Vec<u32>, Vec<u32>) {
    let (ia, ib) = match_ids(a, b, max_diff, offset_b);
    (ia.into_vec(), ib)
}

/// The matched indices of the first trajectory: all of them in order (no list kept: at millions of
/// poses that is memory), or the list.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Ids {
    /// `0..n`.
    All(usize),
    List(Vec<u32>),
}

impl Ids {
    fn push(&mut self, i: usize) {
        match self {
            Ids::All(n) if *n == i => *n += 1,
            Ids::All(n) => {
                let mut v: Vec<u32> = (0..*n as u32).collect();
                v.push(i as u32);
                *self = Ids::List(v);
            }
            Ids::List(v) => v.push(i as u32),
        }
    }

    /// Number of matched indices.
    pub fn len(&self) -> usize {
        match self {
            Ids::All(n) => *n,
            Ids::List(v) => v.len(),
        }
    }

    /// True when nothing matched.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The indices as a list.
    pub fn into_vec(self) -> Vec<u32> {
        match self {
            Ids::All(n) => (0..n as u32).collect(),
            Ids::List(v) => v,
        }
    }
}

/// [`matching_time_indices`] with the first side's indices as [`Ids`].
fn match_ids(a: &[f64], b: &[f64], max_diff: f64, offset_b: f64) -> (Ids, Vec<u32>) {
    let (mut ia, mut ib) = (Ids::All(0), Vec::new());
    if b.is_empty() {
        return (ia, ib);
    }
    // `b + offset` as evo forms it (`stamps_2 += offset_2`), without a copy of the stamps.
    let at = |j: usize| b[j] + offset_b;
    if b.windows(2).any(|w| w[1] < w[0]) {
        // Unsorted stamps: evo's linear search (first minimum), kept for the same pairs.
        for (i, &t) in a.iter().enumerate() {
            let mut best = 0;
            for j in 0..b.len() {
                if (at(j) - t).abs() < (at(best) - t).abs() {
                    best = j;
                }
            }
            if (at(best) - t).abs() <= max_diff {
                ia.push(i);
                ib.push(best as u32);
            }
        }
        return (ia, ib);
    }
    let (first, last) = (at(0), at(b.len() - 1));
    let mut j = 0usize;
    let mut prev = f64::NEG_INFINITY;
    for (i, &t) in a.iter().enumerate() {
        if t < first - max_diff || t > last + max_diff {
            continue;
        }
        // evo's `searchsorted(b, t, side="right")`: a forward walk while `a` is sorted, else a search.
        if t >= prev {
            while j < b.len() && at(j) <= t {
                j += 1;
            }
        } else {
            let (mut lo, mut hi) = (0, b.len());
            while lo < hi {
                let mid = (lo + hi) / 2;
                if at(mid) <= t {
                    lo = mid + 1;
                } else {
                    hi = mid;
                }
            }
            j = lo;
        }
        prev = t;
        let k = j.min(b.len() - 1);
        let ub = at(k) - t;
        let lb = if k > 0 { t - at(k - 1) } else { f64::INFINITY };
        let best = if ub <= max_diff && ub < lb {
            k
        } else if lb <= max_diff && lb <= ub {
            k - 1
        } else {
            continue;
        };
        ia.push(i);
        ib.push(best as u32);
    }
    (ia, ib)
}

/// Associates `reference` and `estimate` (both stamped); returns the pairs in the order of the shorter
/// one. `offset_s` is added to the estimate's stamps for the matching.
pub fn associate(
    reference: Poses,
    estimate: Poses,
    max_diff: f64,
    offset_s: f64,
    method: SyncMethod,
) -> Result<(Poses, Poses)> {
    let (Some(tr), Some(te)) = (&reference.stamps_s, &estimate.stamps_s) else {
        return Err(Error::InvalidArgument(
            "association needs stamped trajectories on both sides".into(),
        ));
    };
    let est_longer = estimate.len() > reference.len();
    let (ts, tl) = if est_longer { (tr, te) } else { (te, tr) };
    let off = if est_longer { offset_s } else { -offset_s };
    let (is, il) = match_ids(ts, tl, max_diff, off);
    if is.is_empty() {
        return Err(no_pairs(tr, te, max_diff, offset_s));
    }
    let (short, long) = if est_longer {
        (reference, estimate)
    } else {
        (estimate, reference)
    };
    let short = kept(short, is);
    let long = match method {
        SyncMethod::NearestTime => long.select(&il),
        SyncMethod::Interpolation => interpolate(&long, &stamps_less(&short, off)),
    };
    Ok(if est_longer {
        (short, long)
    } else {
        (long, short)
    })
}

/// [`associate`] with the estimate borrowed: when it is the longer side (a 200 Hz odometry against a
/// 10 Hz reference), only its poses picked or interpolated for a pair are copied; otherwise it is the
/// side whose poses are kept, and it is copied whole as [`associate`] would keep it.
pub fn associate_borrowed(
    reference: Poses,
    estimate: &Poses,
    max_diff: f64,
    offset_s: f64,
    method: SyncMethod,
) -> Result<(Poses, Poses)> {
    if estimate.len() <= reference.len() {
        return associate(reference, estimate.clone(), max_diff, offset_s, method);
    }
    let (Some(tr), Some(te)) = (&reference.stamps_s, &estimate.stamps_s) else {
        return Err(Error::InvalidArgument(
            "association needs stamped trajectories on both sides".into(),
        ));
    };
    let (is, il) = match_ids(tr, te, max_diff, offset_s);
    if is.is_empty() {
        return Err(no_pairs(tr, te, max_diff, offset_s));
    }
    let short = kept(reference, is);
    let long = match method {
        SyncMethod::NearestTime => estimate.select_copy(&il),
        SyncMethod::Interpolation => interpolate(estimate, &stamps_less(&short, offset_s)),
    };
    Ok((short, long))
}

/// The poses of the shorter side that found a pair.
fn kept(short: Poses, ids: Ids) -> Poses {
    match ids {
        Ids::All(n) if n == short.len() => short,
        other => short.select(&other.into_vec()),
    }
}

/// The stamps of `p` less `off`: where the longer side is interpolated.
fn stamps_less(p: &Poses, off: f64) -> Vec<f64> {
    p.stamps_s
        .as_ref()
        .map(|s| s.iter().map(|t| t - off).collect())
        .unwrap_or_default()
}

/// The "0 pairs" error, with how far apart the clocks look (start to start) and what to try.
fn no_pairs(tr: &[f64], te: &[f64], max_diff: f64, offset_s: f64) -> Error {
    let gap = match (tr.first(), te.first()) {
        (Some(a), Some(b)) => a - (b + offset_s),
        _ => 0.0,
    };
    Error::Metric(format!(
        "0 pairs within t_max_diff {max_diff} s; the clocks differ by about {gap:.3} s: try --time-offset auto (or --t_offset {gap:.3}, or a larger --t_max_diff)"
    ))
}

/// evo's `PoseTrajectory3D.interpolate` without extrapolation: linear positions, slerp rotations,
/// stamps outside the span clamped to the first/last pose.
pub fn interpolate(p: &Poses, at: &[f64]) -> Poses {
    let s = p.stamps_s.as_deref().unwrap_or(&[]);
    let n = s.len();
    let mut positions = Vec::with_capacity(at.len());
    let mut rotations = p.rotations.as_ref().map(|_| Vec::with_capacity(at.len()));
    if n < 2 || p.positions.len() < n {
        // No span to interpolate in: every stamp is clamped to the one pose (none: no pose at all).
        if n == 1 && !p.positions.is_empty() {
            for _ in at {
                positions.push(p.positions[0]);
                if let Some(o) = rotations.as_mut() {
                    o.push(p.rotation(0));
                }
            }
        }
        return Poses {
            stamps_s: Some(at.iter().take(positions.len()).copied().collect()),
            positions,
            rotations: rotations.map(Rotations::Matrices),
        };
    }
    for &t in at {
        let i = s
            .partition_point(|&x| x < t)
            .clamp(1, n.saturating_sub(1).max(1));
        let dt = s[i] - s[i - 1];
        let f = if dt > 0.0 {
            ((t - s[i - 1]) / dt).clamp(0.0, 1.0)
        } else {
            0.0
        };
        positions.push(p.positions[i - 1] + (p.positions[i] - p.positions[i - 1]) * f);
        if let Some(o) = rotations.as_mut() {
            let q = |m: Matrix3<f64>| {
                UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m))
            };
            let qi = q(p.rotation(i - 1)).slerp(&q(p.rotation(i)), f);
            o.push(*qi.to_rotation_matrix().matrix());
        }
    }
    Poses {
        stamps_s: Some(at.to_vec()),
        positions,
        rotations: rotations.map(Rotations::Matrices),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolating_one_pose_or_none_does_not_panic() {
        let one = Poses {
            stamps_s: Some(vec![1.0]),
            positions: vec![nalgebra::Vector3::new(1.0, 2.0, 3.0)],
            rotations: None,
        };
        let p = interpolate(&one, &[0.5, 1.0, 2.0]);
        assert_eq!(p.positions.len(), 3);
        let none = Poses {
            stamps_s: Some(vec![]),
            positions: vec![],
            rotations: None,
        };
        assert!(interpolate(&none, &[0.5]).positions.is_empty());
    }

    #[test]
    fn nearest_within_max_diff_without_uniqueness() {
        let a = [0.0, 0.1, 0.104, 0.5];
        let b = [0.0, 0.103, 0.2, 0.3];
        let (ia, ib) = matching_time_indices(&a, &b, 0.01, 0.0);
        assert_eq!(ia, vec![0, 1, 2]);
        assert_eq!(ib, vec![0, 1, 1]);
        let (ia, ib) = matching_time_indices(&a, &b, 0.01, 0.2);
        assert_eq!((ia, ib), (vec![3], vec![3]));
    }

    #[test]
    fn zero_pairs_names_the_clock_gap() {
        let p = |t0: f64| Poses {
            stamps_s: Some((0..10).map(|i| t0 + i as f64 * 0.1).collect()),
            positions: vec![nalgebra::Vector3::zeros(); 10],
            rotations: None,
        };
        let e = associate(p(100.0), p(105.0), 0.01, 0.0, SyncMethod::NearestTime)
            .unwrap_err()
            .to_string();
        assert!(e.contains("0 pairs within t_max_diff 0.01 s"), "{e}");
        assert!(
            e.contains("about -5.000 s") && e.contains("--time-offset auto"),
            "{e}"
        );
    }
}
