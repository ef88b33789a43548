use std::f64::consts::{FRAC_PI_2, PI};

use raypath_geometry::{Pose2, Scan2};

use super::*;
use crate::{PolarConfig, PolarContext};

type Wall = ([f64; 2], [f64; 2]);

fn rect(lo: [f64; 2], hi: [f64; 2]) -> Vec<Wall> {
    let c = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    (0..4).map(|k| (c[k], c[(k + 1) % 4])).collect()
}

/// An 8 m × 5 m room with a pillar off the centre.
fn room_a() -> Vec<Wall> {
    let mut walls = rect([-4.0, -2.5], [4.0, 2.5]);
    walls.extend(rect([1.0, 0.5], [1.6, 1.1]));
    walls
}

/// A 6 m × 6 m room with two pillars.
fn room_b() -> Vec<Wall> {
    let mut walls = rect([-3.0, -3.0], [3.0, 3.0]);
    walls.extend(rect([-2.0, -2.0], [-1.2, -1.5]));
    walls.extend(rect([0.5, 1.8], [0.9, 2.2]));
    walls
}

/// The range along `direction` from `origin` to the nearest wall.
fn cast(walls: &[Wall], origin: [f64; 2], direction: [f64; 2]) -> Option<f64> {
    walls
        .iter()
        .filter_map(|(a, b)| {
            let e = [b[0] - a[0], b[1] - a[1]];
            let denom = direction[0] * e[1] - direction[1] * e[0];
            if denom.abs() < 1e-12 {
                return None;
            }
            let w = [a[0] - origin[0], a[1] - origin[1]];
            let t = (w[0] * e[1] - w[1] * e[0]) / denom;
            let u = (w[0] * direction[1] - w[1] * direction[0]) / denom;
            (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
        })
        .min_by(f64::total_cmp)
}

/// A scan of `walls` from `pose`: `beams` beams over `fov` radians centred on the heading.
fn scan_at(walls: &[Wall], pose: Pose2, fov: f64, beams: usize) -> Scan2 {
    let increment = fov / beams as f64;
    let angle_min = -fov / 2.0;
    Scan2 {
        angle_min_rad: angle_min,
        angle_increment_rad: increment,
        max_range_m: 20.0,
        ranges: (0..beams)
            .map(|k| {
                let a = pose.theta() + angle_min + k as f64 * increment;
                cast(walls, [pose.x(), pose.y()], [a.cos(), a.sin()]).unwrap_or(20.0)
            })
            .collect(),
        intensities: None,
    }
}

fn checker() -> GeometricCheck<PolarContext> {
    GeometricCheck::new(
        PolarContext::new(PolarConfig::default()).unwrap(),
        GeometricCheckConfig::default(),
    )
    .unwrap()
}

fn support(a: &Scan2, b: &Scan2) -> f64 {
    let check = checker();
    check.support(&check.index(a), &check.index(b))
}

/// Two full-circle scans of one room, 1.2 m and 100° apart, align with almost all points.
#[test]
fn two_scans_of_one_room_are_supported() {
    let a = scan_at(&room_a(), Pose2::new(-1.5, -0.8, 0.2), 2.0 * PI, 360);
    let b = scan_at(&room_a(), Pose2::new(-0.5, -0.2, 0.2 + 1.75), 2.0 * PI, 360);
    let s = support(&a, &b);
    assert!(s > 0.9, "support {s}");
}

/// 180° fans (the CARMEN logs' scanners) 40° apart still share most of their view.
#[test]
fn two_fans_of_one_room_are_supported() {
    let a = scan_at(&room_a(), Pose2::new(-2.0, -0.5, 0.1), PI, 181);
    let b = scan_at(&room_a(), Pose2::new(-1.4, 0.2, 0.1 + 0.7), PI, 181);
    let s = support(&a, &b);
    assert!(s > 0.6, "support {s}");
}

/// Scans of two different rooms do not align with support.
#[test]
fn scans_of_different_rooms_are_not_supported() {
    let a = scan_at(&room_a(), Pose2::new(-1.0, 0.0, 0.0), 2.0 * PI, 360);
    let b = scan_at(&room_b(), Pose2::new(0.0, 0.0, 0.0), 2.0 * PI, 360);
    let s = support(&a, &b);
    assert!(s < 0.5, "support {s}");
}

/// Wrapped around a method, the check keeps the candidates of the queried room and drops the
/// other room's; scores are supports.
#[test]
fn the_check_keeps_only_the_same_room() {
    let mut check = GeometricCheck::new(
        PolarContext::new(PolarConfig::default()).unwrap(),
        GeometricCheckConfig {
            top_k: 4,
            min_support: 0.6,
            ..GeometricCheckConfig::default()
        },
    )
    .unwrap();
    let database = [
        scan_at(&room_a(), Pose2::new(-1.5, -0.8, 0.2), 2.0 * PI, 360),
        scan_at(&room_b(), Pose2::new(0.5, 0.0, 1.0), 2.0 * PI, 360),
        scan_at(&room_a(), Pose2::new(2.5, -1.0, -2.0), 2.0 * PI, 360),
        scan_at(&room_b(), Pose2::new(-1.0, 1.0, 0.0), 2.0 * PI, 360),
    ];
    for scan in &database {
        let d = check.describe(&Frame::Planar(scan)).unwrap();
        check.insert(d);
    }
    let query = scan_at(&room_a(), Pose2::new(0.0, -1.5, FRAC_PI_2), 2.0 * PI, 360);
    let d = check.describe(&Frame::Planar(&query)).unwrap();
    let found = check.query(&d, check.len());
    let frames: Vec<usize> = found.iter().map(|c| c.frame).collect();
    assert!(frames.iter().all(|&f| f == 0 || f == 2), "{found:?}");
    assert!(!frames.is_empty(), "{found:?}");
    assert!(found.iter().all(|c| (0.6..=1.0).contains(&c.score)));
    // Stored frame 0 against the database: itself is never proposed; frame 2 is.
    let stored = check.query_stored(0, check.len());
    assert!(stored.iter().all(|c| c.frame == 2), "{stored:?}");
}

/// A scan without returns, an image frame and bad settings give no candidates or clear
/// errors, never a panic.
#[test]
fn bad_input_is_refused_or_empty() {
    let mut check = checker();
    let empty = Scan2 {
        angle_min_rad: -FRAC_PI_2,
        angle_increment_rad: PI / 180.0,
        max_range_m: 20.0,
        ranges: vec![20.0; 181],
        intensities: None,
    };
    let room = scan_at(&room_a(), Pose2::identity(), PI, 181);
    for scan in [&room, &empty] {
        let d = check.describe(&Frame::Planar(scan)).unwrap();
        check.insert(d);
    }
    let d = check.describe(&Frame::Planar(&empty)).unwrap();
    assert!(check.query(&d, 2).is_empty());
    let image = image::GrayImage::new(8, 8);
    assert!(matches!(
        check.describe(&Frame::Image(&image)),
        Err(PlaceError::UnsupportedFrame { .. })
    ));
    for (config, name) in [
        (
            GeometricCheckConfig {
                top_k: 0,
                ..GeometricCheckConfig::default()
            },
            "top_k",
        ),
        (
            GeometricCheckConfig {
                support_m: f64::NAN,
                ..GeometricCheckConfig::default()
            },
            "support_m",
        ),
        (
            GeometricCheckConfig {
                min_support: 1.5,
                ..GeometricCheckConfig::default()
            },
            "min_support",
        ),
    ] {
        let e = config.validate().unwrap_err();
        assert!(e.to_string().contains(name), "{e}");
    }
}
