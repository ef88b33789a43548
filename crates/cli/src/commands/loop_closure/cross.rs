//! `raypath loop-closure QUERY_DIR --database DB_DIR`: place recognition of a folder of query
//! images against a folder of database images (the Nordland protocol: one season's ride as
//! the database, the other's as the queries). The database is described and stored first,
//! then each query is described and scored against all of it on one thread
//! (`raypath_place_recognition::run_cross`); queries never join the database.
//!
//! Ground truth by file name: a query matches the database frames within `--tolerance`
//! frames (default 2) of the database image with its own file name; a query whose name the
//! database lacks has no true match. Scores: recall at 100 % precision and max F1 over the
//! best match per query, recall@1 and recall@5. `--sequence D_S` adds sequence matching
//! (SeqSLAM: difference matrix, local contrast enhancement over 10 frames, straight lines over
//! the last `D_S` queries at 0.8–1.25 database frames per query) on the method's scores; the
//! summary is then the sequence one (its precision–recall threshold swept over SeqSLAM's
//! uniqueness: the best sequence score's margin over the best one more than 10 frames away),
//! and `single_image` keeps the method's own (threshold on the best score).
//!
//! Every image must have the size of the first database image (an error names the file).
//! `--json` prints `{"method", "queries", "database", "tolerance", "sequence",
//! "ms_per_query", "sequence_ms_per_query", "summary": {"recall_at_100_precision",
//! "recall_at_1", "recall_at_5", "max_f1", "positives"}, "single_image": {…} | null,
//! "matches": [{"query", "match", "score", "correct"}]}` with file names; `ms_per_query` is the
//! mean time to describe and score one query (plus the sequence matching with `--sequence`).

use raypath_place_recognition::report::{CrossMatchReport, CrossReport};
use raypath_place_recognition::{
    Confidence, CrossRun, CrossSummary, CrossTruth, OwnedFrame, PlaceError, PlaceRecognizer,
    ScoreMatrix, SequenceConfig, cross_summary, run_cross, sequence_match_timed,
};

use super::input::{Input, read_images, read_input};
use super::{Args, WithRecognizer, dispatch};
use crate::commands::Failure;

/// Queries and database, read and checked.
struct Folders {
    queries: Input,
    database: Input,
    query_names: Vec<String>,
    database_names: Vec<String>,
}

fn check(args: &Args) -> Result<(), Failure> {
    let bad = |m: &str| Err(Failure::input(m));
    if args.ground_truth.is_some() || args.record.record.is_some() {
        return bad(
            "--database: the ground truth is the file names; --ground-truth and --record do not apply",
        );
    }
    if args.sequence == Some(0) {
        return bad("--sequence: D_S must be at least 1");
    }
    Ok(())
}

fn read_folders(args: &Args) -> Result<Folders, Failure> {
    let Some(db_dir) = &args.database else {
        return Err(Failure::input("--database DIR is missing"));
    };
    let mut queries = read_input(&args.input, &args.source, args.max_frames)?;
    let Some(query_names) = queries.image_names() else {
        return Err(Failure::input(format!(
            "{}: --database needs a folder of query images, not {}",
            args.input.display(),
            queries.kind()
        )));
    };
    let mut database = read_images(db_dir)?;
    let first = database
        .frame(0)
        .map_err(|e| Failure::input(e.to_string()))?;
    let OwnedFrame::Image(first) = first else {
        return Err(Failure::internal("an image folder gave a non-image frame"));
    };
    let size = Some((first.width(), first.height()));
    database.image_size = size;
    queries.image_size = size;
    let database_names = database.image_names().unwrap_or_default();
    Ok(Folders {
        queries,
        database,
        query_names,
        database_names,
    })
}

/// Runs the recognizer over the two folders.
struct Cross<'a> {
    folders: &'a Folders,
}

impl WithRecognizer for Cross<'_> {
    type Output = CrossRun;
    fn run<R: PlaceRecognizer + Sync>(self, mut recognizer: R) -> Result<CrossRun, Failure> {
        let (db, q) = (&self.folders.database, &self.folders.queries);
        let bar = crate::commands::console::progress(db.len() + q.len(), "place recognition");
        let run = run_cross(
            &mut recognizer,
            db.len(),
            |i| {
                bar.inc(1);
                db.frame(i)
            },
            q.len(),
            |i| {
                bar.inc(1);
                q.frame(i)
            },
        );
        run.map_err(|e: PlaceError| Failure::input(e.to_string()))
    }
}

