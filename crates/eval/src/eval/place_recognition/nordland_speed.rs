//! Section 6's speed table: every Nordland method timed against a database of more than
//! 10 000 **real** frames — summer, summer mirrored left–right and winter mirrored (10 728
//! frames; a quick run: three times its first frames) — with the first winter frames as
//! queries (none of them is in the database), on one thread. The aim: at most
//! 5 ms per query at 10 000 frames.

use std::fmt::Write;

use anyhow::Result;
use image::GrayImage;
use image::imageops::flip_horizontal;
use raypath_place_recognition::{SequenceConfig, sequence_match_timed};
use serde_json::{Value, json};

use super::nordland::{METHODS, SEQUENCE, Season, scores_of, vocabulary};
use crate::table::{Table, fmt_num};

/// Queries timed.
const QUERIES: usize = 100;
/// The aim, milliseconds per query.
const AIM_MS: f64 = 5.0;

/// The speed table.
pub struct Speed {
    /// Its markdown.
    pub markdown: String,
    /// Its JSON.
    pub json: Value,
}

/// Times every method (module documentation).
pub fn run(summer: &Season, winter: &Season) -> Result<Speed> {
    let mut database: Vec<GrayImage> = summer.images.clone();
    database.extend(summer.images.iter().map(flip_horizontal));
    database.extend(winter.images.iter().map(flip_horizontal));
    let queries: Vec<GrayImage> = winter.images.iter().take(QUERIES).cloned().collect();
    let vocabulary = vocabulary(&summer.images)?;
    let config = SequenceConfig {
        length: SEQUENCE,
        ..SequenceConfig::default()
    };
    let mut t = Table::new([
        "method",
        "database frames",
        "queries",
        "ms/query single image",
        "ms/query with sequence matching",
        "≤ 5 ms (with sequence)",
    ]);
    let mut rows = Vec::new();
    for method in METHODS {
        let started = std::time::Instant::now();
        let (scores, ms) = scores_of(method, &database, &queries, &vocabulary)?;
        let (_, sequence_ms) = sequence_match_timed(&scores, &config)?;
        let total = ms + sequence_ms;
        t.row([
            method.to_string(),
            database.len().to_string(),
            queries.len().to_string(),
            fmt_num(ms, 2),
            fmt_num(total, 2),
            if total <= AIM_MS { "yes" } else { "**no**" }.to_string(),
        ]);
        rows.push(json!({
            "method": method,
            "database": database.len(),
            "queries": queries.len(),
            "ms_per_query": ms,
            "ms_per_query_with_sequence": total,
        }));
        eprintln!(
            "nordland speed: {method} in {:.0} s",
            started.elapsed().as_secs_f64()
        );
    }
    let mut markdown = String::new();
    writeln!(
        markdown,
        "\n**Speed at a large database** (real frames: summer, summer mirrored and winter \
         mirrored, {} frames; the first {} winter frames as queries, none in the database; one \
         thread; describe + score against the whole database, plus the sequence matching of \
         the query with d_s = {SEQUENCE}). Aim: ≤ {AIM_MS} ms per query at 10 000 frames.\n",
        database.len(),
        queries.len()
    )?;
    markdown.push_str(&t.to_markdown()?);
    markdown.push('\n');
    Ok(Speed {
        markdown,
        json: json!(rows),
    })
}
