//! ROS 1 serialization of the message types trajdrift reads, into the same structs as ROS 2.
//!
//! ROS 1 messages are little-endian with no alignment and no encapsulation header; a string is a
//! `uint32` length then its bytes (no NUL); `time` is `uint32 secs, uint32 nsecs`; `std_msgs/Header`
//! starts with `uint32 seq`. Hand-written because no maintained ROS 1 serde crate exists
//! (`serde_rosmsg` has seen no release since 2019) and the layouts we need are a handful of fixed
//! structs: a bounds-checked cursor is shorter than a serde `Deserializer` and cannot panic. Decoding
//! yields the [`crate::decode::ros2_msgs`] structs so the rest of the crate sees one representation.

use super::ros2_msgs::{
    Header, NavSatFix, NavSatStatus, Odometry, Point, PointStamped, Pose, PoseStamped,
    PoseWithCovariance, PoseWithCovarianceStamped, Quaternion, TFMessage, Time, Transform,
    TransformStamped, Twist, TwistWithCovariance,
};

/// A bounds-checked little-endian cursor over one message.
pub struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    /// A cursor at the start of `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Reader { data, pos: 0 }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(format!(
                "message ends at byte {} but {} more bytes were expected at byte {}",
                self.data.len(),
                n,
                self.pos
            ));
        };
        let s = &self.data[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    /// `uint8`.
    pub fn u8(&mut self) -> Result<u8, String> {
        Ok(self.array::<1>()?[0])
    }
    /// `uint16`.
    pub fn u16(&mut self) -> Result<u16, String> {
        Ok(u16::from_le_bytes(self.array()?))
    }
    /// `uint32`.
    pub fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    /// `float64`.
    pub fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.array()?))
    }
    /// `string` (invalid UTF-8 is replaced, not an error: frame ids are only labels).
    pub fn string(&mut self) -> Result<String, String> {
        let n = self.u32()? as usize;
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }
    /// `time`, as ROS 2's `builtin_interfaces/Time` (same nanoseconds until 2038).
    pub fn time(&mut self) -> Result<Time, String> {
        let secs = self.u32()?;
        let nsecs = self.u32()?;
        Ok(Time::from_ns(secs as i64 * 1_000_000_000 + nsecs as i64))
    }
    /// `std_msgs/Header` (the `seq` is dropped).
    pub fn header(&mut self) -> Result<Header, String> {
        let _seq = self.u32()?;
        Ok(Header {
            stamp: self.time()?,
            frame_id: self.string()?,
        })
    }
    /// `geometry_msgs/Point` or `Vector3`.
    pub fn point(&mut self) -> Result<Point, String> {
        Ok(Point {
            x: self.f64()?,
            y: self.f64()?,
            z: self.f64()?,
        })
    }
    /// `geometry_msgs/Quaternion`.
    pub fn quaternion(&mut self) -> Result<Quaternion, String> {
        Ok(Quaternion {
            x: self.f64()?,
            y: self.f64()?,
            z: self.f64()?,
            w: self.f64()?,
        })
    }
    /// `geometry_msgs/Pose`.
    pub fn pose(&mut self) -> Result<Pose, String> {
        Ok(Pose {
            position: self.point()?,
            orientation: self.quaternion()?,
        })
    }
    fn covariance(&mut self) -> Result<[[f64; 6]; 6], String> {
        let mut c = [[0.0; 6]; 6];
        for row in &mut c {
            for v in row.iter_mut() {
                *v = self.f64()?;
            }
        }
        Ok(c)
    }
    /// `geometry_msgs/PoseWithCovariance`.
    pub fn pose_with_covariance(&mut self) -> Result<PoseWithCovariance, String> {
        Ok(PoseWithCovariance {
            pose: self.pose()?,
            covariance: self.covariance()?,
        })
    }
    /// `geometry_msgs/TransformStamped`.
    pub fn transform_stamped(&mut self) -> Result<TransformStamped, String> {
        Ok(TransformStamped {
            header: self.header()?,
            child_frame_id: self.string()?,
            transform: Transform {
                translation: self.point()?,
                rotation: self.quaternion()?,
            },
        })
    }
}

/// `geometry_msgs/PoseStamped`.
pub fn pose_stamped(data: &[u8]) -> Result<PoseStamped, String> {
    let mut r = Reader::new(data);
    Ok(PoseStamped {
        header: r.header()?,
        pose: r.pose()?,
    })
}

/// `geometry_msgs/PointStamped`.
pub fn point_stamped(data: &[u8]) -> Result<PointStamped, String> {
    let mut r = Reader::new(data);
    Ok(PointStamped {
        header: r.header()?,
        point: r.point()?,
    })
}

/// `geometry_msgs/PoseWithCovarianceStamped`.
pub fn pose_with_covariance_stamped(data: &[u8]) -> Result<PoseWithCovarianceStamped, String> {
    let mut r = Reader::new(data);
    Ok(PoseWithCovarianceStamped {
        header: r.header()?,
        pose: r.pose_with_covariance()?,
    })
}

/// `nav_msgs/Odometry` (the twist is read too, so a short message is an error).
pub fn odometry(data: &[u8]) -> Result<Odometry, String> {
    let mut r = Reader::new(data);
    Ok(Odometry {
        header: r.header()?,
        child_frame_id: r.string()?,
        pose: r.pose_with_covariance()?,
        twist: TwistWithCovariance {
            twist: Twist {
                linear: r.point()?,
                angular: r.point()?,
            },
            covariance: r.covariance()?,
        },
    })
}

