use nalgebra::Point3;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

/// Points placed well inside their (ring, sector) bins: `(sector, ring, u, v, z)` with
/// `u, v ∈ [0, 1)` mapped to `[0.2, 0.8)` of the bin.
fn cloud_from_bins(bins: &[(usize, usize, f64, f64, f64)], rotate_sectors: usize) -> PointCloud {
    let sector_width = std::f64::consts::TAU / 60.0;
    let points = bins
        .iter()
        .map(|&(s, r, u, v, z)| {
            let angle = (s as f64 + 0.2 + 0.6 * u + rotate_sectors as f64) * sector_width;
            let range = (r as f64 + 0.2 + 0.6 * v) * 4.0;
            Point3::new(
                (range * angle.cos()) as f32,
                (range * angle.sin()) as f32,
                z as f32,
            )
        })
        .collect();
    PointCloud::from_points(points)
}

fn random_cloud(rng: &mut ChaCha8Rng, n: usize) -> PointCloud {
    let bins: Vec<_> = (0..n)
        .map(|_| {
            (
                rng.random_range(0..60),
                rng.random_range(0..20),
                rng.random::<f64>(),
                rng.random::<f64>(),
                rng.random_range(-1.5..6.0),
            )
        })
        .collect();
    cloud_from_bins(&bins, 0)
}

#[test]
fn bins_hold_the_maximum_height_plus_sensor_height() {
    let config = ScanContextConfig::default();
    let bins = [
        (3, 2, 0.1, 0.5, 1.0),
        (3, 2, 0.9, 0.2, 2.5),
        (10, 19, 0.5, 0.5, -3.0),
    ];
    let d = ScanContextDescriptor::new(&cloud_from_bins(&bins, 0), &config).unwrap();
    assert!((d.value(2, 3) - 4.5).abs() < 1e-6);
    // Below −h: clamped to 0, so the bin counts as empty.
    assert_eq!(d.value(19, 10), 0.0);
    assert!((d.ring_key()[2] - 1.0 / 60.0).abs() < 1e-12);
    assert_eq!(d.ring_key()[19], 0.0);
    // Beyond 80 m and non-finite points are ignored.
    let far = PointCloud::from_points(vec![
        Point3::new(81.0, 0.0, 1.0),
        Point3::new(f32::NAN, 0.0, 1.0),
    ]);
    let d = ScanContextDescriptor::new(&far, &config).unwrap();
    assert!(d.values.iter().all(|&v| v == 0.0));
}

#[test]
fn empty_columns_are_left_out_of_the_mean() {
    let config = ScanContextConfig::default();
    // One shared column with proportional profiles: distance 0 despite 59 empty columns.
    let a = cloud_from_bins(&[(0, 1, 0.5, 0.5, 1.0), (0, 3, 0.5, 0.5, 3.0)], 0);
    let b = cloud_from_bins(&[(7, 1, 0.5, 0.5, 0.0), (7, 3, 0.5, 0.5, 1.0)], 0);
    let (da, db) = (
        ScanContextDescriptor::new(&a, &config).unwrap(),
        ScanContextDescriptor::new(&b, &config).unwrap(),
    );
    // Columns (3, 5) vs (2, 3): cosine = (6 + 15) / (√34 √13).
    let expected = 1.0 - 21.0 / (34f64.sqrt() * 13f64.sqrt());
    let (d, shift) = da.distance(&db);
    assert!((d - expected).abs() < 1e-6, "{d} vs {expected}");
    assert_eq!(shift, 7);
    let empty = ScanContextDescriptor::new(&PointCloud::default(), &config).unwrap();
    assert_eq!(da.distance(&empty).0, 1.0);
}

#[test]
fn rejects_other_frames_and_bad_configs() {
    let mut sc = ScanContext::new(ScanContextConfig::default()).unwrap();
    let image = image::GrayImage::new(4, 4);
    assert!(matches!(
        sc.describe(&Frame::Image(&image)),
        Err(PlaceError::UnsupportedFrame {
            method: "scan-context",
            ..
        })
    ));
    for config in [
        ScanContextConfig {
            num_sectors: 0,
            ..Default::default()
        },
        ScanContextConfig {
            max_range: f64::NAN,
            ..Default::default()
        },
        ScanContextConfig {
            num_candidates: Some(0),
            ..Default::default()
        },
    ] {
        assert!(ScanContext::new(config).is_err());
    }
}

