//! A long corridor without features along it, scanned every 0.8 m (one scan a second): every
//! pose along the corridor fits a scan equally well, so the front-end must keep the odometry's
//! step. The earlier rule searched the last pose whenever a step exceeded two coarsest cells
//! and took it when it scored a little better: the robot stood still in the corridor.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::f64::consts::TAU;

use nalgebra::Point2;
use raypath_geometry::{Pose2, Scan2};
use raypath_sim::scene2::{SceneBuilder2, Surface};
use raypath_slam::{Slam, SlamConfig};

/// A 60 m × 2 m corridor whose far ends lie beyond the 10 m range of every scan but the first
/// and the last few.
fn corridor() -> raypath_sim::scene2::Scene2 {
    let mut builder = SceneBuilder2::new();
    let wall = builder.add_surface(Surface {
        label: 1,
        reflectivity: 0.5,
    });
    let corners = [[-2.0, -1.0], [58.0, -1.0], [58.0, 1.0], [-2.0, 1.0]];
    let corners: Vec<Point2<f64>> = corners.iter().map(|c| Point2::new(c[0], c[1])).collect();
    builder.add_polygon(&corners, wall);
    builder.build().unwrap()
}

fn scan_at(scene: &raypath_sim::scene2::Scene2, pose: Pose2) -> Scan2 {
    let n = 360;
    let origin = Point2::new(pose.x(), pose.y());
    let ranges = (0..n)
        .map(|k| {
            let a = pose.theta() + k as f64 * TAU / n as f64;
            scene
                .cast_angle(&origin, a, 10.0)
                .map_or(10.0, |h| h.range_m)
        })
        .collect();
    Scan2 {
        angle_min_rad: 0.0,
        angle_increment_rad: TAU / n as f64,
        max_range_m: 10.0,
        ranges,
        intensities: None,
    }
}

#[test]
fn a_featureless_corridor_keeps_the_odometry_step() {
    let scene = corridor();
    let mut slam = Slam::new(SlamConfig {
        loops: None,
        ..SlamConfig::default()
    })
    .unwrap();
    let poses: Vec<Pose2> = (0..50)
        .map(|k| Pose2::new(0.8 * k as f64, 0.0, 0.0))
        .collect();
    for (k, pose) in poses.iter().enumerate() {
        slam.process_scan(k as f64, &scan_at(&scene, *pose), Some(*pose))
            .unwrap();
    }
    let out = slam.finish().unwrap();
    let end = out.world_from_sensor.last().unwrap();
    // 39.2 m driven; the robot must not have stood still (0.8 m lost a scan).
    assert!(
        (end.x() - 39.2).abs() < 0.5 && end.y().abs() < 0.2,
        "ends at {end:?}, expected (39.2, 0)"
    );
}

#[test]
fn bad_front_end_settings_are_errors_naming_the_field() {
    for (name, config) in [
        ("rotation_window_growth", {
            let mut c = SlamConfig::default();
            c.submaps.rotation_window_growth = -0.1;
            c
        }),
        ("tracking.max_speed_mps", {
            let mut c = SlamConfig::default();
            c.tracking.max_speed_mps = Some(f64::NAN);
            c
        }),
    ] {
        let err = Slam::new(config).unwrap_err().to_string();
        assert!(err.contains(name), "{err}");
    }
}
