//! rosbag2 MCAP reading throughput, in MB/s of file (Criterion `Throughput::Bytes` = the
//! `.mcap` file size; for the uncompressed bags that is the message bytes plus about 1 % of
//! MCAP records and indexes).
//!
//! Bags generated once per run with raypath's writer into a temporary directory (seeded):
//! * `planar`: 100 000 `LaserScan`s of 361 beams (with `/odom` and `/tf` per scan, as a
//!   robot records them), read through `rosbag::open_planar` (first pass over odometry and
//!   tf, second pass decoding every scan into a `PlanarFrame`).
//! * `sweeps`: 1 000 `PointCloud2` sweeps of 120 000 points (x, y, z, intensity float32) with
//!   `/tf`, read through `rosbag::open_sweeps` and `sweep(i)` for every sweep.
//!
//! Each in zstd-compressed, LZ4-compressed and uncompressed chunks. Run with
//! `cargo bench -p raypath-io --bench rosbag -- --sample-size 10`. With `RAYPATH_BENCH_BAGS`
//! set to a directory the bags are kept there and reused by later runs (for profiling:
//! `perf record <bench binary> --bench --profile-time 10 planar_100k_scans/Zstd`).
#![allow(clippy::unwrap_used)]

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_geometry::{PointCloud, Pose3, Scan2};
use raypath_io::rosbag::{self, BagCompression, BagWriteOptions, BagWriter, Stamp, Transform};
use raypath_io::sequence::Topics;

const SCANS: usize = 100_000;
const BEAMS: usize = 361;
const SWEEPS: usize = 1_000;
const POINTS: usize = 120_000;

struct Bags {
    _dir: Option<tempfile::TempDir>,
    planar: Vec<(BagCompression, PathBuf)>,
    sweeps: Vec<(BagCompression, PathBuf)>,
}

fn options(compression: BagCompression) -> BagWriteOptions {
    BagWriteOptions {
        compression,
        ..BagWriteOptions::default()
    }
}

fn write_planar(path: &Path, compression: BagCompression) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut w = BagWriter::create(path, &options(compression)).unwrap();
    let mount = Transform {
        stamp: Stamp::default(),
        parent: "base_link".into(),
        child: "laser".into(),
        parent_from_child: Pose3::from_xyz_rpy(0.2, 0.0, 0.1, 0.0, 0.0, 0.0),
    };
    w.write_tf("/tf_static", 1_700_000_000.0, &[mount]).unwrap();
    let mut scan = Scan2 {
        angle_min_rad: -std::f64::consts::FRAC_PI_2,
        angle_increment_rad: std::f64::consts::PI / 360.0,
        max_range_m: 30.0,
        ranges: vec![0.0; BEAMS],
        intensities: None,
    };
    for k in 0..SCANS {
        let t = 1_700_000_000.0 + 0.025 * k as f64;
        let pose = Pose3::from_xyz_rpy(0.01 * k as f64, 0.0, 0.0, 0.0, 0.0, 1e-4 * k as f64);
        w.write_odometry("/odom", t, "odom", "base_link", &pose)
            .unwrap();
        let tf = Transform {
            stamp: Stamp::from_secs(t).unwrap(),
            parent: "odom".into(),
            child: "base_link".into(),
            parent_from_child: pose,
        };
        w.write_tf("/tf", t, &[tf]).unwrap();
        for r in &mut scan.ranges {
            // Millimetre ranges, as a laser reports them.
            *r = (rng.random_range(0.2f64..32.0) * 1000.0).round() / 1000.0;
        }
        w.write_scan("/scan", t, "laser", &scan).unwrap();
    }
    w.finish().unwrap();
}

