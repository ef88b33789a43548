//! Cumulative time per pipeline stage, for a row like Khan 2017, Table 4.3.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Cumulative wall-clock time per IBuILD stage and how often each ran (Table 4.3 stages;
/// keypoint detection and description are one stage here).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StageTimes {
    /// Frame to image, keypoints and descriptors ([`describe`] only; not for
    /// [`describe_descriptors`]).
    ///
    /// [`describe`]: crate::PlaceRecognizer::describe
    /// [`describe_descriptors`]: super::Ibuild::describe_descriptors
    pub features: Duration,
    /// Consecutive-frame matching and merging into words.
    pub matching_merging: Duration,
    /// Assign-BoW-Index (Fig. 4.9), wherever it runs (describe, query or insert).
    pub assignment: Duration,
    /// Hypotheses and similarity (queries).
    pub hypotheses_similarity: Duration,
    /// Vocabulary update (inserts).
    pub update: Duration,
    /// Frames described.
    pub described: u64,
    /// Queries answered.
    pub queries: u64,
    /// Descriptions inserted.
    pub inserted: u64,
}

/// The stages, in [`StageTimes`] order.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Stage {
    Features = 0,
    MatchingMerging = 1,
    Assignment = 2,
    Hypotheses = 3,
    Update = 4,
}

/// Thread-safe accumulators behind [`StageTimes`] (queries take `&self`).
#[derive(Debug, Default)]
pub(crate) struct StageClock {
    nanos: [AtomicU64; 5],
    counts: [AtomicU64; 3],
}

impl StageClock {
    /// Adds the time since `start` to `stage` and returns now.
    pub(crate) fn lap(&self, stage: Stage, start: Instant) -> Instant {
        let now = Instant::now();
        let ns = u64::try_from(now.duration_since(start).as_nanos()).unwrap_or(u64::MAX);
        self.nanos[stage as usize].fetch_add(ns, Ordering::Relaxed);
        now
    }

    /// Counts one describe (0), query (1) or insert (2).
    pub(crate) fn count(&self, which: usize) {
        self.counts[which].fetch_add(1, Ordering::Relaxed);
    }

    pub(crate) fn snapshot(&self) -> StageTimes {
        let d = |i: usize| Duration::from_nanos(self.nanos[i].load(Ordering::Relaxed));
        let c = |i: usize| self.counts[i].load(Ordering::Relaxed);
        StageTimes {
            features: d(0),
            matching_merging: d(1),
            assignment: d(2),
            hypotheses_similarity: d(3),
            update: d(4),
            described: c(0),
            queries: c(1),
            inserted: c(2),
        }
    }

    pub(crate) fn reset(&self) {
        for a in self.nanos.iter().chain(self.counts.iter()) {
            a.store(0, Ordering::Relaxed);
        }
    }
}
