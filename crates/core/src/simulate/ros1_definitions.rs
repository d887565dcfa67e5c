//! ROS 1 message definitions (`gendeps --cat` text: the type's `.msg`, then each nested type after a
//! line of 80 `=` and `MSG: pkg/Type`), written into the simulated bags' connection headers so
//! independent readers (`rosbags`, `mcap-ros1-support`, Foxglove after `--annotate`) can decode them.

const SEP: &str =
    "================================================================================\n";

const HEADER: &str = "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n";
const POINT: &str = "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n";
const QUATERNION: &str =
    "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";
const VECTOR3: &str = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";
const POSE: &str = "MSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation\n";

fn join(main: &str, deps: &[&str]) -> String {
    let mut out = main.to_string();
    for d in deps {
        out.push_str(SEP);
        out.push_str(d);
    }
    out
}

/// The definition of `type_name` (ROS 1 spelling, e.g. `nav_msgs/Odometry`), for the types the
/// simulator writes; empty for others.
pub fn definition(type_name: &str) -> String {
    match type_name {
        "geometry_msgs/PointStamped" => join("Header header\nPoint point\n", &[HEADER, POINT]),
        "nav_msgs/Odometry" => join(
            "Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n",
            &[
                HEADER,
                "MSG: geometry_msgs/PoseWithCovariance\nPose pose\nfloat64[36] covariance\n",
                POSE,
                POINT,
                QUATERNION,
                "MSG: geometry_msgs/TwistWithCovariance\nTwist twist\nfloat64[36] covariance\n",
                "MSG: geometry_msgs/Twist\nVector3 linear\nVector3 angular\n",
                VECTOR3,
            ],
        ),
        "tf2_msgs/TFMessage" => join(
            "geometry_msgs/TransformStamped[] transforms\n",
            &[
                "MSG: geometry_msgs/TransformStamped\nHeader header\nstring child_frame_id\nTransform transform\n",
                HEADER,
                "MSG: geometry_msgs/Transform\nVector3 translation\nQuaternion rotation\n",
                VECTOR3,
                QUATERNION,
            ],
        ),
        "sensor_msgs/PointCloud2" => join(
            "Header header\nuint32 height\nuint32 width\nPointField[] fields\nbool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
            &[
                HEADER,
                "MSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n",
            ],
        ),
        _ => String::new(),
    }
}

/// The MD5 sum ROS 1 computes for `type_name` (what `rosmsg md5` prints), for the types the simulator
/// writes; `*` (any) for others.
pub fn md5sum(type_name: &str) -> &'static str {
    match type_name {
        "geometry_msgs/PointStamped" => "c63aecb41bfdfd6b7e1fac37c7cbe7bf",
        "nav_msgs/Odometry" => "cd5e73d190d741a2f92e81eda573aca7",
        "tf2_msgs/TFMessage" => "94810edda583a504dfda3829e70d7eec",
        "sensor_msgs/PointCloud2" => "1158d486dd51d683ce2f1be655c3c181",
        _ => "*",
    }
}
