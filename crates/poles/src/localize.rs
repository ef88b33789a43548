//! Pole-based particle-filter localization on SE(2) (Schaefer 2020, §12.4.3), on
//! `raypath-localizer`'s [`ParticleFilter`]:
//!
//! * motion: [`PlanarGaussianMotionModel`], `X_t = X_{t−1} · transform(ξ)`, `ξ ~ N(χ, Σ)`
//!   (the thesis prints `X_t = transform(ξ) · X_{t−1}`; body-frame increments compose on the
//!   right, as in the reference code);
//! * measurement: [`PoleLikelihood`], nearest-neighbour association through a k-d tree of the
//!   map poles ([`PoleIndex`]) with the gate `d_max`, `p(Λ | X, L) = Π_k (φ_σ(min(d_k,
//!   d_max)) + ε)`;
//! * low-variance resampling when `n_eff/N < 0.5` (the thesis's `(Σ w²)⁻¹ < 0.5` never holds
//!   for normalized weights; the code normalizes by `N`);
//! * initial particles [`UniformDisc`] uniform in the radius ([`RadialSampling::UniformRadius`],
//!   as the reference code; the thesis says "uniformly in a circle");
//! * the estimate [`Estimator::BestFraction`]: the weighted mean of the best 10 %.
//!
//! [`PoleFilter`] bundles the three models with [`FilterParams`]; a measurement update
//! without poles changes nothing (no reweighting, no resampling), as in the reference code.

use kiddo::{KdTree, SquaredEuclidean};
use nalgebra::Point2;
use raypath_geometry::Pose2;
use raypath_localizer::init::{RadialSampling, UniformDisc};
use raypath_localizer::motion::{PlanarGaussianMotionModel, PlanarIncrement};
use raypath_localizer::{Estimator, FilterConfig, MeasurementModel, ParticleFilter};
use serde::{Deserialize, Serialize};

use crate::error::{PoleError, Result, require};
use crate::pole::Pole;

/// Parameters of the particle filter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterParams {
    /// Number of particles (NCLT 5000, KITTI 2000).
    pub particles: usize,
    /// Initial position spread, metres (NCLT 2.5, KITTI 3.0): radius `r ~ U[0, R]`, bearing
    /// uniform (uniform in radius, as the reference code; the thesis says "uniformly in a
    /// circle").
    pub init_radius_m: f64,
    /// Initial heading spread `U[−Δφ, Δφ]`, radians (5°).
    pub init_heading_rad: f64,
    /// Variance σ² of the reference pole positions, m² (NCLT 1.5, KITTI 1.0, as the reference
    /// code; the thesis prints "σ = 1 m²").
    pub pole_variance_m2: f64,
    /// Probability ε of a pole not in the map (0.1).
    pub epsilon: f64,
    /// The association gate: `d_max` where the Gaussian pdf equals `p_min` (0.01).
    pub p_min: f64,
    /// Resample when `n_eff / N` falls below this (0.5; 0 never resamples).
    pub resample_fraction: f64,
    /// Fraction of best particles averaged into the estimate (0.1).
    pub best_fraction: f64,
}

impl FilterParams {
    /// The NCLT settings (Schaefer 2020, §12.5.1, and `ncltpoles.py`).
    pub fn nclt() -> Self {
        Self {
            particles: 5000,
            init_radius_m: 2.5,
            init_heading_rad: 5f64.to_radians(),
            pole_variance_m2: 1.5,
            epsilon: 0.1,
            p_min: 0.01,
            resample_fraction: 0.5,
            best_fraction: 0.1,
        }
    }

    /// The KITTI settings (Schaefer 2020, §12.5.2, and `kittipoles.py`).
    pub fn kitti() -> Self {
        Self {
            particles: 2000,
            init_radius_m: 3.0,
            pole_variance_m2: 1.0,
            ..Self::nclt()
        }
    }