fn write_sweeps(path: &Path, compression: BagCompression) {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut w = BagWriter::create(path, &options(compression)).unwrap();
    let mut cloud = PointCloud::from_points(vec![Point3::origin(); POINTS]);
    cloud.intensity = Some(vec![0.0; POINTS]);
    for k in 0..SWEEPS {
        let t = 1_700_000_000.0 + 0.1 * k as f64;
        let pose = Pose3::from_xyz_rpy(k as f64, 0.0, 0.0, 0.0, 0.0, 0.0);
        let tf = Transform {
            stamp: Stamp::from_secs(t).unwrap(),
            parent: "odom".into(),
            child: "lidar".into(),
            parent_from_child: pose,
        };
        w.write_tf("/tf", t, &[tf]).unwrap();
        for (p, i) in cloud
            .points
            .iter_mut()
            .zip(cloud.intensity.as_mut().unwrap().iter_mut())
        {
            // Centimetre-quantized points within 80 m, intensity 0–255.
            let q = |v: f32| (v * 100.0).round() / 100.0;
            *p = Point3::new(
                q(rng.random_range(-80.0..80.0)),
                q(rng.random_range(-80.0..80.0)),
                q(rng.random_range(-3.0..10.0)),
            );
            *i = rng.random_range(0..256) as f32;
        }
        w.write_cloud("/points", t, "lidar", &cloud).unwrap();
    }
    w.finish().unwrap();
}

fn bags() -> &'static Bags {
    static BAGS: OnceLock<Bags> = OnceLock::new();
    BAGS.get_or_init(|| {
        let (temp, dir) = match std::env::var_os("RAYPATH_BENCH_BAGS") {
            Some(d) => {
                std::fs::create_dir_all(&d).unwrap();
                (None, PathBuf::from(d))
            }
            None => {
                let t = tempfile::tempdir().unwrap();
                let d = t.path().to_path_buf();
                (Some(t), d)
            }
        };
        let mut planar = Vec::new();
        let mut sweeps = Vec::new();
        for compression in [
            BagCompression::Zstd,
            BagCompression::Lz4,
            BagCompression::None,
        ] {
            let p = dir.join(format!("planar-{compression:?}.mcap"));
            generate(&p, |p| write_planar(p, compression), temp.is_none());
            planar.push((compression, p));
            let s = dir.join(format!("sweeps-{compression:?}.mcap"));
            generate(&s, |s| write_sweeps(s, compression), temp.is_none());
            sweeps.push((compression, s));
        }
        Bags {
            _dir: temp,
            planar,
            sweeps,
        }
    })
}

/// Writes the bag at `path` (unless `reuse` and it is there: a kept bag, written whole, is
/// renamed into place last).
fn generate(path: &Path, write: impl FnOnce(&Path), reuse: bool) {
    if reuse && path.is_file() {
        return;
    }
    let started = std::time::Instant::now();
    let partial = path.with_extension("partial.mcap");
    write(&partial);
    std::fs::rename(&partial, path).unwrap();
    eprintln!(
        "generated {} ({:.1} MB) in {:.1} s",
        path.display(),
        size(path) as f64 / 1e6,
        started.elapsed().as_secs_f64()
    );
}

fn size(path: &Path) -> u64 {
    std::fs::metadata(path).unwrap().len()
}

fn read_planar(path: &Path) -> usize {
    let mut beams = 0;
    for frame in rosbag::open_planar(path, &Topics::default()).unwrap() {
        beams += black_box(frame.unwrap()).scan.len();
    }
    assert_eq!(beams, SCANS * BEAMS);
    beams
}

fn read_sweeps(path: &Path) -> usize {
    let seq = rosbag::open_sweeps(path, &Topics::default()).unwrap();
    let mut points = 0;
    for i in 0..seq.len() {
        points += black_box(seq.sweep(i).unwrap()).len();
    }
    assert_eq!(points, SWEEPS * POINTS);
    points
}

fn bench(c: &mut Criterion) {
    let bags = bags();
    let mut group = c.benchmark_group("rosbag");
    for (compression, path) in &bags.planar {
        group.throughput(Throughput::Bytes(size(path)));
        group.bench_function(format!("planar_100k_scans/{compression:?}"), |b| {
            b.iter(|| read_planar(path))
        });
    }
    for (compression, path) in &bags.sweeps {
        group.throughput(Throughput::Bytes(size(path)));
        group.bench_function(format!("sweeps_1k_clouds/{compression:?}"), |b| {
            b.iter(|| read_sweeps(path))
        });
    }
    group.finish();
}

/// The Criterion group (in a private module: the macro's function has no docs).
mod group {
    use super::*;
    criterion_group! {
        name = benches;
        config = Criterion::default()
            .sample_size(10)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(20));
        targets = bench
    }
}
criterion_main!(group::benches);
