//! Online loop-closure acceptance: from the candidates of each query frame to at most one
//! accepted loop closure, with the temporal-consistency test of IBuILD (Khan 2017, §4.4.3,
//! Fig. 4.11).
//!
//! # Selection
//!
//! The candidate of query frame `t` is the hypothesis with the largest score (Khan 2017,
//! §4.4.3, "argmax"); ties go to the lowest frame index, and NaN scores are ignored. It is a
//! *detection* when its score is at least [`LoopConfig::min_score`]. The thesis traces its
//! precision–recall points by varying the matching threshold δ of the vocabulary and has no
//! threshold on the score (Khan 2017, §4.6.1); the threshold here is our addition to sweep
//! finer curves over any method, and `0` accepts every candidate of a method whose scores are
//! non-negative (all methods of this crate).
//!
//! # Temporal consistency (Khan 2017, §4.4.3, Fig. 4.11)
//!
//! "Consider a scenario in which a robot at time index t−1 returns to a location which was
//! previously visited at time index t−k where k > β. […] after the loop closure event between
//! I_{t−1} and I_{t−k}, all future loop closure events detected in the interval of t and t+β
//! are constrained to lie between t−k and t−k+β." So an accepted closure `(q, m)` opens a
//! *window*: a detection `(t, j)` with `q < t ≤ q + 1 + β` is consistent with it when
//! `m ≤ j ≤ m + β`. "In case the robot return\[s\] to the same location multiple times in the
//! past, the temporal consistency test has to be extended to all such time intervals": we keep
//! every accepted closure whose window still covers the query and accept a detection
//! consistent with **any** of them. While at least one window is open, an inconsistent
//! detection is rejected; only the best candidate is tested (a rejected best candidate is not
//! replaced by the next one — the thesis tests "the loop closure candidate chosen in the last
//! step").
//!
//! Not in the thesis: how the very first loop closure (or the first after every window has
//! closed) is accepted. Our reading: a detection that no open window constrains is accepted as
//! soon as it passes the threshold, since the printed test only constrains events after an
//! accepted closure. As an ablation, [`LoopConfig::consecutive`] = k > 1 requires, DBoW2-style
//! (Gálvez-López and Tardós 2012), that such an unconstrained detection ends a run of k
//! detections of consecutive queries, each consistent (in the sense above) with the one before.
//!
//! With [`LoopConfig::temporal_consistency`] off, every detection is accepted (kidnapped-robot
//! setting, Khan 2017, §4.5).

use serde::{Deserialize, Serialize};

use crate::{Candidate, PlaceError, Result};

/// Parameters of [`LoopDetector`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoopConfig {
    /// Acceptance threshold on the best candidate's score: a candidate with a smaller score is
    /// no detection. Default 0 (ours; the thesis has no score threshold, §4.6.1), which accepts
    /// every candidate with a non-negative score.
    pub min_score: f64,
    /// β, frames: an accepted closure `(q, m)` constrains the queries `q+1 ..= q+1+β` to match
    /// in `m ..= m+β`. Default 10 (Khan 2017, §4.6.1).
    pub temporal_window: usize,
    /// Apply the temporal-consistency test (Khan 2017, §4.4.3). Default true.
    pub temporal_consistency: bool,
    /// Ablation (ours, after DBoW2): an unconstrained detection is accepted only at the end of
    /// a run of this many consistent detections of consecutive queries. 0 and 1 accept it at
    /// once (default 1, our reading of the thesis).
    pub consecutive: usize,
}

impl Default for LoopConfig {
    fn default() -> Self {
        Self {
            min_score: 0.0,
            temporal_window: 10,
            temporal_consistency: true,
            consecutive: 1,
        }
    }
}

impl LoopConfig {
    /// Checks the parameters: `min_score` must not be NaN.
    pub fn validate(&self) -> Result<()> {
        if self.min_score.is_nan() {
            return Err(PlaceError::InvalidParameter {
                name: "min_score",
                reason: "must not be NaN".into(),
            });
        }
        Ok(())
    }
}

