//! The continuous occupancy baselines of thesis Sec. 9.5.2 (Table 9.3, Table 9.4): Gaussian
//! process occupancy maps ([`gpom`]) and Hilbert maps ([`hilbert`]), each with as many
//! real-valued parameters as the DCT map and the grid map they are compared with, and the
//! rasterized ray likelihood ([`raster`]) that scores them on the same rays.
//!
//! ## The idea
//!
//! Both baselines are **classifiers of points**, not ray models: from the rays they take
//! sample points — the end point of every return as *occupied* (`y = +1`) and points drawn
//! along the beam as *free* (`y = −1`) — and learn a continuous occupancy probability
//! `o(x, y)` ([`TrainingSet`], [`TrainingConfig`]).
//!
//! * **GPOM** (O'Callaghan & Ramos 2012; the Matérn-kernel variant of Jadidi et al. 2018, which
//!   the thesis ran): GP regression on the `±1` targets with a Matérn `ν = 3/2` kernel, the
//!   latent mean and variance squashed into a probability by probabilistic least-squares
//!   classification (a probit of the LOO-calibrated latent). Its parameter vector is the
//!   weight vector `(K + σ_n² I)⁻¹ y`, one real per training point, so equal memory means
//!   **as many training points as parameters**, drawn at random from the sampled points
//!   (the thesis "randomly downsample the design matrix and the target vector").
//! * **Hilbert maps** (Ramos & Ott 2016) with **Nyström features** of an RBF kernel:
//!   logistic regression on `M` features, `M` = the number of parameters.
//!
//! ## Scoring rays
//!
//! Neither map has a forward model for a ray; the thesis rasterizes them with 0.05 m pixels,
//! ray-traces and "cumulate the occupancy probabilities along the rays". [`raster`] reads
//! that as the reflection model (Eq. 7.23) with the occupancy as reflection probability,
//! turned into a density per metre like Eq. (7.25).
//!
//! ## Randomness
//!
//! Every random draw (free points along beams, the GPOM subsample, the Nyström landmarks)
//! comes from ChaCha8 seeded by the caller: the same seed gives the same map.

pub mod gpom;
pub mod hilbert;
pub mod raster;

use rand::Rng;
use rand::seq::index;
use rand_chacha::ChaCha8Rng;

use crate::{DctError, MapRay, Outcome};

pub use gpom::{Gpom, GpomConfig, GpomReport};
pub use hilbert::{HilbertConfig, HilbertMap, HilbertReport, NystromFeatures};
pub use raster::{OCCUPANCY_CLAMP, OccupancyField, OccupancyRaster, RateAsOccupancy};

/// How training points are drawn along rays (the rule of Ramos & Ott's published Hilbert-map
/// code, used for both baselines).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainingConfig {
    /// One free point per this many metres of beam, at least one per ray. Default `2.0` m.
    pub free_spacing_m: f64,
    /// Free points of a return are drawn on `[0, r − margin]`, keeping them off the surface.
    /// Default `0.1` m.
    pub free_margin_m: f64,
}

impl Default for TrainingConfig {
    fn default() -> Self {
        Self {
            free_spacing_m: 2.0,
            free_margin_m: 0.1,
        }
    }
}

/// Labelled points in the map frame: `+1` occupied, `−1` free.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrainingSet {
    /// Points (m, map frame).
    pub points: Vec<[f64; 2]>,
    /// Labels, `+1.0` (occupied) or `−1.0` (free), one per point.
    pub labels: Vec<f64>,
}

