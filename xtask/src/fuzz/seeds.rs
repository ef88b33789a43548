//! Small valid inputs for every reader, written with the crate's own writers where it has them
//! (CARMEN, KITTI, NCLT, OctoMap, PCD, rosbag2, pole CSV) and by hand otherwise (Ouster
//! captures and metadata, SegComp rasters, TUM, x y z, CSV). `.Z` streams are the reference
//! files made by ncompress in `crates/io/tests/data/`. Sizes are kept small: the cost of a
//! case grows with its input, and small inputs let a mutation reach every field.

use std::io::Cursor;
use std::path::Path;

use anyhow::{Context, Result};
use nalgebra::{Matrix6, Point3};
use raypath_geometry::testing::workloads::SplitMix64;
use raypath_geometry::{PointCloud, Pose3, Scan2};
use raypath_io::carmen::{CarmenReader, CarmenWriter};
use raypath_io::nclt::{CovarianceRecord, NcltPose};
use raypath_io::octomap::{OcTree, OctreeLeaf, ScanEdge, ScanGraph, ScanNode, TREE_DEPTH};
use raypath_io::ouster::SensorInfo;
use raypath_io::pcd::{self, DataEncoding, WriteOptions};
use raypath_io::poles_csv::{PoleRecord, write_pole_csv_to};
use raypath_io::rosbag::{self, BagCompression, BagWriteOptions, BagWriter, Stamp, Transform};
use raypath_io::{kitti, lzw, nclt, octomap};

/// One seed input and the file name it is read under (errors must name it).
#[derive(Clone, Debug)]
pub struct Seed {
    /// The file name given to the reader.
    pub name: String,
    /// The input.
    pub bytes: Vec<u8>,
}

impl Seed {
    pub fn new(name: impl Into<String>, bytes: impl Into<Vec<u8>>) -> Self {
        Self {
            name: name.into(),
            bytes: bytes.into(),
        }
    }
}

/// A CARMEN log with every message type the reader knows (and two it does not).
pub const CARMEN_LOG: &str = "\
# CARMEN Logfile
PARAM laser_front_laser_resolution 1 0.0 nohost 0
PARAM robot_front_laser_max 30.5 1000.0 host 0.001
PARAM laser_front_laser_flipped 0 nohost 0
ODOM 1.0 2.0 0.5 0.3 -0.1 0.0 1000.25 host 0.25
FLASER 4 1.0 2.0 81.91 4.0 10.0 20.0 1.57 10.5 20.5 1.6 1000.5 robby 0.5
FLASER 4 1.5 81.91 3.0 4.5 10.1 20.0 1.57 10.6 20.5 1.6 1000.6 robby 0.6
RLASER 3 1.0 31.0 2.0 0.0 0.0 0.0 0.0 0.0 0.0 1000.6 robby 0.6
NEFF 27.6 0 pippo 0
ROBOTLASER1 0 -1.0 2.0 1.0 81.9 0.01 1 3 5.0 81.91 6.0 3 100 200 300 1.0 0.0 0.0 0.8 0.0 0.0 0.25 0.1 0.5 0.3 0.2 1000.75 robby 0.75
TRUEPOS 1 2 3 4 5 6 7 h 8
";

/// The hand-written log, and the same records as [`CarmenWriter`] writes them.
pub fn carmen() -> Result<Vec<Seed>> {
    let records = CarmenReader::new(Cursor::new(CARMEN_LOG.as_bytes().to_vec()), "seed.log")
        .collect::<raypath_io::Result<Vec<_>>>()?;
    let mut writer = CarmenWriter::new(Vec::new(), "seed.log");
    writer.header()?;
    for record in &records {
        writer.record(record)?;
    }
    Ok(vec![
        Seed::new("fuzz.log", CARMEN_LOG),
        Seed::new("fuzz.log", writer.finish()?),
    ])
}

/// A small cloud with intensities.
fn cloud(n: usize) -> PointCloud {
    let mut cloud = PointCloud::from_points(
        (0..n)
            .map(|i| Point3::new(i as f32 * 0.75 - 3.0, 2.0 - 0.5 * i as f32, 0.25 * i as f32))
            .collect(),
    );
    cloud.intensity = Some((0..n).map(|i| (i % 5) as f32 * 0.2).collect());
    cloud
}

pub fn kitti_velodyne() -> Result<Vec<Seed>> {
    let name = Path::new("000000.bin");
    Ok(vec![
        Seed::new("000000.bin", kitti::encode_velodyne(&cloud(12), name)?),
        Seed::new("000000.bin", kitti::encode_velodyne(&cloud(1), name)?),
    ])
}

pub fn kitti_labels() -> Vec<Seed> {
    let labels: Vec<u8> = [
        0u32,
        1,
        10,
        40,
        44 | 3 << 16,
        252 | 7 << 16,
        99,
        0xffff_ffff,
    ]
    .iter()
    .flat_map(|v| v.to_le_bytes())
    .collect();
    vec![Seed::new("000000.label", labels)]
}

