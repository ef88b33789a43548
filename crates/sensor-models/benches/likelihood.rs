//! Ray log-likelihood throughput, `cargo bench -p raypath-sensor-models --bench likelihood`.
//!
//! One thread; criterion reports the median time per iteration and the throughput.
//!
//! * `likelihood/2d-ray`: 4 000 rays scored on a 0.1 m map, per model, exact (traversal)
//!   and tabulated ([`Tabulated`], cumulative optical depth in 360 directions). The map is
//!   built from the corrected Intel log when `$RAYPATH_DATA/carmen/corrected/
//!   intel-corrected.log.gz` exists (the test rays are the beams of every 20th scan), else
//!   from a synthetic 40 m × 40 m room with pillars scanned from 400 poses.
//! * `likelihood/2d-scan`: the same with a whole 180-beam scan as the unit (20 scans at
//!   their poses through [`ScanLikelihood`], prepared once): scans per second.
//! * `likelihood/3d-ray`: 5 000 rays on a 0.5 m voxel map (100 m × 100 m × 20 m,
//!   200 × 200 × 40) built from 24 synthetic sweeps of 20 000 rays, exact traversal.

#![allow(clippy::unwrap_used)] // benchmark set-up on fixed, valid inputs

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkGroup, Criterion, Throughput, criterion_main, measurement::WallTime};
use nalgebra::{Point2, Point3, Vector2, Vector3};
use raypath_geometry::{Aabb2, Grid2, Grid3, Pose2, Range, Ray2, Ray3, Scan2};
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use raypath_sensor_models::{
    BetaPosteriorConfig, DecayRateConfig, DecayRateModel, DecayRatePosteriorModel, DenseStats,
    DenseStats2, DenseStats3, Dimension, GammaPosteriorConfig, LikelihoodFieldConfig,
    LikelihoodFieldModel, LogOddsConfig, LogOddsModel, MappingConfig, OpticalDepthConfig,
    PreparedScan, ReflectionConfig, ReflectionModel, ScanLikelihood, SensorModel, SensorRange,
    Tabulated,
};

/// Uniform numbers in `[0, 1)` from SplitMix64 (53 bits).
struct Rng(rand_xoshiro::SplitMix64);
impl Rng {
    fn new(state: u64) -> Self {
        use rand_xoshiro::rand_core::SeedableRng;
        Self(rand_xoshiro::SplitMix64::seed_from_u64(state))
    }