/// An accepted loop closure: query frame `query` revisits the earlier frame `matched`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoopClosure {
    /// The query frame.
    pub query: usize,
    /// The matched database frame.
    pub matched: usize,
    /// The candidate's score.
    pub score: f64,
}

/// The best candidate: largest score, ties to the lowest frame index; NaN scores are ignored.
pub fn best_candidate(candidates: &[Candidate]) -> Option<Candidate> {
    candidates
        .iter()
        .filter(|c| !c.score.is_nan())
        .copied()
        .reduce(|best, c| {
            if c.score > best.score || (c.score == best.score && c.frame < best.frame) {
                c
            } else {
                best
            }
        })
}

/// Decides, query by query, which loop closures to accept (see the module documentation).
///
/// Queries are expected in increasing order, each pushed once.
#[derive(Clone, Debug)]
pub struct LoopDetector {
    config: LoopConfig,
    /// Accepted closures whose window may still cover a future query.
    open: Vec<LoopClosure>,
    /// The last detection (query, match) and the length of the consistent run it ends.
    run: Option<(usize, usize, usize)>,
}

impl LoopDetector {
    /// A detector with no accepted closure yet.
    pub fn new(config: LoopConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self {
            config,
            open: Vec::new(),
            run: None,
        })
    }

    /// The parameters.
    pub fn config(&self) -> &LoopConfig {
        &self.config
    }

    /// Forgets every accepted closure and run.
    pub fn reset(&mut self) {
        self.open.clear();
        self.run = None;
    }

    /// True when the detection `(query, matched)` lies in the window opened by `closure`.
    fn consistent(&self, closure: (usize, usize), query: usize, matched: usize) -> bool {
        let beta = self.config.temporal_window;
        let (q, m) = closure;
        query > q && query - q <= beta + 1 && matched >= m && matched - m <= beta
    }

    /// Takes the candidates of query frame `query` and returns the accepted loop closure, if
    /// any.
    pub fn push(&mut self, query: usize, candidates: &[Candidate]) -> Option<LoopClosure> {
        let beta = self.config.temporal_window;
        self.open
            .retain(|c| query > c.query && query - c.query <= beta + 1);
        let detection = best_candidate(candidates).filter(|c| c.score >= self.config.min_score);
        let Some(best) = detection else {
            self.run = None;
            return None;
        };
        let closure = LoopClosure {
            query,
            matched: best.frame,
            score: best.score,
        };
        // Length of the run of consistent detections of consecutive queries ending here.
        let run = match self.run {
            Some((q, m, n)) if self.consistent((q, m), query, best.frame) && query == q + 1 => {
                n + 1
            }
            _ => 1,
        };
        self.run = Some((query, best.frame, run));
        if !self.config.temporal_consistency {
            return Some(closure);
        }
        let accepted = if self.open.is_empty() {
            run >= self.config.consecutive.max(1)
        } else {
            self.open
                .iter()
                .any(|c| self.consistent((c.query, c.matched), query, best.frame))
        };
        if accepted {
            self.open.push(closure);
            Some(closure)
        } else {
            None
        }
    }
}

