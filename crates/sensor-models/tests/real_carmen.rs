//! Real data: a 2-D map of the Intel Research Lab from the corrected CARMEN log at 0.1 m.
//!
//! Skips (with a message) when `$RAYPATH_DATA/carmen/corrected/intel-corrected.log.gz` is
//! absent.
#![allow(clippy::unwrap_used)] // test code: a panic is the failure report

use nalgebra::Point2;
use raypath_geometry::{Aabb2, Grid2, Pose2, Scan2};
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use raypath_sensor_models::{
    BetaPosteriorConfig, DecayRateConfig, DecayRateModel2, DecayRatePosteriorModel2, DenseStats2,
    GammaPosteriorConfig, LikelihoodFieldConfig, LikelihoodFieldModel2, LogOddsConfig,
    LogOddsModel2, MappingConfig, OpticalDepthConfig, Planar, ReflectionConfig, ReflectionModel2,
    ScanLikelihood, SensorModel, SensorRange, Tabulated,
};

const LOG: &str = "carmen/corrected/intel-corrected.log.gz";

fn load() -> Option<Vec<(Pose2, Scan2)>> {
    let path = raypath_io::data::require(LOG)?;
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    let scans: Vec<(Pose2, Scan2)> = read_planar(&path, &options)
        .expect("read intel log")
        .into_iter()
        .map(|f| (f.world_from_laser, f.scan))
        .collect();
    assert_eq!(scans.len(), 910);
    Some(scans)
}

fn grid_for(scans: &[(Pose2, Scan2)]) -> Grid2 {
    let mut bounds = Aabb2::empty();
    for (pose, scan) in scans {
        for point in scan.points(*pose) {
            bounds.extend(&point);
        }
        bounds.extend(&Point2::new(pose.x(), pose.y()));
    }
    let margin = nalgebra::Vector2::new(1.0, 1.0);
    let bounds = Aabb2::new(bounds.min - margin, bounds.max + margin);
    Grid2::covering(&bounds, 0.1).expect("grid")
}

/// Sum of scan log-likelihoods over test scans at the true pose and at shifted poses.
fn true_pose_wins(name: &str, model: &impl SensorModel<Planar>, test: &[(Pose2, Scan2)]) {
    let adapter = ScanLikelihood::new(model).with_beam_step(2);
    let mut wins = 0;
    let mut total = 0;
    let mut true_sum = 0.0;
    for (pose, scan) in test {
        let at_truth = adapter.log_likelihood(pose, scan);
        assert!(!at_truth.is_nan(), "{name}: NaN at the true pose");
        true_sum += at_truth;
        for (dx, dy, dtheta) in [
            (0.3, 0.0, 0.0),
            (0.0, -0.3, 0.0),
            (-0.2, 0.2, 0.0),
            (0.0, 0.0, 0.08),
            (0.0, 0.0, -0.08),
        ] {
            let shifted = Pose2::new(pose.x() + dx, pose.y() + dy, pose.theta() + dtheta);
            total += 1;
            if at_truth > adapter.log_likelihood(&shifted, scan) {
                wins += 1;
            }
        }
    }
    let rate = f64::from(wins) / f64::from(total);
    eprintln!("{name}: true pose wins {wins}/{total} ({rate:.3}); sum at truth {true_sum:.1}");
    assert!(
        rate > 0.9,
        "{name}: true pose beats shifted poses in only {rate:.3}"
    );
}

#[test]
fn intel_map_is_sane_and_true_poses_score_best() {
    let Some(scans) = load() else {
        return;
    };
    let grid = grid_for(&scans);
    // Map from 9 of every 10 scans, test on the rest.
    let (map_scans, test_scans): (Vec<_>, Vec<_>) =
        scans.iter().enumerate().partition(|(i, _)| i % 10 != 5);
    let map_refs: Vec<(Pose2, &Scan2)> = map_scans.iter().map(|(_, (p, s))| (*p, s)).collect();
    let test: Vec<(Pose2, Scan2)> = test_scans.into_iter().map(|(_, s)| s.clone()).collect();
    let config = MappingConfig::default();
    let mut stats = DenseStats2::new(grid);
    stats.insert_scans_par(&map_refs, &config);
    let summary = *stats.summary();
    eprintln!("grid {:?}, summary {summary:?}", grid.dims());
    assert_eq!(
        summary.rays,
        map_refs.iter().map(|(_, s)| s.len() as u64).sum::<u64>()
    );
    assert!(summary.hits > summary.rays / 2);

    // Sanity: cells with many hits (walls) have high μ and λ; cells crossed often without
    // hits (free space) have low ones.
    let range = SensorRange::default();
    let decay = DecayRateModel2::new(
        &stats,
        DecayRateConfig {
            range,
            ..Default::default()
        },
    )
    .expect("decay");
    let reflection =
        ReflectionModel2::maximum_likelihood(&stats, ReflectionConfig::default()).expect("ref");
    let (mut wall_mu, mut wall_lambda, mut walls) = (0.0, 0.0, 0);
    let (mut free_mu, mut free_lambda, mut frees) = (0.0, 0.0, 0);
    for (i, cell) in stats.cells().iter().enumerate() {
        if cell.hits() >= 20 {
            wall_mu += reflection.field().probability(i);
            wall_lambda += decay.rates()[i];
            walls += 1;
        } else if cell.hits() == 0 && cell.misses() >= 20 {
            free_mu += reflection.field().probability(i);
            free_lambda += decay.rates()[i];
            frees += 1;
        }
    }
    let (wall_mu, wall_lambda) = (wall_mu / f64::from(walls), wall_lambda / f64::from(walls));
    let (free_mu, free_lambda) = (free_mu / f64::from(frees), free_lambda / f64::from(frees));
    eprintln!(
        "walls {walls}: mean μ {wall_mu:.3}, λ {wall_lambda:.2}/m; free {frees}: μ {free_mu:.4}, λ {free_lambda:.4}/m"
    );
    assert!(walls > 1000 && frees > 10_000);
    assert!(wall_mu > 0.3 && free_mu < 0.01);
    assert!(wall_lambda > 3.0 && free_lambda < 0.02);

    true_pose_wins("decay-rate", &decay, &test);
    true_pose_wins("reflection", &reflection, &test);
    let posterior_decay =
        DecayRatePosteriorModel2::new(&stats, GammaPosteriorConfig::default()).expect("fmp dec");
    true_pose_wins("decay-rate posterior", &posterior_decay, &test);
    let posterior_ref =
        ReflectionModel2::posterior(&stats, BetaPosteriorConfig::default()).expect("fmp ref");
    true_pose_wins("reflection posterior", &posterior_ref, &test);
    let field = LikelihoodFieldModel2::new(&stats, LikelihoodFieldConfig::default()).expect("lf");
    true_pose_wins("likelihood field", &field, &test);
    let log_odds = LogOddsModel2::new(&stats, LogOddsConfig::default()).expect("log-odds");
    true_pose_wins("log-odds", &log_odds, &test);
    let tabulated = Tabulated::<DecayRateModel2>::new(decay.clone(), OpticalDepthConfig::default())
        .expect("table");
    true_pose_wins("decay-rate (table)", &tabulated, &test);
}

