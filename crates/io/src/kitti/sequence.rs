//! A KITTI odometry sequence on disk: finding its files and reading scans one at a time.

use std::path::{Path, PathBuf};

use raypath_geometry::{PointCloud, Pose3};

use super::calib::{KittiCalib, read_calib};
use super::labels::{PointLabel, check_label_count, read_labels};
use super::poses::{read_poses, read_times};
use super::velodyne::{read_velodyne, velodyne_point_count};
use crate::numbered_files::numbered_bin_files;
use crate::{Error, Result};

/// A velodyne scan file and its frame number (the number in its name).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScanFile {
    /// Frame number (`000042.bin` → 42); indexes poses and timestamps.
    pub frame: u64,
    /// The file.
    pub path: PathBuf,
}

/// One scan of a sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct KittiScan {
    /// Frame number.
    pub frame: u64,
    /// Points in the velodyne frame (x forward, y left, z up), reflectance as intensity.
    pub points: PointCloud,
}

/// The files of one KITTI odometry sequence. Nothing is read until asked for.
///
/// Recognized layouts, for a directory `dir`:
///
/// * everything inside `dir`: `velodyne/`, `poses.txt`, `times.txt`, `calib.txt` (any subset;
///   for example the pole-map sequences, which have `poses.txt` and `times.txt` only);
/// * the benchmark layout `…/sequences/XX/` (velodyne, times, calib), whose poses are in
///   `…/poses/XX.txt`.
#[derive(Clone, Debug, PartialEq)]
pub struct KittiSequence {
    /// The sequence directory.
    pub dir: PathBuf,
    /// The sequence name (`00`, …): the directory name.
    pub name: Option<String>,
    /// The velodyne directory, when present.
    pub velodyne_dir: Option<PathBuf>,
    /// The scan files, sorted by frame number.
    pub scan_files: Vec<ScanFile>,
    /// The pose file, when present.
    pub poses_path: Option<PathBuf>,
    /// The timestamp file, when present.
    pub times_path: Option<PathBuf>,
    /// The calibration file, when present.
    pub calib_path: Option<PathBuf>,
}

impl KittiSequence {
    /// Finds the files of the sequence in `dir`. Fails when `dir` holds none of them, or when a
    /// `.bin` file in `velodyne/` is not named by a frame number.
    pub fn open(dir: &Path) -> Result<Self> {
        let existing = |p: PathBuf| p.exists().then_some(p);
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .filter(|n| !n.is_empty());
        let velodyne_dir = existing(dir.join("velodyne")).filter(|p| p.is_dir());
        let scan_files = match &velodyne_dir {
            Some(v) => list_scans(v)?,
            None => Vec::new(),
        };
        let benchmark_poses = || {
            let parent = dir.parent()?;
            let is_sequences = parent.file_name()? == "sequences";
            let root = parent.parent()?;
            let name = name.as_ref()?;
            is_sequences
                .then(|| root.join("poses").join(format!("{name}.txt")))
                .and_then(existing)
        };
        let poses_path = existing(dir.join("poses.txt")).or_else(benchmark_poses);
        let sequence = Self {
            dir: dir.to_path_buf(),
            name,
            velodyne_dir,
            scan_files,
            poses_path,
            times_path: existing(dir.join("times.txt")),
            calib_path: existing(dir.join("calib.txt")),
        };
        if sequence.velodyne_dir.is_none()
            && sequence.poses_path.is_none()
            && sequence.times_path.is_none()
            && sequence.calib_path.is_none()
        {
            return Err(Error::UnknownFormat {
                path: dir.to_path_buf(),
                reason: "not a KITTI sequence: no velodyne/, poses.txt (or ../../poses/XX.txt), \
                         times.txt or calib.txt"
                    .into(),
            });
        }
        Ok(sequence)
    }

    /// The poses (`world_from_cam0`, camera axes), empty when the sequence has none.
    pub fn poses(&self) -> Result<Vec<Pose3>> {
        self.poses_path
            .as_deref()
            .map_or(Ok(Vec::new()), read_poses)
    }

    /// The timestamps in seconds, empty when the sequence has none.
    pub fn times(&self) -> Result<Vec<f64>> {
        self.times_path
            .as_deref()
            .map_or(Ok(Vec::new()), read_times)
    }

    /// The calibration, when the sequence has one.
    pub fn calib(&self) -> Result<Option<KittiCalib>> {
        self.calib_path.as_deref().map(read_calib).transpose()
    }

    /// The scans, read lazily one file at a time in frame order.
    pub fn scans(&self) -> KittiScans<'_> {
        KittiScans {
            files: self.scan_files.iter(),
        }
    }

    /// The scan of frame `frame`, `None` when there is no such file.
    pub fn scan(&self, frame: u64) -> Option<Result<PointCloud>> {
        self.scan_file(frame).map(|f| read_velodyne(&f.path))
    }

    /// The SemanticKITTI labels of frame `frame` (`labels/NNNNNN.label` beside `velodyne/`),
    /// `None` when the sequence has no label file for it. One label per point of the scan,
    /// in the same order (checked against the scan file's size).
    pub fn labels(&self, frame: u64) -> Result<Option<Vec<PointLabel>>> {
        let Some(path) = self.labels_path(frame) else {
            return Ok(None);
        };
        let labels = read_labels(&path)?;
        if let Some(scan) = self.scan_file(frame) {
            check_label_count(&labels, velodyne_point_count(&scan.path)? as usize, &path)?;
        }
        Ok(Some(labels))
    }

    /// The label file of frame `frame`, when it exists.
    pub fn labels_path(&self, frame: u64) -> Option<PathBuf> {
        let path = self.dir.join("labels").join(format!("{frame:06}.label"));
        path.is_file().then_some(path)
    }

    fn scan_file(&self, frame: u64) -> Option<&ScanFile> {
        self.scan_files
            .binary_search_by_key(&frame, |f| f.frame)
            .ok()
            .and_then(|i| self.scan_files.get(i))
    }

    /// Total number of points of all scans, from the file sizes (nothing is parsed).
    pub fn count_points(&self) -> Result<u64> {
        self.scan_files
            .iter()
            .map(|f| velodyne_point_count(&f.path))
            .sum()
    }
}

/// Iterator over the scans of a [`KittiSequence`], one file read per step.
pub struct KittiScans<'a> {
    files: std::slice::Iter<'a, ScanFile>,
}

impl Iterator for KittiScans<'_> {
    type Item = Result<KittiScan>;

    fn next(&mut self) -> Option<Self::Item> {
        let file = self.files.next()?;
        Some(read_velodyne(&file.path).map(|points| KittiScan {
            frame: file.frame,
            points,
        }))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.files.size_hint()
    }
}

/// The `.bin` files of a velodyne directory, sorted by frame number.
fn list_scans(dir: &Path) -> Result<Vec<ScanFile>> {
    let files: Vec<ScanFile> = numbered_bin_files(
        dir,
        "velodyne scan names must be frame numbers (000042.bin)",
    )?
    .into_iter()
    .map(|(frame, path)| ScanFile { frame, path })
    .collect();
    if let Some(pair) = files.windows(2).find(|w| w[0].frame == w[1].frame) {
        return Err(Error::UnknownFormat {
            path: pair[1].path.clone(),
            reason: format!(
                "frame {} has two scan files ({})",
                pair[1].frame,
                pair[0].path.display()
            ),
        });
    }
    Ok(files)
}
