//! ROS 2 message types read and written here (CDR): `std_msgs/msg/Header`,
//! `sensor_msgs/msg/LaserScan`, `nav_msgs/msg/Odometry`, `tf2_msgs/msg/TFMessage`,
//! `geometry_msgs/msg/PoseStamped`. `sensor_msgs/msg/PointCloud2` is in [`super::cloud`].

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use raypath_geometry::{Pose3, Scan2};

use super::cdr::{CdrError, CdrReader, CdrResult, CdrWriter};

/// `builtin_interfaces/msg/Time`: seconds and nanoseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Stamp {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, `0..1e9`.
    pub nanosec: u32,
}

impl Stamp {
    /// The time in seconds.
    pub fn secs(self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }

    /// The time in nanoseconds.
    pub fn nanos(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// The stamp nearest to `secs` (to the nanosecond); `None` when it does not fit
    /// (`int32` seconds) or is not finite.
    pub fn from_secs(secs: f64) -> Option<Self> {
        if !secs.is_finite() {
            return None;
        }
        let mut sec = secs.floor();
        let mut nanosec = ((secs - sec) * 1e9).round();
        if nanosec >= 1e9 {
            sec += 1.0;
            nanosec = 0.0;
        }
        if sec < f64::from(i32::MIN) || sec > f64::from(i32::MAX) {
            return None;
        }
        Some(Self {
            sec: sec as i32,
            nanosec: nanosec as u32,
        })
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header<'a> {
    /// Time of the data.
    pub stamp: Stamp,
    /// Frame of the data (without a leading `/`, as tf2 names frames).
    pub frame_id: &'a str,
}

/// Strips the leading `/` that ROS 1 era frame names carry.
pub fn frame_name(name: &str) -> &str {
    name.strip_prefix('/').unwrap_or(name)
}

/// Reads a `Header`.
pub fn read_header<'a>(r: &mut CdrReader<'a>) -> CdrResult<Header<'a>> {
    let sec = r.i32()?;
    let at = r.offset();
    let nanosec = r.u32()?;
    if nanosec >= 1_000_000_000 {
        return Err(CdrError {
            offset: at,
            reason: format!("header stamp nanoseconds {nanosec} ≥ 1e9"),
        });
    }
    let frame_id = frame_name(r.string()?);
    Ok(Header {
        stamp: Stamp { sec, nanosec },
        frame_id,
    })
}

/// Writes a `Header`.
pub fn write_header(w: &mut CdrWriter, stamp: Stamp, frame_id: &str) {
    w.i32(stamp.sec);
    w.u32(stamp.nanosec);
    w.string(frame_id);
}

/// Reads a `geometry_msgs/msg/Pose` (or a `Transform`: translation then rotation).
pub fn read_pose(r: &mut CdrReader<'_>) -> CdrResult<Pose3> {
    let at = r.offset();
    let t = Vector3::new(r.f64()?, r.f64()?, r.f64()?);
    let (x, y, z, w) = (r.f64()?, r.f64()?, r.f64()?, r.f64()?);
    let q = Quaternion::new(w, x, y, z);
    let norm = q.norm();
    if !(t.iter().all(|v| v.is_finite()) && norm.is_finite() && norm > 1e-6) {
        return Err(CdrError {
            offset: at,
            reason: format!(
                "pose is not finite or its quaternion is not a rotation: position ({}, {}, {}), \
                 quaternion (x {x}, y {y}, z {z}, w {w})",
                t.x, t.y, t.z
            ),
        });
    }
    Ok(Pose3::from_parts(t, UnitQuaternion::from_quaternion(q)))
}

/// Writes a `Pose` or `Transform`.
pub fn write_pose(w: &mut CdrWriter, pose: &Pose3) {
    let t = pose.translation();
    let q = pose.rotation();
    for v in [t.x, t.y, t.z, q.i, q.j, q.k, q.w] {
        w.f64(v);
    }
}

/// Widens a `float32` reading to the `f64` a log most likely held: the decimal with at most
/// four fractional digits that rounds to the same `float32`, when there is one (logs and
/// drivers quantise ranges to centimetres or millimetres: `1.23` comes back as `1.23`, not
/// `1.2300000190734863`), else the exact widening. Either way the result rounds to `v`.
pub fn widen_decimal(v: f32) -> f64 {
    let exact = f64::from(v);
    if exact.is_nan() || exact.abs() >= 1e9 {
        return exact;
    }
    let decimal = (exact * 1e4).round() / 1e4;
    if decimal as f32 == v { decimal } else { exact }
}

