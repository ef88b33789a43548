//! Conversion between CARMEN logs, the KITTI layout, Ouster captures, PCD files and rosbag2 recordings
//! (`raypath convert <in> <out>`), so the public benchmark logs become bags and back.
//!
//! | from \ to | CARMEN | KITTI layout | PCD | rosbag2 |
//! |---|---|---|---|---|
//! | CARMEN log | ✓ (laser choice) | | | LaserScan + Odometry + tf |
//! | rosbag2 with LaserScan | ✓ | | | ✓ (topic choice) |
//! | KITTI sequence / NCLT session | | ✓ | one file per sweep | PointCloud2 + tf + reference |
//! | rosbag2 with PointCloud2 | | ✓ | one file per sweep | ✓ |
//! | Ouster capture (`.pcap` + metadata JSON) | | ✓ | one file per frame | PointCloud2 + tf + reference |
//! | PCD file | | one frame | ✓ | one PointCloud2 |
//!
//! * **CARMEN out**: `FLASER` lines when a scan's beams follow the default fan of its beam
//!   count (180 beams over π from −π/2, …; see [`crate::carmen::FanConvention`]), so a log
//!   converted to a bag and back reads like the original; `ROBOTLASER1` lines (which carry
//!   the angles) otherwise. The laser pose is `world_from_laser`, the odometry pose
//!   `world_from_robot`; both timestamps are the scan stamp. Numbers are written in their
//!   shortest lossless form.
//! * **KITTI out**: `velodyne/NNNNNN.bin` (x y z reflectance; 0 without intensity),
//!   `times.txt`, and with reference poses `poses.txt` beside a `calib.txt` whose `Tr` is the
//!   identity (the lidar poses are written as they are; no camera is implied).
//! * **rosbag2 out**: see [`crate::rosbag::write_planar`] and [`crate::rosbag::write_sweeps`].

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use raypath_geometry::{PointCloud, Pose3};
use serde::Serialize;

use crate::Format;
use crate::carmen::{CarmenWriter, FanConvention, LaserKind, LaserMessage, NumberFormat};
use crate::error::{Error, Location, Result};
use crate::kitti::{self, KittiCalib};
use crate::pcd::{self, DataEncoding};
use crate::rosbag::{self, BagWriteOptions};
use crate::sequence::{
    PlanarFrame, PlanarOptions, SweepFormat, SweepOptions, SweepSequence, read_planar,
};

/// What to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Target {
    /// A CARMEN log (plain text).
    Carmen,
    /// A KITTI sequence directory.
    Kitti,
    /// A PCD file (one sweep) or a directory of PCD files (one per sweep).
    Pcd,
    /// A rosbag2 recording: a `.mcap` file, or a bag directory with `metadata.yaml`.
    Rosbag2,
}

impl std::str::FromStr for Target {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "carmen" => Ok(Target::Carmen),
            "kitti" => Ok(Target::Kitti),
            "pcd" => Ok(Target::Pcd),
            "rosbag2" | "bag" | "mcap" => Ok(Target::Rosbag2),
            other => Err(format!("{other:?}: expected carmen, kitti, pcd or rosbag2")),
        }
    }
}

/// Options of [`convert`].
#[derive(Clone, Debug, Default)]
pub struct ConvertOptions {
    /// The output format; `None`: from the output path (`.mcap` → rosbag2, `.pcd` → PCD,
    /// `.log`/`.clf` → CARMEN, a directory → KITTI for 3-D input and a bag for planar input).
    pub target: Option<Target>,
    /// How to read planar input (laser choice, bag topics).
    pub planar: PlanarOptions,
    /// How to read 3-D input (bag topics).
    pub sweeps: SweepOptions,
    /// Bag compression and chunk size.
    pub bag: BagWriteOptions,
}

/// What [`convert`] did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConvertReport {
    /// The input format (`carmen`, `kitti`, `nclt`, `pcd`, `rosbag2`).
    pub from: String,
    /// The output format.
    pub to: Target,
    /// Scans or sweeps written.
    pub frames: usize,
    /// Frames that carried a reference pose.
    pub reference_poses: usize,
    /// The file or directory written.
    pub output: PathBuf,
}

enum Input {
    Planar(Vec<PlanarFrame>),
    Spatial(Box<SweepSequence>),
}

