//! The frames of `raypath loop-closure`, read through `raypath_io::sequence`: planar scans (a
//! CARMEN log's laser `--laser`, or a bag's LaserScan topic), 3-D sweeps (a KITTI sequence,
//! an NCLT session, or a bag's PointCloud2 topic), or the PNG/JPEG images of a folder (sorted
//! by file name).

use std::path::{Path, PathBuf};

use raypath_geometry::{Pose3, Scan2};
use raypath_io::images::ImageFolder;
use raypath_io::sequence::{PlanarFrame, PlanarSource, SweepFormat, SweepSequence};
use raypath_place_recognition::{OwnedFrame, PlaceError};

use super::super::Failure;
use super::super::source_args::{
    BagSource, Laser, SourceArgs, is_bag, reference_track, sweep_poses,
};

/// Where the frames come from.
pub enum Source {
    /// Planar scans, held in memory.
    Planar(Vec<Scan2>),
    /// 3-D sweeps; read one at a time.
    Sweeps(Box<SweepSequence>),
    /// Image files in name order (read by `raypath_io::images`); decoded one at a time.
    Images(ImageFolder),
}

/// The input of the command.
pub struct Input {
    /// The path given on the command line.
    pub path: PathBuf,
    /// The frames.
    pub source: Source,
    /// What the frames are, in words.
    pub kind: &'static str,
    /// Frame times in seconds, when known: CARMEN logger timestamps, bag header stamps, KITTI
    /// `times.txt`, NCLT scan times, or image names of the form `<seconds>.<fraction>.<ext>`
    /// (TUM RGB-D).
    pub times: Option<Vec<f64>>,
    /// The number reported for each frame: its index, or its frame number for KITTI.
    pub labels: Vec<usize>,
    /// The input's own pose of each frame, when it has poses: planar scans their reference
    /// poses (else the logged ones, see `reference_track`), sweeps their reference poses (else
    /// the odometry); images none.
    pub poses: Option<Vec<Option<Pose3>>>,
    /// Number of frames before `--max-frames`.
    pub total: usize,
    /// Images: the size every image must have (`--database`: the first database image's),
    /// else any size.
    pub image_size: Option<(u32, u32)>,
}

impl Input {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// What the frames are, in words.
    pub fn kind(&self) -> &'static str {
        self.kind
    }

    /// The file names of image input (`None` for other input).
    pub fn image_names(&self) -> Option<Vec<String>> {
        match &self.source {
            Source::Images(folder) => Some(
                (0..self.len())
                    .map(|i| folder.name(i).unwrap_or_default())
                    .collect(),
            ),
            _ => None,
        }
    }

    /// True for planar scans.
    pub fn is_planar(&self) -> bool {
        matches!(self.source, Source::Planar(_))
    }

    /// True when ground-truth poses without times pair with the frames by frame number.
    pub fn numbered_by_frame(&self) -> bool {
        matches!(&self.source, Source::Sweeps(s) if s.format == SweepFormat::Kitti)
    }

    /// Angular span of the first scan (planar input), radians.
    pub fn scan_fov_rad(&self) -> Option<f64> {
        match &self.source {
            Source::Planar(scans) => scans
                .first()
                .map(|s| (s.angle_max_rad() - s.angle_min_rad).abs()),
            _ => None,
        }
    }

    /// Frame `i`, read from disk for sweeps and images. Errors name the file.
    pub fn frame(&self, i: usize) -> Result<OwnedFrame, PlaceError> {
        match &self.source {
            Source::Planar(scans) => scans
                .get(i)
                .cloned()
                .map(OwnedFrame::Planar)
                .ok_or_else(|| PlaceError::BadInput(format!("no scan {i}"))),
            Source::Sweeps(sequence) => sequence
                .sweep(i)
                .map(OwnedFrame::Cloud)
                .map_err(|e| PlaceError::BadInput(e.to_string())),
            Source::Images(folder) => {
                let image = match self.image_size {
                    Some((w, h)) => folder.read_sized(i, w, h),
                    None => folder.read(i),
                };
                image
                    .map(OwnedFrame::Image)
                    .map_err(|e| PlaceError::BadInput(e.to_string()))
            }
        }
    }
}

