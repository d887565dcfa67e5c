//! Which ROS 2 message types are trajectories, and how one message becomes one sample.
//!
//! Dispatch is by the channel's schema name, once per channel; [`decode_sample`] then runs per message.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::ros2_msgs::{self, NavSatFix};
use super::{cdr, ros1, ros2_prefix};

/// A message type trajdrift reads as a trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MessageKind {
    /// `geometry_msgs/msg/PoseStamped`: position and orientation.
    PoseStamped,
    /// `geometry_msgs/msg/PointStamped`: position only.
    PointStamped,
    /// `nav_msgs/msg/Odometry`: pose (the twist is ignored).
    Odometry,
    /// `sensor_msgs/msg/NavSatFix`: WGS84 latitude, longitude, ellipsoidal altitude.
    NavSatFix,
    /// `geometry_msgs/msg/PoseWithCovarianceStamped`: pose (the covariance is ignored).
    PoseWithCovarianceStamped,
    /// `geometry_msgs/msg/TransformStamped`: the child frame's pose in the parent frame.
    TransformStamped,
}

const SUPPORTED: [&str; 6] = [
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PointStamped",
    "nav_msgs/msg/Odometry",
    "sensor_msgs/msg/NavSatFix",
    "geometry_msgs/msg/PoseWithCovarianceStamped",
    "geometry_msgs/msg/TransformStamped",
];

/// How a message's bytes are serialized (the MCAP channel's `message_encoding`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// ROS 2: CDR with a 4-byte encapsulation header (`cdr`).
    Cdr,
    /// ROS 1: little-endian, unaligned (`ros1`).
    Ros1,
}

impl Encoding {
    /// The encoding named by an MCAP `message_encoding` (`cdr`, `ros1`) or a rosbag2
    /// `serialization_format`.
    pub fn from_name(name: &str) -> Option<Encoding> {
        match name {
            "cdr" => Some(Encoding::Cdr),
            "ros1" => Some(Encoding::Ros1),
            _ => None,
        }
    }

    /// The name as MCAP writes it.
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Cdr => "cdr",
            Encoding::Ros1 => "ros1",
        }
    }
}

/// Schema names of the message types trajdrift reads (ROS 2 spelling).
pub fn supported_types() -> &'static [&'static str] {
    &SUPPORTED
}

/// The kind of a channel from its schema name. Accepts the ROS 2 name (`geometry_msgs/msg/PoseStamped`)
/// and the ROS 1 spelling without `msg/` (`geometry_msgs/PoseStamped`), which some converters write.
pub fn message_kind(schema_name: &str) -> Option<MessageKind> {
    let normalized = schema_name.replacen("/msg/", "/", 1);
    match normalized.as_str() {
        "geometry_msgs/PoseStamped" => Some(MessageKind::PoseStamped),
        "geometry_msgs/PointStamped" => Some(MessageKind::PointStamped),
        "nav_msgs/Odometry" => Some(MessageKind::Odometry),
        "sensor_msgs/NavSatFix" => Some(MessageKind::NavSatFix),
        "geometry_msgs/PoseWithCovarianceStamped" => Some(MessageKind::PoseWithCovarianceStamped),
        "geometry_msgs/TransformStamped" => Some(MessageKind::TransformStamped),
        _ => None,
    }
}

impl MessageKind {
    /// The ROS 2 schema name.
    pub fn type_name(self) -> &'static str {
        match self {
            MessageKind::PoseStamped => SUPPORTED[0],
            MessageKind::PointStamped => SUPPORTED[1],
            MessageKind::Odometry => SUPPORTED[2],
            MessageKind::NavSatFix => SUPPORTED[3],
            MessageKind::PoseWithCovarianceStamped => SUPPORTED[4],
            MessageKind::TransformStamped => SUPPORTED[5],
        }
    }

    /// True when samples carry an orientation.
    pub fn has_orientation(self) -> bool {
        matches!(
            self,
            MessageKind::PoseStamped
                | MessageKind::Odometry
                | MessageKind::PoseWithCovarianceStamped
                | MessageKind::TransformStamped
        )
    }

    /// True for latitude/longitude messages, which need an ENU origin.
    pub fn is_geodetic(self) -> bool {
        self == MessageKind::NavSatFix
    }
}