/// Widens a `float32` angle to the `f64` of the nearest angle with at most four fractional
/// digits in degrees (`-π/2`, `π/180`, `π/360` …) when it rounds to the same `float32`, else
/// the exact widening: a scan's beam layout comes back as the `f64` fan it was written from.
pub fn widen_angle(v: f32) -> f64 {
    let exact = f64::from(v);
    if !exact.is_finite() {
        return exact;
    }
    let degrees = (exact.to_degrees() * 1e4).round() / 1e4;
    let snapped = degrees * std::f64::consts::PI / 180.0;
    if snapped as f32 == v { snapped } else { exact }
}

/// Decodes a `sensor_msgs/msg/LaserScan` into its header and a [`Scan2`].
///
/// REP-117: `+inf` (no return within range) becomes `range_max`; `-inf` (too close), NaN
/// (invalid) and readings below `range_min` become NaN; all of them are no-returns of the
/// [`Scan2`]. Finite readings at or above `range_max` stay as they are (no-returns too).
/// Ranges, intensities and angles are widened from `float32` by [`widen_decimal`] and
/// [`widen_angle`], so a CARMEN log converted to a bag reads back with its own numbers.
pub fn decode_scan(data: &[u8]) -> CdrResult<(Header<'_>, Scan2)> {
    let mut r = CdrReader::new(data)?;
    let header = read_header(&mut r)?;
    let angle_min = r.f32()?;
    let _angle_max = r.f32()?;
    let angle_increment = r.f32()?;
    let _time_increment = r.f32()?;
    let _scan_time = r.f32()?;
    let range_min = r.f32()?;
    let at = r.offset();
    let range_max = r.f32()?;
    if range_max.is_nan() || range_max <= 0.0 || !angle_min.is_finite() {
        return Err(CdrError {
            offset: at,
            reason: format!(
                "range_max {range_max} is not positive or angle_min {angle_min} is not finite"
            ),
        });
    }
    if !angle_increment.is_finite() {
        return Err(r.error(format!("angle_increment {angle_increment} is not finite")));
    }
    let max = widen_decimal(range_max);
    let mut ranges = Vec::new();
    r.f32_seq_into(&mut ranges, "ranges", |v| {
        if v.is_finite() {
            if v >= range_min {
                widen_decimal(v)
            } else {
                f64::NAN
            }
        } else if v == f32::INFINITY {
            max
        } else {
            f64::NAN
        }
    })?;
    let at = r.offset();
    let mut intensities = Vec::new();
    r.f32_seq_into(&mut intensities, "intensities", widen_decimal)?;
    if !intensities.is_empty() && intensities.len() != ranges.len() {
        return Err(CdrError {
            offset: at,
            reason: format!(
                "{} intensities for {} ranges",
                intensities.len(),
                ranges.len()
            ),
        });
    }
    let scan = Scan2 {
        angle_min_rad: widen_angle(angle_min),
        angle_increment_rad: widen_angle(angle_increment),
        max_range_m: max,
        ranges,
        intensities: (!intensities.is_empty()).then_some(intensities),
    };
    Ok((header, scan))
}

/// Encodes a `sensor_msgs/msg/LaserScan`: ranges as they are (rounded to `float32`),
/// `range_min` 0, `range_max` = [`Scan2::max_range_m`], no timing.
pub fn encode_scan(w: &mut CdrWriter, stamp: Stamp, frame_id: &str, scan: &Scan2) {
    write_header(w, stamp, frame_id);
    w.f32(scan.angle_min_rad as f32);
    w.f32(scan.angle_max_rad() as f32);
    w.f32(scan.angle_increment_rad as f32);
    w.f32(0.0); // time_increment
    w.f32(0.0); // scan_time
    w.f32(0.0); // range_min
    w.f32(scan.max_range_m as f32);
    w.f32_seq(scan.ranges.iter().map(|&r| r as f32));
    match &scan.intensities {
        Some(v) => w.f32_seq(v.iter().map(|&i| i as f32)),
        None => w.seq_len(0),
    }
}

/// A decoded `nav_msgs/msg/Odometry` (pose only).
#[derive(Clone, Debug, PartialEq)]
pub struct Odometry<'a> {
    /// Header: the odometry frame and the time.
    pub header: Header<'a>,
    /// The robot frame.
    pub child_frame_id: &'a str,
    /// `header.frame_id`-from-`child_frame_id`.
    pub pose: Pose3,
}

/// Decodes the pose of a `nav_msgs/msg/Odometry` (covariance and twist are not read).
pub fn decode_odometry(data: &[u8]) -> CdrResult<Odometry<'_>> {
    let mut r = CdrReader::new(data)?;
    let header = read_header(&mut r)?;
    let child_frame_id = frame_name(r.string()?);
    let pose = read_pose(&mut r)?;
    Ok(Odometry {
        header,
        child_frame_id,
        pose,
    })
}

