//! The readers under test: for each, its seeds, extra tokens for the mutator, and how a
//! mutated input is fed to it (the in-memory entry point where there is one, else a file in
//! the case's scratch directory).

use std::io::Cursor;
use std::path::{Path, PathBuf};

use anyhow::Result;
use raypath_io::carmen::{CarmenConfig, CarmenReader, FanConvention, NoReturnRange, Record};
use raypath_io::nclt::HitsReader;
use raypath_io::octomap::ScanGraphReader;
use raypath_io::ouster::{OusterOptions, OusterReader, SensorInfo, XyzLut};
use raypath_io::pcd::{LabelSource, ReadOptions};
use raypath_io::point_csv::{PointCsv, PointCsvReader};
use raypath_io::sequence::{SweepSequence, Topics};
use raypath_io::xyz::XyzReader;
use raypath_io::{
    Error, Location, kitti, lzw, nclt, octomap, pcd, poles_csv, relations, rosbag, segcomp, tum,
};

use raypath_io::samples::{self, Sample};

/// What one case came to.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// The reader accepted the input.
    Ok,
    /// The reader refused it with an error naming the file; `whole_file` when the error names
    /// no line or byte.
    Err {
        /// No line or byte named.
        whole_file: bool,
        /// The error as printed.
        message: String,
    },
    /// The reader refused it with an error that names another file or a place outside the
    /// input: a failure, like a panic.
    Bad(String),
}

/// One mutated input as a reader sees it.
pub struct Input<'a> {
    /// Index of the seed it was made from.
    pub seed: usize,
    /// The file name (errors must name it).
    pub name: &'a str,
    /// The bytes.
    pub bytes: &'a [u8],
    /// Random bits for options.
    pub variant: u64,
    /// An empty directory of this case, for readers that need a file.
    pub dir: Option<&'a Path>,
}