/// Where a sample is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SamplePosition {
    /// Metres in the message's frame.
    Local(Vector3<f64>),
    /// WGS84 degrees and ellipsoidal metres; `valid` is false for NO_FIX or non-finite values.
    Geodetic {
        lat_deg: f64,
        lon_deg: f64,
        alt_m: f64,
        valid: bool,
    },
}

/// One decoded message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// `header.stamp` in nanoseconds.
    pub stamp_ns: i64,
    pub position: SamplePosition,
    /// Orientation (body to frame) for pose messages; `None` when the message has none or its quaternion
    /// is zero or not finite.
    pub orientation: Option<UnitQuaternion<f64>>,
}

impl Sample {
    /// True when the position can be used (finite, and a fix for geodetic samples).
    pub fn is_valid(&self) -> bool {
        match self.position {
            SamplePosition::Local(p) => p.iter().all(|v| v.is_finite()),
            SamplePosition::Geodetic { valid, .. } => valid,
        }
    }
}

/// Decodes one CDR message of `kind`.
pub fn decode_sample(kind: MessageKind, data: &[u8]) -> Result<Sample, String> {
    decode_message(kind, Encoding::Cdr, data)
}

/// Decodes one message of `kind` serialized with `encoding`.
///
/// One flat match over the kinds, each arm the decoder of its encoding and the fields it keeps;
/// what is more than field picking (a pose's orientation, a fix's validity) has its own function.
pub fn decode_message(
    kind: MessageKind,
    encoding: Encoding,
    data: &[u8],
) -> Result<Sample, String> {
    // CDR: only the leading fields a trajectory needs (see `ros2_prefix`). The ROS 1 reader yields
    // the full structs.
    let cdr = encoding == Encoding::Cdr;
    Ok(match kind {
        MessageKind::PoseWithCovarianceStamped | MessageKind::PoseStamped if cdr => {
            let m = cdr::decode::<ros2_prefix::StampedPose>(data)?;
            pose_sample(m.header.stamp, m.pose)
        }
        MessageKind::PoseWithCovarianceStamped => {
            let m = ros1::pose_with_covariance_stamped(data)?;
            pose_sample(m.header.stamp, m.pose.pose)
        }
        MessageKind::PoseStamped => {
            let m = ros1::pose_stamped(data)?;
            pose_sample(m.header.stamp, m.pose)
        }
        MessageKind::Odometry if cdr => {
            let m = cdr::decode::<ros2_prefix::OdometryPose>(data)?;
            pose_sample(m.header.stamp, m.pose)
        }
        MessageKind::Odometry => {
            let m = ros1::odometry(data)?;
            pose_sample(m.header.stamp, m.pose.pose)
        }
        MessageKind::TransformStamped => {
            let (stamp, t) = if cdr {
                let m = cdr::decode::<ros2_prefix::StampedTransform>(data)?;
                (m.header.stamp, m.transform)
            } else {
                let m = ros1::transform_stamped(data)?;
                (m.header.stamp, m.transform)
            };
            Sample {
                stamp_ns: stamp.to_ns(),
                position: local(t.translation),
                orientation: orientation(t.rotation),
            }
        }
        MessageKind::PointStamped => {
            let (stamp, point) = if cdr {
                let m = cdr::decode::<ros2_prefix::StampedPoint>(data)?;
                (m.header.stamp, m.point)
            } else {
                let m = ros1::point_stamped(data)?;
                (m.header.stamp, m.point)
            };
            Sample {
                stamp_ns: stamp.to_ns(),
                position: local(point),
                orientation: None,
            }
        }
        MessageKind::NavSatFix => fix_sample(if cdr {
            cdr::decode::<NavSatFix>(data)?
        } else {
            ros1::nav_sat_fix(data)?
        }),
    })
}