#[test]
fn frames_retrieve_themselves_first_with_and_without_the_tree() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let clouds: Vec<_> = (0..40).map(|_| random_cloud(&mut rng, 300)).collect();
    for config in [
        ScanContextConfig::default(),
        ScanContextConfig {
            num_candidates: None,
            ..Default::default()
        },
        ScanContextConfig {
            sector_key_window: Some(3),
            ..Default::default()
        },
    ] {
        let mut sc = ScanContext::new(config).unwrap();
        for c in &clouds {
            let d = sc.describe(&Frame::Cloud(c)).unwrap();
            sc.insert(d);
        }
        // Duplicated frames share a ring-key group and stay retrievable.
        for _ in 0..40 {
            let d = sc.describe(&Frame::Cloud(&clouds[0])).unwrap();
            sc.insert(d);
        }
        for i in 0..40 {
            let c = sc.query_stored(i, sc.len());
            let best = c.iter().max_by(|a, b| a.score.total_cmp(&b.score)).unwrap();
            assert!((best.score - 1.0).abs() < 1e-9);
            assert!(
                c.iter()
                    .any(|x| x.frame == i && (x.score - 1.0).abs() < 1e-9)
            );
            assert!(c.iter().all(|x| x.frame < sc.len()));
            if i > 0 {
                assert!(
                    c.iter()
                        .filter(|x| x.frame != i)
                        .all(|x| x.score < 1.0 - 1e-6)
                );
            }
        }
        // Only frames before `before`.
        let c = sc.query_stored(30, 20);
        assert!(!c.is_empty() && c.iter().all(|x| x.frame < 20));
        if let Some(n) = config.num_candidates {
            assert_eq!(c.len(), n);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn distance_is_invariant_to_yaw_by_whole_sectors(
        bins in prop::collection::vec(
            (0usize..60, 0usize..20, 0.0..1.0f64, 0.0..1.0f64, -1.0..5.0f64), 1..200),
        k in 0usize..60,
    ) {
        let config = ScanContextConfig::default();
        let a = ScanContextDescriptor::new(&cloud_from_bins(&bins, 0), &config).unwrap();
        let b = ScanContextDescriptor::new(&cloud_from_bins(&bins, k), &config).unwrap();
        for s in 0..60 {
            for r in 0..20 {
                prop_assert_eq!(a.value(r, s), b.value(r, (s + k) % 60));
            }
        }
        let (d, shift) = a.distance(&b);
        prop_assert!(d < 1e-6, "d = {}", d);
        prop_assert_eq!(a.ring_key(), b.ring_key());
        if a.column_norms.iter().filter(|&&n| n > 0.0).count() > 1 {
            prop_assert!(a.shifted_distance(&b, shift) < 1e-6);
        }
        prop_assert!(b.distance(&a).0 < 1e-6);
    }
}

/// Real data: frames 0, 3, 6 of KITTI 00 and 07 (two places). Each frame's best other frame
/// comes from its own sequence, with the tree and exhaustively.
#[test]
fn kitti_frames_prefer_the_same_place() {
    let mut clouds = Vec::new();
    for seq in ["00", "07"] {
        for frame in [0, 3, 6] {
            let Some(c) = crate::local_bow::tests::kitti_scan(seq, frame) else {
                return;
            };
            clouds.push(c);
        }
    }
    for num_candidates in [Some(3), None] {
        let config = ScanContextConfig {
            num_candidates,
            ..Default::default()
        };
        let mut sc = ScanContext::new(config).unwrap();
        for c in &clouds {
            let d = sc.describe(&Frame::Cloud(c)).unwrap();
            sc.insert(d);
        }
        for i in 0..6 {
            let mut c = sc.query_stored(i, 6);
            c.sort_by(|a, b| b.score.total_cmp(&a.score));
            assert_eq!(c[0].frame, i);
            assert_eq!(c[1].frame / 3, i / 3, "frame {i}: {c:?}");
        }
    }
}
