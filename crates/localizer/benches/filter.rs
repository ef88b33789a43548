//! Filter update rate with a cheap synthetic measurement model, so that the overhead of the
//! filter itself (predict + weight + resample) is known apart from the sensor models.
//!
//! The measurement model is 8 beacon ranges with Gaussian noise (8 square roots per
//! particle). Every configuration runs on one thread and on all cores (a rayon pool each).
//! Pole-landmark localization aims at 5000 particles at ≥ 50 Hz: the filter's share of the
//! 20 ms budget is what `step` reports here.
//!
//! Run: `cargo bench -p raypath-localizer --bench filter`.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_main};
use nalgebra::Point3;
use raypath_geometry::{Pose2, Pose3};
use raypath_localizer::init::GaussianInit;
use raypath_localizer::motion::{Gaussian6DofMotionModel, OdometryControl, OdometryMotionModel};
use raypath_localizer::{FilterConfig, FilterState, MeasurementModel, ParticleFilter};

/// Ranges to 8 beacons, Gaussian noise (log-likelihood up to a constant).
struct Beacons {
    at: Vec<Point3<f64>>,
    inv_sigma: f64,
}

impl Beacons {
    fn new() -> Self {
        Self {
            at: (0..8)
                .map(|i| {
                    let a = f64::from(i) * std::f64::consts::TAU / 8.0;
                    Point3::new(20.0 * a.cos(), 20.0 * a.sin(), f64::from(i % 3))
                })
                .collect(),
            inv_sigma: 1.0 / 0.3,
        }
    }

    fn ranges(&self, p: &Point3<f64>) -> Vec<f64> {
        self.at.iter().map(|b| (b - p).norm()).collect()
    }

    fn log_likelihood_at(&self, p: &Point3<f64>, ranges: &[f64]) -> f64 {
        self.at
            .iter()
            .zip(ranges)
            .map(|(b, r)| {
                let e = ((b - p).norm() - r) * self.inv_sigma;
                -0.5 * e * e
            })
            .sum()
    }
}

impl MeasurementModel<Pose2> for Beacons {
    type Observation = [f64];
    fn log_likelihood(&self, pose: &Pose2, ranges: &[f64]) -> f64 {
        self.log_likelihood_at(&Point3::new(pose.x(), pose.y(), 0.0), ranges)
    }
}

impl MeasurementModel<Pose3> for Beacons {
    type Observation = [f64];
    fn log_likelihood(&self, pose: &Pose3, ranges: &[f64]) -> f64 {
        self.log_likelihood_at(&Point3::from(pose.translation()), ranges)
    }
}

fn thread_counts() -> Vec<usize> {
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    if all > 1 { vec![1, all] } else { vec![1] }
}

/// Always resample, so every iteration pays for predict + weight + resample.
fn config() -> FilterConfig {
    FilterConfig {
        resample_ess_ratio: 1.0,
        ..FilterConfig::default()
    }
}

fn planar(c: &mut Criterion) {
    let beacons = Beacons::new();
    let ranges = beacons.ranges(&Point3::new(1.0, 2.0, 0.0));
    let motion = OdometryMotionModel::default();
    let control = OdometryControl::from_increment(&Pose2::new(0.1, 0.0, 0.01));
    let init = GaussianInit::new(Pose2::new(1.0, 2.0, 0.3));
    for stage in ["step", "predict", "update", "resample"] {
        let mut group = c.benchmark_group(format!("se2/{stage}"));
        group
            .sample_size(30)
            .measurement_time(Duration::from_secs(3));
        for particles in [1000usize, 5000] {
            group.throughput(Throughput::Elements(particles as u64));
            for threads in thread_counts() {
                let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build() else {
                    continue;
                };
                let Ok(mut filter) =
                    ParticleFilter::from_initializer(&init, particles, config(), 1)
                else {
                    continue;
                };
                let id = BenchmarkId::new(format!("{threads}thr"), particles);
                group.bench_function(id, |b| {
                    // The timing loop runs inside the pool, so rayon uses its threads.
                    b.iter_custom(|iters| {
                        pool.install(|| {
                            let start = Instant::now();
                            for _ in 0..iters {
                                match stage {
                                    "step" => {
                                        let _ = black_box(filter.step(
                                            &motion,
                                            &control,
                                            &beacons,
                                            ranges.as_slice(),
                                        ));
                                    }
                                    "predict" => filter.predict(&motion, &control),
                                    "update" => {
                                        let _ =
                                            black_box(filter.update(&beacons, ranges.as_slice()));
                                    }
                                    _ => {
                                        black_box(filter.resample());
                                    }
                                }
                            }
                            start.elapsed()
                        })
                    })
                });
                black_box(filter.estimate(Default::default()).to_planar());
            }
        }
        group.finish();
    }
}

fn six_dof(c: &mut Criterion) {
    let beacons = Beacons::new();
    let ranges = beacons.ranges(&Point3::new(1.0, 2.0, 0.5));
    let motion = Gaussian6DofMotionModel::default();
    let increment = Pose3::from_xyz_rpy(0.1, 0.0, 0.0, 0.0, 0.0, 0.01);
    let init = GaussianInit::new(Pose3::from_xyz_rpy(1.0, 2.0, 0.5, 0.0, 0.0, 0.3));
    let mut group = c.benchmark_group("se3/step");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(3));
    for particles in [1000usize, 5000] {
        group.throughput(Throughput::Elements(particles as u64));
        for threads in thread_counts() {
            let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build() else {
                continue;
            };
            let Ok(mut filter) = ParticleFilter::from_initializer(&init, particles, config(), 1)
            else {
                continue;
            };
            let id = BenchmarkId::new(format!("{threads}thr"), particles);
            group.bench_function(id, |b| {
                b.iter_custom(|iters| {
                    pool.install(|| {
                        let start = Instant::now();
                        for _ in 0..iters {
                            let _ = black_box(filter.step(
                                &motion,
                                &increment,
                                &beacons,
                                ranges.as_slice(),
                            ));
                        }
                        start.elapsed()
                    })
                })
            });
        }
    }
    group.finish();
}

/// The Criterion group (in a private module: the macro's function has no docs).
mod group {
    criterion::criterion_group!(benches, super::planar, super::six_dof);
}
criterion_main!(group::benches);