/// Encodes a `nav_msgs/msg/Odometry` with zero covariance and twist.
pub fn encode_odometry(w: &mut CdrWriter, stamp: Stamp, frame_id: &str, child: &str, pose: &Pose3) {
    write_header(w, stamp, frame_id);
    w.string(child);
    write_pose(w, pose);
    // covariance, twist (linear, angular), twist covariance
    for _ in 0..(36 + 6 + 36) {
        w.f64(0.0);
    }
}

/// Decodes a `geometry_msgs/msg/PoseStamped`.
pub fn decode_pose_stamped(data: &[u8]) -> CdrResult<(Header<'_>, Pose3)> {
    let mut r = CdrReader::new(data)?;
    let header = read_header(&mut r)?;
    Ok((header, read_pose(&mut r)?))
}

/// Encodes a `geometry_msgs/msg/PoseStamped`.
pub fn encode_pose_stamped(w: &mut CdrWriter, stamp: Stamp, frame_id: &str, pose: &Pose3) {
    write_header(w, stamp, frame_id);
    write_pose(w, pose);
}

/// One `geometry_msgs/msg/TransformStamped`.
#[derive(Clone, Debug, PartialEq)]
pub struct Transform {
    /// Time of the transform.
    pub stamp: Stamp,
    /// The parent frame (`header.frame_id`).
    pub parent: String,
    /// The child frame.
    pub child: String,
    /// `parent_from_child`.
    pub parent_from_child: Pose3,
}

/// Decodes a `tf2_msgs/msg/TFMessage`.
pub fn decode_tf(data: &[u8]) -> CdrResult<Vec<Transform>> {
    let mut r = CdrReader::new(data)?;
    // header (8) + 2 strings (≥ 4 each) + 7 doubles
    let n = r.seq_len(8 + 8 + 56, "transforms")?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let header = read_header(&mut r)?;
        let child = frame_name(r.string()?);
        let parent_from_child = read_pose(&mut r)?;
        out.push(Transform {
            stamp: header.stamp,
            parent: header.frame_id.to_string(),
            child: child.to_string(),
            parent_from_child,
        });
    }
    Ok(out)
}

/// Encodes a `tf2_msgs/msg/TFMessage`.
pub fn encode_tf(w: &mut CdrWriter, transforms: &[Transform]) {
    w.seq_len(transforms.len());
    for t in transforms {
        write_header(w, t.stamp, &t.parent);
        w.string(&t.child);
        write_pose(w, &t.parent_from_child);
    }
}

