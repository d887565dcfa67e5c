//! Composing a chain of TF edges into one trajectory: the pose of the chain's last frame in its first,
//! sampled over time.
//!
//! A chain is a list of links, each a TF edge taken forward (parent → child) or inverted (walking up
//! the tree). Dynamic edges (from `/tf`) are time series, interpolated between their two neighbouring
//! samples (linear in position, slerp in rotation, the shorter way round); static edges (from
//! `/tf_static`) are constant. Choices where ROS's `tf2` lookups would differ or nothing dictated one:
//!
//! - The chain is sampled at the stamps of its fastest dynamic edge (the one with the most samples;
//!   the first on the chain when two tie), so that edge is never interpolated and a one-edge chain
//!   reproduces its messages exactly (positions and quaternions bit-identical).
//! - No extrapolation: a stamp outside another dynamic edge's first..last stamp is dropped and counted
//!   ([`Composed::outside_span`]).
//! - A chain of static edges only has no trajectory: [`compose`] returns `None` and the caller says so
//!   (a single sample would be no trajectory either).

use nalgebra::{Isometry3, Translation3, UnitQuaternion};

use crate::trajectory::Trajectory;

/// The values of one TF edge: the child's pose in the parent.
#[derive(Debug, Clone, Copy)]
pub enum EdgeSeries<'a> {
    /// A `/tf_static` edge: the same at every time.
    Static(Isometry3<f64>),
    /// A `/tf` edge: `poses[i]` at `stamps_ns[i]`, stamps strictly increasing.
    Dynamic {
        stamps_ns: &'a [i64],
        poses: &'a [Isometry3<f64>],
    },
}

/// One step of a chain.
#[derive(Debug, Clone, Copy)]
pub struct Link<'a> {
    pub series: EdgeSeries<'a>,
    /// True when the chain walks the edge from child to parent (the edge's inverse is used).
    pub inverse: bool,
}

/// A composed chain.
#[derive(Debug, Clone)]
pub struct Composed {
    /// The last frame's pose in the first frame, with orientations.
    pub trajectory: Trajectory,
    /// Stamps of the sampling edge dropped because another dynamic edge had no sample before or after.
    pub outside_span: u64,
}

/// The pose of a dynamic edge at `t_ns`: the sample itself when a stamp matches, else interpolated
/// between the two neighbours; `None` outside the first..last stamp (no extrapolation).
pub fn interpolate(
    stamps_ns: &[i64],
    poses: &[Isometry3<f64>],
    t_ns: i64,
) -> Option<Isometry3<f64>> {
    let i = stamps_ns.partition_point(|&s| s < t_ns);
    if i < stamps_ns.len() && stamps_ns[i] == t_ns {
        return Some(poses[i]);
    }
    if i == 0 || i >= stamps_ns.len() {
        return None;
    }
    let (s0, s1) = (stamps_ns[i - 1], stamps_ns[i]);
    let f = (t_ns - s0) as f64 / (s1 - s0) as f64;
    let (a, b) = (&poses[i - 1], &poses[i]);
    let translation = a.translation.vector + (b.translation.vector - a.translation.vector) * f;
    // `try_slerp` takes the shorter arc; it only gives up for quaternions 180° apart on the 4-sphere,
    // which the shorter-arc flip rules out, so the fallback (the nearer sample) is for safety only.
    // The result is renormalized: for nearby rotations nalgebra's sin(fθ)/sin θ weights share a
    // rounding error of sin θ (from √(1−cos²θ)) that leaves the quaternion off unit length by up to
    // ~1e-12, which would scale every position the rotation touches.
    let rotation = a
        .rotation
        .try_slerp(&b.rotation, f, f64::EPSILON)
        .map(|q| UnitQuaternion::new_normalize(q.into_inner()))
        .unwrap_or(if f < 0.5 { a.rotation } else { b.rotation });
    Some(Isometry3::from_parts(
        Translation3::from(translation),
        rotation,
    ))
}

fn pose_at(link: &Link<'_>, t_ns: i64) -> Option<Isometry3<f64>> {
    let pose = match link.series {
        EdgeSeries::Static(p) => p,
        EdgeSeries::Dynamic { stamps_ns, poses } => interpolate(stamps_ns, poses, t_ns)?,
    };
    Some(if link.inverse { pose.inverse() } else { pose })
}