fn poses() -> Vec<Pose3> {
    (0..3)
        .map(|k| {
            let k = f64::from(k);
            Pose3::from_xyz_rpy(k, -0.5 * k, 0.1, 0.01 * k, -0.02, 0.3 * k)
        })
        .collect()
}

pub fn kitti_poses() -> Result<Vec<Seed>> {
    let mut written = Vec::new();
    kitti::write_poses_to(&mut written, &poses(), Path::new("00.txt"))?;
    let hand = "1 0 0 0 0 1 0 0 0 0 1 0\n\
        9.999978e-01 5.272628e-04 -2.066935e-03 -4.690294e-02 -5.296506e-04 9.999992e-01 \
        -1.154865e-03 -2.839928e-02 2.066324e-03 1.155958e-03 9.999971e-01 8.586941e-01\n\
        0 0 1 5 0 1 0 6 -1 0 0 7\n";
    Ok(vec![
        Seed::new("00.txt", written),
        Seed::new("00.txt", hand),
    ])
}

pub fn kitti_times() -> Result<Vec<Seed>> {
    let mut written = Vec::new();
    kitti::write_times_to(
        &mut written,
        &[0.0, 0.1037359, 0.2073381],
        Path::new("times.txt"),
    )?;
    Ok(vec![Seed::new("times.txt", written)])
}

const KITTI_CALIB: &str = "P0: 7.188560000000e+02 0 6.071928e+02 0 0 7.188560e+02 1.852157e+02 0 0 0 1 0\n\
    P1: 7.188560000000e+02 0 6.071928e+02 -3.861448e+02 0 7.188560e+02 1.852157e+02 0 0 0 1 0\n\
    Tr: 4.276802e-04 -9.999672e-01 -8.084491e-03 -1.198459e-02 -7.210626e-03 8.081198e-03 \
    -9.999413e-01 -5.403984e-02 9.999739e-01 4.859485e-04 -7.206982e-03 -2.921968e-01\n";

pub fn kitti_calib() -> Result<Vec<Seed>> {
    let calib = kitti::parse_calib(Cursor::new(KITTI_CALIB.as_bytes().to_vec()), "calib.txt")?;
    let mut written = Vec::new();
    kitti::write_calib_to(&mut written, &calib, Path::new("calib.txt"))?;
    let raw = "calib_time: 15-Mar-2012 11:37:16\n\
        R: 7.533745e-03 -9.999714e-01 -6.166020e-04 1.480249e-02 7.280733e-04 -9.998902e-01 \
        9.998621e-01 7.523790e-03 1.480755e-02\n\
        T: -4.069766e-03 -7.631618e-02 -2.717806e-01\n";
    Ok(vec![
        Seed::new("calib.txt", written),
        Seed::new("calib_velo_to_cam.txt", raw),
    ])
}

pub fn nclt_sync() -> Result<Vec<Seed>> {
    let mut c = cloud(10);
    c.label = Some((0..10).map(|i| i * 3).collect());
    c.intensity = Some((0..10).map(|i| (i * 25) as f32).collect());
    Ok(vec![Seed::new(
        "1326030975726043.bin",
        nclt::encode_velodyne_sync(&c, Path::new("1326030975726043.bin"))?,
    )])
}

/// A `velodyne_hits.bin` packet stream: packets of `counts[i]` hits.
pub fn nclt_hits() -> Vec<Seed> {
    let stream = |counts: &[u16]| {
        let mut bytes = Vec::new();
        for (i, &n) in counts.iter().enumerate() {
            bytes.extend_from_slice(&nclt::HITS_MAGIC.to_le_bytes());
            bytes.extend_from_slice(&u32::from(n).to_le_bytes());
            bytes.extend_from_slice(&(1_326_030_975_726_043 + i as u64).to_le_bytes());
            bytes.extend_from_slice(&[0xee; 4]);
            for k in 0..n {
                for v in [20000 + k, 20000, 20000 - k] {
                    bytes.extend_from_slice(&v.to_le_bytes());
                }
                bytes.extend_from_slice(&[k as u8, (k % 32) as u8]);
            }
        }
        bytes
    };
    vec![
        Seed::new("velodyne_hits.bin", stream(&[3, 0, 5])),
        Seed::new("velodyne_hits.bin", stream(&[1])),
    ]
}

pub fn nclt_pose_csv() -> Result<Vec<Seed>> {
    let poses: Vec<NcltPose> = poses()
        .iter()
        .enumerate()
        .map(|(i, p)| NcltPose::from_world_from_body(1_326_030_975_726_043 + 10_000 * i as u64, p))
        .collect();
    let mut written = Vec::new();
    nclt::write_pose_csv_to(
        &mut written,
        &poses,
        Path::new("groundtruth_2012-01-08.csv"),
    )?;
    let hand = "utime,x,y,z,roll,pitch,yaw\n\
        1326030975726043,1.0,2.0,3.0,0.0,0.0,0.0\n\
        1326030975736043,nan,nan,nan,nan,nan,nan\n\
        1326030975746043,4.0,5.0,-6.0,0.01,-0.02,1.5707963267948966\n";
    Ok(vec![
        Seed::new("groundtruth_2012-01-08.csv", written),
        Seed::new("groundtruth_2012-01-08.csv", hand),
    ])
}

