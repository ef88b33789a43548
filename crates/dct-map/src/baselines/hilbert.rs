//! Hilbert maps (Ramos & Ott 2016) with Nyström features, the variant the thesis compares with
//! in Sec. 9.5.2 (Table 9.3) and times in Table 9.4.
//!
//! ## Model
//!
//! **Nyström features** (Williams & Seeger 2001) of the RBF kernel `k(x, x') = e^{−γ‖x − x'‖²}`
//! ([`rbf`]): `M` landmarks `z_m` drawn at random from the training points, `K_MM = L Lᵀ`
//! (plus a jitter `ε I`), and
//!
//! ```text
//! φ(x) = L⁻¹ k_M(x),      k_M(x) = (k(x, z_1), …, k(x, z_M)),
//! ```
//!
//! so `φ(x)ᵀ φ(x') = k_M(x)ᵀ K_MM⁻¹ k_M(x')`, the Nyström approximation of `k(x, x')` — exact
//! when `x, x'` are landmarks. (scikit-learn, which Ramos & Ott's code uses, writes
//! `φ = Λ^{−1/2} Uᵀ k_M` from the eigendecomposition `K_MM = U Λ Uᵀ`; the two differ by a
//! rotation, which leaves the L2-regularized fit below unchanged.)
//!
//! **Classifier**: logistic regression `o(x) = σ(wᵀ φ(x) + c)` on the labelled points of a
//! [`TrainingSet`], minimizing the mean logistic loss plus `(α/2) ‖w‖²` (the bias unpenalized)
//! by L-BFGS to convergence. Equal memory: `M` = the number of parameters (thesis Sec. 9.5.2,
//! "number of components of the Nyström features"). Prediction uses `v = L⁻ᵀ w`,
//! `wᵀ φ(x) = vᵀ k_M(x)`, `O(M)` per point.
//!
//! ## Hyperparameters and departures from the published code ([`HilbertConfig`])
//!
//! * `γ = 1 /m²` (length scale `1/√(2γ) ≈ 0.71` m), the default of Ramos & Ott's CARMEN
//!   example; `α = 10⁻⁴`, scikit-learn's `SGDClassifier` default that their code uses. Neither
//!   is tuned here.
//! * Their code fits by one pass of stochastic gradient descent with an elastic-net penalty,
//!   chooses the landmarks by k-means and min-max-scales the features; here the landmarks are
//!   a random subset (scikit-learn's `Nystroem` default), there is no scaling, the penalty is
//!   L2 and the optimizer a seeded, deterministic, converged L-BFGS.
//! * Training points are capped at [`HilbertConfig::max_training_points`] (random subset):
//!   the feature matrix is `M × N` reals.

use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{ColMut, Mat, MatMut, MatRef, Par, Side};
use rand::seq::index;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use raypath_geometry::lane_dot;

use super::raster::OccupancyField;
use super::{TrainingSet, distance_sq, rbf};
use crate::DctError;
use crate::lbfgs::{LbfgsConfig, minimize};

/// Hilbert-map hyperparameters (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HilbertConfig {
    /// RBF `γ` (1/m²). Default `1.0`.
    pub gamma_per_m2: f64,
    /// L2 weight `α` on the mean logistic loss. Default `1e-4`.
    pub regularization: f64,
    /// Jitter `ε` added to the diagonal of `K_MM` (its entries are at most 1). Default `1e-8`.
    pub jitter: f64,
    /// At most this many training points (random subset). Default `20 000`.
    pub max_training_points: usize,
    /// L-BFGS iteration cap. Default `2000`.
    pub max_iterations: usize,
    /// Stop when the gradient's largest entry is below this. Default `1e-6`.
    pub gradient_tolerance: f64,
}

impl Default for HilbertConfig {
    fn default() -> Self {
        Self {
            gamma_per_m2: 1.0,
            regularization: 1e-4,
            jitter: 1e-8,
            max_training_points: 20_000,
            max_iterations: 2000,
            gradient_tolerance: 1e-6,
        }
    }
}

