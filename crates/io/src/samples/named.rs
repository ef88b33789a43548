//! Files under the names format detection goes by, plain and compressed.

use std::io::Write;

use super::Sample;
use super::{
    CARMEN_LOG, LZW_STREAMS, kitti_calib, kitti_poses, kitti_times, kitti_velodyne,
    nclt_covariance, nclt_hits, nclt_pose_csv, octomap_bt, octomap_graph, pcd, point_csv,
    segcomp_gt_ang, xyz,
};
use crate::{Error, Location, Result};

fn gzip(bytes: &[u8]) -> Result<Vec<u8>> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes)
        .and_then(|()| enc.finish())
        .map_err(|e| Error::io("sample.gz", Location::File, e))
}

fn bzip2(bytes: &[u8]) -> Result<Vec<u8>> {
    let mut enc = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::fast());
    enc.write_all(bytes)
        .and_then(|()| enc.finish())
        .map_err(|e| Error::io("sample.bz2", Location::File, e))
}

/// Files of every single-file format under the names format detection goes by, plain and
/// compressed (gzip, bzip2, Unix compress).
pub fn named_files() -> Result<Vec<Sample>> {
    let first = |seeds: Vec<Sample>| {
        seeds
            .into_iter()
            .next()
            .map(|s| s.bytes)
            .unwrap_or_default()
    };
    let log = CARMEN_LOG.as_bytes();
    let pcd = pcd()?;
    Ok(vec![
        Sample::new("intel.log", log),
        Sample::new("intel.log.gz", gzip(log)?),
        Sample::new("intel.clf.bz2", bzip2(log)?),
        Sample::new("cloud.pcd", pcd[1].bytes.clone()),
        Sample::new("cloud.pcd.gz", gzip(&pcd[2].bytes)?),
        Sample::new("points.xyz", xyz()[1].bytes.clone()),
        Sample::new("points.xyz.bz2", bzip2(&xyz()[1].bytes)?),
        Sample::new("map.bt", first(octomap_bt()?)),
        Sample::new("scans.graph", first(octomap_graph()?)),
        Sample::new("000000.bin", first(kitti_velodyne()?)),
        Sample::new("00.txt", first(kitti_poses()?)),
        Sample::new("times.txt", first(kitti_times()?)),
        Sample::new("calib.txt", first(kitti_calib()?)),
        Sample::new("velodyne_hits.bin", first(nclt_hits())),
        Sample::new("groundtruth_2012-01-08.csv", first(nclt_pose_csv()?)),
        Sample::new("odometry_mu_100hz.csv", first(nclt_pose_csv()?)),
        Sample::new("cov_2012-01-08.csv", first(nclt_covariance()?)),
        Sample::new("synth.test.1.Z", LZW_STREAMS[3].1),
        Sample::new("synth.test.1.gt-seg.Z", LZW_STREAMS[4].1),
        Sample::new("synth.test.1.gt-ang", first(segcomp_gt_ang())),
        Sample::new("poles.csv", first(point_csv())),
    ])
}
