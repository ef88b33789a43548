//! `--record OUT.mcap` on the planar commands (`map`, `localize`, `scan-match`, `polylines`,
//! `dct-map`, `loop-closure`) end to end on a synthetic room log: each recording is read back
//! with the `mcap` crate — topics, `foxglove.*` schemas (encoding `jsonschema`), message
//! counts, log times — and decoded values are checked against the command's own JSON; the
//! JSON keeps its keys and only gains `record`.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use serde_json::Value;

mod common;
mod record_common;
use common::{json_of, raypath};
use record_common::{SCANS, T0, along, grid_cells, record, room_log, room_pose, s, xy};

/// The keys of a JSON object.
fn keys(doc: &Value) -> Vec<String> {
    doc.as_object().unwrap().keys().cloned().collect()
}

#[test]
fn map_records_scans_trajectory_and_map() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path());
    let out = dir.path().join("room");
    let grid = ["--model", "reflection", "--resolution", "0.1"];
    let args = [&["map", s(&log), "--out", s(&out)][..], &grid].concat();
    let plain = json_of(&raypath(&[&args[..], &["--json"]].concat()));
    assert!(plain.get("record").is_none());
    let (doc, rec) = record(&args, dir.path().join("rec/map.mcap"));
    // The document keeps every key and value (but the timings) and gains `record`.
    let mut with: Vec<String> = keys(&plain);
    with.push("record".into());
    with.sort();
    assert_eq!(keys(&doc), with);
    for key in ["grid", "cells", "observed_cells", "rays", "hits", "extent"] {
        assert_eq!(doc[key], plain[key], "{key}");
    }

    rec.expect_topics(&doc, &along("/scan", SCANS, "/map"));
    // Scan k at its stamp and pose; the laser sits on the robot (no mount offset).
    for (k, (time, tf)) in rec["/tf"].messages.iter().enumerate() {
        let expected = (T0 + 0.1 * k as f64) * 1e9;
        assert!(
            (*time as f64 - expected).abs() < 1e3,
            "{time} vs {expected}"
        );
        let [x, y, _] = room_pose(k);
        let (tx, ty) = xy(&tf["translation"]);
        assert!((tx - x).abs() < 1e-9 && (ty - y).abs() < 1e-9);
        assert_eq!(tf["parent_frame_id"], "map");
        assert_eq!(tf["child_frame_id"], "base_link");
    }
    let scan = rec.first("/scan");
    assert_eq!(scan["frame_id"], "base_link");
    assert_eq!(scan["ranges"].as_array().unwrap().len(), 181);
    assert_eq!(scan["pose"]["position"]["x"], 0.0);
    let poses = rec.first("/trajectory")["poses"].as_array().unwrap();
    assert_eq!(poses.len(), SCANS);
    // The map: the command's grid, reflection probabilities in [0, 1] (NaN unknown), walls
    // reflecting, the open room not.
    let map = rec.first("/map");
    assert_eq!(map["fields"][0]["name"], "reflection");
    let (columns, rows, cells) = grid_cells(map);
    assert_eq!(doc["grid"], serde_json::json!([columns, rows]));
    let (x0, y0) = xy(&map["pose"]["position"]);
    assert!((x0 - doc["extent"]["min"][0].as_f64().unwrap()).abs() < 1e-9);
    assert!((y0 - doc["extent"]["min"][1].as_f64().unwrap()).abs() < 1e-9);
    let known: Vec<f32> = cells.iter().copied().filter(|v| !v.is_nan()).collect();
    assert_eq!(known.len() as u64, doc["observed_cells"].as_u64().unwrap());
    assert!(known.iter().all(|v| (0.0..=1.0).contains(v)));
    let cell = |x: f64, y: f64| {
        let (i, j) = (((x - x0) / 0.1) as usize, ((y - y0) / 0.1) as usize);
        cells[j * columns + i]
    };
    assert!(cell(1.0, 0.3) < 0.05, "room centre {}", cell(1.0, 0.3));
    assert!(known.iter().any(|&v| v > 0.5));
}

