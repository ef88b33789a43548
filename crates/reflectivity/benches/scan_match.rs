//! Scan-matching throughput: 180-beam scans (1° apart) of a 7 m × 4.5 m room with a pillar,
//! matched and integrated at 5 cm (3 levels), with each residual. Aim: ≥ 200 scans/s.
#![allow(missing_docs, clippy::unwrap_used)]

use std::f64::consts::PI;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raypath_geometry::Pose2;
use raypath_reflectivity::{MatcherConfig, ResidualMode, ScanMatcher, ScanPoints};

fn range(x: f64, y: f64, a: f64) -> f64 {
    let (c, s) = (a.cos(), a.sin());
    let tx = if c > 1e-12 {
        (4.0 - x) / c
    } else if c < -1e-12 {
        (-3.0 - x) / c
    } else {
        f64::INFINITY
    };
    let ty = if s > 1e-12 {
        (2.5 - y) / s
    } else if s < -1e-12 {
        (-2.0 - y) / s
    } else {
        f64::INFINITY
    };
    tx.min(ty)
}

fn scans(n: usize) -> Vec<ScanPoints> {
    (0..n)
        .map(|k| {
            let t = k as f64 * 0.02;
            let pose = Pose2::new(
                -1.5 + t,
                -0.5 + 0.3 * (t * 1.2).sin(),
                0.3 * (t * 0.8).sin(),
            );
            let mut p = ScanPoints::new();
            for i in 0..180 {
                let a = -PI / 2.0 + i as f64 * PI / 180.0;
                let r = range(pose.x(), pose.y(), pose.theta() + a);
                // Wall stripes as reflectivity.
                let (wx, wy) = (
                    pose.x() + r * (pose.theta() + a).cos(),
                    pose.y() + r * (pose.theta() + a).sin(),
                );
                let refl = if ((wx + wy) * 2.0).floor() as i64 % 2 == 0 {
                    0.3
                } else {
                    0.9
                };
                p.push([r * a.cos(), r * a.sin()], refl);
            }
            p
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let data = scans(150);
    let mut group = c.benchmark_group("scan_match_180_beams_5cm");
    group.throughput(Throughput::Elements(data.len() as u64));
    group.sample_size(10);
    for mode in [
        ResidualMode::Occupancy,
        ResidualMode::Reflectivity,
        ResidualMode::Combined,
    ] {
        group.bench_function(mode.name(), |b| {
            b.iter(|| {
                let config = MatcherConfig {
                    mode,
                    map: raypath_reflectivity::MapConfig {
                        size_m: 20.0,
                        ..Default::default()
                    },
                    ..Default::default()
                };
                let mut m = ScanMatcher::new(config).unwrap();
                for s in &data {
                    m.process(s, None);
                }
                m.pose()
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