    /// The gate `d_max = √(−2σ² ln(√(2πσ²) p_min))` (NaN-free: 0 when `p_min` exceeds the
    /// peak density).
    pub fn gate_m(&self) -> f64 {
        let var = self.pole_variance_m2;
        let arg = (2.0 * std::f64::consts::PI * var).sqrt() * self.p_min;
        (-2.0 * var * arg.ln()).max(0.0).sqrt()
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        require(
            (1..=10_000_000).contains(&self.particles),
            "particles",
            || format!("{} is not in 1..=10^7", self.particles),
        )?;
        let nonneg = |v: f64| v.is_finite() && v >= 0.0;
        require(nonneg(self.init_radius_m), "init_radius_m", || {
            format!("{}", self.init_radius_m)
        })?;
        require(nonneg(self.init_heading_rad), "init_heading_rad", || {
            format!("{}", self.init_heading_rad)
        })?;
        require(
            self.pole_variance_m2.is_finite() && self.pole_variance_m2 > 0.0,
            "pole_variance_m2",
            || format!("{}", self.pole_variance_m2),
        )?;
        require(nonneg(self.epsilon), "epsilon", || {
            format!("{}", self.epsilon)
        })?;
        require(self.p_min > 0.0 && self.p_min.is_finite(), "p_min", || {
            format!("{}", self.p_min)
        })?;
        require(
            (0.0..=1.0).contains(&self.resample_fraction),
            "resample_fraction",
            || format!("{}", self.resample_fraction),
        )?;
        require(
            self.best_fraction > 0.0 && self.best_fraction <= 1.0,
            "best_fraction",
            || format!("{}", self.best_fraction),
        )
    }

    /// The localizer's configuration: resampling at `n_eff / N < resample_fraction` (0 maps
    /// to the smallest positive ratio, which `n_eff ≥ 1` never falls below).
    fn config(&self) -> FilterConfig {
        FilterConfig {
            resample_ess_ratio: self.resample_fraction.max(f64::MIN_POSITIVE),
            ..FilterConfig::default()
        }
    }
}

impl Default for FilterParams {
    /// The NCLT settings.
    fn default() -> Self {
        Self::nclt()
    }
}

/// The reference map as a k-d tree over pole centres.
pub struct PoleIndex {
    tree: KdTree<f64, 2>,
    len: usize,
}

impl PoleIndex {
    /// Indexes the poles' ground-plane centres.
    pub fn new(poles: &[Pole]) -> Self {
        let mut tree: KdTree<f64, 2> = KdTree::with_capacity(poles.len().max(1));
        for (i, p) in poles.iter().enumerate() {
            tree.add(&[p.x, p.y], i as u64);
        }
        Self {
            tree,
            len: poles.len(),
        }
    }

    /// Distance to the nearest pole, metres (`∞` for an empty map).
    #[inline]
    pub fn nearest_distance(&self, x: f64, y: f64) -> f64 {
        if self.len == 0 {
            return f64::INFINITY;
        }
        self.tree
            .nearest_one::<SquaredEuclidean>(&[x, y])
            .distance
            .sqrt()
    }
}

/// The pole measurement model of §12.4.3 as a [`MeasurementModel`] over [`Pose2`]: the
/// observation is the online poles in the robot frame (metres); each is moved into the map
/// frame by the particle's pose, associated with its nearest map pole at distance `d_k`,
/// and contributes `ln(φ_σ(min(d_k, d_max)) + ε)` to the log-likelihood.
pub struct PoleLikelihood {
    index: PoleIndex,
    /// σ², m².
    variance: f64,
    /// `d_max`, metres.
    gate: f64,
    /// `1 / √(2πσ²)`.
    norm: f64,
    /// ε.
    epsilon: f64,
}

impl PoleLikelihood {
    /// The model on the reference map `map` with the variance, ε and gate of `params`.
    pub fn new(map: &[Pole], params: &FilterParams) -> Result<Self> {
        params.validate()?;
        let variance = params.pole_variance_m2;
        Ok(Self {
            index: PoleIndex::new(map),
            variance,
            gate: params.gate_m(),
            norm: 1.0 / (2.0 * std::f64::consts::PI * variance).sqrt(),
            epsilon: params.epsilon,
        })
    }

    /// The k-d tree of the map poles.
    pub fn index(&self) -> &PoleIndex {
        &self.index
    }
}

impl MeasurementModel<Pose2> for PoleLikelihood {
    type Observation = [Point2<f64>];

