//! Criterion benchmark: PPE (preset `synpeb`, with its refinement rounds) on a 500 × 500
//! organized scan of a box room with 2 cm radial noise (synthetic, so it runs without data),
//! and PPE and the PEAC-style baseline on the first generated SynPEB-style scan (σ = 2 cm)
//! when `cargo xtask datasets generate` has written it.
//!
//! To compare two versions: `cargo bench -p raypath-planes --bench ppe -- --save-baseline
//! before` on the first, `cargo bench -p raypath-planes --bench ppe -- --baseline before` on
//! the second (the PEAC-style baseline, unchanged by PPE work, shows the machine's drift).
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use raypath_planes::{PeacParams, PpeParams, extract, extract_grid, peac};

fn room(n: usize, sigma: f64) -> Vec<Vector3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let noise = Normal::new(0.0, sigma).unwrap();
    let (lo, hi) = (Vector3::new(-3.0, -3.0, -1.2), Vector3::new(4.0, 3.5, 1.8));
    let mut out = Vec::with_capacity(n * n);
    for row in 0..n {
        for col in 0..n {
            let az = -std::f64::consts::PI + col as f64 / n as f64 * 2.0 * std::f64::consts::PI;
            let el = 0.7 - row as f64 / (n - 1) as f64 * 1.4;
            let v = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
            let mut t = f64::INFINITY;
            for i in 0..3 {
                if v[i] > 1e-12 {
                    t = t.min(hi[i] / v[i]);
                } else if v[i] < -1e-12 {
                    t = t.min(lo[i] / v[i]);
                }
            }
            out.push(v * (t + noise.sample(&mut rng)));
        }
    }
    out
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("ppe");
    group.sample_size(10);
    let pts = room(500, 0.02);
    let params = PpeParams::synpeb();
    group.bench_function("box_room_500x500", |b| {
        b.iter(|| extract_grid(&pts, 500, 500, &params).unwrap())
    });
    let generated = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../datasets/generated/synpeb/test/2.0/pc_01.pcd");
    if let Ok(pcd) = raypath_io::pcd::read_pcd(&generated, &raypath_io::pcd::ReadOptions::synpeb())
    {
        group.bench_function("synpeb_generated_500x500", |b| {
            b.iter(|| extract(&pcd.cloud, &params).unwrap())
        });
        let points: Vec<Vector3<f64>> = pcd
            .cloud
            .points
            .iter()
            .map(|p| p.coords.cast::<f64>())
            .collect();
        let peac_params = PeacParams::synpeb();
        group.bench_function("peac_synpeb_generated_500x500", |b| {
            b.iter(|| peac(&points, 500, 500, &peac_params).unwrap())
        });
    } else {
        eprintln!(
            "skipping synpeb_generated_500x500: {} not found (cargo xtask datasets generate)",
            generated.display()
        );
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
