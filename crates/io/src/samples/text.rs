//! Text formats: CARMEN logs, KITTI poses, times and calibration, NCLT pose and covariance
//! CSVs, point and pole CSVs, TUM trajectories, SLAM-benchmark relation files, x y z files,
//! rosbag2 metadata.

use std::io::Cursor;
use std::path::Path;

use nalgebra::Matrix6;
use raypath_geometry::Pose3;

use super::Sample;
use crate::carmen::{CarmenReader, CarmenWriter};
use crate::kitti;
use crate::nclt::{self, CovarianceRecord, NcltPose};
use crate::poles_csv::{PoleRecord, write_pole_csv_to};
use crate::{Error, Location, Result};

/// A CARMEN log with every message type the reader knows (and two it does not).
pub const CARMEN_LOG: &str = "\
# CARMEN Logfile
PARAM laser_front_laser_resolution 1 0.0 nohost 0
PARAM robot_front_laser_max 30.5 1000.0 host 0.001
PARAM laser_front_laser_flipped 0 nohost 0
ODOM 1.0 2.0 0.5 0.3 -0.1 0.0 1000.25 host 0.25
FLASER 4 1.0 2.0 81.91 4.0 10.0 20.0 1.57 10.5 20.5 1.6 1000.5 robby 0.5
FLASER 4 1.5 81.91 3.0 4.5 10.1 20.0 1.57 10.6 20.5 1.6 1000.6 robby 0.6
RLASER 3 1.0 31.0 2.0 0.0 0.0 0.0 0.0 0.0 0.0 1000.6 robby 0.6
NEFF 27.6 0 pippo 0
ROBOTLASER1 0 -1.0 2.0 1.0 81.9 0.01 1 3 5.0 81.91 6.0 3 100 200 300 1.0 0.0 0.0 0.8 0.0 0.0 0.25 0.1 0.5 0.3 0.2 1000.75 robby 0.75
TRUEPOS 1 2 3 4 5 6 7 h 8
";

/// The hand-written log, and the same records as [`CarmenWriter`] writes them.
pub fn carmen() -> Result<Vec<Sample>> {
    let records = CarmenReader::new(Cursor::new(CARMEN_LOG.as_bytes().to_vec()), "seed.log")
        .collect::<Result<Vec<_>>>()?;
    let mut writer = CarmenWriter::new(Vec::new(), "seed.log");
    writer.header()?;
    for record in &records {
        writer.record(record)?;
    }
    Ok(vec![
        Sample::new("fuzz.log", CARMEN_LOG),
        Sample::new("fuzz.log", writer.finish()?),
    ])
}

fn poses() -> Vec<Pose3> {
    (0..3)
        .map(|k| {
            let k = f64::from(k);
            Pose3::from_xyz_rpy(k, -0.5 * k, 0.1, 0.01 * k, -0.02, 0.3 * k)
        })
        .collect()
}

/// KITTI pose files (written, and hand-typed with the published precision).
pub fn kitti_poses() -> Result<Vec<Sample>> {
    let mut written = Vec::new();
    kitti::write_poses_to(&mut written, &poses(), Path::new("00.txt"))?;
    let hand = "1 0 0 0 0 1 0 0 0 0 1 0\n\
        9.999978e-01 5.272628e-04 -2.066935e-03 -4.690294e-02 -5.296506e-04 9.999992e-01 \
        -1.154865e-03 -2.839928e-02 2.066324e-03 1.155958e-03 9.999971e-01 8.586941e-01\n\
        0 0 1 5 0 1 0 6 -1 0 0 7\n";
    Ok(vec![
        Sample::new("00.txt", written),
        Sample::new("00.txt", hand),
    ])
}

/// A KITTI `times.txt`.
pub fn kitti_times() -> Result<Vec<Sample>> {
    let mut written = Vec::new();
    kitti::write_times_to(
        &mut written,
        &[0.0, 0.1037359, 0.2073381],
        Path::new("times.txt"),
    )?;
    Ok(vec![Sample::new("times.txt", written)])
}

const KITTI_CALIB: &str = "P0: 7.188560000000e+02 0 6.071928e+02 0 0 7.188560e+02 1.852157e+02 0 0 0 1 0\n\
    P1: 7.188560000000e+02 0 6.071928e+02 -3.861448e+02 0 7.188560e+02 1.852157e+02 0 0 0 1 0\n\
    Tr: 4.276802e-04 -9.999672e-01 -8.084491e-03 -1.198459e-02 -7.210626e-03 8.081198e-03 \
    -9.999413e-01 -5.403984e-02 9.999739e-01 4.859485e-04 -7.206982e-03 -2.921968e-01\n";

/// KITTI calibration files: an odometry `calib.txt` and a raw `calib_velo_to_cam.txt`.
pub fn kitti_calib() -> Result<Vec<Sample>> {
    let calib = kitti::parse_calib(Cursor::new(KITTI_CALIB.as_bytes().to_vec()), "calib.txt")?;
    let mut written = Vec::new();
    kitti::write_calib_to(&mut written, &calib, Path::new("calib.txt"))?;
    let raw = "calib_time: 15-Mar-2012 11:37:16\n\
        R: 7.533745e-03 -9.999714e-01 -6.166020e-04 1.480249e-02 7.280733e-04 -9.998902e-01 \
        9.998621e-01 7.523790e-03 1.480755e-02\n\
        T: -4.069766e-03 -7.631618e-02 -2.717806e-01\n";
    Ok(vec![
        Sample::new("calib.txt", written),
        Sample::new("calib_velo_to_cam.txt", raw),
    ])
}

