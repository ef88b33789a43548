//! Gaussian process occupancy maps (GPOM; O'Callaghan & Ramos 2012) with the Matérn
//! `ν = 3/2` kernel of Jadidi et al. (2018), the variant the thesis compares with in
//! Sec. 9.5.2 (Table 9.3) and times in Table 9.4.
//!
//! ## Model
//!
//! GP regression of the labels `y ∈ {+1, −1}` (occupied, free) of a [`TrainingSet`] with
//! kernel `k = σ_f² (1 + √3 r/ℓ) e^{−√3 r/ℓ}` ([`matern32`]) and Gaussian noise `σ_n²`.
//! With `K_y = K + σ_n² I = L Lᵀ` and `w = K_y⁻¹ y` (Rasmussen & Williams 2006, Eq. 2.25–2.26)
//! the latent field at `x_*` has
//!
//! ```text
//! μ_* = k_*ᵀ w,        σ_*² = σ_f² − ‖L⁻¹ k_*‖².
//! ```
//!
//! **Squashing** (probabilistic least-squares classification, R&W Sec. 6.5, as in GPOM):
//! `o(x_*) = Φ((a μ_* + b) / √(1 + a² σ_*²))` with `a > 0`, `b` maximizing the leave-one-out
//! pseudo-likelihood `Σ_i ln Φ(y_i (a μ_{−i} + b) / √(1 + a² σ_{−i}²))` (R&W Eq. 6.42), whose
//! LOO moments come in closed form from `K_y⁻¹`: `μ_{−i} = y_i − w_i / [K_y⁻¹]_ii`,
//! `σ_{−i}² = 1 / [K_y⁻¹]_ii` (R&W Eq. 5.12).
//!
//! **Equal memory** (thesis Sec. 9.5.2): the map is the weight vector `w`, one real per
//! training point, so [`Gpom::fit`] first draws `n` of the sampled points at random.
//!
//! **Hyperparameters** ([`GpomConfig`]). The thesis used Jadidi et al.'s GPML code and its
//! hyperparameters, which it does not list. Here `σ_f = 1` (the labels are `±1`) and
//! `(ℓ, σ_n)` are chosen on the training points only, by the highest log marginal likelihood
//! (R&W Eq. 2.30, what GPML maximizes) over a small grid: `ℓ ∈ {0.2, 0.5, 1, 2}` m,
//! `σ_n ∈ {0.1, 0.3, 1}`. One-element lists fix them. The grid search is part of the fit time.

use faer::linalg::solvers::Solve;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Mat, MatMut, Par, Side};
use rand_chacha::ChaCha8Rng;
use statrs::function::erf::erfc;

use super::raster::OccupancyField;
use super::{TrainingSet, distance_sq, matern32};
use crate::DctError;
use crate::lbfgs::{LbfgsConfig, minimize};

/// GPOM hyperparameters (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct GpomConfig {
    /// Candidate Matérn length scales `ℓ` (m). Default `[0.2, 0.5, 1.0, 2.0]`.
    pub length_scales_m: Vec<f64>,
    /// Candidate noise standard deviations `σ_n` (label units). Default `[0.1, 0.3, 1.0]`.
    pub noise_stds: Vec<f64>,
    /// Signal standard deviation `σ_f`. Default `1.0`.
    pub signal_std: f64,
}

impl Default for GpomConfig {
    fn default() -> Self {
        Self {
            length_scales_m: vec![0.2, 0.5, 1.0, 2.0],
            noise_stds: vec![0.1, 0.3, 1.0],
            signal_std: 1.0,
        }
    }
}

/// What a GPOM fit chose and reached.
#[derive(Clone, Debug, PartialEq)]
pub struct GpomReport {
    /// Training points used (the parameter count unless fewer were sampled).
    pub training_points: usize,
    /// Of which occupied.
    pub occupied: usize,
    /// Chosen `ℓ` (m).
    pub length_scale_m: f64,
    /// Chosen `σ_n`.
    pub noise_std: f64,
    /// Log marginal likelihood of the labels at the chosen hyperparameters.
    pub log_marginal_likelihood: f64,
    /// Squashing scale `a`.
    pub squash_scale: f64,
    /// Squashing offset `b`.
    pub squash_offset: f64,
}

