//! Pole scores per voxel (Schaefer 2020, §12.4.1): for every footprint width `a` and every
//! voxel `j`, the best placement of an `a × a` footprint containing `j` of (mean occupancy
//! inside) − (max occupancy of the free hull of thickness `f` around it), remapped to `[0, 1]`.

use rayon::prelude::*;

use crate::filters::{Scratch, rect_max, summed_area};

/// Pole scores of a local map.
#[derive(Clone, Debug, PartialEq)]
pub struct ScoreVolume {
    /// Dimensions `(nx, ny, nz)`.
    pub dims: [usize; 3],
    /// Number of widths scored (`a = 1..=widths`).
    pub widths: usize,
    /// `Q = max_a q'_a` per voxel (linear index, x fastest), in `[0, 1]`. Scores at or below
    /// 1/2 (raw score ≤ 0: no evidence for a pole) are stored as 0, so slices and widths
    /// without any positive raw score skip the last filter pass; this is exact for every
    /// `q_min > 1/2` ([`PoleParams::min_score`](crate::PoleParams::min_score)).
    pub best: Vec<f32>,
    /// `q'_a` per width and voxel (0 at or below 1/2), quantized to `u8` (`q' ≈ v / 255`),
    /// width-major:
    /// `per_width[(a − 1) · n + j]`.
    pub per_width: Vec<u8>,
}

impl ScoreVolume {
    /// `q'_a` of voxel `index` (`a` from 1).
    #[inline]
    pub fn width_score(&self, a: usize, index: usize) -> f32 {
        let n = self.best.len();
        self.per_width
            .get((a - 1) * n + index)
            .map_or(0.0, |&v| v as f32 / 255.0)
    }
}

/// Computes the scores of an occupancy volume (`occupancy` per voxel, x fastest) with widths
/// `1..=widths` and hull thickness `hull` cells. Slices are scored in parallel.
pub fn pole_scores(occupancy: &[f32], dims: [usize; 3], widths: usize, hull: usize) -> ScoreVolume {
    pole_scores_with(occupancy, dims, widths, hull, Path::Auto)
}

/// How `q_a` is computed from the raw scores.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
enum Path {
    /// Scattered from the positive anchors when their footprints have fewer voxels than two
    /// slices (the scatter touches each footprint voxel three times, the rectangle maximum
    /// every voxel of the slice about ten times).
    #[default]
    Auto,
    /// Always scattered (tests).
    #[cfg(test)]
    Sparse,
    /// Always the rectangle maximum over the slice (tests).
    #[cfg(test)]
    Dense,
}

fn pole_scores_with(
    occupancy: &[f32],
    dims: [usize; 3],
    widths: usize,
    hull: usize,
    path: Path,
) -> ScoreVolume {
    let [nx, ny, nz] = dims;
    let n_slice = nx * ny;
    let n = n_slice * nz;
    let mut best = vec![0.0f32; n];
    let mut per_width = vec![0u8; widths * n];
    // Slice-major work: each task fills the best scores and its own per-width bytes.
    let mut width_slices: Vec<Vec<&mut [u8]>> = (0..nz).map(|_| Vec::new()).collect();
    for chunk in per_width.chunks_mut(n) {
        for (z, slice) in chunk.chunks_mut(n_slice).enumerate() {
            if let Some(list) = width_slices.get_mut(z) {
                list.push(slice);
            }
        }
    }
    best.par_chunks_mut(n_slice)
        .zip(occupancy.par_chunks(n_slice))
        .zip(width_slices.into_par_iter())
        .for_each_init(
            || SliceWork {
                path,
                ..SliceWork::default()
            },
            |work, ((best, occ), mut per_a)| {
                work.score_slice(occ, nx, ny, widths, hull, best, &mut per_a);
            },
        );
    ScoreVolume {
        dims,
        widths,
        best,
        per_width,
    }
}

#[derive(Default)]
struct SliceWork {
    scratch: Scratch,
    table: Vec<f64>,
    /// Max over `f` rows upwards: `max_{dy<f} o(x, y + dy)`.
    rows_f: Vec<f32>,
    /// Max over `f` columns rightwards: `max_{dx<f} o(x + dx, y)`.
    cols_f: Vec<f32>,
    /// `max_{dx<span} rows_f(x + dx, y)`: the horizontal hull strips, grown with the span.
    strip_h: Vec<f32>,
    /// `max_{dy<span} cols_f(x, y + dy)`: the vertical hull strips, grown with the span.
    strip_v: Vec<f32>,
    raw: Vec<f32>,
    /// Anchors (linear index in the slice) with a positive raw score, for the current width.
    positive: Vec<usize>,
    q: Vec<f32>,
    path: Path,
}

/// `acc(i) = max(acc(i), src(i + shift))` where `i + shift` is inside (a running window
/// maximum grown by one element; entries whose window leaves the slice are never read).
#[inline]
fn grow(acc: &mut [f32], src: &[f32], shift: usize) {
    if shift >= src.len() {
        return;
    }
    for (a, s) in acc.iter_mut().zip(&src[shift..]) {
        *a = a.max(*s);
    }
}

