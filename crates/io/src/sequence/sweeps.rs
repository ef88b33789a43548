//! Sequences of timestamped 3-D sweeps with sensor poses: KITTI sequences, NCLT sessions,
//! rosbag2 recordings, or sweeps produced in memory.

use std::path::{Path, PathBuf};

use raypath_geometry::{PointCloud, Pose3};

use crate::error::{Error, Result};
use crate::kitti::{self, KittiSequence};
use crate::nclt::{self, NcltPose, NcltSession};
use crate::sequence::Topics;

/// The layout a sweep sequence was read from (it selects presets and noise models in the
/// commands).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SweepFormat {
    /// KITTI odometry layout (`velodyne/*.bin`, `poses.txt`, `times.txt`, `calib.txt`).
    Kitti,
    /// NCLT session layout (`velodyne_sync/*.bin`, `groundtruth_*.csv`, `odometry_*.csv`).
    Nclt,
    /// A rosbag2 recording (`sensor_msgs/msg/PointCloud2`).
    Bag,
    /// An Ouster capture (`.pcap` with the sensor's metadata JSON).
    Ouster,
}

/// The error a sweep function of an in-memory sequence may return.
pub type SweepError = Box<dyn std::error::Error + Send + Sync>;

/// A sweep source held in memory: sweep `index` → points in the sensor frame.
pub type SweepFn = Box<dyn Fn(usize) -> std::result::Result<PointCloud, SweepError> + Send + Sync>;

/// Random access into a file-backed source (a bag): sweep `index` → points.
pub(crate) type ReadFn = Box<dyn Fn(usize) -> Result<PointCloud> + Send + Sync>;

enum Source {
    Kitti(KittiSequence),
    Nclt(NcltSession),
    Reader(ReadFn),
    Memory(SweepFn),
}

/// A sequence of 3-D sweeps: per sweep a time, a reference (ground-truth) sensor pose and an
/// odometry sensor pose when the source has them, and the sweep itself, read on demand.
///
/// * **KITTI**: `world_from_velo = velo_from_cam0 · world_from_cam0 · cam0_from_velo` (the
///   velodyne frame of the first scan is the world frame); without `Tr` in `calib.txt` the
///   poses of `poses.txt` are taken as the velodyne's. KITTI has no odometry: the odometry
///   track is the ground truth.
/// * **NCLT**: scans from `velodyne_sync/` turned to REP-103 axes; ground truth and integrated
///   odometry (`odometry_mu_100hz.csv`) interpolated at the scan times (linear in position,
///   slerp in rotation).
/// * **Bags**: see [`crate::rosbag`].
pub struct SweepSequence {
    /// The directory or file (for an in-memory sequence: its name), used in errors.
    pub name: PathBuf,
    /// The layout.
    pub format: SweepFormat,
    /// Sweep times, seconds (strictly increasing).
    pub stamps_secs: Vec<f64>,
    /// Reference `world_from_sensor` per sweep, when known.
    pub reference: Option<Vec<Pose3>>,
    /// Odometry `odom_from_sensor` per sweep, when known.
    pub odometry: Option<Vec<Pose3>>,
    /// Per sweep: standard deviations `[x m, y m, yaw rad]` of the odometry increment from the
    /// previous sweep, when the source states them (NCLT `odometry_cov.csv`).
    pub odometry_std: Option<Vec<[f64; 3]>>,
    source: Source,
}

/// How to open a sweep sequence.
#[derive(Clone, Debug, Default)]
pub struct SweepOptions {
    /// Topic and frame choice for bags.
    pub topics: Topics,
}

fn bad(name: &Path, reason: impl Into<String>) -> Error {
    Error::UnknownFormat {
        path: name.to_path_buf(),
        reason: reason.into(),
    }
}

