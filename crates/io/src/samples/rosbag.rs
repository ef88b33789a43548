//! ROS 2 bags (MCAP) and single CDR messages.

use std::path::Path;

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3, Scan2};

use super::Sample;
use crate::rosbag::{self, BagCompression, BagWriteOptions, BagWriter, Stamp, Transform};
use crate::{Error, Location, Result};

/// Small bags (uncompressed, zstd, LZ4 chunks) with tf, odometry, poses, scans and clouds.
pub fn rosbag_bags(dir: &Path) -> Result<Vec<Sample>> {
    let mut seeds = Vec::new();
    for compression in [
        BagCompression::None,
        BagCompression::Zstd,
        BagCompression::Lz4,
    ] {
        let path = dir.join(format!("seed-{compression:?}.mcap"));
        let options = BagWriteOptions {
            compression,
            chunk_size_bytes: 1024,
        };
        let mut w = BagWriter::create(&path, &options)?;
        let tf = Transform {
            stamp: Stamp::default(),
            parent: "base_link".into(),
            child: "laser".into(),
            parent_from_child: Pose3::from_xyz_rpy(0.1, 0.0, 0.0, 0.0, 0.0, 0.2),
        };
        w.write_tf("/tf_static", 1.0, &[tf])?;
        for k in 0..2 {
            let t = 1.0 + 0.1 * f64::from(k);
            let pose = Pose3::from_xyz_rpy(0.1 * f64::from(k), 0.0, 0.0, 0.0, 0.0, 0.05);
            w.write_odometry("/odom", t, "odom", "base_link", &pose)?;
            w.write_pose("/truth", t, "map", &pose)?;
            let scan = Scan2 {
                angle_min_rad: -0.5,
                angle_increment_rad: 0.25,
                max_range_m: 10.0,
                ranges: vec![1.0, 2.0, f64::INFINITY, 10.0, 0.5],
                intensities: (k == 0).then(|| vec![1.0; 5]),
            };
            w.write_scan("/scan", t, "laser", &scan)?;
            let mut cloud = PointCloud::from_points(
                (0..4)
                    .map(|i| Point3::new(i as f32, 1.0, k as f32))
                    .collect(),
            );
            cloud.intensity = Some(vec![3.0; 4]);
            if k == 1 {
                cloud.width = 2;
                cloud.height = 2;
            }
            w.write_cloud("/points", t, "laser", &cloud)?;
        }
        w.finish()?;
        let bytes = std::fs::read(&path).map_err(|e| Error::io(&path, Location::File, e))?;
        seeds.push(Sample::new("fuzz.mcap", bytes));
    }
    Ok(seeds)
}

/// One CDR message of every type the rosbag reader decodes.
pub fn rosbag_cdr() -> Vec<Sample> {
    let stamp = Stamp { sec: 3, nanosec: 4 };
    let pose = Pose3::from_xyz_rpy(1.0, 2.0, 3.0, 0.1, 0.2, 0.3);
    let mut seeds = Vec::new();
    for which in 0..5 {
        let mut w = rosbag::cdr::CdrWriter::new();
        match which {
            0 => rosbag::encode_scan(
                &mut w,
                stamp,
                "laser",
                &Scan2 {
                    angle_min_rad: -1.0,
                    angle_increment_rad: 0.1,
                    max_range_m: 5.0,
                    ranges: vec![1.0, 2.0, 3.0, f64::INFINITY],
                    intensities: Some(vec![2.0; 4]),
                },
            ),
            1 => {
                let mut cloud = PointCloud::from_points(vec![Point3::new(1.0, 2.0, 3.0); 4]);
                cloud.intensity = Some(vec![1.0; 4]);
                cloud.width = 2;
                cloud.height = 2;
                rosbag::encode_cloud(&mut w, stamp, "lidar", &cloud);
            }
            2 => rosbag::encode_odometry(&mut w, stamp, "odom", "base_link", &pose),
            3 => rosbag::encode_tf(
                &mut w,
                &[Transform {
                    stamp,
                    parent: "a".into(),
                    child: "b".into(),
                    parent_from_child: pose,
                }],
            ),
            _ => rosbag::encode_pose_stamped(&mut w, stamp, "map", &pose),
        }
        seeds.push(Sample::new("message.cdr", w.bytes().to_vec()));
    }
    seeds
}