    fn next(&mut self) -> f64 {
        use rand_xoshiro::rand_core::RngCore;
        (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Scans with their poses: the Intel log, or a synthetic room.
fn scans_2d() -> (&'static str, Vec<(Pose2, Scan2)>) {
    if let Some(path) = raypath_io::data::require("carmen/corrected/intel-corrected.log.gz") {
        let options = PlanarOptions {
            laser: LaserChoice::Front,
            ..PlanarOptions::default()
        };
        let scans = read_planar(&path, &options)
            .unwrap()
            .into_iter()
            .map(|f| (f.world_from_laser, f.scan))
            .collect();
        return ("intel", scans);
    }
    ("synthetic room", synthetic_room())
}

/// A 40 m square room with a 4 × 4 lattice of 1 m round pillars, scanned by 180 beams.
fn synthetic_room() -> Vec<(Pose2, Scan2)> {
    let mut rng = Rng::new(7);
    let pillars: Vec<Point2<f64>> = (0..16)
        .map(|i| Point2::new(-15.0 + 10.0 * (i % 4) as f64, -15.0 + 10.0 * (i / 4) as f64))
        .collect();
    (0..400)
        .map(|_| {
            let pose = Pose2::new(
                -18.0 + 36.0 * rng.next(),
                -18.0 + 36.0 * rng.next(),
                std::f64::consts::TAU * rng.next(),
            );
            let origin = Point2::new(pose.x(), pose.y());
            let ranges: Vec<f64> = (0..180)
                .map(|i| {
                    let angle = pose.theta() + (i as f64 - 90.0).to_radians();
                    let d = Vector2::new(angle.cos(), angle.sin());
                    let wall = [(20.0 - origin.x) / d.x, (-20.0 - origin.x) / d.x]
                        .into_iter()
                        .chain([(20.0 - origin.y) / d.y, (-20.0 - origin.y) / d.y])
                        .filter(|t| *t > 0.0)
                        .fold(f64::INFINITY, f64::min);
                    let pillar = pillars
                        .iter()
                        .filter_map(|c| {
                            let oc = origin - c;
                            let b = oc.dot(&d);
                            let disc = b * b - (oc.norm_squared() - 0.25);
                            (disc >= 0.0).then(|| -b - disc.sqrt()).filter(|t| *t > 0.0)
                        })
                        .fold(f64::INFINITY, f64::min);
                    wall.min(pillar)
                })
                .collect();
            let scan = Scan2 {
                angle_min_rad: -std::f64::consts::FRAC_PI_2,
                angle_increment_rad: 1f64.to_radians(),
                max_range_m: 30.0,
                ranges,
                intensities: None,
            };
            (pose, scan)
        })
        .collect()
}

fn grid_2d(scans: &[(Pose2, Scan2)]) -> Grid2 {
    let mut bounds = Aabb2::empty();
    for (pose, scan) in scans {
        scan.points(*pose).for_each(|p| bounds.extend(&p));
        bounds.extend(&Point2::new(pose.x(), pose.y()));
    }
    let margin = Vector2::new(1.0, 1.0);
    Grid2::covering(&Aabb2::new(bounds.min - margin, bounds.max + margin), 0.1).unwrap()
}

fn bench_rays<D: Dimension>(
    group: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    model: &impl SensorModel<D>,
    rays: &[D::Ray],
) {
    group.bench_function(name, |b| {
        b.iter(|| {
            rays.iter()
                .map(|ray| model.ray_log_likelihood(ray))
                .sum::<f64>()
        })
    });
}

fn bench_scans(
    group: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    model: &impl SensorModel<raypath_sensor_models::Planar>,
    scans: &[(Pose2, Scan2)],
) {
    let adapter = ScanLikelihood::new(model);
    let prepared: Vec<(Pose2, PreparedScan)> = scans
        .iter()
        .map(|(pose, scan)| (*pose, adapter.prepare(scan)))
        .collect();
    group.bench_function(name, |b| {
        b.iter(|| {
            prepared
                .iter()
                .map(|(pose, scan)| adapter.log_likelihood_prepared(pose, scan))
                .sum::<f64>()
        })
    });
}

/// Every model of the crate on `stats`.
struct Models<D: Dimension> {
    decay_ml: DecayRateModel<D>,
    decay_posterior: DecayRatePosteriorModel<D>,
    reflection_ml: ReflectionModel<D>,
    reflection_posterior: ReflectionModel<D>,
    log_odds: LogOddsModel<D>,
    likelihood_field: LikelihoodFieldModel<D>,
}

fn models<D: Dimension>(stats: &DenseStats<D>, range: SensorRange) -> Models<D> {
    Models {
        decay_ml: DecayRateModel::new(
            stats,
            DecayRateConfig {
                range,
                ..Default::default()
            },
        )
        .unwrap(),
        decay_posterior: DecayRatePosteriorModel::new(
            stats,
            GammaPosteriorConfig { range, prior: None },
        )
        .unwrap(),
        reflection_ml: ReflectionModel::maximum_likelihood(
            stats,
            ReflectionConfig {
                range,
                ..Default::default()
            },
        )
        .unwrap(),
        reflection_posterior: ReflectionModel::posterior(
            stats,
            BetaPosteriorConfig { range, prior: None },
        )
        .unwrap(),
        log_odds: LogOddsModel::new(
            stats,
            LogOddsConfig {
                range,
                ..Default::default()
            },
        )
        .unwrap(),
        likelihood_field: LikelihoodFieldModel::new(
            stats,
            LikelihoodFieldConfig {
                range,
                ..Default::default()
            },
        )
        .unwrap(),
    }
}

fn likelihood_2d(c: &mut Criterion) {
    let (source, scans) = scans_2d();
    let range = SensorRange::new(0.0, 30.0).unwrap();
    let mut stats = DenseStats2::planar(grid_2d(&scans));
    let refs: Vec<(Pose2, &Scan2)> = scans.iter().map(|(p, s)| (*p, s)).collect();
    stats.insert_scans_par(
        &refs,
        &MappingConfig {
            range,
            ..Default::default()
        },
    );
    let m = models(&stats, range);
    let od = OpticalDepthConfig::default();
    let tab_decay = Tabulated::<DecayRateModel<_>>::new(m.decay_ml.clone(), od).unwrap();
    let tab_decay_post =
        Tabulated::<DecayRatePosteriorModel<_>>::new(m.decay_posterior.clone(), od).unwrap();
    let tab_reflection = Tabulated::<ReflectionModel<_>>::new(m.reflection_ml.clone(), od).unwrap();
    let tab_reflection_post =
        Tabulated::<ReflectionModel<_>>::new(m.reflection_posterior.clone(), od).unwrap();
    let tab_log_odds = Tabulated::<LogOddsModel<_>>::new(m.log_odds.clone(), od).unwrap();
    let tab_field =
        Tabulated::<LikelihoodFieldModel<_>>::new(m.likelihood_field.clone(), od).unwrap();
    eprintln!(
        "2-D map: {source}, {} scans, grid {:?} at 0.1 m",
        scans.len(),
        stats.grid().dims()
    );

    let rays: Vec<Ray2> = scans
        .iter()
        .step_by(20)
        .flat_map(|(pose, scan)| scan.rays(*pose).collect::<Vec<_>>())
        .take(4000)
        .collect();
    let mut group = c.benchmark_group("likelihood/2d-ray");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(rays.len() as u64));
    bench_rays(&mut group, "decay-rate", &m.decay_ml, &rays);
    bench_rays(
        &mut group,
        "decay-rate-posterior",
        &m.decay_posterior,
        &rays,
    );
    bench_rays(&mut group, "reflection", &m.reflection_ml, &rays);
    bench_rays(
        &mut group,
        "reflection-posterior",
        &m.reflection_posterior,
        &rays,
    );
    bench_rays(&mut group, "log-odds", &m.log_odds, &rays);
    bench_rays(&mut group, "likelihood-field", &m.likelihood_field, &rays);
    bench_rays(&mut group, "decay-rate-tabulated", &tab_decay, &rays);
    bench_rays(
        &mut group,
        "decay-rate-posterior-tabulated",
        &tab_decay_post,
        &rays,
    );
    bench_rays(&mut group, "reflection-tabulated", &tab_reflection, &rays);
    bench_rays(
        &mut group,
        "reflection-posterior-tabulated",
        &tab_reflection_post,
        &rays,
    );
    bench_rays(&mut group, "log-odds-tabulated", &tab_log_odds, &rays);
    bench_rays(&mut group, "likelihood-field-tabulated", &tab_field, &rays);
    group.finish();

    let test: Vec<(Pose2, Scan2)> = scans.iter().step_by(40).take(20).cloned().collect();
    let mut group = c.benchmark_group("likelihood/2d-scan");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(test.len() as u64));
    bench_scans(&mut group, "decay-rate", &m.decay_ml, &test);
    bench_scans(
        &mut group,
        "decay-rate-posterior",
        &m.decay_posterior,
        &test,
    );
    bench_scans(&mut group, "reflection", &m.reflection_ml, &test);
    bench_scans(
        &mut group,
        "reflection-posterior",
        &m.reflection_posterior,
        &test,
    );
    bench_scans(&mut group, "log-odds", &m.log_odds, &test);
    bench_scans(&mut group, "likelihood-field", &m.likelihood_field, &test);
    bench_scans(&mut group, "decay-rate-tabulated", &tab_decay, &test);
    bench_scans(
        &mut group,
        "decay-rate-posterior-tabulated",
        &tab_decay_post,
        &test,
    );
    bench_scans(&mut group, "reflection-tabulated", &tab_reflection, &test);
    bench_scans(
        &mut group,
        "reflection-posterior-tabulated",
        &tab_reflection_post,
        &test,
    );
    bench_scans(&mut group, "log-odds-tabulated", &tab_log_odds, &test);
    bench_scans(&mut group, "likelihood-field-tabulated", &tab_field, &test);
    group.finish();
}

/// Synthetic sweeps: rays from poses on a 30 m circle, elevations −24.8° to +2°, ranges
/// 5–40 m, 5 % no-returns.
fn sweeps_3d(count: usize, rays: usize, seed: u64) -> Vec<Vec<Ray3>> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|s| {
            let phase = s as f64 / count as f64 * std::f64::consts::TAU;
            let origin = Point3::new(30.0 * phase.cos(), 30.0 * phase.sin(), 1.8);
            (0..rays)
                .map(|_| {
                    let azimuth = rng.next() * std::f64::consts::TAU;
                    let elevation = (-24.8 + 26.8 * rng.next()).to_radians();
                    let direction = Vector3::new(
                        elevation.cos() * azimuth.cos(),
                        elevation.cos() * azimuth.sin(),
                        elevation.sin(),
                    );
                    let range = if rng.next() < 0.05 {
                        Range::NoReturn
                    } else {
                        Range::Hit(5.0 + 35.0 * rng.next())
                    };
                    Ray3::new(origin, direction, range).unwrap()
                })
                .collect()
        })
        .collect()
}

