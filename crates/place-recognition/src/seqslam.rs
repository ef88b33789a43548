//! Sequence matching (SeqSLAM; Milford & Wyeth, ICRA 2012), fed by **any** per-image method:
//! the similarities of a query-against-database run ([`ScoreMatrix`]) become a difference
//! matrix, its contrast is enhanced locally, and each query's match is the straight line
//! through the last `d_s` queries with the smallest summed enhanced difference.
//!
//! 1. **Difference matrix**: `D(q, j) = s_max(q) − s(q, j)` per query row (so `D ≥ 0`, 0 at
//!    the best frame); frames the method did not propose get the row's largest difference.
//!    For the raw-pixel baseline this is the paper's mean absolute difference up to a
//!    per-row constant.
//! 2. **Local contrast enhancement** (Eq. (2)): `D̂(q, j) = (D(q, j) − D̄_l) / σ_l`, with the
//!    mean and standard deviation of `D(q, ·)` over the window of `R_window` database frames
//!    centred on `j` (clipped at the ends; `σ_l` at least 10⁻⁹).
//! 3. **Sequence search** (Eqs. (3)–(4)): for query `q`, database frame `j` and velocity `v`
//!    from `V_min` to `V_max` in `velocity_steps` even steps, the line score is
//!    `S = (1/n) Σ_{k=0}^{n−1} D̂(q − k, j − round(v k))` with `n = min(d_s, q + 1)` (the
//!    queries up to `q` only: online, ours — the paper centres the window); a line that
//!    leaves the database (`j < round(v (n − 1))`) is not tried — shorter lines would be
//!    noisier and win by chance. The sequence score of `(q, j)` is `−min_v S` (higher = more
//!    similar), NaN (not proposed) when no line fits.
//!
//! The paper accepts a match by the ratio of the best to the second best sequence score
//! outside a window: [`crate::Confidence::Margin`] sweeps the threshold over that margin. Cost per query: `O(N · velocity_steps · d_s)` for `N`
//! database frames, plus `O(N)` for the contrast enhancement of its row.

use rayon::prelude::*;

use crate::{PlaceError, Result, ScoreMatrix};

/// Parameters of sequence matching.
#[derive(Clone, Debug, PartialEq)]
pub struct SequenceConfig {
    /// Sequence length `d_s` in queries (default 10; 1 = single-image matching on the enhanced
    /// differences).
    pub length: usize,
    /// Window `R_window` of the local contrast enhancement, database frames (default 10).
    pub contrast_window: usize,
    /// Smallest velocity `V_min`, database frames per query (default 0.8).
    pub min_velocity: f64,
    /// Largest velocity `V_max` (default 1.25).
    pub max_velocity: f64,
    /// Number of velocities tried, evenly spaced from `V_min` to `V_max` (default 5).
    pub velocity_steps: usize,
}

impl Default for SequenceConfig {
    fn default() -> Self {
        Self {
            length: 10,
            contrast_window: 10,
            min_velocity: 0.8,
            max_velocity: 1.25,
            velocity_steps: 5,
        }
    }
}

impl SequenceConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, reason: String| Err(PlaceError::InvalidParameter { name, reason });
        if self.length == 0 {
            return bad("length (d_s)", "must be at least 1".into());
        }
        if self.contrast_window < 2 {
            return bad("contrast_window", "must be at least 2 frames".into());
        }
        if self.velocity_steps == 0 {
            return bad("velocity_steps", "must be at least 1".into());
        }
        let (lo, hi) = (self.min_velocity, self.max_velocity);
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) {
            return bad(
                "velocity",
                format!("need 0 ≤ V_min ≤ V_max, got {lo} and {hi}"),
            );
        }
        Ok(())
    }

    /// The velocities tried.
    fn velocities(&self) -> Vec<f64> {
        let n = self.velocity_steps;
        if n == 1 {
            return vec![0.5 * (self.min_velocity + self.max_velocity)];
        }
        (0..n)
            .map(|k| {
                self.min_velocity
                    + (self.max_velocity - self.min_velocity) * k as f64 / (n - 1) as f64
            })
            .collect()
    }
}

