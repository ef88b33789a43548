//! Place recognition of a **query sequence against a database sequence** (the Nordland
//! protocol: one season's ride as the database, the other's as the queries; Sünderhauf et
//! al., ICRA 2013 workshop). Unlike loop closure within one sequence, the database is complete
//! before the first query and the queries never join it.
//!
//! [`run_cross`] describes and inserts every database frame, then describes each query and
//! scores it against the whole database, one query after another on one thread; the scores
//! land in a dense [`ScoreMatrix`] (queries × database frames; frames a method does not propose
//! are NaN), which [`crate::cross_summary`] scores and [`crate::sequence_match`] turns into
//! sequence scores.

use std::time::Instant;

use crate::run::sort_candidates;
use crate::{Candidate, FrameTiming, OwnedFrame, PlaceError, PlaceRecognizer, Result};

/// Similarities of every query against every database frame, row-major (one row per query);
/// higher = more similar, NaN = not proposed by the method.
#[derive(Clone, Debug, PartialEq)]
pub struct ScoreMatrix {
    queries: usize,
    database: usize,
    scores: Vec<f32>,
}

impl ScoreMatrix {
    /// A `queries × database` matrix of NaN.
    pub fn new(queries: usize, database: usize) -> Self {
        Self {
            queries,
            database,
            scores: vec![f32::NAN; queries * database],
        }
    }

    /// A matrix from row-major values; errors when the length is not `queries × database`.
    pub fn from_rows(queries: usize, database: usize, scores: Vec<f32>) -> Result<Self> {
        if scores.len() != queries * database {
            return Err(PlaceError::BadInput(format!(
                "{} scores for a {queries} × {database} matrix",
                scores.len()
            )));
        }
        Ok(Self {
            queries,
            database,
            scores,
        })
    }

    /// Number of queries (rows).
    pub fn queries(&self) -> usize {
        self.queries
    }

    /// Number of database frames (columns).
    pub fn database(&self) -> usize {
        self.database
    }

    /// The scores of query `q` against the database (empty out of range).
    pub fn row(&self, q: usize) -> &[f32] {
        self.scores
            .get(q * self.database..(q + 1) * self.database)
            .unwrap_or(&[])
    }

    /// Mutable row `q` (empty out of range).
    pub fn row_mut(&mut self, q: usize) -> &mut [f32] {
        let d = self.database;
        self.scores.get_mut(q * d..(q + 1) * d).unwrap_or(&mut [])
    }

    /// Writes candidates into row `q` (frames out of range are ignored).
    pub fn fill_row(&mut self, q: usize, candidates: &[Candidate]) {
        let row = self.row_mut(q);
        for c in candidates {
            if let Some(cell) = row.get_mut(c.frame) {
                *cell = c.score as f32;
            }
        }
    }

    /// The `k` best database frames of query `q`, by score descending (ties: lowest frame
    /// first); NaN scores are left out.
    pub fn best(&self, q: usize, k: usize) -> Vec<Candidate> {
        let mut found: Vec<Candidate> = self
            .row(q)
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.is_nan())
            .map(|(frame, &s)| Candidate {
                frame,
                score: f64::from(s),
            })
            .collect();
        if found.len() > k && k > 0 {
            found.select_nth_unstable_by(k - 1, |a, b| {
                b.score.total_cmp(&a.score).then(a.frame.cmp(&b.frame))
            });
            found.truncate(k);
        }
        sort_candidates(&mut found);
        found.truncate(k);
        found
    }
}

/// The result of [`run_cross`].
#[derive(Clone, Debug)]
pub struct CrossRun {
    /// The method's name.
    pub method: &'static str,
    /// Query × database similarities.
    pub scores: ScoreMatrix,
    /// Per database frame: describe and insert times.
    pub database_timings: Vec<FrameTiming>,
    /// Per query: describe and query times (nothing is inserted).
    pub query_timings: Vec<FrameTiming>,
}

impl CrossRun {
    /// Mean time per query (describe + query), milliseconds.
    pub fn ms_per_query(&self) -> f64 {
        FrameTiming::mean(&self.query_timings).total_s * 1e3
    }
}

