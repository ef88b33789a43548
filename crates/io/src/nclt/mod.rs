//! NCLT (University of Michigan North Campus Long-Term) data: velodyne scans, the raw
//! velodyne packet stream, ground truth, odometry and covariances.
//!
//! Formats as published with the data set (Carlevaris-Bianco, Ushani and Eustice, "University
//! of Michigan North Campus long-term vision and lidar dataset", IJRR 2016;
//! <http://robots.engin.umich.edu/nclt/>, scripts `read_vel_sync.py`, `read_vel_hits.py`):
//!
//! ```text
//! <date>/velodyne_data/<date>_vel/velodyne_sync/<utime>.bin  one revolution, 8-byte records
//! <date>/velodyne_data/<date>_vel/velodyne_hits.bin          raw packet stream
//! <date>/ground_truth/groundtruth_<date>.csv                 utime, x, y, z, roll, pitch, yaw
//! <date>/ground_truth_cov/cov_<date>.csv                     utime + 21 covariance values
//! <date>/sensor_data/<date>_sen/odometry_mu_100hz.csv        utime, x, y, z, roll, pitch, yaw
//! <date>/sensor_data/<date>_sen/odometry_mu.csv              same layout (relative increments)
//! <date>/sensor_data/<date>_sen/odometry_cov_100hz.csv       utime + 21 covariance values
//! ```
//!
//! `utime` is microseconds since the UNIX epoch; raypath reports seconds (`utime · 1e-6`).
//!
//! ## Frames
//!
//! NCLT uses aerospace conventions. The ground-truth world frame is **NED-like** (x north,
//! y east, z down) and the body frame **x forward, y right, z down**; roll, pitch, yaw are
//! fixed-axis x-y-z angles (`R = Rz(yaw)·Ry(pitch)·Rx(roll)`, transforms3d's `'sxyz'`).
//! [`NcltPose::world_from_body_ned`] is the pose exactly as stored;
//! [`NcltPose::world_from_body`] converts it to REP-103 (world x east, y north, z up; body
//! x forward, y left, z up). The pole-localization reference implementation (Schaefer 2020)
//! instead left-multiplies the stored pose by `T_wo = [[0,1,0],[1,0,0],[0,0,−1]]` only
//! (world to ENU, body left as is) and flips the z of the velodyne points; that pose is
//! `ENU_FROM_NED · world_from_body_ned()` ([`enu_from_ned`]).
//!
//! Velodyne points are returned as stored, in the velodyne frame of the data set (z down like
//! the body frame); [`flu_from_frd`] turns a cloud into x forward, y left, z up. Per-point
//! laser ids (0–31) are kept in [`PointCloud::label`], intensities (0–255) in
//! [`PointCloud::intensity`].
//!
//! Writers ([`write_velodyne_sync`], [`write_pose_csv`], [`write_covariance_csv`],
//! [`NcltLayout`]) produce the same files; see their module for the encoding rules.
//!
//! [`PointCloud::label`]: raypath_geometry::PointCloud::label
//! [`PointCloud::intensity`]: raypath_geometry::PointCloud::intensity

mod csv;
mod session;
mod velodyne;
mod write;

use std::path::Path;

use raypath_geometry::Aabb3;

use crate::summary::{BoundingBox, Summary, TimeSpan};
use crate::{Format, Result};

pub use csv::{
    CovarianceReader, CovarianceRecord, CovarianceTable, NcltPose, PoseCsvReader, PoseTable,
    parse_covariance, parse_pose_csv, read_covariance, read_pose_csv,
};
pub use session::{NcltScan, NcltScans, NcltSession, SyncFile};
pub use velodyne::{
    HITS_HEADER_BYTES, HITS_MAGIC, HitsHeader, HitsPacket, HitsReader, MAX_HITS_PER_PACKET,
    OFFSET_M, RECORD_BYTES, SCALE_M, decode_coordinate, flu_from_frd, parse_velodyne_sync,
    read_velodyne_sync, utime_from_path,
};
pub use write::{
    NcltLayout, encode_coordinate, encode_velodyne_sync, write_covariance_csv,
    write_covariance_csv_to, write_pose_csv, write_pose_csv_to, write_velodyne_sync,
};

/// `T_wo` of the reference implementation: NED world axes to ENU (x east, y north, z up).
pub fn enu_from_ned() -> raypath_geometry::Pose3 {
    let rotation = nalgebra::Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0);
    raypath_geometry::Pose3::from_parts(
        nalgebra::Vector3::zeros(),
        nalgebra::UnitQuaternion::from_matrix(&rotation),
    )
}

/// Microseconds to seconds.
pub fn utime_to_secs(utime: u64) -> f64 {
    utime as f64 * 1e-6
}