#[test]
fn localize_records_map_estimates_and_ground_truth() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path());
    let prefix = dir.path().join("room");
    json_of(&raypath(&[
        "map",
        s(&log),
        "--model",
        "decay-rate",
        "--resolution",
        "0.1",
        "--out",
        s(&prefix),
        "--json",
    ]));
    let map = dir.path().join("room.rpmap");
    let args = [
        "localize",
        "--map",
        s(&map),
        "--log",
        s(&log),
        "--ground-truth",
        s(&log),
        "--particles",
        "200",
    ];
    let (doc, rec) = record(&args, dir.path().join("localize.mcap"));
    assert!(!doc["error"].is_null(), "{doc}");
    let estimates = rec["/tf"].messages.len();
    assert!(estimates >= 2, "{estimates}");
    let mut topics = along("/scan", estimates, "/map");
    topics.push(("/ground_truth", 1));
    rec.expect_topics(&doc, &topics);
    // The map is there from the first scan on; the last estimate is the final pose.
    assert_eq!(rec["/map"].messages[0].0, (T0 * 1e9) as u64);
    assert_eq!(rec.first("/map")["fields"][0]["name"], "hit_probability");
    let poses = rec.first("/trajectory")["poses"].as_array().unwrap();
    assert_eq!(poses.len(), estimates);
    let (x, y) = xy(&poses[estimates - 1]["position"]);
    let final_pose = &doc["final_pose"];
    assert!((x - final_pose[0].as_f64().unwrap()).abs() < 1e-9);
    assert!((y - final_pose[1].as_f64().unwrap()).abs() < 1e-9);
    let truth = rec.first("/ground_truth")["poses"].as_array().unwrap();
    assert_eq!(truth.len(), SCANS);
    let [x, y, _] = room_pose(SCANS - 1);
    let (tx, ty) = xy(&truth[SCANS - 1]["position"]);
    assert!((tx - x).abs() < 1e-9 && (ty - y).abs() < 1e-9);
}

#[test]
fn scan_match_records_scans_trajectory_and_occupancy() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path());
    let args = ["scan-match", s(&log), "--odometry", "--size", "20"];
    let (doc, rec) = record(&args, dir.path().join("scan-match.mcap"));
    // No remissions: no reflectivity layer.
    rec.expect_topics(&doc, &along("/scan", SCANS, "/map"));
    let map = rec.first("/map");
    assert_eq!(map["fields"][0]["name"], "occupancy");
    assert!((map["cell_size"]["x"].as_f64().unwrap() - 0.05).abs() < 1e-12);
    let (_, _, cells) = grid_cells(map);
    let known: Vec<f32> = cells.into_iter().filter(|v| !v.is_nan()).collect();
    assert!(known.iter().all(|v| (0.0..=1.0).contains(v)));
    assert!(known.iter().any(|v| *v > 0.65) && known.iter().any(|v| *v < 0.2));
    // The map frame starts at the first scan.
    let (x, y) = xy(&rec.first("/tf")["translation"]);
    assert!(x.abs() < 1e-9 && y.abs() < 1e-9);
}

#[test]
fn polylines_records_scans_and_line_strips_and_reports_in_text() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path());
    let mcap = dir.path().join("polylines.mcap");
    let (doc, rec) = record(&["polylines", s(&log), "--scans", "0,5"], mcap.clone());
    rec.expect_topics(&doc, &[("/tf", 2), ("/scan", 2), ("/polylines", 2)]);
    // Each scan's polylines, in base_link (= the laser frame here), vertex for vertex.
    for (i, (time, update)) in rec["/polylines"].messages.iter().enumerate() {
        let index = doc["scans"][i]["index"].as_u64().unwrap();
        assert!((*time as f64 - (T0 + 0.1 * index as f64) * 1e9).abs() < 1e3);
        let entity = &update["entities"][0];
        assert_eq!(entity["id"], "polylines");
        assert_eq!(entity["frame_id"], "base_link");
        let lines = entity["lines"].as_array().unwrap();
        let expected = doc["scans"][i]["polylines"].as_array().unwrap();
        assert_eq!(lines.len(), expected.len());
        for (line, vertices) in lines.iter().zip(expected) {
            let points = line["points"].as_array().unwrap();
            let vertices = vertices.as_array().unwrap();
            assert_eq!(points.len(), vertices.len());
            for (p, v) in points.iter().zip(vertices) {
                let (x, y) = xy(p);
                assert!((x - v[0].as_f64().unwrap()).abs() < 1e-9);
                assert!((y - v[1].as_f64().unwrap()).abs() < 1e-9);
            }
        }
    }
    // Without --json, one line names the recording and its messages.
    let out = raypath(&["polylines", s(&log), "--record", s(&mcap)]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let line = format!(
        "recorded {}: 3 messages (/polylines 1, /scan 1, /tf 1)",
        s(&mcap)
    );
    assert!(text.lines().any(|l| l == line), "{text}");
}

