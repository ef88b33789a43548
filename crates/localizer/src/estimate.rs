//! Point estimates of the particle set.
//!
//! * [`Estimator::WeightedMean`]: the weighted mean of all particles (circular mean for the
//!   heading, quaternion average for SE(3) rotations; see [`crate::FilterState`]).
//! * [`Estimator::BestFraction`]: the weighted mean of the best fraction of particles by
//!   weight — Schaefer (2020), ch. 12 uses the best 10 % (the default), which ignores distant
//!   modes that would drag a plain mean between them.
//! * [`Estimator::MaxWeight`]: the particle of largest weight (ties: lowest index).

use std::cmp::Ordering;

use serde::{Deserialize, Serialize};

use crate::state::FilterState;

/// How to turn the particle set into one pose (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Estimator {
    /// Weighted mean of all particles.
    WeightedMean,
    /// Weighted mean of the best fraction (0, 1] of particles by weight (at least one).
    BestFraction(f64),
    /// The particle of largest weight.
    MaxWeight,
}

impl Default for Estimator {
    /// The thesis's ch. 12 estimator: the best 10 %.
    fn default() -> Self {
        Estimator::BestFraction(0.1)
    }
}

/// Index of the largest log-weight (lowest index on ties); `None` for an empty slice.
fn arg_max(log_weights: &[f64]) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, &l) in log_weights.iter().enumerate() {
        if best.is_none_or(|(_, b)| l > b) {
            best = Some((i, l));
        }
    }
    best.map(|(i, _)| i)
}

/// The estimate of `states` with (not necessarily normalized) `log_weights`. `None` only
/// for an empty set. `order` is scratch space for [`Estimator::BestFraction`].
pub(crate) fn estimate<S: FilterState>(
    states: &[S],
    log_weights: &[f64],
    estimator: Estimator,
    order: &mut Vec<usize>,
) -> Option<S> {
    let best = arg_max(log_weights)?;
    let max_state = states.get(best).copied()?;
    let max_log = log_weights.get(best).copied()?;
    // Relative weights e^{l − max} ∈ [0, 1]: no overflow whatever the normalization.
    let rel = |l: f64| (l - max_log).exp();
    let mean = match estimator {
        Estimator::MaxWeight => return Some(max_state),
        Estimator::WeightedMean => {
            S::weighted_mean(states.iter().zip(log_weights).map(|(s, &l)| (s, rel(l))))
        }
        Estimator::BestFraction(fraction) => {
            let n = states.len().min(log_weights.len());
            let fraction = if fraction.is_finite() {
                fraction.clamp(0.0, 1.0)
            } else {
                1.0
            };
            let count = ((fraction * n as f64).ceil() as usize).clamp(1, n);
            order.clear();
            order.extend(0..n);
            // Descending weight, ties by index: deterministic selection.
            let by_weight = |a: &usize, b: &usize| {
                let la = log_weights.get(*a).copied().unwrap_or(f64::NEG_INFINITY);
                let lb = log_weights.get(*b).copied().unwrap_or(f64::NEG_INFINITY);
                lb.partial_cmp(&la)
                    .unwrap_or(Ordering::Equal)
                    .then(a.cmp(b))
            };
            if count < n {
                order.select_nth_unstable_by(count - 1, by_weight);
                order.truncate(count);
            }
            order.sort_unstable();
            S::weighted_mean(
                order
                    .iter()
                    .filter_map(|&i| Some((states.get(i)?, rel(log_weights.get(i).copied()?)))),
            )
        }
    };
    Some(mean.unwrap_or(max_state))
}

#[cfg(test)]
mod tests {
    use super::*;
    use raypath_geometry::Pose2;

    #[test]
    fn best_fraction_ignores_a_distant_light_mode() {
        // 90 light particles at x = 10, 10 heavy ones at x = 0.
        let mut states = vec![Pose2::new(10.0, 0.0, 0.0); 90];
        states.extend(vec![Pose2::new(0.0, 0.0, 0.0); 10]);
        let mut logw = vec![-3.0; 90];
        logw.extend(vec![0.0; 10]);
        let mut order = Vec::new();
        let best = estimate(&states, &logw, Estimator::BestFraction(0.1), &mut order).unwrap();
        assert!(best.x().abs() < 1e-12);
        let mean = estimate(&states, &logw, Estimator::WeightedMean, &mut order).unwrap();
        assert!((mean.x() - 900.0 * (-3f64).exp() / (90.0 * (-3f64).exp() + 10.0)).abs() < 1e-9);
        let max = estimate(&states, &logw, Estimator::MaxWeight, &mut order).unwrap();
        assert_eq!(max.x(), 0.0);
    }
}
