//! KITTI velodyne scans: `NNNNNN.bin`, N × 16 bytes (`f32` x, y, z, reflectance, little-endian).

use std::path::{Path, PathBuf};

use nalgebra::Point3;
use raypath_geometry::PointCloud;

use crate::{Error, Location, Result, source};

/// Bytes of one point in a KITTI velodyne file.
pub const VELODYNE_POINT_BYTES: u64 = 16;

/// Reads one scan (plain or compressed): points in the velodyne frame (x forward, y left,
/// z up, metres) with the reflectance as intensity.
pub fn read_velodyne(path: &Path) -> Result<PointCloud> {
    parse_velodyne(&source::read_all(path)?, path)
}

/// Parses a scan held in memory; `name` is used in errors. Fails when the length is not a
/// multiple of 16 bytes or a value is not finite.
pub fn parse_velodyne(bytes: &[u8], name: impl Into<PathBuf>) -> Result<PointCloud> {
    let name = name.into();
    check_len(bytes.len() as u64, &name)?;
    let n = bytes.len() / VELODYNE_POINT_BYTES as usize;
    let mut points = Vec::with_capacity(n);
    let mut intensity = Vec::with_capacity(n);
    for (i, record) in bytes
        .chunks_exact(VELODYNE_POINT_BYTES as usize)
        .enumerate()
    {
        let mut v = [0f32; 4];
        for (value, raw) in v.iter_mut().zip(record.chunks_exact(4)) {
            *value = f32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]);
        }
        if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
            return Err(Error::malformed(
                &name,
                Location::Byte(i as u64 * VELODYNE_POINT_BYTES),
                format!("point {i} has a non-finite value {bad}"),
            ));
        }
        points.push(Point3::new(v[0], v[1], v[2]));
        intensity.push(v[3]);
    }
    let mut cloud = PointCloud::from_points(points);
    cloud.intensity = Some(intensity);
    Ok(cloud)
}

/// Number of points of a scan file from its size alone (no parsing); fails when the size is
/// not a multiple of 16 bytes. For uncompressed files only.
pub fn velodyne_point_count(path: &Path) -> Result<u64> {
    let len = std::fs::metadata(path)
        .map_err(|e| Error::io(path, Location::File, e))?
        .len();
    check_len(len, path)?;
    Ok(len / VELODYNE_POINT_BYTES)
}

fn check_len(len: u64, name: &Path) -> Result<()> {
    if len % VELODYNE_POINT_BYTES != 0 {
        return Err(Error::malformed(
            name,
            Location::Byte(len - len % VELODYNE_POINT_BYTES),
            format!(
                "file size {len} is not a multiple of {VELODYNE_POINT_BYTES} bytes \
                 (x, y, z, reflectance as f32); the last point is incomplete"
            ),
        ));
    }
    Ok(())
}
