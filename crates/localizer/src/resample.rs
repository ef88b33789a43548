//! Low-variance (systematic) resampling (Thrun et al. 2005, Table 4.4).
//!
//! One uniform offset u₀ ∈ [0, 1/N) and N equally spaced pointers uₘ = u₀ + m/N walk
//! through the cumulative weights; particle i is copied once for every pointer that falls
//! into its interval [cᵢ₋₁, cᵢ). Each particle therefore gets either ⌊N·wᵢ⌋ or ⌈N·wᵢ⌉
//! copies (within ±1 of its expectation N·wᵢ), the sample keeps the particle order, costs
//! O(N) and uses a single random number — lower variance than independent (multinomial)
//! draws.

/// Fills `indices` (cleared first) with `n_out` particle indices chosen by systematic
/// resampling of `weights` with offset `u0_unit ∈ [0, 1)` (scaled internally to
/// `[0, 1/n_out)`). Weights need not be normalized; they must be non-negative with a positive
/// finite sum, else `indices` stays empty. Indices come out non-decreasing.
pub fn systematic_resample(weights: &[f64], n_out: usize, u0_unit: f64, indices: &mut Vec<usize>) {
    indices.clear();
    let total: f64 = weights.iter().sum();
    if weights.is_empty() || n_out == 0 || !(total.is_finite() && total > 0.0) {
        return;
    }
    indices.reserve(n_out);
    let step = total / n_out as f64;
    let u0 = u0_unit.clamp(0.0, 1.0 - f64::EPSILON);
    let mut index = 0;
    // Rounding in the cumulative sum can leave the last pointers just past the total: they
    // belong to the last particle of positive weight, never to a trailing zero-weight one.
    let last = weights.iter().rposition(|&w| w > 0.0).unwrap_or(0);
    let mut cumulative = weights.first().copied().unwrap_or(0.0);
    for m in 0..n_out {
        let pointer = (u0 + m as f64) * step;
        while pointer >= cumulative && index < last {
            index += 1;
            cumulative += weights.get(index).copied().unwrap_or(0.0);
        }
        indices.push(index);
    }
}

/// The number of copies of each particle in `indices` (as produced by
/// [`systematic_resample`]) for `n_particles` particles.
pub fn copy_counts(indices: &[usize], n_particles: usize) -> Vec<usize> {
    let mut counts = vec![0; n_particles];
    for &i in indices {
        if let Some(c) = counts.get_mut(i) {
            *c += 1;
        }
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_weights_copy_every_particle_once() {
        let mut idx = Vec::new();
        systematic_resample(&[0.25; 4], 4, 0.999, &mut idx);
        assert_eq!(idx, vec![0, 1, 2, 3]);
    }

    #[test]
    fn zero_weight_particles_are_never_copied() {
        let mut idx = Vec::new();
        systematic_resample(&[0.0, 1.0, 0.0], 5, 0.0, &mut idx);
        assert_eq!(idx, vec![1; 5]);
        systematic_resample(&[0.0, 0.0], 5, 0.0, &mut idx);
        assert!(idx.is_empty());
    }
}
