//! Toy localization problems with beacon range measurements: convergence from a uniform
//! start, determinism per seed and across thread counts, SE(3), KLD-sampling.

#![allow(clippy::unwrap_used)]

use nalgebra::{Point3, Vector3};
use rand_distr::{Distribution, Normal};
use raypath_geometry::{Pose2, Pose3, wrap_angle};
use raypath_localizer::init::{GaussianInit, UniformBox};
use raypath_localizer::kld::KldConfig;
use raypath_localizer::motion::{Gaussian6DofMotionModel, OdometryControl, OdometryMotionModel};
use raypath_localizer::{
    Estimator, FilterConfig, LocalizerError, MeasurementModel, ParticleFilter, ParticleRng,
};

/// Range measurements to known beacons with Gaussian noise (log-likelihood up to a constant).
struct Beacons {
    at: Vec<Point3<f64>>,
    sigma_m: f64,
}

impl Beacons {
    fn ranges(&self, position: &Point3<f64>, noise_seed: u64) -> Vec<f64> {
        let mut rng = ParticleRng::seed_from_u64(noise_seed);
        let noise = Normal::new(0.0, self.sigma_m).unwrap();
        self.at
            .iter()
            .map(|b| (b - position).norm() + noise.sample(&mut rng))
            .collect()
    }