impl TrainingSet {
    /// Samples a training set from `rays` (`sub` rays carry no position and are skipped):
    /// the end point of every [`Outcome::Hit`] is occupied; each ray gives
    /// `max(1, ⌊length / free_spacing⌋)` free points uniform on `[0, length − margin]` for a
    /// return, on `[0, length]` for a ray that crosses the map without one.
    pub fn sample(
        rays: &[MapRay],
        config: &TrainingConfig,
        rng: &mut ChaCha8Rng,
    ) -> Result<Self, DctError> {
        crate::error::positive("free_spacing_m", config.free_spacing_m)?;
        if !(config.free_margin_m.is_finite() && config.free_margin_m >= 0.0) {
            return Err(DctError::InvalidParameter {
                name: "free_margin_m",
                reason: format!("must be finite and ≥ 0, got {}", config.free_margin_m),
            });
        }
        let mut set = Self::default();
        for ray in rays.iter().filter(|r| r.is_valid()) {
            let free_end = match ray.outcome {
                Outcome::Hit => {
                    set.push(ray.end(), 1.0);
                    (ray.length_m - config.free_margin_m).max(0.0)
                }
                Outcome::Super => ray.length_m,
                Outcome::Sub => continue,
            };
            let count = ((ray.length_m / config.free_spacing_m).floor() as usize).max(1);
            for _ in 0..count {
                let t = rng.random::<f64>() * free_end;
                set.push(ray.at(t), -1.0);
            }
        }
        if set.is_empty() {
            return Err(DctError::NoData("no training point from the rays".into()));
        }
        Ok(set)
    }

    fn push(&mut self, p: [f64; 2], label: f64) {
        self.points.push(p);
        self.labels.push(label);
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Number of occupied points.
    pub fn occupied(&self) -> usize {
        self.labels.iter().filter(|y| **y > 0.0).count()
    }

    /// `n` points drawn without replacement (all of them, in order, when `n ≥ len`).
    pub fn subsample(&self, n: usize, rng: &mut ChaCha8Rng) -> Self {
        if n >= self.len() {
            return self.clone();
        }
        let mut picked = index::sample(rng, self.len(), n).into_vec();
        picked.sort_unstable();
        Self {
            points: picked.iter().map(|&i| self.points[i]).collect(),
            labels: picked.iter().map(|&i| self.labels[i]).collect(),
        }
    }
}

/// Squared distance between two points.
#[inline]
pub(crate) fn distance_sq(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

/// Matérn `ν = 3/2` kernel, `σ_f² (1 + √3 r/ℓ) e^{−√3 r/ℓ}` (Rasmussen & Williams 2006,
/// Eq. 4.17).
#[inline]
pub fn matern32(r_m: f64, length_scale_m: f64, signal_var: f64) -> f64 {
    let s = 3f64.sqrt() * r_m / length_scale_m;
    signal_var * (1.0 + s) * (-s).exp()
}

/// RBF kernel `exp(−γ r²)` in the parametrisation of Ramos & Ott's code (`γ` in 1/m²).
#[inline]
pub fn rbf(r_sq_m2: f64, gamma_per_m2: f64) -> f64 {
    (-gamma_per_m2 * r_sq_m2).exp()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // test code: a panic is the failure report
mod tests {
    use rand::SeedableRng;

    use super::*;

    #[test]
    fn training_points_lie_on_the_rays_with_the_right_labels() {
        let rays = [
            MapRay::from_angle([0.0, 1.0], 0.0, 5.0, Outcome::Hit),
            MapRay::from_angle([0.0, 2.0], 0.0, 9.0, Outcome::Super),
        ];
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let set = TrainingSet::sample(&rays, &TrainingConfig::default(), &mut rng).unwrap();
        // 1 hit + ⌊5/2⌋ = 2 free, then ⌊9/2⌋ = 4 free.
        assert_eq!(set.len(), 7);
        assert_eq!(set.occupied(), 1);
        assert_eq!(set.points[0], [5.0, 1.0]);
        for (p, y) in set.points.iter().zip(&set.labels).skip(1) {
            assert_eq!(*y, -1.0);
            if p[1] == 1.0 {
                assert!(p[0] >= 0.0 && p[0] <= 4.9, "{p:?}");
            } else {
                assert!(p[0] >= 0.0 && p[0] <= 9.0, "{p:?}");
            }
        }
        let sub = set.subsample(3, &mut rng);
        assert_eq!(sub.len(), 3);
        assert!(sub.points.iter().all(|p| set.points.contains(p)));
        assert_eq!(set.subsample(100, &mut rng), set);
    }

    #[test]
    fn kernels_at_zero_and_decaying() {
        assert_eq!(matern32(0.0, 0.5, 2.0), 2.0);
        assert!(matern32(1.0, 0.5, 1.0) < matern32(0.5, 0.5, 1.0));
        assert_eq!(rbf(0.0, 1.0), 1.0);
        assert!((rbf(2.0, 0.5) - (-1.0f64).exp()).abs() < 1e-15);
    }
}