/// Reads only the header of a message that starts with one (all stamped types).
pub fn decode_header(data: &[u8]) -> CdrResult<Header<'_>> {
    let mut r = CdrReader::new(data)?;
    read_header(&mut r)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use raypath_geometry::Range;

    #[test]
    fn widening_gives_back_short_decimals_and_fans() {
        assert_eq!(widen_decimal(1.23_f32), 1.23);
        assert_eq!(widen_decimal(81.83_f32), 81.83);
        assert_eq!(widen_decimal(0.001_f32), 0.001);
        // Not a short decimal: the exact widening, which rounds back.
        let odd = 1.234_567_9_f32;
        assert_eq!(widen_decimal(odd), f64::from(odd));
        for v in [
            0.1_f32,
            3.3,
            12.345,
            1e-7,
            5e3,
            f32::MAX,
            f32::MIN_POSITIVE,
            -2.5,
        ] {
            assert_eq!(widen_decimal(v) as f32, v, "{v}");
            assert_eq!(widen_angle(v) as f32, v, "{v}");
        }
        // The CARMEN fans (FanConvention::Auto over π) come back bit for bit.
        for n in [180_usize, 181, 360, 361] {
            let (first, increment) =
                crate::carmen::FanConvention::Auto.layout(n, std::f64::consts::PI, None);
            assert_eq!(widen_angle(first as f32), first, "{n}");
            assert_eq!(widen_angle(increment as f32), increment, "{n}");
        }
        assert!(widen_decimal(f32::NAN).is_nan());
        assert_eq!(widen_angle(f32::INFINITY), f64::INFINITY);
    }

    fn stamp() -> Stamp {
        Stamp::from_secs(1_700_000_000.25).unwrap()
    }

    #[test]
    fn stamps() {
        let s = Stamp::from_secs(32.9068).unwrap();
        assert_eq!(
            s,
            Stamp {
                sec: 32,
                nanosec: 906_800_000
            }
        );
        assert!((s.secs() - 32.9068).abs() < 1e-12);
        assert_eq!(
            Stamp::from_secs(-0.5).unwrap(),
            Stamp {
                sec: -1,
                nanosec: 500_000_000
            }
        );
        assert_eq!(
            Stamp::from_secs(0.9999999999).unwrap(),
            Stamp { sec: 1, nanosec: 0 }
        );
        assert!(Stamp::from_secs(1e12).is_none());
        assert!(Stamp::from_secs(f64::NAN).is_none());
    }

    #[test]
    fn scan_round_trip() {
        let scan = Scan2 {
            angle_min_rad: -1.5,
            angle_increment_rad: 0.25,
            max_range_m: 30.0,
            ranges: vec![1.25, 30.0, 2.5, 0.0],
            intensities: Some(vec![10.0, 0.0, 3.5, 1.0]),
        };
        let mut w = CdrWriter::new();
        encode_scan(&mut w, stamp(), "laser", &scan);
        let (header, back) = decode_scan(w.bytes()).unwrap();
        assert_eq!(header.frame_id, "laser");
        assert_eq!(header.stamp, stamp());
        assert_eq!(back, scan);
        let no_int = Scan2 {
            intensities: None,
            ..scan
        };
        w.reset();
        encode_scan(&mut w, stamp(), "/laser", &no_int);
        let (header, back) = decode_scan(w.bytes()).unwrap();
        assert_eq!(header.frame_id, "laser");
        assert_eq!(back, no_int);
    }

    #[test]
    fn rep_117_ranges() {
        let mut w = CdrWriter::new();
        write_header(&mut w, stamp(), "laser");
        for v in [-0.5f32, 0.5, 0.5, 0.0, 0.0, 0.2, 10.0] {
            w.f32(v);
        }
        let raw = [
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            0.1,
            5.0,
            10.0,
            12.0,
        ];
        w.f32_seq(raw.into_iter());
        w.seq_len(0);
        let (_, scan) = decode_scan(w.bytes()).unwrap();
        assert_eq!(scan.ranges[0], 10.0);
        assert!(scan.ranges[1].is_nan() && scan.ranges[2].is_nan() && scan.ranges[3].is_nan());
        assert_eq!(scan.ranges[4], 5.0);
        let kinds: Vec<_> = (0..7).map(|i| scan.range(i)).collect();
        assert_eq!(
            kinds,
            vec![
                Range::NoReturn,
                Range::NoReturn,
                Range::NoReturn,
                Range::NoReturn,
                Range::Hit(5.0),
                Range::NoReturn,
                Range::NoReturn
            ]
        );
        assert_eq!(scan.intensities, None);
    }

    #[test]
    fn odometry_pose_and_tf_round_trip() {
        let pose = Pose3::from_xyz_rpy(1.0, -2.0, 0.5, 0.1, -0.2, 2.5);
        let mut w = CdrWriter::new();
        encode_odometry(&mut w, stamp(), "odom", "base_link", &pose);
        // Body: stamp 8, "odom" 4 + 5, child at 24 (4 + 10), pose at 40 (56), 78 doubles more.
        assert_eq!(w.bytes().len(), 4 + 40 + 56 + 78 * 8);
        let odom = decode_odometry(w.bytes()).unwrap();
        assert_eq!(odom.header.frame_id, "odom");
        assert_eq!(odom.child_frame_id, "base_link");
        assert!((odom.pose.translation() - pose.translation()).norm() < 1e-15);
        assert!(odom.pose.rotation().angle_to(&pose.rotation()) < 1e-12);

        w.reset();
        encode_pose_stamped(&mut w, stamp(), "map", &pose);
        let (h, back) = decode_pose_stamped(w.bytes()).unwrap();
        assert_eq!(h.frame_id, "map");
        assert!(back.rotation().angle_to(&pose.rotation()) < 1e-12);

        let tfs = vec![
            Transform {
                stamp: stamp(),
                parent: "odom".into(),
                child: "base_link".into(),
                parent_from_child: pose,
            },
            Transform {
                stamp: Stamp::default(),
                parent: "base_link".into(),
                child: "laser".into(),
                parent_from_child: Pose3::identity(),
            },
        ];
        w.reset();
        encode_tf(&mut w, &tfs);
        let back = decode_tf(w.bytes()).unwrap();
        assert_eq!(back.len(), 2);
        assert_eq!(back[1].child, "laser");
        assert_eq!(back[0].stamp, stamp());
        assert!((back[0].parent_from_child.translation() - pose.translation()).norm() < 1e-15);
    }

    #[test]
    fn bad_quaternion_is_an_error() {
        let mut w = CdrWriter::new();
        write_header(&mut w, stamp(), "map");
        for _ in 0..7 {
            w.f64(0.0);
        }
        let e = decode_pose_stamped(w.bytes()).unwrap_err();
        assert!(e.reason.contains("quaternion"), "{e}");
        assert_eq!(e.offset, 20);
    }
}
