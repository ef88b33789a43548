//! Format detection: from a path to the reader that understands it.

use std::fmt;
use std::path::Path;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::summary::Summary;
use crate::{carmen, kitti, nclt, octomap, ouster, pcd, point_csv, segcomp, source, xyz};

/// The file formats and directory layouts raypath reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Format {
    /// CARMEN log (`.log`, `.clf`; plain, gzip or bzip2).
    Carmen,
    /// Point Cloud Library PCD (ascii, binary, binary_compressed).
    Pcd,
    /// Plain text points, one `x y z` per line.
    Xyz,
    /// OctoMap binary occupancy tree (`.bt`).
    OctomapBt,
    /// OctoMap ScanGraph (`.graph`).
    OctomapGraph,
    /// A KITTI odometry sequence directory (`velodyne/`, `poses.txt`, `times.txt`, `calib.txt`).
    KittiSequence,
    /// One KITTI velodyne scan (`.bin`, float32 x y z reflectance).
    KittiVelodyne,
    /// KITTI poses (12 numbers a line, row-major 3×4).
    KittiPoses,
    /// KITTI timestamps (one number a line, seconds).
    KittiTimes,
    /// KITTI calibration (`P0: …`, `Tr: …`).
    KittiCalib,
    /// An NCLT session directory (`velodyne_data/`, `ground_truth/`, `sensor_data/`).
    NcltSession,
    /// One NCLT `velodyne_sync/<utime>.bin` revolution.
    NcltVelodyneSync,
    /// The NCLT raw `velodyne_hits.bin` packet stream.
    NcltVelodyneHits,
    /// NCLT `groundtruth_<date>.csv`.
    NcltGroundTruth,
    /// NCLT `odometry_mu*.csv`.
    NcltOdometry,
    /// NCLT `cov_<date>.csv` or `odometry_cov*.csv`.
    NcltCovariance,
    /// SegComp Perceptron range image (`perc.train.N`, `perc.test.N`).
    SegcompRange,
    /// SegComp ground-truth segmentation raster (`.gt-seg`).
    SegcompGtSeg,
    /// SegComp ground-truth angles between adjacent planes (`.gt-ang`).
    SegcompGtAng,
    /// CSV of points with a header row (`x,y[,z][,…]`), such as pole maps.
    PointCsv,
    /// A rosbag2 recording with MCAP storage: its directory (with `metadata.yaml`) or its
    /// `.mcap` file.
    Rosbag2,
    /// Ouster lidar packets in a pcap/pcapng capture, with the sensor's metadata JSON beside
    /// it (found by [`ouster::find_metadata`]).
    OusterPcap,
    /// Ouster OSF recording (`.osf`): recognized, not read.
    OusterOsf,
}

impl Format {
    /// Every format, in documentation order.
    pub const ALL: [Format; 23] = [
        Format::Carmen,
        Format::Pcd,
        Format::Xyz,
        Format::OctomapBt,
        Format::OctomapGraph,
        Format::KittiSequence,
        Format::KittiVelodyne,
        Format::KittiPoses,
        Format::KittiTimes,
        Format::KittiCalib,
        Format::NcltSession,
        Format::NcltVelodyneSync,
        Format::NcltVelodyneHits,
        Format::NcltGroundTruth,
        Format::NcltOdometry,
        Format::NcltCovariance,
        Format::SegcompRange,
        Format::SegcompGtSeg,
        Format::SegcompGtAng,
        Format::PointCsv,
        Format::Rosbag2,
        Format::OusterPcap,
        Format::OusterOsf,
    ];

    /// The format with this [`Format::name`].
    pub fn from_name(name: &str) -> Option<Format> {
        Format::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The name printed by `raypath info` and used as the JSON `format` value.
    pub fn name(self) -> &'static str {
        match self {
            Format::Carmen => "carmen",
            Format::Pcd => "pcd",
            Format::Xyz => "xyz",
            Format::OctomapBt => "octomap-bt",
            Format::OctomapGraph => "octomap-graph",
            Format::KittiSequence => "kitti",
            Format::KittiVelodyne => "kitti-velodyne",
            Format::KittiPoses => "kitti-poses",
            Format::KittiTimes => "kitti-times",
            Format::KittiCalib => "kitti-calib",
            Format::NcltSession => "nclt",
            Format::NcltVelodyneSync => "nclt-velodyne-sync",
            Format::NcltVelodyneHits => "nclt-velodyne-hits",
            Format::NcltGroundTruth => "nclt-groundtruth",
            Format::NcltOdometry => "nclt-odometry",
            Format::NcltCovariance => "nclt-covariance",
            Format::SegcompRange => "segcomp-range",
            Format::SegcompGtSeg => "segcomp-gt-seg",
            Format::SegcompGtAng => "segcomp-gt-ang",
            Format::PointCsv => "point-csv",
            Format::Rosbag2 => "rosbag2",
            Format::OusterPcap => "ouster-pcap",
            Format::OusterOsf => "ouster-osf",
        }
    }