/// A position in the message's frame.
#[inline]
fn local(p: ros2_msgs::Point) -> SamplePosition {
    SamplePosition::Local(Vector3::new(p.x, p.y, p.z))
}

/// The sample of a stamped pose: every pose-carrying kind ends here, whatever wraps the pose.
#[inline]
fn pose_sample(stamp: ros2_msgs::Time, pose: ros2_msgs::Pose) -> Sample {
    Sample {
        stamp_ns: stamp.to_ns(),
        position: local(pose.position),
        orientation: orientation(pose.orientation),
    }
}

/// The geodetic sample of a fix. Apart from decoding because it decides something: which fixes are
/// usable (a status of at least FIX and finite values), which later steps only read.
#[inline]
fn fix_sample(m: NavSatFix) -> Sample {
    // STATUS_NO_FIX = -1; anything below FIX (0) is not a fix.
    let valid = m.status.status >= 0
        && m.latitude.is_finite()
        && m.longitude.is_finite()
        && m.altitude.is_finite();
    Sample {
        stamp_ns: m.header.stamp.to_ns(),
        position: SamplePosition::Geodetic {
            lat_deg: m.latitude,
            lon_deg: m.longitude,
            alt_m: m.altitude,
            valid,
        },
        orientation: None,
    }
}

/// A unit quaternion from a message's, or `None` for a zero or non-finite one (drivers that do not
/// fill the orientation leave it all zeros).
fn orientation(q: ros2_msgs::Quaternion) -> Option<UnitQuaternion<f64>> {
    let q = Quaternion::new(q.w, q.x, q.y, q.z);
    let norm = q.norm();
    (norm.is_finite() && norm > 1e-9).then(|| UnitQuaternion::from_quaternion(q))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decode::ros2_msgs::*;

    #[test]
    fn kinds_round_trip_names() {
        for name in supported_types() {
            let kind = message_kind(name).unwrap();
            assert_eq!(kind.type_name(), *name);
        }
        assert_eq!(
            message_kind("geometry_msgs/PoseStamped"),
            Some(MessageKind::PoseStamped)
        );
        assert_eq!(message_kind("sensor_msgs/msg/Imu"), None);
    }

    #[test]
    fn decodes_pose_and_fix() {
        let mut m = PoseStamped::default();
        m.header.stamp = Time::from_ns(1_718_460_000_500_000_001);
        m.pose.position = Point {
            x: 1.0,
            y: 2.0,
            z: 3.0,
        };
        let s = decode_sample(MessageKind::PoseStamped, &cdr::encode_le(&m)).unwrap();
        assert_eq!(s.stamp_ns, 1_718_460_000_500_000_001);
        assert_eq!(
            s.position,
            SamplePosition::Local(Vector3::new(1.0, 2.0, 3.0))
        );
        assert_eq!(s.orientation, Some(UnitQuaternion::identity()));
        assert!(s.is_valid());

        let mut f = NavSatFix {
            latitude: 46.78,
            longitude: -71.27,
            altitude: 50.0,
            ..Default::default()
        };
        let s = decode_sample(MessageKind::NavSatFix, &cdr::encode_le(&f)).unwrap();
        assert!(s.is_valid());
        f.status.status = -1;
        let s = decode_sample(MessageKind::NavSatFix, &cdr::encode_le(&f)).unwrap();
        assert!(!s.is_valid());
        f.status.status = 0;
        f.latitude = f64::NAN;
        let s = decode_sample(MessageKind::NavSatFix, &cdr::encode_le(&f)).unwrap();
        assert!(!s.is_valid());
    }

    #[test]
    fn wrong_type_is_an_error_not_a_panic() {
        let m = PointStamped::default();
        assert!(decode_sample(MessageKind::Odometry, &cdr::encode_le(&m)).is_err());
    }
}