/// What a Hilbert-map fit used and reached.
#[derive(Clone, Debug, PartialEq)]
pub struct HilbertReport {
    /// Nyström components (the parameter count unless fewer points were sampled).
    pub components: usize,
    /// Training points used.
    pub training_points: usize,
    /// L-BFGS iterations.
    pub iterations: usize,
    /// Whether L-BFGS met a tolerance before the iteration cap.
    pub converged: bool,
    /// The final objective (mean logistic loss + penalty).
    pub objective: f64,
}

/// Nyström features of an RBF kernel: landmarks and the Cholesky factor of `K_MM + ε I`.
#[derive(Clone, Debug)]
pub struct NystromFeatures {
    landmarks: Vec<[f64; 2]>,
    chol: Mat<f64>,
    gamma: f64,
}

impl NystromFeatures {
    /// Features on `landmarks` (module docs).
    pub fn new(landmarks: Vec<[f64; 2]>, gamma_per_m2: f64, jitter: f64) -> Result<Self, DctError> {
        let gamma = crate::error::positive("gamma_per_m2", gamma_per_m2)?;
        if landmarks.is_empty() {
            return Err(DctError::NoData("Nyström features need a landmark".into()));
        }
        if !(jitter.is_finite() && jitter >= 0.0) {
            return Err(DctError::InvalidParameter {
                name: "jitter",
                reason: format!("must be finite and ≥ 0, got {jitter}"),
            });
        }
        let m = landmarks.len();
        let k = Mat::<f64>::from_fn(m, m, |i, j| {
            rbf(distance_sq(landmarks[i], landmarks[j]), gamma) + if i == j { jitter } else { 0.0 }
        });
        let chol = k
            .llt(Side::Lower)
            .map_err(|e| DctError::NoData(format!("K_MM is not positive definite: {e:?}")))?
            .L()
            .to_owned();
        Ok(Self {
            landmarks,
            chol,
            gamma,
        })
    }

    /// Number of components `M`.
    pub fn components(&self) -> usize {
        self.landmarks.len()
    }

    /// `k_M(x)` for each point, column-major `M × n` (point `j` at `j·M .. (j+1)·M`).
    fn kernel_columns(&self, points: &[[f64; 2]]) -> Vec<f64> {
        let m = self.components();
        let mut k = vec![0.0; m * points.len()];
        k.par_chunks_mut(m).zip(points).for_each(|(col, p)| {
            for (c, z) in col.iter_mut().zip(&self.landmarks) {
                *c = rbf(distance_sq(*p, *z), self.gamma);
            }
        });
        k
    }

    /// The features `φ(x) = L⁻¹ k_M(x)` of each point, as the columns of an `M × n` matrix.
    pub fn features(&self, points: &[[f64; 2]]) -> Mat<f64> {
        let k = self.kernel_columns(points);
        let mut phi =
            MatRef::from_column_major_slice(&k, self.components(), points.len()).to_owned();
        solve_lower_triangular_in_place(self.chol.as_ref(), phi.as_mut(), Par::rayon(0));
        phi
    }
}

/// A fitted Hilbert map.
#[derive(Clone, Debug)]
pub struct HilbertMap {
    features: NystromFeatures,
    /// `v = L⁻ᵀ w`, so that `wᵀ φ(x) = vᵀ k_M(x)`.
    v: Vec<f64>,
    bias: f64,
}

/// `ln(1 + e^x)` without overflow.
fn softplus(x: f64) -> f64 {
    if x > 0.0 {
        x + (-x).exp().ln_1p()
    } else {
        x.exp().ln_1p()
    }
}

/// The logistic function.
fn sigmoid(x: f64) -> f64 {
    if x >= 0.0 {
        1.0 / (1.0 + (-x).exp())
    } else {
        let e = x.exp();
        e / (1.0 + e)
    }
}

/// Training points per parallel task of the logistic objective.
const COLUMNS_PER_TASK: usize = 512;

/// The training data of the logistic fit in kernel form: `K_MN` (column-major, `k_M(x_j)` per
/// point), the factor `L` of `K_MM + ε I` and the labels. The features `Φ = L⁻¹ K_MN` are
/// never formed (`M²N` flops saved; two `M²` triangular solves per evaluation instead), and
/// one pass over `K_MN` gives both the logits and the gradient.
struct LogisticProblem<'a> {
    kernel: &'a [f64],
    chol: &'a Mat<f64>,
    labels: &'a [f64],
    alpha: f64,
}