fn likelihood_3d(c: &mut Criterion) {
    let range = SensorRange::new(0.0, 40.0).unwrap();
    let grid = Grid3::new(Point3::new(-50.0, -50.0, -5.0), 0.5, [200, 200, 40]).unwrap();
    let mut stats = DenseStats3::spatial(grid);
    stats.insert_par(
        &sweeps_3d(24, 20_000, 3),
        &MappingConfig {
            range,
            ..Default::default()
        },
        |sweep, sink| sweep.iter().for_each(&mut *sink),
    );
    let m = models(&stats, range);
    let rays: Vec<Ray3> = sweeps_3d(7, 5_000, 11).swap_remove(3);
    let mut group = c.benchmark_group("likelihood/3d-ray");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(rays.len() as u64));
    bench_rays(&mut group, "decay-rate", &m.decay_ml, &rays);
    bench_rays(
        &mut group,
        "decay-rate-posterior",
        &m.decay_posterior,
        &rays,
    );
    bench_rays(&mut group, "reflection", &m.reflection_ml, &rays);
    bench_rays(
        &mut group,
        "reflection-posterior",
        &m.reflection_posterior,
        &rays,
    );
    bench_rays(&mut group, "log-odds", &m.log_odds, &rays);
    bench_rays(&mut group, "likelihood-field", &m.likelihood_field, &rays);
    group.finish();
    black_box(&stats);
}

fn benches() {
    let mut criterion = Criterion::default().configure_from_args();
    likelihood_2d(&mut criterion);
    likelihood_3d(&mut criterion);
}

criterion_main!(benches);
