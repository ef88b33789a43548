//! KLD-sampling: adapting the number of particles (Fox, "Adapting the sample size in particle
//! filters through KLD-sampling", IJRR 22(12), 2003; Thrun et al. 2005, §8.3.7).
//!
//! The particles are histogrammed into bins of size [`KldBins`]. When the drawn particles
//! occupy `k` bins, the number of samples needed so that, with probability `1 − δ`, the
//! Kullback–Leibler divergence between the sample-based maximum-likelihood estimate and the
//! true posterior stays below `ε` is (Fox 2003, Eq. 13, with the Wilson–Hilferty
//! approximation of the χ² quantile):
//!
//! ```text
//!            k − 1  ⎧     2           ⎛   2    ⎞½       ⎫³
//!   n(k) =  ─────── ⎨ 1 − ──────── +  ⎜────────⎟  z₁₋δ  ⎬
//!             2ε    ⎩     9(k − 1)    ⎝9(k − 1)⎠        ⎭
//! ```
//!
//! with z₁₋δ the upper `1 − δ` quantile of the standard normal distribution. Resampling draws
//! particles one at a time (independently, proportional to weight, as in Fox's algorithm and
//! AMCL: the total is unknown in advance, so systematic resampling cannot be used) and stops
//! at the first `n` with `n ≥ n(k)` and `n ≥ min_particles`, or at `max_particles`. For
//! `k ≤ 1` the bound is 0 (Fox), so a cloud inside a single bin shrinks to `min_particles`
//! (AMCL instead returns `max_particles` there).
//!
//! Defaults are AMCL's (`kld_err` ε = 0.01, `kld_z` = 0.99 ⇒ δ = 0.01, bins 0.5 m × 0.5 m ×
//! 10°, 100 – 5000 particles); the vertical bin size for SE(3) (0.5 m) is ours.

use std::collections::HashSet;

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::error::{LocalizerError, require_open_interval, require_positive};
use crate::state::FilterState;

/// Bin sizes of the KLD-sampling histogram. SE(2) bins x, y and θ; SE(3) bins x, y, z and
/// roll, pitch, yaw.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KldBins {
    /// Horizontal bin size (x and y) in metres. Default 0.5 m (AMCL).
    pub xy_m: f64,
    /// Vertical bin size (z, SE(3) only) in metres. Default 0.5 m.
    pub z_m: f64,
    /// Angular bin size in radians. Default 10° (AMCL).
    pub angle_rad: f64,
}

impl Default for KldBins {
    fn default() -> Self {
        Self {
            xy_m: 0.5,
            z_m: 0.5,
            angle_rad: 10f64.to_radians(),
        }
    }
}

/// Parameters of KLD-sampling.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KldConfig {
    /// Bound ε on the KL divergence. Default 0.01 (AMCL `kld_err`).
    pub epsilon: f64,
    /// Probability δ that the bound is exceeded. Default 0.01 (AMCL `kld_z` = 1 − δ = 0.99).
    pub delta: f64,
    /// Histogram bin sizes.
    pub bins: KldBins,
    /// Fewest particles after resampling. Default 100 (AMCL `min_particles`).
    pub min_particles: usize,
    /// Most particles after resampling. Default 5000 (AMCL `max_particles`).
    pub max_particles: usize,
}

impl Default for KldConfig {
    fn default() -> Self {
        Self {
            epsilon: 0.01,
            delta: 0.01,
            bins: KldBins::default(),
            min_particles: 100,
            max_particles: 5000,
        }
    }
}

impl KldConfig {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), LocalizerError> {
        require_open_interval("kld.epsilon", self.epsilon, 0.0, f64::INFINITY)?;
        require_open_interval("kld.delta", self.delta, 0.0, 1.0)?;
        require_positive("kld.bins.xy_m", self.bins.xy_m)?;
        require_positive("kld.bins.z_m", self.bins.z_m)?;
        require_positive("kld.bins.angle_rad", self.bins.angle_rad)?;
        if self.min_particles == 0 || self.min_particles > self.max_particles {
            return Err(LocalizerError::InvalidParameter {
                name: "kld.min_particles",
                reason: format!(
                    "need 1 <= min_particles <= max_particles, got {} and {}",
                    self.min_particles, self.max_particles
                ),
            });
        }
        Ok(())
    }

    /// The sample-size bound n(k) for `k` occupied bins (module docs), not yet clamped to
    /// `[min_particles, max_particles]`.
    pub fn bound(&self, k: usize) -> f64 {
        kld_bound(k, self.epsilon, normal_quantile(1.0 - self.delta))
    }
}