/// `raypath loop-closure QUERY_DIR --database DB_DIR` (module documentation).
pub fn run(args: &Args) -> Result<(), Failure> {
    check(args)?;
    let folders = read_folders(args)?;
    let run = dispatch(args, &folders.database, Cross { folders: &folders })?;
    let truth = CrossTruth::by_name(
        &folders.query_names,
        &folders.database_names,
        args.tolerance,
    );
    let place = |e: PlaceError| Failure::input(format!("{}: {e}", args.input.display()));
    let single = cross_summary(&run.scores, &truth, Confidence::Score).map_err(place)?;
    let (scores, summary, sequence_ms) = match args.sequence {
        Some(length) => {
            let config = SequenceConfig {
                length,
                ..SequenceConfig::default()
            };
            let (scores, ms) = sequence_match_timed(&run.scores, &config).map_err(place)?;
            let margin = Confidence::Margin {
                window: config.contrast_window,
            };
            let summary = cross_summary(&scores, &truth, margin).map_err(place)?;
            (scores, summary, Some(ms))
        }
        None => (run.scores.clone(), single, None),
    };
    let ms = run.ms_per_query() + sequence_ms.unwrap_or(0.0);
    let report = Report {
        args,
        folders: &folders,
        method: run.method,
        scores: &scores,
        truth: &truth,
        summary,
        single: args.sequence.map(|_| single),
        ms,
        sequence_ms,
    };
    if crate::commands::console::json() {
        crate::commands::print_json(&report.json())?;
    } else {
        report.print();
    }
    Ok(())
}

/// What the command prints.
struct Report<'a> {
    args: &'a Args,
    folders: &'a Folders,
    method: &'static str,
    scores: &'a ScoreMatrix,
    truth: &'a CrossTruth,
    summary: CrossSummary,
    single: Option<CrossSummary>,
    ms: f64,
    sequence_ms: Option<f64>,
}

impl Report<'_> {
    fn json(&self) -> CrossReport {
        let f = self.folders;
        let matches = (0..self.scores.queries())
            .filter_map(|q| {
                let best = self.scores.best(q, 1).into_iter().next()?;
                Some(CrossMatchReport {
                    query: f.query_names[q].clone(),
                    matched: f.database_names.get(best.frame).cloned(),
                    score: best.score,
                    correct: self.truth.is_match(q, best.frame),
                })
            })
            .collect();
        CrossReport {
            method: self.method,
            queries: f.queries.len(),
            database: f.database.len(),
            tolerance: self.args.tolerance,
            sequence: self.args.sequence,
            ms_per_query: self.ms,
            sequence_ms_per_query: self.sequence_ms,
            summary: self.summary,
            single_image: self.single,
            matches,
        }
    }

    fn print(&self) {
        let f = self.folders;
        println!(
            "{}: {} query images against {} database images ({}), method {}{}",
            self.args.input.display(),
            f.queries.len(),
            f.database.len(),
            f.database.path.display(),
            self.method,
            match self.args.sequence {
                Some(d) => format!(", sequence matching d_s = {d}"),
                None => String::new(),
            }
        );
        println!("{:.2} ms per query", self.ms);
        let line = |what: &str, s: &CrossSummary| {
            println!(
                "{what}: recall at 100% precision {:.4}, recall@1 {:.4}, recall@5 {:.4}, max F1 \
                 {:.4} ({} queries with a match within {} frames)",
                s.recall_at_100_precision,
                s.recall_at_1,
                s.recall_at_5,
                s.max_f1,
                s.positives,
                self.args.tolerance
            );
        };
        line(
            if self.single.is_some() {
                "sequence"
            } else {
                "single image"
            },
            &self.summary,
        );
        if let Some(s) = &self.single {
            line("single image", s);
        }
        if self.summary.positives == 0 {
            println!("warning: no query's file name is in the database; the summary is empty");
        }
    }
}
