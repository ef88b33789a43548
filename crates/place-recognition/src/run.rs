//! Runners that drive any [`PlaceRecognizer`] over a sequence of frames, in the two settings of
//! Khan 2017, ch. 4, and time each stage.
//!
//! - [`run_online`] (loop closure, Khan 2017, §4.4): frame by frame, describe frame `t`, query
//!   the database frames `0 .. t − exclusion_frames` (recent frames are not proposed, the β of
//!   §4.4.3 or a larger window), then insert `t` — the database grows after the query, as
//!   IBuILD's vocabulary.
//! - [`run_kidnapped`] (place recognition without temporal consistency, Khan 2017, §4.5):
//!   describe and insert every frame, then query each stored frame against the whole database
//!   (the full similarity matrix, §4.5.3); queries run in parallel with rayon.
//!
//! Candidates are recorded sorted by score, descending (ties: lowest frame first; NaN scores
//! last). Times are wall-clock seconds from [`std::time::Instant`] and exclude loading the
//! frames.

use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::online::{LoopClosure, LoopConfig, detect_loops};
use crate::{Candidate, OwnedFrame, PlaceError, PlaceRecognizer, Result};

/// Time spent on one frame, seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameTiming {
    /// Describing the frame.
    pub describe_s: f64,
    /// Scoring the database against it.
    pub query_s: f64,
    /// Inserting its description.
    pub insert_s: f64,
    /// The sum of the three.
    pub total_s: f64,
}

impl FrameTiming {
    /// A timing from its three stages (the total is their sum).
    pub(crate) fn new(describe_s: f64, query_s: f64, insert_s: f64) -> Self {
        Self {
            describe_s,
            query_s,
            insert_s,
            total_s: describe_s + query_s + insert_s,
        }
    }

    /// The mean of `timings` (zero for none).
    pub fn mean(timings: &[FrameTiming]) -> FrameTiming {
        let n = timings.len().max(1) as f64;
        let sum = |f: fn(&FrameTiming) -> f64| timings.iter().map(f).sum::<f64>() / n;
        FrameTiming {
            describe_s: sum(|t| t.describe_s),
            query_s: sum(|t| t.query_s),
            insert_s: sum(|t| t.insert_s),
            total_s: sum(|t| t.total_s),
        }
    }
}

/// The result of [`run_online`].
#[derive(Clone, Debug, PartialEq)]
pub struct OnlineRun {
    /// The method's name.
    pub method: &'static str,
    /// Per query frame `t`, its candidates among the frames `0 .. t − exclusion_frames`,
    /// sorted by score descending.
    pub candidates: Vec<Vec<Candidate>>,
    /// Per query frame, the time of each stage.
    pub timings: Vec<FrameTiming>,
}

impl OnlineRun {
    /// The best candidate of each query (the first of its sorted list).
    pub fn best(&self) -> Vec<Option<Candidate>> {
        self.candidates.iter().map(|c| c.first().copied()).collect()
    }

    /// The accepted loop closures under `config` ([`crate::LoopDetector`]).
    pub fn loops(&self, config: &LoopConfig) -> Result<Vec<LoopClosure>> {
        detect_loops(config, &self.candidates)
    }
}

/// The result of [`run_kidnapped`].
#[derive(Clone, Debug, PartialEq)]
pub struct KidnappedRun {
    /// The method's name.
    pub method: &'static str,
    /// Per stored frame `i`, its candidates among all frames (itself included), sorted by
    /// score descending, at most `top_k` of them.
    pub candidates: Vec<Vec<Candidate>>,
    /// Per frame, the time to describe and insert it and to query it.
    pub timings: Vec<FrameTiming>,
}

/// Sorts candidates by score descending, ties by frame ascending, NaN scores last.
pub fn sort_candidates(candidates: &mut [Candidate]) {
    candidates.sort_unstable_by(|a, b| {
        a.score
            .is_nan()
            .cmp(&b.score.is_nan())
            .then(b.score.total_cmp(&a.score))
            .then(a.frame.cmp(&b.frame))
    });
}

fn require_empty<R: PlaceRecognizer>(recognizer: &R) -> Result<()> {
    if recognizer.is_empty() {
        Ok(())
    } else {
        Err(PlaceError::BadInput(format!(
            "{}: the database already holds {} frames; the runners need an empty one",
            recognizer.name(),
            recognizer.len()
        )))
    }
}

/// Adds the frame index to input errors of `describe`.
fn at_frame(t: usize, error: PlaceError) -> PlaceError {
    match error {
        PlaceError::BadInput(m) => PlaceError::BadInput(format!("frame {t}: {m}")),
        other => other,
    }
}

fn seconds_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64()
}