pub fn nclt_covariance() -> Result<Vec<Seed>> {
    let records: Vec<CovarianceRecord> = (0..2u32)
        .map(|k| CovarianceRecord {
            utime: 1_326_030_975_726_043 + u64::from(k),
            matrix: Matrix6::from_fn(|r, c| {
                if r == c {
                    0.5 + f64::from(k)
                } else {
                    0.01 * (r + c) as f64
                }
            }),
        })
        .collect();
    let mut written = Vec::new();
    nclt::write_covariance_csv_to(&mut written, &records, Path::new("cov_2012-01-08.csv"))?;
    Ok(vec![Seed::new("cov_2012-01-08.csv", written)])
}

/// A tree of a few finest-level leaves and a few coarse ones (in separate octants), and a
/// coarse-only tree.
pub fn octomap_bt() -> Result<Vec<Seed>> {
    let mut rng = SplitMix64(11);
    let mut leaves: Vec<OctreeLeaf> = Vec::new();
    let mut taken = std::collections::HashSet::new();
    let res = 0.1;
    for i in 0..24 {
        let depth = if i % 4 == 0 { 12 } else { TREE_DEPTH };
        let span = 1u16 << (TREE_DEPTH - depth);
        let base: u16 = if depth == TREE_DEPTH { 32768 } else { 0 };
        let key = [0; 3].map(|_: u16| base + (rng.next_u64() % 8) as u16 * span);
        if !taken.insert((key, depth)) {
            continue;
        }
        let span_f = f64::from(span);
        let center = key.map(|k| (f64::from(k) - 32768.0 + span_f / 2.0) * res);
        leaves.push(OctreeLeaf {
            center: Point3::from(center),
            size_m: span_f * res,
            occupied: rng.next_u64() % 2 == 0,
            depth,
            key_min: key,
        });
    }
    let tree = |leaves: Vec<OctreeLeaf>| OcTree {
        id: "OcTree".into(),
        resolution_m: res,
        nodes_in_file: 0,
        inner_nodes: 0,
        leaves,
    };
    let mut fine = Vec::new();
    octomap::write_bt(&mut fine, &tree(leaves), Path::new("fuzz.bt"))?;
    // Root: child 0 free, child 1 occupied, child 7 inner with child 5 occupied.
    let mut coarse = b"# Octomap OcTree binary file\nid OcTree\nsize 5\nres 0.5\ndata\n".to_vec();
    coarse.extend_from_slice(&[0b0000_1001, 0b1100_0000, 0, 0b0000_1000]);
    Ok(vec![
        Seed::new("fuzz.bt", fine),
        Seed::new("fuzz.bt", coarse),
    ])
}

pub fn octomap_graph() -> Result<Vec<Seed>> {
    let nodes: Vec<ScanNode> = (0..3u32)
        .map(|id| ScanNode {
            id,
            world_from_sensor: Pose3::from_xyz_rpy(
                f64::from(id),
                2.0,
                0.5,
                0.1,
                -0.2,
                0.3 * f64::from(id),
            ),
            points: PointCloud::from_points(
                (0..2 + id)
                    .map(|i| Point3::new(i as f32 * 0.5, -(id as f32), 1.25 + i as f32))
                    .collect(),
            ),
        })
        .collect();
    let edges = vec![ScanEdge {
        first_id: 0,
        second_id: 2,
        first_from_second: nodes[0].world_from_sensor.inverse() * nodes[2].world_from_sensor,
        weight: 1.0,
    }];
    let mut bytes = Vec::new();
    octomap::write_graph(
        &mut bytes,
        &ScanGraph { nodes, edges },
        Path::new("fuzz.graph"),
    )?;
    Ok(vec![Seed::new("fuzz.graph", bytes)])
}

/// Every encoding of a small organized cloud with labels, colour and NaN points, and an
/// ASCII file with exotic fields.
pub fn pcd() -> Result<Vec<Seed>> {
    let n = 6;
    let cloud = PointCloud {
        points: (0..n)
            .map(|i| {
                if i % 5 == 3 {
                    Point3::new(f32::NAN, f32::NAN, f32::NAN)
                } else {
                    Point3::new(i as f32, -0.5 * i as f32, 2.0)
                }
            })
            .collect(),
        intensity: Some((0..n).map(|i| (i % 4) as f32 + 10.0).collect()),
        label: Some((0..n).map(|i| i as u32 * 3).collect()),
        rgb: Some((0..n).map(|i| i as u32 * 0x010203).collect()),
        width: 3,
        height: 2,
    };
    let mut seeds = Vec::new();
    for encoding in DataEncoding::ALL {
        let mut bytes = Vec::new();
        pcd::write_pcd_to(
            &mut bytes,
            &cloud,
            Path::new("fuzz.pcd"),
            &WriteOptions::new(encoding),
        )?;
        seeds.push(Seed::new("fuzz.pcd", bytes));
    }
    seeds.push(Seed::new(
        "fuzz.pcd",
        "VERSION .7\nFIELDS x y z w _ label\nSIZE 8 4 4 2 1 2\nTYPE F F F I U U\n\
         COUNT 1 1 1 2 3 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n\
         1.5 2 3 -1 4 0 0 0 7\nnan nan nan 0 0 1 1 1 8\n-2 1e3 0 5 5 2 2 2 9\n",
    ));
    Ok(seeds)
}