/// Accuracy of the optical-depth tables against the exact traversal on real scans: scan
/// log-likelihoods at the true pose and at poses up to 0.5 m / 0.15 rad away.
#[test]
fn optical_depth_table_accuracy() {
    let Some(scans) = load() else {
        return;
    };
    let grid = grid_for(&scans);
    let refs: Vec<(Pose2, &Scan2)> = scans.iter().map(|(p, s)| (*p, s)).collect();
    let mut stats = DenseStats2::new(grid);
    stats.insert_scans_par(&refs, &MappingConfig::default());
    let decay = DecayRateModel2::new(&stats, DecayRateConfig::default()).unwrap();
    let reflection =
        ReflectionModel2::maximum_likelihood(&stats, ReflectionConfig::default()).unwrap();
    let posterior = DecayRatePosteriorModel2::new(&stats, GammaPosteriorConfig::default()).unwrap();
    for blend in [false, true] {
        let config = OpticalDepthConfig {
            blend_directions: blend,
            ..Default::default()
        };
        let started = std::time::Instant::now();
        let decay_table = Tabulated::<DecayRateModel2>::new(decay.clone(), config).unwrap();
        eprintln!(
            "table: {} directions, {:.0} MB, built in {:.2} s",
            decay_table.table().num_directions(),
            decay_table.table().memory_bytes() as f64 / 1e6,
            started.elapsed().as_secs_f64()
        );
        let reflection_table =
            Tabulated::<ReflectionModel2>::new(reflection.clone(), config).unwrap();
        let posterior_table =
            Tabulated::<DecayRatePosteriorModel2>::new(posterior.clone(), config).unwrap();
        for (name, exact, table) in [
            (
                "decay-rate",
                &decay as &dyn SensorModel<Planar>,
                &decay_table as &dyn SensorModel<Planar>,
            ),
            ("reflection", &reflection, &reflection_table),
            ("decay-rate posterior", &posterior, &posterior_table),
        ] {
            let exact = ScanLikelihood::new(exact);
            let table = ScanLikelihood::new(table);
            let mut relative = Vec::new();
            let mut per_ray = Vec::new();
            let (mut agree, mut pairs) = (0u32, 0u32);
            for (i, (pose, scan)) in scans.iter().enumerate().step_by(23) {
                let mut values = Vec::new();
                for k in 0..8 {
                    let f = (i * 8 + k) as f64;
                    let (dx, dy, dt) = if k == 0 {
                        (0.0, 0.0, 0.0)
                    } else {
                        (
                            0.5 * (f * 0.37).sin(),
                            0.5 * (f * 0.71).cos(),
                            0.15 * (f * 1.3).sin(),
                        )
                    };
                    let p = Pose2::new(pose.x() + dx, pose.y() + dy, pose.theta() + dt);
                    let (e, t) = (
                        exact.log_likelihood(&p, scan),
                        table.log_likelihood(&p, scan),
                    );
                    relative.push(((t - e) / e).abs());
                    per_ray.push((t - e).abs() / scan.len() as f64);
                    values.push((e, t));
                }
                for a in 0..values.len() {
                    for b in a + 1..values.len() {
                        pairs += 1;
                        if (values[a].0 > values[b].0) == (values[a].1 > values[b].1) {
                            agree += 1;
                        }
                    }
                }
            }
            relative.sort_by(f64::total_cmp);
            per_ray.sort_by(f64::total_cmp);
            let q = |v: &[f64], p: f64| v[((v.len() - 1) as f64 * p) as usize];
            eprintln!(
                "{name} blend={blend}: relative error of scan log-likelihoods median {:.4} p95 {:.4}; |Δ| per ray median {:.4} p95 {:.4} nats; pose order agrees {:.3}",
                q(&relative, 0.5),
                q(&relative, 0.95),
                q(&per_ray, 0.5),
                q(&per_ray, 0.95),
                f64::from(agree) / f64::from(pairs)
            );
            assert!(
                q(&relative, 0.5) < 0.1,
                "{name}: median relative error too large"
            );
            assert!(f64::from(agree) / f64::from(pairs) > 0.9);
        }
    }
}
