//! The typed records of a CARMEN log: one per message line.

use raypath_geometry::{Pose2, Scan2};

/// One message of a CARMEN log (comments and blank lines yield no record).
#[derive(Clone, Debug, PartialEq)]
pub enum Record {
    /// A laser scan with its poses (`FLASER`, `RLASER`, `ROBOTLASER1`).
    Laser(LaserMessage),
    /// A wheel-odometry message (`ODOM`).
    Odometry(OdometryMessage),
    /// A parameter (`PARAM name value …`), as text.
    Param {
        /// The parameter's name, for example `laser_front_laser_resolution`.
        name: String,
        /// The parameter's value as written (numbers are not converted).
        value: String,
    },
    /// Any other message (`NEFF`, `TRUEPOS`, `SYNC`, `RAWLASER1`, …), kept as text.
    Other {
        /// The first word of the line, for example `NEFF`.
        tag: String,
        /// The 1-based line number (after decompression).
        line: u64,
        /// The rest of the line after the tag, unparsed.
        text: String,
    },
}

/// Which laser message a scan came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LaserKind {
    /// `FLASER`: the front laser, old format (beam angles not in the line).
    Front,
    /// `RLASER`: the rear laser, old format (beam angles not in the line).
    Rear,
    /// `ROBOTLASER1`: the new format, with start angle, resolution and maximum range in the line.
    RobotLaser1,
}

impl LaserKind {
    /// The tag that starts the line: `FLASER`, `RLASER` or `ROBOTLASER1`.
    pub fn tag(self) -> &'static str {
        match self {
            LaserKind::Front => "FLASER",
            LaserKind::Rear => "RLASER",
            LaserKind::RobotLaser1 => "ROBOTLASER1",
        }
    }
}

/// Translational and rotational velocity of the robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Velocities {
    /// Forward velocity in metres per second.
    pub tv_mps: f64,
    /// Rotational velocity in radians per second (counter-clockwise positive).
    pub rv_radps: f64,
}

/// The extra fields of a `ROBOTLASER1` line, as stated in the line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotLaserInfo {
    /// The laser type code (0 = SICK LMS, 1 = SICK PLS, 2 = Hokuyo URG, …; CARMEN's numbering).
    pub laser_type: i64,
    /// Field of view in radians.
    pub fov_rad: f64,
    /// Maximum range in metres as stated by the line (the reader's no-return threshold may
    /// be lower, see [`crate::carmen::no_return`]).
    pub stated_max_range_m: f64,
    /// Range accuracy in metres.
    pub accuracy_m: f64,
    /// Remission mode (0 = none).
    pub remission_mode: i64,
    /// Forward safety distance in metres.
    pub forward_safety_m: f64,
    /// Side safety distance in metres.
    pub side_safety_m: f64,
    /// Turn axis (CARMEN's `turn_axis` field, metres).
    pub turn_axis: f64,
}

/// A laser scan with the poses and times logged with it.
///
/// Frames follow REP-103 (x forward, y left, angles counter-clockwise). "World" is the frame
/// the log's poses are in: the odometry frame in raw logs, the SLAM-corrected map frame in the
/// `*-corrected` logs.
#[derive(Clone, Debug, PartialEq)]
pub struct LaserMessage {
    /// `FLASER`, `RLASER` or `ROBOTLASER1`.
    pub kind: LaserKind,
    /// Ranges with beam angles (from the line for `ROBOTLASER1`, from the reader's
    /// [`crate::carmen::FanConvention`] for `FLASER`/`RLASER`), the no-return threshold as
    /// `max_range_m`, and remissions as `intensities` when the line has them.
    pub scan: Scan2,
    /// The laser's pose (`x y theta` of FLASER/RLASER, `laser_x laser_y laser_theta` of
    /// ROBOTLASER1).
    pub world_from_laser: Pose2,
    /// The robot's pose logged with the scan: `odom_x odom_y odom_theta` of FLASER/RLASER
    /// (raw odometry in raw logs; a copy of the corrected pose in corrected logs), or
    /// `robot_x robot_y robot_theta` of ROBOTLASER1.
    pub world_from_robot: Pose2,
    /// Velocities (ROBOTLASER1 only).
    pub velocities: Option<Velocities>,
    /// The other stated fields of a ROBOTLASER1 line.
    pub robot_laser: Option<RobotLaserInfo>,
    /// IPC timestamp in seconds (usually UNIX time).
    pub ipc_timestamp_secs: f64,
    /// The host that sent the message.
    pub hostname: String,
    /// Logger timestamp in seconds (usually since the start of logging).
    pub logger_timestamp_secs: f64,
    /// The 1-based line number of the message (after decompression).
    pub line: u64,
}

/// A wheel-odometry message: `ODOM x y theta tv rv accel ipc_timestamp host logger_timestamp`.
#[derive(Clone, Debug, PartialEq)]
pub struct OdometryMessage {
    /// The robot's pose in the odometry frame.
    pub world_from_robot: Pose2,
    /// Velocities.
    pub velocities: Velocities,
    /// Acceleration in metres per second squared.
    pub accel_mps2: f64,
    /// IPC timestamp in seconds.
    pub ipc_timestamp_secs: f64,
    /// The host that sent the message.
    pub hostname: String,
    /// Logger timestamp in seconds.
    pub logger_timestamp_secs: f64,
    /// The 1-based line number of the message.
    pub line: u64,
}