/// Small bags (uncompressed, zstd, LZ4 chunks) with tf, odometry, poses, scans and clouds.
pub fn rosbag_bags(dir: &Path) -> Result<Vec<Seed>> {
    let mut seeds = Vec::new();
    for compression in [
        BagCompression::None,
        BagCompression::Zstd,
        BagCompression::Lz4,
    ] {
        let path = dir.join(format!("seed-{compression:?}.mcap"));
        let options = BagWriteOptions {
            compression,
            chunk_size_bytes: 1024,
        };
        let mut w = BagWriter::create(&path, &options)?;
        let tf = Transform {
            stamp: Stamp::default(),
            parent: "base_link".into(),
            child: "laser".into(),
            parent_from_child: Pose3::from_xyz_rpy(0.1, 0.0, 0.0, 0.0, 0.0, 0.2),
        };
        w.write_tf("/tf_static", 1.0, &[tf])?;
        for k in 0..2 {
            let t = 1.0 + 0.1 * f64::from(k);
            let pose = Pose3::from_xyz_rpy(0.1 * f64::from(k), 0.0, 0.0, 0.0, 0.0, 0.05);
            w.write_odometry("/odom", t, "odom", "base_link", &pose)?;
            w.write_pose("/truth", t, "map", &pose)?;
            let scan = Scan2 {
                angle_min_rad: -0.5,
                angle_increment_rad: 0.25,
                max_range_m: 10.0,
                ranges: vec![1.0, 2.0, f64::INFINITY, 10.0, 0.5],
                intensities: (k == 0).then(|| vec![1.0; 5]),
            };
            w.write_scan("/scan", t, "laser", &scan)?;
            let mut cloud = PointCloud::from_points(
                (0..4)
                    .map(|i| Point3::new(i as f32, 1.0, k as f32))
                    .collect(),
            );
            cloud.intensity = Some(vec![3.0; 4]);
            if k == 1 {
                cloud.width = 2;
                cloud.height = 2;
            }
            w.write_cloud("/points", t, "laser", &cloud)?;
        }
        w.finish()?;
        let bytes = std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
        seeds.push(Seed::new("fuzz.mcap", bytes));
    }
    Ok(seeds)
}

/// One CDR message of every type the rosbag reader decodes.
pub fn rosbag_cdr() -> Vec<Seed> {
    let stamp = Stamp { sec: 3, nanosec: 4 };
    let pose = Pose3::from_xyz_rpy(1.0, 2.0, 3.0, 0.1, 0.2, 0.3);
    let mut seeds = Vec::new();
    for which in 0..5 {
        let mut w = rosbag::cdr::CdrWriter::new();
        match which {
            0 => rosbag::encode_scan(
                &mut w,
                stamp,
                "laser",
                &Scan2 {
                    angle_min_rad: -1.0,
                    angle_increment_rad: 0.1,
                    max_range_m: 5.0,
                    ranges: vec![1.0, 2.0, 3.0, f64::INFINITY],
                    intensities: Some(vec![2.0; 4]),
                },
            ),
            1 => {
                let mut cloud = PointCloud::from_points(vec![Point3::new(1.0, 2.0, 3.0); 4]);
                cloud.intensity = Some(vec![1.0; 4]);
                cloud.width = 2;
                cloud.height = 2;
                rosbag::encode_cloud(&mut w, stamp, "lidar", &cloud);
            }
            2 => rosbag::encode_odometry(&mut w, stamp, "odom", "base_link", &pose),
            3 => rosbag::encode_tf(
                &mut w,
                &[Transform {
                    stamp,
                    parent: "a".into(),
                    child: "b".into(),
                    parent_from_child: pose,
                }],
            ),
            _ => rosbag::encode_pose_stamped(&mut w, stamp, "map", &pose),
        }
        seeds.push(Seed::new("message.cdr", w.bytes().to_vec()));
    }
    seeds
}

/// An Ouster sensor for the synthetic captures: its metadata, the capture layout, the lidar
/// port.
pub struct OusterSeed {
    pub json: String,
    pub capture: Capture,
}

/// How a synthetic capture is packaged.
#[derive(Clone, Copy)]
pub enum Capture {
    /// Classic pcap, little-endian, microseconds.
    Classic,
    /// Classic pcap, big-endian, nanoseconds.
    ClassicBigNanos,
    /// pcapng with a section header, an interface, a block to skip and enhanced packets.
    Pcapng,
    /// Classic pcap with the lidar packets cut into IP fragments and an 802.1Q tag.
    Fragmented,
}

fn lidar_transform() -> &'static str {
    "[-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1]"
}

