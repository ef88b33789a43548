//! An NCLT session on disk: finding its files and reading scans one at a time.

use std::path::{Path, PathBuf};

use raypath_geometry::PointCloud;

use super::csv::{CovarianceTable, PoseTable, read_covariance, read_pose_csv};
use super::velodyne::{HitsReader, RECORD_BYTES, read_velodyne_sync};
use crate::numbered_files::numbered_bin_files;
use crate::{Error, Location, Result};

/// A `velodyne_sync` file and its timestamp.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SyncFile {
    /// Microseconds since the UNIX epoch (the file name).
    pub utime: u64,
    /// The file.
    pub path: PathBuf,
}

/// One `velodyne_sync` revolution.
#[derive(Clone, Debug, PartialEq)]
pub struct NcltScan {
    /// Microseconds since the UNIX epoch.
    pub utime: u64,
    /// Points as stored (see the [module documentation](super)), intensity and laser id.
    pub points: PointCloud,
}

/// The files of one NCLT session. Nothing is read until asked for.
///
/// For a directory `dir` and a session date `D` (found from the file names), the files are
/// looked up in the data set's layout and, failing that, directly inside `dir`:
///
/// | file | layout | or |
/// |---|---|---|
/// | scans | `velodyne_data/D_vel/velodyne_sync/*.bin` | `D_vel/velodyne_sync/`, `velodyne_sync/` |
/// | packets | `velodyne_data/D_vel/velodyne_hits.bin` | `D_vel/…`, `velodyne_hits.bin` |
/// | ground truth | `ground_truth/groundtruth_D.csv` | `groundtruth_D.csv` |
/// | its covariance | `ground_truth_cov/cov_D.csv` | `cov_D.csv` |
/// | odometry | `sensor_data/D_sen/odometry_mu_100hz.csv` | `D_sen/…`, `odometry_mu_100hz.csv` |
/// | relative odometry | `sensor_data/D_sen/odometry_mu.csv` | … |
/// | its covariance | `sensor_data/D_sen/odometry_cov.csv` | … |
#[derive(Clone, Debug, PartialEq)]
pub struct NcltSession {
    /// The session directory.
    pub dir: PathBuf,
    /// The session date (`2012-01-08`), when file names tell it.
    pub date: Option<String>,
    /// The `velodyne_sync` directory, when present.
    pub velodyne_sync_dir: Option<PathBuf>,
    /// The revolutions, sorted by timestamp.
    pub sync_files: Vec<SyncFile>,
    /// `velodyne_hits.bin`, when present.
    pub hits_path: Option<PathBuf>,
    /// `groundtruth_<date>.csv`, when present.
    pub ground_truth_path: Option<PathBuf>,
    /// `cov_<date>.csv`, when present.
    pub ground_truth_cov_path: Option<PathBuf>,
    /// `odometry_mu_100hz.csv` (integrated odometry), when present.
    pub odometry_path: Option<PathBuf>,
    /// `odometry_mu.csv` (relative increments), when present.
    pub relative_odometry_path: Option<PathBuf>,
    /// `odometry_cov.csv` (covariance of the increments), when present.
    pub relative_odometry_cov_path: Option<PathBuf>,
}

impl NcltSession {
    /// Finds the files of the session in `dir`. Fails when `dir` holds files of several
    /// sessions (use [`NcltSession::open_date`]) or none at all.
    pub fn open(dir: &Path) -> Result<Self> {
        let mut dates = find_dates(dir)?;
        dates.sort();
        dates.dedup();
        match dates.as_slice() {
            [] => Self::open_date(dir, None),
            [date] => Self::open_date(dir, Some(date)),
            _ => Err(Error::UnknownFormat {
                path: dir.to_path_buf(),
                reason: format!(
                    "the directory holds several NCLT sessions ({}); open one by date",
                    dates.join(", ")
                ),
            }),
        }
    }

    /// Finds the files of the session of `date` (`2012-01-08`; `None` when the files are not
    /// named by date) in `dir`.
    pub fn open_date(dir: &Path, date: Option<&str>) -> Result<Self> {
        let find = |candidates: &[PathBuf]| candidates.iter().find(|p| p.exists()).cloned();
        let vel = date.map(|d| format!("{d}_vel"));
        let sen = date.map(|d| format!("{d}_sen"));
        let mut vel_dirs = Vec::new();
        if let Some(v) = &vel {
            vel_dirs.push(dir.join("velodyne_data").join(v));
            vel_dirs.push(dir.join(v));
        }
        vel_dirs.push(dir.to_path_buf());
        let mut sen_dirs = Vec::new();
        if let Some(s) = &sen {
            sen_dirs.push(dir.join("sensor_data").join(s));
            sen_dirs.push(dir.join(s));
        }
        sen_dirs.push(dir.to_path_buf());
        let in_dirs = |dirs: &[PathBuf], name: &str| {
            find(&dirs.iter().map(|d| d.join(name)).collect::<Vec<_>>())
        };
        let dated = |sub: &str, prefix: &str| {
            let d = date?;
            let name = format!("{prefix}{d}.csv");
            find(&[dir.join(sub).join(&name), dir.join(&name)])
        };
        let velodyne_sync_dir = in_dirs(&vel_dirs, "velodyne_sync").filter(|p| p.is_dir());
        let sync_files = match &velodyne_sync_dir {
            Some(d) => list_sync(d)?,
            None => Vec::new(),
        };
        let session = Self {
            dir: dir.to_path_buf(),
            date: date.map(str::to_owned),
            velodyne_sync_dir,
            sync_files,
            hits_path: in_dirs(&vel_dirs, "velodyne_hits.bin"),
            ground_truth_path: dated("ground_truth", "groundtruth_"),
            ground_truth_cov_path: dated("ground_truth_cov", "cov_"),
            odometry_path: in_dirs(&sen_dirs, "odometry_mu_100hz.csv"),
            relative_odometry_path: in_dirs(&sen_dirs, "odometry_mu.csv"),
            relative_odometry_cov_path: in_dirs(&sen_dirs, "odometry_cov.csv"),
        };
        if session.velodyne_sync_dir.is_none()
            && session.hits_path.is_none()
            && session.ground_truth_path.is_none()
            && session.odometry_path.is_none()
            && session.relative_odometry_path.is_none()
        {
            return Err(Error::UnknownFormat {
                path: dir.to_path_buf(),
                reason: "not an NCLT session: no velodyne_sync/, velodyne_hits.bin, \
                         groundtruth_<date>.csv or odometry_mu*.csv in the documented places"
                    .into(),
            });
        }
        Ok(session)
    }