impl SweepSequence {
    /// Opens a KITTI sequence, an NCLT session (detected from the directory contents), a
    /// rosbag2 recording or an Ouster capture (`.pcap`/`.pcapng`, see
    /// [`crate::ouster::open_sweeps`]). A KITTI dataset root holding exactly one sequence under
    /// `sequences/` opens that sequence.
    pub fn open(path: &Path, options: &SweepOptions) -> Result<Self> {
        if path.is_file() && crate::ouster::is_capture_name(path) {
            return crate::ouster::open_sweeps(path);
        }
        if crate::rosbag::is_bag(path)? {
            return crate::rosbag::open_sweeps(path, &options.topics);
        }
        let has = |p: &str| path.join(p).exists();
        if has("sequences") && !has("velodyne") {
            let mut sequences: Vec<PathBuf> = std::fs::read_dir(path.join("sequences"))
                .map(|it| it.filter_map(|e| e.ok().map(|e| e.path())).collect())
                .unwrap_or_default();
            sequences.retain(|p| p.is_dir());
            sequences.sort();
            return match sequences.as_slice() {
                [one] => Self::open(one, options),
                _ => Err(bad(
                    path,
                    format!(
                        "a KITTI root with {} sequences under sequences/: name one (e.g. {})",
                        sequences.len(),
                        path.join("sequences/00").display()
                    ),
                )),
            };
        }
        if has("velodyne") || has("poses.txt") || has("calib.txt") || has("times.txt") {
            return Self::open_kitti(path);
        }
        if has("velodyne_sync") || path.is_dir() {
            return Self::open_nclt(path);
        }
        Err(bad(
            path,
            "not a KITTI sequence, an NCLT session or a rosbag2 recording",
        ))
    }

    /// A sequence from parts held in memory: `name` (used in errors), the layout its
    /// conventions follow, sweep times (seconds, strictly increasing), the reference and
    /// odometry `world_from_sensor` per sweep when known, and `sweep`, which returns sweep
    /// `index` (points in the sensor frame, REP-103 axes, metres) for `index <
    /// stamps_secs.len()`.
    ///
    /// Fails when a track does not have one pose per time or the times are not strictly
    /// increasing.
    pub fn from_fn(
        name: &str,
        format: SweepFormat,
        stamps_secs: Vec<f64>,
        reference: Option<Vec<Pose3>>,
        odometry: Option<Vec<Pose3>>,
        sweep: SweepFn,
    ) -> Result<Self> {
        Self::from_parts(
            PathBuf::from(name),
            format,
            stamps_secs,
            reference,
            odometry,
            Source::Memory(sweep),
        )
    }

    pub(crate) fn from_reader(
        name: PathBuf,
        format: SweepFormat,
        stamps_secs: Vec<f64>,
        reference: Option<Vec<Pose3>>,
        odometry: Option<Vec<Pose3>>,
        read: ReadFn,
    ) -> Result<Self> {
        Self::from_parts(
            name,
            format,
            stamps_secs,
            reference,
            odometry,
            Source::Reader(read),
        )
    }

    fn from_parts(
        name: PathBuf,
        format: SweepFormat,
        stamps_secs: Vec<f64>,
        reference: Option<Vec<Pose3>>,
        odometry: Option<Vec<Pose3>>,
        source: Source,
    ) -> Result<Self> {
        for (what, track) in [("reference", &reference), ("odometry", &odometry)] {
            if let Some(t) = track
                && t.len() != stamps_secs.len()
            {
                return Err(bad(
                    &name,
                    format!(
                        "{} {what} poses for {} sweep times",
                        t.len(),
                        stamps_secs.len()
                    ),
                ));
            }
        }
        check_increasing(&name, &stamps_secs)?;
        Ok(Self {
            name,
            format,
            stamps_secs,
            reference,
            odometry,
            odometry_std: None,
            source,
        })
    }

