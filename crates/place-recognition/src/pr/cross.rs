//! Precision–recall of a query sequence against a database sequence ([`crate::run_cross`]),
//! as on Nordland (Sünderhauf et al. 2013): query `q` is at the same place as the database
//! frames within `tolerance` frames of its own frame, found **by file name** (the two seasons'
//! files are time-aligned, the same name is the same place).
//!
//! * **PR curve** (one hypothesis per query, the usual single-image protocol): each query
//!   proposes its best database frame (ties: the lowest frame); sweeping a threshold over the
//!   best scores, a query is *detected* when its best score is at least the threshold,
//!   *correct* when its best frame is a true match. Precision = correct / detected, recall =
//!   correct / queries with a true match in the database. Conventions as in [`crate::PrCurve`].
//!   The confidence swept is the best score itself ([`Confidence::Score`]) or, as SeqSLAM
//!   accepts a match (Milford & Wyeth 2012, §III-C), its margin over the best score outside
//!   a window around the best frame ([`Confidence::Margin`]; ours: the difference, where the
//!   paper takes the ratio of the two differences — scores may be negative here).
//! * **Recall@K**: the share of queries with a true match that have one among their `K` best
//!   frames (no threshold).

use serde::{Deserialize, Serialize};

use crate::cross::ScoreMatrix;
use crate::pr::{PrCurve, point};
use crate::{Candidate, PlaceError, Result};

/// Which database frames are the same place as each query.
#[derive(Clone, Debug, PartialEq)]
pub struct CrossTruth {
    /// Per query, the database frame of the same name, when there is one.
    same: Vec<Option<usize>>,
    database: usize,
    tolerance: usize,
}

impl CrossTruth {
    /// Query `q` is the place of the database frame with its file name; the true matches are
    /// the database frames within `tolerance` frames of that one. Queries whose name the
    /// database lacks have no true match (any detection of theirs is false).
    pub fn by_name<S: AsRef<str>>(queries: &[S], database: &[S], tolerance: usize) -> Self {
        let index: std::collections::HashMap<&str, usize> = database
            .iter()
            .enumerate()
            .map(|(j, n)| (n.as_ref(), j))
            .collect();
        let same = queries
            .iter()
            .map(|n| index.get(n.as_ref()).copied())
            .collect();
        Self {
            same,
            database: database.len(),
            tolerance,
        }
    }

    /// From the database frame of each query directly (ours, for tests and aligned data).
    pub fn from_frames(same: Vec<Option<usize>>, database: usize, tolerance: usize) -> Self {
        Self {
            same,
            database,
            tolerance,
        }
    }

    /// Number of queries.
    pub fn len(&self) -> usize {
        self.same.len()
    }

    /// True when there is no query.
    pub fn is_empty(&self) -> bool {
        self.same.is_empty()
    }

    /// The frame tolerance.
    pub fn tolerance(&self) -> usize {
        self.tolerance
    }

    /// True when database frame `j` is a true match of query `q`.
    pub fn is_match(&self, q: usize, j: usize) -> bool {
        j < self.database
            && self
                .same
                .get(q)
                .copied()
                .flatten()
                .is_some_and(|s| s.abs_diff(j) <= self.tolerance)
    }

    /// True when query `q` has a true match in the database.
    pub fn has_match(&self, q: usize) -> bool {
        self.same.get(q).copied().flatten().is_some()
    }

    /// Number of queries with a true match.
    pub fn positives(&self) -> usize {
        (0..self.len()).filter(|&q| self.has_match(q)).count()
    }
}

/// What the threshold of [`cross_pr`] is swept over.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Confidence {
    /// The best match's score.
    #[default]
    Score,
    /// The best score minus the best score of the frames more than `window` frames from the
    /// best one (NaN, never detected, when there is none).
    Margin {
        /// Half-width of the excluded window, database frames.
        window: usize,
    },
}

impl Confidence {
    /// The confidence of query row `row` whose best match is `best`.
    fn of(self, row: &[f32], best: Candidate) -> f64 {
        match self {
            Confidence::Score => best.score,
            Confidence::Margin { window } => {
                let runner_up = row
                    .iter()
                    .enumerate()
                    .filter(|(j, s)| j.abs_diff(best.frame) > window && !s.is_nan())
                    .map(|(_, &s)| f64::from(s))
                    .fold(f64::NEG_INFINITY, f64::max);
                if runner_up.is_finite() {
                    best.score - runner_up
                } else {
                    f64::NAN
                }
            }
        }
    }
}

/// The criteria of a query-against-database run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrossSummary {
    /// Largest recall with 100 % precision (0 when there is none).
    pub recall_at_100_precision: f64,
    /// Share of queries with a true match whose best frame is one.
    pub recall_at_1: f64,
    /// Share of queries with a true match with one among their 5 best frames.
    pub recall_at_5: f64,
    /// Largest F1 over the curve.
    pub max_f1: f64,
    /// Queries with a true match in the database.
    pub positives: usize,
}

fn check(scores: &ScoreMatrix, truth: &CrossTruth) -> Result<()> {
    if scores.queries() != truth.len() || scores.database() != truth.database {
        return Err(PlaceError::BadInput(format!(
            "a {} × {} score matrix for {} queries against {} database frames",
            scores.queries(),
            scores.database(),
            truth.len(),
            truth.database
        )));
    }
    Ok(())
}

