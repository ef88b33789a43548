//! Indoor worlds: the logs read like the real CARMEN logs, the robot's path is collision-free
//! and plausible, laser, intensity and odometry noise statistics, labels, determinism.

#![allow(clippy::unwrap_used, clippy::needless_range_loop)]

use std::path::Path;

use nalgebra::{Point2, Unit, Vector2};
use raypath_geometry::{Pose2, wrap_angle};
use raypath_io::carmen::{CarmenReader, LaserKind, Record};
use raypath_sim::indoor::odometry::{decompose, sample_step};
use raypath_sim::indoor::{
    self, Compression, FloorPlanConfig, IndoorConfig, Laser2Config, NoReturn, OdometryConfig,
    WorldConfig, WorldRun,
};
use raypath_sim::no_progress;
use raypath_sim::rng::stream;

fn small_plan() -> FloorPlanConfig {
    FloorPlanConfig {
        width_m: 16.0,
        height_m: 12.0,
        ..FloorPlanConfig::default()
    }
}

/// A small two-world set: a 181-beam FLASER world (compressed) and a 360° world with
/// intensities (ROBOTLASER1 raw log).
fn small_config() -> IndoorConfig {
    let mut office = WorldConfig::new("office", small_plan(), Laser2Config::sick_180(), 150);
    office.corrected_compression = Compression::Gzip;
    office.raw_compression = Compression::Bzip2;
    let lab = WorldConfig::new(
        "lab",
        FloorPlanConfig {
            width_m: 18.0,
            cross_corridor: true,
            glass_partition_probability: 0.5,
            ..small_plan()
        },
        Laser2Config::full_360().with_intensities(),
        120,
    );
    IndoorConfig {
        worlds: vec![office, lab],
    }
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

fn close_pose(a: &Pose2, b: &Pose2, tol: f64) -> bool {
    (a.translation() - b.translation()).norm() < tol
        && wrap_angle(a.theta() - b.theta()).abs() < tol
}

/// Reads a log; returns the laser messages, the number of ODOM lines and the inferred code.
fn read_log(path: &Path) -> (Vec<raypath_io::carmen::LaserMessage>, usize, Option<f64>) {
    let reader = CarmenReader::open(path).unwrap();
    let code = [LaserKind::Front, LaserKind::RobotLaser1]
        .iter()
        .find_map(|&k| reader.no_return(k))
        .map(|e| e.code_m);
    let (mut lasers, mut odom) = (Vec::new(), 0);
    for r in reader {
        match r.unwrap() {
            Record::Laser(l) => lasers.push(l),
            Record::Odometry(_) => odom += 1,
            _ => {}
        }
    }
    (lasers, odom, code)
}

#[test]
fn logs_read_like_the_real_ones() {
    let config = small_config();
    let dir = tempfile::tempdir().unwrap();
    let set = indoor::generate(&config, 21, dir.path(), no_progress()).unwrap();
    assert_eq!(set.files.len(), 8);
    for (i, world) in config.worlds.iter().enumerate() {
        let run = indoor::simulate_world(world, indoor::world_seed(21, i), no_progress()).unwrap();
        let name = &world.name;
        let corrected = dir.path().join(format!(
            "{name}-corrected.log{}",
            world.corrected_compression.suffix()
        ));
        let raw = dir
            .path()
            .join(format!("{name}.clf{}", world.raw_compression.suffix()));
        let l = &world.laser;

        let (lasers, odom, code) = read_log(&corrected);
        assert_eq!(lasers.len(), world.scans);
        assert_eq!(odom, run.odometry_times.len());
        assert_eq!(
            code,
            Some(l.no_return_code_m),
            "{name}: inferred no-return code"
        );
        for (k, m) in lasers.iter().enumerate() {
            assert_eq!(m.kind, LaserKind::Front);
            assert_eq!(m.scan.len(), l.beams);
            assert!((m.scan.angle_min_rad - l.angle_min_rad).abs() < 1e-9);
            assert!((m.scan.angle_increment_rad - l.angle_increment_rad).abs() < 1e-12);
            // Ground truth to the written precision (6 decimals).
            assert!(close_pose(&m.world_from_laser, &run.laser_poses[k], 1e-6));
            assert!((m.logger_timestamp_secs - run.scan_times[k]).abs() < 1e-6);
            for (b, (&got, &want)) in m.scan.ranges.iter().zip(&run.scans[k].ranges).enumerate() {
                assert!(
                    (got - want).abs() <= 5e-4 + 1e-12,
                    "{name} scan {k} beam {b}"
                );
                let no_return = run.scans[k].no_returns[b].is_some();
                assert_eq!(got >= m.scan.max_range_m, no_return);
            }
        }

        let (lasers, odom, code) = read_log(&raw);
        assert_eq!(lasers.len(), world.scans);
        assert_eq!(odom, run.odometry_times.len());
        assert_eq!(code, Some(l.no_return_code_m));
        let robot_laser = world.raw_uses_robot_laser();
        for (k, m) in lasers.iter().enumerate() {
            assert_eq!(m.kind == LaserKind::RobotLaser1, robot_laser);
            assert!(close_pose(&m.world_from_robot, &run.scan_odometry[k], 1e-6));
            assert!((m.scan.angle_min_rad - l.angle_min_rad).abs() < 1e-6);
            if robot_laser {
                let want = run.scans[k].intensities.as_ref().unwrap();
                let got = m.scan.intensities.as_ref().unwrap();
                assert!(
                    got.iter()
                        .zip(want)
                        .all(|(a, b)| (a - b).abs() <= 5e-4 + 1e-9)
                );
                // The stated maximum range is the threshold.
                assert_eq!(m.scan.max_range_m, l.max_range_m);
            }
        }

        // `raypath info` reads everything but the JSON.
        let s = raypath_io::summarize(&corrected).unwrap();
        assert_eq!(
            (s.scans, s.beams),
            (Some(world.scans as u64), Some(l.beams as u64))
        );
        assert_eq!(s.odometry, Some(run.odometry_times.len() as u64));
        let s = raypath_io::summarize(&raw).unwrap();
        assert_eq!(s.scans, Some(world.scans as u64));
        let poses = dir.path().join(format!("{name}-poses.csv"));
        let s = raypath_io::summarize(&poses).unwrap();
        assert_eq!(s.points, Some(world.scans as u64));
        let csv = raypath_io::point_csv::PointCsv::read(&poses).unwrap();
        for (k, row) in csv.rows().enumerate() {
            assert!(close_pose(
                &Pose2::new(row[0], row[1], row[2]),
                &run.laser_poses[k],
                1e-12
            ));
        }
        let json: serde_json::Value = serde_json::from_slice(
            &std::fs::read(dir.path().join(format!("{name}-world.json"))).unwrap(),
        )
        .unwrap();
        assert_eq!(
            json["segments"].as_array().unwrap().len(),
            run.world.segments.len()
        );
        assert_eq!(set.stats[name.as_str()]["scans"], world.scans);
    }
}

#[test]
fn same_seed_same_bytes_whatever_the_threads() {
    let mut config = small_config();
    for w in &mut config.worlds {
        w.scans = 40;
    }
    let (a, b, c) = (
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
    );
    indoor::generate(&config, 3, a.path(), no_progress()).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| indoor::generate(&config, 3, b.path(), no_progress()).unwrap());
    assert_eq!(files(a.path()), files(b.path()));
    indoor::generate(&config, 4, c.path(), no_progress()).unwrap();
    assert_ne!(files(a.path()), files(c.path()));
}