/// Converts `input` to `output` (module docs).
pub fn convert(input: &Path, output: &Path, options: &ConvertOptions) -> Result<ConvertReport> {
    let format = Format::detect(input)?;
    let data = read_input(input, format, options)?;
    let target = match options.target {
        Some(t) => t,
        None => target_from_path(output, matches!(data, Input::Planar(_)))?,
    };
    let (frames, reference_poses) = match &data {
        Input::Planar(f) => (f.len(), f.iter().filter(|f| f.reference.is_some()).count()),
        Input::Spatial(s) => (s.len(), s.reference.as_ref().map_or(0, Vec::len)),
    };
    let written = match (data, target) {
        (Input::Planar(frames), Target::Carmen) => write_carmen(output, &frames)?,
        (Input::Planar(frames), Target::Rosbag2) => {
            rosbag::write_planar(output, &frames, &options.bag)?
        }
        (Input::Spatial(sweeps), Target::Rosbag2) => {
            rosbag::write_sweeps(output, &sweeps, &options.bag)?
        }
        (Input::Spatial(sweeps), Target::Kitti) => write_kitti(output, &sweeps)?,
        (Input::Spatial(sweeps), Target::Pcd) => write_pcds(output, &sweeps)?,
        (Input::Planar(_), t) => {
            return Err(unsupported(
                input,
                format!("planar scans cannot be written as {t:?}"),
            ));
        }
        (Input::Spatial(_), Target::Carmen) => {
            return Err(unsupported(
                input,
                "3-D sweeps cannot be written as a CARMEN log".into(),
            ));
        }
    };
    Ok(ConvertReport {
        from: format.name().into(),
        to: target,
        frames,
        reference_poses,
        output: written,
    })
}

fn unsupported(path: &Path, reason: String) -> Error {
    Error::UnknownFormat {
        path: path.to_path_buf(),
        reason,
    }
}

fn read_input(input: &Path, format: Format, options: &ConvertOptions) -> Result<Input> {
    match format {
        Format::Carmen => Ok(Input::Planar(read_planar(input, &options.planar)?)),
        Format::KittiSequence | Format::NcltSession | Format::OusterPcap => Ok(Input::Spatial(
            Box::new(SweepSequence::open(input, &options.sweeps)?),
        )),
        Format::Pcd => {
            let pcd = pcd::read_pcd(input, &pcd::ReadOptions::default())?;
            let cloud = pcd.cloud;
            let sequence = SweepSequence::from_fn(
                &input.display().to_string(),
                SweepFormat::Kitti,
                vec![0.0],
                Some(vec![pcd.cloud_from_sensor]),
                None,
                Box::new(move |_| Ok(cloud.clone())),
            )?;
            Ok(Input::Spatial(Box::new(sequence)))
        }
        Format::Rosbag2 => read_bag(input, options),
        other => Err(unsupported(
            input,
            format!(
                "{} files cannot be converted; inputs are CARMEN logs, KITTI sequences, NCLT \
                 sessions, Ouster captures (.pcap), PCD files and rosbag2 recordings",
                other.name()
            ),
        )),
    }
}

/// A bag is planar when a scan topic is named or it has LaserScans and no PointCloud2.
fn read_bag(input: &Path, options: &ConvertOptions) -> Result<Input> {
    let topics = &options.planar.topics;
    let sweep_topics = &options.sweeps.topics;
    let info = rosbag::info(input)?;
    let has = |t: &str| info.topics.iter().any(|x| x.type_name == t);
    let scans = has("sensor_msgs/msg/LaserScan");
    let clouds = has("sensor_msgs/msg/PointCloud2");
    let planar = topics.scan.is_some() || (scans && (!clouds || sweep_topics.cloud.is_none()));
    if planar && scans {
        Ok(Input::Planar(read_planar(input, &options.planar)?))
    } else if clouds {
        Ok(Input::Spatial(Box::new(SweepSequence::open(
            input,
            &options.sweeps,
        )?)))
    } else {
        Err(unsupported(
            input,
            "the bag has no sensor_msgs/msg/LaserScan or sensor_msgs/msg/PointCloud2 topic".into(),
        ))
    }
}

fn target_from_path(output: &Path, planar: bool) -> Result<Target> {
    let name = output
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let stem = name
        .strip_suffix(".gz")
        .or_else(|| name.strip_suffix(".bz2"))
        .unwrap_or(&name);
    Ok(if stem.ends_with(".mcap") {
        Target::Rosbag2
    } else if stem.ends_with(".pcd") {
        Target::Pcd
    } else if stem.ends_with(".log") || stem.ends_with(".clf") {
        Target::Carmen
    } else if output.extension().is_none() {
        if planar {
            Target::Rosbag2
        } else {
            Target::Kitti
        }
    } else {
        return Err(unsupported(
            output,
            "cannot tell the output format from the name: use .mcap, .log, .pcd, a directory, \
             or say --to carmen|kitti|pcd|rosbag2"
                .into(),
        ));
    })
}

