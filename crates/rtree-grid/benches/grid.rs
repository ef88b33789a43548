//! Criterion benchmarks: scan insertion and occupied-cell iteration.

#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Point3;
use raypath_rtree_grid::{FusionRule, GridConfig, RtreeGrid, SensorModel};

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

criterion_group!(benches, bench);
criterion_main!(benches);