fn check_motion(world: &WorldConfig, run: &WorldRun) {
    let robot = &world.robot;
    let states = &run.trajectory.states;
    let end = *run.scan_times.last().unwrap();
    for w in states.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        assert!(b.t >= a.t);
        assert!(b.v <= robot.max_speed_mps + 1e-9 && b.v >= 0.0);
        assert!(
            b.omega.abs() <= robot.max_turn_rate_radps + 1e-9,
            "{}",
            b.omega
        );
        let ds = (b.position() - a.position()).norm();
        let dt = b.t - a.t;
        if dt > 0.0 {
            // Speeds, accelerations and turn rates between keyframes.
            assert!(ds / dt <= robot.max_speed_mps + 1e-6);
            assert!((b.v - a.v).abs() / dt <= robot.max_accel_mps2 * 1.001 + 1e-9);
            assert!((b.theta - a.theta).abs() / dt <= robot.max_turn_rate_radps * 1.001 + 1e-9);
        }
        // Continuous motion: keyframes are close (1 cm of arc turns by at most 0.1 rad on the
        // smallest, 10 cm fillet).
        assert!(
            ds < 0.011 && (b.theta - a.theta).abs() < 0.101,
            "{a:?} {b:?}"
        );
    }
    // Collision-free with a margin: the robot's disc never touches anything (tables included).
    let clearance = states
        .iter()
        .filter(|s| s.t <= end)
        .map(|s| run.world.planning_scene.distance(&s.position()))
        .fold(f64::INFINITY, f64::min);
    assert!(clearance >= robot.radius_m + 0.04, "clearance {clearance}");
    // It gets somewhere: several goals, most of the log spent moving.
    assert!(run.goals.len() >= 2, "{} goals", run.goals.len());
    assert!(run.trajectory.length_m() > 0.1 * robot.max_speed_mps * end);
}

