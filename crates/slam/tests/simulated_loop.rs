//! A simulated ring corridor driven twice with drifting odometry: loop closure pulls the
//! trajectory back to the truth, and every accepted loop closure agrees with the truth.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use raypath_geometry::{Pose2, Scan2};
use raypath_slam::benchmark::{
    LoopPairing, check_loops, loop_error, submap_disagreement, support_share,
};
use raypath_slam::{Slam, SlamConfig, SlamOutput};

type Segment = ([f64; 2], [f64; 2]);

/// A 24 m × 14 m block of corridors 2 m wide around a 20 m × 10 m inner block, with a few
/// doorway stubs so that the corridors are not perfectly self-similar.
fn walls() -> Vec<Segment> {
    let rect = |x0: f64, y0: f64, x1: f64, y1: f64| {
        vec![
            ([x0, y0], [x1, y0]),
            ([x1, y0], [x1, y1]),
            ([x1, y1], [x0, y1]),
            ([x0, y1], [x0, y0]),
        ]
    };
    let mut w = rect(-12.0, -7.0, 12.0, 7.0);
    w.extend(rect(-10.0, -5.0, 10.0, 5.0));
    for (x, y, dx, dy) in [
        (-6.0, 7.0, 0.0, -0.6),
        (3.0, 7.0, 0.0, -0.4),
        (12.0, 1.0, -0.5, 0.0),
        (5.0, -7.0, 0.0, 0.7),
        (-4.0, -7.0, 0.0, 0.3),
        (-12.0, -2.0, 0.6, 0.0),
    ] {
        w.push(([x, y], [x + dx, y + dy]));
    }
    w
}

fn scan_at(pose: Pose2, walls: &[Segment]) -> Scan2 {
    let n = 360;
    let inc = std::f64::consts::TAU / n as f64;
    let ranges = (0..n)
        .map(|k| {
            let a = pose.theta() + k as f64 * inc;
            let d = [a.cos(), a.sin()];
            walls
                .iter()
                .filter_map(|(p, q)| {
                    let e = [q[0] - p[0], q[1] - p[1]];
                    let den = d[0] * e[1] - d[1] * e[0];
                    let w = [p[0] - pose.x(), p[1] - pose.y()];
                    let t = (w[0] * e[1] - w[1] * e[0]) / den;
                    let s = (w[0] * d[1] - w[1] * d[0]) / den;
                    (den.abs() > 1e-12 && t > 0.0 && (0.0..=1.0).contains(&s)).then_some(t)
                })
                .fold(30.0, f64::min)
        })
        .collect();
    Scan2 {
        angle_min_rad: 0.0,
        angle_increment_rad: inc,
        max_range_m: 30.0,
        ranges,
        intensities: None,
    }
}

/// Poses along the corridors' centre line (a 22 m × 12 m rectangle), `laps` times, 0.1 m apart,
/// turning on the spot at the corners.
fn path(laps: usize) -> Vec<Pose2> {
    let corners: [[f64; 2]; 4] = [[-11.0, -6.0], [11.0, -6.0], [11.0, 6.0], [-11.0, 6.0]];
    let mut out = Vec::new();
    for _ in 0..laps {
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            let heading = (b[1] - a[1]).atan2(b[0] - a[0]);
            let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            let steps = (len / 0.1).round() as usize;
            for s in 0..steps {
                let t = s as f64 / steps as f64;
                out.push(Pose2::new(
                    a[0] + t * (b[0] - a[0]),
                    a[1] + t * (b[1] - a[1]),
                    heading,
                ));
            }
            for s in 1..=8 {
                out.push(Pose2::new(
                    b[0],
                    b[1],
                    heading + s as f64 * std::f64::consts::FRAC_PI_2 / 8.0,
                ));
            }
        }
    }
    out
}

/// Odometry with a heading bias of `bias` per radian turned and 1 % too long steps.
fn odometry(truth: &[Pose2], bias: f64) -> Vec<Pose2> {
    let mut odo = vec![truth[0]];
    for w in truth.windows(2) {
        let d = w[0].inverse() * w[1];
        let noisy = Pose2::new(1.01 * d.x(), 1.01 * d.y(), d.theta() * (1.0 + bias) + 0.002);
        let last = *odo.last().unwrap();
        odo.push(last * noisy);
    }
    odo
}

fn run(config: SlamConfig, truth: &[Pose2], odo: &[Pose2]) -> SlamOutput {
    let walls = walls();
    let mut slam = Slam::new(config).unwrap();
    for (k, (p, o)) in truth.iter().zip(odo).enumerate() {
        slam.process_scan(k as f64 * 0.05, &scan_at(*p, &walls), Some(*o))
            .unwrap();
    }
    slam.finish().unwrap()
}

