//! Exact Euclidean distance transform (Felzenszwalb & Huttenlocher 2012).
//!
//! P. F. Felzenszwalb and D. P. Huttenlocher, "Distance transforms of sampled functions",
//! *Theory of Computing* 8, 2012. The squared distance transform separates into 1-D
//! transforms along each axis; the 1-D transform is the lower envelope of the parabolas
//! `(q − p)² + f(p)`, computed in linear time. Exact (not a chamfer approximation), `O(n)`
//! per axis for `n` cells.

/// Squared Euclidean distance, in cells², from every cell to the nearest `site` cell, on a
/// grid of `dims` cells (x fastest, then y, then z; use `dims[2] = 1` in 2-D). Cells are
/// `+∞` when there is no site at all. `sites.len()` must equal the number of cells (extra
/// cells are ignored, missing ones count as non-sites).
pub fn squared_distance_transform(dims: [usize; 3], sites: &[bool]) -> Vec<f64> {
    let n = dims[0] * dims[1] * dims[2];
    let mut grid: Vec<f64> = (0..n)
        .map(|i| {
            if sites.get(i).copied().unwrap_or(false) {
                0.0
            } else {
                f64::INFINITY
            }
        })
        .collect();
    let longest = dims.iter().copied().max().unwrap_or(0);
    let mut line = vec![0.0; longest];
    let mut out = vec![0.0; longest];
    let mut v = vec![0usize; longest];
    let mut z = vec![0.0; longest + 1];
    let strides = [1, dims[0], dims[0] * dims[1]];
    for axis in 0..3 {
        let len = dims[axis];
        if len <= 1 {
            continue;
        }
        let stride = strides[axis];
        // Every line along `axis`: its first cell has coordinate 0 along the axis.
        for start in 0..n {
            if (start / stride) % len != 0 {
                continue;
            }
            for (q, value) in line.iter_mut().take(len).enumerate() {
                *value = grid[start + q * stride];
            }
            transform_1d(&line[..len], &mut out[..len], &mut v, &mut z);
            for (q, value) in out.iter().take(len).enumerate() {
                grid[start + q * stride] = *value;
            }
        }
    }
    grid
}

/// 1-D squared distance transform `d(q) = min_p (q − p)² + f(p)` (Felzenszwalb &
/// Huttenlocher 2012, Algorithm 1), skipping `p` with `f(p) = +∞`.
fn transform_1d(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    let mut k = 0usize;
    let mut any = false;
    for q in 0..n {
        let fq = f[q];
        if !fq.is_finite() {
            continue;
        }
        if !any {
            any = true;
            v[0] = q;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
            continue;
        }
        let qf = q as f64;
        let mut s;
        loop {
            let p = v[k];
            let pf = p as f64;
            // Intersection of the parabolas rooted at q and p.
            s = ((fq + qf * qf) - (f[p] + pf * pf)) / (2.0 * (qf - pf));
            if s <= z[k] && k > 0 {
                k -= 1;
            } else {
                break;
            }
        }
        if s <= z[k] {
            // k == 0 and the new parabola dominates everywhere.
            v[0] = q;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
            continue;
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    if !any {
        d.fill(f64::INFINITY);
        return;
    }
    k = 0;
    for (q, out) in d.iter_mut().enumerate() {
        let qf = q as f64;
        while z[k + 1] < qf {
            k += 1;
        }
        let p = v[k];
        let dq = qf - p as f64;
        *out = dq * dq + f[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force on a small 3-D grid with random sites.
    #[test]
    fn matches_brute_force() {
        let dims = [7, 5, 4];
        let n = dims[0] * dims[1] * dims[2];
        let mut state = 12345u64;
        let sites: Vec<bool> = (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 60) == 0
            })
            .collect();
        let edt = squared_distance_transform(dims, &sites);
        let coords = |i: usize| {
            [
                (i % dims[0]) as f64,
                ((i / dims[0]) % dims[1]) as f64,
                (i / (dims[0] * dims[1])) as f64,
            ]
        };
        for (i, &got) in edt.iter().enumerate() {
            let a = coords(i);
            let best = (0..n)
                .filter(|&j| sites[j])
                .map(|j| {
                    let b = coords(j);
                    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
                })
                .fold(f64::INFINITY, f64::min);
            assert_eq!(got, best, "cell {i}");
        }
    }

    #[test]
    fn no_sites_and_2d() {
        assert!(
            squared_distance_transform([3, 3, 1], &[false; 9])
                .iter()
                .all(|d| d.is_infinite())
        );
        let mut sites = [false; 12];
        sites[0] = true;
        let edt = squared_distance_transform([4, 3, 1], &sites);
        assert_eq!(edt[4 * 2 + 3], 9.0 + 4.0);
    }
}
