//! The frames of `raypath loop-closure`: the front-laser scans of a CARMEN log, the velodyne
//! scans of a KITTI sequence, or the PNG/JPEG images of a folder (sorted by file name).

use std::path::{Path, PathBuf};

use raypath_geometry::Scan2;
use raypath_io::carmen::CarmenReader;
use raypath_io::kitti::KittiSequence;
use raypath_place_recognition::{OwnedFrame, PlaceError};

use super::super::Failure;

/// Where the frames come from.
pub enum Source {
    /// Front-laser scans of a CARMEN log, held in memory.
    Carmen(Vec<Scan2>),
    /// A KITTI sequence; scans are read one at a time.
    Kitti(KittiSequence),
    /// Image files in name order; decoded one at a time.
    Images(Vec<PathBuf>),
}

/// The input of the command.
pub struct Input {
    /// The path given on the command line.
    pub path: PathBuf,
    /// The frames.
    pub source: Source,
    /// Frame times in seconds, when known: CARMEN logger timestamps, KITTI `times.txt`, or
    /// image names of the form `<seconds>.<fraction>.<ext>` (TUM RGB-D).
    pub times: Option<Vec<f64>>,
    /// The number reported for each frame: its index, or its frame number for KITTI.
    pub labels: Vec<usize>,
    /// Number of frames before `--max-frames`.
    pub total: usize,
}

impl Input {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// What the frames are, in words.
    pub fn kind(&self) -> &'static str {
        match self.source {
            Source::Carmen(_) => "CARMEN front-laser scans",
            Source::Kitti(_) => "KITTI velodyne scans",
            Source::Images(_) => "images",
        }
    }

    /// True for planar scans.
    pub fn is_planar(&self) -> bool {
        matches!(self.source, Source::Carmen(_))
    }

    /// Angular span of the first scan (planar input), radians.
    pub fn scan_fov_rad(&self) -> Option<f64> {
        match &self.source {
            Source::Carmen(scans) => scans
                .first()
                .map(|s| (s.angle_max_rad() - s.angle_min_rad).abs()),
            _ => None,
        }
    }

    /// Frame `i`, read from disk for KITTI and images. Errors name the file.
    pub fn frame(&self, i: usize) -> Result<OwnedFrame, PlaceError> {
        match &self.source {
            Source::Carmen(scans) => scans
                .get(i)
                .cloned()
                .map(OwnedFrame::Planar)
                .ok_or_else(|| PlaceError::BadInput(format!("no scan {i}"))),
            Source::Kitti(seq) => {
                let frame = self.labels.get(i).copied().unwrap_or(usize::MAX) as u64;
                match seq.scan(frame) {
                    Some(Ok(cloud)) => Ok(OwnedFrame::Cloud(cloud)),
                    Some(Err(e)) => Err(PlaceError::BadInput(e.to_string())),
                    None => Err(PlaceError::BadInput(format!("no velodyne scan {frame}"))),
                }
            }
            Source::Images(files) => {
                let path = files
                    .get(i)
                    .ok_or_else(|| PlaceError::BadInput(format!("no image {i}")))?;
                let image = image::open(path)
                    .map_err(|e| PlaceError::BadInput(format!("{}: {e}", path.display())))?;
                Ok(OwnedFrame::Image(image.to_luma8()))
            }
        }
    }
}

/// Reads the input: a directory is a KITTI sequence (with `velodyne/`) or an image folder, a
/// file a CARMEN log. `max_frames` keeps the first frames only.
pub fn read_input(path: &Path, max_frames: Option<usize>, json: bool) -> Result<Input, Failure> {
    let mut input = if path.is_dir() {
        match KittiSequence::open(path) {
            Ok(seq) if !seq.scan_files.is_empty() => read_kitti(path, seq, json)?,
            _ => read_images(path, json)?,
        }
    } else {
        read_carmen(path, json)?
    };
    input.total = input.labels.len();
    if let Some(n) = max_frames {
        input.labels.truncate(n);
        if let Some(t) = &mut input.times {
            t.truncate(n);
        }
    }
    if input.labels.is_empty() {
        return Err(Failure::input(
            format!("{}: no frames", path.display()),
            json,
        ));
    }
    Ok(input)
}

fn read_carmen(path: &Path, json: bool) -> Result<Input, Failure> {
    let reader = CarmenReader::open(path).map_err(|e| Failure::input(e, json))?;
    let mut scans = Vec::new();
    let mut times = Vec::new();
    for m in reader.front_lasers() {
        let m = m.map_err(|e| Failure::input(e, json))?;
        times.push(m.logger_timestamp_secs);
        scans.push(m.scan);
    }
    if scans.is_empty() {
        return Err(Failure::input(
            format!(
                "{}: no front-laser scans (FLASER or ROBOTLASER1)",
                path.display()
            ),
            json,
        ));
    }
    let times = times.iter().all(|t| t.is_finite()).then_some(times);
    Ok(Input {
        path: path.to_path_buf(),
        labels: (0..scans.len()).collect(),
        source: Source::Carmen(scans),
        times,
        total: 0,
    })
}

fn read_kitti(path: &Path, seq: KittiSequence, json: bool) -> Result<Input, Failure> {
    let labels: Vec<usize> = seq.scan_files.iter().map(|f| f.frame as usize).collect();
    let all_times = seq.times().map_err(|e| Failure::input(e, json))?;
    // Times are indexed by frame number.
    let times: Option<Vec<f64>> = labels.iter().map(|&f| all_times.get(f).copied()).collect();
    Ok(Input {
        path: path.to_path_buf(),
        source: Source::Kitti(seq),
        times,
        labels,
        total: 0,
    })
}

fn read_images(path: &Path, json: bool) -> Result<Input, Failure> {
    let entries = std::fs::read_dir(path)
        .map_err(|e| Failure::input(format!("{}: {e}", path.display()), json))?;
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Failure::input(format!("{}: {e}", path.display()), json))?;
        let file = entry.path();
        let image_ext = file
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "png" | "jpg" | "jpeg"));
        if image_ext && file.is_file() {
            files.push(file);
        }
    }
    if files.is_empty() {
        return Err(Failure::input(
            format!(
                "{}: neither a KITTI sequence (velodyne/*.bin) nor a folder of PNG/JPEG images",
                path.display()
            ),
            json,
        ));
    }
    files.sort_by(|a, b| a.file_name().cmp(&b.file_name()));
    let times: Option<Vec<f64>> = files.iter().map(|f| stamp_of(f)).collect();
    Ok(Input {
        path: path.to_path_buf(),
        labels: (0..files.len()).collect(),
        source: Source::Images(files),
        times,
        total: 0,
    })
}

/// The time of an image named `<seconds>.<fraction>.<ext>` (TUM RGB-D style).
fn stamp_of(file: &Path) -> Option<f64> {
    let stem = file.file_stem()?.to_str()?;
    if !stem.contains('.') {
        return None;
    }
    stem.parse::<f64>().ok().filter(|t| t.is_finite())
}
