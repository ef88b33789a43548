//! `ros2msg` schema texts of the types the writer produces: the message definition followed
//! by each dependent type after a line of 80 `=` and a `MSG: pkg/Type` line, as rosbag2
//! stores them.

const SEP: &str =
    "================================================================================\n";

const HEADER: &str = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n";
const TIME: &str = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";
const POSE: &str =
    "MSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n";
const POINT: &str = "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n";
const QUATERNION: &str =
    "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";
const VECTOR3: &str = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";

fn join(main: &str, deps: &[&str]) -> String {
    let mut out = main.to_string();
    for d in deps {
        out.push_str(SEP);
        out.push_str(d);
    }
    out
}

/// The schema text of `type_name` (one of the types the writer produces).
pub fn definition(type_name: &str) -> Option<String> {
    Some(match type_name {
        super::select::LASER_SCAN => join(
            "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n\
             float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\n\
             float32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n",
            &[HEADER, TIME],
        ),
        super::select::POINT_CLOUD2 => join(
            "std_msgs/Header header\nuint32 height\nuint32 width\n\
             sensor_msgs/PointField[] fields\nbool is_bigendian\nuint32 point_step\n\
             uint32 row_step\nuint8[] data\nbool is_dense\n",
            &[
                HEADER,
                TIME,
                "MSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\n\
                 uint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\n\
                 uint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n",
            ],
        ),
        super::select::ODOMETRY => join(
            "std_msgs/Header header\nstring child_frame_id\n\
             geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n",
            &[
                HEADER,
                TIME,
                "MSG: geometry_msgs/PoseWithCovariance\ngeometry_msgs/Pose pose\n\
                 float64[36] covariance\n",
                POSE,
                POINT,
                QUATERNION,
                "MSG: geometry_msgs/TwistWithCovariance\ngeometry_msgs/Twist twist\n\
                 float64[36] covariance\n",
                "MSG: geometry_msgs/Twist\ngeometry_msgs/Vector3 linear\n\
                 geometry_msgs/Vector3 angular\n",
                VECTOR3,
            ],
        ),
        super::select::TF_MESSAGE => join(
            "geometry_msgs/TransformStamped[] transforms\n",
            &[
                "MSG: geometry_msgs/TransformStamped\nstd_msgs/Header header\n\
                 string child_frame_id\ngeometry_msgs/Transform transform\n",
                HEADER,
                TIME,
                "MSG: geometry_msgs/Transform\ngeometry_msgs/Vector3 translation\n\
                 geometry_msgs/Quaternion rotation\n",
                VECTOR3,
                QUATERNION,
            ],
        ),
        super::select::POSE_STAMPED => join(
            "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
            &[HEADER, TIME, POSE, POINT, QUATERNION],
        ),
        _ => return None,
    })
}