/// Step 1: the difference row of one similarity row (module documentation).
pub fn difference_row(scores: &[f32]) -> Vec<f32> {
    let finite = scores.iter().copied().filter(|s| s.is_finite());
    let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), s| {
        (lo.min(s), hi.max(s))
    });
    if lo > hi {
        return vec![0.0; scores.len()];
    }
    scores
        .iter()
        .map(|&s| if s.is_finite() { hi - s } else { hi - lo })
        .collect()
}

/// Step 2: local contrast enhancement of one difference row over a window of `window` frames
/// (Milford & Wyeth 2012, Eq. (2)); prefix sums make it `O(N)`.
pub fn enhance_row(differences: &[f32], window: usize) -> Vec<f32> {
    let n = differences.len();
    let (mut sum, mut sum2) = (vec![0.0f64; n + 1], vec![0.0f64; n + 1]);
    for (j, &d) in differences.iter().enumerate() {
        sum[j + 1] = sum[j] + f64::from(d);
        sum2[j + 1] = sum2[j] + f64::from(d) * f64::from(d);
    }
    let half = window / 2;
    (0..n)
        .map(|j| {
            let (a, b) = (j.saturating_sub(half), (j + window - half).min(n));
            let m = (b - a) as f64;
            let mean = (sum[b] - sum[a]) / m;
            let var = ((sum2[b] - sum2[a]) / m - mean * mean).max(0.0);
            ((f64::from(differences[j]) - mean) / var.sqrt().max(1e-9)) as f32
        })
        .collect()
}

/// The enhanced difference matrix (steps 1 and 2 on every query row), in parallel.
pub fn enhanced_differences(scores: &ScoreMatrix, config: &SequenceConfig) -> Result<ScoreMatrix> {
    config.validate()?;
    let rows: Vec<Vec<f32>> = (0..scores.queries())
        .into_par_iter()
        .map(|q| enhance_row(&difference_row(scores.row(q)), config.contrast_window))
        .collect();
    ScoreMatrix::from_rows(scores.queries(), scores.database(), rows.concat())
}

/// Step 3 for query `q` over an enhanced difference matrix: the sequence score of every
/// database frame (higher = more similar).
pub fn sequence_row(enhanced: &ScoreMatrix, q: usize, config: &SequenceConfig) -> Vec<f32> {
    let n = enhanced.database();
    let steps = config.length.min(q + 1);
    let rows: Vec<&[f32]> = (0..steps).map(|k| enhanced.row(q - k)).collect();
    let velocities = config.velocities();
    // Offsets round(v k) per velocity and step.
    let offsets: Vec<Vec<usize>> = velocities
        .iter()
        .map(|v| {
            (0..steps)
                .map(|k| (v * k as f64).round() as usize)
                .collect()
        })
        .collect();
    (0..n)
        .map(|j| {
            let mut best = f32::INFINITY;
            for off in offsets.iter().filter(|off| off[steps - 1] <= j) {
                let total: f32 = rows.iter().zip(off).map(|(row, &o)| row[j - o]).sum();
                best = best.min(total / steps as f32);
            }
            // No line fits inside the database: not proposed.
            if best.is_finite() { -best } else { f32::NAN }
        })
        .collect()
}

/// Sequence matching of a query-against-database similarity matrix (module documentation):
/// the matrix of sequence scores, same shape. Each query row depends on itself and the
/// `d_s − 1` queries before it only.
pub fn sequence_match(scores: &ScoreMatrix, config: &SequenceConfig) -> Result<ScoreMatrix> {
    let enhanced = enhanced_differences(scores, config)?;
    let rows: Vec<Vec<f32>> = (0..scores.queries())
        .into_par_iter()
        .map(|q| sequence_row(&enhanced, q, config))
        .collect();
    ScoreMatrix::from_rows(scores.queries(), scores.database(), rows.concat())
}