/// Online loop-closure run (see the module documentation): frames `0 .. n_frames` from
/// `frame_source`, each queried against the frames `0 .. t − exclusion_frames` before it is
/// inserted. The recognizer must start empty.
pub fn run_online<R: PlaceRecognizer>(
    recognizer: &mut R,
    n_frames: usize,
    mut frame_source: impl FnMut(usize) -> Result<OwnedFrame>,
    exclusion_frames: usize,
) -> Result<OnlineRun> {
    require_empty(recognizer)?;
    let mut candidates = Vec::with_capacity(n_frames);
    let mut timings = Vec::with_capacity(n_frames);
    for t in 0..n_frames {
        let mut found = Vec::new();
        let timing = step(recognizer, t, &mut frame_source, |r, d| {
            found = r.query(d, t.saturating_sub(exclusion_frames));
        })?;
        sort_candidates(&mut found);
        candidates.push(found);
        timings.push(timing);
    }
    Ok(OnlineRun {
        method: recognizer.name(),
        candidates,
        timings,
    })
}

/// Describes and inserts every frame; returns the per-frame describe and insert times.
fn build_database<R: PlaceRecognizer>(
    recognizer: &mut R,
    n_frames: usize,
    frame_source: &mut impl FnMut(usize) -> Result<OwnedFrame>,
) -> Result<Vec<FrameTiming>> {
    require_empty(recognizer)?;
    let mut timings = Vec::with_capacity(n_frames);
    for t in 0..n_frames {
        timings.push(step(recognizer, t, frame_source, |_, _| {})?);
    }
    Ok(timings)
}

/// One frame of a run: describe frame `t`, call `query` on the description (timed), insert it.
fn step<R: PlaceRecognizer>(
    recognizer: &mut R,
    t: usize,
    frame_source: &mut impl FnMut(usize) -> Result<OwnedFrame>,
    query: impl FnOnce(&R, &R::Description),
) -> Result<FrameTiming> {
    let frame = frame_source(t)?;
    let start = Instant::now();
    let description = recognizer
        .describe(&frame.as_frame())
        .map_err(|e| at_frame(t, e))?;
    let describe_s = seconds_since(start);
    let start = Instant::now();
    query(recognizer, &description);
    let query_s = seconds_since(start);
    let start = Instant::now();
    recognizer.insert(description);
    Ok(FrameTiming::new(describe_s, query_s, seconds_since(start)))
}

/// Queries stored frame `i` against all `n` frames: sorted, truncated candidates and the time.
fn query_one<R: PlaceRecognizer>(
    recognizer: &R,
    i: usize,
    n: usize,
    top_k: Option<usize>,
) -> (Vec<Candidate>, f64) {
    let start = Instant::now();
    let mut found = recognizer.query_stored(i, n);
    let query_s = seconds_since(start);
    sort_candidates(&mut found);
    if let Some(k) = top_k {
        found.truncate(k);
    }
    (found, query_s)
}

fn finish<R: PlaceRecognizer>(
    recognizer: &R,
    mut timings: Vec<FrameTiming>,
    queried: Vec<(Vec<Candidate>, f64)>,
) -> KidnappedRun {
    let mut candidates = Vec::with_capacity(queried.len());
    for ((found, query_s), t) in queried.into_iter().zip(&mut timings) {
        *t = FrameTiming::new(t.describe_s, query_s, t.insert_s);
        candidates.push(found);
    }
    KidnappedRun {
        method: recognizer.name(),
        candidates,
        timings,
    }
}

/// Kidnapped-robot run (see the module documentation): describe and insert frames
/// `0 .. n_frames`, then query every stored frame against all of them, in parallel. `top_k`
/// keeps only the best candidates of each query (all when `None`); pairs dropped this way are
/// never detected by [`crate::kidnapped_pr`]. The recognizer must start empty.
pub fn run_kidnapped<R: PlaceRecognizer + Sync>(
    recognizer: &mut R,
    n_frames: usize,
    mut frame_source: impl FnMut(usize) -> Result<OwnedFrame>,
    top_k: Option<usize>,
) -> Result<KidnappedRun> {
    let timings = build_database(recognizer, n_frames, &mut frame_source)?;
    let shared = &*recognizer;
    let queried: Vec<(Vec<Candidate>, f64)> = (0..n_frames)
        .into_par_iter()
        .map(|i| query_one(shared, i, n_frames, top_k))
        .collect();
    Ok(finish(shared, timings, queried))
}

/// [`run_kidnapped`] for recognizers that are not `Sync`: the queries run one after another.
pub fn run_kidnapped_serial<R: PlaceRecognizer>(
    recognizer: &mut R,
    n_frames: usize,
    mut frame_source: impl FnMut(usize) -> Result<OwnedFrame>,
    top_k: Option<usize>,
) -> Result<KidnappedRun> {
    let timings = build_database(recognizer, n_frames, &mut frame_source)?;
    let shared = &*recognizer;
    let queried: Vec<(Vec<Candidate>, f64)> = (0..n_frames)
        .map(|i| query_one(shared, i, n_frames, top_k))
        .collect();
    Ok(finish(shared, timings, queried))
}

#[cfg(test)]
mod tests;