/// `q(j) = max raw(k)` over the `positive` anchors `k` whose `a × a` footprint
/// `[kx, kx + a) × [ky, ky + a)` contains `j`, written to the footprints only (other entries
/// of `q` are left as they are): the positive part of the rectangle maximum, for footprints
/// inside the slice.
fn scatter_max(raw: &[f32], positive: &[usize], nx: usize, a: usize, q: &mut [f32]) {
    for_footprints(positive, nx, a, q, |_, v| *v = -1.0);
    for &anchor in positive {
        let Some(&r) = raw.get(anchor) else {
            continue;
        };
        for_footprints(&[anchor], nx, a, q, |_, v| *v = v.max(r));
    }
}

/// Calls `f(index, &mut q[index])` for every voxel of the `a × a` footprints of `anchors`
/// (a voxel of overlapping footprints once per footprint).
#[inline]
fn for_footprints<T>(
    anchors: &[usize],
    nx: usize,
    a: usize,
    q: &mut [T],
    mut f: impl FnMut(usize, &mut T),
) {
    for &anchor in anchors {
        for dy in 0..a {
            let start = anchor + dy * nx;
            if let Some(row) = q.get_mut(start..start + a) {
                for (i, v) in row.iter_mut().enumerate() {
                    f(start + i, v);
                }
            }
        }
    }
}

/// Sets `raw` to −1 outside the anchors `[lo, hi_x] × [lo, hi_y]` of a slice `nx` wide.
fn clear_outside(raw: &mut [f32], nx: usize, lo: usize, hi_x: usize, hi_y: usize) {
    for (y, row) in raw.chunks_exact_mut(nx).enumerate() {
        if y < lo || y > hi_y {
            row.fill(-1.0);
        } else {
            for (x, v) in row.iter_mut().enumerate() {
                if x < lo || x > hi_x {
                    *v = -1.0;
                }
            }
        }
    }
}

