//! The ray model shared by the reflection model, its posterior and log-odds occupancy:
//! every cell reflects a ray that enters it with probability `μ_i` (Eq. 7.23, 8.3).

use crate::dimension::{Crossing, Dimension};
use crate::models::{finite_or_neg_inf, ln_one_minus_exp_neg};
use crate::{Reading, SensorRange};

/// Smallest chord used in the density conversion (Eq. 7.32), as a fraction of the cell
/// edge: a ray that only grazes a cell's corner would otherwise divide by zero.
pub(crate) const MIN_CHORD_FRACTION: f64 = 1e-6;

/// A grid of per-cell reflection probabilities `μ_i` with the ray likelihood of the
/// reflection model (Hähnel et al. 2003; Schaefer 2020, Eq. 7.23 and 7.32):
///
/// ```text
/// P(x(r) ∈ v_k) = μ_k Π_{i ∈ B(k)} (1 − μ_i)                       (Eq. 7.23)
/// ln p(r)       = ln μ_k + Σ_{i ∈ B(k)} ln(1 − μ_i) − ln |chord_k|  (Eq. 7.32)
/// ln P(sup)     = Σ_{i ∈ I(r_max)} ln(1 − μ_i)
/// ln P(sub)     = ln(1 − Π_{i ∈ B(r_min)} (1 − μ_i))
/// ```
///
/// `B(k)`: the cells the ray crosses (with positive length) before the endpoint cell `v_k`;
/// `chord_k`: the part of the ray's line inside `v_k` that the sensor can measure, i.e. the chord
/// clipped to `[r_min, r_max]` (the thesis prints the integral of Eq. 7.30–7.32 over `v_i`; it runs
/// over `v_k`). Clipping makes the probabilities sum to exactly one: the cell that straddles
/// `r_max` gets its full mass as density, and the cell that straddles `r_min` counts to the
/// in-range part, so `B(r_min)` holds the cells the ray has left before `r_min`. Outside the grid
/// the ray crosses virtual cells of edge `c` with the outside probability `μ₀`: it loses
/// `ln(1 − μ₀)` per `c` metres, and an endpoint there has density `μ₀ / c`.
///
/// [`crate::ReflectionModel`] and [`crate::LogOddsModel`] build this field from counts.
#[derive(Clone, Debug)]
pub struct BernoulliField<D: Dimension> {
    grid: D::Grid,
    /// Per cell `[ln μ_i, ln(1 − μ_i)]`.
    log_probs: Vec<[f64; 2]>,
    outside_probability: f64,
    outside: [f64; 2],
    range: SensorRange,
}

/// What one trace along a ray collects.
struct Trace {
    /// Σ ln(1 − μ_i) over crossings before the last (positive length only).
    before_last: f64,
    /// ln(1 − μ) of the last crossing (0 for zero length), and its cell.
    last: Option<(usize, f64)>,
    /// Path length outside the grid.
    outside_m: f64,
}

impl<D: Dimension> BernoulliField<D> {
    /// A field from per-cell probabilities (one per cell of `grid`, each in `(0, 1)`), the
    /// probability `outside_probability` of space outside the grid, and the range limits.
    pub(crate) fn from_probabilities(
        grid: D::Grid,
        probabilities: impl Iterator<Item = f64>,
        outside_probability: f64,
        range: SensorRange,
    ) -> Self {
        Self {
            grid,
            log_probs: probabilities.map(log_pair).collect(),
            outside_probability,
            outside: log_pair(outside_probability),
            range,
        }
    }

    /// A field whose cell `i` has `μ_i = a_i / (a_i + b_i)` for the pairs `(a_i, b_i)` of
    /// `weights` (each `a_i, b_i > 0`, e.g. posterior pseudo-hits and pseudo-misses).
    /// Both logarithms are taken of the weights, not of `μ_i`, so a cell with
    /// `b_i ≪ a_i` keeps a finite `ln(1 − μ_i)` where `1 − μ_i` rounds to zero.
    pub(crate) fn from_weights(
        grid: D::Grid,
        weights: impl Iterator<Item = (f64, f64)>,
        outside_probability: f64,
        range: SensorRange,
    ) -> Self {
        Self {
            grid,
            log_probs: weights
                .map(|(a, b)| {
                    let ln_total = (a + b).ln();
                    [a.ln() - ln_total, b.ln() - ln_total]
                })
                .collect(),
            outside_probability,
            outside: log_pair(outside_probability),
            range,
        }
    }

