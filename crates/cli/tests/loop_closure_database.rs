//! `raypath loop-closure QUERY_DIR --database DB_DIR`: a generated query folder against a
//! generated database folder (known answer: every query finds its own place), the JSON
//! contract, bad input exiting with 2 and naming the file, and the real Nordland seasons when
//! RAYPATH_DATA has them.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::path::{Path, PathBuf};

use image::{GrayImage, Luma};
use raypath_io::data::require;

mod common;
use common::{json_of, raypath};

/// A textured 64 × 32 image: seeded pseudo-random blocks of 4 × 4 pixels, scaled by `gain`
/// and shifted by `offset` (a season change the patch normalisation undoes).
fn texture(seed: u64, gain: f64, offset: f64) -> GrayImage {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut blocks = [0u8; 16 * 8];
    for b in &mut blocks {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        *b = (state >> 56) as u8;
    }
    GrayImage::from_fn(64, 32, |x, y| {
        let v = f64::from(blocks[(y / 4 * 16 + x / 4) as usize]) * gain + offset;
        Luma([v.clamp(0.0, 255.0) as u8])
    })
}

/// Twenty places: `db/place-NN.png` as they are, `queries/place-NN.png` dimmer (the queries
/// in reverse name order on disk does not matter: folders are read in name order).
fn write_folders(dir: &Path) -> (PathBuf, PathBuf) {
    let (db, queries) = (dir.join("db"), dir.join("queries"));
    std::fs::create_dir_all(&db).unwrap();
    std::fs::create_dir_all(&queries).unwrap();
    for place in 0..20u64 {
        let name = format!("place-{place:02}.png");
        texture(place, 1.0, 0.0).save(db.join(&name)).unwrap();
        texture(place, 0.6, 30.0).save(queries.join(&name)).unwrap();
    }
    (queries, db)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn queries_find_their_places_with_and_without_sequences() {
    let dir = tempfile::tempdir().unwrap();
    let (queries, db) = write_folders(dir.path());
    let out = raypath(&[
        "loop-closure",
        s(&queries),
        "--database",
        s(&db),
        "--method",
        "raw-pixels",
        "--tolerance",
        "0",
        "--json",
    ]);
    let doc = json_of(&out);
    let mut keys: Vec<&str> = doc
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        [
            "database",
            "matches",
            "method",
            "ms_per_query",
            "queries",
            "sequence",
            "sequence_ms_per_query",
            "single_image",
            "summary",
            "tolerance"
        ]
    );
    assert_eq!(doc["method"], "raw-pixels");
    assert_eq!(doc["queries"], 20);
    assert_eq!(doc["summary"]["recall_at_1"], 1.0);
    assert_eq!(doc["summary"]["positives"], 20);
    let first = &doc["matches"][0];
    assert_eq!(first["query"], "place-00.png");
    assert_eq!(first["match"], "place-00.png");
    assert_eq!(first["correct"], true);

    // Sequence matching keeps the known answer; the single-image summary is kept beside it.
    let out = raypath(&[
        "loop-closure",
        s(&queries),
        "--database",
        s(&db),
        "--method",
        "hog",
        "--sequence",
        "3",
        "--json",
    ]);
    let doc = json_of(&out);
    assert_eq!(doc["sequence"], 3);
    assert_eq!(doc["summary"]["recall_at_1"], 1.0);
    assert!(doc["single_image"]["recall_at_1"].as_f64().unwrap() > 0.0);
    assert!(doc["sequence_ms_per_query"].as_f64().unwrap() >= 0.0);

    // The feature methods run on 64 × 32 images (enlarged 4× by default).
    for method in ["ibuild", "dbow", "gist"] {
        let out = raypath(&[
            "loop-closure",
            s(&queries),
            "--database",
            s(&db),
            "--method",
            method,
        ]);
        assert!(
            out.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("recall@1"), "{text}");
    }
}

#[test]
fn bad_folders_and_parameters_exit_2_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let (queries, db) = write_folders(dir.path());
    let run = |args: &[&str]| {
        let mut all = vec!["loop-closure", s(&queries)];
        all.extend_from_slice(args);
        let out = raypath(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let missing = dir.path().join("nowhere");
    assert!(run(&["--database", s(&missing)]).contains("nowhere"));
    let empty = dir.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    assert!(run(&["--database", s(&empty)]).contains("empty"));
    assert!(run(&["--database", s(&db), "--sequence", "0"]).contains("--sequence"));
    assert!(run(&["--sequence", "5"]).contains("--database"));
    assert!(run(&["--database", s(&db), "--upscale", "0"]).contains("--upscale"));

    // A PNG of another size, and a file named .png that is not one.
    GrayImage::new(32, 32)
        .save(queries.join("place-05.png"))
        .unwrap();
    let err = run(&["--database", s(&db), "--method", "raw-pixels"]);
    assert!(
        err.contains("place-05.png") && err.contains("32×32"),
        "{err}"
    );
    std::fs::write(queries.join("place-05.png"), b"not a png").unwrap();
    let err = run(&["--database", s(&db), "--method", "raw-pixels"]);
    assert!(err.contains("place-05.png"), "{err}");
}

#[test]
fn nordland_sequences_beat_single_images() {
    let (Some(summer), Some(winter)) = (require("nordland/summer"), require("nordland/winter"))
    else {
        return;
    };
    let run = |extra: &[&str]| {
        let mut args = vec![
            "loop-closure",
            winter.to_str().unwrap(),
            "--database",
            summer.to_str().unwrap(),
            "--method",
            "raw-pixels",
            "--max-frames",
            "400",
            "--json",
        ];
        args.extend_from_slice(extra);
        json_of(&raypath(&args))
    };
    let doc = run(&["--sequence", "10"]);
    let single = doc["single_image"]["recall_at_1"].as_f64().unwrap();
    let sequence = doc["summary"]["recall_at_1"].as_f64().unwrap();
    // Across seasons single raw-pixel images rarely find their place; sequences of ten do far
    // more often (SeqSLAM's point).
    assert!(
        single < 0.5 && sequence > 2.0 * single,
        "{single} {sequence}"
    );
    assert_eq!(doc["database"], 3576);
    assert_eq!(doc["queries"], 400);
}
