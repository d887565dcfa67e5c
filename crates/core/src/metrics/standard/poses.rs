//! Poses as evo holds them: stamps in `f64` seconds, positions, and rotation matrices when the source has
//! orientation. The standard metrics (APE, RPE) work on this form so that every float operation follows
//! evo's order and its numbers come out to the last printed decimal.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use crate::sources::tum::{DecimalQuaternions, TumOrientations};
use crate::trajectory::rows::usable_position;
use crate::trajectory::Trajectory;

/// How a source's nanosecond stamps become the `f64` seconds evo compares: each reader of evo converts
/// differently, and association at `t_max_diff` is decided on those floats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StampSeconds {
    /// A decimal number parsed from text (TUM, KITTI times): the nearest double.
    Decimal,
    /// Integer nanoseconds read as a double, then divided by 1e9 (evo's EuRoC reader).
    NanosOverE9,
    /// `sec + nanosec · 1e-9` (evo's ROS bag and MCAP readers).
    SecPlusNanos,
}

impl StampSeconds {
    /// Converts one stamp.
    pub fn convert(self, ns: i64) -> f64 {
        let (sec, nsec) = (ns.div_euclid(1_000_000_000), ns.rem_euclid(1_000_000_000));
        match self {
            StampSeconds::Decimal => sec as f64 + nsec as f64 / 1e9,
            StampSeconds::NanosOverE9 => ns as f64 / 1e9,
            StampSeconds::SecPlusNanos => sec as f64 + nsec as f64 * 1e-9,
        }
    }
}

/// Orientations, kept in the form the source gave them.
#[derive(Debug, Clone, PartialEq)]
pub enum Rotations {
    /// Unit quaternions as read, and the rotation an alignment applied on their left: pose `i` is
    /// `left · M(q_i)`, the product evo forms (its poses are `quaternion_matrix(q)`, then transformed).
    /// Half the memory of matrices, which matters at millions of poses.
    Quaternions {
        q: Vec<UnitQuaternion<f64>>,
        left: Matrix3<f64>,
    },
    /// Rotation matrices as read (KITTI rows, not re-orthonormalised, as evo uses them).
    Matrices(Vec<Matrix3<f64>>),
    /// Like `Quaternions`, kept as a TUM file's decimal digits (each decoded into the quaternion the
    /// parser gives): half the memory again, which keeps a million-pose RPE at a tenth of evo's.
    Decimal {
        q: DecimalQuaternions,
        left: Matrix3<f64>,
    },
}

impl Rotations {
    /// The rotation matrix of pose `i`.
    pub fn get(&self, i: usize) -> Matrix3<f64> {
        match self {
            Rotations::Quaternions { q, left } => left * quaternion_matrix(&q[i]),
            Rotations::Matrices(m) => m[i],
            Rotations::Decimal { q, left } => left * quaternion_matrix(&q.get(i)),
        }
    }

    /// Number of rotations.
    pub fn len(&self) -> usize {
        match self {
            Rotations::Quaternions { q, .. } => q.len(),
            Rotations::Matrices(m) => m.len(),
            Rotations::Decimal { q, .. } => q.digits.len(),
        }
    }

    /// True when there is none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Applies `r` on the left of every rotation.
    pub fn rotate(&mut self, r: &Matrix3<f64>) {
        match self {
            Rotations::Quaternions { left, .. } | Rotations::Decimal { left, .. } => {
                *left = r * *left
            }
            Rotations::Matrices(m) => m.iter_mut().for_each(|x| *x = r * *x),
        }
    }

    fn select(self, ids: &[u32]) -> Rotations {
        match self {
            Rotations::Quaternions { q, left } => Rotations::Quaternions {
                q: select_vec(q, ids),
                left,
            },
            Rotations::Matrices(m) => Rotations::Matrices(select_vec(m, ids)),
            Rotations::Decimal { q, left } => Rotations::Decimal {
                q: DecimalQuaternions {
                    digits: select_vec(q.digits, ids),
                    frac: q.frac,
                },
                left,
            },
        }
    }
}

