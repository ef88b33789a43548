//! Closed-form cosine moments of a ray segment: `T_pq = ∫_0^r cos(p x̃(t)) cos(q ỹ(t)) dt`.
//!
//! Along `x(t) = s + v t` the phases are linear in `t`; with the product-to-sum identity
//! `cos(p x̃) cos(q ỹ) = ½ Σ_± cos(p x̃ ± q ỹ)` every term integrates in closed form (Eq. (9.10),
//! rewritten with `sinc`, which covers the axis-parallel case `ω = 0` without a branch):
//!
//! ```text
//! ∫_0^r cos(φ + ω t) dt = r · cos(φ + ω r / 2) · sinc(ω r / 2),   sinc(u) = sin(u) / u.
//! ```
//!
//! The phases of all `(p, q)` come from products of per-axis complex exponentials, so a
//! ray costs `(2L − 1)(2M − 1)` pairs of a few multiplications each and no trigonometric
//! call in the inner loop.

use crate::Shape;

/// A straight segment in the map frame (metres from the map's lower-left corner).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Start `s` (m).
    pub origin: [f64; 2],
    /// Unit direction `v`.
    pub direction: [f64; 2],
    /// Length `r` (m).
    pub length_m: f64,
}

/// Per-axis tables of one segment for the moment kernel (structure of arrays, so the inner
/// loop vectorizes): `cos`/`sin` of `k c̃` at the midpoint and of `k ũ` (half-length phase),
/// and `k ũ` itself, for `k < n`.
#[derive(Default)]
struct AxisTables {
    mid_cos: Vec<f64>,
    mid_sin: Vec<f64>,
    half_cos: Vec<f64>,
    half_sin: Vec<f64>,
    u: Vec<f64>,
}

impl AxisTables {
    fn fill(&mut self, n: usize, mid_phase: f64, half_phase: f64) {
        for v in [
            &mut self.mid_cos,
            &mut self.mid_sin,
            &mut self.half_cos,
            &mut self.half_sin,
            &mut self.u,
        ] {
            v.clear();
        }
        for k in 0..n {
            let kf = k as f64;
            let (s, c) = (kf * mid_phase).sin_cos();
            self.mid_cos.push(c);
            self.mid_sin.push(s);
            let (s, c) = (kf * half_phase).sin_cos();
            self.half_cos.push(c);
            self.half_sin.push(s);
            self.u.push(kf * half_phase);
        }
    }
}

/// `sin(u) / u`, with the series `1 − u²/6` where `|u| ≤ 1e-4` (branch-free select).
#[inline(always)]
fn sinc_over(sin_u: f64, u: f64) -> f64 {
    let small = u.abs() <= 1e-4;
    let ratio = sin_u / if small { 1.0 } else { u };
    if small { 1.0 - u * u / 6.0 } else { ratio }
}

thread_local! {
    static TABLES: std::cell::RefCell<(AxisTables, AxisTables)> = Default::default();
}

/// Adds `weight · T_pq(segment)` for `p < P`, `q < Q` of `shape` to `out` (length `P · Q`,
/// row-major `p · Q + q`) for a map of extent `extent_m = [X, Y]`.
pub fn add_moments(shape: Shape, extent_m: [f64; 2], seg: &Segment, weight: f64, out: &mut [f64]) {
    let (pn, qn) = (shape.p(), shape.q());
    let r = seg.length_m;
    if r.is_nan() || r <= 0.0 || out.len() < pn * qn {
        return;
    }
    let sx = std::f64::consts::PI / extent_m[0];
    let sy = std::f64::consts::PI / extent_m[1];
    let mid_x = (seg.origin[0] + seg.direction[0] * r * 0.5) * sx;
    let mid_y = (seg.origin[1] + seg.direction[1] * r * 0.5) * sy;
    let half_x = seg.direction[0] * r * 0.5 * sx;
    let half_y = seg.direction[1] * r * 0.5 * sy;
    let scale = 0.5 * r * weight;
    TABLES.with(|cell| {
        let (tx, ty) = &mut *cell.borrow_mut();
        tx.fill(pn, mid_x, half_x);
        ty.fill(qn, mid_y, half_y);
        for p in 0..pn {
            let (mxr, mxi) = (tx.mid_cos[p], tx.mid_sin[p]);
            let (hxr, hxi) = (tx.half_cos[p], tx.half_sin[p]);
            let ux = tx.u[p];
            let row = &mut out[p * qn..(p + 1) * qn];
            let it = row
                .iter_mut()
                .zip(&ty.mid_cos)
                .zip(&ty.mid_sin)
                .zip(&ty.half_cos)
                .zip(&ty.half_sin)
                .zip(&ty.u);
            for (((((o, &myr), &myi), &hyr), &hyi), &uy) in it {
                // cos(p x̃ ± q ỹ) at the midpoint, sin(p ũx ± q ũy) of the half length.
                let (rr, ii) = (mxr * myr, mxi * myi);
                let (cos_p, cos_m) = (rr - ii, rr + ii);
                let (a, b) = (hxr * hyi, hxi * hyr);
                let (sin_p, sin_m) = (b + a, b - a);
                // Eq. (9.10), sinc form: r cos(φ + ω r/2) sinc(ω r/2).
                *o +=
                    scale * (cos_p * sinc_over(sin_p, ux + uy) + cos_m * sinc_over(sin_m, ux - uy));
            }
        }
    });
}

/// `T_pq` of one segment (a fresh vector of length `P · Q`).
pub fn moments(shape: Shape, extent_m: [f64; 2], seg: &Segment) -> Vec<f64> {
    let mut out = vec![0.0; shape.spectrum_len()];
    add_moments(shape, extent_m, seg, 1.0, &mut out);
    out
}

/// `cos(k c̃)` for `k < n` at coordinate `c` (m) on an axis of length `extent` (m).
pub fn cosines(n: usize, c: f64, extent: f64) -> impl Iterator<Item = f64> {
    let phase = std::f64::consts::PI * c / extent;
    (0..n).map(move |k| (k as f64 * phase).cos())
}