/// Nested (firmware 3.x) metadata.
fn nested_json(profile: &str, w: usize, h: usize, cpp: usize, shifts: &[i32]) -> String {
    let altitudes: Vec<String> = (0..h)
        .map(|r| format!("{}", 10.0 - 20.0 * r as f64 / (h.max(2) - 1) as f64))
        .collect();
    let azimuths: Vec<String> = (0..h).map(|r| format!("{}", 1.5 - r as f64)).collect();
    let shifts: Vec<String> = shifts.iter().map(i32::to_string).collect();
    format!(
        r#"{{
  "sensor_info": {{"prod_line": "OS-1-16", "prod_sn": "991234567890", "build_rev": "v3.0.1",
                  "initialization_id": 4242}},
  "config_params": {{"lidar_mode": "{w}x10", "udp_port_lidar": 7502,
                    "udp_profile_lidar": "{profile}"}},
  "lidar_data_format": {{"columns_per_frame": {w}, "columns_per_packet": {cpp},
                        "pixels_per_column": {h}, "column_window": [0, {last}],
                        "pixel_shift_by_row": [{shifts}],
                        "udp_profile_lidar": "{profile}"}},
  "beam_intrinsics": {{"beam_altitude_angles": [{alt}],
                      "beam_azimuth_angles": [{azi}],
                      "lidar_origin_to_beam_origin_mm": 15.806}},
  "lidar_intrinsics": {{"lidar_to_sensor_transform": {tr}}}
}}"#,
        last = w - 1,
        shifts = shifts.join(", "),
        alt = altitudes.join(", "),
        azi = azimuths.join(", "),
        tr = lidar_transform(),
    )
}

/// Four sensors: nested metadata with the standard profile, nested with the low-data
/// profile in FUSA packets, flat (firmware 2.x) with the dual-return profile, flat without a
/// data format (firmware 1.x, legacy packets; a partial frame).
pub fn ouster_sensors() -> Vec<OusterSeed> {
    let flat2 = format!(
        r#"{{"prod_line": "OS-0-32", "prod_sn": "992000000001", "build_rev": "v2.3.0",
 "initialization_id": 77, "lidar_mode": "512x20", "udp_port_lidar": 7502,
 "data_format": {{"columns_per_frame": 8, "columns_per_packet": 4, "pixels_per_column": 2,
                 "column_window": [6, 3], "pixel_shift_by_row": [1, 0],
                 "udp_profile_lidar": "RNG19_RFL8_SIG16_NIR16_DUAL"}},
 "beam_altitude_angles": [4.5, -4.5], "beam_azimuth_angles": [0.5, -0.5],
 "lidar_origin_to_beam_origin_mm": 27.116, "lidar_to_sensor_transform": {tr}}}"#,
        tr = lidar_transform(),
    );
    let legacy = r#"{"prod_line": "OS-1-64", "prod_sn": "991900001", "build_rev": "v1.13.0",
 "lidar_mode": "512x10", "beam_altitude_angles": [16.0, 15.5, 15.0, 14.5],
 "beam_azimuth_angles": [3.0, 1.0, -1.0, -3.0]}"#
        .to_string();
    vec![
        OusterSeed {
            json: nested_json("RNG19_RFL8_SIG16_NIR16", 16, 4, 4, &[3, 2, -1, 0]),
            capture: Capture::Classic,
        },
        OusterSeed {
            json: nested_json("RNG19_RFL8_SIG16_NIR16", 16, 4, 4, &[3, 2, -1, 0]),
            capture: Capture::Fragmented,
        },
        OusterSeed {
            json: nested_json("FUSA_RNG15_RFL8_NIR8_DUAL", 8, 4, 4, &[0, 0, 0, 0]),
            capture: Capture::Pcapng,
        },
        OusterSeed {
            json: flat2,
            capture: Capture::ClassicBigNanos,
        },
        OusterSeed {
            json: legacy,
            capture: Capture::Classic,
        },
    ]
}

fn put16(b: &mut [u8], at: usize, v: u16) {
    b[at..at + 2].copy_from_slice(&v.to_le_bytes());
}

fn put32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// One lidar packet of frame `f` with columns `first..first + cpp`; pixel bytes are
/// pseudo-random (every bit pattern is a valid pixel).
fn ouster_packet(info: &SensorInfo, f: u32, first: usize, rng: &mut SplitMix64) -> Vec<u8> {
    use raypath_io::ouster::{HeaderType, LidarProfile};
    let legacy = info.profile == LidarProfile::Legacy;
    let (packet_header, column_header, column_footer) =
        if legacy { (0, 16, 4) } else { (32, 12, 0) };
    let pixels = info.pixels_per_column * info.profile.pixel_bytes();
    let column_bytes = column_header + pixels + column_footer;
    let mut b = vec![0u8; info.lidar_packet_bytes()];
    let serial: u64 = info.serial.trim().parse().unwrap_or(0);
    let init_id = info.init_id.unwrap_or(0);
    match (legacy, info.header_type) {
        (true, _) => {}
        (false, HeaderType::Standard) => {
            put16(&mut b, 0, 1);
            put16(&mut b, 2, f as u16);
            put32(&mut b, 4, init_id);
            b[7..12].copy_from_slice(&serial.to_le_bytes()[..5]);
        }
        (false, HeaderType::Fusa) => {
            put32(&mut b, 0, 1 | init_id << 8);
            put32(&mut b, 4, f);
            b[11..16].copy_from_slice(&serial.to_le_bytes()[..5]);
        }
    }
    for c in 0..info.columns_per_packet {
        let m = first + c;
        let at = packet_header + c * column_bytes;
        let col = &mut b[at..at + column_bytes];
        col[..8].copy_from_slice(&(1_000_000_000 * u64::from(f) + 1000 * m as u64).to_le_bytes());
        put16(col, 8, m as u16);
        if legacy {
            put16(col, 10, f as u16);
            put32(col, column_bytes - 4, u32::MAX);
        } else {
            put16(col, 10, 1);
        }
        for byte in &mut col[column_header..column_header + pixels] {
            *byte = rng.next_u64() as u8;
        }
    }
    b
}

