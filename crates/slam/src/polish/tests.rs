use std::f64::consts::TAU;

use raypath_geometry::{Pose2, Scan2};

use super::*;
use raypath_geometry::LineTarget;

type Wall = ([f64; 2], [f64; 2]);

fn rect(lo: [f64; 2], hi: [f64; 2]) -> Vec<Wall> {
    let c = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    (0..4).map(|k| (c[k], c[(k + 1) % 4])).collect()
}

/// An 8 m × 5 m room with a pillar off the centre.
fn room() -> Vec<Wall> {
    let mut walls = rect([-4.0, -2.5], [4.0, 2.5]);
    walls.extend(rect([1.0, 0.5], [1.6, 1.1]));
    walls
}

/// Scan points (sensor frame) of `walls` from `pose`, 360 beams cast by the simulator.
fn points_at(walls: &[Wall], pose: Pose2) -> Vec<[f64; 2]> {
    use nalgebra::Point2;
    use raypath_sim::scene2::{SceneBuilder2, Surface};
    let mut builder = SceneBuilder2::new();
    let wall = builder.add_surface(Surface {
        label: 1,
        reflectivity: 0.5,
    });
    for (a, b) in walls {
        builder.add_segment(Point2::new(a[0], a[1]), Point2::new(b[0], b[1]), wall);
    }
    let scene = builder.build().unwrap();
    let n = 360;
    let origin = Point2::new(pose.x(), pose.y());
    let scan = Scan2 {
        angle_min_rad: 0.0,
        angle_increment_rad: TAU / n as f64,
        max_range_m: 20.0,
        ranges: (0..n)
            .map(|k| {
                let a = pose.theta() + k as f64 * TAU / n as f64;
                scene
                    .cast_angle(&origin, a, 20.0)
                    .map_or(20.0, |h| h.range_m)
            })
            .collect(),
        intensities: None,
    };
    scan.points(Pose2::identity())
        .filter(|p| p.coords.norm() < 19.0)
        .map(|p| [p.x, p.y])
        .collect()
}

fn off_by(a: Pose2, b: Pose2) -> (f64, f64) {
    let d = a.inverse() * b;
    (d.translation().norm(), d.theta().abs())
}

/// From a start 4 cm and 1° off, the alignment reaches the true relative pose.
#[test]
fn icp_reaches_the_true_relative_pose() {
    let walls = room();
    let (a, b) = (Pose2::new(-1.0, -0.5, 0.2), Pose2::new(-0.7, -0.4, 0.35));
    let config = PolishConfig::default();
    let target = LineTarget::new(&points_at(&walls, a), config.normal_radius_m).unwrap();
    let truth = a.inverse() * b;
    let start = truth * Pose2::new(0.03, -0.025, 1f64.to_radians());
    let aligned = target
        .align(&points_at(&walls, b), start, &config.icp())
        .unwrap();
    let (t, r) = off_by(truth, aligned.target_from_source);
    assert!(t < 1e-3 && r < 1e-4, "{t} m, {r} rad off");
    assert!(aligned.used > 100);
    // The information is symmetric positive definite in a room.
    let eig = aligned.mean_information.symmetric_eigenvalues();
    assert!(eig.min() > 0.0, "{eig:?}");
}

/// In a corridor the alignment has (almost) no information along it, full across it.
#[test]
fn a_corridor_leaves_its_axis_without_information() {
    let walls = vec![([-20.0, -1.0], [20.0, -1.0]), ([-20.0, 1.0], [20.0, 1.0])];
    let (a, b) = (Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.3, 0.05, 0.02));
    let config = PolishConfig::default();
    let target = LineTarget::new(&points_at(&walls, a), config.normal_radius_m).unwrap();
    let aligned = target
        .align(&points_at(&walls, b), a.inverse() * b, &config.icp())
        .unwrap();
    let h = aligned.mean_information;
    assert!(h[(0, 0)] < 1e-3 * h[(1, 1)], "{h}");
}

