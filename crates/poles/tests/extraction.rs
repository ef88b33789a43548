//! Property tests of pole extraction on synthetic scenes: a vertical cylinder is found at its
//! centre within a voxel; a wall is not a pole.

use nalgebra::{Point3, Vector3};
use proptest::prelude::*;
use raypath_geometry::{PointCloud, Pose3};
use raypath_poles::{PoleParams, extract_poles};

/// A scan of a scene from `sensor`: rays on a fan of azimuths and elevations, each ending at
/// the first of a vertical cylinder (centre, radius), a wall plane `x = wall_x` (finite
/// `y` span) or the ground `z = 0`; none beyond 40 m.
fn scan(
    sensor: &Point3<f64>,
    cylinder: Option<(f64, f64, f64)>,
    wall: Option<(f64, f64, f64)>,
) -> PointCloud {
    let mut points = Vec::new();
    for e in 0..24 {
        let elevation = (-25.0 + e as f64 * 1.7f64).to_radians();
        for k in 0..1800 {
            let azimuth = (k as f64 * 0.2).to_radians();
            let d = Vector3::new(
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            );
            let mut t_best = 40.0f64;
            if d.z < 0.0 {
                t_best = t_best.min(-sensor.z / d.z);
            }
            if let Some((cx, cy, r)) = cylinder {
                // |(o + t d − c)_xy|² = r²
                let (ox, oy) = (sensor.x - cx, sensor.y - cy);
                let a = d.x * d.x + d.y * d.y;
                let b = 2.0 * (ox * d.x + oy * d.y);
                let c = ox * ox + oy * oy - r * r;
                let disc = b * b - 4.0 * a * c;
                if a > 0.0 && disc >= 0.0 {
                    let t = (-b - disc.sqrt()) / (2.0 * a);
                    if t > 0.0 && sensor.z + t * d.z < 6.0 {
                        t_best = t_best.min(t);
                    }
                }
            }
            if let Some((wx, y0, y1)) = wall
                && d.x.abs() > 1e-9
            {
                let t = (wx - sensor.x) / d.x;
                let y = sensor.y + t * d.y;
                if t > 0.0 && y >= y0 && y <= y1 && sensor.z + t * d.z < 4.0 {
                    t_best = t_best.min(t);
                }
            }
            if t_best < 40.0 {
                let p = t_best * d;
                points.push(Point3::new(p.x as f32, p.y as f32, p.z as f32));
            }
        }
    }
    PointCloud::from_points(points)
}

/// The KITTI preset in a 16 m × 16 m × 3 m local map (the full 30 m × 30 m only costs time).
fn params() -> PoleParams {
    PoleParams {
        extent_m: [16.0, 16.0, 3.0],
        sensor_in_grid_m: [8.0, 8.0, 2.0],
        ..PoleParams::kitti()
    }
}

/// Sensor positions of a drive past `(cx, cy)` at 4 m lateral distance, every 2 m.
fn sensors(cx: f64, cy: f64) -> Vec<Point3<f64>> {
    (0..9)
        .map(|i| Point3::new(cx - 4.0, cy - 8.0 + 2.0 * i as f64, 1.8))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3))]

    #[test]
    fn a_cylinder_is_found_at_its_centre(
        cx in -3.0f64..3.0, cy in -3.0f64..3.0, r in 0.06f64..0.3
    ) {
        let params = params();
        let clouds: Vec<(Pose3, PointCloud)> = sensors(cx, cy)
            .into_iter()
            .map(|s| (Pose3::from_xyz_rpy(s.x, s.y, s.z, 0.0, 0.0, 0.0), scan(&s, Some((cx, cy, r)), None)))
            .collect();
        let scans: Vec<(Pose3, &PointCloud)> = clouds.iter().map(|(p, c)| (*p, c)).collect();
        let (poles, _) = extract_poles(&scans, &Point3::new(cx - 4.0, cy, 1.8), &params).expect("extract");
        prop_assert_eq!(poles.len(), 1, "poles {:?}", poles);
        let p = poles[0];
        let err = ((p.x - cx).powi(2) + (p.y - cy).powi(2)).sqrt();
        prop_assert!(err <= params.voxel_m, "centre error {} m, pole {:?}", err, p);
        prop_assert!((p.width - 2.0 * r).abs() < 0.35, "width {} for radius {}", p.width, r);
        prop_assert!(p.height() >= 1.0);
    }

    #[test]
    fn a_wall_is_not_a_pole(wx in 0.0f64..6.0, len in 3.0f64..10.0) {
        let params = params();
        let clouds: Vec<(Pose3, PointCloud)> = sensors(0.0, 0.0)
            .into_iter()
            .map(|s| (Pose3::from_xyz_rpy(s.x, s.y, s.z, 0.0, 0.0, 0.0), scan(&s, None, Some((wx, -len / 2.0, len / 2.0)))))
            .collect();
        let scans: Vec<(Pose3, &PointCloud)> = clouds.iter().map(|(p, c)| (*p, c)).collect();
        let (poles, _) = extract_poles(&scans, &Point3::new(-4.0, 0.0, 1.8), &params).expect("extract");
        prop_assert!(poles.is_empty(), "a wall gave poles {:?}", poles);
    }
}
