//! TF messages as edges of the transform tree, for building frame chains (e.g. map→odom→base_link).
//!
//! `tf2_msgs/TFMessage` (ROS 1 `tf/tfMessage` has the same layout) carries a batch of
//! `geometry_msgs/TransformStamped`; each becomes one [`TfEdge`].

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::ros2_msgs::{TFMessage, TransformStamped};
use super::{cdr, ros1, Encoding};

/// One transform: the pose of `child` in `parent` at `stamp_ns`.
#[derive(Debug, Clone, PartialEq)]
pub struct TfEdge {
    /// `header.frame_id`.
    pub parent: String,
    /// `child_frame_id`.
    pub child: String,
    /// `header.stamp` in nanoseconds.
    pub stamp_ns: i64,
    pub translation: Vector3<f64>,
    /// Identity when the message's quaternion is zero or not finite.
    pub rotation: UnitQuaternion<f64>,
}

impl From<&TransformStamped> for TfEdge {
    fn from(t: &TransformStamped) -> Self {
        let (a, q) = (t.transform.translation, t.transform.rotation);
        let q = Quaternion::new(q.w, q.x, q.y, q.z);
        let n = q.norm();
        TfEdge {
            parent: t.header.frame_id.clone(),
            child: t.child_frame_id.clone(),
            stamp_ns: t.header.stamp.to_ns(),
            translation: Vector3::new(a.x, a.y, a.z),
            rotation: if n.is_finite() && n > 1e-9 {
                UnitQuaternion::from_quaternion(q)
            } else {
                UnitQuaternion::identity()
            },
        }
    }
}

/// Decodes one `tf2_msgs/TFMessage` (or `tf/tfMessage`) into its edges.
pub fn decode_tf_message(encoding: Encoding, data: &[u8]) -> Result<Vec<TfEdge>, String> {
    let m: TFMessage = match encoding {
        Encoding::Cdr => cdr::decode(data)?,
        Encoding::Ros1 => ros1::tf_message(data)?,
    };
    Ok(m.transforms.iter().map(TfEdge::from).collect())
}

/// Decodes one `geometry_msgs/TransformStamped` into its edge.
pub fn decode_transform_stamped(encoding: Encoding, data: &[u8]) -> Result<TfEdge, String> {
    let m: TransformStamped = match encoding {
        Encoding::Cdr => cdr::decode(data)?,
        Encoding::Ros1 => ros1::transform_stamped(data)?,
    };
    Ok(TfEdge::from(&m))
}

/// True for the TF batch types (`tf2_msgs/msg/TFMessage`, `tf2_msgs/TFMessage`, `tf/tfMessage`).
pub fn is_tf_message(schema_name: &str) -> bool {
    matches!(
        schema_name,
        "tf2_msgs/msg/TFMessage" | "tf2_msgs/TFMessage" | "tf/tfMessage"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decode::ros2_msgs::Time;

    #[test]
    fn both_encodings_give_the_same_edges() {
        let mut t = TransformStamped::default();
        t.header.frame_id = "odom".into();
        t.header.stamp = Time::from_ns(1_000_000_123);
        t.child_frame_id = "base_link".into();
        t.transform.translation.x = 2.5;
        let m = TFMessage {
            transforms: vec![t.clone(), t],
        };
        let a = decode_tf_message(Encoding::Cdr, &cdr::encode_le(&m)).unwrap();
        let b = decode_tf_message(Encoding::Ros1, &ros1::encode_tf_message(3, &m)).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.len(), 2);
        assert_eq!(a[0].parent, "odom");
        assert_eq!(a[0].child, "base_link");
        assert_eq!(a[0].stamp_ns, 1_000_000_123);
        assert_eq!(a[0].translation.x, 2.5);
    }
}