    fn open_kitti(dir: &Path) -> Result<Self> {
        let sequence = KittiSequence::open(dir)?;
        let missing = |what: &str| bad(dir, format!("the KITTI sequence has no {what}"));
        if sequence.scan_files.is_empty() {
            return Err(missing("velodyne scans"));
        }
        let times = sequence.times()?;
        let poses = sequence.poses()?;
        let world_from_velo = match sequence.calib()?.and_then(|c| c.cam0_from_velo()) {
            Some(cam0_from_velo) => kitti::velodyne_poses_from_cam0(&poses, &cam0_from_velo),
            // Without `Tr` the poses are taken as the velodyne's own poses.
            None => poses,
        };
        let mut stamps = Vec::with_capacity(sequence.scan_files.len());
        let mut truth = Vec::with_capacity(sequence.scan_files.len());
        for (k, file) in sequence.scan_files.iter().enumerate() {
            let frame = file.frame as usize;
            let t = match times.get(frame) {
                Some(&t) => t,
                None if times.is_empty() => k as f64 * 0.1,
                None => return Err(missing(&format!("time for frame {frame} in times.txt"))),
            };
            stamps.push(t);
            if let Some(p) = world_from_velo.get(frame) {
                truth.push(*p);
            }
        }
        let reference = (truth.len() == stamps.len()).then_some(truth);
        Self::from_parts(
            dir.to_path_buf(),
            SweepFormat::Kitti,
            stamps,
            reference.clone(),
            reference,
            Source::Kitti(sequence),
        )
    }

    fn open_nclt(dir: &Path) -> Result<Self> {
        let session = NcltSession::open(dir)?;
        if session.sync_files.is_empty() {
            return Err(bad(dir, "the NCLT session has no velodyne_sync scans"));
        }
        let stamps: Vec<f64> = session
            .sync_files
            .iter()
            .map(|f| nclt::utime_to_secs(f.utime))
            .collect();
        let reference = match session.ground_truth_path {
            Some(_) => sample(&session.ground_truth()?.poses, &stamps),
            None => None,
        };
        let odometry = match session.odometry_path {
            Some(_) => sample(&session.odometry()?.poses, &stamps),
            None => None,
        };
        let odometry_std = match session.relative_odometry_cov_path {
            Some(_) => {
                let cov = session.relative_odometry_cov()?;
                let times: Vec<f64> = cov
                    .records
                    .iter()
                    .map(|r| nclt::utime_to_secs(r.utime))
                    .collect();
                (!cov.records.is_empty()).then(|| {
                    stamps
                        .iter()
                        .map(|&t| {
                            let k = times.partition_point(|&s| s < t).min(times.len() - 1);
                            let m = &cov.records[k].matrix;
                            [m[(0, 0)], m[(1, 1)], m[(5, 5)]].map(|v| v.max(0.0).sqrt())
                        })
                        .collect()
                })
            }
            None => None,
        };
        let mut out = Self::from_parts(
            dir.to_path_buf(),
            SweepFormat::Nclt,
            stamps,
            reference,
            odometry,
            Source::Nclt(session),
        )?;
        out.odometry_std = odometry_std;
        Ok(out)
    }

    /// Number of sweeps.
    pub fn len(&self) -> usize {
        self.stamps_secs.len()
    }

    /// True when the sequence has no sweeps.
    pub fn is_empty(&self) -> bool {
        self.stamps_secs.is_empty()
    }

    /// Reads sweep `index` (points in the sensor frame, REP-103 axes).
    pub fn sweep(&self, index: usize) -> Result<PointCloud> {
        let out_of_range = || bad(&self.name, format!("no sweep {index}"));
        match &self.source {
            Source::Kitti(sequence) => {
                let file = sequence.scan_files.get(index).ok_or_else(out_of_range)?;
                kitti::read_velodyne(&file.path)
            }
            Source::Nclt(session) => {
                let file = session.sync_files.get(index).ok_or_else(out_of_range)?;
                let mut cloud = nclt::read_velodyne_sync(&file.path)?;
                nclt::flu_from_frd(&mut cloud);
                Ok(cloud)
            }
            Source::Reader(read) => {
                if index >= self.len() {
                    return Err(out_of_range());
                }
                read(index)
            }
            Source::Memory(sweep) => {
                if index >= self.len() {
                    return Err(out_of_range());
                }
                sweep(index).map_err(|e| bad(&self.name, format!("sweep {index}: {e}")))
            }
        }
    }

