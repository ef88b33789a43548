//! Times the stages of one extraction (development aid).
#![allow(missing_docs, clippy::expect_used)]
use nalgebra::{Point3, Vector3};
use raypath_geometry::{PointCloud, Pose3};
use raypath_poles::{HitMissGrid, PoleParams, extract_poles, local_grid, occupancy, pole_scores};
const CYLINDERS: [(f64, f64, f64); 6] = [
    (5.0, 6.0, 0.1),
    (12.0, 6.0, 0.15),
    (-7.0, 6.0, 0.3),
    (3.0, -6.0, 0.05),
    (-10.0, -6.0, 0.12),
    (9.0, -6.0, 0.2),
];

fn scan(sensor: &Point3<f64>) -> PointCloud {
    let mut points = Vec::with_capacity(64 * 1800);
    for e in 0..64 {
        let elevation = (-24.8 + e as f64 * 0.42f64).to_radians();
        for k in 0..1800 {
            let azimuth = (k as f64 * 0.2).to_radians();
            let d = Vector3::new(
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            );
            let mut t = 80.0f64;
            if d.z < 0.0 {
                t = t.min(-sensor.z / d.z);
            }
            for wall_y in [9.0, -9.0f64] {
                let tw = (wall_y - sensor.y) / d.y;
                if tw > 0.0 {
                    t = t.min(tw);
                }
            }
            for (cx, cy, r) in CYLINDERS {
                let (ox, oy) = (sensor.x - cx, sensor.y - cy);
                let a = d.x * d.x + d.y * d.y;
                let b = 2.0 * (ox * d.x + oy * d.y);
                let c = ox * ox + oy * oy - r * r;
                let disc = b * b - 4.0 * a * c;
                if a > 0.0 && disc >= 0.0 {
                    let tc = (-b - disc.sqrt()) / (2.0 * a);
                    if tc > 0.0 {
                        t = t.min(tc);
                    }
                }
            }
            if t < 80.0 {
                let p = t * d;
                points.push(Point3::new(p.x as f32, p.y as f32, p.z as f32));
            }
        }
    }
    PointCloud::from_points(points)
}
fn main() {
    let sensors: Vec<Point3<f64>> = (0..5)
        .map(|i| Point3::new(-2.0 + i as f64, 0.0, 1.73))
        .collect();
    let clouds: Vec<(Pose3, PointCloud)> = sensors
        .iter()
        .map(|s| (Pose3::from_xyz_rpy(s.x, s.y, s.z, 0.0, 0.0, 0.0), scan(s)))
        .collect();
    let scans: Vec<(Pose3, &PointCloud)> = clouds.iter().map(|(p, c)| (*p, c)).collect();
    for _ in 0..3 {
        let (poles, stats) =
            extract_poles(&scans, &Point3::new(0.0, 0.0, 1.73), &PoleParams::kitti())
                .expect("extract");
        println!("{} poles, {:?}", poles.len(), stats);
    }
    let params = PoleParams::kitti();
    let mut counts =
        HitMissGrid::new(local_grid(&Point3::new(0.0, 0.0, 1.73), &params).expect("grid"));
    counts.insert_scans_par(&scans, 120.0);
    for _ in 0..3 {
        let t = std::time::Instant::now();
        let (occ, _) = occupancy(&counts, params.occupancy_threshold);
        let t_occ = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let s = pole_scores(
            &occ,
            params.dims(),
            params.max_width_cells,
            params.hull_cells(),
        );
        let t_score = t.elapsed().as_secs_f64();
        println!(
            "occupancy {t_occ:.3} s, scores {t_score:.3} s ({} voxels)",
            s.best.len()
        );
    }
}