    fn log_likelihood_at(&self, position: &Point3<f64>, ranges: &[f64]) -> f64 {
        self.at
            .iter()
            .zip(ranges)
            .map(|(b, r)| {
                let e = ((b - position).norm() - r) / self.sigma_m;
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

fn planar_beacons() -> Beacons {
    Beacons {
        at: [
            (0.0, 0.0),
            (20.0, 0.0),
            (0.0, 20.0),
            (20.0, 20.0),
            (10.0, 12.0),
        ]
        .iter()
        .map(|&(x, y)| Point3::new(x, y, 0.0))
        .collect(),
        sigma_m: 0.3,
    }
}

/// The true robot path: a circle of radius 5 m around (10, 10), 0.5 m per step.
fn true_pose(step: usize) -> Pose2 {
    let angle = step as f64 * 0.1;
    Pose2::new(
        10.0 + 5.0 * angle.cos(),
        10.0 + 5.0 * angle.sin(),
        wrap_angle(angle + std::f64::consts::FRAC_PI_2),
    )
}

/// Runs the planar problem from a uniform start; returns the filter and the final errors.
fn run_planar(
    seed: u64,
    particles: usize,
    config: FilterConfig,
    steps: usize,
) -> ParticleFilter<Pose2> {
    let beacons = planar_beacons();
    let motion = OdometryMotionModel::new(0.02, 0.02, 0.02, 0.02).unwrap();
    let start = UniformBox::new([0.0, 20.0], [0.0, 20.0]);
    let mut filter = ParticleFilter::from_initializer(&start, particles, config, seed).unwrap();
    let first = true_pose(0);
    filter
        .update(
            &beacons,
            &beacons.ranges(&Point3::new(first.x(), first.y(), 0.0), 1000),
        )
        .unwrap();
    filter.resample_if_needed();
    for step in 1..=steps {
        let (previous, current) = (true_pose(step - 1), true_pose(step));
        let control = OdometryControl::from_poses(&previous, &current);
        let ranges = beacons.ranges(
            &Point3::new(current.x(), current.y(), 0.0),
            1000 + step as u64,
        );
        filter
            .step(&motion, &control, &beacons, ranges.as_slice())
            .unwrap();
    }
    filter
}

fn planar_error(filter: &ParticleFilter<Pose2>, truth: &Pose2) -> (f64, f64) {
    let estimate = filter.estimate(Estimator::default());
    (
        (estimate.translation() - truth.translation()).norm(),
        wrap_angle(estimate.theta() - truth.theta()).abs(),
    )
}

#[test]
fn converges_from_a_uniform_start() {
    for seed in [1, 2, 3] {
        let filter = run_planar(seed, 3000, FilterConfig::default(), 40);
        let (position, heading) = planar_error(&filter, &true_pose(40));
        assert!(position < 0.3, "seed {seed}: position error {position} m");
        assert!(heading < 0.1, "seed {seed}: heading error {heading} rad");
        // The particle cloud has collapsed around the truth.
        let spread = filter
            .states()
            .iter()
            .zip(filter.weights())
            .map(|(s, w)| w * (s.translation() - true_pose(40).translation()).norm_squared())
            .sum::<f64>()
            .sqrt();
        assert!(spread < 0.5, "seed {seed}: spread {spread} m");
    }
}

fn bits(filter: &ParticleFilter<Pose2>) -> Vec<u64> {
    filter
        .states()
        .iter()
        .flat_map(|s| [s.x().to_bits(), s.y().to_bits(), s.theta().to_bits()])
        .chain(filter.log_weights().iter().map(|l| l.to_bits()))
        .collect()
}

#[test]
fn deterministic_per_seed_and_across_thread_counts() {
    let run_with_particles = |threads: usize, seed: u64, particles: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| run_planar(seed, particles, FilterConfig::default(), 15))
    };
    let run_with = |threads: usize, seed: u64| run_with_particles(threads, seed, 1000);
    let one = run_with(1, 11);
    let two = run_with(2, 11);
    let again = run_with(2, 11);
    let other = run_with(2, 12);
    assert_eq!(bits(&one), bits(&two), "1 vs 2 threads differ");
    assert_eq!(bits(&two), bits(&again));
    assert_ne!(bits(&two), bits(&other));
    // More particles than one summation chunk (2048): parallel normalization and ESS.
    let big_one = run_with_particles(1, 13, 5000);
    let big_two = run_with_particles(2, 13, 5000);
    assert_eq!(
        bits(&big_one),
        bits(&big_two),
        "5000 particles: 1 vs 2 threads differ"
    );
    // KLD-sampling (sequential draws) is deterministic too.
    let kld = FilterConfig {
        kld: Some(KldConfig::default()),
        ..FilterConfig::default()
    };
    let pool1 = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let pool2 = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let a = pool1.install(|| run_planar(5, 2000, kld, 10));
    let b = pool2.install(|| run_planar(5, 2000, kld, 10));
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn kld_sampling_converges_with_fewer_particles() {
    let config = FilterConfig {
        kld: Some(KldConfig {
            max_particles: 5000,
            min_particles: 100,
            ..KldConfig::default()
        }),
        resample_ess_ratio: 1.0,
        ..FilterConfig::default()
    };
    let filter = run_planar(4, 5000, config, 40);
    let (position, heading) = planar_error(&filter, &true_pose(40));
    // Heading is only observed through the motion (ranges give positions): 0.15 rad.
    assert!(
        position < 0.3 && heading < 0.15,
        "errors {position} m, {heading} rad"
    );
    // A converged cloud occupies few 0.5 m × 0.5 m × 10° bins: far fewer than the 5000
    // particles a uniform cloud over 20 m × 20 m × 2π needs.
    assert!(
        filter.len() < 3000,
        "{} particles after convergence",
        filter.len()
    );
}

#[test]
fn impossible_and_nan_likelihoods_are_errors_that_keep_the_weights() {
    struct Constant(f64);
    impl MeasurementModel<Pose2> for Constant {
        type Observation = ();
        fn log_likelihood(&self, _: &Pose2, _: &()) -> f64 {
            self.0
        }
    }
    let start = UniformBox::new([0.0, 1.0], [0.0, 1.0]);
    let mut filter =
        ParticleFilter::from_initializer(&start, 100, FilterConfig::default(), 0).unwrap();
    let before = filter.log_weights().to_vec();
    assert!(matches!(
        filter.update(&Constant(f64::NEG_INFINITY), &()),
        Err(LocalizerError::AllParticlesImpossible { particles: 100 })
    ));
    assert!(matches!(
        filter.update(&Constant(f64::NAN), &()),
        Err(LocalizerError::NanLikelihood { particle: 0 })
    ));
    assert_eq!(filter.log_weights(), before.as_slice());
    assert!(ParticleFilter::<Pose2>::new(vec![], FilterConfig::default(), 0).is_err());
    let bad = FilterConfig {
        resample_ess_ratio: 0.0,
        ..FilterConfig::default()
    };
    assert!(ParticleFilter::from_initializer(&start, 10, bad, 0).is_err());
}

/// 6-DOF: beacons at different heights, the thesis's ch. 7 Gaussian initialization (1 m,
/// 0.2 m, 0.1 rad) around a start 1 m off the truth. (Orientation is observed only through the
/// motion, so 1000 particles rather than the thesis's 300 lidar-weighted ones.)
#[test]
fn six_dof_filter_tracks_from_a_gaussian_start() {
    let beacons = Beacons {
        at: [
            (0.0, 0.0, -5.0),
            (30.0, 0.0, 15.0),
            (0.0, 30.0, 15.0),
            (30.0, 30.0, -5.0),
            (15.0, 10.0, 20.0),
            (5.0, 25.0, -10.0),
            (25.0, 20.0, 1.0),
        ]
        .iter()
        .map(|&(x, y, z)| Point3::new(x, y, z))
        .collect(),
        sigma_m: 0.2,
    };
    let truth = |step: usize| {
        let s = step as f64;
        Pose3::from_xyz_rpy(
            5.0 + 0.5 * s,
            5.0 + 0.3 * s,
            1.0,
            0.0,
            0.0,
            0.3f64.atan2(0.5),
        )
    };
    let increment = truth(0).inverse() * truth(1);
    let mut init = GaussianInit::new(truth(0));
    init.mean = Pose3::from_parts(
        truth(0).translation() + Vector3::new(0.8, -0.6, 0.1),
        truth(0).rotation(),
    );
    for seed in [1, 2, 3, 4] {
        let mut filter =
            ParticleFilter::from_initializer(&init, 1000, FilterConfig::default(), seed).unwrap();
        let motion = Gaussian6DofMotionModel::default();
        for step in 1..=30 {
            let position = Point3::from(truth(step).translation());
            let ranges = beacons.ranges(&position, 77 + step as u64);
            filter
                .step(&motion, &increment, &beacons, ranges.as_slice())
                .unwrap();
        }
        let estimate = filter.estimate(Estimator::WeightedMean);
        let error = (estimate.translation() - truth(30).translation()).norm();
        assert!(error < 0.3, "seed {seed}: 3-D position error {error} m");
        let yaw = wrap_angle(estimate.to_planar().theta() - truth(30).to_planar().theta());
        assert!(yaw.abs() < 0.1, "seed {seed}: yaw error {yaw} rad");
    }
}