impl LogisticProblem<'_> {
    /// Mean logistic loss + `(α/2)‖w‖²` at `x = (w, c)`, and its gradient in `grad`.
    fn evaluate(&self, x: &[f64], grad: &mut [f64]) -> f64 {
        let m = self.chol.nrows();
        let n = self.labels.len() as f64;
        let (w, c) = (&x[..m], x[m]);
        let (gw, gb) = grad.split_at_mut(m);
        // v = L⁻ᵀ w, so that the logit of point j is k_M(x_j)ᵀ v + c = φ(x_j)ᵀ w + c.
        gw.copy_from_slice(w);
        solve_upper_triangular_in_place(
            self.chol.transpose(),
            ColMut::from_slice_mut(gw).as_mat_mut(),
            Par::Seq,
        );
        let v: &[f64] = gw;
        // Per task: loss, ∂/∂c, and u = Σ_j r_j k_M(x_j); summed in task order.
        let parts: Vec<(f64, f64, Vec<f64>)> = self
            .kernel
            .par_chunks(m * COLUMNS_PER_TASK)
            .zip(self.labels.par_chunks(COLUMNS_PER_TASK))
            .map(|(block, ys)| {
                let (mut loss, mut gc, mut u) = (0.0, 0.0, vec![0.0; m]);
                for (col, y) in block.chunks_exact(m).zip(ys) {
                    let margin = y * (lane_dot(col, v) + c);
                    loss += softplus(-margin);
                    let r = -y * sigmoid(-margin) / n;
                    gc += r;
                    u.iter_mut().zip(col).for_each(|(u, k)| *u += r * k);
                }
                (loss, gc, u)
            })
            .collect();
        let (mut loss, mut gc) = (0.0, 0.0);
        gw.fill(0.0);
        for (l, g, u) in &parts {
            loss += l;
            gc += g;
            gw.iter_mut().zip(u).for_each(|(a, b)| *a += b);
        }
        // ∇_w = Φ r + α w = L⁻¹ u + α w.
        solve_lower_triangular_in_place(
            self.chol.as_ref(),
            ColMut::from_slice_mut(gw).as_mat_mut(),
            Par::Seq,
        );
        let mut penalty = 0.0;
        for (g, w) in gw.iter_mut().zip(w) {
            *g += self.alpha * w;
            penalty += w * w;
        }
        gb[0] = gc;
        loss / n + 0.5 * self.alpha * penalty
    }
}

impl HilbertMap {
    /// Fits a Hilbert map with `components` Nyström components (landmarks drawn from the
    /// training points with `rng`; at most as many as there are points).
    pub fn fit(
        training: &TrainingSet,
        components: usize,
        config: &HilbertConfig,
        rng: &mut ChaCha8Rng,
    ) -> Result<(Self, HilbertReport), DctError> {
        if components == 0 || training.is_empty() {
            return Err(DctError::NoData(
                "a Hilbert map needs a component and a point".into(),
            ));
        }
        crate::error::positive("regularization", config.regularization)?;
        let set = training.subsample(config.max_training_points.max(1), rng);
        let mut picked = index::sample(rng, set.len(), components.min(set.len())).into_vec();
        picked.sort_unstable();
        let landmarks = picked.iter().map(|&i| set.points[i]).collect();
        let features = NystromFeatures::new(landmarks, config.gamma_per_m2, config.jitter)?;
        let kernel = features.kernel_columns(&set.points);
        let m = features.components();
        let problem = LogisticProblem {
            kernel: &kernel,
            chol: &features.chol,
            labels: &set.labels,
            alpha: config.regularization,
        };
        let lbfgs = LbfgsConfig {
            max_iterations: config.max_iterations,
            memory: 10,
            gradient_tolerance: config.gradient_tolerance,
            relative_tolerance: 1e-12,
            first_step_relative: None,
        };
        let mut objective = |x: &[f64], g: &mut [f64]| problem.evaluate(x, g);
        let result = minimize(&mut objective, vec![0.0; m + 1], &lbfgs);
        let mut v = Mat::<f64>::from_fn(m, 1, |i, _| result.x[i]);
        let vm: MatMut<'_, f64> = v.as_mut();
        solve_upper_triangular_in_place(features.chol.transpose(), vm, Par::Seq);
        let report = HilbertReport {
            components: m,
            training_points: set.len(),
            iterations: result.iterations(),
            converged: result.converged,
            objective: result.value(),
        };
        let map = Self {
            v: (0..m).map(|i| v[(i, 0)]).collect(),
            bias: result.x[m],
            features,
        };
        Ok((map, report))
    }

