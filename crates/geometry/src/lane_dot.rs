//! [`lane_dot`]: a dot product with a fixed summation order that the compiler vectorizes.

use std::iter::Sum;
use std::ops::{Add, AddAssign, Mul};

/// The dot product of `a` and `b` (over their common length) in eight independent partial
/// sums: element `k` of the full chunks of eight goes to sum `k % 8`, the eight sums are
/// added in order and the products of the last `len % 8` elements after them. The order is
/// fixed, so the result is deterministic (the same bits on every run and machine), and the
/// independent sums let the loop vectorize. For `f32` and `f64`; the kernel of the cosine
/// similarities of global image descriptors and of kernel logistic regressions.
///
/// ```
/// use raypath_geometry::lane_dot;
///
/// let a: Vec<f64> = (0..11).map(f64::from).collect();
/// assert_eq!(lane_dot(&a, &a), 385.0);
/// assert_eq!(lane_dot(&[1.5f32, 2.0], &[2.0, -1.0]), 1.0);
/// ```
#[inline]
pub fn lane_dot<T>(a: &[T], b: &[T]) -> T
where
    T: Copy + Default + Add<Output = T> + AddAssign + Mul<Output = T> + Sum<T>,
{
    let mut acc = [T::default(); 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: T = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(&x, &y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for ((s, &xv), &yv) in acc.iter_mut().zip(x).zip(y) {
            *s += xv * yv;
        }
    }
    acc.into_iter().sum::<T>() + tail
}