/// `T · exp(ξ) = exp(Ad(T) ξ) · T` to first order.
#[test]
fn the_adjoint_turns_right_increments_into_left_ones() {
    let t = Pose2::new(1.5, -0.7, 0.9);
    let xi = [1e-4, -2e-4, 3e-4];
    let right = t * Pose2::new(xi[0], xi[1], xi[2]);
    let v = adjoint(&t) * nalgebra::Vector3::new(xi[0], xi[1], xi[2]);
    let left = Pose2::new(v.x, v.y, v.z) * t;
    let (dt, dr) = off_by(right, left);
    assert!(dt < 1e-7 && dr < 1e-9, "{dt} {dr}");
}

/// A chain of scans in the room whose poses carry centimetre errors between neighbours:
/// polishing with ICP edges (and no node graph) brings every relative pose to within a few
/// millimetres of the truth.
#[test]
fn polishing_removes_centimetre_errors_between_scans() {
    let walls = room();
    let truth: Vec<Pose2> = (0..12)
        .map(|k| {
            Pose2::new(
                -2.5 + 0.35 * k as f64,
                -0.8 + 0.05 * k as f64,
                0.15 * k as f64,
            )
        })
        .collect();
    let points: Vec<Vec<[f64; 2]>> = truth.iter().map(|p| points_at(&walls, *p)).collect();
    let noisy: Vec<Pose2> = truth
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let s = if k % 2 == 0 { 1.0 } else { -1.0 };
            *p * Pose2::new(0.02 * s, -0.015 * s, 0.4f64.to_radians() * s)
        })
        .collect();
    let scans: Vec<ScanPose> = noisy
        .iter()
        .enumerate()
        .map(|(k, p)| ScanPose {
            stamp_secs: k as f64,
            local: *p,
            node: k,
            is_node: true,
        })
        .collect();
    let node_scan: Vec<usize> = (0..truth.len()).collect();
    let nodes = ScanNodes {
        scans: &scans,
        node_scan: &node_scan,
        node_local: &noisy,
    };
    let weak = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, 10.0));
    let config = PolishConfig {
        neighbours: 2,
        ..PolishConfig::default()
    };
    let (polished, edges) = polish(
        &noisy,
        &points,
        &PoseGraph::new(),
        &nodes,
        &weak,
        &config,
        &SolverConfig::default(),
    )
    .unwrap();
    assert_eq!(edges, 2 * truth.len() - 3);
    let worst = |poses: &[Pose2]| {
        (1..poses.len())
            .map(|k| {
                off_by(
                    truth[k - 1].inverse() * truth[k],
                    poses[k - 1].inverse() * poses[k],
                )
                .0
            })
            .fold(0.0, f64::max)
    };
    let (before, after) = (worst(&noisy), worst(&polished));
    assert!(
        before > 0.02 && after < 2e-3,
        "before {before} m, after {after} m"
    );
}

/// Settings out of range are errors naming the field.
#[test]
fn bad_settings_are_errors() {
    let ok = PolishConfig::default();
    assert!(ok.validate().is_ok());
    let cases = [
        (
            PolishConfig {
                neighbours: 0,
                ..ok.clone()
            },
            "polish.neighbours",
        ),
        (
            PolishConfig {
                gates_m: vec![0.1, -1.0],
                ..ok.clone()
            },
            "polish.gates_m",
        ),
        (
            PolishConfig {
                point_sigma_m: f64::NAN,
                ..ok.clone()
            },
            "polish.point_sigma_m",
        ),
        (
            PolishConfig {
                max_correction: (0.1, 0.0),
                ..ok.clone()
            },
            "polish.max_correction.1",
        ),
    ];
    for (config, name) in cases {
        let err = config.validate().unwrap_err().to_string();
        assert!(err.contains(name), "{err}");
    }
}
