//! Numerical helpers shared by the model tests: ln Γ, adaptive Simpson, Gauss–Legendre.

#![allow(dead_code)]

/// ln Γ(x) for x > 0 (a reference independent of the crate's own code: `statrs`).
pub fn ln_gamma(x: f64) -> f64 {
    statrs::function::gamma::ln_gamma(x)
}

/// Adaptive Simpson quadrature of `f` over `[a, b]` to absolute tolerance `tol`.
pub fn simpson(f: &impl Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> f64 {
    fn step(
        f: &impl Fn(f64) -> f64,
        a: f64,
        b: f64,
        fa: f64,
        fm: f64,
        fb: f64,
        whole: f64,
        tol: f64,
        depth: u32,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
        let delta = left + right - whole;
        if depth == 0 || delta.abs() <= 15.0 * tol {
            left + right + delta / 15.0
        } else {
            step(f, a, m, fa, flm, fm, left, tol / 2.0, depth - 1)
                + step(f, m, b, fm, frm, fb, right, tol / 2.0, depth - 1)
        }
    }
    let (fa, fb, fm) = (f(a), f(b), f(0.5 * (a + b)));
    let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    step(f, a, b, fa, fm, fb, whole, tol, 50)
}

/// 10-point Gauss–Legendre on `[a, b]` split into `pieces` equal parts (open rule: never
/// evaluates `f` at the ends).
pub fn gauss_legendre(f: &impl Fn(f64) -> f64, a: f64, b: f64, pieces: usize) -> f64 {
    const X: [f64; 5] = [
        0.148_874_338_981_631_2,
        0.433_395_394_129_247_2,
        0.679_409_568_299_024_4,
        0.865_063_366_688_984_5,
        0.973_906_528_517_171_7,
    ];
    const W: [f64; 5] = [
        0.295_524_224_714_752_9,
        0.269_266_719_309_996_4,
        0.219_086_362_515_982_04,
        0.149_451_349_150_580_6,
        0.066_671_344_308_688_14,
    ];
    let h = (b - a) / pieces as f64;
    let mut total = 0.0;
    for p in 0..pieces {
        let lo = a + p as f64 * h;
        let (c, r) = (lo + 0.5 * h, 0.5 * h);
        for (x, w) in X.iter().zip(W) {
            total += w * r * (f(c - r * x) + f(c + r * x));
        }
    }
    total
}