    /// The grid.
    pub fn grid(&self) -> &D::Grid {
        &self.grid
    }

    /// `μ_i` of the cell with linear index `index` (the outside value beyond the grid).
    pub fn probability(&self, index: usize) -> f64 {
        self.log_probs
            .get(index)
            .map_or(self.outside_probability, |[ln_mu, _]| ln_mu.exp())
    }

    /// All cells' `μ_i`.
    pub fn probabilities(&self) -> Vec<f64> {
        self.log_probs
            .iter()
            .map(|[ln_mu, _]| ln_mu.exp())
            .collect()
    }

    /// `μ₀`, the reflection probability of unobserved space outside the grid.
    pub fn outside_probability(&self) -> f64 {
        self.outside_probability
    }

    /// Per cell `[ln μ_i, ln(1 − μ_i)]`.
    pub(crate) fn log_probs(&self) -> &[[f64; 2]] {
        &self.log_probs
    }

    /// The range limits.
    pub fn sensor_range(&self) -> SensorRange {
        self.range
    }

    #[inline]
    fn trace(&self, ray: &D::Ray, length_m: f64) -> Trace {
        let mut traversal = D::traverse(&self.grid, ray, length_m);
        let Some(first) = traversal.next() else {
            return Trace {
                before_last: 0.0,
                last: None,
                outside_m: length_m.max(0.0),
            };
        };
        let mut inside = 0.0;
        let mut before_last = 0.0;
        let log_miss = |c: &D::Crossing| {
            if c.length() > 0.0 {
                self.log_probs.get(c.index()).map_or(0.0, |p| p[1])
            } else {
                0.0
            }
        };
        let last = traversal.fold(first, |previous, crossing| {
            inside += previous.length();
            before_last += log_miss(&previous);
            crossing
        });
        inside += last.length();
        Trace {
            before_last,
            last: Some((last.index(), log_miss(&last))),
            outside_m: (length_m - inside).max(0.0),
        }
    }

    /// `ln(1 − μ₀)` per metre outside the grid.
    #[inline]
    fn outside_log_miss_per_m(&self) -> f64 {
        self.outside[1] / D::cell_size(&self.grid)
    }

    /// The ray log-likelihood (see the type docs).
    pub fn ray_log_likelihood(&self, ray: &D::Ray) -> f64 {
        let range = self.range;
        let outside_rate = self.outside_log_miss_per_m();
        let value = match range.classify(D::range(ray)) {
            Reading::Hit(r) => {
                let trace = self.trace(ray, r);
                let outside = outside_rate * trace.outside_m;
                let endpoint = D::cell_index_at(&self.grid, ray, r);
                // Cells before the endpoint cell: all but the last crossing when the last
                // crossing is the endpoint cell (always, up to rounding), else all.
                let all_misses = trace.before_last + trace.last.map_or(0.0, |(_, lm)| lm);
                match endpoint {
                    Some(k) => {
                        let misses = match trace.last {
                            Some((last, _)) if last == k => trace.before_last,
                            _ => all_misses,
                        };
                        let ln_mu = self.log_probs.get(k).map_or(self.outside[0], |p| p[0]);
                        let (t0, t1) = D::chord(&self.grid, ray, k);
                        let chord = t1.min(range.max_range_m) - t0.max(range.min_range_m);
                        let chord = chord.max(MIN_CHORD_FRACTION * D::cell_size(&self.grid));
                        // Eq. (7.23) and (7.32)
                        misses + outside + ln_mu - chord.ln()
                    }
                    None => all_misses + outside + self.outside[0] - D::cell_size(&self.grid).ln(),
                }
            }
            Reading::Sup => {
                let trace = self.trace(ray, range.max_range_m);
                trace.before_last
                    + trace.last.map_or(0.0, |(_, lm)| lm)
                    + outside_rate * trace.outside_m
            }
            Reading::Sub => {
                let trace = self.trace(ray, range.min_range_m);
                ln_one_minus_exp_neg(-(trace.before_last + outside_rate * trace.outside_m))
            }
        };
        finite_or_neg_inf(value)
    }
}

/// `[ln μ, ln(1 − μ)]`.
#[inline]
fn log_pair(mu: f64) -> [f64; 2] {
    [mu.ln(), (-mu).ln_1p()]
}