    /// Recognizes the format of a file or directory from its name, its place and its first
    /// bytes (decompressed).
    pub fn detect(path: &Path) -> Result<Format> {
        let meta =
            std::fs::metadata(path).map_err(|e| Error::io(path, crate::Location::File, e))?;
        if crate::rosbag::is_bag(path)? {
            return Ok(Format::Rosbag2);
        }
        if meta.is_dir() {
            return detect_dir(path);
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let parent = path
            .parent()
            .and_then(Path::file_name)
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let head = source::peek(path, 4096)?;
        let text = String::from_utf8_lossy(&head);
        let stem = strip_compression_suffix(&name);

        if head.starts_with(b"# Octomap OcTree binary file") {
            return Ok(Format::OctomapBt);
        }
        if ouster::is_osf(path, &head) {
            return Ok(Format::OusterOsf);
        }
        if ouster::is_capture_name(path)
            || (ouster::is_capture_head(&head) && !stem.ends_with(".bin"))
        {
            ouster::find_metadata(path)?;
            return Ok(Format::OusterPcap);
        }
        if head.len() >= 8 && u64::from_le_bytes(head_8(&head)) == nclt::HITS_MAGIC {
            return Ok(Format::NcltVelodyneHits);
        }
        if stem.ends_with(".graph") {
            return Ok(Format::OctomapGraph);
        }
        if stem.ends_with(".pcd") || is_pcd_header(&text) {
            return Ok(Format::Pcd);
        }
        if stem.ends_with(".gt-seg") {
            return Ok(Format::SegcompGtSeg);
        }
        if stem.ends_with(".gt-ang") {
            return Ok(Format::SegcompGtAng);
        }
        if is_segcomp_range_name(stem) {
            return Ok(Format::SegcompRange);
        }
        if stem.ends_with(".bin") {
            return Ok(if parent == "velodyne_sync" {
                Format::NcltVelodyneSync
            } else {
                Format::KittiVelodyne
            });
        }
        if stem.starts_with("groundtruth_") && stem.ends_with(".csv") {
            return Ok(Format::NcltGroundTruth);
        }
        if stem.starts_with("odometry_mu") && stem.ends_with(".csv") {
            return Ok(Format::NcltOdometry);
        }
        if (stem.starts_with("cov_") || stem.starts_with("odometry_cov")) && stem.ends_with(".csv")
        {
            return Ok(Format::NcltCovariance);
        }
        if stem.ends_with(".log") || stem.ends_with(".clf") || is_carmen_text(&text) {
            return Ok(Format::Carmen);
        }
        if stem == "calib.txt" || text.starts_with("P0:") {
            return Ok(Format::KittiCalib);
        }
        if stem.ends_with(".csv") && is_point_csv_header(&text) {
            return Ok(Format::PointCsv);
        }
        if head
            .iter()
            .any(|&b| b == 0 || (b >= 0x80 && std::str::from_utf8(&head).is_err()))
        {
            return Err(Error::UnknownFormat {
                path: path.to_path_buf(),
                reason: format!("unrecognized binary file; {}", SUPPORTED),
            });
        }
        match numeric_columns(&text) {
            Some(12) if stem.contains("pose") || !stem.ends_with(".csv") => Ok(Format::KittiPoses),
            Some(1) => Ok(Format::KittiTimes),
            Some(3) => Ok(Format::Xyz),
            _ => Err(Error::UnknownFormat {
                path: path.to_path_buf(),
                reason: format!("unrecognized text file; {}", SUPPORTED),
            }),
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

const SUPPORTED: &str = "raypath reads CARMEN logs (.log/.clf[.gz|.bz2]), PCD, OctoMap .bt/.graph, \
    x y z text, KITTI and NCLT directories and files, SegComp range and ground-truth files, \
    point CSVs with an x,y header, and Ouster pcap captures with their metadata JSON";

/// Reads a file that holds one point cloud: a KITTI velodyne `.bin`, a PCD file or an `x y z`
/// text file (what `raypath register` and the Python package's `raypath.open` read as a single
/// scan). Any other format is an [`Error::UnknownFormat`] that names it and says what is read.
pub fn read_cloud(path: &Path) -> Result<raypath_geometry::PointCloud> {
    match Format::detect(path)? {
        Format::KittiVelodyne => kitti::read_velodyne(path),
        Format::Pcd => Ok(pcd::read_pcd(path, &Default::default())?.cloud),
        Format::Xyz => xyz::read_xyz(path),
        other => Err(Error::UnknownFormat {
            path: path.to_path_buf(),
            reason: format!(
                "a {} is not a single scan; give a KITTI .bin, a PCD file or an x y z list",
                other.name()
            ),
        }),
    }
}

/// Summarizes a file or directory of any supported format (what `raypath info` prints).
pub fn summarize(path: &Path) -> Result<Summary> {
    let format = Format::detect(path)?;
    summarize_as(path, format)
}

/// Summarizes a file or directory read as `format`.
pub fn summarize_as(path: &Path, format: Format) -> Result<Summary> {
    match format {
        Format::Carmen => carmen::summarize(path),
        Format::Pcd => pcd::summarize(path),
        Format::Xyz => xyz::summarize(path),
        Format::OctomapBt => octomap::summarize_bt(path),
        Format::OctomapGraph => octomap::summarize_graph(path),
        Format::KittiSequence
        | Format::KittiVelodyne
        | Format::KittiPoses
        | Format::KittiTimes
        | Format::KittiCalib => kitti::summarize(path, format),
        Format::NcltSession
        | Format::NcltVelodyneSync
        | Format::NcltVelodyneHits
        | Format::NcltGroundTruth
        | Format::NcltOdometry
        | Format::NcltCovariance => nclt::summarize(path, format),
        Format::SegcompRange | Format::SegcompGtSeg | Format::SegcompGtAng => {
            segcomp::summarize(path, format)
        }
        Format::PointCsv => point_csv::summarize(path),
        Format::Rosbag2 => bag_summary(path),
        Format::OusterPcap => ouster::summarize(path),
        Format::OusterOsf => Err(ouster::osf_unsupported(path)),
    }
}

/// A bag's summary: LaserScan and PointCloud2 messages as scans, PoseStamped as poses,
/// Odometry as odometry, the log-time span, and per topic its type, count and rate under
/// `topics` (with `profile`, `storage`, `compression`, `indexed`, `file_size_bytes`,
/// `warnings`).
fn bag_summary(path: &Path) -> Result<Summary> {
    let info = crate::rosbag::info(path)?;
    let count = |types: &[&str]| -> Option<u64> {
        let n: u64 = info
            .topics
            .iter()
            .filter(|t| types.contains(&t.type_name.as_str()))
            .map(|t| t.message_count)
            .sum();
        (n > 0).then_some(n)
    };
    let mut summary = Summary {
        format: Format::Rosbag2.name().into(),
        scans: count(&["sensor_msgs/msg/LaserScan", "sensor_msgs/msg/PointCloud2"]),
        poses: count(&["geometry_msgs/msg/PoseStamped"]),
        odometry: count(&["nav_msgs/msg/Odometry"]),
        time_span: match (info.start_secs, info.end_secs) {
            (Some(start), Some(end)) => Some(crate::TimeSpan {
                start,
                end,
                duration: end - start,
            }),
            _ => None,
        },
        ..Summary::default()
    };
    let mut put = |key: &str, value: serde_json::Value| {
        summary.extra.insert(key.into(), value);
    };
    put("profile", info.profile.clone().into());
    put("storage", info.storage.clone().into());
    put("compression", info.compression.clone().into());
    put("indexed", info.indexed.into());
    put("file_size_bytes", info.file_size_bytes.into());
    put("messages", info.message_count.into());
    put(
        "topics",
        serde_json::to_value(&info.topics).unwrap_or_default(),
    );
    if !info.warnings.is_empty() {
        put("warnings", info.warnings.clone().into());
    }
    Ok(summary)
}

fn detect_dir(path: &Path) -> Result<Format> {
    let has = |name: &str| path.join(name).exists();
    if has("velodyne_sync")
        || has("velodyne_data")
        || has("ground_truth")
        || has("sensor_data")
        || has("velodyne_hits.bin")
        || dir_has_prefix(path, "groundtruth_")
        || !nclt::session_dirs(path).is_empty()
    {
        return Ok(Format::NcltSession);
    }
    if has("velodyne")
        || has("poses.txt")
        || has("times.txt")
        || has("calib.txt")
        || kitti::is_dataset_root(path)
    {
        return Ok(Format::KittiSequence);
    }
    Err(Error::UnknownFormat {
        path: path.to_path_buf(),
        reason:
            "directory is neither a KITTI sequence (velodyne/, poses.txt, times.txt, calib.txt) \
                 nor an NCLT session (velodyne_sync/, velodyne_data/, ground_truth/, sensor_data/)"
                .into(),
    })
}

fn dir_has_prefix(path: &Path, prefix: &str) -> bool {
    std::fs::read_dir(path).is_ok_and(|entries| {
        entries
            .flatten()
            .any(|e| e.file_name().to_string_lossy().starts_with(prefix))
    })
}

fn head_8(head: &[u8]) -> [u8; 8] {
    let mut bytes = [0u8; 8];
    bytes.copy_from_slice(&head[..8]);
    bytes
}

fn strip_compression_suffix(name: &str) -> &str {
    for suffix in [".gz", ".bz2", ".z"] {
        if let Some(stem) = name.strip_suffix(suffix) {
            return stem;
        }
    }
    name
}

fn is_segcomp_range_name(stem: &str) -> bool {
    let mut parts = stem.split('.');
    matches!(
        (parts.next(), parts.next(), parts.next(), parts.next()),
        (Some(_), Some("train" | "test"), Some(n), None) if n.parse::<u32>().is_ok()
    )
}

fn is_pcd_header(text: &str) -> bool {
    text.lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .is_some_and(|l| l.starts_with("VERSION") || l.starts_with("FIELDS"))
}

fn is_carmen_text(text: &str) -> bool {
    const TAGS: [&str; 8] = [
        "FLASER ",
        "RLASER ",
        "ROBOTLASER1 ",
        "ODOM ",
        "PARAM ",
        "RAWLASER",
        "TRUEPOS ",
        "# message formats",
    ];
    text.lines()
        .take(50)
        .any(|l| TAGS.iter().any(|t| l.starts_with(t)))
}

fn is_point_csv_header(text: &str) -> bool {
    text.lines().next().is_some_and(|h| {
        let cols: Vec<_> = h
            .split(',')
            .map(|c| c.trim().to_ascii_lowercase())
            .collect();
        cols.len() >= 2 && cols[0] == "x" && cols[1] == "y"
    })
}

/// The number of whitespace-separated numeric columns when the first non-empty lines agree.
fn numeric_columns(text: &str) -> Option<usize> {
    let mut columns = None;
    for line in text.lines().filter(|l| !l.trim().is_empty()).take(5) {
        let fields: Vec<_> = line.split_whitespace().collect();
        if fields.iter().any(|f| f.parse::<f64>().is_err()) {
            return None;
        }
        match columns {
            None => columns = Some(fields.len()),
            Some(n) if n != fields.len() => return None,
            Some(_) => {}
        }
    }
    columns
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for format in Format::ALL {
            assert_eq!(Format::from_name(format.name()), Some(format));
        }
    }

    #[test]
    fn recognizes_segcomp_names() {
        assert!(is_segcomp_range_name("perc.test.23"));
        assert!(is_segcomp_range_name("abw.train.0"));
        assert!(!is_segcomp_range_name("perc.test.23.gt-seg"));
        assert!(!is_segcomp_range_name("poses.txt"));
    }

    #[test]
    fn recognizes_text_headers() {
        assert!(is_pcd_header("# comment\nVERSION .7\nFIELDS x y z\n"));
        assert!(is_carmen_text(
            "# hello\nFLASER 3 1 2 3 0 0 0 0 0 0 1.0 host 1.0\n"
        ));
        assert!(is_point_csv_header("x,y,w\n1,2,3\n"));
        assert_eq!(numeric_columns("1 2 3\n4 5 6\n"), Some(3));
        assert_eq!(numeric_columns("1 2 3\n4 5\n"), None);
    }
}
