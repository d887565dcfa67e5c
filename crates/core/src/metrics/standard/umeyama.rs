//! Alignment of an estimate onto its reference from associated positions: Umeyama's least-squares
//! SE(3)/Sim(3) (as evo's `geometry.umeyama_alignment`, SVD by nalgebra), evo's scale-only and origin
//! alignments, and a 4-DoF alignment (yaw about z + translation) for gravity-aligned frames, which evo
//! lacks: with an IMU both frames share "up", and freeing roll and pitch would hide a tilt error.

use nalgebra::{Matrix3, Vector3};

use super::poses::Poses;
use crate::error::{Error, Result};

/// A similarity `p ↦ s·R·p + t` (rotations `R_e ↦ R·R_e`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Similarity {
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
    pub scale: f64,
}

impl Similarity {
    /// The identity.
    pub fn identity() -> Self {
        Similarity {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
            scale: 1.0,
        }
    }

    /// Applies the similarity to every pose (evo: `scale(s)` then `transform(se3(R, t))`).
    pub fn apply(&self, p: &mut Poses) {
        for x in &mut p.positions {
            *x = self.rotation * (*x * self.scale) + self.translation;
        }
        if let Some(r) = p.rotations.as_mut() {
            r.rotate(&self.rotation);
        }
    }
}

/// Umeyama's least-squares similarity mapping the points `x` (estimate) onto `y` (reference);
/// `with_scale` frees the scale. Fails like evo on a degenerate covariance (fewer than two singular
/// values above machine epsilon: all points equal, or on one line).
pub fn umeyama(x: &[Vector3<f64>], y: &[Vector3<f64>], with_scale: bool) -> Result<Similarity> {
    let n = x.len();
    if n == 0 || n != y.len() {
        return Err(Error::Metric(format!(
            "alignment needs the same non-zero number of poses on both sides (got {n} and {})",
            y.len()
        )));
    }
    let nf = n as f64;
    let mean = |v: &[Vector3<f64>]| v.iter().fold(Vector3::zeros(), |a, p| a + p) / nf;
    let (mx, my) = (mean(x), mean(y));
    let sigma_x = x.iter().map(|p| (p - mx).norm_squared()).sum::<f64>() / nf;
    let mut outer = Matrix3::zeros();
    for (a, b) in x.iter().zip(y) {
        outer += (b - my) * (a - mx).transpose();
    }
    let cov = outer * (1.0 / nf);
    let svd = cov.svd(true, true);
    let (u, vt) = match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => (u, vt),
        _ => return Err(degenerate()),
    };
    let d = svd.singular_values;
    if d.iter().filter(|&&s| s > f64::EPSILON).count() < 2 {
        return Err(degenerate());
    }
    let mut s = Vector3::new(1.0, 1.0, 1.0);
    if u.determinant() * vt.determinant() < 0.0 {
        // Flip the axis of the smallest singular value (evo's are sorted, nalgebra's need not be).
        let k = (0..3).min_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap_or(2);
        s[k] = -1.0;
    }
    let rotation = u * Matrix3::from_diagonal(&s) * vt;
    let scale = if with_scale {
        d.component_mul(&s).sum() / sigma_x
    } else {
        1.0
    };
    let translation = my - rotation * mx * scale;
    Ok(Similarity {
        rotation,
        translation,
        scale,
    })
}

fn degenerate() -> Error {
    Error::Metric(
        "degenerate covariance rank, Umeyama alignment is not possible: the associated estimate positions are all equal or on one line; drop -a/-s or use --align_origin".into(),
    )
}

/// 4-DoF alignment: the yaw about z and the translation minimising the squared position error (closed
/// form on the horizontal components). Fails when the horizontal positions are all equal.
pub fn yaw_translation(x: &[Vector3<f64>], y: &[Vector3<f64>]) -> Result<Similarity> {
    let n = x.len();
    if n == 0 || n != y.len() {
        return Err(Error::Metric(format!(
            "alignment needs the same non-zero number of poses on both sides (got {n} and {})",
            y.len()
        )));
    }
    let nf = n as f64;
    let mean = |v: &[Vector3<f64>]| v.iter().fold(Vector3::zeros(), |a, p| a + p) / nf;
    let (mx, my) = (mean(x), mean(y));
    let (mut sin, mut cos, mut spread) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        let (a, b) = (a - mx, b - my);
        cos += a.x * b.x + a.y * b.y;
        sin += a.x * b.y - a.y * b.x;
        spread += a.x * a.x + a.y * a.y;
    }
    if spread <= f64::EPSILON * nf {
        return Err(Error::Metric(
            "degenerate 4-DoF alignment: the associated estimate positions do not move horizontally; drop --align-yaw".into(),
        ));
    }
    let yaw = sin.atan2(cos);
    let rotation = *nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), yaw).matrix();
    Ok(Similarity {
        rotation,
        translation: my - rotation * mx,
        scale: 1.0,
    })
}

/// evo's `--align_origin`: the rigid motion taking the estimate's first pose onto the reference's
/// (identity rotations where a side has no orientation).
pub fn origin(reference: &Poses, estimate: &Poses) -> Result<Similarity> {
    if reference.is_empty() || estimate.is_empty() {
        return Err(Error::Metric("can't align an empty trajectory".into()));
    }
    let (rr, re) = (reference.rotation(0), estimate.rotation(0));
    let rotation = rr * re.transpose();
    Ok(Similarity {
        rotation,
        translation: reference.positions[0] - rotation * estimate.positions[0],
        scale: 1.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn cloud() -> Vec<Vector3<f64>> {
        (0..50)
            .map(|i| {
                let t = i as f64 * 0.37;
                Vector3::new(t.cos() * 3.0, (2.0 * t).sin(), 0.1 * t)
            })
            .collect()
    }

    proptest! {
        #[test]
        fn recovers_a_known_similarity(yaw in -3.0f64..3.0, roll in -1.0f64..1.0, s in 0.5f64..2.0,
                                       tx in -10.0f64..10.0) {
            let r = *nalgebra::Rotation3::from_euler_angles(roll, 0.3, yaw).matrix();
            let t = Vector3::new(tx, -2.0, 0.5);
            let x = cloud();
            let y: Vec<_> = x.iter().map(|p| r * p * s + t).collect();
            let a = umeyama(&x, &y, true).unwrap();
            prop_assert!((a.rotation - r).norm() < 1e-9);
            prop_assert!((a.scale - s).abs() < 1e-9);
            prop_assert!((a.translation - t).norm() < 1e-8);
            let b = yaw_translation(&x, &x.iter().map(|p| {
                nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), yaw) * p + t
            }).collect::<Vec<_>>()).unwrap();
            prop_assert!((b.translation - t).norm() < 1e-8);
        }
    }

    #[test]
    fn all_equal_points_are_degenerate() {
        let x = vec![Vector3::new(1.0, 2.0, 3.0); 10];
        let e = umeyama(&x, &cloud()[..10], false).unwrap_err().to_string();
        assert!(e.contains("degenerate covariance rank"), "{e}");
    }
}