/// Query-against-database run (see the module documentation). The recognizer must start
/// empty; [`PlaceRecognizer::start_sequence`] is called before the first query (a new
/// sequence: IBuILD forgets the last database frame). Errors name the frame (`database frame
/// i`, `query i`).
pub fn run_cross<R: PlaceRecognizer>(
    recognizer: &mut R,
    n_database: usize,
    mut database: impl FnMut(usize) -> Result<OwnedFrame>,
    n_queries: usize,
    mut queries: impl FnMut(usize) -> Result<OwnedFrame>,
) -> Result<CrossRun> {
    if !recognizer.is_empty() {
        return Err(PlaceError::BadInput(format!(
            "{}: the database already holds {} frames; run_cross needs an empty one",
            recognizer.name(),
            recognizer.len()
        )));
    }
    let at = |what: &str, i: usize, e: PlaceError| match e {
        PlaceError::BadInput(m) => PlaceError::BadInput(format!("{what} {i}: {m}")),
        other => other,
    };
    let mut database_timings = Vec::with_capacity(n_database);
    recognizer.start_sequence();
    for i in 0..n_database {
        let frame = database(i)?;
        let start = Instant::now();
        let d = recognizer
            .describe(&frame.as_frame())
            .map_err(|e| at("database frame", i, e))?;
        let describe_s = start.elapsed().as_secs_f64();
        let start = Instant::now();
        recognizer.insert(d);
        database_timings.push(FrameTiming::new(
            describe_s,
            0.0,
            start.elapsed().as_secs_f64(),
        ));
    }
    recognizer.start_sequence();
    let mut scores = ScoreMatrix::new(n_queries, n_database);
    let mut query_timings = Vec::with_capacity(n_queries);
    for q in 0..n_queries {
        let frame = queries(q)?;
        let start = Instant::now();
        let d = recognizer
            .describe(&frame.as_frame())
            .map_err(|e| at("query", q, e))?;
        let describe_s = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let found = recognizer.query(&d, n_database);
        let query_s = start.elapsed().as_secs_f64();
        scores.fill_row(q, &found);
        query_timings.push(FrameTiming::new(describe_s, query_s, 0.0));
    }
    Ok(CrossRun {
        method: recognizer.name(),
        scores,
        database_timings,
        query_timings,
    })
}

#[cfg(test)]
mod tests {
    use image::GrayImage;

    use super::*;
    use crate::{RawPixelConfig, RawPixels};

    fn scene(seed: u32) -> GrayImage {
        GrayImage::from_fn(64, 32, |x, y| {
            let v = (x * 7 + y * 13 + seed * 31) ^ (x * y + seed * 5);
            image::Luma([(v % 251) as u8])
        })
    }

    #[test]
    fn best_sorts_and_skips_unscored_frames() {
        let m = ScoreMatrix::from_rows(1, 5, vec![0.1, f32::NAN, 0.7, 0.7, -1.0]).expect("5");
        let best = m.best(0, 3);
        let frames: Vec<usize> = best.iter().map(|c| c.frame).collect();
        assert_eq!(frames, [2, 3, 0]);
        assert_eq!(m.best(0, 10).len(), 4);
        assert!(ScoreMatrix::from_rows(2, 2, vec![0.0; 3]).is_err());
    }

    #[test]
    fn queries_find_their_database_frames_and_are_not_inserted() {
        let mut r = RawPixels::new(RawPixelConfig::default()).expect("config");
        let db: Vec<GrayImage> = (0..6).map(scene).collect();
        // The queries: database frames 4, 1, 3, slightly darker.
        let qs: Vec<GrayImage> = [4u32, 1, 3]
            .iter()
            .map(|&s| {
                GrayImage::from_fn(64, 32, |x, y| {
                    image::Luma([scene(s).get_pixel(x, y).0[0] / 2 + 10])
                })
            })
            .collect();
        let run = run_cross(
            &mut r,
            db.len(),
            |i| Ok(OwnedFrame::Image(db[i].clone())),
            qs.len(),
            |i| Ok(OwnedFrame::Image(qs[i].clone())),
        )
        .expect("run");
        assert_eq!(r.len(), 6);
        let best: Vec<usize> = (0..3).map(|q| run.scores.best(q, 1)[0].frame).collect();
        assert_eq!(best, [4, 1, 3]);
        assert_eq!(run.query_timings.len(), 3);
        assert!(run_cross(&mut r, 0, |_| unreachable!(), 0, |_| unreachable!()).is_err());
    }
}