/// Largest position error after expressing both trajectories relative to their first pose.
fn max_error(truth: &[Pose2], estimate: &[Pose2]) -> f64 {
    truth
        .iter()
        .zip(estimate)
        .map(|(t, e)| {
            let a = truth[0].inverse() * *t;
            let b = estimate[0].inverse() * *e;
            (a.translation() - b.translation()).norm()
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_simulated_loop_is_closed_and_no_wrong_loop_is_accepted() {
    let truth = path(2);
    let odo = odometry(&truth, 0.03);
    let full = run(SlamConfig::default(), &truth, &odo);
    let open = run(
        SlamConfig {
            loops: None,
            ..SlamConfig::default()
        },
        &truth,
        &odo,
    );
    let e_full = max_error(&truth, &full.world_from_sensor);
    let e_open = max_error(&truth, &open.world_from_sensor);
    let e_odo = max_error(&truth, &odo);
    assert!(!full.loop_closures.is_empty(), "no loop closure accepted");
    assert!(e_full < 0.25, "with loop closure: {e_full} m");
    assert!(e_full < e_open, "loops {e_full} m, no loops {e_open} m");
    assert!(e_open < e_odo, "front-end {e_open} m, odometry {e_odo} m");
    // Every accepted loop closure agrees with the truth (scan poses relative to the first).
    let world = |k: usize| truth[0].inverse() * truth[k];
    for c in &full.loop_closures {
        let (a, b) = (full.node_scan[c.anchor], full.node_scan[c.node]);
        let (t, r) = loop_error(Some(world(a)), Some(world(b)), c.submap_from_sensor).unwrap();
        assert!(t < 0.15 && r < 0.03, "loop {a} → {b}: {t} m, {r} rad");
    }
    check_against_references(&full, &truth);
}

/// `check_loops` with both pairings: no loop closure is wrong against the truth; against a
/// reference that turns the second lap by 5°, the loop closures into the first lap are; the
/// overlap pairing picks a node that shares at least as much with the loop's scan as the
/// nearest node does.
fn check_against_references(out: &SlamOutput, truth: &[Pose2]) {
    let walls = walls();
    let scans: Vec<Scan2> = truth.iter().map(|p| scan_at(*p, &walls)).collect();
    let scans: Vec<&Scan2> = scans.iter().collect();
    let exact: Vec<Option<Pose2>> = truth.iter().map(|p| Some(*p)).collect();
    let lap = truth.len() / 2;
    let turned: Vec<Option<Pose2>> = truth
        .iter()
        .enumerate()
        .map(|(k, p)| {
            Some(if k < lap {
                *p
            } else {
                Pose2::new(0.0, 0.0, 0.087) * *p
            })
        })
        .collect();
    let share = |c: &raypath_slam::benchmark::LoopCheck| {
        support_share(scans[c.near_scan], scans[c.scan], &c.reference()).unwrap_or(0.0)
    };
    let (_, _, nearest) = check_loops(out, &scans, &exact, 50, LoopPairing::Nearest);
    for pairing in [LoopPairing::Overlap, LoopPairing::Nearest] {
        let (checked, wrong, checks) = check_loops(out, &scans, &exact, 50, pairing);
        assert_eq!(checked, out.loop_closures.len(), "{pairing:?}");
        assert_eq!(wrong, 0, "{pairing:?}: {checks:?}");
        if pairing == LoopPairing::Overlap {
            for (o, n) in checks.iter().zip(&nearest) {
                assert!(share(o) >= share(n), "{o:?} against {n:?}");
            }
        }
        let (_, wrong, checks) = check_loops(out, &scans, &turned, 50, pairing);
        let across = checks
            .iter()
            .filter(|c| c.near_scan < lap && c.scan >= lap)
            .count();
        assert!(
            across > 0 && wrong >= across,
            "{pairing:?}: {wrong} of {across}"
        );
    }
}

#[test]
fn bad_scans_are_errors_not_panics() {
    let mut slam = Slam::new(SlamConfig::default()).unwrap();
    let mut scan = scan_at(Pose2::identity(), &walls());
    assert!(slam.process_scan(f64::NAN, &scan, None).is_err());
    scan.ranges.iter_mut().for_each(|r| *r = f64::NAN);
    slam.process_scan(0.0, &scan, None).unwrap();
    scan.ranges.clear();
    slam.process_scan(0.1, &scan, Some(Pose2::new(f64::NAN, 0.0, 0.0)))
        .unwrap();
    let out = slam.finish().unwrap();
    assert_eq!(out.scans.len(), 2);
    assert!(out.world_from_sensor.iter().all(|p| p.is_finite()));
    assert!(
        Slam::new(SlamConfig {
            optimize_every_nodes: 0,
            ..SlamConfig::default()
        })
        .is_err()
    );
    // The rotation-ambiguity test's parameters are checked, with the field named.
    for (ratio, angle) in [(Some(1.5), 0.05), (Some(0.0), 0.05), (Some(0.9), f64::NAN)] {
        let mut config = SlamConfig::default();
        let loops = config.loops.as_mut().unwrap();
        loops.ambiguity_ratio = ratio;
        loops.ambiguity_min_angle_rad = angle;
        let err = Slam::new(config).unwrap_err().to_string();
        assert!(err.contains("ambiguity"), "{err}");
    }
    for shift in [0.0, -0.3, f64::INFINITY] {
        let mut config = SlamConfig::default();
        config.loops.as_mut().unwrap().ambiguity_min_shift_m = Some(shift);
        let err = Slam::new(config).unwrap_err().to_string();
        assert!(err.contains("ambiguity_min_shift_m"), "{err}");
    }
}

/// Jumps in the odometry (as the raw MIT CSAIL log has: 0.5–0.9 m and 30–50° between two
/// scans 0.2 s apart) do not break the front-end: the pose of the last scan is tried as a
/// second guess, so the trajectory stays as good as without the jumps.
#[test]
fn odometry_jumps_do_not_break_the_front_end() {
    let truth = path(1);
    let clean = odometry(&truth, 0.03);
    let mut jumped = vec![clean[0]];
    for (k, w) in clean.windows(2).enumerate() {
        let mut d = w[0].inverse() * w[1];
        if [40, 150, 400].contains(&k) {
            d = d * Pose2::new(0.8, -0.3, 0.8);
        }
        let last = *jumped.last().unwrap();
        jumped.push(last * d);
    }
    let open = SlamConfig {
        loops: None,
        ..SlamConfig::default()
    };
    let e_clean = max_error(&truth, &run(open.clone(), &truth, &clean).world_from_sensor);
    let e_jumped = max_error(&truth, &run(open, &truth, &jumped).world_from_sensor);
    assert!(
        e_jumped < e_clean + 0.1,
        "with jumps {e_jumped} m, without {e_clean} m"
    );
}

/// The self-consistency measure of the large-loop logs: low for a closed loop, high once the
/// second lap is moved off the first by 0.4 m and 3°.
#[test]
fn submap_disagreement_sees_a_broken_loop() {
    let truth = path(2);
    let mut out = run(SlamConfig::default(), &truth, &odometry(&truth, 0.03));
    let (consistent, compared) = submap_disagreement(&out);
    assert!(compared > 1000, "{compared} cells compared");
    let half = out.nodes.len() / 2;
    for p in &mut out.nodes[half..] {
        *p = Pose2::new(0.4, 0.0, 0.05) * *p;
    }
    let (inconsistent, _) = submap_disagreement(&out);
    assert!(
        consistent < 0.05 && inconsistent > 4.0 * consistent.max(0.02),
        "closed loop {consistent}, broken {inconsistent}"
    );
}

/// The final polishing (ICP between neighbouring scans and revisits, one pose graph over all
/// scans) brings the relative poses of the scans closer to the simulator's truth than the
/// front-end and node graph leave them: consecutive relations and random pairs across the
/// loop both.
#[test]
fn polishing_lowers_the_relation_error_against_the_truth() {
    use raypath_slam::benchmark::{consecutive_relations, random_relations, relation_errors};
    let truth = path(2);
    let odo = odometry(&truth, 0.03);
    let unpolished = run(
        SlamConfig {
            polish: None,
            ..SlamConfig::default()
        },
        &truth,
        &odo,
    );
    let polished = run(
        SlamConfig {
            polish: Some(raypath_slam::PolishConfig::default()),
            ..SlamConfig::default()
        },
        &truth,
        &odo,
    );
    assert!(polished.stats.polish_edges > truth.len());
    let reference: Vec<Option<Pose2>> = truth.iter().copied().map(Some).collect();
    let all: Vec<usize> = (0..truth.len()).collect();
    for (name, relations) in [
        ("consecutive", consecutive_relations(&all)),
        ("random", random_relations(&all, 500, 3)),
    ] {
        let before = relation_errors(&reference, &unpolished.world_from_sensor, &relations);
        let after = relation_errors(&reference, &polished.world_from_sensor, &relations);
        assert!(
            // By more than a quarter (0.70× on the random pairs with the default loop σ).
            after.trans_error_m < 0.75 * before.trans_error_m
                && after.rot_error_deg <= before.rot_error_deg,
            "{name}: before {before:?}, after {after:?}"
        );
    }
}