    fn log_likelihood(&self, pose: &Pose2, poles_in_robot: &[Point2<f64>]) -> f64 {
        let mut sum = 0.0;
        for p in poles_in_robot {
            let w = pose.transform_point(p);
            let d = self.index.nearest_distance(w.x, w.y).min(self.gate);
            // §12.4.3: p(λ_k | X, l_n(k)) = N(‖Xλ_k − l_n(k)‖; 0, σ) + ε
            sum += (self.norm * (-0.5 * d * d / self.variance).exp() + self.epsilon).ln();
        }
        sum
    }
}

/// The pole particle filter: [`ParticleFilter`] over [`Pose2`] with the models and settings
/// of §12.4.3 and [`FilterParams`] (module docs).
pub struct PoleFilter {
    params: FilterParams,
    model: PoleLikelihood,
    filter: ParticleFilter<Pose2>,
    resamples: usize,
}

impl PoleFilter {
    /// A filter on the reference map `map`, particles drawn around `start` (uniform radius
    /// and bearing, uniform heading offset) from per-particle streams of `seed`.
    pub fn new(map: &[Pole], params: FilterParams, start: Pose2, seed: u64) -> Result<Self> {
        params.validate()?;
        if !start.is_finite() {
            return Err(PoleError::InvalidParameter {
                name: "start",
                reason: "the start pose is not finite".into(),
            });
        }
        let initial = UniformDisc {
            radial: RadialSampling::UniformRadius,
            ..UniformDisc::new(start, params.init_radius_m, params.init_heading_rad)
        };
        let filter =
            ParticleFilter::from_initializer(&initial, params.particles, params.config(), seed)?;
        Ok(Self {
            model: PoleLikelihood::new(map, &params)?,
            params,
            filter,
            resamples: 0,
        })
    }

    /// The particles.
    pub fn particles(&self) -> &[Pose2] {
        self.filter.states()
    }

    /// The underlying particle filter (weights, effective sample size, …).
    pub fn filter(&self) -> &ParticleFilter<Pose2> {
        &self.filter
    }

    /// How often the filter resampled.
    pub fn resamples(&self) -> usize {
        self.resamples
    }

    /// Motion update with the odometry increment `increment` (body frame of the previous
    /// pose) and per-component standard deviations `std = [x m, y m, θ rad]` (finite,
    /// non-negative).
    pub fn predict(&mut self, increment: &Pose2, std: [f64; 3]) -> Result<()> {
        let control = PlanarIncrement::with_std(increment, std)?;
        self.filter
            .predict(&PlanarGaussianMotionModel::default(), &control);
        Ok(())
    }

    /// Measurement update with online poles in the robot frame (metres), then resampling
    /// when `n_eff / N` falls below [`FilterParams::resample_fraction`]. Without poles
    /// nothing changes.
    pub fn update(&mut self, poles_in_robot: &[Point2<f64>]) -> Result<()> {
        if poles_in_robot.is_empty() {
            return Ok(());
        }
        self.filter.update(&self.model, poles_in_robot)?;
        if self.filter.resample_if_needed().is_some() {
            self.resamples += 1;
        }
        Ok(())
    }

