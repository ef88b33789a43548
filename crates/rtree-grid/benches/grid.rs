//! Criterion benchmarks: scan insertion and occupied-cell iteration.

#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Point3, UnitQuaternion};
use raypath_geometry::{PointCloud, Pose3};
use raypath_rtree_grid::{FusionRule, GridConfig, RtreeGrid, Selection, SensorModel};

fn room_scan(n: usize) -> Vec<Point3<f64>> {
    (0..n)
        .map(|i| {
            let a = i as f64 * 0.7548776662;
            let b = i as f64 * 0.5698402910;
            let (u, v) = (a.fract(), b.fract());
            let az = u * std::f64::consts::TAU;
            let el = -0.4 + 0.8 * v;
            let range = 8.0 + 2.0 * (3.0 * az).sin();
            Point3::new(
                range * az.cos() * el.cos(),
                range * az.sin() * el.cos(),
                range * el.sin(),
            )
        })
        .collect()
}

/// One scan of a spinning 64-beam lidar at `origin` in a street (ground 1.73 m below the
/// sensor, facades at y = ±7 m, a wall at x = 60 m), ranges with ±3 cm of hashed noise;
/// beams that hit nothing within 40 m are dropped.
fn street_scan(origin: &Point3<f64>, azimuths: usize) -> Vec<Point3<f64>> {
    let mut out = Vec::with_capacity(64 * azimuths);
    for ring in 0..64u32 {
        let el = (-24.8 + 26.8 * f64::from(ring) / 63.0).to_radians();
        for i in 0..azimuths {
            let az = std::f64::consts::TAU * i as f64 / azimuths as f64;
            let d = [az.cos() * el.cos(), az.sin() * el.cos(), el.sin()];
            let mut t = f64::INFINITY;
            if d[2] < 0.0 {
                t = t.min(-1.73 / d[2]);
            }
            if d[1] != 0.0 {
                t = t.min((7.0f64.copysign(d[1]) - origin.y) / d[1]);
            }
            if d[0] > 0.0 {
                t = t.min((60.0 - origin.x) / d[0]);
            }
            if t > 40.0 {
                continue;
            }
            let h =
                (u64::from(ring) * azimuths as u64 + i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            let t = t + 0.06 * ((h >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
            out.push(Point3::new(
                origin.x + t * d[0],
                origin.y + t * d[1],
                origin.z + t * d[2],
            ));
        }
    }
    out
}

/// The equal-value hot path: a car driving 1 m per scan down a street, so every scan
/// changes part of the fused free space of the last (splits and re-fusion).
fn bench_street(c: &mut Criterion) {
    let street: Vec<(Point3<f64>, Vec<Point3<f64>>)> = (0..5)
        .map(|i| {
            let origin = Point3::new(f64::from(i), 0.0, 0.0);
            let scan = street_scan(&origin, 360);
            (origin, scan)
        })
        .collect();
    let mut group = c.benchmark_group("street");
    group.sample_size(10);
    group.bench_function(
        "insert 5 × 23k-beam street scans, 1 m apart (EqualValue, beam, r = 0.2, M = 8)",
        |b| {
            b.iter(|| {
                let mut config = GridConfig::with(0.2, 8, SensorModel::BeamBased);
                config.fusion_rule = FusionRule::EqualValue;
                let mut grid = RtreeGrid::new(config).unwrap();
                for (origin, scan) in &street {
                    grid.insert_scan(origin, scan);
                }
                grid.num_leaves()
            })
        },
    );
    // Fusion from every updated cell, after each scan and once after the five.
    for interval in [1u32, 5] {
        group.bench_function(
            format!(
                "insert 5 street scans (EqualValue, every updated cell, fused every {interval} scans)"
            ),
            |b| {
                b.iter(|| {
                    let mut config = GridConfig::with(0.2, 8, SensorModel::BeamBased);
                    config.fusion_rule = FusionRule::EqualValue;
                    config.selection = Selection::UpdatedCells;
                    config.fusion_interval_scans = interval;
                    let mut grid = RtreeGrid::new(config).unwrap();
                    for (origin, scan) in &street {
                        grid.insert_scan(origin, scan);
                    }
                    grid.fuse_pending();
                    grid.num_leaves()
                })
            },
        );
    }
    // The same five scans as one batch (cells enter the tree only after the fusion pass).
    let clouds: Vec<(Pose3, PointCloud)> = street
        .iter()
        .map(|(origin, scan)| {
            let local = scan
                .iter()
                .map(|p| (p - origin).cast::<f32>().into())
                .collect();
            let pose = Pose3::from_parts(origin.coords, UnitQuaternion::identity());
            (pose, PointCloud::from_points(local))
        })
        .collect();
    group.bench_function(
        "insert 5 street scans as one batch (EqualValue, every updated cell, fused every 5 scans)",
        |b| {
            b.iter(|| {
                let mut config = GridConfig::with(0.2, 8, SensorModel::BeamBased);
                config.fusion_rule = FusionRule::EqualValue;
                config.selection = Selection::UpdatedCells;
                config.fusion_interval_scans = 5;
                let mut grid = RtreeGrid::new(config).unwrap();
                grid.insert_clouds(clouds.iter().map(|(p, c)| (p, c)));
                grid.num_leaves()
            })
        },
    );
    group.finish();
}

fn bench(c: &mut Criterion) {
    let scan = room_scan(20_000);
    for model in [SensorModel::BeamBased, SensorModel::BeamEndPoint] {
        c.bench_function(
            &format!("insert 3 × 20k-beam scans ({model:?}, r = 0.2, M = 8)"),
            |b| {
                b.iter(|| {
                    let mut grid = RtreeGrid::new(GridConfig::with(0.2, 8, model)).unwrap();
                    for _ in 0..3 {
                        grid.insert_scan(&Point3::origin(), &scan);
                    }
                    grid.num_leaves()
                })
            },
        );
    }
    // A moving sensor (0.5 m per scan): later scans change parts of fused cells.
    for rule in [FusionRule::Clamped, FusionRule::EqualValue] {
        c.bench_function(
            &format!("insert 3 × 20k-beam scans, moving ({rule:?}, beam, r = 0.2, M = 8)"),
            |b| {
                b.iter(|| {
                    let mut config = GridConfig::with(0.2, 8, SensorModel::BeamBased);
                    config.fusion_rule = rule;
                    let mut grid = RtreeGrid::new(config).unwrap();
                    for i in 0..3 {
                        let origin = Point3::new(0.5 * f64::from(i), 0.0, 0.0);
                        let points: Vec<_> = scan.iter().map(|p| p + origin.coords).collect();
                        grid.insert_scan(&origin, &points);
                    }
                    grid.num_leaves()
                })
            },
        );
    }
    let mut grid = RtreeGrid::new(GridConfig::with(0.2, 8, SensorModel::BeamBased)).unwrap();
    for _ in 0..5 {
        grid.insert_scan(&Point3::origin(), &scan);
    }
    c.bench_function("visit occupied cells (r = 0.2, M = 8)", |b| {
        b.iter(|| grid.for_each_occupied(|_| {}))
    });
}

criterion_group!(benches, bench_street, bench);
criterion_main!(benches);