    /// Number of Nyström components.
    pub fn components(&self) -> usize {
        self.features.components()
    }

    /// The logit `wᵀ φ(x) + c` at a point.
    pub fn logit(&self, p: [f64; 2]) -> f64 {
        let g = self.features.gamma;
        self.features
            .landmarks
            .iter()
            .zip(&self.v)
            .map(|(z, v)| v * rbf(distance_sq(p, *z), g))
            .sum::<f64>()
            + self.bias
    }
}

impl OccupancyField for HilbertMap {
    fn occupancy(&self, points: &[[f64; 2]], out: &mut [f64]) {
        for (o, p) in out.iter_mut().zip(points) {
            *o = sigmoid(self.logit(*p));
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // test code: a panic is the failure report
mod tests {
    use rand::SeedableRng;

    use super::super::TrainingConfig;
    use super::*;
    use crate::{MapRay, Outcome};

    /// With every point a landmark, `ΦᵀΦ` reproduces the kernel matrix.
    #[test]
    fn nystrom_with_all_points_reproduces_the_kernel() {
        let pts: Vec<[f64; 2]> = (0..40)
            .map(|k| [0.9 * (k % 8) as f64, 1.1 * (k / 8) as f64 + 0.05 * k as f64])
            .collect();
        let f = NystromFeatures::new(pts.clone(), 1.0, 1e-12).unwrap();
        let phi = f.features(&pts);
        for i in 0..pts.len() {
            for j in 0..pts.len() {
                let dot: f64 = (0..pts.len()).map(|k| phi[(k, i)] * phi[(k, j)]).sum();
                let want = rbf(distance_sq(pts[i], pts[j]), 1.0);
                assert!((dot - want).abs() < 1e-8, "({i}, {j}): {dot} vs {want}");
            }
        }
    }

    /// Rays from x = 1 to a wall at x = 6: the map is occupied at the wall and free along
    /// the beams.
    #[test]
    fn classifies_a_wall_scene() {
        let rays: Vec<MapRay> = (0..400)
            .map(|k| {
                let y = 1.0 + 8.0 * k as f64 / 400.0;
                MapRay::from_angle([1.0, y], 0.0, 5.0, Outcome::Hit)
            })
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let set = TrainingSet::sample(&rays, &TrainingConfig::default(), &mut rng).unwrap();
        let (map, report) =
            HilbertMap::fit(&set, 100, &HilbertConfig::default(), &mut rng).unwrap();
        assert!(report.converged, "{report:?}");
        let mut o = [0.0; 4];
        map.occupancy(&[[6.0, 5.0], [6.0, 2.5], [3.0, 5.0], [4.5, 7.0]], &mut o);
        assert!(o[0] > 0.5 && o[1] > 0.5, "wall {o:?}");
        assert!(o[2] < 0.2 && o[3] < 0.2, "free {o:?}");
    }

    #[test]
    fn same_seed_same_map() {
        let rays: Vec<MapRay> = (0..100)
            .map(|k| MapRay::from_angle([0.5, 0.1 * k as f64], 0.1, 4.0, Outcome::Hit))
            .collect();
        let fit = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let set = TrainingSet::sample(&rays, &TrainingConfig::default(), &mut rng).unwrap();
            HilbertMap::fit(&set, 30, &HilbertConfig::default(), &mut rng).unwrap()
        };
        let (a, ra) = fit(5);
        let (b, rb) = fit(5);
        assert_eq!(ra, rb);
        assert_eq!(a.v, b.v);
        assert_eq!(a.bias, b.bias);
    }
}