/// Ethernet frames carrying one UDP datagram in IPv4, fragmented to `mtu_payload` bytes of
/// IP payload per frame (a multiple of 8), with an 802.1Q tag when `vlan`.
fn udp_frames(payload: &[u8], port: u16, id: u16, mtu_payload: usize, vlan: bool) -> Vec<Vec<u8>> {
    let mut udp = Vec::new();
    udp.extend_from_slice(&7502u16.to_be_bytes());
    udp.extend_from_slice(&port.to_be_bytes());
    udp.extend_from_slice(&((payload.len() + 8) as u16).to_be_bytes());
    udp.extend_from_slice(&[0, 0]);
    udp.extend_from_slice(payload);
    let mut frames = Vec::new();
    let mut offset = 0;
    loop {
        let end = udp.len().min(offset + mtu_payload);
        let more = end < udp.len();
        let mut f = vec![0u8; 12];
        if vlan {
            f.extend_from_slice(&[0x81, 0x00, 0x00, 0x05]);
        }
        f.extend_from_slice(&[0x08, 0x00, 0x45, 0]);
        f.extend_from_slice(&((20 + end - offset) as u16).to_be_bytes());
        f.extend_from_slice(&id.to_be_bytes());
        f.extend_from_slice(&((offset / 8) as u16 | if more { 0x2000 } else { 0 }).to_be_bytes());
        f.extend_from_slice(&[64, 17, 0, 0, 10, 5, 5, 1, 10, 5, 5, 2]);
        f.extend_from_slice(&udp[offset..end]);
        frames.push(f);
        offset = end;
        if !more {
            return frames;
        }
    }
}

/// A capture of the sensor of `json`: two frames (legacy: the first two packets of one frame
/// and one of the next), with a non-lidar datagram after each frame.
pub fn ouster_capture(info: &SensorInfo, capture: Capture) -> Vec<u8> {
    use raypath_io::ouster::LidarProfile;
    let mut rng = SplitMix64(5);
    let cpp = info.columns_per_packet;
    let packets: Vec<(u32, usize)> = if info.profile == LidarProfile::Legacy {
        vec![(5, 0), (5, cpp), (6, 0)]
    } else {
        [5u32, 6]
            .iter()
            .flat_map(|&f| {
                (0..info.columns_per_frame)
                    .step_by(cpp)
                    .map(move |m| (f, m))
            })
            .collect()
    };
    let (mtu, vlan) = match capture {
        Capture::Fragmented => (96, true),
        _ => (usize::MAX / 2, false),
    };
    let mut frames = Vec::new();
    for (k, &(f, first)) in packets.iter().enumerate() {
        let packet = ouster_packet(info, f, first, &mut rng);
        frames.extend(udp_frames(&packet, 7502, k as u16, mtu, vlan));
        let last_of_frame = packets.get(k + 1).is_none_or(|next| next.0 != f);
        if last_of_frame {
            frames.extend(udp_frames(&[7u8; 48], 7503, 1000 + k as u16, mtu, vlan));
        }
    }
    match capture {
        Capture::Classic | Capture::Fragmented => classic_pcap(&frames, false, false),
        Capture::ClassicBigNanos => classic_pcap(&frames, true, true),
        Capture::Pcapng => pcapng(&frames),
    }
}

fn classic_pcap(frames: &[Vec<u8>], big: bool, nanos: bool) -> Vec<u8> {
    let w32 = |v: u32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let w16 = |v: u16| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let mut b = Vec::new();
    b.extend_from_slice(&w32(if nanos { 0xa1b2_3c4d } else { 0xa1b2_c3d4 }));
    b.extend_from_slice(&w16(2));
    b.extend_from_slice(&w16(4));
    b.extend_from_slice(&[0; 8]);
    b.extend_from_slice(&w32(65535));
    b.extend_from_slice(&w32(1));
    for (k, f) in frames.iter().enumerate() {
        b.extend_from_slice(&w32(1_700_000_000 + k as u32));
        b.extend_from_slice(&w32(500));
        b.extend_from_slice(&w32(f.len() as u32));
        b.extend_from_slice(&w32(f.len() as u32));
        b.extend_from_slice(f);
    }
    b
}