#[test]
fn robot_paths_are_collision_free_and_plausible() {
    for seed in 0..4 {
        let mut world = WorldConfig::new(
            "w",
            FloorPlanConfig {
                cross_corridor: seed % 2 == 1,
                width_m: 18.0,
                ..small_plan()
            },
            Laser2Config::sick_180(),
            300,
        );
        world.odometry = OdometryConfig::noiseless();
        let run = indoor::simulate_world(&world, seed, no_progress()).unwrap();
        check_motion(&world, &run);
        // Noiseless odometry is the true motion in the odometry frame.
        let world_from_odom = run.scan_states[0].pose() * run.scan_odometry[0].inverse();
        for (s, o) in run.scan_states.iter().zip(&run.scan_odometry) {
            assert!(close_pose(&(world_from_odom * *o), &s.pose(), 1e-6));
        }
    }
    // The default worlds too (one seed).
    for world in &IndoorConfig::default().worlds {
        let mut w = world.clone();
        w.scans = 400;
        let run = indoor::simulate_world(&w, 7, no_progress()).unwrap();
        check_motion(&w, &run);
    }
}

#[test]
fn every_room_has_a_door_to_a_corridor() {
    for seed in 0..6 {
        for cross in [false, true] {
            let plan = FloorPlanConfig {
                cross_corridor: cross,
                ..FloorPlanConfig::default()
            };
            let world = indoor::generate_world(&plan, &mut stream(seed, 1, 0)).unwrap();
            for (i, s) in world.spaces.iter().enumerate() {
                if s.kind != indoor::floorplan::SpaceKind::Room {
                    continue;
                }
                let to_corridor = world.doors.iter().any(|d| {
                    d.spaces.contains(&i)
                        && d.spaces.iter().any(|&j| {
                            world.spaces[j].kind == indoor::floorplan::SpaceKind::Corridor
                        })
                });
                assert!(to_corridor, "seed {seed}: room {i} has no door");
            }
            assert!(world.windows > 0);
        }
    }
}