/// Fox's bound n(k) (module docs) for `k` occupied bins, error bound `epsilon` and normal
/// quantile `z` = z₁₋δ. Returns 0 for `k ≤ 1`.
pub fn kld_bound(k: usize, epsilon: f64, z: f64) -> f64 {
    if k <= 1 {
        return 0.0;
    }
    let km1 = (k - 1) as f64;
    let a = 2.0 / (9.0 * km1);
    let cube = 1.0 - a + a.sqrt() * z;
    km1 / (2.0 * epsilon) * cube * cube * cube
}

/// The quantile function Φ⁻¹(p) of the standard normal distribution, by Acklam's rational
/// approximation (relative error below 1.2·10⁻⁹). Returns ±∞ at 0 and 1 and NaN outside.
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    const P_LOW: f64 = 0.02425;
    if p.is_nan() || !(0.0..=1.0).contains(&p) {
        return f64::NAN;
    }
    if p == 0.0 {
        return f64::NEG_INFINITY;
    }
    if p == 1.0 {
        return f64::INFINITY;
    }
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < P_LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - P_LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// What one KLD resampling did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KldReport {
    /// Number of particles drawn.
    pub particles: usize,
    /// Number of occupied histogram bins among them.
    pub bins: usize,
    /// The bound n(k) for that number of bins (unclamped).
    pub bound: f64,
}

/// Reusable buffers of KLD resampling.
#[derive(Clone, Debug, Default)]
pub(crate) struct KldScratch {
    cumulative: Vec<f64>,
    occupied: HashSet<[i64; 6]>,
}

/// Draws particles independently in proportion to `weights` (normalized or not) until the
/// KLD bound is met (module docs); writes them to `out` (cleared first).
pub(crate) fn kld_resample<S: FilterState, R: Rng + ?Sized>(
    states: &[S],
    weights: &[f64],
    config: &KldConfig,
    rng: &mut R,
    out: &mut Vec<S>,
    scratch: &mut KldScratch,
) -> KldReport {
    let z = normal_quantile(1.0 - config.delta);
    scratch.cumulative.clear();
    let mut total = 0.0;
    for &w in weights {
        total += w;
        scratch.cumulative.push(total);
    }
    scratch.occupied.clear();
    out.clear();
    let last = states.len().saturating_sub(1);
    let mut bound = 0.0;
    while out.len() < config.max_particles {
        let u = rng.random::<f64>() * total;
        // First index whose cumulative weight exceeds u.
        let index = scratch.cumulative.partition_point(|&c| c <= u).min(last);
        let Some(state) = states.get(index) else {
            break;
        };
        out.push(*state);
        scratch.occupied.insert(state.kld_bin(&config.bins));
        bound = kld_bound(scratch.occupied.len(), config.epsilon, z);
        let n = out.len();
        if n >= config.min_particles && n as f64 >= bound {
            break;
        }
    }
    KldReport {
        particles: out.len(),
        bins: scratch.occupied.len(),
        bound,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_match_tables() {
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959_963_984_540_054),
            (0.99, 2.326_347_874_040_841),
            (0.999, 3.090_232_306_167_813),
            (0.01, -2.326_347_874_040_841),
            (1e-6, -4.753_424_308_822_899),
        ] {
            let got = normal_quantile(p);
            assert!(
                (got - z).abs() < 1e-8 * z.abs().max(1.0),
                "p {p}: {got} vs {z}"
            );
        }
        assert!(normal_quantile(-0.1).is_nan() && normal_quantile(f64::NAN).is_nan());
        assert_eq!(normal_quantile(1.0), f64::INFINITY);
    }

    #[test]
    fn default_config_is_valid() {
        assert!(KldConfig::default().validate().is_ok());
        let bad = KldConfig {
            min_particles: 10,
            max_particles: 5,
            ..KldConfig::default()
        };
        assert!(bad.validate().is_err());
    }
}
