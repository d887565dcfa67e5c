//! ROS 2 message definitions in the MCAP `ros2msg` schema encoding, for writing MCAP files.
//!
//! A `ros2msg` schema is the type's `.msg` text, then for every nested type a line of 80 `=`, a line
//! `MSG: pkg/Type` and that type's `.msg` text (comments stripped), as `rosbag2` and `mcap-ros2-support`
//! write them. Readers (Foxglove, `ros2 bag`, `mcap` tools) parse these to decode our messages.

/// `geometry_msgs/msg/PoseStamped` as a `ros2msg` schema.
pub const POSE_STAMPED: &str = r#"std_msgs/Header header
geometry_msgs/Pose pose
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Pose
geometry_msgs/Point position
geometry_msgs/Quaternion orientation
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
"#;

/// `geometry_msgs/msg/PointStamped` as a `ros2msg` schema.
pub const POINT_STAMPED: &str = r#"std_msgs/Header header
geometry_msgs/Point point
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
"#;

/// `nav_msgs/msg/Odometry` as a `ros2msg` schema.
pub const ODOMETRY: &str = r#"std_msgs/Header header
string child_frame_id
geometry_msgs/PoseWithCovariance pose
geometry_msgs/TwistWithCovariance twist
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/PoseWithCovariance
geometry_msgs/Pose pose
float64[36] covariance
================================================================================
MSG: geometry_msgs/Pose
geometry_msgs/Point position
geometry_msgs/Quaternion orientation
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
================================================================================
MSG: geometry_msgs/TwistWithCovariance
geometry_msgs/Twist twist
float64[36] covariance
================================================================================
MSG: geometry_msgs/Twist
geometry_msgs/Vector3 linear
geometry_msgs/Vector3 angular
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"#;

/// `sensor_msgs/msg/NavSatFix` as a `ros2msg` schema.
pub const NAV_SAT_FIX: &str = r#"uint8 COVARIANCE_TYPE_UNKNOWN=0
uint8 COVARIANCE_TYPE_APPROXIMATED=1
uint8 COVARIANCE_TYPE_DIAGONAL_KNOWN=2
uint8 COVARIANCE_TYPE_KNOWN=3
std_msgs/Header header
sensor_msgs/NavSatStatus status
float64 latitude
float64 longitude
float64 altitude
float64[9] position_covariance
uint8 position_covariance_type
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: sensor_msgs/NavSatStatus
int8 STATUS_NO_FIX=-1
int8 STATUS_FIX=0
int8 STATUS_SBAS_FIX=1
int8 STATUS_GBAS_FIX=2
uint16 SERVICE_GPS=1
uint16 SERVICE_GLONASS=2
uint16 SERVICE_COMPASS=4
uint16 SERVICE_GALILEO=8
int8 status
uint16 service
"#;

/// `geometry_msgs/msg/PoseWithCovarianceStamped` as a `ros2msg` schema.
pub const POSE_WITH_COVARIANCE_STAMPED: &str = r#"std_msgs/Header header
geometry_msgs/PoseWithCovariance pose
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/PoseWithCovariance
geometry_msgs/Pose pose
float64[36] covariance
================================================================================
MSG: geometry_msgs/Pose
geometry_msgs/Point position
geometry_msgs/Quaternion orientation
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
"#;

/// `geometry_msgs/msg/TransformStamped` as a `ros2msg` schema.
pub const TRANSFORM_STAMPED: &str = r#"std_msgs/Header header
string child_frame_id
geometry_msgs/Transform transform
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Transform
geometry_msgs/Vector3 translation
geometry_msgs/Quaternion rotation
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
"#;

/// The `ros2msg` schema text of `type_name` (e.g. `geometry_msgs/msg/PoseStamped`), for the types
/// trajdrift reads and writes.
pub fn schema_text(type_name: &str) -> Option<&'static str> {
    match type_name {
        "geometry_msgs/msg/PoseStamped" => Some(POSE_STAMPED),
        "geometry_msgs/msg/PointStamped" => Some(POINT_STAMPED),
        "nav_msgs/msg/Odometry" => Some(ODOMETRY),
        "sensor_msgs/msg/NavSatFix" => Some(NAV_SAT_FIX),
        "geometry_msgs/msg/PoseWithCovarianceStamped" => Some(POSE_WITH_COVARIANCE_STAMPED),
        "geometry_msgs/msg/TransformStamped" => Some(TRANSFORM_STAMPED),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_supported_type_has_a_schema() {
        for t in crate::decode::supported_types() {
            let text = schema_text(t).unwrap();
            assert!(text.ends_with('\n'));
            assert!(text.contains("std_msgs/Header header"));
        }
        assert!(schema_text("sensor_msgs/msg/Imu").is_none());
    }
}
