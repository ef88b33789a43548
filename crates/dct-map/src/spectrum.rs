//! Cosine spectra of products: the self-convolution `b_pq` of the coefficients and the
//! "product matrix" that turns a spectrum of integrals into the Gram matrix of the basis.
//!
//! With `φ_lm(x, y) = cos(l x̃) cos(m ỹ)` the product of two basis functions is, by the
//! product-to-sum identity applied twice (the factor `1/8` of Eq. (9.7) before the sum over
//! `α, β, γ` collapses to `1/4` once `cos` is even),
//!
//! ```text
//! φ_lm φ_l'm' = ¼ Σ_{p ∈ {l+l', |l−l'|}} Σ_{q ∈ {m+m', |m−m'|}} cos(p x̃) cos(q ỹ),
//! ```
//!
//! so `λ = g² = Σ_pq b_pq cos(p x̃) cos(q ỹ)` with `p < P = 2L − 1`, `q < Q = 2M − 1`, and
//! any integral `∫ λ` is `Σ_pq b_pq T_pq` with `T_pq = ∫ cos(p x̃) cos(q ỹ)`.

/// Shape of a coefficient matrix: `L` rows (x frequencies), `M` columns (y frequencies).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shape {
    /// Number of x frequencies `L`.
    pub l: usize,
    /// Number of y frequencies `M`.
    pub m: usize,
}

impl Shape {
    /// Number of coefficients `I = L · M`.
    #[inline]
    pub fn len(&self) -> usize {
        self.l * self.m
    }

    /// Whether the shape holds no coefficient.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of x frequencies of the product spectrum, `P = 2L − 1`.
    #[inline]
    pub fn p(&self) -> usize {
        (2 * self.l).saturating_sub(1)
    }

    /// Number of y frequencies of the product spectrum, `Q = 2M − 1`.
    #[inline]
    pub fn q(&self) -> usize {
        (2 * self.m).saturating_sub(1)
    }

    /// Length of a product spectrum, `P · Q`.
    #[inline]
    pub fn spectrum_len(&self) -> usize {
        self.p() * self.q()
    }
}

/// The cosine self-convolution `b_pq` of the coefficients `a` (row-major `l · M + m`):
/// `λ(x, y) = Σ_pq b_pq cos(p x̃) cos(q ỹ)` exactly (an algebraic rearrangement of Eq. (9.7),
/// not in the thesis). `O(4 I²)`.
pub fn self_convolution(shape: Shape, a: &[f64]) -> Vec<f64> {
    let (lm, mm, qn) = (shape.l, shape.m, shape.q());
    let mut b = vec![0.0; shape.spectrum_len()];
    for l in 0..lm {
        for m in 0..mm {
            let ai = a[l * mm + m] * 0.25;
            if ai == 0.0 {
                continue;
            }
            for l2 in 0..lm {
                let (ps, pd) = (l + l2, l.abs_diff(l2));
                let row = &a[l2 * mm..(l2 + 1) * mm];
                for (m2, &aj) in row.iter().enumerate() {
                    let w = ai * aj;
                    let (qs, qd) = (m + m2, m.abs_diff(m2));
                    b[ps * qn + qs] += w;
                    b[ps * qn + qd] += w;
                    b[pd * qn + qs] += w;
                    b[pd * qn + qd] += w;
                }
            }
        }
    }
    b
}

/// The Gram-type matrix `K_ij = ¼ Σ T(l_i ± l_j, m_i ± m_j)` of a spectrum `t` (length
/// `P · Q`), row-major `I × I`; `aᵀ K a = Σ_pq b_pq t_pq` for `b` = [`self_convolution`]`(a)`.
/// With `t` the moments of a ray, `2 K` is the thesis's `C_ij` (Sec. 9.4.4).
pub fn product_matrix(shape: Shape, t: &[f64]) -> Vec<f64> {
    let n = shape.len();
    let mut k = vec![0.0; n * n];
    fill_product_matrix(shape, t, |i, j, v| k[i * n + j] = v);
    k
}

/// Calls `set(i, j, K_ij)` for every entry of [`product_matrix`] (no allocation).
pub fn fill_product_matrix(shape: Shape, t: &[f64], mut set: impl FnMut(usize, usize, f64)) {
    let (lm, mm, qn) = (shape.l, shape.m, shape.q());
    for l in 0..lm {
        for m in 0..mm {
            let i = l * mm + m;
            for l2 in 0..lm {
                let rs = &t[(l + l2) * qn..(l + l2 + 1) * qn];
                let rd = &t[l.abs_diff(l2) * qn..(l.abs_diff(l2) + 1) * qn];
                for m2 in 0..mm {
                    let (qs, qd) = (m + m2, m.abs_diff(m2));
                    set(i, l2 * mm + m2, 0.25 * (rs[qs] + rs[qd] + rd[qs] + rd[qd]));
                }
            }
        }
    }
}

/// `K v` for the [`product_matrix`] `K` of `t`, without forming `K`. `O(4 I²)`.
pub fn product_matrix_times(shape: Shape, t: &[f64], v: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; shape.len()];
    fill_product_matrix(shape, t, |i, j, kij| out[i] += kij * v[j]);
    out
}