#[test]
fn laser_noise_labels_and_no_returns() {
    let mut world = WorldConfig::new(
        "w",
        FloorPlanConfig {
            glass_partition_probability: 0.5,
            ..small_plan()
        },
        Laser2Config {
            max_range_m: 8.0,
            range_sigma_m: 0.02,
            ..Laser2Config::full_360()
        },
        120,
    );
    world.laser.intensity = None;
    let run = indoor::simulate_world(&world, 11, no_progress()).unwrap();
    let (mut errors, mut beyond, mut glass) = (Vec::new(), 0, 0);
    for (k, scan) in run.scans.iter().enumerate() {
        let pose = run.laser_poses[k];
        let origin = Point2::new(pose.x(), pose.y());
        for b in 0..scan.ranges.len() {
            let angle = pose.theta()
                + world.laser.angle_min_rad
                + b as f64 * world.laser.angle_increment_rad;
            let dir = Vector2::new(angle.cos(), angle.sin());
            match scan.no_returns[b] {
                None => {
                    errors.push(scan.ranges[b] - scan.true_ranges[b]);
                    // The label is that of a segment through the true end point.
                    let end = origin + dir * scan.true_ranges[b];
                    let label = run
                        .world
                        .segments
                        .iter()
                        .filter(|s| {
                            let (a, c) = (Point2::new(s.a[0], s.a[1]), Point2::new(s.b[0], s.b[1]));
                            let e = c - a;
                            let t = ((end - a).dot(&e) / e.norm_squared()).clamp(0.0, 1.0);
                            (a + e * t - end).norm() < 1e-7
                        })
                        .map(|s| run.world.materials[s.surface as usize].label)
                        .collect::<Vec<_>>();
                    assert!(
                        label.contains(&scan.labels[b]),
                        "{label:?} vs {}",
                        scan.labels[b]
                    );
                    assert!(scan.ranges[b] < world.laser.max_range_m);
                }
                Some(NoReturn::BeyondRange) => {
                    beyond += 1;
                    assert_eq!(scan.ranges[b], world.laser.no_return_code_m);
                    // Nothing opaque closer than the maximum range (minus the noise).
                    let hit = run
                        .world
                        .scene
                        .cast(&origin, &Unit::new_normalize(dir), 100.0);
                    if let Some(h) = hit {
                        let m = run.world.materials[h.surface as usize];
                        assert!(
                            m.transmission > 0.0 || h.range_m > world.laser.max_range_m - 0.1,
                            "{} m",
                            h.range_m
                        );
                    }
                }
                Some(NoReturn::ThroughGlass) => {
                    glass += 1;
                    let hit = run
                        .world
                        .scene
                        .cast(&origin, &Unit::new_normalize(dir), 100.0)
                        .unwrap();
                    assert!(run.world.materials[hit.surface as usize].transmission > 0.0);
                }
            }
        }
    }
    assert!(beyond > 100 && glass > 100, "{beyond} {glass}");
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / n;
    let std = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(n > 20_000.0);
    assert!(mean.abs() < 0.001, "{mean}");
    assert!((std / 0.02 - 1.0).abs() < 0.03, "{std}");
}