/// The precision–recall curve of the best match per query, the threshold swept over
/// `confidence` (module documentation).
pub fn cross_pr(
    scores: &ScoreMatrix,
    truth: &CrossTruth,
    confidence: Confidence,
) -> Result<PrCurve> {
    check(scores, truth)?;
    let mut best: Vec<(f64, bool)> = (0..scores.queries())
        .filter_map(|q| {
            let b = scores.best(q, 1).into_iter().next()?;
            let c = confidence.of(scores.row(q), b);
            c.is_finite().then(|| (c, truth.is_match(q, b.frame)))
        })
        .collect();
    best.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
    let positives = truth.positives();
    let mut points = Vec::new();
    let mut correct = 0;
    for (k, &(score, ok)) in best.iter().enumerate() {
        correct += usize::from(ok);
        if best.get(k + 1).is_none_or(|next| next.0 < score) {
            points.push(point(score, correct, k + 1, positives));
        }
    }
    Ok(PrCurve { points, positives })
}

/// Recall@K (module documentation); 0 when no query has a true match.
pub fn recall_at_k(scores: &ScoreMatrix, truth: &CrossTruth, k: usize) -> Result<f64> {
    check(scores, truth)?;
    let positives = truth.positives();
    if positives == 0 {
        return Ok(0.0);
    }
    let found = (0..scores.queries())
        .filter(|&q| truth.has_match(q))
        .filter(|&q| scores.best(q, k).iter().any(|c| truth.is_match(q, c.frame)))
        .count();
    Ok(found as f64 / positives as f64)
}

/// Recall at 100 % precision, recall@1, recall@5 and max F1 of a run (the curve's threshold
/// swept over `confidence`).
pub fn cross_summary(
    scores: &ScoreMatrix,
    truth: &CrossTruth,
    confidence: Confidence,
) -> Result<CrossSummary> {
    let curve = cross_pr(scores, truth, confidence)?.summary();
    Ok(CrossSummary {
        recall_at_100_precision: curve.recall_at_100_precision,
        recall_at_1: recall_at_k(scores, truth, 1)?,
        recall_at_5: recall_at_k(scores, truth, 5)?,
        max_f1: curve.max_f1,
        positives: truth.positives(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truth_by_name_with_tolerance() {
        let db = ["a", "b", "c", "d", "e"];
        let truth = CrossTruth::by_name(&["c", "x", "a"], &db, 1);
        assert!(truth.is_match(0, 1) && truth.is_match(0, 3) && !truth.is_match(0, 4));
        assert!(!truth.has_match(1) && !truth.is_match(1, 0));
        assert!(truth.is_match(2, 0) && truth.is_match(2, 1) && !truth.is_match(2, 2));
        assert_eq!(truth.positives(), 2);
    }

    #[test]
    fn known_curve_and_recalls() {
        // Three queries, four database frames; query q is frame q, tolerance 0.
        // q0: best frame 0 (correct, 0.9); q1: best frame 3 (wrong, 0.8), frame 1 second;
        // q2: best frame 2 (correct, 0.5).
        let rows = vec![
            0.9,
            0.1,
            0.0,
            0.0, //
            0.0,
            0.7,
            0.1,
            0.8, //
            0.1,
            0.2,
            0.5,
            f32::NAN,
        ];
        let scores = ScoreMatrix::from_rows(3, 4, rows).expect("3 × 4");
        let truth = CrossTruth::from_frames(vec![Some(0), Some(1), Some(2)], 4, 0);
        let s = cross_summary(&scores, &truth, Confidence::Score).expect("summary");
        assert!((s.recall_at_100_precision - 1.0 / 3.0).abs() < 1e-12);
        assert!((s.recall_at_1 - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!(s.recall_at_5, 1.0);
        // Max F1 at the lowest threshold: P = R = 2/3.
        assert!((s.max_f1 - 2.0 / 3.0).abs() < 1e-12);
        let wrong = CrossTruth::from_frames(vec![Some(0)], 4, 0);
        assert!(cross_summary(&scores, &wrong, Confidence::Score).is_err());
    }

    #[test]
    fn margin_ranks_distinct_matches_first() {
        // q0: best 0.9 at frame 0, runner-up outside ±1 is 0.85 (margin 0.05, wrong match);
        // q1: best 0.5 at frame 1 (correct), runner-up outside ±1 is 0.1 (margin 0.4). By score
        // the wrong match comes first (recall at 100 % precision 0); by margin the right one.
        let rows = vec![0.9, 0.0, 0.85, 0.0, 0.1, 0.5, 0.4, 0.0];
        let scores = ScoreMatrix::from_rows(2, 4, rows).expect("2 × 4");
        let truth = CrossTruth::from_frames(vec![Some(3), Some(1)], 4, 0);
        let by_score = cross_summary(&scores, &truth, Confidence::Score).expect("score");
        let by_margin =
            cross_summary(&scores, &truth, Confidence::Margin { window: 1 }).expect("margin");
        assert_eq!(by_score.recall_at_100_precision, 0.0);
        assert_eq!(by_margin.recall_at_100_precision, 0.5);
        assert_eq!(by_score.recall_at_1, by_margin.recall_at_1);
    }
}
