//! Relative pose error, as evo's `metrics.RPE`: pose pairs `(i, j)` chosen on one trajectory (the
//! estimate by default) by a delta in frames, metres of path or degrees/radians of rotation, then per
//! pair `E = (Q_i⁻¹Q_j)⁻¹ (P_i⁻¹P_j)` reduced by the pose relation. Path deltas in consecutive mode
//! restart the accumulated length at 0 after each pair, as evo does.

use nalgebra::{Matrix3, Vector3};

use super::poses::{rotation_angle, Poses};
use super::relation::PoseRelation;
use crate::error::{Error, Result};

/// `-u/--delta_unit`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DeltaUnit {
    #[default]
    Frames,
    Meters,
    Degrees,
    Radians,
}

impl DeltaUnit {
    /// evo's letter.
    pub fn parse(s: &str) -> Result<Self> {
        Ok(match s {
            "f" => DeltaUnit::Frames,
            "m" => DeltaUnit::Meters,
            "d" => DeltaUnit::Degrees,
            "r" => DeltaUnit::Radians,
            _ => {
                return Err(Error::InvalidArgument(format!(
                    "-u {s}: expected f (frames), m (metres), d (degrees) or r (radians)"
                )))
            }
        })
    }

    /// evo's name of the unit.
    pub fn as_str(self) -> &'static str {
        match self {
            DeltaUnit::Frames => "frames",
            DeltaUnit::Meters => "m",
            DeltaUnit::Degrees => "deg",
            DeltaUnit::Radians => "rad",
        }
    }
}

/// One RPE pose pair `(i, j)`.
pub type Pair = (usize, usize);

/// How RPE pairs are chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairSelection {
    pub delta: f64,
    pub unit: DeltaUnit,
    /// `-t/--delta_tol`: relative tolerance of all-pairs mode (evo: 0.1).
    pub rel_tol: f64,
    pub all_pairs: bool,
    pub from_reference: bool,
}

impl Default for PairSelection {
    fn default() -> Self {
        PairSelection {
            delta: 1.0,
            unit: DeltaUnit::Frames,
            rel_tol: 0.1,
            all_pairs: false,
            from_reference: false,
        }
    }
}

/// The index pairs of `poses` for `sel` (evo's `id_pairs_from_delta`).
pub fn pairs(poses: &Poses, sel: &PairSelection) -> Result<Vec<(usize, usize)>> {
    let n = poses.len();
    let out = match sel.unit {
        DeltaUnit::Frames => {
            if sel.delta < 1.0 || sel.delta.fract() != 0.0 {
                return Err(Error::InvalidArgument(format!(
                    "-d {}: a delta in frames must be a whole number ≥ 1",
                    sel.delta
                )));
            }
            let d = sel.delta as usize;
            if sel.all_pairs {
                (0..n.saturating_sub(d)).map(|i| (i, i + d)).collect()
            } else {
                let ids: Vec<usize> = (0..n).step_by(d).collect();
                ids.windows(2).map(|w| (w[0], w[1])).collect()
            }
        }
        DeltaUnit::Meters => by_path(
            &poses.positions,
            sel.delta,
            sel.delta * sel.rel_tol,
            sel.all_pairs,
        ),
        DeltaUnit::Degrees | DeltaUnit::Radians => {
            if poses.rotations.is_none() {
                return Err(needs_orientation(&format!("-u {}", sel.unit.as_str())));
            }
            let bound = if sel.unit == DeltaUnit::Degrees {
                180.0
            } else {
                std::f64::consts::PI
            };
            if !(0.0..=bound).contains(&sel.delta) {
                return Err(Error::InvalidArgument(format!(
                    "-d {}: an angle delta must be within [0, {bound}]",
                    sel.delta
                )));
            }
            let scale = if sel.unit == DeltaUnit::Degrees {
                std::f64::consts::PI / 180.0
            } else {
                1.0
            };
            by_angle(
                poses,
                sel.delta * scale,
                sel.delta * sel.rel_tol * scale,
                sel.all_pairs,
            )
        }
    };
    if out.is_empty() {
        return Err(Error::Metric(format!(
            "delta = {} ({}) produced no pair among {n} poses; try a lower delta (or a larger --delta_tol with --all_pairs)",
            sel.delta,
            sel.unit.as_str()
        )));
    }
    Ok(out)
}

/// The one-line error for an option that needs orientation on position-only data.
pub fn needs_orientation(what: &str) -> Error {
    Error::Metric(format!(
        "{what} needs orientations, and a trajectory has positions only (TUM rows of 4 values, PointStamped, NavSatFix); use -r point_distance (RPE) or -r trans_part (APE)"
    ))
}

fn by_path(p: &[Vector3<f64>], delta: f64, tol: f64, all_pairs: bool) -> Vec<(usize, usize)> {
    if p.is_empty() {
        return Vec::new();
    }
    if !all_pairs {
        let mut ids = vec![0];
        let mut path = 0.0;
        for i in 1..p.len() {
            path += (p[i] - p[i - 1]).norm();
            if path >= delta {
                ids.push(i);
                path = 0.0;
            }
        }
        return ids.windows(2).map(|w| (w[0], w[1])).collect();
    }
    // Accumulated distances are non-decreasing: the argmin of |d_j − d_i − δ| over j > i is found by
    // binary search instead of evo's scan (same pick: the first index on ties).
    let mut d = Vec::with_capacity(p.len());
    d.push(0.0);
    for i in 1..p.len() {
        d.push(d[i - 1] + (p[i] - p[i - 1]).norm());
    }
    let mut out = Vec::new();
    for i in 0..d.len().saturating_sub(1) {
        let rest = &d[i + 1..];
        let from = |x: f64| x - d[i];
        let k = rest.partition_point(|&x| from(x) < delta);
        let cand = |j: usize| (from(rest[j]) - delta).abs();
        let pick = if k == rest.len() {
            k - 1
        } else if k == 0 {
            0
        } else if cand(k) < cand(k - 1) {
            k
        } else {
            k - 1
        };
        // The first index with the same accumulated distance (argmin's tie rule).
        let v = from(rest[pick]);
        let pick = rest.partition_point(|&x| from(x) < v);
        if cand(pick) <= tol {
            out.push((i, i + 1 + pick));
        }
    }
    out
}

