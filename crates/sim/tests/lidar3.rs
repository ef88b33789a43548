//! Lidar scans against analytic answers: ranges on a plane and a cylinder, noise statistics,
//! dropout, labels, intensities and determinism across thread counts.

#![allow(clippy::unwrap_used)]

use nalgebra::{Point3, Vector3};
use raypath_geometry::{Pose3, Range};
use raypath_sim::lidar3::{IntensityModel, Lidar3};
use raypath_sim::scene3::{Scene3, SceneBuilder3, Surface};

/// A 400 m square floor at z = 0 (label 10) and a wall at x = 20 (label 11), both reflectivity 0.5.
fn floor_and_wall() -> Scene3 {
    let mut b = SceneBuilder3::new();
    let floor = b.add_surface(Surface {
        label: 10,
        reflectivity: 0.5,
    });
    let wall = b.add_surface(Surface {
        label: 11,
        reflectivity: 0.5,
    });
    let s = 200.0;
    b.add_polygon(
        &[
            Point3::new(-s, -s, 0.0),
            Point3::new(s, -s, 0.0),
            Point3::new(s, s, 0.0),
            Point3::new(-s, s, 0.0),
        ],
        floor,
    );
    b.add_polygon(
        &[
            Point3::new(20.0, -s, -1.0),
            Point3::new(20.0, s, -1.0),
            Point3::new(20.0, s, 50.0),
            Point3::new(20.0, -s, 50.0),
        ],
        wall,
    );
    b.build().unwrap()
}

fn noiseless(mut lidar: Lidar3) -> Lidar3 {
    lidar.range_noise_sigma_m = 0.0;
    lidar.angular_noise_sigma_rad = 0.0;
    lidar.dropout_probability = 0.0;
    lidar.intensity = IntensityModel::lambertian();
    lidar
}

/// Analytic range of a beam from `origin` (height h above the floor) to the floor or wall.
/// The unit direction of beam (`row`, `col`) from its elevation and azimuth, computed here
/// rather than taken from the simulator so the tests check it.
fn beam(lidar: &Lidar3, row: usize, col: usize) -> Vector3<f64> {
    let (el, az) = (lidar.elevations_rad[row], lidar.azimuths_rad[col]);
    Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
}

fn analytic(origin: &Point3<f64>, dir: &Vector3<f64>) -> Option<(f64, u32)> {
    let floor = (dir.z < 0.0).then(|| -origin.z / dir.z);
    let wall = (dir.x > 0.0).then(|| (20.0 - origin.x) / dir.x);
    match (floor, wall) {
        (Some(f), Some(w)) if w < f => Some((w, 11)),
        (Some(f), _) => Some((f, 10)),
        (None, Some(w)) => Some((w, 11)),
        (None, None) => None,
    }
}

#[test]
fn hdl64e_ranges_on_floor_and_wall_match_the_analytic_answer() {
    let scene = floor_and_wall();
    let lidar = noiseless(Lidar3::hdl64e().with_firings(360).unwrap());
    let pose = Pose3::from_xyz_rpy(0.0, 0.0, 1.73, 0.0, 0.0, 0.0);
    let scan = lidar.scan(&scene, &pose, 1, 0).unwrap();
    assert_eq!((scan.cloud.height, scan.cloud.width), (64, 360));
    let origin = Point3::new(0.0, 0.0, 1.73);
    let labels = scan.cloud.label.as_ref().unwrap();
    let mut checked = 0;
    for row in 0..64 {
        for col in 0..360 {
            let i = row * 360 + col;
            let dir = beam(&lidar, row, col);
            let p = scan.cloud.points[i];
            match analytic(&origin, &dir).filter(|(r, _)| *r <= lidar.max_range_m && *r >= 0.9) {
                Some((r, label)) => {
                    let expected = (dir * r).cast::<f32>();
                    assert!((p.coords - expected).norm() < 1e-3, "{row},{col}");
                    assert_eq!(labels[i], label);
                    assert!(scan.surfaces[i].is_some());
                    checked += 1;
                }
                None => {
                    assert!(p.x.is_nan(), "{row},{col}: {p:?}");
                    assert_eq!(labels[i], 0);
                }
            }
        }
    }
    assert!(checked > 64 * 300, "{checked}");
    // The ideal image equals the measured one without noise.
    let ideal = scan.ideal_range_image().unwrap();
    let measured = scan.range_image().unwrap();
    for (a, b) in ideal.ranges_m().iter().zip(measured.ranges_m()) {
        assert!((a.is_nan() && b.is_nan()) || (a - b).abs() < 1e-3);
    }
    assert_eq!(
        measured.range(63, 0).map(|r| matches!(r, Range::Hit(_))),
        Some(true)
    );
}

