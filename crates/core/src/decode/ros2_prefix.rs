//! What a trajectory reads of a ROS 2 message: the stamp and the pose, nothing after them.
//!
//! Plain CDR is positional, so a struct holding a message's leading fields decodes the same bytes as
//! the whole message and stops there: an `Odometry`'s two 36-double covariances and its twist are
//! never decoded or copied, and frame ids are checked as UTF-8 and dropped without an allocation.
//! On a 200 Hz odometry topic those are most of the message ([`crate::decode::ros2_msgs`] keeps the
//! full layouts, for writers and tests).

use serde::de::{Deserializer, Visitor};
use serde::Deserialize;

use super::ros2_msgs::{Point, Pose, Time, Transform};

/// A string read and dropped.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Skipped;

impl<'de> Deserialize<'de> for Skipped {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Skipped, D::Error> {
        struct Drop;
        impl Visitor<'_> for Drop {
            type Value = Skipped;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a string")
            }
            fn visit_str<E: serde::de::Error>(self, _: &str) -> Result<Skipped, E> {
                Ok(Skipped)
            }
            fn visit_string<E: serde::de::Error>(self, _: String) -> Result<Skipped, E> {
                Ok(Skipped)
            }
        }
        d.deserialize_str(Drop)
    }
}

/// `std_msgs/msg/Header` without its frame id.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
pub struct Stamp {
    pub stamp: Time,
    pub frame_id: Skipped,
}

/// `PoseStamped`, and the leading fields of `PoseWithCovarianceStamped` (its covariance follows).
#[derive(Debug, Clone, Copy, Deserialize)]
pub struct StampedPose {
    pub header: Stamp,
    pub pose: Pose,
}

/// The leading fields of `nav_msgs/msg/Odometry` (covariance and twist follow).
#[derive(Debug, Clone, Copy, Deserialize)]
pub struct OdometryPose {
    pub header: Stamp,
    /// Read past, not kept (CDR is positional).
    pub _child_frame_id: Skipped,
    pub pose: Pose,
}

/// `geometry_msgs/msg/PointStamped`.
#[derive(Debug, Clone, Copy, Deserialize)]
pub struct StampedPoint {
    pub header: Stamp,
    pub point: Point,
}

/// `geometry_msgs/msg/TransformStamped`.
#[derive(Debug, Clone, Copy, Deserialize)]
pub struct StampedTransform {
    pub header: Stamp,
    /// Read past, not kept (CDR is positional).
    pub _child_frame_id: Skipped,
    pub transform: Transform,
}
