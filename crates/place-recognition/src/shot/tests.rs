use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_geometry::PointCloud;

use super::*;

/// A lattice of 0.05 m spacing filling [0, 1) × [0, 0.5) × [0, 0.2), off the voxel faces.
fn lattice() -> PointCloud {
    let mut points = Vec::new();
    let mut intensity = Vec::new();
    for i in 0..20 {
        for j in 0..10 {
            for k in 0..4 {
                let p = Point3::new(
                    i as f32 * 0.05 + 0.0125,
                    j as f32 * 0.05 + 0.0125,
                    k as f32 * 0.05 + 0.0125,
                );
                points.push(p);
                intensity.push((i % 2) as f32);
            }
        }
    }
    points.push(Point3::new(f32::NAN, 0.0, 0.0));
    intensity.push(1.0);
    let mut cloud = PointCloud::from_points(points);
    cloud.intensity = Some(intensity);
    cloud
}

#[test]
fn voxel_grid_counts_centroids_and_order() {
    let cloud = lattice();
    let down = voxel_downsample(&cloud, 0.1).unwrap();
    assert_eq!(down.len(), 10 * 5 * 2);
    // Lexicographic voxel order: z fastest. Voxel (0, 0, 0) holds 8 points centred at 0.0375.
    assert!((down.points[0] - Point3::new(0.0375, 0.0375, 0.0375)).norm() < 1e-6);
    assert!((down.points[1] - Point3::new(0.0375, 0.0375, 0.1375)).norm() < 1e-6);
    assert!((down.points[10] - Point3::new(0.1375, 0.0375, 0.0375)).norm() < 1e-6);
    // Intensity 0 and 1 alternate along x: the mean of every voxel is 0.5.
    assert!(
        down.intensity
            .as_ref()
            .unwrap()
            .iter()
            .all(|&v| (v - 0.5).abs() < 1e-6)
    );
    // The input order does not matter.
    let mut order: Vec<usize> = (0..cloud.len()).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(3));
    let mut shuffled = PointCloud::from_points(order.iter().map(|&i| cloud.points[i]).collect());
    shuffled.intensity = Some(
        order
            .iter()
            .map(|&i| cloud.intensity.as_ref().unwrap()[i])
            .collect(),
    );
    let again = voxel_downsample(&shuffled, 0.1).unwrap();
    for (a, b) in down.points.iter().zip(&again.points) {
        assert!((a - b).norm() < 1e-6);
    }
    assert_eq!(voxel_downsample(&cloud, 0.25).unwrap().len(), 4 * 2);
    assert!(voxel_downsample(&cloud, 0.0).is_err());
}

#[test]
fn keypoints_one_per_coarse_cell_nearest_first() {
    let down = voxel_downsample(&lattice(), 0.1).unwrap();
    let all = uniform_keypoints(&down, 0.5, 100).unwrap();
    assert_eq!(all.len(), 2);
    let some = uniform_keypoints(&down, 0.1, 30).unwrap();
    assert_eq!(some.len(), 30);
    assert!(some.windows(2).all(|w| w[0] < w[1]));
    // The 30 nearest the origin: no kept point is farther than any dropped one.
    let r = |i: usize| down.point_f64(i).coords.norm();
    let kept = some.iter().map(|&i| r(i)).fold(0.0, f64::max);
    let dropped = (0..down.len())
        .filter(|i| !some.contains(i))
        .map(r)
        .fold(f64::INFINITY, f64::min);
    assert!(kept <= dropped);
}

/// A smooth, generic surface patch with a ridge, sampled randomly, with intensities.
fn surface(n: usize) -> PointCloud {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut points = Vec::with_capacity(n);
    let mut intensity = Vec::with_capacity(n);
    for _ in 0..n {
        let (x, y) = (
            rng.random_range(-1.5..1.5f64),
            rng.random_range(-1.5..1.5f64),
        );
        let z = 0.3 * (2.0 * x).sin() * (1.5 * y + 0.3).cos()
            + 0.1 * x * y
            + 0.2 * (-(x - 0.3).powi(2) * 8.0).exp();
        points.push(Point3::new(x as f32, y as f32, z as f32));
        intensity.push((50.0 + 40.0 * (3.0 * x + y).sin()) as f32);
    }
    let mut cloud = PointCloud::from_points(points);
    cloud.intensity = Some(intensity);
    cloud
}

