//! Loop-closure hypotheses and the modified Jaccard similarity of IBuILD (Khan 2017, §4.4.3).
//!
//! The hypotheses `L` are the images `< before` that share an old word with the current image
//! (through the inverted index). For a hypothesis `I_i`, with `U` the common words, `T` the
//! words of `I_i` not in the current image, `f` the occurrence frequencies before the update and
//! `N_new` the number of new words of the current image,
//!
//! ```text
//! S(I_i, I_t) = Σ_{m∈U} f_m⁻¹ |U| / ( Σ_{m∈U} f_m⁻¹ |U| + Σ_{k∈T} f_k⁻¹ |T| + N_new )   (§4.4.3)
//! Ŝ(I_i, I_t) = S(I_i, I_t) / Σ_{I∈L} S(I, I_t)
//! ```
//!
//! implemented as printed (the inverse-frequency sums are multiplied by the cardinalities).
//! No candidate is proposed from a single hypothesis: `|L| ≤ 1` gives none. There is no
//! threshold on `Ŝ` (the thesis traces its precision–recall points by varying δ).

use super::config::IbuildScore;
use super::vocabulary::Vocabulary;
use crate::Candidate;

/// Scores every hypothesis for an image with the distinct old words `old` (sorted ascending)
/// and `n_new` new words, against the images `< before`. Candidates are in frame order.
pub(crate) fn hypotheses(
    vocabulary: &Vocabulary,
    old: &[u32],
    n_new: usize,
    before: usize,
    mode: IbuildScore,
) -> Vec<Candidate> {
    let limit = before.min(vocabulary.num_images());
    if limit < 2 {
        return Vec::new();
    }
    // Per image: Σ_{m∈U} 1/f_m and |U|.
    let mut common = vec![(0.0f64, 0u32); limit];
    let mut touched: Vec<u32> = Vec::new();
    for &m in old {
        let Some(&f) = vocabulary.frequencies().get(m as usize) else {
            continue;
        };
        let inverse = 1.0 / f64::from(f.max(1));
        for &image in vocabulary.images_with(m) {
            let Some(c) = common.get_mut(image as usize) else {
                break; // the list is ascending: every later image is ≥ before
            };
            if c.1 == 0 {
                touched.push(image);
            }
            c.0 += inverse;
            c.1 += 1;
        }
    }
    if touched.len() <= 1 {
        return Vec::new(); // |L| > 1 is required (§4.4.3)
    }
    touched.sort_unstable();
    let n_new = n_new as f64;
    // Σ 1/f over the query's old words (for the symmetric score's Q = old \ U).
    let query_sum: f64 = old
        .iter()
        .filter_map(|&m| vocabulary.frequencies().get(m as usize))
        .map(|&f| 1.0 / f64::from(f.max(1)))
        .sum();
    let mut out: Vec<Candidate> = touched
        .iter()
        .map(|&image| {
            let (u_sum, u_count) = common[image as usize];
            let t_count = vocabulary.words_of(image as usize).len() as f64 - f64::from(u_count);
            let t_sum = if t_count > 0.0 {
                (vocabulary.inverse_frequency_sum(image as usize) - u_sum).max(0.0)
            } else {
                0.0
            };
            let u = u_sum * f64::from(u_count);
            let mut denominator = u + t_sum * t_count + n_new; // §4.4.3, S(I_i, I_t)
            if mode == IbuildScore::Symmetric {
                let q_count = old.len() as f64 - f64::from(u_count);
                denominator += (query_sum - u_sum).max(0.0) * q_count;
            }
            let score = u / denominator;
            Candidate {
                frame: image as usize,
                score,
            }
        })
        .collect();
    if mode == IbuildScore::Printed {
        let total: f64 = out.iter().map(|c| c.score).sum();
        for c in &mut out {
            c.score /= total; // Ŝ = S / Σ_L S
        }
    }
    out
}
