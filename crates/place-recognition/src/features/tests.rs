use image::GrayImage;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

/// A seeded synthetic scene: random grey rectangles and discs on a gradient.
fn textured(width: u32, height: u32, seed: u64) -> GrayImage {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Smooth random texture: a sum of six plane waves of random direction and period.
    let waves: Vec<[f64; 4]> = (0..6)
        .map(|_| {
            let a = rng.random_range(0.0..std::f64::consts::TAU);
            let k = std::f64::consts::TAU / rng.random_range(6.0..30.0);
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
        image::Luma([(128.0 + v).clamp(0.0, 255.0) as u8])
    });
    let shapes = (width * height / 900).max(4);
    for _ in 0..shapes {
        let cx = rng.random_range(0..width) as i64;
        let cy = rng.random_range(0..height) as i64;
        let a = rng.random_range(4..24i64);
        let b = rng.random_range(4..24i64);
        let grey: u8 = rng.random();
        let disc = rng.random_bool(0.4);
        for y in (cy - b).max(0)..(cy + b).min(height as i64) {
            for x in (cx - a).max(0)..(cx + a).min(width as i64) {
                let (dx, dy) = ((x - cx) as f64 / a as f64, (y - cy) as f64 / b as f64);
                if !disc || dx * dx + dy * dy <= 1.0 {
                    img.put_pixel(x as u32, y as u32, image::Luma([grey]));
                }
            }
        }
    }
    img
}

/// The image turned a quarter (a pixel permutation): `new(x, y) = old(w − 1 − y, x)`.
fn quarter_turn(img: &GrayImage) -> GrayImage {
    let (w, h) = img.dimensions();
    GrayImage::from_fn(h, w, |x, y| *img.get_pixel(w - 1 - y, x))
}

fn nearest(d: &Bits512, set: &[Bits512]) -> u32 {
    set.iter().map(|e| d.hamming(e)).min().unwrap_or(512)
}

#[test]
fn quarter_turn_keeps_descriptors_close() {
    let img = textured(200, 200, 7);
    let turned = quarter_turn(&img);
    let other = textured(200, 200, 8);
    let config = FeatureConfig::default();
    let (k0, d0) = detect_and_describe(&img, &config).unwrap();
    let (k1, d1) = detect_and_describe(&turned, &config).unwrap();
    let (_, d2) = detect_and_describe(&other, &config).unwrap();
    assert!(
        k0.len() >= 50 && k1.len() >= 50,
        "{} {}",
        k0.len(),
        k1.len()
    );
    // Nearest neighbours in the original: most within 32 of 512 bits (the full-resolution
    // level maps exactly; coarser levels are resampled on a turned grid) …
    let near = |set: &[Bits512]| set.iter().filter(|d| nearest(d, &d0) <= 32).count();
    let (close, unrelated) = (near(&d1), near(&d2));
    assert!(
        close as f64 >= 0.6 * d1.len() as f64,
        "{close} of {} within 32 bits",
        d1.len()
    );
    // … while hardly any descriptor of an unrelated image is.
    assert!(
        unrelated as f64 <= 0.05 * d2.len() as f64,
        "{unrelated} of {}",
        d2.len()
    );
}

#[test]
fn quarter_turn_moves_keypoints_with_the_image() {
    let img = textured(160, 160, 11);
    let config = FeatureConfig {
        octaves: 1,
        ..FeatureConfig::default()
    };
    let (k0, d0) = detect_and_describe(&img, &config).unwrap();
    let (k1, d1) = detect_and_describe(&quarter_turn(&img), &config).unwrap();
    assert_eq!(k0.len(), k1.len());
    // On the full-resolution level the permutation is exact: positions map, angles turn by
    // a quarter and descriptors coincide.
    let mut exact = 0;
    for (k, d) in k1.iter().zip(&d1) {
        let (u, v) = (159.0 - k.y, k.x);
        let Some(j) = k0.iter().position(|o| o.x == u && o.y == v) else {
            panic!("no keypoint at ({u}, {v})");
        };
        exact += usize::from(d0[j] == *d);
    }
    assert!(
        exact as f64 >= 0.9 * k1.len() as f64,
        "{exact} of {}",
        k1.len()
    );
}

#[test]
fn blank_tiny_and_empty_images_have_no_keypoints() {
    let config = FeatureConfig::default();
    for img in [
        GrayImage::from_pixel(120, 90, image::Luma([128])),
        GrayImage::new(0, 0),
        textured(20, 20, 1),
    ] {
        let (k, d) = detect_and_describe(&img, &config).unwrap();
        assert!(k.is_empty() && d.is_empty());
    }
}

#[test]
fn results_are_deterministic_and_bounded() {
    let img = textured(240, 180, 3);
    let config = FeatureConfig {
        max_keypoints: 40,
        ..FeatureConfig::default()
    };
    let a = detect_and_describe(&img, &config).unwrap();
    let b = detect_and_describe(&img, &config).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.0.len(), 40);
    assert!(a.0.windows(2).all(|w| w[0].response >= w[1].response));
    for k in &a.0 {
        assert!(k.x >= 0.0 && k.y >= 0.0 && k.x < 240.0 && k.y < 180.0);
    }
}

#[test]
fn zero_size_configs_are_rejected() {
    let img = textured(64, 64, 2);
    let base = FeatureConfig::default();
    for bad in [
        FeatureConfig {
            octaves: 0,
            ..base.clone()
        },
        FeatureConfig {
            max_keypoints: 0,
            ..base.clone()
        },
        FeatureConfig {
            patch_size: 0,
            ..base.clone()
        },
        FeatureConfig {
            sigma: 0.0,
            ..base.clone()
        },
        FeatureConfig {
            scale_factor: f32::NAN,
            ..base.clone()
        },
    ] {
        assert!(matches!(
            detect_and_describe(&img, &bad),
            Err(PlaceError::InvalidParameter { .. })
        ));
    }
}