type ReadFn = Box<dyn Fn(&Input<'_>) -> Verdict + Send + Sync>;

/// A reader under test.
pub struct Target {
    /// Name on the command line and in the table.
    pub name: &'static str,
    /// The entry points exercised.
    pub reads: &'static str,
    /// Valid inputs to mutate.
    pub seeds: Vec<Sample>,
    /// Tokens the mutator writes or inserts (format keywords added to the common ones).
    pub tokens: Vec<&'static [u8]>,
    /// True when inputs go through a file (the case gets a scratch directory).
    pub needs_file: bool,
    /// Feeds one input to the reader.
    pub read: ReadFn,
}

impl Target {
    fn new(
        name: &'static str,
        reads: &'static str,
        seeds: Vec<Sample>,
        tokens: &[&'static [u8]],
        read: impl Fn(&Input<'_>) -> Verdict + Send + Sync + 'static,
    ) -> Self {
        let mut all: Vec<&'static [u8]> = super::mutate::COMMON_TOKENS.to_vec();
        all.extend_from_slice(tokens);
        Self {
            name,
            reads,
            seeds,
            tokens: all,
            needs_file: false,
            read: Box::new(read),
        }
    }

    fn with_file(mut self) -> Self {
        self.needs_file = true;
        self
    }
}

/// Collects the errors of a case and judges them: each must name one of `names` and, when
/// it names the input itself and `plain` (offsets are offsets of the input), a line or byte
/// inside it.
pub struct Check {
    names: Vec<PathBuf>,
    len: u64,
    lines: u64,
    plain: bool,
    verdict: Verdict,
}

impl Check {
    fn new(input: &Input<'_>, name: impl Into<PathBuf>, plain: bool) -> Self {
        let lines = input.bytes.iter().filter(|&&b| b == b'\n').count() as u64 + 1;
        Self {
            names: vec![name.into()],
            len: input.bytes.len() as u64,
            lines,
            plain,
            verdict: Verdict::Ok,
        }
    }

    /// Also accepts errors naming `name` (a second file the reader was given).
    fn or_naming(mut self, name: impl Into<PathBuf>) -> Self {
        self.names.push(name.into());
        self
    }

    fn record(&mut self, verdict: Verdict) {
        let rank = |v: &Verdict| match v {
            Verdict::Ok => 0,
            Verdict::Err {
                whole_file: true, ..
            } => 1,
            Verdict::Err {
                whole_file: false, ..
            } => 2,
            Verdict::Bad(_) => 3,
        };
        if rank(&verdict) > rank(&self.verdict) {
            self.verdict = verdict;
        }
    }

    /// Judges an error of the crate.
    fn error(&mut self, e: &Error) {
        let Some(k) = self.names.iter().position(|n| n == e.path()) else {
            let names: Vec<String> = self.names.iter().map(|n| n.display().to_string()).collect();
            return self.record(Verdict::Bad(format!(
                "the error names {} instead of {}: {e}",
                e.path().display(),
                names.join(" or ")
            )));
        };
        let inside = !self.plain || k > 0;
        let verdict = match e.location() {
            Location::File => Verdict::Err {
                whole_file: true,
                message: e.to_string(),
            },
            Location::Byte(at) if !inside && at > self.len => Verdict::Bad(format!(
                "the error names byte {at} of a {}-byte input: {e}",
                self.len
            )),
            Location::Line(0) => Verdict::Bad(format!("the error names line 0: {e}")),
            // The line after the last is where an unexpected end of file is.
            Location::Line(line)
                if !inside
                    && line > self.lines + u64::from(matches!(e, Error::Truncated { .. })) =>
            {
                Verdict::Bad(format!(
                    "the error names line {line} of a {}-line input: {e}",
                    self.lines
                ))
            }
            _ => Verdict::Err {
                whole_file: false,
                message: e.to_string(),
            },
        };
        self.record(verdict);
    }

    /// The value of `r`, judging its error.
    fn ok<T>(&mut self, r: raypath_io::Result<T>) -> Option<T> {
        r.map_err(|e| self.error(&e)).ok()
    }

    /// Judges an error that is a byte offset in the input (CDR, LZW).
    fn offset<T>(&mut self, r: Result<T, (u64, String)>) -> Option<T> {
        match r {
            Ok(v) => Some(v),
            Err((at, reason)) => {
                self.record(if at > self.len {
                    Verdict::Bad(format!(
                        "the error names byte {at} of a {}-byte input: {reason}",
                        self.len
                    ))
                } else {
                    Verdict::Err {
                        whole_file: false,
                        message: format!("byte {at}: {reason}"),
                    }
                });
                None
            }
        }
    }

    /// Takes the failures (not the errors) of `other`.
    fn merge_bad(&mut self, other: Check) {
        if let Verdict::Bad(_) = other.verdict {
            self.record(other.verdict);
        }
    }

    fn verdict(self) -> Verdict {
        self.verdict
    }
}

/// Iterates `items` (at most `max`), judging errors; stops at the first error.
fn drain<T>(check: &mut Check, items: impl Iterator<Item = raypath_io::Result<T>>, max: usize) {
    for item in items.take(max) {
        if check.ok(item).is_none() {
            break;
        }
    }
}

fn cursor(input: &Input<'_>) -> Cursor<Vec<u8>> {
    Cursor::new(input.bytes.to_vec())
}

/// Writes the input to `name` in the case's directory.
fn file(input: &Input<'_>) -> PathBuf {
    let dir = input.dir.unwrap_or_else(|| Path::new("."));
    let path = dir.join(input.name);
    if let Err(e) = std::fs::write(&path, input.bytes) {
        panic!("fuzz harness: cannot write {}: {e}", path.display());
    }
    path
}

const CARMEN_TOKENS: &[&[u8]] = &[
    b"FLASER",
    b"RLASER",
    b"ROBOTLASER1",
    b"ODOM",
    b"PARAM",
    b"TRUEPOS",
    b"81.91",
    b"laser_front_laser_resolution",
    b"laser_front_laser_fov",
    b"robot_front_laser_max",
    b"laser_front_laser_flipped",
    b"1000000000",
];
const KITTI_TOKENS: &[&[u8]] = &[
    b"P0:",
    b"Tr:",
    b"R:",
    b"T:",
    b"Tr_velo_to_cam:",
    b"e+",
    b"e-0",
];
const CSV_TOKENS: &[&[u8]] = &[b"x", b"y", b"z", b"w", b"width", b"score", b",,", b"utime"];
const PCD_TOKENS: &[&[u8]] = &[
    b"FIELDS",
    b"SIZE",
    b"TYPE",
    b"COUNT",
    b"WIDTH",
    b"HEIGHT",
    b"POINTS",
    b"VIEWPOINT",
    b"DATA",
    b"ascii",
    b"binary",
    b"binary_compressed",
    b"label",
    b"rgb",
    b"intensity",
    b"F",
    b"U",
    b"I",
    b"8",
    b"4",
    b"2",
];
const OCTOMAP_TOKENS: &[&[u8]] = &[
    b"# Octomap OcTree binary file",
    b"id",
    b"size",
    b"res",
    b"data",
    b"OcTree",
    b"ColorOcTree",
];
const JSON_TOKENS: &[&[u8]] = &[
    b"{",
    b"}",
    b"[",
    b"]",
    b":",
    b"null",
    b"true",
    b"[]",
    b"{}",
    b"\"\"",
    b"1e999",
    b"-5",
    b"8192",
    b"513",
    b"65536",
    b"\"LEGACY\"",
    b"\"RNG15_RFL8_NIR8\"",
    b"\"FUSA_RNG15_RFL8_NIR8_DUAL\"",
    b"\"header_type\": \"FUSA\"",
    b"\\u0000",
    b"\\",
];
const SEGCOMP_TOKENS: &[&[u8]] = &[
    b"rows",
    b"columns",
    b"P5",
    b"P2",
    b"65535",
    b"\x59\xa6\x6a\x95",
    b"\x80",
];
const YAML_TOKENS: &[&[u8]] = &[
    b"storage_identifier:",
    b"relative_file_paths:",
    b"- ",
    b"[a, b]",
    b"'",
    b"mcap",
    b"  ",
];

/// Every reader, in table order.
pub fn all(scratch: &Path) -> Result<Vec<Target>> {
    let mut targets = vec![
        Target::new(
            "carmen",
            "carmen::CarmenReader::with_config (look-ahead, fan, no-return and strictness varied)",
            samples::carmen()?,
            CARMEN_TOKENS,
            |input| {
                let v = input.variant;
                let config = CarmenConfig {
                    lookahead_scans: [1, 2, 3, 1000][(v & 3) as usize],
                    strict: v & 4 != 0,
                    fan: FanConvention::ALL[((v >> 3) & 3) as usize],
                    no_return: if v & 32 != 0 {
                        NoReturnRange::Fixed(30.0)
                    } else {
                        NoReturnRange::Infer
                    },
                    ..CarmenConfig::default()
                };
                let mut check = Check::new(input, input.name, true);
                if let Some(reader) =
                    check.ok(CarmenReader::with_config(cursor(input), input.name, config))
                {
                    for record in reader {
                        match check.ok(record) {
                            Some(Record::Laser(laser)) => {
                                let _ = laser.scan.points(laser.world_from_laser).count();
                            }
                            Some(_) => {}
                            None => break,
                        }
                    }
                }
                check.verdict()
            },
        ),
        Target::new(
            "kitti-velodyne",
            "kitti::parse_velodyne",
            samples::kitti_velodyne()?,
            &[],
            |input| {
                let mut check = Check::new(input, input.name, true);
                if let Some(cloud) = check.ok(kitti::parse_velodyne(input.bytes, input.name)) {
                    let _ = cloud.bounding_box();
                }
                check.verdict()
            },
        ),
        Target::new(
            "kitti-labels",
            "kitti::parse_labels, count_classes",
            samples::kitti_labels(),
            &[],
            |input| {
                let mut check = Check::new(input, input.name, true);
                if let Some(labels) = check.ok(kitti::parse_labels(input.bytes, input.name)) {
                    let _ = kitti::count_classes(&labels);
                }
                check.verdict()
            },
        ),
        Target::new(
            "kitti-poses",
            "kitti::parse_poses",
            samples::kitti_poses()?,
            KITTI_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                check.ok(kitti::parse_poses(cursor(input), input.name));
                check.verdict()
            },
        ),
        Target::new(
            "kitti-times",
            "kitti::parse_times",
            samples::kitti_times()?,
            KITTI_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                check.ok(kitti::parse_times(cursor(input), input.name));
                check.verdict()
            },
        ),
        Target::new(
            "kitti-calib",
            "kitti::parse_calib, cam0_from_velo, projection",
            samples::kitti_calib()?,
            KITTI_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                if let Some(calib) = check.ok(kitti::parse_calib(cursor(input), input.name)) {
                    let _ = calib.cam0_from_velo();
                    for camera in 0..4 {
                        let _ = calib.projection(camera);
                    }
                }
                check.verdict()
            },
        ),
        Target::new(
            "nclt-sync",
            "nclt::parse_velodyne_sync",
            samples::nclt_sync()?,
            &[],
            |input| {
                let mut check = Check::new(input, input.name, true);
                if let Some(mut cloud) =
                    check.ok(nclt::parse_velodyne_sync(input.bytes, input.name))
                {
                    nclt::flu_from_frd(&mut cloud);
                }
                check.verdict()
            },
        ),
        Target::new(
            "nclt-hits",
            "nclt::HitsReader (packets or headers only; length known or not)",
            samples::nclt_hits(),
            &[],
            |input| {
                let mut check = Check::new(input, input.name, true);
                let len = (input.variant & 1 != 0).then_some(input.bytes.len() as u64);
                let mut reader = HitsReader::new(input.bytes, input.name, len);
                if input.variant & 2 != 0 {
                    for _ in 0..1000 {
                        match check.ok(reader.next_header_skip_points()) {
                            Some(Some(_)) => {}
                            _ => break,
                        }
                    }
                } else {
                    drain(&mut check, reader, 1000);
                }
                check.verdict()
            },
        ),
        Target::new(
            "nclt-pose-csv",
            "nclt::parse_pose_csv, NcltPose::world_from_body",
            samples::nclt_pose_csv()?,
            CSV_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                if let Some(table) = check.ok(nclt::parse_pose_csv(cursor(input), input.name)) {
                    for pose in &table.poses {
                        let _ = pose.world_from_body();
                    }
                    let _ = (table.time_span(), table.bbox());
                }
                check.verdict()
            },
        ),
        Target::new(
            "nclt-covariance",
            "nclt::parse_covariance",
            samples::nclt_covariance()?,
            CSV_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                check.ok(nclt::parse_covariance(cursor(input), input.name));
                check.verdict()
            },
        ),
        Target::new(
            "octomap-bt",
            "octomap::parse_bt (BtReader), OcTree::bounding_box",
            samples::octomap_bt()?,
            OCTOMAP_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                if let Some(tree) = check.ok(octomap::parse_bt(input.bytes, input.name)) {
                    let _ = (tree.bounding_box(true), tree.occupied_leaves());
                }
                check.verdict()
            },
        ),
        Target::new(
            "octomap-graph",
            "octomap::parse_graph, ScanGraphReader (node by node, read_edges)",
            samples::octomap_graph()?,
            &[],
            |input| {
                let mut check = Check::new(input, input.name, true);
                match input.variant % 3 {
                    0 => {
                        check.ok(octomap::parse_graph(input.bytes, input.name));
                    }
                    1 => {
                        let len = Some(input.bytes.len() as u64);
                        if let Some(reader) =
                            check.ok(ScanGraphReader::new(input.bytes, input.name, len))
                        {
                            drain(&mut check, reader, 1000);
                        }
                    }
                    _ => {
                        if let Some(mut reader) =
                            check.ok(ScanGraphReader::new(input.bytes, input.name, None))
                            && let Some(Some(_)) = reader.next().map(|n| check.ok(n))
                        {
                            check.ok(reader.read_edges());
                        }
                    }
                }
                check.verdict()
            },
        ),
        Target::new(
            "pcd",
            "pcd::read_pcd_bytes (every label source)",
            samples::pcd()?,
            PCD_TOKENS,
            |input| {
                let label_from = match input.variant % 4 {
                    0 => LabelSource::LabelField,
                    1 => LabelSource::Intensity,
                    2 => LabelSource::Field("w".into()),
                    _ => LabelSource::None,
                };
                let options = ReadOptions { label_from };
                let mut check = Check::new(input, input.name, true);
                if let Some(read) = check.ok(pcd::read_pcd_bytes(input.bytes, input.name, &options))
                {
                    let _ = read.cloud.bounding_box();
                }
                check.verdict()
            },
        ),
        Target::new(
            "rosbag",
            "rosbag::info, rosbag::open_planar or SweepSequence::open + sweep (one a case; a file)",
            samples::rosbag_bags(scratch)?,
            &[],
            |input| {
                let path = file(input);
                let mut check = Check::new(input, &path, true);
                // One entry point a case: each starts worker threads, the cost of a case.
                match input.variant % 3 {
                    0 => {
                        check.ok(rosbag::info(&path));
                    }
                    1 => {
                        if let Some(scans) =
                            check.ok(rosbag::open_planar(&path, &Topics::default()))
                        {
                            drain(&mut check, scans, 100);
                        }
                    }
                    _ => {
                        if let Some(sweeps) =
                            check.ok(SweepSequence::open(&path, &Default::default()))
                        {
                            for i in 0..sweeps.len().min(100) {
                                if check.ok(sweeps.sweep(i)).is_none() {
                                    break;
                                }
                            }
                        }
                    }
                }
                check.verdict()
            },
        )
        .with_file(),
        Target::new(
            "rosbag-cdr",
            "rosbag::decode_scan/cloud/odometry/tf/pose_stamped (each input through all five)",
            samples::rosbag_cdr(),
            &[],
            |input| {
                let cdr = |r: Result<(), rosbag::cdr::CdrError>| {
                    r.map_err(|e| (e.offset as u64, e.reason))
                };
                let results = [
                    cdr(rosbag::decode_scan(input.bytes).map(|_| ())),
                    cdr(rosbag::decode_cloud(input.bytes).map(|_| ())),
                    cdr(rosbag::decode_odometry(input.bytes).map(|_| ())),
                    cdr(rosbag::decode_tf(input.bytes).map(|_| ())),
                    cdr(rosbag::decode_pose_stamped(input.bytes).map(|_| ())),
                ];
                let mut check = Check::new(input, input.name, true);
                for (k, result) in results.into_iter().enumerate() {
                    if k == input.seed {
                        check.offset(result);
                    } else {
                        let mut other = Check::new(input, input.name, true);
                        other.offset(result);
                        check.merge_bad(other);
                    }
                }
                check.verdict()
            },
        ),
        ouster_pcap()?,
        ouster_json()?,
        Target::new(
            "segcomp-range",
            "segcomp::parse_range_image",
            samples::segcomp_range()?,
            SEGCOMP_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                check.ok(segcomp::parse_range_image(input.bytes, input.name));
                check.verdict()
            },
        ),
        Target::new(
            "segcomp-gt-seg",
            "segcomp::parse_gt_seg (Sun raster, PGM, raw), labels",
            samples::segcomp_gt_seg()?,
            SEGCOMP_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                if let Some(seg) = check.ok(segcomp::parse_gt_seg(input.bytes, input.name)) {
                    let _ = (seg.distinct_labels(), seg.plane_labels());
                }
                check.verdict()
            },
        ),
        Target::new(
            "segcomp-gt-ang",
            "segcomp::parse_gt_ang",
            samples::segcomp_gt_ang(),
            SEGCOMP_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                check.ok(segcomp::parse_gt_ang(cursor(input), input.name));
                check.verdict()
            },
        ),
        Target::new(
            "lzw",
            "lzw::decompress (Unix compress .Z)",
            samples::lzw(),
            &[
                b"\x1f\x9d\x90",
                b"\x1f\x9d\x10",
                b"\x1f\x9d\x8c",
                b"\x00\x01",
            ],
            |input| {
                let mut check = Check::new(input, input.name, true);
                check.offset(
                    lzw::decompress(input.bytes, 1 << 20).map_err(|e| (e.offset, e.reason)),
                );
                check.verdict()
            },
        ),
        Target::new(
            "point-csv",
            "point_csv::PointCsv::parse, PointCsvReader::next_row",
            samples::point_csv(),
            CSV_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                if input.variant & 1 == 0 {
                    if let Some(csv) = check.ok(PointCsv::parse(cursor(input), input.name)) {
                        let _ = (csv.points(), csv.column("x"));
                    }
                } else if let Some(mut reader) =
                    check.ok(PointCsvReader::new(cursor(input), input.name))
                {
                    while let Some(Some(_)) = check.ok(reader.next_row()) {}
                }
                check.verdict()
            },
        ),
        Target::new(
            "poles-csv",
            "poles_csv::parse_pole_csv",
            samples::poles_csv()?,
            CSV_TOKENS,
            |input| {
                let mut check = Check::new(input, input.name, true);
                check.ok(poles_csv::parse_pole_csv(cursor(input), input.name));
                check.verdict()
            },
        ),
        Target::new(
            "relations",
            "relations::parse_relations",
            samples::relations(),
            &[],
            |input| {
                let mut check = Check::new(input, input.name, true);
                check.ok(relations::parse_relations(cursor(input), input.name));
                check.verdict()
            },
        ),
        Target::new("tum", "tum::parse_tum", samples::tum(), &[], |input| {
            let mut check = Check::new(input, input.name, true);
            check.ok(tum::parse_tum(cursor(input), input.name));
            check.verdict()
        }),
        Target::new(
            "xyz",
            "xyz::read_xyz_from, XyzReader::next_chunk",
            samples::xyz(),
            &[],
            |input| {
                let mut check = Check::new(input, input.name, true);
                if input.variant & 1 == 0 {
                    check.ok(raypath_io::xyz::read_xyz_from(cursor(input), input.name));
                } else {
                    let mut reader = XyzReader::new(cursor(input), input.name);
                    let mut chunk = Vec::new();
                    while let Some(n) = check.ok(reader.next_chunk(3, &mut chunk)) {
                        if n == 0 {
                            break;
                        }
                    }
                }
                check.verdict()
            },
        ),
        Target::new(
            "rosbag-metadata",
            "rosbag::Metadata::parse (metadata.yaml)",
            samples::rosbag_metadata(),
            YAML_TOKENS,
            |input| {
                let _ = rosbag::Metadata::parse(&String::from_utf8_lossy(input.bytes));
                Verdict::Ok
            },
        ),
        Target::new(
            "summarize",
            "Format::detect + summarize of a file (every single-file format; gzip, bzip2, .Z)",
            samples::named_files()?,
            CARMEN_TOKENS,
            |input| {
                let path = file(input);
                let mut check = Check::new(input, &path, false);
                check.ok(raypath_io::summarize(&path));
                check.verdict()
            },
        )
        .with_file(),
    ];
    targets.sort_by_key(|t| ORDER.iter().position(|n| *n == t.name));
    Ok(targets)
}