#[test]
fn cylinder_hits_match_the_circle() {
    let mut b = SceneBuilder3::new();
    let s = b.add_surface(Surface {
        label: 3,
        reflectivity: 0.7,
    });
    b.add_cylinder(Point3::new(6.0, 0.0, -5.0), 1.0, 10.0, 720, s);
    let scene = b.build().unwrap();
    let lidar = Lidar3::organized(3, 41, 0.1, -0.1, -0.15, 0.15).unwrap();
    let scan = lidar.scan(&scene, &Pose3::identity(), 0, 0).unwrap();
    for (i, p) in scan.cloud.points.iter().enumerate() {
        let row = i / 41;
        let horizontal = p.coords.xy().cast::<f64>();
        assert!(!p.x.is_nan());
        // On the 720-gon: within (1 − cos(π/720)) of the unit circle around (6, 0).
        let d = (horizontal - nalgebra::Vector2::new(6.0, 0.0)).norm();
        assert!((d - 1.0).abs() < 1e-4, "{i}: {d}");
        assert!(
            (f64::from(p.z) - p.coords.xy().norm() as f64 * lidar.elevations_rad[row].tan()).abs()
                < 1e-4
        );
        assert_eq!(scan.cloud.label.as_ref().unwrap()[i], 3);
    }
}

/// Thousands of beams on a wall: the sample mean and standard deviation of the range error
/// match the configured noise.
#[test]
fn range_noise_has_the_configured_standard_deviation() {
    let scene = floor_and_wall();
    let mut lidar = Lidar3::organized(60, 100, 0.2, 0.05, -0.4, 0.4).unwrap();
    lidar.range_noise_sigma_m = 0.02;
    let pose = Pose3::from_xyz_rpy(0.0, 0.0, 2.0, 0.0, 0.0, 0.0);
    let scan = lidar.scan(&scene, &pose, 42, 7).unwrap();
    let ranges = scan.ranges_m();
    let errors: Vec<f64> = ranges
        .iter()
        .zip(&scan.true_ranges_m)
        .map(|(m, t)| f64::from(m - t))
        .collect();
    assert_eq!(errors.len(), 6000);
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / n;
    let std = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    assert!(mean.abs() < 3.0 * 0.02 / n.sqrt() + 1e-5, "mean {mean}");
    assert!((std / 0.02 - 1.0).abs() < 0.05, "std {std}");
    // Extra noise from a noise-free scan: the same statistics.
    let clean = {
        let mut l = lidar.clone();
        l.range_noise_sigma_m = 0.0;
        l.scan(&scene, &pose, 42, 7).unwrap()
    };
    let noisy = clean.with_range_noise(0.04, 5, 1).unwrap();
    let errors: Vec<f64> = noisy
        .points
        .iter()
        .zip(&clean.true_ranges_m)
        .map(|(p, t)| f64::from(p.coords.norm() - t))
        .collect();
    let std = (errors.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
    assert!((std / 0.04 - 1.0).abs() < 0.05, "std {std}");
    assert_eq!(noisy, clean.with_range_noise(0.04, 5, 1).unwrap());
    assert_ne!(noisy, clean.with_range_noise(0.04, 5, 2).unwrap());
}

/// Angular noise moves where the beam lands, not where the point is reported: on a wall seen
/// head-on at 20 m, σ_ang = 1 mrad changes the range by ≈ 20 m · (1 − cos δ) only, but on
/// the floor seen at a grazing angle the range error is about r · σ_ang / tan(incidence).
#[test]
fn angular_noise_spreads_grazing_ranges_and_keeps_nominal_directions() {
    let scene = floor_and_wall();
    let sigma = 1e-3;
    let mut lidar = Lidar3::organized(50, 100, -0.10, -0.11, -0.3, 0.3).unwrap();
    lidar.angular_noise_sigma_rad = sigma;
    let pose = Pose3::from_xyz_rpy(0.0, 0.0, 1.0, 0.0, 0.0, 0.0);
    let scan = lidar.scan(&scene, &pose, 3, 0).unwrap();
    let mut sum_sq = 0.0;
    let mut expected_sq = 0.0;
    for (i, p) in scan.cloud.points.iter().enumerate() {
        let (row, col) = (i / 100, i % 100);
        let el = lidar.elevations_rad[row];
        let dir = beam(&lidar, row, col);
        let v = p.coords.cast::<f64>();
        assert!(
            (v.normalize() - dir).norm() < 1e-6,
            "reported off the nominal beam"
        );
        let r0 = 1.0 / -el.sin();
        // d r / d el = r / tan(el) for a floor at height 1.
        let slope = r0 / el.tan();
        sum_sq += (v.norm() - r0).powi(2);
        expected_sq += (slope * sigma).powi(2);
    }
    let ratio = (sum_sq / expected_sq).sqrt();
    assert!((ratio - 1.0).abs() < 0.06, "{ratio}");
}

#[test]
fn dropout_intensity_and_labels() {
    let scene = floor_and_wall();
    let mut lidar = Lidar3::organized(40, 200, -0.05, -0.4, -1.0, 1.0).unwrap();
    lidar.dropout_probability = 0.1;
    let pose = Pose3::from_xyz_rpy(0.0, 0.0, 2.0, 0.0, 0.0, 0.0);
    let scan = lidar.scan(&scene, &pose, 11, 0).unwrap();
    let hits = scan.surfaces.iter().filter(|s| s.is_some()).count();
    let returns = scan.cloud.num_valid();
    let lost = (hits - returns) as f64 / hits as f64;
    // 8000 beams: binomial standard deviation ≈ 0.34 %.
    assert!((lost - 0.1).abs() < 0.012, "{lost}");
    let intensity = scan.cloud.intensity.as_ref().unwrap();
    let labels = scan.cloud.label.as_ref().unwrap();
    for i in 0..scan.cloud.len() {
        let surface = scan.surfaces[i].map(|s| scene.surface(s).unwrap().label);
        if scan.cloud.is_valid(i) {
            assert_eq!(Some(labels[i]), surface);
            // Lambertian: reflectivity × cos(incidence): 0.5 · |sin el| on the floor,
            // 0.5 · cos el · cos az on the wall.
            let (el, az) = (lidar.elevations_rad[i / 200], lidar.azimuths_rad[i % 200]);
            let cos = if labels[i] == 10 {
                el.sin().abs()
            } else {
                el.cos() * az.cos()
            };
            assert!((f64::from(intensity[i]) - 0.5 * cos).abs() < 1e-5);
        } else {
            assert_eq!((labels[i], intensity[i]), (0, 0.0));
        }
    }
}

#[test]
fn scans_are_identical_for_any_thread_count_and_differ_between_scan_indices() {
    let scene = floor_and_wall();
    let lidar = Lidar3::hdl32e().with_firings(500).unwrap();
    let pose = Pose3::from_xyz_rpy(1.0, -2.0, 1.8, 0.01, -0.02, 0.3);
    let run = |threads: usize, index: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| lidar.scan(&scene, &pose, 99, index).unwrap())
    };
    let one = run(1, 4);
    let two = run(2, 4);
    let bytes = |s: &raypath_sim::lidar3::SimScan| -> Vec<u32> {
        s.cloud
            .points
            .iter()
            .flat_map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .chain(
                s.cloud
                    .intensity
                    .as_ref()
                    .unwrap()
                    .iter()
                    .map(|v| v.to_bits()),
            )
            .collect()
    };
    assert_eq!(bytes(&one), bytes(&two));
    assert_eq!(one.cloud.label, two.cloud.label);
    assert_ne!(bytes(&one), bytes(&run(2, 5)));
}

