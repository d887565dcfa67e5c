//! evo's pose relations: which part of the error pose `E` becomes the per-pair number.

use nalgebra::{Matrix3, Vector3};

use super::poses::rotation_angle;
use crate::error::{Error, Result};

/// `-r/--pose_relation`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PoseRelation {
    /// |t(E)|, metres.
    #[default]
    TransPart,
    /// ‖R(E) − I‖_F.
    RotPart,
    /// ‖E − I₄‖_F.
    Full,
    /// Angle of R(E), degrees.
    AngleDeg,
    /// Angle of R(E), radians.
    AngleRad,
    /// APE: distance between positions; RPE: difference of the pair distances, metres.
    PointDistance,
    /// RPE only: point distance error over the reference pair distance, percent.
    PointDistanceErrorRatio,
}

impl PoseRelation {
    /// evo's name.
    pub fn as_str(self) -> &'static str {
        match self {
            PoseRelation::TransPart => "trans_part",
            PoseRelation::RotPart => "rot_part",
            PoseRelation::Full => "full",
            PoseRelation::AngleDeg => "angle_deg",
            PoseRelation::AngleRad => "angle_rad",
            PoseRelation::PointDistance => "point_distance",
            PoseRelation::PointDistanceErrorRatio => "point_distance_error_ratio",
        }
    }

    /// Parses evo's name.
    pub fn parse(s: &str) -> Result<Self> {
        Ok(match s {
            "trans_part" => PoseRelation::TransPart,
            "rot_part" => PoseRelation::RotPart,
            "full" => PoseRelation::Full,
            "angle_deg" => PoseRelation::AngleDeg,
            "angle_rad" => PoseRelation::AngleRad,
            "point_distance" => PoseRelation::PointDistance,
            "point_distance_error_ratio" => PoseRelation::PointDistanceErrorRatio,
            _ => return Err(Error::InvalidArgument(format!(
                "-r {s}: expected trans_part, rot_part, full, angle_deg, angle_rad, point_distance or point_distance_error_ratio"
            ))),
        })
    }

    /// True when the relation reads the rotation of the error pose.
    pub fn needs_orientation(self) -> bool {
        matches!(
            self,
            PoseRelation::RotPart
                | PoseRelation::Full
                | PoseRelation::AngleDeg
                | PoseRelation::AngleRad
        )
    }

    /// The unit evo prints.
    pub fn unit(self) -> &'static str {
        match self {
            PoseRelation::TransPart | PoseRelation::PointDistance => "m",
            PoseRelation::AngleDeg => "deg",
            PoseRelation::AngleRad => "rad",
            PoseRelation::PointDistanceErrorRatio => "%",
            PoseRelation::RotPart | PoseRelation::Full => "",
        }
    }

    /// The number of one error pose `E = (R, t)` for the pose relations that read `E`.
    pub fn of_error_pose(self, r: &Matrix3<f64>, t: &Vector3<f64>) -> f64 {
        match self {
            PoseRelation::RotPart => (r - Matrix3::identity()).norm(),
            PoseRelation::Full => {
                ((r - Matrix3::identity()).norm_squared() + t.norm_squared()).sqrt()
            }
            PoseRelation::AngleDeg => rotation_angle(r).to_degrees(),
            PoseRelation::AngleRad => rotation_angle(r),
            _ => t.norm(),
        }
    }
}
