//! Faults a held-out log may bring, injected into a simulated two-lap drive around a ring of
//! corridors (scans cast by raypath-sim): a 1 m / 20° jump in the odometry, a burst of scans
//! the matcher cannot place, and a planted wrong loop closure. The map must come out unbroken:
//! relative motions and the aligned trajectory stay close to the simulator's truth.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::f64::consts::{FRAC_PI_2, TAU};

use nalgebra::Point2;
use raypath_geometry::{Pose2, Scan2};
use raypath_sim::scene2::{Scene2, SceneBuilder2, Surface};
use raypath_slam::{LoopSource, Slam, SlamConfig, SlamOutput};

/// The ring of corridors of `simulated_loop.rs`: 2 m wide around a 20 m × 10 m block, with a
/// few doorway stubs so that the corridors are not perfectly self-similar.
fn scene() -> Scene2 {
    let mut b = SceneBuilder2::new();
    let wall = b.add_surface(Surface {
        label: 1,
        reflectivity: 0.5,
    });
    let rect = |b: &mut SceneBuilder2, x0: f64, y0: f64, x1: f64, y1: f64| {
        let c = [
            Point2::new(x0, y0),
            Point2::new(x1, y0),
            Point2::new(x1, y1),
            Point2::new(x0, y1),
        ];
        b.add_polygon(&c, wall);
    };
    rect(&mut b, -12.0, -7.0, 12.0, 7.0);
    rect(&mut b, -10.0, -5.0, 10.0, 5.0);
    for (x, y, dx, dy) in [
        (-6.0, 7.0, 0.0, -0.6),
        (3.0, 7.0, 0.0, -0.4),
        (12.0, 1.0, -0.5, 0.0),
        (5.0, -7.0, 0.0, 0.7),
        (-4.0, -7.0, 0.0, 0.3),
        (-12.0, -2.0, 0.6, 0.0),
    ] {
        b.add_segment(Point2::new(x, y), Point2::new(x + dx, y + dy), wall);
    }
    b.build().unwrap()
}

fn scan_at(scene: &Scene2, pose: Pose2) -> Scan2 {
    let n = 360;
    let origin = Point2::new(pose.x(), pose.y());
    let ranges = (0..n)
        .map(|k| {
            let a = pose.theta() + k as f64 * TAU / n as f64;
            scene
                .cast_angle(&origin, a, 30.0)
                .map_or(30.0, |h| h.range_m)
        })
        .collect();
    Scan2 {
        angle_min_rad: 0.0,
        angle_increment_rad: TAU / n as f64,
        max_range_m: 30.0,
        ranges,
        intensities: None,
    }
}

/// Poses along the corridors' centre line, `laps` times, 0.1 m apart, turning on the spot at
/// the corners.
fn path(laps: usize) -> Vec<Pose2> {
    let corners: [[f64; 2]; 4] = [[-11.0, -6.0], [11.0, -6.0], [11.0, 6.0], [-11.0, 6.0]];
    let mut out = Vec::new();
    for _ in 0..laps {
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            let heading = (b[1] - a[1]).atan2(b[0] - a[0]);
            let steps = ((b[0] - a[0]).hypot(b[1] - a[1]) / 0.1).round() as usize;
            for s in 0..steps {
                let t = s as f64 / steps as f64;
                let (x, y) = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
                out.push(Pose2::new(x, y, heading));
            }
            for s in 1..=8 {
                out.push(Pose2::new(b[0], b[1], heading + s as f64 * FRAC_PI_2 / 8.0));
            }
        }
    }
    out
}

/// Odometry 1 % too long, turning 3 % too much, with `jumps` `(step, extra motion)` added.
fn odometry(truth: &[Pose2], jumps: &[(usize, Pose2)]) -> Vec<Pose2> {
    let mut odo = vec![truth[0]];
    for (k, w) in truth.windows(2).enumerate() {
        let d = w[0].inverse() * w[1];
        let mut step = Pose2::new(1.01 * d.x(), 1.01 * d.y(), d.theta() * 1.03 + 0.002);
        for (at, extra) in jumps {
            if *at == k {
                step = step * *extra;
            }
        }
        odo.push(*odo.last().unwrap() * step);
    }
    odo
}

const DT: f64 = 0.05;

/// Errors of the estimate against the truth: (largest error of the motion over 20 scans,
/// metres; RMS position error after the best rigid alignment, metres).
fn errors(truth: &[Pose2], estimate: &[Pose2]) -> (f64, f64) {
    errors_without(truth, estimate, 0..0)
}

