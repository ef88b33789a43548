//! The Beta-posterior occupancy of a voxel from its hit/miss counts (after Luft et al.;
//! Schaefer 2020, ch. 8 and §12.4.1).
//!
//! A voxel with `h` hits and `m` misses has the reflection-rate posterior
//! `Beta(h + α, m + β)`; its occupancy is the posterior mass above the threshold `μ_o`,
//! `o = 1 − I_{μ_o}(h + α, m + β)` with the regularized incomplete beta function `I`. The prior
//! `Beta(α, β)` ([`BetaPrior`] of `raypath-sensor-models`) is fitted by the method of moments
//! ([`MomentStatistics`]) to the maximum-likelihood reflection rates `h / (h + m)` of the
//! observed voxels.

use raypath_sensor_models::{BetaPrior, MomentStatistics};

/// The regularized incomplete beta function `I_x(a, b)` for `a, b > 0`, `x ∈ [0, 1]` (from
/// `statrs`; `x` outside `[0, 1]` is clamped, invalid shapes give NaN).
fn regularized_incomplete_beta(x: f64, a: f64, b: f64) -> f64 {
    statrs::function::beta::checked_beta_reg(a, b, x.clamp(0.0, 1.0)).unwrap_or(f64::NAN)
}

/// Smallest concentration `α + β` accepted from the moments (a guard the thesis does not
/// need: a (nearly) binary maximum-likelihood map makes the moment estimate degenerate, with
/// `α, β → 0` or negative; see [`BetaPrior::from_moments_clamped`]).
pub(crate) const MIN_CONCENTRATION: f64 = 1e-3;

/// The prior `Beta(α, β)` of the reflection rates, fitted by the method of moments to the
/// maximum-likelihood rates `h / (h + m)` of the voxels with `h + m > 0` (Schaefer 2020,
/// §12.4.1; degenerate moments clamped, [`MIN_CONCENTRATION`]).
pub(crate) fn reflection_prior(hits: &[u16], misses: &[u16]) -> BetaPrior {
    let rates = hits.iter().zip(misses).filter_map(|(&h, &m)| {
        let total = h as u32 + m as u32;
        (total > 0).then(|| h as f64 / total as f64)
    });
    let moments = MomentStatistics::of(rates).unwrap_or(MomentStatistics {
        cells: 0,
        mean: f64::NAN,
        variance: f64::NAN,
    });
    BetaPrior::from_moments_clamped(&moments, MIN_CONCENTRATION)
}

/// The occupancy `1 − I_{μ_o}(h + α, m + β)` of a voxel with `hits` and `misses` under
/// `prior`: the posterior probability that its reflection rate exceeds `threshold`.
pub(crate) fn occupancy_of(prior: &BetaPrior, hits: u32, misses: u32, threshold: f64) -> f64 {
    1.0 - regularized_incomplete_beta(
        threshold,
        hits as f64 + prior.alpha,
        misses as f64 + prior.beta,
    )
}

/// Occupancies of small counts, computed once per map (most voxels share a few `(h, m)`).
pub(crate) struct OccupancyTable {
    prior: BetaPrior,
    threshold: f64,
    table: Vec<f32>,
}

/// Counts below these are tabulated.
const TABLE_HITS: usize = 16;
const TABLE_MISSES: usize = 512;

impl OccupancyTable {
    pub(crate) fn new(prior: BetaPrior, threshold: f64) -> Self {
        Self {
            prior,
            threshold,
            table: vec![f32::NAN; TABLE_HITS * TABLE_MISSES],
        }
    }

    /// The occupancy of `(hits, misses)`.
    #[inline]
    pub(crate) fn get(&mut self, hits: u32, misses: u32) -> f32 {
        let (h, m) = (hits as usize, misses as usize);
        if h < TABLE_HITS && m < TABLE_MISSES {
            let slot = h * TABLE_MISSES + m;
            if let Some(v) = self.table.get(slot).copied() {
                if !v.is_nan() {
                    return v;
                }
                let v = occupancy_of(&self.prior, hits, misses, self.threshold) as f32;
                if let Some(s) = self.table.get_mut(slot) {
                    *s = v;
                }
                return v;
            }
        }
        occupancy_of(&self.prior, hits, misses, self.threshold) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn incomplete_beta_known_values() {
        // I_x(1, 1) = x; I_x(a, 1) = x^a; I_x(1, b) = 1 − (1 − x)^b.
        for &x in &[0.05, 0.2, 0.5, 0.9] {
            assert!((regularized_incomplete_beta(x, 1.0, 1.0) - x).abs() < 1e-12);
            assert!((regularized_incomplete_beta(x, 3.0, 1.0) - x.powi(3)).abs() < 1e-12);
            let expected = 1.0 - (1.0 - x).powi(7);
            assert!((regularized_incomplete_beta(x, 1.0, 7.0) - expected).abs() < 1e-12);
        }
        // Symmetry I_x(a, b) = 1 − I_{1−x}(b, a) with large counts.
        let v = regularized_incomplete_beta(0.2, 40.5, 300.25);
        let w = regularized_incomplete_beta(0.8, 300.25, 40.5);
        assert!((v + w - 1.0).abs() < 1e-10);
    }

    #[test]
    fn method_of_moments_recovers_the_prior() {
        // Beta(2, 6): mean 0.25, variance ab/((a+b)²(a+b+1)) = 12/(64·9).
        let moments = MomentStatistics {
            cells: 8,
            mean: 0.25,
            variance: 12.0 / 576.0,
        };
        let prior = BetaPrior::from_moments_clamped(&moments, MIN_CONCENTRATION);
        assert!((prior.alpha - 2.0).abs() < 1e-9 && (prior.beta - 6.0).abs() < 1e-9);
        // Degenerate (binary) data stays valid.
        let binary = reflection_prior(&[1, 0, 1, 0], &[0, 3, 0, 2]);
        assert!(binary.alpha > 0.0 && binary.beta > 0.0);
        assert!((binary.alpha + binary.beta - MIN_CONCENTRATION).abs() < 1e-15);
        // Counts: rates 1/4, 3/4, 1/2 (the unobserved voxel left out): mean 1/2, variance
        // 1/24, so α + β = (1/4)/(1/24) − 1 = 5.
        let prior = reflection_prior(&[1, 3, 2, 0], &[3, 1, 2, 0]);
        assert!((prior.alpha - 2.5).abs() < 1e-9 && (prior.beta - 2.5).abs() < 1e-9);
    }

    #[test]
    fn occupancy_grows_with_hits() {
        let prior = BetaPrior::from_moments_clamped(
            &MomentStatistics {
                cells: 10,
                mean: 0.1,
                variance: 0.02,
            },
            MIN_CONCENTRATION,
        );
        let free = occupancy_of(&prior, 0, 10, 0.2);
        let hit = occupancy_of(&prior, 5, 1, 0.2);
        assert!(free < 0.05 && hit > 0.95, "free {free}, hit {hit}");
    }
}