    /// The estimate: weighted mean of the best `best_fraction` of the particles (position
    /// mean, circular heading mean).
    pub fn estimate(&self) -> Pose2 {
        self.filter
            .estimate(Estimator::BestFraction(self.params.best_fraction))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pole(x: f64, y: f64) -> Pole {
        Pole {
            x,
            y,
            z_start: 0.0,
            z_end: 3.0,
            width: 0.2,
            score: 0.8,
        }
    }

    #[test]
    fn gate_matches_the_spec() {
        assert!((FilterParams::nclt().gate_m() - 3.233).abs() < 2e-3);
        assert!((FilterParams::kitti().gate_m() - 2.715).abs() < 2e-3);
    }

    #[test]
    fn likelihood_sums_gated_gaussians_plus_epsilon() {
        let params = FilterParams::kitti();
        let model = PoleLikelihood::new(&[pole(2.0, 0.0), pole(0.0, 10.0)], &params).unwrap();
        let pose = Pose2::new(1.0, 0.0, std::f64::consts::FRAC_PI_2);
        // (0, −0.5) in the robot frame is (1.5, 0) in the map: 0.5 m from the first pole;
        // (0, 20) is 19 m from the nearest one, beyond the gate.
        let observed = [Point2::new(0.0, -0.5), Point2::new(0.0, 20.0)];
        let phi = |d: f64| (-0.5 * d * d).exp() / (2.0 * std::f64::consts::PI).sqrt();
        let expected = (phi(0.5) + 0.1).ln() + (phi(params.gate_m()) + 0.1).ln();
        let got = model.log_likelihood(&pose, &observed);
        assert!((got - expected).abs() < 1e-12, "{got} vs {expected}");
        // The gate: the pdf there is p_min.
        assert!((phi(params.gate_m()) - params.p_min).abs() < 1e-12);
        assert_eq!(model.log_likelihood(&pose, &[]), 0.0);
        // An empty map: every pole at the gate.
        let empty = PoleLikelihood::new(&[], &params).unwrap();
        let at_gate = empty.log_likelihood(&pose, &observed[..1]);
        assert!((at_gate - (phi(params.gate_m()) + 0.1).ln()).abs() < 1e-12);
    }

    #[test]
    fn initial_particles_are_uniform_in_the_radius_around_the_start() {
        let params = FilterParams {
            particles: 20_000,
            ..FilterParams::kitti()
        };
        let start = Pose2::new(5.0, -2.0, 1.0);
        let filter = PoleFilter::new(&[pole(0.0, 0.0)], params.clone(), start, 3).unwrap();
        let n = filter.particles().len() as f64;
        let (mut radius, mut inner) = (0.0, 0.0);
        for p in filter.particles() {
            let r = (p.x() - 5.0).hypot(p.y() + 2.0);
            let dtheta = raypath_geometry::wrap_angle(p.theta() - 1.0);
            assert!(r <= params.init_radius_m + 1e-9);
            assert!(dtheta.abs() <= params.init_heading_rad + 1e-9);
            radius += r / n;
            inner += f64::from(u8::from(r < 0.5 * params.init_radius_m)) / n;
        }
        // Uniform in the radius: mean R/2 and half the particles inside R/2 (uniform in area
        // would give 2R/3 and a quarter).
        assert!((radius - 1.5).abs() < 0.03, "mean radius {radius}");
        assert!((inner - 0.5).abs() < 0.02, "inside R/2: {inner}");
    }

    #[test]
    fn an_update_without_poles_changes_nothing() {
        let map = [pole(3.0, 1.0), pole(-2.0, 4.0), pole(6.0, -3.0)];
        let mut filter =
            PoleFilter::new(&map, FilterParams::kitti(), Pose2::identity(), 11).unwrap();
        filter
            .predict(&Pose2::new(0.5, 0.0, 0.0), [0.05, 0.05, 0.01])
            .unwrap();
        filter.update(&[Point2::new(3.0, 1.0)]).unwrap();
        let (states, weights, operations) = (
            filter.particles().to_vec(),
            filter.filter().log_weights().to_vec(),
            filter.filter().operations(),
        );
        filter.update(&[]).unwrap();
        assert_eq!(filter.particles(), states.as_slice());
        assert_eq!(filter.filter().log_weights(), weights.as_slice());
        assert_eq!(filter.filter().operations(), operations);
    }

    #[test]
    fn resampling_at_half_the_particles_leaves_uniform_weights() {
        let map = [pole(3.0, 1.0), pole(-2.0, 4.0), pole(6.0, -3.0)];
        let mut filter =
            PoleFilter::new(&map, FilterParams::kitti(), Pose2::identity(), 5).unwrap();
        // Three poles seen from the true pose (the start): the 3 m spread collapses.
        let seen: Vec<Point2<f64>> = map.iter().map(|p| Point2::new(p.x, p.y)).collect();
        filter.update(&seen).unwrap();
        assert_eq!(filter.resamples(), 1);
        let n = filter.particles().len() as f64;
        assert!(
            filter
                .filter()
                .log_weights()
                .iter()
                .all(|&l| (l + n.ln()).abs() < 1e-12)
        );
        assert!(filter.estimate().translation().norm() < 1.0);
        // The filter never resamples at a ratio of 0.
        let never = FilterParams {
            resample_fraction: 0.0,
            ..FilterParams::kitti()
        };
        let mut filter = PoleFilter::new(&map, never, Pose2::identity(), 5).unwrap();
        filter.update(&seen).unwrap();
        assert_eq!(filter.resamples(), 0);
        assert!(filter.filter().ess_ratio() < 0.5);
    }
}
