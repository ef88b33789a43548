//! Separable 2-D filters on one horizontal slice (row-major, x fastest): rectangle maxima by
//! the van Herk / Gil-Werman algorithm (three comparisons per element whatever the window)
//! and box sums from a summed-area table. No per-pixel loop over a neighbourhood.

/// Reusable buffers of the filters.
#[derive(Default)]
pub(crate) struct Scratch {
    ext: Vec<f32>,
    prefix: Vec<f32>,
    suffix: Vec<f32>,
    tmp: Vec<f32>,
}

/// `out[i] = max(input[i + lo .. i + lo + w])` with `pad` outside `input` (`w ≥ 1`).
pub(crate) fn sliding_max(
    input: &[f32],
    lo: isize,
    w: usize,
    pad: f32,
    out: &mut [f32],
    s: &mut Scratch,
) {
    let n = input.len();
    let w = w.max(1);
    let m = n + w - 1;
    s.ext.clear();
    s.ext.extend((0..m).map(|k| {
        let j = k as isize + lo;
        if j >= 0 && (j as usize) < n {
            input[j as usize]
        } else {
            pad
        }
    }));
    s.prefix.clear();
    s.prefix.resize(m, pad);
    s.suffix.clear();
    s.suffix.resize(m, pad);
    // Block-wise running maxima from the left (prefix) and from the right (suffix).
    let mut block = 0;
    while block < m {
        let end = (block + w).min(m);
        let mut run = f32::NEG_INFINITY;
        for k in block..end {
            run = run.max(s.ext[k]);
            s.prefix[k] = run;
        }
        let mut run = f32::NEG_INFINITY;
        for k in (block..end).rev() {
            run = run.max(s.ext[k]);
            s.suffix[k] = run;
        }
        block = end;
    }
    for (i, o) in out.iter_mut().enumerate().take(n) {
        // Window [i, i + w) in ext: suffix of its first block and prefix of its last block.
        *o = s.suffix[i].max(s.prefix[i + w - 1]);
    }
}

/// `out(x, y) = max input over [x + lo_x, x + lo_x + w) × [y + lo_y, y + lo_y + h)`, `pad`
/// outside the slice of `nx × ny`. Both passes run van Herk / Gil-Werman; the vertical pass
/// works on whole rows (contiguous memory).
#[allow(clippy::too_many_arguments)]
pub(crate) fn rect_max(
    input: &[f32],
    nx: usize,
    ny: usize,
    (lo_x, w): (isize, usize),
    (lo_y, h): (isize, usize),
    pad: f32,
    out: &mut [f32],
    s: &mut Scratch,
) {
    let mut tmp = std::mem::take(&mut s.tmp);
    tmp.clear();
    tmp.resize(nx * ny, pad);
    for (row_in, row_out) in input.chunks_exact(nx).zip(tmp.chunks_exact_mut(nx)) {
        sliding_max(row_in, lo_x, w, pad, row_out, s);
    }
    sliding_max_rows(&tmp, nx, ny, lo_y, h, pad, out, s);
    s.tmp = tmp;
}

/// Row `i` of `out` = element-wise max of rows `[i + lo, i + lo + w)` of `input` (`pad`
/// rows outside), by van Herk / Gil-Werman over whole rows.
#[allow(clippy::too_many_arguments)]
fn sliding_max_rows(
    input: &[f32],
    nx: usize,
    ny: usize,
    lo: isize,
    w: usize,
    pad: f32,
    out: &mut [f32],
    s: &mut Scratch,
) {
    let w = w.max(1);
    let m = ny + w - 1;
    let row = |k: usize| -> Option<&[f32]> {
        let j = k as isize + lo;
        (j >= 0 && (j as usize) < ny).then(|| &input[j as usize * nx..(j as usize + 1) * nx])
    };
    s.prefix.clear();
    s.prefix.resize(m * nx, pad);
    s.suffix.clear();
    s.suffix.resize(m * nx, pad);
    let mut block = 0;
    while block < m {
        let end = (block + w).min(m);
        for k in block..end {
            let (before, current) = s.prefix.split_at_mut(k * nx);
            let current = &mut current[..nx];
            match row(k) {
                Some(r) => current.copy_from_slice(r),
                None => current.fill(pad),
            }
            if k > block {
                let previous = &before[(k - 1) * nx..];
                for (c, p) in current.iter_mut().zip(previous) {
                    *c = c.max(*p);
                }
            }
        }
        for k in (block..end).rev() {
            let (current, after) = s.suffix.split_at_mut((k + 1) * nx);
            let current = &mut current[k * nx..];
            match row(k) {
                Some(r) => current.copy_from_slice(r),
                None => current.fill(pad),
            }
            if k + 1 < end {
                for (c, n) in current.iter_mut().zip(&after[..nx]) {
                    *c = c.max(*n);
                }
            }
        }
        block = end;
    }
    for (i, out_row) in out.chunks_exact_mut(nx).enumerate().take(ny) {
        let a = &s.suffix[i * nx..(i + 1) * nx];
        let b = &s.prefix[(i + w - 1) * nx..(i + w) * nx];
        for ((o, x), y) in out_row.iter_mut().zip(a).zip(b) {
            *o = x.max(*y);
        }
    }
}