    /// The revolutions, read lazily one file at a time in time order.
    pub fn scans(&self) -> NcltScans<'_> {
        NcltScans {
            files: self.sync_files.iter(),
        }
    }

    /// Total number of points of all revolutions, from the file sizes (nothing is parsed).
    pub fn count_points(&self) -> Result<u64> {
        let mut total = 0;
        for file in &self.sync_files {
            let len = std::fs::metadata(&file.path)
                .map_err(|e| Error::io(&file.path, Location::File, e))?
                .len();
            if len % RECORD_BYTES != 0 {
                return Err(Error::malformed(
                    &file.path,
                    Location::Byte(len - len % RECORD_BYTES),
                    format!("file size {len} is not a multiple of {RECORD_BYTES}-byte records"),
                ));
            }
            total += len / RECORD_BYTES;
        }
        Ok(total)
    }

    /// The ground truth (empty when absent).
    pub fn ground_truth(&self) -> Result<PoseTable> {
        self.ground_truth_path
            .as_deref()
            .map_or(Ok(PoseTable::default()), read_pose_csv)
    }

    /// The ground-truth covariances (empty when absent).
    pub fn ground_truth_cov(&self) -> Result<CovarianceTable> {
        self.ground_truth_cov_path
            .as_deref()
            .map_or(Ok(CovarianceTable::default()), read_covariance)
    }

    /// The integrated odometry (`odometry_mu_100hz.csv`; empty when absent).
    pub fn odometry(&self) -> Result<PoseTable> {
        self.odometry_path
            .as_deref()
            .map_or(Ok(PoseTable::default()), read_pose_csv)
    }

    /// The relative odometry increments (`odometry_mu.csv`; empty when absent).
    pub fn relative_odometry(&self) -> Result<PoseTable> {
        self.relative_odometry_path
            .as_deref()
            .map_or(Ok(PoseTable::default()), read_pose_csv)
    }

    /// The covariances of the increments (`odometry_cov.csv`; empty when absent).
    pub fn relative_odometry_cov(&self) -> Result<CovarianceTable> {
        self.relative_odometry_cov_path
            .as_deref()
            .map_or(Ok(CovarianceTable::default()), read_covariance)
    }

    /// The packet stream, when present.
    pub fn hits(&self) -> Option<Result<HitsReader<Box<dyn std::io::BufRead + Send>>>> {
        self.hits_path.as_deref().map(HitsReader::open)
    }
}

/// Iterator over the revolutions of an [`NcltSession`], one file read per step.
pub struct NcltScans<'a> {
    files: std::slice::Iter<'a, SyncFile>,
}

impl Iterator for NcltScans<'_> {
    type Item = Result<NcltScan>;

    fn next(&mut self) -> Option<Self::Item> {
        let file = self.files.next()?;
        Some(read_velodyne_sync(&file.path).map(|points| NcltScan {
            utime: file.utime,
            points,
        }))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.files.size_hint()
    }
}

/// Session dates named by the files and folders of `dir` (and its documented subfolders).
fn find_dates(dir: &Path) -> Result<Vec<String>> {
    let mut dates = Vec::new();
    for sub in [
        dir.to_path_buf(),
        dir.join("velodyne_data"),
        dir.join("ground_truth"),
        dir.join("sensor_data"),
    ] {
        let Ok(entries) = std::fs::read_dir(&sub) else {
            continue;
        };
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(&sub, Location::File, e))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            let date = name
                .strip_prefix("groundtruth_")
                .and_then(|n| n.strip_suffix(".csv"))
                .or_else(|| name.strip_suffix("_vel"))
                .or_else(|| name.strip_suffix("_sen"));
            if let Some(date) = date.filter(|d| is_date(d)) {
                dates.push(date.to_owned());
            }
        }
    }
    Ok(dates)
}

/// `YYYY-MM-DD`.
fn is_date(text: &str) -> bool {
    text.len() == 10
        && text.char_indices().all(|(i, c)| {
            if i == 4 || i == 7 {
                c == '-'
            } else {
                c.is_ascii_digit()
            }
        })
}

/// The `.bin` files of a `velodyne_sync` directory, sorted by timestamp.
fn list_sync(dir: &Path) -> Result<Vec<SyncFile>> {
    let files = numbered_bin_files(
        dir,
        "velodyne_sync file names must be microsecond timestamps (1326030975726043.bin)",
    )?;
    Ok(files
        .into_iter()
        .map(|(utime, path)| SyncFile { utime, path })
        .collect())
}
