//! Invariants of the filter under arbitrary log-likelihoods (including −∞).

#![allow(clippy::unwrap_used)]

use proptest::prelude::*;
use raypath_geometry::Pose2;
use raypath_localizer::init::UniformBox;
use raypath_localizer::kld::KldConfig;
use raypath_localizer::motion::{OdometryControl, OdometryMotionModel};
use raypath_localizer::{Estimator, FilterConfig, MeasurementModel, ParticleFilter};

/// A log-likelihood looked up from a table by a hash of the particle's position bits.
struct Table(Vec<f64>);

impl MeasurementModel<Pose2> for Table {
    type Observation = u64;
    fn log_likelihood(&self, pose: &Pose2, salt: &u64) -> f64 {
        let h = pose.x().to_bits() ^ pose.y().to_bits().rotate_left(17) ^ salt;
        let h = h.wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.0[(h >> 40) as usize % self.0.len()]
    }
}

fn table() -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(
        prop_oneof![
            4 => -1e4..10.0f64,
            1 => Just(f64::NEG_INFINITY),
        ],
        1..64,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn weights_stay_normalized_and_counts_stay_in_bounds(
        tables in prop::collection::vec(table(), 1..6),
        particles in 1usize..400,
        ratio in 0.05..1.0f64,
        kld in any::<bool>(),
        seed in any::<u64>(),
    ) {
        let kld_config = KldConfig { min_particles: 5, max_particles: 500, ..KldConfig::default() };
        let config = FilterConfig {
            resample_ess_ratio: ratio,
            kld: kld.then_some(kld_config),
            ..FilterConfig::default()
        };
        let init = UniformBox::new([0.0, 10.0], [0.0, 10.0]);
        let mut filter = ParticleFilter::from_initializer(&init, particles, config, seed).unwrap();
        let motion = OdometryMotionModel::default();
        let control = OdometryControl::from_increment(&Pose2::new(0.3, 0.0, 0.1));
        for (step, t) in tables.iter().enumerate() {
            let before = filter.log_weights().to_vec();
            match filter.step(&motion, &control, &Table(t.clone()), &(step as u64)) {
                Ok(report) => {
                    prop_assert!(report.update.ess >= 1.0 - 1e-9);
                    if let Some(r) = report.resample {
                        if kld {
                            prop_assert!(r.particles_after >= 5 && r.particles_after <= 500);
                        } else {
                            prop_assert_eq!(r.particles_after, r.particles_before);
                        }
                    }
                }
                Err(_) => {
                    // Only an all-impossible update fails, and it keeps the weights.
                    prop_assert!(t.contains(&f64::NEG_INFINITY));
                    prop_assert_eq!(filter.log_weights(), before.as_slice());
                }
            }
            let total: f64 = filter.weights().sum();
            prop_assert!((total - 1.0).abs() < 1e-9, "weights sum to {}", total);
            prop_assert!(filter.log_weights().iter().all(|l| !l.is_nan()));
            let ess = filter.ess();
            prop_assert!(ess >= 1.0 - 1e-9 && ess <= filter.len() as f64 * (1.0 + 1e-9));
            for estimator in [Estimator::WeightedMean, Estimator::default(), Estimator::MaxWeight] {
                prop_assert!(filter.estimate(estimator).is_finite());
            }
        }
    }
}
