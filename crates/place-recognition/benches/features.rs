//! Image features on a synthetic 640 × 480 image and a rasterised scan, and the planar polar
//! descriptor (describe + query) on a 1 000-frame database.
//!
//! `cargo bench -p raypath-place-recognition --bench features -- --quick`

#![allow(missing_docs)] // criterion_group! generates an undocumented function

use std::f64::consts::TAU;
use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use image::{GrayImage, Luma};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_geometry::Scan2;
use raypath_place_recognition::{
    FeatureConfig, Frame, PlaceRecognizer, PolarConfig, PolarContext, RasterConfig,
    detect_and_describe, rasterize_scan,
};

/// A seeded textured image: plane waves plus random grey rectangles.
fn textured(width: u32, height: u32, seed: u64) -> GrayImage {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let waves: Vec<[f64; 4]> = (0..6)
        .map(|_| {
            let a = rng.random_range(0.0..TAU);
            let k = TAU / rng.random_range(6.0..30.0);
            [
                k * a.cos(),
                k * a.sin(),
                rng.random_range(0.0..6.3),
                rng.random_range(8.0..20.0),
            ]
        })
        .collect();
    let mut img = GrayImage::from_fn(width, height, |x, y| {
        let v: f64 = waves
            .iter()
            .map(|w| w[3] * (w[0] * x as f64 + w[1] * y as f64 + w[2]).sin())
            .sum();
        Luma([(128.0 + v).clamp(0.0, 255.0) as u8])
    });
    for _ in 0..300 {
        let (cx, cy) = (rng.random_range(0..width), rng.random_range(0..height));
        let (a, b) = (rng.random_range(4..24u32), rng.random_range(4..24u32));
        let grey: u8 = rng.random();
        for y in cy.saturating_sub(b)..(cy + b).min(height) {
            for x in cx.saturating_sub(a)..(cx + a).min(width) {
                img.put_pixel(x, y, Luma([grey]));
            }
        }
    }
    img
}

/// A 360-beam scan from `(x, y, heading)` in a corridor world of rooms and pillars.
fn room_scan(x: f64, y: f64, heading: f64, walls: &[[f64; 4]]) -> Scan2 {
    let inc = TAU / 360.0;
    let ranges = (0..360)
        .map(|i| {
            let a = heading + (i as f64 + 0.5) * inc;
            let (dx, dy) = (a.cos(), a.sin());
            let mut best = 30.0;
            for w in walls {
                let (ex, ey) = (w[2] - w[0], w[3] - w[1]);
                let den = dx * ey - dy * ex;
                if den.abs() < 1e-12 {
                    continue;
                }
                let (wx, wy) = (w[0] - x, w[1] - y);
                let t = (wx * ey - wy * ex) / den;
                let u = (wx * dy - wy * dx) / den;
                if t > 0.0 && (0.0..=1.0).contains(&u) && t < best {
                    best = t;
                }
            }
            best
        })
        .collect();
    Scan2 {
        angle_min_rad: 0.5 * inc,
        angle_increment_rad: inc,
        max_range_m: 30.0,
        ranges,
        intensities: None,
    }
}

/// A 60 m × 20 m floor: outer walls, a row of rooms and square pillars.
fn world() -> Vec<[f64; 4]> {
    let mut walls = vec![
        [0.0, 0.0, 60.0, 0.0],
        [60.0, 0.0, 60.0, 20.0],
        [60.0, 20.0, 0.0, 20.0],
        [0.0, 20.0, 0.0, 0.0],
    ];
    for k in 0..6 {
        let x0 = 10.0 * k as f64;
        // Room walls along y = 12 with a 1.2 m door, and a partition to the next room.
        walls.push([x0, 12.0, x0 + 4.0, 12.0]);
        walls.push([x0 + 5.2, 12.0, x0 + 10.0, 12.0]);
        walls.push([x0 + 10.0, 12.0, x0 + 10.0, 20.0]);
        // A pillar in the corridor, offset differently per bay.
        let (px, py) = (x0 + 3.0 + 0.7 * k as f64, 3.0 + 0.9 * k as f64);
        walls.push([px, py, px + 0.6, py]);
        walls.push([px + 0.6, py, px + 0.6, py + 0.6]);
        walls.push([px + 0.6, py + 0.6, px, py + 0.6]);
        walls.push([px, py + 0.6, px, py]);
    }
    walls
}

fn bench(c: &mut Criterion) {
    let config = FeatureConfig::default();
    let img = textured(640, 480, 1);
    c.bench_function("detect_and_describe 640x480 textured", |b| {
        b.iter(|| detect_and_describe(black_box(&img), &config))
    });

    let walls = world();
    let scan = room_scan(23.0, 7.0, 0.4, &walls);
    let raster = RasterConfig::default();
    c.bench_function("rasterize_scan 360 beams", |b| {
        b.iter(|| rasterize_scan(black_box(&scan), &raster))
    });
    let scan_img = rasterize_scan(&scan, &raster).expect("valid raster config");
    c.bench_function("detect_and_describe rasterised scan 601x601", |b| {
        b.iter(|| detect_and_describe(black_box(&scan_img), &config))
    });

    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let scans: Vec<Scan2> = (0..1000)
        .map(|_| {
            let x = rng.random_range(1.0..59.0);
            let y = rng.random_range(1.0..11.0);
            room_scan(x, y, rng.random_range(0.0..TAU), &walls)
        })
        .collect();
    for (name, candidates) in [("tree k=10", Some(10)), ("exhaustive", None)] {
        let mut pc = PolarContext::new(PolarConfig {
            candidates,
            ..PolarConfig::default()
        })
        .expect("valid config");
        for s in &scans {
            let d = pc.describe(&Frame::Planar(s)).expect("planar frame");
            pc.insert(d);
        }
        let query = pc.describe_scan(&scan).expect("planar frame");
        c.bench_function(&format!("polar-context query 1000 frames {name}"), |b| {
            b.iter(|| pc.query(black_box(&query), 1000))
        });
    }
    let pc = PolarContext::default();
    c.bench_function("polar-context describe 360 beams", |b| {
        b.iter(|| pc.describe_scan(black_box(&scan)))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
