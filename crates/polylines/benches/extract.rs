//! Criterion benchmarks of PLE and PLE+ (both solvers) at J = 20, per scan, single thread.
//!
//! Real scans: 20 evenly spaced scans of `$RAYPATH_DATA/carmen/corrected/intel-corrected.log.gz`
//! when that file exists; otherwise 20 simulated polygon scans (raypath-sim, thesis protocol).

#![allow(missing_docs)]

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use raypath_geometry::Scan2;
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use raypath_polylines::{Method, Optimizer, PolylineConfig, extract};
use raypath_sim::polygons::{PolygonsConfig, simulate_scan};

fn scans() -> (String, Vec<Scan2>) {
    let dir = std::env::var_os("RAYPATH_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../datasets"));
    let path = dir.join("carmen/corrected/intel-corrected.log.gz");
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    if path.exists()
        && let Ok(frames) = read_planar(&path, &options)
    {
        // read_planar fails on a log without scans, so `frames` is not empty.
        let step = (frames.len() / 20).max(1);
        let scans = frames.into_iter().step_by(step).take(20).map(|f| f.scan);
        return ("intel".into(), scans.collect());
    }
    eprintln!(
        "{} not found: benchmarking simulated polygon scans",
        path.display()
    );
    let config = PolygonsConfig::default();
    let scans = (0..20)
        .filter_map(|i| simulate_scan(&config, 0, i).ok().map(|s| s.scan))
        .collect();
    ("simulated".into(), scans)
}

fn bench(c: &mut Criterion) {
    let (name, scans) = scans();
    let mut group = c.benchmark_group(format!("polylines-{name}-J20"));
    let variants = [
        ("PLE", Method::Ple, Optimizer::default()),
        ("PLE+ LM", Method::PlePlus, Optimizer::LEVENBERG_MARQUARDT),
        ("PLE+ NM", Method::PlePlus, Optimizer::NELDER_MEAD),
    ];
    for (label, method, optimizer) in variants {
        let config = PolylineConfig {
            optimizer,
            ..PolylineConfig::new(method, 20)
        };
        let mut i = 0;
        group.bench_function(label, |b| {
            b.iter(|| {
                i = (i + 1) % scans.len();
                black_box(extract(black_box(&scans[i]), &config))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