#[test]
fn intensities_follow_the_model() {
    let world = WorldConfig::new(
        "w",
        small_plan(),
        Laser2Config::sick_180().with_intensities(),
        150,
    );
    let model = world.laser.intensity.unwrap();
    let run = indoor::simulate_world(&world, 5, no_progress()).unwrap();
    let mut z = Vec::new();
    for (k, scan) in run.scans.iter().enumerate() {
        let pose = run.laser_poses[k];
        let origin = Point2::new(pose.x(), pose.y());
        let intensities = scan.intensities.as_ref().unwrap();
        for b in 0..scan.ranges.len() {
            if scan.no_returns[b].is_some() {
                assert_eq!(intensities[b], 0.0);
                continue;
            }
            let angle = pose.theta()
                + world.laser.angle_min_rad
                + b as f64 * world.laser.angle_increment_rad;
            let dir = Unit::new_normalize(Vector2::new(angle.cos(), angle.sin()));
            // Recover reflectivity and incidence from the scene (glass may let the beam on:
            // skip beams whose first hit is not the reflecting surface).
            let hit = run.world.scene.cast(&origin, &dir, 100.0).unwrap();
            if (hit.range_m - scan.true_ranges[b]).abs() > 1e-9 {
                continue;
            }
            let rho = run.world.materials[hit.surface as usize].reflectivity;
            let incidence = (-hit.normal.dot(&dir)).clamp(-1.0, 1.0).acos();
            let expected = model.expected(rho, scan.true_ranges[b], incidence);
            let i = intensities[b];
            if i <= 0.0 || i >= model.saturation || expected < 20.0 {
                continue; // clipped
            }
            let sd =
                ((model.sigma_relative * expected).powi(2) + model.sigma_absolute.powi(2)).sqrt();
            z.push((i - expected) / sd);
        }
    }
    let n = z.len() as f64;
    assert!(n > 5000.0, "{n}");
    let mean = z.iter().sum::<f64>() / n;
    let std = (z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(
        mean.abs() < 0.05 && (std - 1.0).abs() < 0.05,
        "{mean} {std}"
    );
}

#[test]
fn odometry_noise_has_the_model_variances() {
    let alphas = [0.05, 0.02, 0.03, 0.01];
    let from = Pose2::new(1.0, 2.0, 0.3);
    let to = from * Pose2::new(0.0, 0.0, 0.2) * Pose2::new(0.5, 0.0, -0.1);
    let (rot1, trans, rot2) = decompose(&from, &to);
    assert!(
        (rot1 - 0.2).abs() < 1e-12 && (trans - 0.5).abs() < 1e-12 && (rot2 + 0.1).abs() < 1e-12
    );
    let mut rng = stream(1, 2, 3);
    let n = 40_000;
    let samples: Vec<(f64, f64, f64)> = (0..n)
        .map(|_| decompose(&from, &sample_step(&alphas, &from, &to, &from, &mut rng)))
        .collect();
    let var = |f: &dyn Fn(&(f64, f64, f64)) -> f64, truth: f64| {
        samples.iter().map(|s| (f(s) - truth).powi(2)).sum::<f64>() / n as f64
    };
    let [a1, a2, a3, a4] = alphas;
    let want = [
        a1 * rot1 * rot1 + a2 * trans * trans,
        a3 * trans * trans + a4 * (rot1 * rot1 + rot2 * rot2),
        a1 * rot2 * rot2 + a2 * trans * trans,
    ];
    let got = [
        var(&|s| s.0, rot1),
        var(&|s| s.1, trans),
        var(&|s| s.2, rot2),
    ];
    for (g, w) in got.iter().zip(want) {
        assert!((g / w - 1.0).abs() < 0.04, "{got:?} vs {want:?}");
    }
    // Turning in place: no translation noise from the (zero) translation.
    let turned = Pose2::new(1.0, 2.0, 1.0);
    let p = sample_step(&[0.0, 0.0, 0.0, 0.0], &from, &turned, &from, &mut rng);
    assert!(close_pose(&p, &turned, 1e-12));
}

#[test]
fn bad_configurations_are_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let base = || WorldConfig::new("w", small_plan(), Laser2Config::sick_180(), 10);
    let mut bad = vec![base(), base(), base(), base(), base(), base()];
    bad[0].scans = 0;
    bad[1].laser.no_return_code_m = 30.0;
    bad[2].plan.height_m = 5.0;
    bad[3].plan.door_width_m = [0.5, 0.6];
    bad[4].odometry.alphas[2] = -1.0;
    bad[5].name = "a/b".into();
    for w in bad {
        let config = IndoorConfig { worlds: vec![w] };
        assert!(indoor::generate(&config, 1, tmp.path(), no_progress()).is_err());
    }
    assert!(
        indoor::generate(
            &IndoorConfig { worlds: vec![] },
            1,
            tmp.path(),
            no_progress()
        )
        .is_err()
    );
}
