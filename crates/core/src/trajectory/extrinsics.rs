//! Known extrinsics: moving a trajectory with orientation to another point of the same rigid body.
//!
//! Convention (the one of `--estimate-lever` and `--reference-lever`): a lever `l` is the position of a
//! sensor relative to a common body point, in the body frame (x forward, y left, z up for ROS robots).
//! A trajectory of sensor A (positions `p`, orientations `R` = body to world) becomes the trajectory of
//! sensor B's point by `p' = p − R·(l_A − l_B)`; with `l_B = 0` that is the body point itself. Curvature
//! of a body point ahead of the turning centre leads the one behind by about Δx/v; moving the estimate
//! onto the reference's point before alignment removes that bias.

use nalgebra::Vector3;

use crate::trajectory::Trajectory;

/// Moves `traj` (whose points are at lever `from` in the body frame) to the body point at lever `to`:
/// `p' = p − R·(from − to)`. Returns `None` when `traj` has no orientation (a position-only trajectory
/// cannot be moved) unless `from == to`.
pub fn move_to_body_point(
    traj: &Trajectory,
    from: &Vector3<f64>,
    to: &Vector3<f64>,
) -> Option<Trajectory> {
    let d = from - to;
    if d == Vector3::zeros() {
        return Some(traj.clone());
    }
    let orientations = traj.orientations.as_ref()?;
    let mut out = traj.clone();
    for (p, q) in out.positions.iter_mut().zip(orientations) {
        *p -= q * d;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;
    use proptest::prelude::*;

    proptest! {
        /// Two sensors on one rigid body: moving either onto the other's point gives the other's track.
        #[test]
        fn sensors_on_one_body_meet(
            yaws in prop::collection::vec(-3.1f64..3.1, 1..20),
            la in prop::array::uniform3(-1.0f64..1.0),
            lb in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let (la, lb) = (Vector3::from(la), Vector3::from(lb));
            let mut a = Trajectory::new(true);
            let mut b = Trajectory::new(true);
            for (i, &yaw) in yaws.iter().enumerate() {
                let r = UnitQuaternion::from_euler_angles(0.1 * yaw, -0.05 * yaw, yaw);
                let body = Vector3::new(i as f64, (i as f64).sin(), 0.3);
                a.push(i as i64, body + r * la, Some(r));
                b.push(i as i64, body + r * lb, Some(r));
            }
            let moved = move_to_body_point(&a, &la, &lb).unwrap();
            for (p, q) in moved.positions.iter().zip(&b.positions) {
                prop_assert!((p - q).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn position_only_is_refused_unless_nothing_moves() {
        let mut t = Trajectory::new(false);
        t.push(0, Vector3::zeros(), None);
        let l = Vector3::new(0.2, 0.0, 0.3);
        assert!(move_to_body_point(&t, &l, &Vector3::zeros()).is_none());
        assert!(move_to_body_point(&t, &l, &l).is_some());
    }
}