/// A fitted GPOM: training points, weights `w = K_y⁻¹ y` and the Cholesky factor of `K_y`.
#[derive(Clone, Debug)]
pub struct Gpom {
    points: Vec<[f64; 2]>,
    weights: Vec<f64>,
    chol: Mat<f64>,
    length_scale_m: f64,
    signal_var: f64,
    squash: [f64; 2],
}

/// `Φ(z)`, the standard normal CDF.
pub fn normal_cdf(z: f64) -> f64 {
    0.5 * erfc(-z / std::f64::consts::SQRT_2)
}

/// `ln Φ(z)`, accurate in the far left tail.
fn ln_normal_cdf(z: f64) -> f64 {
    if z > -30.0 {
        normal_cdf(z).ln()
    } else {
        -0.5 * z * z - (-z).ln() - 0.5 * (2.0 * std::f64::consts::PI).ln()
    }
}

/// `φ(z) / Φ(z)`, the derivative of `ln Φ`.
fn inverse_mills(z: f64) -> f64 {
    if z > -30.0 {
        (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt() / normal_cdf(z)
    } else {
        -z
    }
}

/// `K_y = K + σ_n² I` over `points`.
fn kernel_matrix(points: &[[f64; 2]], ell: f64, signal_var: f64, noise_var: f64) -> Mat<f64> {
    Mat::from_fn(points.len(), points.len(), |i, j| {
        let k = matern32(distance_sq(points[i], points[j]).sqrt(), ell, signal_var);
        if i == j { k + noise_var } else { k }
    })
}

/// One candidate's factor, weights and log marginal likelihood (R&W Eq. 2.30).
fn factor(
    points: &[[f64; 2]],
    labels: &[f64],
    ell: f64,
    signal_var: f64,
    noise_var: f64,
) -> Option<(Mat<f64>, Vec<f64>, f64)> {
    let n = points.len();
    let llt = kernel_matrix(points, ell, signal_var, noise_var)
        .llt(Side::Lower)
        .ok()?;
    let mut w = Mat::<f64>::from_fn(n, 1, |i, _| labels[i]);
    llt.solve_in_place(w.as_mut());
    let w: Vec<f64> = (0..n).map(|i| w[(i, 0)]).collect();
    let l = llt.L().to_owned();
    let log_det_half: f64 = (0..n).map(|i| l[(i, i)].ln()).sum();
    let fit: f64 = labels.iter().zip(&w).map(|(y, w)| y * w).sum();
    let lml = -0.5 * fit - log_det_half - 0.5 * n as f64 * (2.0 * std::f64::consts::PI).ln();
    lml.is_finite().then_some((l, w, lml))
}

/// The diagonal of `K_y⁻¹ = L⁻ᵀ L⁻¹`: squared column norms of `L⁻¹`.
fn inverse_diagonal(l: &Mat<f64>) -> Vec<f64> {
    let n = l.nrows();
    let mut inv = Mat::<f64>::identity(n, n);
    solve_lower_triangular_in_place(l.as_ref(), inv.as_mut(), Par::rayon(0));
    (0..n)
        .map(|j| (j..n).map(|k| inv[(k, j)].powi(2)).sum())
        .collect()
}

/// `(a, b)` maximizing the LOO pseudo-likelihood of R&W Eq. (6.42): a coarse grid over
/// `(ln a, b)`, refined by L-BFGS.
fn calibrate_squash(labels: &[f64], loo_mean: &[f64], loo_var: &[f64]) -> [f64; 2] {
    // Negative LOO pseudo-log-likelihood in (u = ln a, b) and its gradient.
    let mut objective = |x: &[f64], g: &mut [f64]| {
        let (a, b) = (x[0].exp(), x[1]);
        let (mut f, mut gu, mut gb) = (0.0, 0.0, 0.0);
        for ((y, m), v) in labels.iter().zip(loo_mean).zip(loo_var) {
            let s = (1.0 + a * a * v).sqrt();
            let z = y * (a * m + b) / s;
            let r = inverse_mills(z);
            f -= ln_normal_cdf(z);
            gu -= r * a * y * (m / s - (a * m + b) * a * v / (s * s * s));
            gb -= r * y / s;
        }
        g[0] = gu;
        g[1] = gb;
        f
    };
    let mut best = ([0.0, 0.0], f64::INFINITY);
    let mut scratch = [0.0; 2];
    for iu in -6..=6 {
        for ib in -8..=8 {
            let x = [0.5 * iu as f64, 0.25 * ib as f64];
            let f = objective(&x, &mut scratch);
            if f < best.1 {
                best = (x, f);
            }
        }
    }
    let config = LbfgsConfig {
        max_iterations: 100,
        memory: 5,
        gradient_tolerance: 1e-8,
        relative_tolerance: 1e-12,
        first_step_relative: None,
    };
    let r = minimize(&mut objective, best.0.to_vec(), &config);
    let x = if r.value() <= best.1 {
        r.x
    } else {
        best.0.to_vec()
    };
    [x[0].exp(), x[1]]
}

impl Gpom {
    /// Fits a GPOM to at most `n_points` points of `training`, drawn at random with `rng`
    /// (module docs: the memory match), choosing `(ℓ, σ_n)` from `config` by marginal
    /// likelihood and calibrating the squashing.
    pub fn fit(
        training: &TrainingSet,
        n_points: usize,
        config: &GpomConfig,
        rng: &mut ChaCha8Rng,
    ) -> Result<(Self, GpomReport), DctError> {
        if n_points == 0 || training.is_empty() {
            return Err(DctError::NoData(
                "GPOM needs at least one training point".into(),
            ));
        }
        if config.length_scales_m.is_empty() || config.noise_stds.is_empty() {
            return Err(DctError::InvalidParameter {
                name: "GpomConfig",
                reason: "empty hyperparameter grid".into(),
            });
        }
        for &v in config.length_scales_m.iter().chain(&config.noise_stds) {
            crate::error::positive("GpomConfig grid value", v)?;
        }
        let signal_var = crate::error::positive("signal_std", config.signal_std)?.powi(2);
        let set = training.subsample(n_points, rng);
        // (ℓ, σ_n, L, w, log marginal likelihood) of the best candidate so far.
        type Candidate = (f64, f64, Mat<f64>, Vec<f64>, f64);
        let mut best: Option<Candidate> = None;
        for &ell in &config.length_scales_m {
            for &sn in &config.noise_stds {
                if let Some((l, w, lml)) =
                    factor(&set.points, &set.labels, ell, signal_var, sn * sn)
                    && best.as_ref().is_none_or(|b| lml > b.4)
                {
                    best = Some((ell, sn, l, w, lml));
                }
            }
        }
        let Some((ell, sn, chol, weights, lml)) = best else {
            return Err(DctError::NoData(
                "no GPOM kernel matrix was positive definite".into(),
            ));
        };
        let d = inverse_diagonal(&chol);
        let loo_mean: Vec<f64> = (0..set.len())
            .map(|i| set.labels[i] - weights[i] / d[i])
            .collect();
        let loo_var: Vec<f64> = d.iter().map(|d| 1.0 / d).collect();
        let squash = calibrate_squash(&set.labels, &loo_mean, &loo_var);
        let report = GpomReport {
            training_points: set.len(),
            occupied: set.occupied(),
            length_scale_m: ell,
            noise_std: sn,
            log_marginal_likelihood: lml,
            squash_scale: squash[0],
            squash_offset: squash[1],
        };
        let map = Self {
            points: set.points,
            weights,
            chol,
            length_scale_m: ell,
            signal_var,
            squash,
        };
        Ok((map, report))
    }

    /// Number of real parameters (the weights).
    pub fn parameters(&self) -> usize {
        self.weights.len()
    }

    /// Latent mean and variance at `points` (R&W Eq. 2.25–2.26), sequential (call it per
    /// chunk from a parallel loop).
    pub fn latent(&self, points: &[[f64; 2]]) -> (Vec<f64>, Vec<f64>) {
        let (n, p) = (self.points.len(), points.len());
        let mut ks = Mat::<f64>::from_fn(n, p, |i, j| {
            matern32(
                distance_sq(self.points[i], points[j]).sqrt(),
                self.length_scale_m,
                self.signal_var,
            )
        });
        let mean: Vec<f64> = (0..p)
            .map(|j| (0..n).map(|i| ks[(i, j)] * self.weights[i]).sum())
            .collect();
        let v: MatMut<'_, f64> = ks.as_mut();
        solve_lower_triangular_in_place(self.chol.as_ref(), v, Par::Seq);
        let var = (0..p)
            .map(|j| {
                let q: f64 = (0..n).map(|i| ks[(i, j)].powi(2)).sum();
                (self.signal_var - q).max(0.0)
            })
            .collect();
        (mean, var)
    }
}

impl OccupancyField for Gpom {
    fn occupancy(&self, points: &[[f64; 2]], out: &mut [f64]) {
        let (mean, var) = self.latent(points);
        let [a, b] = self.squash;
        for ((o, m), v) in out.iter_mut().zip(&mean).zip(&var) {
            *o = normal_cdf((a * m + b) / (1.0 + a * a * v).sqrt());
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // test code: a panic is the failure report
mod tests {
    use rand::SeedableRng;

    use super::*;

    fn fixed(ell: f64, noise: f64) -> GpomConfig {
        GpomConfig {
            length_scales_m: vec![ell],
            noise_stds: vec![noise],
            signal_std: 1.0,
        }
    }

    /// With tiny noise the posterior mean interpolates the training labels and the
    /// variance vanishes there.
    #[test]
    fn tiny_noise_interpolates_the_targets() {
        let points: Vec<[f64; 2]> = (0..30)
            .map(|k| [0.37 * (k % 6) as f64, 0.53 * (k / 6) as f64])
            .collect();
        let labels: Vec<f64> = (0..30)
            .map(|k| if k % 3 == 0 { 1.0 } else { -1.0 })
            .collect();
        let set = TrainingSet {
            points: points.clone(),
            labels: labels.clone(),
        };
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let (gp, report) = Gpom::fit(&set, 30, &fixed(0.5, 1e-4), &mut rng).unwrap();
        assert_eq!(report.training_points, 30);
        let (mean, var) = gp.latent(&points);
        for ((m, v), y) in mean.iter().zip(&var).zip(&labels) {
            assert!((m - y).abs() < 1e-3, "{m} vs {y}");
            assert!(*v < 1e-4, "{v}");
        }
        // Far away the latent reverts to the prior.
        let (m, v) = gp.latent(&[[50.0, 50.0]]);
        assert!(m[0].abs() < 1e-9 && (v[0] - 1.0).abs() < 1e-9);
    }

    /// The closed-form LOO moments equal refitting without the point.
    #[test]
    fn loo_moments_match_refits() {
        let points: Vec<[f64; 2]> = (0..12)
            .map(|k| [0.3 * k as f64, (0.7 * k as f64).sin()])
            .collect();
        let labels: Vec<f64> = (0..12)
            .map(|k| if k % 4 == 1 { 1.0 } else { -1.0 })
            .collect();
        let (l, w, _) = factor(&points, &labels, 0.8, 1.0, 0.09).unwrap();
        let d = inverse_diagonal(&l);
        for i in [0, 5, 11] {
            let (p2, y2): (Vec<_>, Vec<_>) = points
                .iter()
                .zip(&labels)
                .enumerate()
                .filter(|(k, _)| *k != i)
                .map(|(_, (p, y))| (*p, *y))
                .unzip();
            let (l2, w2, _) = factor(&p2, &y2, 0.8, 1.0, 0.09).unwrap();
            let gp = Gpom {
                points: p2,
                weights: w2,
                chol: l2,
                length_scale_m: 0.8,
                signal_var: 1.0,
                squash: [1.0, 0.0],
            };
            let (m, v) = gp.latent(&[points[i]]);
            assert!((m[0] - (labels[i] - w[i] / d[i])).abs() < 1e-9);
            // R&W Eq. 5.12's variance includes the noise.
            assert!((v[0] + 0.09 - 1.0 / d[i]).abs() < 1e-9);
        }
    }

    #[test]
    fn same_seed_same_map() {
        let set = TrainingSet {
            points: (0..200)
                .map(|k| [0.05 * k as f64, (0.1 * k as f64).cos()])
                .collect(),
            labels: (0..200)
                .map(|k| if k % 5 == 0 { 1.0 } else { -1.0 })
                .collect(),
        };
        let fit = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            Gpom::fit(&set, 50, &GpomConfig::default(), &mut rng).unwrap()
        };
        let (a, ra) = fit(7);
        let (b, rb) = fit(7);
        assert_eq!(ra, rb);
        assert_eq!(a.weights, b.weights);
        let (c, _) = fit(8);
        assert_ne!(a.points, c.points);
    }

    #[test]
    fn normal_tails() {
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-15);
        assert!((ln_normal_cdf(-29.999) - ln_normal_cdf(-30.001)).abs() < 0.1);
        assert!((inverse_mills(-29.999) - inverse_mills(-30.001)).abs() < 0.05);
        assert!(ln_normal_cdf(-100.0).is_finite());
    }
}