fn by_angle(p: &Poses, delta: f64, tol: f64, all_pairs: bool) -> Vec<(usize, usize)> {
    let r: Vec<Matrix3<f64>> = (0..p.len()).map(|i| p.rotation(i)).collect();
    let rel = |a: &Matrix3<f64>, b: &Matrix3<f64>| rotation_angle(&(a.transpose() * b));
    let mut out = Vec::new();
    if all_pairs {
        for i in 0..r.len().saturating_sub(1) {
            for j in i + 1..r.len() {
                let a = rel(&r[i], &r[j]);
                if delta - tol <= a && a <= delta + tol {
                    out.push((i, j));
                }
            }
        }
        return out;
    }
    let (mut acc, mut start) = (0.0, 0);
    for i in 0..r.len().saturating_sub(1) {
        acc += rel(&r[i], &r[i + 1]);
        if acc >= delta {
            out.push((start, i + 1));
            acc = 0.0;
            start = i + 1;
        }
    }
    out
}

/// The per-pair RPE values of two associated trajectories (same length), and the pairs used.
pub fn rpe_errors(
    reference: &Poses,
    estimate: &Poses,
    relation: PoseRelation,
    sel: &PairSelection,
) -> Result<(Vec<f64>, Vec<Pair>)> {
    if reference.len() != estimate.len() {
        return Err(Error::Metric(format!(
            "RPE pairs poses one to one: the reference has {} and the estimate {}",
            reference.len(),
            estimate.len()
        )));
    }
    let ids = pairs(
        if sel.from_reference {
            reference
        } else {
            estimate
        },
        sel,
    )?;
    let dist = |p: &Poses, i: usize, j: usize| (p.positions[i] - p.positions[j]).norm();
    let values = match relation {
        PoseRelation::PointDistance => ids
            .iter()
            .map(|&(i, j)| (dist(reference, i, j) - dist(estimate, i, j)).abs())
            .collect(),
        PoseRelation::PointDistanceErrorRatio => ids
            .iter()
            .filter(|&&(i, j)| dist(reference, i, j) != 0.0)
            .map(|&(i, j)| {
                let r = dist(reference, i, j);
                (r - dist(estimate, i, j)).abs() / r * 100.0
            })
            .collect(),
        _ => ids
            .iter()
            .map(|&(i, j)| {
                let (rq, tq) = relative(reference, i, j);
                let (rp, tp) = relative(estimate, i, j);
                let rq_t = rq.transpose();
                relation.of_error_pose(&(rq_t * rp), &(rq_t * tp - rq_t * tq))
            })
            .collect(),
    };
    Ok((values, ids))
}

/// `P_i⁻¹ P_j` as evo computes it: `[R_iᵀ R_j | R_iᵀ t_j − R_iᵀ t_i]`.
fn relative(p: &Poses, i: usize, j: usize) -> (Matrix3<f64>, Vector3<f64>) {
    let ri_t = p.rotation(i).transpose();
    (
        ri_t * p.rotation(j),
        ri_t * p.positions[j] - ri_t * p.positions[i],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(steps: &[f64]) -> Poses {
        let mut x = 0.0;
        let mut positions = vec![Vector3::zeros()];
        for s in steps {
            x += s;
            positions.push(Vector3::new(x, 0.0, 0.0));
        }
        Poses {
            stamps_s: None,
            positions,
            rotations: None,
        }
    }

    #[test]
    fn path_pairs_restart_after_each_pair() {
        let p = line(&[0.6, 0.6, 0.3, 0.3, 0.5]);
        let sel = PairSelection {
            delta: 1.0,
            unit: DeltaUnit::Meters,
            ..Default::default()
        };
        assert_eq!(pairs(&p, &sel).unwrap(), vec![(0, 2), (2, 5)]);
        let all = PairSelection {
            all_pairs: true,
            ..sel
        };
        assert_eq!(pairs(&p, &all).unwrap(), vec![(1, 3), (2, 5)]);
    }

    #[test]
    fn all_pairs_by_path_matches_a_scan() {
        let steps: Vec<f64> = (0..200).map(|i| ((i * 7919) % 13) as f64 * 0.05).collect();
        let p = line(&steps);
        let sel = PairSelection {
            delta: 1.0,
            unit: DeltaUnit::Meters,
            all_pairs: true,
            ..Default::default()
        };
        let fast = pairs(&p, &sel).unwrap();
        let mut d = vec![0.0];
        for w in p.positions.windows(2) {
            d.push(d.last().unwrap() + (w[1] - w[0]).norm());
        }
        let mut slow = Vec::new();
        for i in 0..d.len() - 1 {
            let mut best = i + 1;
            for j in i + 1..d.len() {
                if ((d[j] - d[i]) - 1.0).abs() < ((d[best] - d[i]) - 1.0).abs() {
                    best = j;
                }
            }
            if ((d[best] - d[i]) - 1.0).abs() <= 0.1 {
                slow.push((i, best));
            }
        }
        assert_eq!(fast, slow);
    }
}
