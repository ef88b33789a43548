//! Analytic first and second derivatives of one ray's log-likelihood with respect to the
//! coefficients (Sec. 9.4.4), in the thesis's notation, `O(I²)` per ray.
//!
//! * `B_i = ∂λ/∂a_i = 2 φ_i g`, `B_ij = 2 φ_i φ_j` at the endpoint (`φ_i = cos(l_i x̃) cos(m_i ỹ)`);
//! * `C_ij = ∂²𝒮/∂a_i∂a_j = 2 K_ij` with `K` the [`product_matrix`] of the ray's moments,
//!   `C_i = Σ_j C_ij a_j = ∂𝒮/∂a_i`; `𝒩 = e^{−𝒮}`.
//!
//! | outcome | gradient | Hessian |
//! |---|---|---|
//! | hit | `B_i/λ − C_i` | `B_ij/λ − B_i B_j/λ² − C_ij` |
//! | sub | `𝒩 C_i/(1 − 𝒩)` | `𝒩 C_ij/(1 − 𝒩) − 𝒩 C_i C_j/(1 − 𝒩)²` |
//! | super | `−C_i` | `−C_ij` |
//!
//! **Erratum (sub Hessian).** The thesis prints `𝒩 (C_ij − C_i C_j)/(1 − 𝒩) + 𝒩² C_i C_j/(1 − 𝒩)²`.
//! Differentiating `𝒩 C_i/(1 − 𝒩)` with `∂𝒩/∂a_j = −𝒩 C_j` gives the same first term but a
//! **minus** before `𝒩² C_i C_j/(1 − 𝒩)²`; the two collapse to the form in the table. That is
//! what is implemented, and the tests check it against finite differences (the printed form
//! fails them).

use crate::moments::{cosines, moments};
use crate::spectrum::product_matrix;
use crate::{DctMap, MapRay, Outcome};

/// Log-likelihood of one ray with its gradient and Hessian (row-major `I × I`).
#[derive(Clone, Debug, PartialEq)]
pub struct RayDerivatives {
    /// `ln p(z | 𝒜)`.
    pub log_likelihood: f64,
    /// `∂ ln p / ∂a_i`.
    pub gradient: Vec<f64>,
    /// `∂² ln p / ∂a_i ∂a_j`.
    pub hessian: Vec<f64>,
}

/// Which printed formula to use for the `sub` Hessian.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SubHessian {
    /// The re-derived form (implemented everywhere else).
    Corrected,
    /// The form printed in the thesis (kept only to show that it fails the check).
    AsPrinted,
}

/// The analytic derivatives of `ray`'s log-likelihood under `map` (Sec. 9.4.4).
pub fn ray_derivatives(map: &DctMap, ray: &MapRay, sub: SubHessian) -> RayDerivatives {
    let shape = map.shape();
    let n = shape.len();
    let a = map.coefficients();
    let t = moments(shape, map.extent_m(), &ray.segment());
    let k = product_matrix(shape, &t);
    let c_ij: Vec<f64> = k.iter().map(|v| 2.0 * v).collect();
    let c_i: Vec<f64> = (0..n)
        .map(|i| {
            c_ij[i * n..(i + 1) * n]
                .iter()
                .zip(a)
                .map(|(c, a)| c * a)
                .sum()
        })
        .collect();
    let s: f64 = 0.5 * c_i.iter().zip(a).map(|(c, a)| c * a).sum::<f64>();
    let nn = (-s).exp();
    match ray.outcome {
        Outcome::Hit => {
            let end = ray.end();
            let [xe, ye] = map.extent_m();
            let cx: Vec<f64> = cosines(shape.l, end[0], xe).collect();
            let cy: Vec<f64> = cosines(shape.m, end[1], ye).collect();
            let phi: Vec<f64> = (0..n).map(|i| cx[i / shape.m] * cy[i % shape.m]).collect();
            let g: f64 = phi.iter().zip(a).map(|(p, a)| p * a).sum();
            let lambda = g * g;
            let b_i: Vec<f64> = phi.iter().map(|p| 2.0 * p * g).collect();
            let gradient = (0..n).map(|i| b_i[i] / lambda - c_i[i]).collect();
            let mut hessian = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    let b_ij = 2.0 * phi[i] * phi[j];
                    hessian[i * n + j] =
                        b_ij / lambda - b_i[i] * b_i[j] / (lambda * lambda) - c_ij[i * n + j];
                }
            }
            RayDerivatives {
                log_likelihood: lambda.ln() - s,
                gradient,
                hessian,
            }
        }
        Outcome::Super => RayDerivatives {
            log_likelihood: -s,
            gradient: c_i.iter().map(|c| -c).collect(),
            hessian: c_ij.iter().map(|c| -c).collect(),
        },
        Outcome::Sub => {
            let one_minus = -(-s).exp_m1();
            let w = nn / one_minus;
            let mut hessian = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    let cij = c_ij[i * n + j];
                    let cc = c_i[i] * c_i[j];
                    hessian[i * n + j] = match sub {
                        SubHessian::Corrected => w * cij - nn * cc / (one_minus * one_minus),
                        SubHessian::AsPrinted => {
                            nn * (cij - cc) / one_minus + nn * nn * cc / (one_minus * one_minus)
                        }
                    };
                }
            }
            RayDerivatives {
                log_likelihood: one_minus.ln(),
                gradient: c_i.iter().map(|c| w * c).collect(),
                hessian,
            }
        }
    }
}