/// A trajectory in evo's form.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Poses {
    /// Stamps in seconds; `None` for a path paired by index (KITTI pose files).
    pub stamps_s: Option<Vec<f64>>,
    pub positions: Vec<Vector3<f64>>,
    /// Body-to-frame rotations, when the source has orientation.
    pub rotations: Option<Rotations>,
}

impl Poses {
    /// Converts a trajectory (moving its vectors), stamped (`Some(conv)`) or a path paired by index
    /// (`None`).
    pub fn from_trajectory(t: Trajectory, stamps: Option<StampSeconds>) -> Poses {
        Poses {
            // Same size as i64: the allocation is reused.
            stamps_s: stamps.map(|c| t.stamps_ns.into_iter().map(|s| c.convert(s)).collect()),
            positions: t.positions,
            rotations: t.orientations.map(|q| Rotations::Quaternions {
                q,
                left: Matrix3::identity(),
            }),
        }
    }

    /// A TUM file's rows (stamps as decimal seconds) with its orientations apart.
    pub fn from_tum(t: Trajectory, orientations: Option<TumOrientations>) -> Poses {
        let mut p = Poses::from_trajectory(t, Some(StampSeconds::Decimal));
        let left = Matrix3::identity();
        p.rotations = orientations.map(|o| match o {
            TumOrientations::Decimal(q) => Rotations::Decimal { q, left },
            TumOrientations::Quaternions(q) => Rotations::Quaternions { q, left },
        });
        p
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there is no pose.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Keeps the poses at `ids`, in that order (repeats allowed: evo's association is not unique); in
    /// place when the ids allow it.
    pub fn select(self, ids: &[u32]) -> Poses {
        Poses {
            stamps_s: self.stamps_s.map(|s| select_vec(s, ids)),
            positions: select_vec(self.positions, ids),
            rotations: self.rotations.map(|r| r.select(ids)),
        }
    }

    /// The poses whose position is usable (finite, in range: the rows every reader of the project
    /// keeps, [`crate::trajectory::rows::usable_position`]), in file order with repeated stamps kept
    /// as evo reads them.
    pub fn usable(self) -> Poses {
        if self.positions.iter().all(usable_position) {
            return self;
        }
        let ids: Vec<u32> = (0..self.positions.len())
            .filter(|&i| usable_position(&self.positions[i]))
            .map(|i| i as u32)
            .collect();
        self.select(&ids)
    }

    /// Copies of the poses at `ids`, in that order (the source stays whole).
    pub fn select_copy(&self, ids: &[u32]) -> Poses {
        let pick = |v: &[f64]| ids.iter().map(|&i| v[i as usize]).collect();
        Poses {
            stamps_s: self.stamps_s.as_deref().map(pick),
            positions: ids.iter().map(|&i| self.positions[i as usize]).collect(),
            rotations: self.rotations.clone().map(|r| r.select(ids)),
        }
    }

    /// Keeps the poses stamped in `[start, end]` (either bound optional), like evo's
    /// `reduce_to_time_range`.
    pub fn crop(self, start: Option<f64>, end: Option<f64>) -> Poses {
        if start.is_none() && end.is_none() {
            return self;
        }
        let Some(s) = &self.stamps_s else {
            return self;
        };
        let ids: Vec<u32> = (0..s.len())
            .filter(|&i| start.is_none_or(|a| s[i] >= a) && end.is_none_or(|b| s[i] <= b))
            .map(|i| i as u32)
            .collect();
        self.select(&ids)
    }

    /// The rotation of pose `i` (identity when the source has none).
    pub fn rotation(&self, i: usize) -> Matrix3<f64> {
        self.rotations
            .as_ref()
            .map_or_else(Matrix3::identity, |r| r.get(i))
    }
}

/// `v[ids]`; in place (no second buffer) when every id is at or after its slot, as association's are.
fn select_vec<T: Copy>(mut v: Vec<T>, ids: &[u32]) -> Vec<T> {
    if ids.iter().enumerate().all(|(k, &i)| i as usize >= k) {
        for (k, &i) in ids.iter().enumerate() {
            v[k] = v[i as usize];
        }
        v.truncate(ids.len());
        v
    } else {
        ids.iter().map(|&i| v[i as usize]).collect()
    }
}

/// The rotation matrix of a quaternion, as evo's `transformations.quaternion_matrix` computes it
/// (normalising by `sqrt(2 / |q|²)`, then the outer product).
pub fn quaternion_matrix(q: &UnitQuaternion<f64>) -> Matrix3<f64> {
    let v = [q.w, q.i, q.j, q.k];
    let n: f64 = v.iter().map(|x| x * x).sum();
    if n < f64::EPSILON * 4.0 {
        return Matrix3::identity();
    }
    let f = (2.0 / n).sqrt();
    let v = v.map(|x| x * f);
    let o = |a: usize, b: usize| v[a] * v[b];
    Matrix3::new(
        1.0 - o(2, 2) - o(3, 3),
        o(1, 2) - o(3, 0),
        o(1, 3) + o(2, 0),
        o(1, 2) + o(3, 0),
        1.0 - o(1, 1) - o(3, 3),
        o(2, 3) - o(1, 0),
        o(1, 3) - o(2, 0),
        o(2, 3) + o(1, 0),
        1.0 - o(1, 1) - o(2, 2),
    )
}

/// The angle of a rotation matrix's logarithm, radians, as scipy's `Rotation.from_matrix(r).as_rotvec()`
/// norm (Markley's quaternion extraction, then `2·atan2(|v|, |w|)`), which evo's `so3_log_angle` uses.
pub fn rotation_angle(m: &Matrix3<f64>) -> f64 {
    // scipy first replaces a matrix that is not orthogonal (its Gram matrix not within
    // `isclose(…, I, rtol=1e-5, atol=1e-12)`) by the nearest rotation U·Vᵀ of its SVD.
    let g = m * m.transpose();
    let close = (0..3).all(|i| {
        (0..3).all(|j| {
            let e = if i == j { 1.0 } else { 0.0 };
            (g[(i, j)] - e).abs() <= 1e-12 + 1e-5 * f64::abs(e)
        })
    });
    let orthogonal;
    let m = if close {
        m
    } else {
        let svd = m.svd(true, true);
        orthogonal = match (svd.u, svd.v_t) {
            (Some(u), Some(vt)) => u * vt,
            _ => *m,
        };
        &orthogonal
    };
    let d = [
        m[(0, 0)],
        m[(1, 1)],
        m[(2, 2)],
        m[(0, 0)] + m[(1, 1)] + m[(2, 2)],
    ];
    let mut choice = 0;
    for k in 1..4 {
        if d[k] > d[choice] {
            choice = k;
        }
    }
    let mut q = [0.0f64; 4];
    if choice != 3 {
        let (i, j, k) = (choice, (choice + 1) % 3, (choice + 2) % 3);
        q[i] = 1.0 - d[3] + 2.0 * m[(i, i)];
        q[j] = m[(j, i)] + m[(i, j)];
        q[k] = m[(k, i)] + m[(i, k)];
        q[3] = m[(k, j)] - m[(j, k)];
    } else {
        q[0] = m[(2, 1)] - m[(1, 2)];
        q[1] = m[(0, 2)] - m[(2, 0)];
        q[2] = m[(1, 0)] - m[(0, 1)];
        q[3] = 1.0 + d[3];
    }
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    let q = q.map(|x| x / n);
    let v = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
    2.0 * v.atan2(q[3].abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_convert_like_evo_readers() {
        let ns = 1_311_868_164_363_181_000;
        assert_eq!(StampSeconds::Decimal.convert(ns), 1311868164.363181);
        assert_eq!(
            StampSeconds::NanosOverE9.convert(1_403_715_524_907_143_168),
            1_403_715_524_907_143_168f64 / 1e9
        );
        assert_eq!(StampSeconds::SecPlusNanos.convert(-500_000_000), -0.5);
    }

    #[test]
    fn angle_of_known_rotations() {
        for a in [0.0, 1e-6, 0.3, 1.0, 3.0, std::f64::consts::PI - 1e-9] {
            let r = UnitQuaternion::from_euler_angles(0.2 * a, -0.5 * a, 0.8 * a);
            let m = quaternion_matrix(&r);
            assert!((rotation_angle(&m) - r.angle()).abs() < 1e-12, "{a}");
        }
    }
}