    /// The sweeps in order, each with its index.
    pub fn sweeps(&self) -> impl Iterator<Item = Result<(usize, PointCloud)>> + '_ {
        (0..self.len()).map(|i| self.sweep(i).map(|cloud| (i, cloud)))
    }

    /// Total number of points of all sweeps (from file sizes where the layout allows; other
    /// sources read every sweep to count them).
    pub fn count_points(&self) -> Result<u64> {
        Ok(match &self.source {
            Source::Kitti(sequence) => sequence.count_points()?,
            Source::Nclt(session) => session.count_points()?,
            Source::Reader(_) | Source::Memory(_) => {
                let mut total = 0;
                for i in 0..self.len() {
                    total += self.sweep(i)?.len() as u64;
                }
                total
            }
        })
    }

    /// The reference poses, or an error naming the sequence.
    pub fn require_reference(&self) -> Result<&[Pose3]> {
        self.reference
            .as_deref()
            .ok_or_else(|| bad(&self.name, "no reference (ground-truth) poses"))
    }

    /// The odometry poses, or an error naming the sequence.
    pub fn require_odometry(&self) -> Result<&[Pose3]> {
        self.odometry
            .as_deref()
            .ok_or_else(|| bad(&self.name, "no odometry poses"))
    }

    /// The sequence with an odometry track for every sweep: the recorded odometry, else the
    /// reference poses for the layouts that record none (KITTI, whose odometry benchmark
    /// gives poses only; bags without an odometry topic; Ouster captures). Fails, naming the
    /// sequence and the file the poses would come from, when neither track is there, and for
    /// an NCLT session without odometry covering every sweep time (NCLT records its odometry;
    /// the ground truth is no stand-in for it).
    pub fn with_odometry_or_reference(mut self) -> Result<Self> {
        if self.odometry.is_some() {
            return Ok(self);
        }
        let missing = match self.format {
            SweepFormat::Nclt => {
                "the NCLT session has no odometry covering every scan time \
                 (odometry_mu_100hz.csv)"
            }
            SweepFormat::Kitti => {
                "the KITTI sequence has no pose for every scan in poses.txt (KITTI odometry \
                 comes from the poses)"
            }
            SweepFormat::Bag => "the bag has neither odometry nor reference poses for every sweep",
            SweepFormat::Ouster => {
                "the Ouster capture has no poses for its frames (<capture stem>_poses_kitti.txt \
                 beside the .pcap)"
            }
        };
        match (self.format, self.reference.clone()) {
            (SweepFormat::Kitti | SweepFormat::Bag | SweepFormat::Ouster, Some(reference)) => {
                self.odometry = Some(reference);
                Ok(self)
            }
            _ => Err(bad(&self.name, missing)),
        }
    }
}

/// The poses of a table at `stamps` (linear in position, slerp in rotation); `None` when the
/// table does not cover every stamp.
fn sample(rows: &[NcltPose], stamps: &[f64]) -> Option<Vec<Pose3>> {
    let mut times = Vec::with_capacity(rows.len());
    let mut poses = Vec::with_capacity(rows.len());
    for r in rows {
        let t = r.stamp_secs();
        if times.last().is_some_and(|&last| t <= last) {
            continue;
        }
        times.push(t);
        poses.push(r.world_from_body());
    }
    stamps
        .iter()
        .map(|&t| interpolate(&times, &poses, t))
        .collect()
}

/// The pose at `t` on a track with strictly increasing `times`; `None` outside it.
pub(crate) fn interpolate(times: &[f64], poses: &[Pose3], t: f64) -> Option<Pose3> {
    let k = times.partition_point(|&s| s < t);
    if k < times.len() && times[k] == t {
        return Some(poses[k]);
    }
    if k == 0 || k == times.len() {
        return None;
    }
    let (t0, t1) = (times[k - 1], times[k]);
    Some(poses[k - 1].interpolate(&poses[k], (t - t0) / (t1 - t0)))
}

fn check_increasing(name: &Path, stamps: &[f64]) -> Result<()> {
    if let Some(k) = stamps
        .windows(2)
        .position(|w| !(w[0].is_finite() && w[1].is_finite() && w[1] > w[0]))
    {
        return Err(bad(
            name,
            format!("sweep times are not strictly increasing at sweep {}", k + 1),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