/// [`sequence_match`] on one thread, with the mean time per query in milliseconds (the
/// enhancement of its row and its line search).
pub fn sequence_match_timed(
    scores: &ScoreMatrix,
    config: &SequenceConfig,
) -> Result<(ScoreMatrix, f64)> {
    config.validate()?;
    let start = std::time::Instant::now();
    let rows: Vec<f32> = (0..scores.queries())
        .flat_map(|q| enhance_row(&difference_row(scores.row(q)), config.contrast_window))
        .collect();
    let enhanced = ScoreMatrix::from_rows(scores.queries(), scores.database(), rows)?;
    let rows: Vec<f32> = (0..scores.queries())
        .flat_map(|q| sequence_row(&enhanced, q, config))
        .collect();
    let ms = 1e3 * start.elapsed().as_secs_f64() / scores.queries().max(1) as f64;
    Ok((
        ScoreMatrix::from_rows(scores.queries(), scores.database(), rows)?,
        ms,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Confidence, CrossTruth, cross_summary};

    /// splitmix64 in [0, 1).
    fn noise(seed: u64) -> f32 {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn enhancement_has_zero_mean_in_a_flat_window() {
        let d = [1.0f32, 3.0, 1.0, 3.0, 1.0, 3.0];
        let e = enhance_row(&d, 12);
        // One window covers the whole row: mean 2, σ 1.
        assert!(e.iter().zip(&d).all(|(e, d)| (e - (d - 2.0)).abs() < 1e-6));
        assert_eq!(difference_row(&[0.5, f32::NAN, 0.25]), [0.0, 0.25, 0.25]);
    }

    #[test]
    fn sequences_recover_matches_single_images_miss() {
        // 60 queries against 60 database frames, query q at frame q; single-image scores are
        // noise plus a weak true signal, so single images often fail while lines of 10 win.
        let n = 60;
        let mut rows = Vec::new();
        for q in 0..n {
            for j in 0..n {
                let signal = if q == j { 0.35 } else { 0.0 };
                rows.push(noise((q * 1000 + j) as u64) + signal);
            }
        }
        let scores = ScoreMatrix::from_rows(n, n, rows).expect("n × n");
        let truth = CrossTruth::from_frames((0..n).map(Some).collect(), n, 0);
        let single = cross_summary(&scores, &truth, Confidence::Score).expect("single");
        let seq = sequence_match(&scores, &SequenceConfig::default()).expect("seq");
        let (timed, _) = sequence_match_timed(&scores, &SequenceConfig::default()).expect("timed");
        let bits = |m: &ScoreMatrix| -> Vec<u32> {
            (0..n)
                .flat_map(|q| m.row(q).iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                .collect()
        };
        assert!(bits(&seq) == bits(&timed), "parallel and timed runs differ");
        let s = cross_summary(&seq, &truth, Confidence::Score).expect("sequence");
        assert!(single.recall_at_1 < 0.8, "{single:?}");
        // Queries 9.. have full sequences; at least 95 % of them find their frame (the noise
        // is random: a rare noise line can still win).
        let full = (9..n).filter(|&q| seq.best(q, 1)[0].frame == q).count();
        assert!(full as f64 >= 0.95 * (n - 9) as f64, "{full} {s:?}");
        assert!(s.recall_at_1 > single.recall_at_1);
    }

    #[test]
    fn invalid_parameters_are_refused() {
        let m = ScoreMatrix::new(2, 2);
        for bad in [
            SequenceConfig {
                length: 0,
                ..SequenceConfig::default()
            },
            SequenceConfig {
                contrast_window: 1,
                ..SequenceConfig::default()
            },
            SequenceConfig {
                min_velocity: 2.0,
                ..SequenceConfig::default()
            },
        ] {
            assert!(sequence_match(&m, &bad).is_err());
        }
    }
}