#[test]
fn bad_pose_is_an_error() {
    let scene = floor_and_wall();
    let pose = Pose3::from_xyz_rpy(f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0);
    assert!(Lidar3::hdl32e().scan(&scene, &pose, 0, 0).is_err());
}

#[test]
fn moving_sweeps_start_beams_where_the_sensor_was_and_report_in_the_reference_frame() {
    let scene = floor_and_wall();
    let lidar = noiseless(Lidar3::hdl64e().with_firings(360).unwrap());
    let pose = Pose3::from_xyz_rpy(0.0, 0.0, 1.73, 0.0, 0.0, 0.0);
    // 2 m forward over the sweep: the beams facing forward (middle column) start at the pose,
    // the first column (the back, half a turn earlier) 1 m behind, the last 1 m ahead.
    let motion = Vector3::new(2.0, 0.0, 0.0);
    let moving = lidar.scan_moving(&scene, &pose, &motion, 1, 0).unwrap();
    let still = lidar.scan(&scene, &pose, 1, 0).unwrap();
    let mut checked = 0;
    for row in 0..64 {
        for col in 0..360 {
            let i = row * 360 + col;
            let dir = beam(&lidar, row, col);
            let tau = (col as f64 + 0.5) / 360.0 - 0.5;
            let start = Point3::new(2.0 * tau, 0.0, 1.73);
            let Some((r, _)) = analytic(&start, &dir).filter(|(r, _)| (0.9..=120.0).contains(r))
            else {
                continue;
            };
            // The point is the moving origin plus the range, in the frame of the pose.
            let expected = Vector3::new(2.0 * tau, 0.0, 0.0) + dir * r;
            let p = moving.cloud.points[i].cast::<f64>();
            assert!((p.coords - expected).norm() < 1e-3, "row {row} col {col}");
            assert!((f64::from(moving.true_ranges_m[i]) - r).abs() < 1e-3);
            checked += 1;
        }
    }
    assert!(checked > 10_000);
    // Without motion the moving scan is the still one, bit for bit.
    let zero = lidar
        .scan_moving(&scene, &pose, &Vector3::zeros(), 1, 0)
        .unwrap();
    let bits = |s: &raypath_sim::lidar3::SimScan| -> Vec<u32> {
        s.cloud
            .points
            .iter()
            .flat_map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .chain(s.true_ranges_m.iter().map(|r| r.to_bits()))
            .collect()
    };
    assert_eq!(bits(&zero), bits(&still));
}
