//! Precision–recall evaluation of place recognition (Khan 2017, §4.5.3) and of online loop
//! closure (Khan 2017, §4.6.1).
//!
//! # Ground truth
//!
//! [`GroundTruth`] marks the pairs of frames at the same place: positions less than a radius
//! apart (5 m in Khan 2017, §4.6.2), or planar poses less than a radius apart with overlapping
//! fields of view. Pairs inside an [`Exclusion`] window (in frames and seconds) are not
//! evaluated: neighbouring frames trivially look alike.
//!
//! # Kidnapped mode (Khan 2017, §4.5.3)
//!
//! "The square similarity matrix is thresholded to generate the hypotheses of places which
//! look similar to each other. The true and false positives are extracted from these
//! hypotheses based on the groundtruth." [`kidnapped_pr`] takes, for each query `i`, its
//! candidates against all frames. Not in the thesis: each unordered evaluable pair counts
//! once, with the larger of its two scores (the matrix is symmetric for global descriptors;
//! for the bag of words it need not be); the diagonal and non-evaluable pairs are left out; a
//! pair in neither list has score −∞ and is never detected. Sweeping the threshold over every
//! distinct score, a pair is detected when its score is at least the threshold:
//! precision = true detected pairs / detected pairs, recall = true detected pairs / true
//! pairs.
//!
//! # Online mode (Khan 2017, §4.6.1)
//!
//! Loop closure accepts at most one loop per query, with temporal consistency
//! ([`LoopDetector`]). [`online_pr`] re-runs the detector for each threshold on the best
//! candidate's score (the test is stateful), over the distinct best-candidate scores, or that
//! many evenly spaced quantiles of them. As in the thesis, precision = correct accepted loops /
//! accepted loops and recall = correct detections / ground-truth loop-closure events; our
//! event is a query frame with at least one evaluable true revisit among the earlier frames,
//! and a query counts as detected when its accepted loop is a true revisit. Accepted loops on
//! non-evaluable pairs (inside the exclusion window, or without ground truth) are left out of
//! both counts.
//!
//! # Conventions (ours)
//!
//! The precision of an empty detection set is 1; the recall is 0 when the ground truth has no
//! revisit at all ([`PrCurve::positives`] = 0). [`PrSummary::recall_at_100_precision`] is 0 when
//! no threshold gives 100 % precision with a detection (the empty set at an infinite threshold
//! has recall 0), and [`PrSummary::precision_at_100_recall`] is 0 when 100 % recall is never
//! reached (the maximum over an empty set of precisions, taken as their lower bound). Scores
//! that are not finite are ignored (never detected).

mod cross;
mod truth;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use cross::{Confidence, CrossSummary, CrossTruth, cross_pr, cross_summary, recall_at_k};
pub use truth::{Exclusion, GroundTruth};

use crate::online::{LoopConfig, LoopDetector, best_candidate};
use crate::{Candidate, PlaceError, Result};

/// One operating point: detections with a score at or above `threshold`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PrPoint {
    /// The score threshold.
    pub threshold: f64,
    /// Correct detections / detections (1 for no detection).
    pub precision: f64,
    /// Correct detections / ground-truth events.
    pub recall: f64,
}

/// A precision–recall curve, thresholds descending (recall non-decreasing in kidnapped mode).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PrCurve {
    /// The operating points.
    pub points: Vec<PrPoint>,
    /// Number of ground-truth events (true pairs, or queries with an earlier revisit).
    pub positives: usize,
}

/// The two key criteria of Khan 2017, §4.5.3, and the maximum F1 score.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PrSummary {
    /// Largest recall of an operating point with 100 % precision (0 when there is none).
    pub recall_at_100_precision: f64,
    /// Largest precision of an operating point with 100 % recall (0 when there is none).
    pub precision_at_100_recall: f64,
    /// Largest F1 = 2PR / (P + R) over the operating points (0 when there is none).
    pub max_f1: f64,
}

impl PrCurve {
    /// The summary criteria. Exact: a point has precision exactly 1 only without false
    /// detections and recall exactly 1 only when every event is detected.
    pub fn summary(&self) -> PrSummary {
        let mut s = PrSummary {
            recall_at_100_precision: 0.0,
            precision_at_100_recall: 0.0,
            max_f1: 0.0,
        };
        for p in &self.points {
            if p.precision == 1.0 {
                s.recall_at_100_precision = s.recall_at_100_precision.max(p.recall);
            }
            if p.recall == 1.0 {
                s.precision_at_100_recall = s.precision_at_100_recall.max(p.precision);
            }
            if p.precision + p.recall > 0.0 {
                let f1 = 2.0 * p.precision * p.recall / (p.precision + p.recall);
                s.max_f1 = s.max_f1.max(f1);
            }
        }
        s
    }
}

/// Precision and recall from counts, with the conventions of the module documentation.
pub(crate) fn point(threshold: f64, correct: usize, detected: usize, positives: usize) -> PrPoint {
    PrPoint {
        threshold,
        precision: if detected == 0 {
            1.0
        } else {
            correct as f64 / detected as f64
        },
        recall: if positives == 0 {
            0.0
        } else {
            correct as f64 / positives as f64
        },
    }
}