/// Runs a fresh [`LoopDetector`] over the candidate lists of the queries `0, 1, …` and returns
/// the accepted loop closures in query order.
pub fn detect_loops(
    config: &LoopConfig,
    candidates: &[Vec<Candidate>],
) -> Result<Vec<LoopClosure>> {
    let mut detector = LoopDetector::new(*config)?;
    Ok(candidates
        .iter()
        .enumerate()
        .filter_map(|(t, c)| detector.push(t, c))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(frame: usize, score: f64) -> Vec<Candidate> {
        vec![Candidate { frame, score }]
    }

    #[test]
    fn best_is_max_score_ties_to_lowest_frame() {
        let c = [
            Candidate {
                frame: 7,
                score: 0.5,
            },
            Candidate {
                frame: 3,
                score: 0.9,
            },
            Candidate {
                frame: 2,
                score: f64::NAN,
            },
            Candidate {
                frame: 1,
                score: 0.9,
            },
        ];
        assert_eq!(
            best_candidate(&c),
            Some(Candidate {
                frame: 1,
                score: 0.9
            })
        );
        assert_eq!(best_candidate(&[]), None);
    }

    #[test]
    fn first_loop_accepted_then_window_constrains() {
        let config = LoopConfig {
            temporal_window: 3,
            ..LoopConfig::default()
        };
        let mut d = LoopDetector::new(config).unwrap();
        // t = 50 ↔ 10 accepted (first loop, no window open).
        assert!(d.push(50, &one(10, 0.8)).is_some());
        // t = 51: inside [10, 13] → accepted; 52: 30 is outside every window → rejected.
        assert!(d.push(51, &one(12, 0.8)).is_some());
        assert!(d.push(52, &one(30, 0.9)).is_none());
        // 53 is covered by the window of 51 (queries 52..=55, matches 12..=15).
        assert!(d.push(53, &one(15, 0.7)).is_some());
        // A match before every window's start is rejected (windows only look forward).
        assert!(d.push(54, &one(9, 0.7)).is_none());
        // 14 lies in the window of (51, 12).
        assert!(d.push(55, &one(14, 0.7)).is_some());
    }

    #[test]
    fn window_expires_after_beta_plus_one_queries() {
        let config = LoopConfig {
            temporal_window: 2,
            ..LoopConfig::default()
        };
        let mut d = LoopDetector::new(config).unwrap();
        assert!(d.push(20, &[]).is_none());
        assert!(d.push(40, &one(5, 1.0)).is_some());
        // Window of (40, 5): queries 41..=43. Query 43 with an inconsistent match: rejected.
        assert!(d.push(43, &one(30, 1.0)).is_none());
        // Query 44: no window open any more → accepted as a new first loop.
        assert!(d.push(44, &one(30, 1.0)).is_some());
    }

    #[test]
    fn several_earlier_visits_any_window_suffices() {
        let mut d = LoopDetector::new(LoopConfig::default()).unwrap();
        // Two closures accepted in a row, the second consistent with the first.
        assert!(d.push(100, &one(10, 1.0)).is_some());
        assert!(d.push(101, &one(11, 1.0)).is_some());
        // A third visit: 102 matches the place seen at 11..=21 or, through (101, 11), too.
        assert!(d.push(102, &one(21, 1.0)).is_some());
        // 103 matches 31 (=21+10): consistent with (102, 21) only.
        assert!(d.push(103, &one(31, 1.0)).is_some());
        assert!(d.push(104, &one(60, 1.0)).is_none());
    }

    #[test]
    fn threshold_and_no_consistency() {
        let config = LoopConfig {
            min_score: 0.5,
            temporal_consistency: false,
            ..LoopConfig::default()
        };
        let candidates = vec![one(0, 0.9), one(0, 0.4), vec![], one(1, 0.6), one(90, 0.5)];
        let loops = detect_loops(&config, &candidates).unwrap();
        let got: Vec<(usize, usize)> = loops.iter().map(|l| (l.query, l.matched)).collect();
        assert_eq!(got, vec![(0, 0), (3, 1), (4, 90)]);
    }

    #[test]
    fn consecutive_ablation_needs_a_consistent_run() {
        let config = LoopConfig {
            consecutive: 3,
            ..LoopConfig::default()
        };
        let mut d = LoopDetector::new(config).unwrap();
        assert!(d.push(50, &one(10, 1.0)).is_none());
        assert!(d.push(51, &one(11, 1.0)).is_none());
        // Third consistent detection of consecutive queries: accepted, window opens.
        assert!(d.push(52, &one(12, 1.0)).is_some());
        assert!(d.push(53, &one(13, 1.0)).is_some());
        // A gap (no detection) breaks the run but the window still constrains.
        assert!(d.push(54, &[]).is_none());
        assert!(d.push(55, &one(30, 1.0)).is_none());
        d.reset();
        assert!(d.push(60, &one(30, 1.0)).is_none());
        assert!(
            d.push(62, &one(31, 1.0)).is_none(),
            "queries not consecutive"
        );
    }

    #[test]
    fn nan_threshold_is_rejected() {
        let config = LoopConfig {
            min_score: f64::NAN,
            ..LoopConfig::default()
        };
        assert!(LoopDetector::new(config).is_err());
    }
}