/// Composes `links` (first frame → last frame) at the stamps of the fastest dynamic link. `None` when
/// no link is dynamic or the chain is empty.
pub fn compose(links: &[Link<'_>]) -> Option<Composed> {
    let stamps = links
        .iter()
        .filter_map(|l| match l.series {
            EdgeSeries::Dynamic { stamps_ns, .. } => Some(stamps_ns),
            EdgeSeries::Static(_) => None,
        })
        // `max_by_key` keeps the last maximum; reversing first keeps the first on the chain.
        .rev()
        .max_by_key(|s| s.len())?;
    let mut trajectory = Trajectory::new(true);
    let mut outside_span = 0;
    'stamps: for &t in stamps {
        // Folding from the first link (not from the identity) keeps a one-link chain exact.
        let mut pose: Option<Isometry3<f64>> = None;
        for link in links {
            let Some(p) = pose_at(link, t) else {
                outside_span += 1;
                continue 'stamps;
            };
            pose = Some(match pose {
                None => p,
                Some(acc) => acc * p,
            });
        }
        if let Some(p) = pose {
            trajectory.push(t, p.translation.vector, Some(p.rotation));
        }
    }
    Some(Composed {
        trajectory,
        outside_span,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use std::f64::consts::FRAC_PI_2;

    fn iso(x: f64, y: f64, z: f64, yaw: f64) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        )
    }

    #[test]
    fn halfway_is_the_midpoint_and_half_the_turn() {
        let stamps = [0, 1_000_000_000];
        let poses = [iso(0.0, 0.0, 0.0, 0.0), iso(2.0, -4.0, 1.0, FRAC_PI_2)];
        let mid = interpolate(&stamps, &poses, 500_000_000).unwrap();
        assert!((mid.translation.vector - Vector3::new(1.0, -2.0, 0.5)).norm() < 1e-15);
        let yaw = mid.rotation.euler_angles().2;
        assert!((yaw - FRAC_PI_2 / 2.0).abs() < 1e-15, "{yaw}");
        // Exact stamps give the samples themselves; outside the span gives nothing.
        assert_eq!(interpolate(&stamps, &poses, 1_000_000_000), Some(poses[1]));
        assert_eq!(interpolate(&stamps, &poses, -1), None);
        assert_eq!(interpolate(&stamps, &poses, 1_000_000_001), None);
    }

    #[test]
    fn slerp_takes_the_shorter_way_round() {
        // 170° and −170° of yaw are 20° apart: halfway is 180°, not 0°.
        let a = iso(0.0, 0.0, 0.0, 170f64.to_radians());
        let b = iso(0.0, 0.0, 0.0, -170f64.to_radians());
        let mid = interpolate(&[0, 2], &[a, b], 1).unwrap();
        assert!(
            mid.rotation.angle_to(&UnitQuaternion::from_euler_angles(
                0.0,
                0.0,
                std::f64::consts::PI
            )) < 1e-12
        );
    }

    #[test]
    fn map_odom_base_link_composes() {
        // map→odom: odom 10 m east of map, turned 90° left. odom→base_link: 1 m ahead along odom's x.
        // base_link in map: (10, 1), facing north (yaw 90°).
        let map_odom = iso(10.0, 0.0, 0.0, FRAC_PI_2);
        let stamps = [0, 10, 20];
        let odom_base = [
            iso(0.0, 0.0, 0.0, 0.0),
            iso(1.0, 0.0, 0.0, 0.0),
            iso(2.0, 0.0, 0.0, 0.0),
        ];
        let links = [
            Link {
                series: EdgeSeries::Static(map_odom),
                inverse: false,
            },
            Link {
                series: EdgeSeries::Dynamic {
                    stamps_ns: &stamps,
                    poses: &odom_base,
                },
                inverse: false,
            },
        ];
        let c = compose(&links).unwrap();
        assert_eq!(c.trajectory.stamps_ns, vec![0, 10, 20]);
        assert!((c.trajectory.positions[1] - Vector3::new(10.0, 1.0, 0.0)).norm() < 1e-12);
        let yaw = c.trajectory.orientations.as_ref().unwrap()[1]
            .euler_angles()
            .2;
        assert!((yaw - FRAC_PI_2).abs() < 1e-12);
        // Walking the same chain backwards (base_link → map) gives the inverse.
        let back = [
            Link {
                inverse: true,
                ..links[1]
            },
            Link {
                inverse: true,
                ..links[0]
            },
        ];
        let b = compose(&back).unwrap();
        let p = Isometry3::from_parts(
            Translation3::from(c.trajectory.positions[2]),
            c.trajectory.orientations.as_ref().unwrap()[2],
        );
        let q = Isometry3::from_parts(
            Translation3::from(b.trajectory.positions[2]),
            b.trajectory.orientations.as_ref().unwrap()[2],
        );
        assert!(((p * q).translation.vector).norm() < 1e-12);
    }

    #[test]
    fn fastest_edge_sets_the_stamps_and_others_are_not_extrapolated() {
        let slow_stamps = [5, 15];
        let slow = [iso(0.0, 0.0, 0.0, 0.0), iso(1.0, 0.0, 0.0, 0.0)];
        let fast_stamps = [0, 5, 10, 15, 20];
        let fast = [iso(0.0, 0.0, 0.0, 0.0); 5];
        let links = [
            Link {
                series: EdgeSeries::Dynamic {
                    stamps_ns: &slow_stamps,
                    poses: &slow,
                },
                inverse: false,
            },
            Link {
                series: EdgeSeries::Dynamic {
                    stamps_ns: &fast_stamps,
                    poses: &fast,
                },
                inverse: false,
            },
        ];
        let c = compose(&links).unwrap();
        assert_eq!(c.trajectory.stamps_ns, vec![5, 10, 15]);
        assert_eq!(c.outside_span, 2);
        assert!((c.trajectory.positions[1].x - 0.5).abs() < 1e-15);
        // Static only: no trajectory.
        let statics = [Link {
            series: EdgeSeries::Static(slow[0]),
            inverse: false,
        }];
        assert!(compose(&statics).is_none());
    }
}
