//! Lidar images and global descriptors (Khan 2017, §4.5.1–§4.5.2): equirectangular projection
//! of a 120 k-point cloud, HOG and GIST of a 1024 × 64 image, and a cosine query over 10 000
//! stored descriptors.

#![allow(missing_docs)] // criterion_group! generates an undocumented function

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use image::GrayImage;
use nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_geometry::PointCloud;
use raypath_place_recognition::{
    EquirectConfig, Gist, GistConfig, GlobalDescriptorDb, HogConfig, ImageConfig, PlaceRecognizer,
    equirectangular, hog,
};

/// A 64-beam, 1875-column scan (120 000 points) of a street-like scene.
fn cloud() -> PointCloud {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let (beams, columns) = (64usize, 1875usize);
    let mut points = Vec::with_capacity(beams * columns);
    let mut intensity = Vec::with_capacity(beams * columns);
    for b in 0..beams {
        let elevation = (2.0 - 26.9 * (b as f64 + 0.5) / beams as f64).to_radians();
        for c in 0..columns {
            let azimuth = std::f64::consts::TAU * c as f64 / columns as f64;
            let range = if elevation < -0.05 {
                (1.73 / -elevation.sin()).min(80.0)
            } else {
                8.0 + 20.0 * (azimuth * 3.0).sin().abs()
            } + rng.random_range(-0.02..0.02);
            points.push(Point3::new(
                (range * elevation.cos() * azimuth.cos()) as f32,
                (range * elevation.cos() * azimuth.sin()) as f32,
                (range * elevation.sin()) as f32,
            ));
            intensity.push(rng.random::<f32>());
        }
    }
    PointCloud {
        intensity: Some(intensity),
        ..PointCloud::from_points(points)
    }
}

fn bench(c: &mut Criterion) {
    let cloud = cloud();
    let config = EquirectConfig::default();
    c.bench_function("equirectangular 120k points -> 1024x64", |b| {
        b.iter(|| equirectangular(black_box(&cloud), &config).map(|i| i.range.len()))
    });
    let image: GrayImage = equirectangular(&cloud, &config)
        .expect("projection")
        .intensity;
    let hog_config = HogConfig::default();
    c.bench_function("hog 1024x64", |b| {
        b.iter(|| hog(black_box(&image), &hog_config).map(|d| d.len()))
    });
    let gist = Gist::new(GistConfig::default()).expect("gist filter bank");
    c.bench_function("gist 1024x64 (128 px, 4x8 filters, 4x4 blocks)", |b| {
        b.iter(|| gist.describe(black_box(&image)).map(|d| d.len()))
    });

    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let mut db = GlobalDescriptorDb::hog(HogConfig::default(), ImageConfig::default());
    for _ in 0..10_000 {
        db.insert((0..512).map(|_| rng.random::<f32>()).collect());
    }
    let query: Vec<f32> = (0..512).map(|_| rng.random::<f32>()).collect();
    c.bench_function("cosine query 512-d over 10000 descriptors", |b| {
        b.iter(|| db.query(black_box(&query), 10_000).len())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