#[test]
fn dct_map_records_the_map_and_the_baseline() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path());
    let args = [
        "dct-map",
        s(&log),
        "--patch=-2,-2,4,4",
        "--coefficients",
        "4,4",
        "--rays",
        "2000",
    ];
    let (doc, rec) = record(&args, dir.path().join("dct.mcap"));
    rec.expect_topics(&doc, &[("/map", 1), ("/baseline", 1), ("/trajectory", 1)]);
    let last = ((T0 + 0.1 * (SCANS - 1) as f64) * 1e9) as u64;
    assert!(rec["/map"].messages[0].0.abs_diff(last) < 1000);
    // The DCT map on 5 cm cells over the 4 m patch; the baseline 4 × 4 cells of 1 m.
    let map = rec.first("/map");
    assert_eq!(map["fields"][0]["name"], "decay_rate");
    assert_eq!(xy(&map["pose"]["position"]), (-2.0, -2.0));
    let (columns, rows, rates) = grid_cells(map);
    assert_eq!((columns, rows), (80, 80));
    assert!(rates.iter().all(|r| r.is_finite() && *r >= 0.0));
    let baseline = rec.first("/baseline");
    assert_eq!(xy(&baseline["pose"]["position"]), (-2.0, -2.0));
    let (columns, rows, rates) = grid_cells(baseline);
    assert_eq!((columns, rows), (4, 4));
    assert!((baseline["cell_size"]["x"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    assert!(rates.iter().all(|r| r.is_finite() && *r > 0.0));
    assert_eq!(
        rec.first("/trajectory")["poses"].as_array().unwrap().len(),
        SCANS
    );
}

#[test]
fn loop_closure_records_the_trajectory_and_the_loops() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path());
    let args = [
        "loop-closure",
        s(&log),
        "--method",
        "polar",
        "--exclusion-frames",
        "6",
        "--no-temporal-consistency",
    ];
    let (doc, rec) = record(&args, dir.path().join("loops.mcap"));
    let loops = doc["loops"].as_array().unwrap();
    assert!(!loops.is_empty(), "{doc}");
    rec.expect_topics(&doc, &[("/tf", SCANS), ("/trajectory", 1), ("/loops", 1)]);
    // One segment per loop, from the query's pose to the match's.
    let line = &rec.first("/loops")["entities"][0]["lines"][0];
    assert_eq!(line["type"], 2, "LINE_LIST");
    let points = line["points"].as_array().unwrap();
    assert_eq!(points.len(), 2 * loops.len());
    for (l, pair) in loops.iter().zip(points.chunks(2)) {
        for (frame, point) in [(&l["query"], &pair[0]), (&l["match"], &pair[1])] {
            let [x, y, _] = room_pose(frame.as_u64().unwrap() as usize);
            let (px, py) = xy(point);
            assert!((px - x).abs() < 1e-9 && (py - y).abs() < 1e-9);
        }
    }
}

#[test]
fn an_unwritable_recording_fails_with_exit_1_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path());
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, "not a directory").unwrap();
    let mcap = blocker.join("out.mcap");
    let out = raypath(&["polylines", s(&log), "--record", s(&mcap), "--json"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(s(&blocker)), "{stderr}");
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(doc["error"].is_string());
}
