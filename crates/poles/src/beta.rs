//! The Beta-posterior occupancy of a voxel from its hit/miss counts (after Luft et al.;
//! Schaefer 2020, ch. 8 and §12.4.1).
//!
//! A voxel with `h` hits and `m` misses has the reflection-rate posterior
//! `Beta(h + α, m + β)`; its occupancy is the posterior mass above the threshold `μ_o`,
//! `o = 1 − I_{μ_o}(h + α, m + β)` with the regularized incomplete beta function `I`. The prior
//! `Beta(α, β)` is fitted by the method of moments to the maximum-likelihood reflection rates
//! `h / (h + m)` of the observed voxels.

/// The regularized incomplete beta function `I_x(a, b)` for `a, b > 0`, `x ∈ [0, 1]` (from
/// `statrs`; `x` outside `[0, 1]` is clamped, invalid shapes give NaN).
fn regularized_incomplete_beta(x: f64, a: f64, b: f64) -> f64 {
    statrs::function::beta::checked_beta_reg(a, b, x.clamp(0.0, 1.0)).unwrap_or(f64::NAN)
}

/// The prior `Beta(α, β)` of the reflection rates, fitted by the method of moments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectionPrior {
    /// α > 0.
    pub alpha: f64,
    /// β > 0.
    pub beta: f64,
}

impl ReflectionPrior {
    /// Smallest concentration `α + β` accepted from the moments (a guard the thesis does not
    /// need: a (nearly) binary maximum-likelihood map makes the moment estimate degenerate,
    /// with `α, β → 0` or negative).
    pub const MIN_CONCENTRATION: f64 = 1e-3;

    /// Fits the prior to the mean `γ` and variance `δ` of the maximum-likelihood reflection
    /// rates: `α = γc`, `β = (1 − γ)c` with `c = γ(1 − γ)/δ − 1` (Schaefer 2020, §12.4.1,
    /// the method of moments). Degenerate moments (no data, `δ = 0`, `c` below
    /// [`Self::MIN_CONCENTRATION`]) are clamped; the mean is clamped to `[1e-6, 1 − 1e-6]`.
    pub fn from_moments(mean: f64, variance: f64) -> Self {
        let gamma = if mean.is_finite() {
            mean.clamp(1e-6, 1.0 - 1e-6)
        } else {
            0.5
        };
        let c = gamma * (1.0 - gamma) / variance - 1.0; // Eq. (12.x): α = −γ(γ² − γ + δ)/δ
        let c = if c.is_finite() {
            c.max(Self::MIN_CONCENTRATION)
        } else {
            Self::MIN_CONCENTRATION
        };
        Self {
            alpha: gamma * c,
            beta: (1.0 - gamma) * c,
        }
    }

    /// Fits the prior to hit/miss counts (voxels with `h + m > 0` only).
    pub fn estimate(hits: &[u16], misses: &[u16]) -> Self {
        let (mut n, mut sum, mut sum_sq) = (0u64, 0.0f64, 0.0f64);
        for (&h, &m) in hits.iter().zip(misses) {
            let total = h as u64 + m as u64;
            if total > 0 {
                let r = h as f64 / total as f64;
                n += 1;
                sum += r;
                sum_sq += r * r;
            }
        }
        if n == 0 {
            return Self::from_moments(f64::NAN, f64::NAN);
        }
        let mean = sum / n as f64;
        let variance = (sum_sq / n as f64 - mean * mean).max(0.0);
        Self::from_moments(mean, variance)
    }

    /// The occupancy `1 − I_{μ_o}(h + α, m + β)` of a voxel with `hits` and `misses`.
    pub fn occupancy(&self, hits: u32, misses: u32, threshold: f64) -> f64 {
        1.0 - regularized_incomplete_beta(
            threshold,
            hits as f64 + self.alpha,
            misses as f64 + self.beta,
        )
    }
}

/// Occupancies of small counts, computed once per map (most voxels share a few `(h, m)`).
pub(crate) struct OccupancyTable {
    prior: ReflectionPrior,
    threshold: f64,
    table: Vec<f32>,
}

/// Counts below these are tabulated.
const TABLE_HITS: usize = 16;
const TABLE_MISSES: usize = 512;

impl OccupancyTable {
    pub(crate) fn new(prior: ReflectionPrior, threshold: f64) -> Self {
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
                let v = self.prior.occupancy(hits, misses, self.threshold) as f32;
                if let Some(s) = self.table.get_mut(slot) {
                    *s = v;
                }
                return v;
            }
        }
        self.prior.occupancy(hits, misses, self.threshold) as f32
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
        let prior = ReflectionPrior::from_moments(0.25, 12.0 / 576.0);
        assert!((prior.alpha - 2.0).abs() < 1e-9 && (prior.beta - 6.0).abs() < 1e-9);
        // Degenerate (binary) data stays valid.
        let binary = ReflectionPrior::estimate(&[1, 0, 1, 0], &[0, 3, 0, 2]);
        assert!(binary.alpha > 0.0 && binary.beta > 0.0);
    }

    #[test]
    fn occupancy_grows_with_hits() {
        let prior = ReflectionPrior::from_moments(0.1, 0.02);
        let free = prior.occupancy(0, 10, 0.2);
        let hit = prior.occupancy(5, 1, 0.2);
        assert!(free < 0.05 && hit > 0.95, "free {free}, hit {hit}");
    }
}