impl SliceWork {
    #[allow(clippy::too_many_arguments)]
    fn score_slice(
        &mut self,
        occ: &[f32],
        nx: usize,
        ny: usize,
        widths: usize,
        f: usize,
        best: &mut [f32],
        per_a: &mut [&mut [u8]],
    ) {
        let n = nx * ny;
        // `best` and `per_a` arrive zeroed (fresh pages stay untouched where nothing scores).
        // A slice without occupied voxels cannot hold a pole (the inside mean is ≈ 0).
        if occ.iter().all(|&o| o < 0.05) || 1 + 2 * f > nx || 1 + 2 * f > ny {
            return;
        }
        summed_area(occ, nx, ny, &mut self.table);
        // Row/column maxima over the hull thickness f (once per slice).
        self.rows_f.clear();
        self.rows_f.extend_from_slice(occ);
        self.cols_f.clear();
        self.cols_f.extend_from_slice(occ);
        for d in 1..f {
            grow(&mut self.rows_f, occ, d * nx);
            grow(&mut self.cols_f, occ, d);
        }
        // Strips of span 2f (width a = 0), grown by one per width below.
        self.strip_h.clear();
        self.strip_h.extend_from_slice(&self.rows_f);
        self.strip_v.clear();
        self.strip_v.extend_from_slice(&self.cols_f);
        for s in 1..2 * f {
            grow(&mut self.strip_h, &self.rows_f, s);
            grow(&mut self.strip_v, &self.cols_f, s * nx);
        }
        self.raw.clear();
        self.raw.resize(n, -1.0);
        self.q.clear();
        self.q.resize(n, -1.0);
        for a in 1..=widths {
            let span = a + 2 * f;
            if span > nx || span > ny {
                break;
            }
            grow(&mut self.strip_h, &self.rows_f, span - 1);
            grow(&mut self.strip_v, &self.cols_f, (span - 1) * nx);
            self.positive.clear();
            let inv_area = 1.0 / (a * a) as f64;
            // Anchors kx ∈ [f, nx − a − f] of row ky, as zipped row slices (no index checks in
            // the loop; vectorizable).
            let count = nx - a - 2 * f + 1;
            let w = nx + 1;
            for ky in f..=(ny - a - f) {
                let t0 = &self.table[ky * w + f..][..count + a];
                let t1 = &self.table[(ky + a) * w + f..][..count + a];
                let below = &self.strip_h[(ky - f) * nx..][..count];
                let above = &self.strip_h[(ky + a) * nx..][..count];
                let left = &self.strip_v[(ky - f) * nx..][..count];
                let right = &self.strip_v[(ky - f) * nx + f + a..][..count];
                let out = &mut self.raw[ky * nx + f..][..count];
                let mut row_positive = false;
                for (i, o) in out.iter_mut().enumerate() {
                    // Box sum over [kx, kx + a) × [ky, ky + a) from the summed-area table.
                    let inside = (t1[i + a] - t1[i] - t0[i + a] + t0[i]) * inv_area;
                    let hull = below[i].max(above[i]).max(left[i]).max(right[i]);
                    let raw = inside as f32 - hull;
                    row_positive |= raw > 0.0;
                    *o = raw;
                }
                if row_positive {
                    let row = ky * nx + f;
                    self.positive.extend(
                        out.iter()
                            .enumerate()
                            .filter(|&(_, &r)| r > 0.0)
                            .map(|(i, _)| row + i),
                    );
                }
            }
            if self.positive.is_empty() {
                // No placement with evidence for a pole: every q'_a ≤ 1/2 is stored as 0.
                continue;
            }
            // q_a(j): best placement whose a × a footprint contains j (anchors j−a+1 ..= j).
            // Only q_a > 0 is used, i.e. the maximum over the positive anchors: scattered
            // from them when they are few (typical: poles are sparse), else the separable
            // rectangle maximum over the whole slice.
            let Some(bytes) = per_a.get_mut(a - 1) else {
                continue;
            };
            let update = |b: &mut f32, q: f32, out: &mut u8| {
                if q > 0.0 {
                    let remapped = 0.5 * q + 0.5; // q' = q/2 + 1/2 in [0, 1], as `poles.py`
                    *b = b.max(remapped);
                    *out = (remapped.min(1.0) * 255.0).round() as u8;
                }
            };
            let sparse = match self.path {
                Path::Auto => self.positive.len() * a * a < 2 * n,
                #[cfg(test)]
                Path::Sparse => true,
                #[cfg(test)]
                Path::Dense => false,
            };
            if sparse {
                scatter_max(&self.raw, &self.positive, nx, a, &mut self.q);
                let q = &self.q;
                for_footprints(&self.positive, nx, a, best, |j, b| {
                    if let (Some(&q), Some(out)) = (q.get(j), bytes.get_mut(j)) {
                        update(b, q, out);
                    }
                });
            } else {
                clear_outside(&mut self.raw, nx, f, nx - a - f, ny - a - f);
                let lo = -(a as isize - 1);
                rect_max(
                    &self.raw,
                    nx,
                    ny,
                    (lo, a),
                    (lo, a),
                    -1.0,
                    &mut self.q,
                    &mut self.scratch,
                );
                for ((b, &q), out) in best.iter_mut().zip(&self.q).zip(bytes.iter_mut()) {
                    update(b, q, out);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sparse_and_dense_paths_give_the_same_scores() {
        // Occupancy with isolated occupied voxels and blocks (poles of several widths), a
        // wall, and pseudo-random clutter; the sparse path is taken for some widths and
        // slices in `Auto`, so compare all three.
        let dims = [40, 33, 4];
        let occupancy: Vec<f32> = (0..dims[0] * dims[1] * dims[2])
            .map(|i| {
                let (x, y, z) = (
                    i % dims[0],
                    (i / dims[0]) % dims[1],
                    i / (dims[0] * dims[1]),
                );
                let pole = (x % 9 < 1 + z % 3) && (y % 8 < 1 + (x / 9) % 3);
                let wall = y == 30;
                let clutter = ((i * 2654435761) >> 7) % 97;
                if pole || wall {
                    0.9 + (clutter % 10) as f32 * 0.01
                } else {
                    clutter as f32 / 400.0
                }
            })
            .collect();
        for hull in [1, 2] {
            let auto = pole_scores_with(&occupancy, dims, 6, hull, Path::Auto);
            let sparse = pole_scores_with(&occupancy, dims, 6, hull, Path::Sparse);
            let dense = pole_scores_with(&occupancy, dims, 6, hull, Path::Dense);
            assert!(dense.best.iter().filter(|&&b| b > 0.6).count() > 50);
            assert_eq!(auto, dense, "hull {hull}");
            assert_eq!(sparse, dense, "hull {hull}");
        }
    }

    #[test]
    fn scattered_maxima_equal_the_rectangle_maximum_where_positive() {
        let (nx, ny) = (23, 17);
        for (a, density) in [(1, 3), (2, 5), (3, 11), (5, 40)] {
            // Raw scores in [−1, 1): positive at about one anchor in `density`, and only at
            // anchors whose footprint lies inside the slice (as in `score_slice`).
            let raw: Vec<f32> = (0..nx * ny)
                .map(|i| {
                    let (x, y) = (i % nx, i / nx);
                    let v = ((i * 7919 + 13) % 1000) as f32 / 1000.0;
                    if x + a <= nx && y + a <= ny && (i * 31) % density == 0 {
                        v
                    } else {
                        -v
                    }
                })
                .collect();
            let positive: Vec<usize> = (0..raw.len()).filter(|&i| raw[i] > 0.0).collect();
            assert!(!positive.is_empty());
            let mut scattered = vec![-1.0; nx * ny];
            scatter_max(&raw, &positive, nx, a, &mut scattered);
            let mut dense = vec![0.0; nx * ny];
            let lo = -(a as isize - 1);
            let mut scratch = Scratch::default();
            rect_max(
                &raw,
                nx,
                ny,
                (lo, a),
                (lo, a),
                -1.0,
                &mut dense,
                &mut scratch,
            );
            for (j, (&s, &d)) in scattered.iter().zip(&dense).enumerate() {
                if d > 0.0 || s > 0.0 {
                    assert_eq!(s, d, "a {a} voxel {j}");
                }
            }
        }
    }
}