/// NCLT ground-truth pose CSVs (written, and hand-typed with a NaN row).
pub fn nclt_pose_csv() -> Result<Vec<Sample>> {
    let poses: Vec<NcltPose> = poses()
        .iter()
        .enumerate()
        .map(|(i, p)| NcltPose::from_world_from_body(1_326_030_975_726_043 + 10_000 * i as u64, p))
        .collect();
    let mut written = Vec::new();
    nclt::write_pose_csv_to(
        &mut written,
        &poses,
        Path::new("groundtruth_2012-01-08.csv"),
    )?;
    let hand = "utime,x,y,z,roll,pitch,yaw\n\
        1326030975726043,1.0,2.0,3.0,0.0,0.0,0.0\n\
        1326030975736043,nan,nan,nan,nan,nan,nan\n\
        1326030975746043,4.0,5.0,-6.0,0.01,-0.02,1.5707963267948966\n";
    Ok(vec![
        Sample::new("groundtruth_2012-01-08.csv", written),
        Sample::new("groundtruth_2012-01-08.csv", hand),
    ])
}

/// An NCLT covariance CSV of two records.
pub fn nclt_covariance() -> Result<Vec<Sample>> {
    let records: Vec<CovarianceRecord> = (0..2u32)
        .map(|k| CovarianceRecord {
            utime: 1_326_030_975_726_043 + u64::from(k),
            matrix: Matrix6::from_fn(|r, c| {
                if r == c {
                    0.5 + f64::from(k)
                } else {
                    0.01 * (r + c) as f64
                }
            }),
        })
        .collect();
    let mut written = Vec::new();
    nclt::write_covariance_csv_to(&mut written, &records, Path::new("cov_2012-01-08.csv"))?;
    Ok(vec![Sample::new("cov_2012-01-08.csv", written)])
}

/// Point CSVs with headers in different spellings.
pub fn point_csv() -> Vec<Sample> {
    vec![
        Sample::new(
            "points.csv",
            "x,y,w\n8.1320,-1.7499,0.0468\n-5.5911,6.3091,0.0504\n1e3,2,3\n",
        ),
        Sample::new("points.csv", "X, Y ,z\n1,2,3\n\n5,6,7\n"),
    ]
}

/// Pole-map CSVs (written, and hand-typed with extra columns).
pub fn poles_csv() -> Result<Vec<Sample>> {
    let poles = [
        PoleRecord {
            x: 1.5,
            y: -2.25,
            width: 0.2,
            height: 3.0,
            score: 0.8,
        },
        PoleRecord {
            x: -10.0,
            y: 4.0,
            width: 0.15,
            height: 2.5,
            score: 1.0,
        },
    ];
    let mut written = Vec::new();
    write_pole_csv_to(&mut written, &poles)
        .map_err(|e| Error::io("poles.csv", Location::File, e))?;
    Ok(vec![
        Sample::new("poles.csv", written),
        Sample::new(
            "poles.csv",
            "x,y,w,h,kind,id\n1,2,0.2,3,0,7\n-4,5.5,0.1,2,1,8\n",
        ),
    ])
}

/// A TUM trajectory (`t x y z qx qy qz qw`).
pub fn tum() -> Vec<Sample> {
    vec![Sample::new(
        "trajectory.tum",
        "# t x y z qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.1 0.5 -0.25 0.1 0 0 0.0499792 0.9987503\n\
         1.2 1 -0.5 0.2 0.01 -0.02 0.0998334 0.9950042\n",
    )]
}

/// A SLAM-benchmark relation file (`t1 t2 x y z roll pitch yaw`).
pub fn relations() -> Vec<Sample> {
    vec![Sample::new(
        "intel.relations",
        "# timestamp1 timestamp2 x y z roll pitch yaw\n\
         976052857.337530 976052858.412270 0.412305 -0.010521 0.000000 0.000000 -0.000000 0.021807\n\
         976052858.412270 976052861.093361 1.035640 0.046930 0.000000 0.000000 0.000000 -1.570796\n",
    )]
}

/// Plain `x y z [w]` point files with comments and blank lines.
pub fn xyz() -> Vec<Sample> {
    vec![
        Sample::new(
            "points.xyz",
            "# header\n\n1 2 3 0.5\n  -4\t5e-1 6 7 # note\n0 0 0 1\n",
        ),
        Sample::new("points.xyz", "1 2 3\n-1.5 2.25 1e2\n"),
    ]
}

/// rosbag2 `metadata.yaml`.
pub fn rosbag_metadata() -> Vec<Sample> {
    vec![Sample::new(
        "metadata.yaml",
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  \
         relative_file_paths:\n    - bag_0.mcap\n    - \"bag_1.mcap\"\n  compression_mode: ''\n  \
         duration:\n    nanoseconds: 100\n",
    )]
}