fn pcapng(frames: &[Vec<u8>]) -> Vec<u8> {
    let block = |kind: u32, body: &[u8]| {
        let mut body = body.to_vec();
        while body.len() % 4 != 0 {
            body.push(0);
        }
        let total = (body.len() + 12) as u32;
        let mut b = kind.to_le_bytes().to_vec();
        b.extend_from_slice(&total.to_le_bytes());
        b.extend_from_slice(&body);
        b.extend_from_slice(&total.to_le_bytes());
        b
    };
    let mut shb = 0x1a2b_3c4du32.to_le_bytes().to_vec();
    shb.extend_from_slice(&[1, 0, 0, 0]);
    shb.extend_from_slice(&u64::MAX.to_le_bytes());
    let mut out = block(0x0a0d_0d0a, &shb);
    // Interface: Ethernet, snap length 0, option if_tsresol = 9 (nanoseconds).
    let mut idb = vec![1, 0, 0, 0];
    idb.extend_from_slice(&0u32.to_le_bytes());
    idb.extend_from_slice(&[9, 0, 1, 0, 9, 0, 0, 0, 0, 0, 0, 0]);
    out.extend(block(1, &idb));
    out.extend(block(4, &[0, 0, 0, 0]));
    for (k, f) in frames.iter().enumerate() {
        let ns = 1_700_000_000_000_000_000u64 + k as u64;
        let mut epb = 0u32.to_le_bytes().to_vec();
        epb.extend_from_slice(&((ns >> 32) as u32).to_le_bytes());
        epb.extend_from_slice(&(ns as u32).to_le_bytes());
        epb.extend_from_slice(&(f.len() as u32).to_le_bytes());
        epb.extend_from_slice(&(f.len() as u32).to_le_bytes());
        epb.extend_from_slice(f);
        out.extend(block(6, &epb));
    }
    out
}

/// The Unix `compress` reference streams of the `.Z` decoder's tests (ncompress 4.2.4.6:
/// 9-bit codes with clear codes, 12-bit and 16-bit codes), and the SegComp test images.
pub const LZW_STREAMS: [(&str, &[u8]); 5] = [
    (
        "tobe.Z",
        include_bytes!("../../../crates/io/tests/data/lzw/tobe.Z"),
    ),
    (
        "mixed-b12.Z",
        include_bytes!("../../../crates/io/tests/data/lzw/mixed-b12.Z"),
    ),
    (
        "text-b16.Z",
        include_bytes!("../../../crates/io/tests/data/lzw/text-b16.Z"),
    ),
    (
        "synth.test.1.Z",
        include_bytes!("../../../crates/io/tests/data/segcomp/synth.test.1.Z"),
    ),
    (
        "synth.test.1.gt-seg.Z",
        include_bytes!("../../../crates/io/tests/data/segcomp/synth.test.1.gt-seg.Z"),
    ),
];

pub fn lzw() -> Vec<Seed> {
    LZW_STREAMS
        .iter()
        .map(|(name, bytes)| Seed::new(*name, *bytes))
        .collect()
}

fn unpack(name: &str) -> Result<Vec<u8>> {
    let (_, packed) = LZW_STREAMS
        .iter()
        .find(|(n, _)| *n == name)
        .context("no such stream")?;
    lzw::decompress(packed, 1 << 20).map_err(|e| anyhow::anyhow!("{name}: {e:?}"))
}

pub fn segcomp_range() -> Result<Vec<Seed>> {
    let mut bytes = b"3 rows\n2 columns\n".to_vec();
    bytes.extend(b"header line\n".repeat(8));
    bytes.extend(b"\n");
    for i in 0..6u32 {
        bytes.extend((0x5000_0000 | (i * 500)).to_be_bytes());
    }
    Ok(vec![
        Seed::new("perc.test.1", bytes),
        Seed::new("synth.test.1", unpack("synth.test.1.Z")?),
    ])
}

pub fn segcomp_gt_seg() -> Result<Vec<Seed>> {
    let mut sun = Vec::new();
    for w in [0x59a6_6a95u32, 3, 2, 8, 12, 2, 1, 3] {
        sun.extend(w.to_be_bytes());
    }
    sun.extend([1, 2, 3]);
    sun.extend([0x80, 2, 10, 0, 0x80, 0, 11, 12, 0]);
    let mut plain = Vec::new();
    for w in [0x59a6_6a95u32, 3, 2, 8, 8, 1, 0, 0] {
        plain.extend(w.to_be_bytes());
    }
    plain.extend([10, 10, 11, 0, 12, 12, 13, 0]);
    let mut pgm = b"P5\n# c\n3 2\n300\n".to_vec();
    pgm.extend([0, 10, 0, 11, 1, 44, 0, 12, 0, 13, 0, 14]);
    let mut raw = b"2 rows\n3 columns\n".to_vec();
    raw.extend(b"x\n".repeat(9));
    raw.extend([10, 11, 12, 13, 14, 15]);
    Ok(vec![
        Seed::new("fuzz.gt-seg", sun),
        Seed::new("fuzz.gt-seg", plain),
        Seed::new("fuzz.gt-seg", pgm),
        Seed::new("fuzz.gt-seg", "P2 2 2 20\n1 2\n3 20\n"),
        Seed::new("fuzz.gt-seg", raw),
        Seed::new("synth.test.1.gt-seg", unpack("synth.test.1.gt-seg.Z")?),
    ])
}