/// Table order: by crate module.
const ORDER: [&str; 28] = [
    "carmen",
    "kitti-velodyne",
    "kitti-labels",
    "kitti-poses",
    "kitti-times",
    "kitti-calib",
    "nclt-sync",
    "nclt-hits",
    "nclt-pose-csv",
    "nclt-covariance",
    "octomap-bt",
    "octomap-graph",
    "pcd",
    "rosbag",
    "rosbag-cdr",
    "rosbag-metadata",
    "ouster-pcap",
    "ouster-json",
    "segcomp-range",
    "segcomp-gt-seg",
    "segcomp-gt-ang",
    "lzw",
    "point-csv",
    "poles-csv",
    "relations",
    "tum",
    "xyz",
    "summarize",
];

/// Ouster captures, each read with the metadata it was made for.
fn ouster_pcap() -> Result<Target> {
    let sensors = samples::ouster_sensors();
    let mut infos = Vec::new();
    let mut captures = Vec::new();
    for (k, sensor) in sensors.iter().enumerate() {
        let info = SensorInfo::parse(sensor.json.as_bytes(), format!("sensor-{k}.json"))?;
        let name = match sensor.capture {
            samples::Capture::Pcapng => "fuzz.pcapng",
            _ => "fuzz.pcap",
        };
        captures.push(Sample::new(
            name,
            samples::ouster_capture(&info, sensor.capture),
        ));
        let lut = XyzLut::new(&info)?;
        infos.push((info, lut));
    }
    Ok(Target::new(
        "ouster-pcap",
        "ouster::OusterReader over pcap/pcapng (sensor ids checked or not), XyzLut::cloud",
        captures,
        &[
            b"\xd4\xc3\xb2\xa1",
            b"\x0a\x0d\x0d\x0a",
            b"\x08\x00\x45\x00",
            b"\x1e\x4e",
        ],
        move |input| {
            let (info, lut) = &infos[input.seed];
            let options = OusterOptions {
                check_sensor_ids: input.variant & 1 == 0,
                ..OusterOptions::default()
            };
            // Errors about the metadata name its file.
            let mut check = Check::new(input, input.name, true).or_naming(&info.source);
            if let Some(reader) =
                check.ok(OusterReader::new(cursor(input), input.name, info, options))
            {
                for frame in reader.take(64) {
                    let Some(frame) = check.ok(frame) else { break };
                    check.ok(lut.cloud(&frame));
                }
            }
            check.verdict()
        },
    ))
}