/// True when the scan's beams follow the default fan of an old-format (FLASER) line.
fn default_fan(frame: &PlanarFrame) -> bool {
    let n = frame.scan.ranges.len();
    let (min, increment) = FanConvention::default().layout(n, PI, None);
    (frame.scan.angle_min_rad - min).abs() < 1e-9
        && (frame.scan.angle_increment_rad - increment).abs() < 1e-9
}

/// Writes planar frames as a CARMEN log (`FLASER` lines when the beams follow the default
/// fan, `ROBOTLASER1` otherwise) with lossless numbers ([`NumberFormat::exact`]): the frames'
/// `world_from_laser` and `world_from_robot` become the logged poses, so frames with corrected
/// poses give a corrected log. Returns the path written.
pub fn write_carmen(path: &Path, frames: &[PlanarFrame]) -> Result<PathBuf> {
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, Location::File, e))?;
    let mut writer =
        CarmenWriter::with_format(std::io::BufWriter::new(file), path, NumberFormat::exact());
    writer.header()?;
    writer.comment("written by raypath convert")?;
    for frame in frames {
        let kind = if default_fan(frame) {
            LaserKind::Front
        } else {
            LaserKind::RobotLaser1
        };
        writer.laser(&LaserMessage {
            kind,
            scan: frame.scan.clone(),
            world_from_laser: frame.world_from_laser,
            world_from_robot: frame.world_from_robot,
            velocities: None,
            robot_laser: None,
            ipc_timestamp_secs: frame.ipc_stamp_secs.unwrap_or(frame.stamp_secs),
            hostname: "raypath".into(),
            logger_timestamp_secs: frame.stamp_secs,
            line: 0,
        })?;
    }
    writer.finish()?;
    Ok(path.to_path_buf())
}

fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, Location::File, e))
}

fn write_kitti(dir: &Path, sweeps: &SweepSequence) -> Result<PathBuf> {
    let velodyne = dir.join("velodyne");
    create_dir(&velodyne)?;
    for sweep in sweeps.sweeps() {
        let (i, cloud) = sweep?;
        kitti::write_velodyne(&velodyne.join(format!("{i:06}.bin")), &cloud)?;
    }
    kitti::write_times(&dir.join("times.txt"), &sweeps.stamps_secs)?;
    if let Some(poses) = &sweeps.reference {
        kitti::write_calib(
            &dir.join("calib.txt"),
            &KittiCalib::odometry(&[], &Pose3::identity()),
        )?;
        kitti::write_poses(&dir.join("poses.txt"), poses)?;
    }
    Ok(dir.to_path_buf())
}

fn write_pcds(output: &Path, sweeps: &SweepSequence) -> Result<PathBuf> {
    let single = output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pcd"));
    if single {
        if sweeps.len() != 1 {
            return Err(unsupported(
                output,
                format!(
                    "{} sweeps do not fit one PCD file: give a directory",
                    sweeps.len()
                ),
            ));
        }
        let cloud: PointCloud = sweeps.sweep(0)?;
        pcd::write_pcd(output, &cloud, DataEncoding::Binary)?;
        return Ok(output.to_path_buf());
    }
    create_dir(output)?;
    for sweep in sweeps.sweeps() {
        let (i, cloud) = sweep?;
        pcd::write_pcd(
            &output.join(format!("{i:06}.pcd")),
            &cloud,
            DataEncoding::Binary,
        )?;
    }
    Ok(output.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_follow_the_output_name() {
        let t = |p: &str, planar| target_from_path(Path::new(p), planar).ok();
        assert_eq!(t("out.mcap", true), Some(Target::Rosbag2));
        assert_eq!(t("out.log", false), Some(Target::Carmen));
        assert_eq!(t("out.clf.gz", true), Some(Target::Carmen));
        assert_eq!(t("scan.pcd", false), Some(Target::Pcd));
        assert_eq!(t("seq00", false), Some(Target::Kitti));
        assert_eq!(t("bagdir", true), Some(Target::Rosbag2));
        assert_eq!(t("out.txt", true), None);
    }
}
