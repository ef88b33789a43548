//! Typed reports of loop-closure detection and of query-against-database runs: the JSON
//! documents of `raypath loop-closure --json` (the keys are a contract).

use serde::Serialize;

use crate::{Candidate, CrossSummary, LoopClosure, PrSummary};

/// A query and its match, frames by their labels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MatchReport {
    /// The query frame.
    pub query: usize,
    /// The matched frame.
    #[serde(rename = "match")]
    pub matched: usize,
    /// The score (higher = more similar).
    pub score: f64,
}

/// Loop closures and best candidates of a run over one input.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LoopClosureReport {
    /// The method's name.
    pub method: &'static str,
    /// Frames of the input.
    pub frames: usize,
    /// Mean time to describe, query and insert a frame, milliseconds.
    pub ms_per_query: f64,
    /// The accepted loop closures.
    pub loops: Vec<MatchReport>,
    /// Every query's best candidate (queries with any).
    pub candidates: Vec<MatchReport>,
    /// Precision–recall against the ground truth, when given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub summary: Option<PrSummary>,
}

impl LoopClosureReport {
    /// The report of a run over `frames` frames: `loops` and `candidates` (per query, sorted
    /// best first), frames named by `label` (e.g. KITTI frame numbers).
    pub fn new(
        method: &'static str,
        frames: usize,
        ms_per_query: f64,
        loops: &[LoopClosure],
        candidates: &[Vec<Candidate>],
        label: impl Fn(usize) -> usize,
        summary: Option<PrSummary>,
    ) -> Self {
        Self {
            method,
            frames,
            ms_per_query,
            loops: loops
                .iter()
                .map(|l| MatchReport {
                    query: label(l.query),
                    matched: label(l.matched),
                    score: l.score,
                })
                .collect(),
            candidates: candidates
                .iter()
                .enumerate()
                .filter_map(|(i, list)| {
                    let best = list.first()?;
                    Some(MatchReport {
                        query: label(i),
                        matched: label(best.frame),
                        score: best.score,
                    })
                })
                .collect(),
            summary,
        }
    }
}

/// A query image's best database match.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CrossMatchReport {
    /// The query's name.
    pub query: String,
    /// The match's name.
    #[serde(rename = "match")]
    pub matched: Option<String>,
    /// The score.
    pub score: f64,
    /// Whether the ground truth calls it the same place.
    pub correct: bool,
}

/// Query images against database images.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CrossReport {
    /// The method's name.
    pub method: &'static str,
    /// Query images.
    pub queries: usize,
    /// Database images.
    pub database: usize,
    /// Ground-truth tolerance, frames.
    pub tolerance: usize,
    /// Sequence length of sequence matching (SeqSLAM), when used.
    pub sequence: Option<usize>,
    /// Milliseconds per query.
    pub ms_per_query: f64,
    /// Milliseconds per query of the sequence matching.
    pub sequence_ms_per_query: Option<f64>,
    /// The criteria.
    pub summary: CrossSummary,
    /// The criteria of single images, with sequence matching.
    pub single_image: Option<CrossSummary>,
    /// Every query's best match.
    pub matches: Vec<CrossMatchReport>,
}
