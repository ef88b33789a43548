//! Shared helpers of the integration tests.
#![allow(missing_docs)]
#![allow(dead_code)]
#![allow(clippy::unwrap_used)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_dct_map::{DctMap, MapRay, Outcome, Shape};

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// A map with random coefficients around a positive mean amplitude.
pub fn random_map(seed: u64, extent: [f64; 2], shape: Shape) -> DctMap {
    let mut r = rng(seed);
    let mut a: Vec<f64> = (0..shape.len())
        .map(|_| r.random_range(-0.3..0.3))
        .collect();
    a[0] = 0.8;
    DctMap::new(extent, shape, a).unwrap()
}

/// A random ray inside the extent with the given outcome.
pub fn random_ray(r: &mut ChaCha8Rng, extent: [f64; 2], outcome: Outcome) -> MapRay {
    let o = [
        r.random_range(0.0..extent[0]),
        r.random_range(0.0..extent[1]),
    ];
    let angle: f64 = r.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let len = r.random_range(0.3..3.0);
    MapRay::from_angle(o, angle, len, outcome)
}

/// `n` random rays ([`random_ray`]) from `r`, the `k`-th with outcome
/// `outcomes[k % outcomes.len()]`.
pub fn random_rays(
    r: &mut ChaCha8Rng,
    extent: [f64; 2],
    n: usize,
    outcomes: &[Outcome],
) -> Vec<MapRay> {
    (0..n)
        .map(|k| random_ray(r, extent, outcomes[k % outcomes.len()]))
        .collect()
}

/// Composite Simpson rule of `f` on `[0, len]` with `n` (even) intervals.
pub fn simpson(f: impl Fn(f64) -> f64, len: f64, n: usize) -> f64 {
    let h = len / n as f64;
    let mut s = f(0.0) + f(len);
    for i in 1..n {
        s += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}
