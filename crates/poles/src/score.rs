//! Pole scores per voxel (spec §3.1): for every footprint width `a` and every voxel `j`, the
//! best placement of an `a × a` footprint containing `j` of (mean occupancy inside) − (max
//! occupancy of the free hull of thickness `f` around it), remapped to `[0, 1]`.

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
        .for_each_init(SliceWork::default, |work, ((best, occ), mut per_a)| {
            work.score_slice(occ, nx, ny, widths, hull, best, &mut per_a);
        });
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
/// `[kx, kx + a) × [ky, ky + a)` contains `j`, −1 where none does: the positive part of the
/// rectangle maximum, for footprints inside the slice.
fn scatter_max(raw: &[f32], positive: &[usize], nx: usize, a: usize, q: &mut [f32]) {
    q.fill(-1.0);
    for &anchor in positive {
        let Some(&r) = raw.get(anchor) else {
            continue;
        };
        for dy in 0..a {
            if let Some(row) = q.get_mut(anchor + dy * nx..anchor + dy * nx + a) {
                for v in row {
                    *v = v.max(r);
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
        best.fill(0.0);
        for s in per_a.iter_mut() {
            s.fill(0);
        }
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
            self.raw.fill(-1.0);
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
            if self.positive.len() * a * a < n / 4 {
                scatter_max(&self.raw, &self.positive, nx, a, &mut self.q);
            } else {
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
            }
            let Some(bytes) = per_a.get_mut(a - 1) else {
                continue;
            };
            for ((b, &q), out) in best.iter_mut().zip(&self.q).zip(bytes.iter_mut()) {
                if q > 0.0 {
                    let remapped = 0.5 * q + 0.5; // errata 12: q' = q/2 + 1/2
                    *b = b.max(remapped);
                    *out = (remapped.min(1.0) * 255.0).round() as u8;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            let mut scattered = vec![0.0; nx * ny];
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