/// [`errors`], the relations leaving out the scans `skip` (the motion over 20 scans that
/// start or end there).
fn errors_without(truth: &[Pose2], estimate: &[Pose2], skip: std::ops::Range<usize>) -> (f64, f64) {
    let relation = (0..truth.len() - 20)
        .filter(|k| !skip.contains(k) && !skip.contains(&(k + 20)))
        .map(|k| {
            let t = truth[k].inverse() * truth[k + 20];
            let e = estimate[k].inverse() * estimate[k + 20];
            (t.inverse() * e).translation().norm()
        })
        .fold(0.0, f64::max);
    // Best rotation and translation taking the estimate onto the truth (2-D Umeyama).
    let n = truth.len() as f64;
    let mean = |p: &[Pose2]| {
        p.iter()
            .map(|q| q.translation())
            .sum::<nalgebra::Vector2<f64>>()
            / n
    };
    let (mt, me) = (mean(truth), mean(estimate));
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (t, e) in truth.iter().zip(estimate) {
        let (a, b) = (e.translation() - me, t.translation() - mt);
        sxx += a.dot(&b);
        sxy += a.x * b.y - a.y * b.x;
    }
    let r = nalgebra::Rotation2::new(sxy.atan2(sxx));
    let rms = (truth
        .iter()
        .zip(estimate)
        .map(|(t, e)| (r * (e.translation() - me) - (t.translation() - mt)).norm_squared())
        .sum::<f64>()
        / n)
        .sqrt();
    (relation, rms)
}

/// Runs SLAM over `truth` with odometry `odo`; `scan` may replace a scan, `each_node` is
/// called after every scan that became a node (with the scan index).
fn run(
    config: SlamConfig,
    truth: &[Pose2],
    odo: &[Pose2],
    scan: impl Fn(usize, Scan2) -> Scan2,
    mut each_node: impl FnMut(&mut Slam, usize, &[usize]),
) -> SlamOutput {
    let scene = scene();
    let mut slam = Slam::new(config).unwrap();
    let mut node_scans = Vec::new();
    for (k, (p, o)) in truth.iter().zip(odo).enumerate() {
        let nodes = slam.nodes();
        slam.process_scan(k as f64 * DT, &scan(k, scan_at(&scene, *p)), Some(*o))
            .unwrap();
        if slam.nodes() > nodes {
            node_scans.push(k);
            each_node(&mut slam, k, &node_scans);
        }
    }
    slam.finish().unwrap()
}

/// A jump of 1 m and 20° in the odometry between two scans 0.05 s apart (a glitch the robot
/// cannot have driven) is not trusted: the map stays as good as without it.
#[test]
fn an_odometry_jump_leaves_the_map_unbroken() {
    let truth = path(2);
    let jump = Pose2::new(1.0, 0.0, 20f64.to_radians());
    for at in [120, 700] {
        let odo = odometry(&truth, &[(at, jump)]);
        let out = run(SlamConfig::default(), &truth, &odo, |_, s| s, |_, _, _| {});
        let (relation, rms) = errors(&truth, &out.world_from_sensor);
        assert!(out.stats.tracking.odometry_outliers >= 1, "{:?}", out.stats);
        assert!(
            relation < 0.1 && rms < 0.15,
            "jump at {at}: relation {relation} m, aligned RMS {rms} m"
        );
        assert!(!out.loop_closures.is_empty());
    }
}

/// Ten scans in a row that show nothing of the walls (a person in front of the sensor,
/// random ranges below 1 m) cannot be matched: the front-end keeps the odometry there, inserts
/// none of them into a submap, and matches the scans after them against the same submap.
#[test]
fn scans_the_matcher_cannot_place_break_a_submap_not_the_map() {
    use rand::{Rng, SeedableRng};
    let truth = path(2);
    let odo = odometry(&truth, &[]);
    let garbage = |k: usize, mut s: Scan2| {
        if (300..310).contains(&k) {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(k as u64);
            s.ranges
                .iter_mut()
                .for_each(|r| *r = rng.random_range(0.3..1.0));
        }
        s
    };
    let out = run(SlamConfig::default(), &truth, &odo, garbage, |_, _, _| {});
    let t = out.stats.tracking;
    assert!(t.failed >= 5, "{t:?}");
    // The poses of the scans that show nothing are meaningless; the motion across them is
    // kept to centimetres, and the map stays whole: the aligned error is as without the burst
    // (0.017 m in our run). Elsewhere in the second lap one stretch of 2 m moves by 0.23 m
    // against 0.03 m without the burst (not understood yet), far from a broken map.
    let (across, _) = errors_without(&truth[280..340], &out.world_from_sensor[280..340], 20..30);
    let (relation, rms) = errors_without(&truth, &out.world_from_sensor, 300..310);
    assert!(across < 0.1, "across the burst: {across} m");
    assert!(
        relation < 0.3 && rms < 0.05,
        "relation {relation} m, aligned RMS {rms} m"
    );
}