fn transformed(cloud: &PointCloud, t: &Isometry3<f64>) -> PointCloud {
    let mut out = cloud.clone();
    for p in &mut out.points {
        *p = (t * p.cast::<f64>()).cast::<f32>();
    }
    out
}

#[test]
fn shot_is_invariant_to_a_rigid_motion() {
    let cloud = surface(6000);
    let keypoints: Vec<usize> = (0..cloud.len())
        .filter(|&i| cloud.points[i].x.abs() < 0.7 && cloud.points[i].y.abs() < 0.7)
        .step_by(40)
        .take(12)
        .collect();
    let t = Isometry3::from_parts(
        Translation3::new(10.0, -4.0, 2.0),
        UnitQuaternion::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0)),
            1.0,
        ),
    );
    let moved = transformed(&cloud, &t);
    let viewpoint = Point3::new(0.0, 0.0, 5.0);
    for with_intensity in [false, true] {
        let config = ShotConfig {
            with_intensity,
            ..ShotConfig::default()
        };
        let a = shot_at_keypoints(&cloud, &keypoints, &viewpoint, &config).unwrap();
        let b = shot_at_keypoints(&moved, &keypoints, &(t * viewpoint), &config).unwrap();
        assert_eq!(a.keypoints, keypoints);
        assert_eq!(b.keypoints, keypoints);
        assert_eq!(a.dim, if with_intensity { 1344 } else { 352 });
        for i in 0..a.len() {
            let (da, db) = (a.get(i), b.get(i));
            let norm = da.iter().map(|v| v * v).sum::<f32>().sqrt();
            assert!((norm - 1.0).abs() < 1e-5);
            if with_intensity {
                let shape = da[..SHOT_SHAPE_LEN]
                    .iter()
                    .map(|v| v * v)
                    .sum::<f32>()
                    .sqrt();
                assert!((shape - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-5);
            }
            let diff = da
                .iter()
                .zip(db)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f32>()
                .sqrt();
            assert!(diff < 1e-3, "keypoint {i}: |a − b| = {diff}");
        }
        // Different places give clearly different descriptors.
        let cross = a
            .get(0)
            .iter()
            .zip(a.get(5))
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f32>();
        assert!(cross.sqrt() > 0.05);
    }
}

#[test]
fn sparse_keypoints_are_skipped_and_bad_input_rejected() {
    let cloud =
        PointCloud::from_points(vec![Point3::new(0.0, 0.0, 0.0), Point3::new(0.1, 0.0, 0.0)]);
    let config = ShotConfig::default();
    let d = shot_at_keypoints(&cloud, &[0, 1], &Point3::origin(), &config).unwrap();
    assert!(d.is_empty());
    assert!(shot_at_keypoints(&cloud, &[2], &Point3::origin(), &config).is_err());
    let textured = ShotConfig {
        with_intensity: true,
        ..config
    };
    assert!(shot_at_keypoints(&cloud, &[0], &Point3::origin(), &textured).is_err());
    assert!(
        describe_cloud(
            &cloud,
            &ShotConfig {
                max_keypoints: 0,
                ..config
            }
        )
        .is_err()
    );
    assert!(
        describe_cloud(&PointCloud::default(), &config)
            .unwrap()
            .is_empty()
    );
}

#[test]
fn describe_cloud_runs_the_pipeline() {
    let cloud = surface(20_000);
    let config = ShotConfig {
        keypoint_spacing: 0.5,
        with_intensity: true,
        ..ShotConfig::default()
    };
    let d = describe_cloud(&cloud, &config).unwrap();
    assert!(d.len() >= 20, "{} keypoints", d.len());
    assert_eq!(d.values.len(), d.len() * 1344);
    assert_eq!(d, describe_cloud(&cloud, &config).unwrap());
}