/// Reads the input: a bag (its LaserScan or PointCloud2 topic), a directory with velodyne
/// scans (a KITTI sequence or an NCLT session) or else an image folder, a file a CARMEN log.
/// `max_frames` keeps the first frames only.
pub fn read_input(
    path: &Path,
    source: &SourceArgs,
    max_frames: Option<usize>,
) -> Result<Input, Failure> {
    let mut input = if is_bag(path) {
        match source.open_bag(path).map_err(Failure::input)? {
            BagSource::Planar(frames) => read_planar(path, frames, "LaserScan messages")?,
            BagSource::Sweeps(sequence) => read_sweeps(path, *sequence),
        }
    } else if path.is_dir() {
        let has = |p: &str| path.join(p).exists();
        if has("velodyne") || has("velodyne_sync") || has("sequences") {
            let sequence = source.open_sweeps(path).map_err(Failure::input)?;
            read_sweeps(path, sequence)
        } else {
            read_images(path)?
        }
    } else {
        let frames = source.open_planar(path).map_err(Failure::input)?;
        let kind = match source.laser {
            Laser::Front => "CARMEN front-laser scans",
            Laser::Rear => "CARMEN rear-laser scans",
            Laser::Any => "CARMEN laser scans",
        };
        let input = read_planar(path, frames, kind)?;
        if input.labels.is_empty() {
            return Err(Failure::input(format!(
                "{}: no laser scans ({})",
                path.display(),
                source.laser_lines()
            )));
        }
        input
    };
    input.total = input.labels.len();
    if let Some(n) = max_frames {
        input.labels.truncate(n);
        if let Some(t) = &mut input.times {
            t.truncate(n);
        }
        if let Some(p) = &mut input.poses {
            p.truncate(n);
        }
    }
    if input.labels.is_empty() {
        return Err(Failure::input(format!("{}: no frames", path.display())));
    }
    Ok(input)
}

fn read_planar(
    path: &Path,
    source: Box<dyn PlanarSource>,
    kind: &'static str,
) -> Result<Input, Failure> {
    let frames: Vec<PlanarFrame> = source
        .collect::<raypath_io::Result<_>>()
        .map_err(Failure::input)?;
    let times: Vec<f64> = frames.iter().map(|f| f.stamp_secs).collect();
    let times = times.iter().all(|t| t.is_finite()).then_some(times);
    let poses = reference_track(&frames)
        .into_iter()
        .map(|p| p.map(|p| p.to_pose3()))
        .collect();
    let scans: Vec<Scan2> = frames.into_iter().map(|f| f.scan).collect();
    Ok(Input {
        path: path.to_path_buf(),
        labels: (0..scans.len()).collect(),
        poses: Some(poses),
        source: Source::Planar(scans),
        kind,
        times,
        total: 0,
        image_size: None,
    })
}

fn read_sweeps(path: &Path, sequence: SweepSequence) -> Input {
    let kind = match sequence.format {
        SweepFormat::Kitti => "KITTI velodyne scans",
        SweepFormat::Nclt => "NCLT velodyne scans",
        SweepFormat::Bag => "PointCloud2 sweeps",
        SweepFormat::Ouster => "Ouster sweeps",
    };
    let labels = frame_numbers(&sequence);
    let poses = sweep_poses(&sequence).map(|(poses, _)| poses.iter().copied().map(Some).collect());
    Input {
        path: path.to_path_buf(),
        times: Some(sequence.stamps_secs.clone()),
        labels,
        poses,
        kind,
        source: Source::Sweeps(Box::new(sequence)),
        total: 0,
        image_size: None,
    }
}

/// The number of each sweep: its KITTI frame number (from its file name), else its index.
fn frame_numbers(sequence: &SweepSequence) -> Vec<usize> {
    let indices = || (0..sequence.len()).collect();
    if sequence.format != SweepFormat::Kitti {
        return indices();
    }
    // TODO(raypath-io): `SweepSequence` does not expose KITTI frame numbers yet; the scan
    // list (a directory listing, no scan is read) gives them.
    match raypath_io::kitti::KittiSequence::open(&sequence.name) {
        Ok(listing) if listing.scan_files.len() == sequence.len() => listing
            .scan_files
            .iter()
            .map(|f| usize::try_from(f.frame).unwrap_or(usize::MAX))
            .collect(),
        _ => indices(),
    }
}

/// Reads a folder of PNG/JPEG images (`raypath_io::images`).
pub fn read_images(path: &Path) -> Result<Input, Failure> {
    let folder = ImageFolder::open(path).map_err(|e| {
        Failure::input(format!(
            "{e} (the input is neither a KITTI sequence (velodyne/*.bin), an NCLT session \
             (velodyne_sync/*.bin), a rosbag2 bag nor a folder of PNG/JPEG images)"
        ))
    })?;
    let times: Option<Vec<f64>> = folder.files().iter().map(|f| stamp_of(f)).collect();
    Ok(Input {
        path: path.to_path_buf(),
        labels: (0..folder.len()).collect(),
        total: folder.len(),
        source: Source::Images(folder),
        poses: None,
        kind: "images",
        times,
        image_size: None,
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