/// Summed-area table of a slice: `table[(y)(nx+1) + x]` = sum over `[0, x) × [0, y)`.
pub(crate) fn summed_area(input: &[f32], nx: usize, ny: usize, table: &mut Vec<f64>) {
    table.clear();
    table.resize((nx + 1) * (ny + 1), 0.0);
    for y in 0..ny {
        let mut row = 0.0f64;
        for x in 0..nx {
            row += input[y * nx + x] as f64;
            table[(y + 1) * (nx + 1) + x + 1] = table[y * (nx + 1) + x + 1] + row;
        }
    }
}

/// The sum over `[x, x + w) × [y, y + h)` from a summed-area table (the box must lie inside).
#[inline]
#[cfg(test)]
pub(crate) fn box_sum(table: &[f64], nx: usize, x: usize, y: usize, w: usize, h: usize) -> f64 {
    let s = nx + 1;
    table[(y + h) * s + x + w] - table[y * s + x + w] - table[(y + h) * s + x] + table[y * s + x]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sliding_max_matches_brute_force() {
        let input: Vec<f32> = (0..37).map(|i| ((i * 7919) % 23) as f32).collect();
        let mut s = Scratch::default();
        for w in 1..9 {
            for lo in -5..3 {
                let mut out = vec![0.0; input.len()];
                sliding_max(&input, lo, w, -1.0, &mut out, &mut s);
                for (i, o) in out.iter().enumerate() {
                    let brute = (0..w)
                        .map(|k| {
                            let j = i as isize + lo + k as isize;
                            if j >= 0 && (j as usize) < input.len() {
                                input[j as usize]
                            } else {
                                -1.0
                            }
                        })
                        .fold(f32::NEG_INFINITY, f32::max);
                    assert_eq!(*o, brute, "w {w} lo {lo} i {i}");
                }
            }
        }
    }

    #[test]
    fn rect_max_and_box_sum_match_brute_force() {
        let (nx, ny) = (11, 7);
        let input: Vec<f32> = (0..nx * ny).map(|i| ((i * 31) % 17) as f32).collect();
        let mut s = Scratch::default();
        let mut out = vec![0.0; nx * ny];
        rect_max(&input, nx, ny, (-1, 3), (2, 2), 0.5, &mut out, &mut s);
        for y in 0..ny {
            for x in 0..nx {
                let mut best = f32::NEG_INFINITY;
                for dy in 0..2 {
                    for dx in 0..3 {
                        let (xx, yy) = (x as isize - 1 + dx, y as isize + 2 + dy);
                        let v = if xx >= 0 && yy >= 0 && (xx as usize) < nx && (yy as usize) < ny {
                            input[yy as usize * nx + xx as usize]
                        } else {
                            0.5
                        };
                        best = best.max(v);
                    }
                }
                assert_eq!(out[y * nx + x], best);
            }
        }
        let mut table = Vec::new();
        summed_area(&input, nx, ny, &mut table);
        let brute: f32 = (2..5)
            .flat_map(|y| (3..7).map(move |x| (x, y)))
            .map(|(x, y)| input[y * nx + x])
            .sum();
        assert!((box_sum(&table, nx, 3, 2, 4, 3) - brute as f64).abs() < 1e-9);
    }
}