/// Ouster metadata; what parses reads the capture made for the seed's sensor.
fn ouster_json() -> Result<Target> {
    let sensors = samples::ouster_sensors();
    let mut jsons = Vec::new();
    let mut captures = Vec::new();
    for (k, sensor) in sensors.iter().enumerate() {
        let info = SensorInfo::parse(sensor.json.as_bytes(), format!("sensor-{k}.json"))?;
        captures.push(samples::ouster_capture(&info, sensor.capture));
        jsons.push(Sample::new("fuzz.json", sensor.json.clone()));
    }
    Ok(Target::new(
        "ouster-json",
        "ouster::SensorInfo::parse, then XyzLut::new and OusterReader with it",
        jsons,
        JSON_TOKENS,
        move |input| {
            let mut check = Check::new(input, input.name, true);
            if let Some(info) = check.ok(SensorInfo::parse(input.bytes, input.name)) {
                let lut = check.ok(XyzLut::new(&info));
                let mut capture = Check::new(input, "capture.pcap", false).or_naming(input.name);
                let reader = OusterReader::new(
                    Cursor::new(captures[input.seed].clone()),
                    "capture.pcap",
                    &info,
                    OusterOptions::default(),
                );
                if let Some(reader) = capture.ok(reader) {
                    for frame in reader.take(8) {
                        let Some(frame) = capture.ok(frame) else {
                            break;
                        };
                        if let Some(lut) = &lut {
                            capture.ok(lut.cloud(&frame));
                        }
                    }
                }
                check.merge_bad(capture);
            }
            check.verdict()
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(bytes: &[u8]) -> Input<'_> {
        Input {
            seed: 0,
            name: "in.txt",
            bytes,
            variant: 0,
            dir: None,
        }
    }

    #[test]
    fn errors_must_name_the_file_and_a_place_inside_it() {
        let bytes = b"a\nb";
        let judge = |e: Error| {
            let mut check = Check::new(&input(bytes), "in.txt", true);
            check.error(&e);
            check.verdict()
        };
        let place = |v: &Verdict| match v {
            Verdict::Err { whole_file, .. } => Some(*whole_file),
            _ => None,
        };
        assert_eq!(
            place(&judge(Error::malformed("in.txt", Location::Line(2), "x"))),
            Some(false)
        );
        assert_eq!(
            place(&judge(Error::malformed("in.txt", Location::Byte(3), "x"))),
            Some(false)
        );
        assert_eq!(
            place(&judge(Error::malformed("in.txt", Location::File, "x"))),
            Some(true)
        );
        // The end of file may be named as the line after the last.
        assert_eq!(
            place(&judge(Error::truncated("in.txt", Location::Line(3), "x"))),
            Some(false)
        );
        for bad in [
            Error::malformed("other.txt", Location::Line(1), "x"),
            Error::malformed("in.txt", Location::Line(0), "x"),
            Error::malformed("in.txt", Location::Line(3), "x"),
            Error::truncated("in.txt", Location::Line(4), "x"),
            Error::truncated("in.txt", Location::Byte(4), "x"),
        ] {
            assert!(matches!(judge(bad), Verdict::Bad(_)));
        }
        // A second file's errors are judged by name only; the worst verdict wins.
        let mut check = Check::new(&input(bytes), "in.txt", true).or_naming("meta.json");
        check.error(&Error::malformed("meta.json", Location::Line(99), "x"));
        assert!(matches!(check.verdict, Verdict::Err { .. }));
        check.error(&Error::malformed("x.json", Location::Line(1), "x"));
        check.error(&Error::malformed("in.txt", Location::Line(1), "x"));
        assert!(matches!(check.verdict(), Verdict::Bad(_)));
    }

    #[test]
    fn every_reader_reads_its_seeds() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let targets = all(dir.path()).unwrap_or_else(|e| panic!("{e:#}"));
        assert_eq!(targets.len(), ORDER.len());
        for target in &targets {
            assert!(!target.seeds.is_empty(), "{}", target.name);
            for (k, seed) in target.seeds.iter().enumerate() {
                let case_dir = dir.path().join(format!("{}-{k}", target.name));
                std::fs::create_dir_all(&case_dir).unwrap_or_else(|e| panic!("{e}"));
                let input = Input {
                    seed: k,
                    name: &seed.name,
                    bytes: &seed.bytes,
                    variant: 0,
                    dir: Some(&case_dir),
                };
                assert_eq!(
                    (target.read)(&input),
                    Verdict::Ok,
                    "{} seed {k}",
                    target.name
                );
            }
        }
    }
}