fn check_lengths(candidates: &[Vec<Candidate>], truth: &GroundTruth) -> Result<()> {
    if candidates.len() != truth.len() {
        return Err(PlaceError::BadInput(format!(
            "{} candidate lists for {} ground-truth frames",
            candidates.len(),
            truth.len()
        )));
    }
    for (i, list) in candidates.iter().enumerate() {
        if let Some(c) = list.iter().find(|c| c.frame >= truth.len()) {
            return Err(PlaceError::BadInput(format!(
                "query {i}: candidate frame {} is out of range (0..{})",
                c.frame,
                truth.len()
            )));
        }
    }
    Ok(())
}

/// Kidnapped-robot precision–recall over the similarity matrix (Khan 2017, §4.5.3): see the
/// module documentation. `candidates[i]` holds query `i`'s candidates against all frames.
pub fn kidnapped_pr(candidates: &[Vec<Candidate>], truth: &GroundTruth) -> Result<PrCurve> {
    check_lengths(candidates, truth)?;
    let mut pairs: Vec<(usize, usize, f64)> = candidates
        .iter()
        .enumerate()
        .flat_map(|(i, list)| list.iter().map(move |c| (i, c)))
        .filter(|(i, c)| c.score.is_finite() && truth.is_evaluable(*i, c.frame))
        .map(|(i, c)| (i.min(c.frame), i.max(c.frame), c.score))
        .collect();
    // One entry per unordered pair, with the larger score.
    pairs.sort_unstable_by(|a, b| (a.0, a.1).cmp(&(b.0, b.1)).then(b.2.total_cmp(&a.2)));
    pairs.dedup_by(|later, first| (later.0, later.1) == (first.0, first.1));
    pairs.sort_unstable_by(|a, b| b.2.total_cmp(&a.2));
    let positives = truth.true_pairs();
    let mut points = Vec::new();
    let mut correct = 0;
    for (k, &(i, j, score)) in pairs.iter().enumerate() {
        if truth.is_revisit(i, j) {
            correct += 1;
        }
        let last_of_score = pairs.get(k + 1).is_none_or(|next| next.2 < score);
        if last_of_score {
            points.push(point(score, correct, k + 1, positives));
        }
    }
    Ok(PrCurve { points, positives })
}

/// The thresholds of the online sweep: the distinct finite best-candidate scores, descending,
/// or `max_thresholds` evenly spaced quantiles of them (always the largest and the smallest;
/// `0` keeps every score).
fn online_thresholds(best: &[Option<Candidate>], max_thresholds: usize) -> Vec<f64> {
    let mut scores: Vec<f64> = best.iter().flatten().map(|c| c.score).collect();
    scores.sort_unstable_by(|a, b| b.total_cmp(a));
    scores.dedup();
    if max_thresholds == 0 || scores.len() <= max_thresholds {
        return scores;
    }
    if max_thresholds == 1 {
        return scores.last().copied().into_iter().collect();
    }
    let last = scores.len() - 1;
    let mut picked: Vec<f64> = (0..max_thresholds)
        .map(|k| scores[(k * last + (max_thresholds - 1) / 2) / (max_thresholds - 1)])
        .collect();
    picked.dedup();
    picked
}

/// Online loop-closure precision–recall (Khan 2017, §4.6.1): see the module documentation.
/// `candidates[t]` holds query `t`'s candidates among the earlier frames; `config` gives the
/// temporal-consistency parameters (its `min_score` is replaced by each swept threshold);
/// `max_thresholds` caps the number of operating points (0 = every distinct score).
pub fn online_pr(
    candidates: &[Vec<Candidate>],
    truth: &GroundTruth,
    config: &LoopConfig,
    max_thresholds: usize,
) -> Result<PrCurve> {
    check_lengths(candidates, truth)?;
    config.validate()?;
    let positives = (0..truth.len())
        .filter(|&t| truth.has_earlier_revisit(t))
        .count();
    // The detector only looks at the best candidate: find it once.
    let best: Vec<Option<Candidate>> = candidates
        .iter()
        .map(|list| best_candidate(list).filter(|c| c.score.is_finite()))
        .collect();
    let points = online_thresholds(&best, max_thresholds)
        .into_par_iter()
        .map(|threshold| {
            let mut detector = LoopDetector::new(LoopConfig {
                min_score: threshold,
                ..*config
            })?;
            let (mut correct, mut detected) = (0, 0);
            for (t, b) in best.iter().enumerate() {
                let Some(l) = detector.push(t, b.as_slice()) else {
                    continue;
                };
                if truth.is_evaluable(l.query, l.matched) {
                    detected += 1;
                    correct += usize::from(truth.is_revisit(l.query, l.matched));
                }
            }
            Ok(point(threshold, correct, detected, positives))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(PrCurve { points, positives })
}

#[cfg(test)]
mod tests;