/// `sensor_msgs/NavSatFix`.
pub fn nav_sat_fix(data: &[u8]) -> Result<NavSatFix, String> {
    let mut r = Reader::new(data);
    let header = r.header()?;
    let status = NavSatStatus {
        status: r.u8()? as i8,
        service: r.u16()?,
    };
    let (latitude, longitude, altitude) = (r.f64()?, r.f64()?, r.f64()?);
    let mut position_covariance = [0.0; 9];
    for v in &mut position_covariance {
        *v = r.f64()?;
    }
    Ok(NavSatFix {
        header,
        status,
        latitude,
        longitude,
        altitude,
        position_covariance,
        position_covariance_type: r.u8()?,
    })
}

/// `geometry_msgs/TransformStamped`.
pub fn transform_stamped(data: &[u8]) -> Result<TransformStamped, String> {
    Reader::new(data).transform_stamped()
}

/// `tf2_msgs/TFMessage` (and the identical `tf/tfMessage`).
pub fn tf_message(data: &[u8]) -> Result<TFMessage, String> {
    let mut r = Reader::new(data);
    let n = r.u32()? as usize;
    // Each transform is at least 72 bytes: a corrupt count cannot allocate more than the message.
    let mut transforms = Vec::with_capacity(n.min(data.len() / 72));
    for _ in 0..n {
        transforms.push(r.transform_stamped()?);
    }
    Ok(TFMessage { transforms })
}

/// A little-endian ROS 1 writer for the types above (tests, benchmarks and the bag writer).
#[derive(Debug, Default)]
pub struct Writer {
    /// The bytes written so far.
    pub out: Vec<u8>,
}

impl Writer {
    /// `uint32`.
    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.out.extend_from_slice(&v.to_le_bytes());
        self
    }
    /// `float64`s.
    pub fn f64s(&mut self, v: &[f64]) -> &mut Self {
        for x in v {
            self.out.extend_from_slice(&x.to_le_bytes());
        }
        self
    }
    /// `string`.
    pub fn string(&mut self, s: &str) -> &mut Self {
        self.u32(s.len() as u32);
        self.out.extend_from_slice(s.as_bytes());
        self
    }
    /// `std_msgs/Header` with `seq`.
    pub fn header(&mut self, seq: u32, h: &Header) -> &mut Self {
        let ns = h.stamp.to_ns();
        self.u32(seq)
            .u32(ns.div_euclid(1_000_000_000) as u32)
            .u32(ns.rem_euclid(1_000_000_000) as u32)
            .string(&h.frame_id)
    }
    /// `geometry_msgs/Pose`.
    pub fn pose(&mut self, p: &Pose) -> &mut Self {
        let (a, q) = (p.position, p.orientation);
        self.f64s(&[a.x, a.y, a.z, q.x, q.y, q.z, q.w])
    }
}

/// Encodes a `geometry_msgs/PointStamped`.
pub fn encode_point_stamped(seq: u32, m: &PointStamped) -> Vec<u8> {
    let mut w = Writer::default();
    w.header(seq, &m.header)
        .f64s(&[m.point.x, m.point.y, m.point.z]);
    w.out
}

/// Encodes a `geometry_msgs/PoseStamped`.
pub fn encode_pose_stamped(seq: u32, m: &PoseStamped) -> Vec<u8> {
    let mut w = Writer::default();
    w.header(seq, &m.header).pose(&m.pose);
    w.out
}

/// Encodes a `nav_msgs/Odometry`.
pub fn encode_odometry(seq: u32, m: &Odometry) -> Vec<u8> {
    let mut w = Writer::default();
    w.header(seq, &m.header)
        .string(&m.child_frame_id)
        .pose(&m.pose.pose)
        .f64s(m.pose.covariance.as_flattened());
    let t = m.twist.twist;
    w.f64s(&[
        t.linear.x,
        t.linear.y,
        t.linear.z,
        t.angular.x,
        t.angular.y,
        t.angular.z,
    ])
    .f64s(m.twist.covariance.as_flattened());
    w.out
}

/// Encodes a `tf2_msgs/TFMessage`.
pub fn encode_tf_message(seq: u32, m: &TFMessage) -> Vec<u8> {
    let mut w = Writer::default();
    w.u32(m.transforms.len() as u32);
    for t in &m.transforms {
        let (a, q) = (t.transform.translation, t.transform.rotation);
        w.header(seq, &t.header)
            .string(&t.child_frame_id)
            .f64s(&[a.x, a.y, a.z, q.x, q.y, q.z, q.w]);
    }
    w.out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_rejects_short_input() {
        let mut m = Odometry::default();
        m.header.stamp = Time::from_ns(1_718_460_000_123_456_789);
        m.header.frame_id = "odom".into();
        m.child_frame_id = "base_link".into();
        m.pose.pose.position = Point {
            x: 1.0,
            y: -2.0,
            z: 0.5,
        };
        let bytes = encode_odometry(7, &m);
        assert_eq!(
            bytes.len(),
            4 + 8 + 8 + 13 + 7 * 8 + 36 * 8 + 6 * 8 + 36 * 8
        );
        assert_eq!(odometry(&bytes).unwrap(), m);
        for cut in 0..bytes.len() {
            assert!(odometry(&bytes[..cut]).is_err(), "cut {cut}");
        }
        let tf = TFMessage {
            transforms: vec![TransformStamped::default(); 3],
        };
        assert_eq!(tf_message(&encode_tf_message(0, &tf)).unwrap(), tf);
        let mut bad = encode_tf_message(0, &tf);
        bad[..4].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(tf_message(&bad).is_err());
    }
}
