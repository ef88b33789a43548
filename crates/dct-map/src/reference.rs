//! The thesis's formulas taken literally, `O(8 I²)` per point or ray — kept as the
//! reference the fast forms are tested against.

use crate::{DctMap, MapRay};

const Q: [f64; 2] = [-1.0, 1.0];

fn pairs(map: &DctMap) -> impl Iterator<Item = (usize, usize, f64, f64)> + '_ {
    let a = map.coefficients();
    (0..a.len()).flat_map(move |i| (0..a.len()).map(move |j| (i, j, a[i], a[j])))
}

fn lm(map: &DctMap, i: usize) -> (f64, f64) {
    let mm = map.shape().m;
    ((i / mm) as f64, (i % mm) as f64)
}

/// `λ(x, y)` by Eq. (9.7): `⅛ Σ_i Σ_j a_i a_j Σ_{α,β,γ ∈ {±1}} cos((l_i + α l_j) x̃ + β (m_i + γ m_j) ỹ)`.
pub fn rate_at(map: &DctMap, p: [f64; 2]) -> f64 {
    let [xe, ye] = map.extent_m();
    let (xt, yt) = (
        std::f64::consts::PI * p[0] / xe,
        std::f64::consts::PI * p[1] / ye,
    );
    let mut sum = 0.0;
    for (i, j, ai, aj) in pairs(map) {
        let ((li, mi), (lj, mj)) = (lm(map, i), lm(map, j));
        for al in Q {
            for be in Q {
                for ga in Q {
                    sum += ai * aj * ((li + al * lj) * xt + be * (mi + ga * mj) * yt).cos(); // Eq. (9.7)
                }
            }
        }
    }
    sum / 8.0
}

/// `A(i, j, α, β, γ)` of Eq. (9.10) for one ray, with the thesis's two branches.
pub fn a_term(map: &DctMap, ray: &MapRay, i: usize, j: usize, al: f64, be: f64, ga: f64) -> f64 {
    let [xe, ye] = map.extent_m();
    let pi = std::f64::consts::PI;
    let (sx, sy) = (pi * ray.origin[0] / xe, pi * ray.origin[1] / ye);
    let (vx, vy) = (pi * ray.direction[0] / xe, pi * ray.direction[1] / ye);
    let ((li, mi), (lj, mj)) = (lm(map, i), lm(map, j));
    let (kx, ky) = (li + al * lj, be * (mi + ga * mj));
    let omega = kx * vx + ky * vy;
    let phi = kx * sx + ky * sy;
    let r = ray.length_m;
    if omega != 0.0 {
        ((phi + omega * r).sin() - phi.sin()) / omega // Eq. (9.10), ω ≠ 0
    } else {
        r * phi.cos() // Eq. (9.10), ω = 0
    }
}

/// `𝒮(s, v, r) = ⅛ Σ_i Σ_j a_i a_j Σ_{α,β,γ} A_ij` (Eq. 9.9–9.10).
pub fn optical_depth(map: &DctMap, ray: &MapRay) -> f64 {
    let mut sum = 0.0;
    for (i, j, ai, aj) in pairs(map) {
        for al in Q {
            for be in Q {
                for ga in Q {
                    sum += ai * aj * a_term(map, ray, i, j, al, be, ga);
                }
            }
        }
    }
    sum / 8.0
}

/// `C_ij = ⅛ Σ_{α,β,γ} (A_ij + A_ji)` (Sec. 9.4.4, read as the sum of both terms), row-major.
pub fn c_matrix(map: &DctMap, ray: &MapRay) -> Vec<f64> {
    let n = map.coefficients().len();
    let mut c = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let mut s = 0.0;
            for al in Q {
                for be in Q {
                    for ga in Q {
                        s +=
                            a_term(map, ray, i, j, al, be, ga) + a_term(map, ray, j, i, al, be, ga);
                    }
                }
            }
            c[i * n + j] = s / 8.0;
        }
    }
    c
}