/// After every node of the second lap's stretch `lap + 200 .. lap + 260` (scans), proposes a
/// wrong loop closure: the first lap's submap whose anchor is nearest the node, seen 3 m and
/// 25° off (the same offset for all, so the wrong loops agree with each other, as a repeated
/// room would give). Records the proposed poses in `planted`.
fn planter<'a>(
    planted: &'a mut Vec<Pose2>,
    truth: &'a [Pose2],
) -> impl FnMut(&mut Slam, usize, &[usize]) + 'a {
    let lap = truth.len() / 2;
    let offset = Pose2::new(3.0, 0.0, 25f64.to_radians());
    let world = move |k: usize| truth[0].inverse() * truth[k];
    move |slam: &mut Slam, k: usize, node_scans: &[usize]| {
        if !(lap + 200..lap + 260).contains(&k) || slam.submaps().len() < 3 {
            return;
        }
        let near = |s: usize| (world(s).translation() - world(k).translation()).norm();
        let (submap, anchor_scan) = slam
            .submaps()
            .iter()
            .enumerate()
            .map(|(i, s)| (i, node_scans[s.anchor()]))
            .filter(|(_, a)| *a < lap)
            .min_by(|a, b| near(a.1).total_cmp(&near(b.1)))
            .unwrap();
        let wrong = world(anchor_scan).inverse() * offset * world(k);
        slam.propose_loop_closure(submap, wrong, 0.9, LoopSource::Nearby);
        planted.push(wrong);
    }
}

/// Wrong loop closures planted in the second lap (see [`planter`]) are rejected by the
/// consistency test before they enter the pose graph, and the map stays unbroken; without the
/// test, every one of them enters the graph (only the robust back-end then stands between them
/// and the map).
#[test]
fn a_planted_wrong_loop_is_rejected_and_the_map_stays_unbroken() {
    let truth = path(2);
    let odo = odometry(&truth, &[]);
    let mut planted = Vec::new();
    let out = run(
        SlamConfig::default(),
        &truth,
        &odo,
        |_, s| s,
        planter(&mut planted, &truth),
    );
    assert!(planted.len() >= 5, "{} planted", planted.len());
    let entered = out
        .loop_closures
        .iter()
        .chain(&out.rejected_loop_closures)
        .filter(|c| planted.contains(&c.submap_from_sensor))
        .count();
    assert_eq!(entered, 0, "{:?}", out.stats.consistency);
    let (relation, rms) = errors(&truth, &out.world_from_sensor);
    assert!(
        relation < 0.1 && rms < 0.15,
        "relation {relation} m, aligned RMS {rms} m"
    );

    let mut planted = Vec::new();
    let open = SlamConfig {
        consistency: None,
        ..SlamConfig::default()
    };
    let out = run(open, &truth, &odo, |_, s| s, planter(&mut planted, &truth));
    let entered = out
        .loop_closures
        .iter()
        .chain(&out.rejected_loop_closures)
        .filter(|c| planted.contains(&c.submap_from_sensor))
        .count();
    let (_, rms_open) = errors(&truth, &out.world_from_sensor);
    eprintln!("without the test: {entered} planted loops entered, aligned RMS {rms_open} m");
    assert!(entered == planted.len(), "{entered} of {}", planted.len());
}

/// Bad settings are errors that name the field.
#[test]
fn new_settings_are_validated() {
    let check = |config: SlamConfig, field: &str| {
        let err = Slam::new(config).unwrap_err().to_string();
        assert!(err.contains(field), "{err}");
    };
    let mut c = SlamConfig::default();
    c.tracking.min_score = Some(1.5);
    check(c, "tracking.min_score");
    let mut c = SlamConfig::default();
    c.tracking.max_correction_m = -1.0;
    check(c, "tracking.max_correction_m");
    let mut c = SlamConfig::default();
    c.tracking.degenerate_ratio = Some(0.0);
    check(c, "tracking.degenerate_ratio");
    let mut c = SlamConfig::default();
    c.tracking.fallback_sigma[2] = f64::NAN;
    check(c, "tracking.fallback_sigma");
    let mut c = SlamConfig::default();
    c.consistency.as_mut().unwrap().chi2_gate = 0.0;
    check(c, "consistency.chi2_gate");
    let mut c = SlamConfig::default();
    c.consistency.as_mut().unwrap().drift[0] = -0.1;
    check(c, "consistency.drift");
}
