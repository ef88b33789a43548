//! Point CSV reader: the real pole maps, known answers, error places, no panic.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::io::Cursor;

mod common;

use proptest::prelude::*;
use raypath_io::Location;
use raypath_io::data::require;
use raypath_io::point_csv::{PointCsv, PointCsvReader};

#[test]
fn nclt_pole_maps() {
    for (name, rows, columns) in [
        ("ground-truth-poles.csv", 1205, &["x", "y", "z"][..]),
        ("pole-map-polemeans.csv", 1635, &["x", "y", "w"][..]),
        ("pole-map-segment-positions.csv", 12999, &["x", "y"][..]),
    ] {
        let Some(path) = require(format!("nclt-poles/{name}")) else {
            return;
        };
        let csv = PointCsv::read(&path).unwrap();
        assert_eq!(csv.len(), rows, "{name}");
        assert_eq!(csv.columns, columns, "{name}");
        let summary = raypath_io::summarize(&path).unwrap();
        assert_eq!(summary.format, "point-csv");
        assert_eq!(summary.points, Some(rows as u64));
        assert_eq!(summary.extra["columns"], serde_json::json!(columns));
        let bbox = summary.bbox.unwrap();
        // The campus spans hundreds of metres.
        assert!(bbox.max[0] - bbox.min[0] > 100.0 && bbox.max[1] - bbox.min[1] > 100.0);
        if columns.len() == 2 {
            assert_eq!((bbox.min[2], bbox.max[2]), (0.0, 0.0));
        }
    }
    let Some(path) = require("nclt-poles/pole-map-polemeans.csv") else {
        return;
    };
    // Pole widths are centimetres to decimetres.
    let widths = PointCsv::read(&path).unwrap().column("w").unwrap();
    assert!(widths.iter().all(|&w| w > 0.0 && w < 1.0));
    // Ground-truth pole heights are metres above the ground (z column).
    let Some(path) = require("nclt-poles/ground-truth-poles.csv") else {
        return;
    };
    let poles = PointCsv::read(&path).unwrap();
    let first = poles.points()[0];
    assert_eq!((first.x, first.y, first.z), (8.0801, -1.7903, 1.6079));
}

#[test]
fn kitti_pole_maps() {
    let Some(root) = require("kitti-poles") else {
        return;
    };
    for seq in ["00", "01", "02", "03", "04", "05", "06", "07"] {
        let path = root.join(seq).join("poles.csv");
        let text = std::fs::read_to_string(&path).unwrap();
        let rows = text
            .lines()
            .skip(1)
            .filter(|l| !l.trim().is_empty())
            .count();
        let csv = PointCsv::read(&path).unwrap();
        assert_eq!(csv.columns, ["x", "y"]);
        assert_eq!(csv.len(), rows, "sequence {seq}");
        assert!(rows > 10);
    }
}

fn parse(text: &str) -> raypath_io::Result<PointCsv> {
    PointCsv::parse(Cursor::new(text.as_bytes().to_vec()), "p.csv")
}

#[test]
fn known_answers_and_errors() {
    let csv = parse("X, Y ,z,w\n1,2,3,4\n\n5,6,7,8\n").unwrap();
    assert_eq!(csv.columns, ["X", "Y", "z", "w"]);
    assert_eq!(csv.len(), 2);
    assert_eq!(csv.row(1), Some(&[5.0, 6.0, 7.0, 8.0][..]));
    assert_eq!(csv.row(2), None);
    assert_eq!(csv.points()[1], nalgebra::Point3::new(5.0, 6.0, 7.0));
    assert_eq!(csv.column("W"), Some(vec![4.0, 8.0]));
    // Header only: no points.
    assert!(parse("x,y\n").unwrap().is_empty());
    // Streaming gives the same rows.
    let mut reader =
        PointCsvReader::new(Cursor::new(b"x,y\n1,2\n3,4\n".to_vec()), "p.csv").unwrap();
    assert_eq!(reader.next_row().unwrap(), Some(&[1.0, 2.0][..]));
    assert_eq!(reader.next_row().unwrap(), Some(&[3.0, 4.0][..]));
    assert_eq!(reader.next_row().unwrap(), None);

    let cases: [(&str, u64, &str); 7] = [
        ("", 1, "unexpected end of file"),
        ("a,b\n1,2\n", 1, "must start with the columns x,y"),
        ("x,y,,w\n", 1, "column 3 has no name"),
        ("x,y\n1,2\n3\n", 3, "1 values, the header has 2 columns"),
        ("x,y\n1,2,3\n", 2, "more than the 2 columns"),
        ("x,y\n1,two\n", 2, "y: cannot parse \"two\""),
        ("x,y\n1,2\nnan,2\n", 3, "x is NaN"),
    ];
    for (text, line, message) in cases {
        let err = parse(text).unwrap_err();
        assert_eq!(err.location(), Location::Line(line), "{text:?}: {err}");
        assert!(err.to_string().contains(message), "{text:?}: {err}");
    }
}

const ALPHABET: &[u8] = b"0123456789.-+e,\n xyzwn";

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn reader_never_panics(
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<usize>(), any::<usize>()), 0..5),
        invalid_utf8 in any::<bool>(),
    ) {
        let source = b"x,y,w\n8.1320,-1.7499,0.0468\n-5.5911,6.3091,0.0504\n1e3,2,3\n";
        let bytes = common::mutated(source, cut, &edits, invalid_utf8, ALPHABET);
        match PointCsv::parse(Cursor::new(bytes), "p.csv") {
            Ok(csv) => {
                prop_assert_eq!(csv.values.len(), csv.len() * csv.columns.len());
                prop_assert!(csv.values.iter().all(|v| v.is_finite()));
            }
            Err(e) => prop_assert!(matches!(e.location(), Location::Line(_))),
        }
    }
}