/// Summarizes an NCLT session directory or one of its files, read as `format`.
pub fn summarize(path: &Path, format: Format) -> Result<Summary> {
    let mut summary = Summary::new(format.name());
    match format {
        Format::NcltVelodyneSync => {
            let cloud = read_velodyne_sync(path)?;
            summary.points = Some(cloud.len() as u64);
            summary.bbox = BoundingBox::from_aabb(&cloud.bounding_box());
            summary.labels = Some(distinct_labels(cloud.label.as_deref().unwrap_or(&[])));
            if let Some(utime) = utime_from_path(path) {
                summary.time_span = TimeSpan::from_times([utime_to_secs(utime)]);
            }
        }
        Format::NcltVelodyneHits => {
            let mut reader = HitsReader::open(path)?;
            let (mut packets, mut points) = (0u64, 0u64);
            let mut span = None;
            while let Some(header) = reader.next_header_skip_points()? {
                packets += 1;
                points += u64::from(header.num_hits);
                TimeSpan::extend(&mut span, utime_to_secs(header.utime));
            }
            summary = summary.with_extra("packets", packets);
            summary.points = Some(points);
            summary.time_span = span;
        }
        Format::NcltGroundTruth | Format::NcltOdometry => {
            let table = read_pose_csv(path)?;
            if format == Format::NcltOdometry {
                summary.odometry = Some(table.poses.len() as u64);
            } else {
                summary.poses = Some(table.poses.len() as u64);
            }
            summary = summary.with_extra("nan_rows_skipped", table.nan_rows);
            summary.time_span = table.time_span();
            summary.bbox = table.bbox();
        }
        Format::NcltCovariance => {
            let table = read_covariance(path)?;
            summary = summary
                .with_extra("covariances", table.records.len() as u64)
                .with_extra("nan_rows_skipped", table.nan_rows);
            summary.time_span =
                TimeSpan::from_times(table.records.iter().map(|r| utime_to_secs(r.utime)));
        }
        _ if !is_session_dir(path) && !session_dirs(path).is_empty() => {
            return summarize_sessions(path, summary);
        }
        _ => return summarize_session(path, summary),
    }
    Ok(summary)
}

/// True when `path` holds the folders of a session (`velodyne_data/`, `ground_truth/`,
/// `sensor_data/`).
fn is_session_dir(path: &Path) -> bool {
    ["velodyne_data", "ground_truth", "sensor_data"]
        .iter()
        .any(|name| path.join(name).is_dir())
}

/// The session folders (`YYYY-MM-DD/` holding session folders) directly inside `path`, sorted.
pub(crate) fn session_dirs(path: &Path) -> Vec<std::path::PathBuf> {
    let Ok(entries) = std::fs::read_dir(path) else {
        return Vec::new();
    };
    let mut dirs: Vec<_> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let name = p
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let is_date = name.len() == 10
                && name.char_indices().all(|(i, c)| {
                    if i == 4 || i == 7 {
                        c == '-'
                    } else {
                        c.is_ascii_digit()
                    }
                });
            is_date && is_session_dir(p)
        })
        .collect();
    dirs.sort();
    dirs
}

/// The sums over the sessions in a folder of sessions, with their dates in `sessions`.
fn summarize_sessions(path: &Path, mut summary: Summary) -> Result<Summary> {
    let add = |total: &mut Option<u64>, part: Option<u64>| {
        if let Some(part) = part {
            *total = Some(total.unwrap_or(0) + part);
        }
    };
    let mut dates = Vec::new();
    let mut span: Option<TimeSpan> = None;
    for dir in session_dirs(path) {
        let part = summarize_session(&dir, Summary::new(summary.format.clone()))?;
        add(&mut summary.scans, part.scans);
        add(&mut summary.points, part.points);
        add(&mut summary.poses, part.poses);
        add(&mut summary.odometry, part.odometry);
        if let Some(t) = part.time_span {
            TimeSpan::extend(&mut span, t.start);
            TimeSpan::extend(&mut span, t.end);
        }
        dates.push(
            dir.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        );
    }
    summary.time_span = span;
    Ok(summary.with_extra("sessions", dates))
}

fn summarize_session(path: &Path, mut summary: Summary) -> Result<Summary> {
    let session = NcltSession::open(path)?;
    let mut span = None;
    if session.velodyne_sync_dir.is_some() {
        summary.scans = Some(session.sync_files.len() as u64);
        summary.points = Some(session.count_points()?);
        for file in &session.sync_files {
            TimeSpan::extend(&mut span, utime_to_secs(file.utime));
        }
    }
    if let Some(gt) = &session.ground_truth_path {
        let table = read_pose_csv(gt)?;
        summary.poses = Some(table.poses.len() as u64);
        summary.bbox = table.bbox();
        summary = summary.with_extra("ground_truth_nan_rows_skipped", table.nan_rows);
        for pose in &table.poses {
            TimeSpan::extend(&mut span, utime_to_secs(pose.utime));
        }
    }
    if let Some(odometry) = &session.odometry_path {
        let table = read_pose_csv(odometry)?;
        summary.odometry = Some(table.poses.len() as u64);
    }
    if let Some(hits) = &session.hits_path {
        let bytes = std::fs::metadata(hits)
            .map_err(|e| crate::Error::io(hits, crate::Location::File, e))?
            .len();
        summary = summary.with_extra("velodyne_hits_bytes", bytes);
    }
    if let Some(date) = &session.date {
        summary = summary.with_extra("session", date.clone());
    }
    summary.time_span = span;
    Ok(summary)
}

fn distinct_labels(labels: &[u32]) -> Vec<u32> {
    let mut seen = [false; 256];
    for &l in labels {
        if let Some(s) = seen.get_mut(l as usize) {
            *s = true;
        }
    }
    (0..256u32).filter(|&l| seen[l as usize]).collect()
}

/// Bounding box of positions.
fn positions_bbox(
    positions: impl IntoIterator<Item = nalgebra::Point3<f64>>,
) -> Option<BoundingBox> {
    let mut bbox = Aabb3::empty();
    for p in positions {
        bbox.extend(&p);
    }
    BoundingBox::from_aabb(&bbox)
}