pub fn segcomp_gt_ang() -> Vec<Seed> {
    vec![
        Seed::new("fuzz.gt-ang", "3\n10 11 90\n11 12 45\n\n10 12 135\n"),
        Seed::new(
            "synth.test.1.gt-ang",
            &include_bytes!("../../../crates/io/tests/data/segcomp/synth.test.1.gt-ang")[..],
        ),
    ]
}

pub fn point_csv() -> Vec<Seed> {
    vec![
        Seed::new(
            "points.csv",
            "x,y,w\n8.1320,-1.7499,0.0468\n-5.5911,6.3091,0.0504\n1e3,2,3\n",
        ),
        Seed::new("points.csv", "X, Y ,z\n1,2,3\n\n5,6,7\n"),
    ]
}

pub fn poles_csv() -> Result<Vec<Seed>> {
    let poles = [
        PoleRecord {
            x: 1.5,
            y: -2.25,
            width: 0.2,
            height: 3.0,
            score: 0.8,
        },
        PoleRecord {
            x: -10.0,
            y: 4.0,
            width: 0.15,
            height: 2.5,
            score: 1.0,
        },
    ];
    let mut written = Vec::new();
    write_pole_csv_to(&mut written, &poles)?;
    Ok(vec![
        Seed::new("poles.csv", written),
        Seed::new(
            "poles.csv",
            "x,y,w,h,kind,id\n1,2,0.2,3,0,7\n-4,5.5,0.1,2,1,8\n",
        ),
    ])
}

pub fn tum() -> Vec<Seed> {
    vec![Seed::new(
        "trajectory.tum",
        "# t x y z qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.1 0.5 -0.25 0.1 0 0 0.0499792 0.9987503\n\
         1.2 1 -0.5 0.2 0.01 -0.02 0.0998334 0.9950042\n",
    )]
}

pub fn xyz() -> Vec<Seed> {
    vec![
        Seed::new(
            "points.xyz",
            "# header\n\n1 2 3 0.5\n  -4\t5e-1 6 7 # note\n0 0 0 1\n",
        ),
        Seed::new("points.xyz", "1 2 3\n-1.5 2.25 1e2\n"),
    ]
}

/// rosbag2 `metadata.yaml`.
pub fn rosbag_metadata() -> Vec<Seed> {
    vec![Seed::new(
        "metadata.yaml",
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  \
         relative_file_paths:\n    - bag_0.mcap\n    - \"bag_1.mcap\"\n  compression_mode: ''\n  \
         duration:\n    nanoseconds: 100\n",
    )]
}

fn gzip(bytes: &[u8]) -> Result<Vec<u8>> {
    use std::io::Write;
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes)?;
    Ok(enc.finish()?)
}

fn bzip2(bytes: &[u8]) -> Result<Vec<u8>> {
    use std::io::Write;
    let mut enc = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::fast());
    enc.write_all(bytes)?;
    Ok(enc.finish()?)
}

/// Files of every single-file format under the names format detection goes by, plain and
/// compressed (gzip, bzip2, Unix compress).
pub fn summarize() -> Result<Vec<Seed>> {
    let first = |seeds: Vec<Seed>| {
        seeds
            .into_iter()
            .next()
            .map(|s| s.bytes)
            .unwrap_or_default()
    };
    let log = CARMEN_LOG.as_bytes();
    let pcd = pcd()?;
    Ok(vec![
        Seed::new("intel.log", log),
        Seed::new("intel.log.gz", gzip(log)?),
        Seed::new("intel.clf.bz2", bzip2(log)?),
        Seed::new("cloud.pcd", pcd[1].bytes.clone()),
        Seed::new("cloud.pcd.gz", gzip(&pcd[2].bytes)?),
        Seed::new("points.xyz", xyz()[1].bytes.clone()),
        Seed::new("points.xyz.bz2", bzip2(&xyz()[1].bytes)?),
        Seed::new("map.bt", first(octomap_bt()?)),
        Seed::new("scans.graph", first(octomap_graph()?)),
        Seed::new("000000.bin", first(kitti_velodyne()?)),
        Seed::new("00.txt", first(kitti_poses()?)),
        Seed::new("times.txt", first(kitti_times()?)),
        Seed::new("calib.txt", first(kitti_calib()?)),
        Seed::new("velodyne_hits.bin", first(nclt_hits())),
        Seed::new("groundtruth_2012-01-08.csv", first(nclt_pose_csv()?)),
        Seed::new("odometry_mu_100hz.csv", first(nclt_pose_csv()?)),
        Seed::new("cov_2012-01-08.csv", first(nclt_covariance()?)),
        Seed::new("synth.test.1.Z", LZW_STREAMS[3].1),
        Seed::new("synth.test.1.gt-seg.Z", LZW_STREAMS[4].1),
        Seed::new("synth.test.1.gt-ang", first(segcomp_gt_ang())),
        Seed::new("poles.csv", first(point_csv())),
    ])
}
