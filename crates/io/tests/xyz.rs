//! Plain x y z text: known answers, errors, the OctoMap sample scan, robustness.
#![allow(clippy::unwrap_used)]

use std::io::Write;

use nalgebra::Point3;
use proptest::prelude::*;
use raypath_io::xyz::{self, XyzReader};
use raypath_io::{Format, Location, summarize};

fn reader(text: &str) -> XyzReader {
    XyzReader::new(std::io::Cursor::new(text.as_bytes().to_vec()), "t.xyz")
}

#[test]
fn reads_points_comments_and_extra_columns() {
    let text = "# header\n\n1 2 3 0.5\n  -4\t5e-1 6 7 # note\n";
    let cloud = xyz::read_xyz_from(text.as_bytes(), "t.xyz").unwrap();
    assert_eq!(
        cloud.points,
        vec![Point3::new(1.0, 2.0, 3.0), Point3::new(-4.0, 0.5, 6.0)]
    );
    assert_eq!((cloud.width, cloud.height), (2, 1));
    let mut r = reader(text);
    let mut chunk = Vec::new();
    assert_eq!(r.next_chunk(1, &mut chunk).unwrap(), 1);
    assert_eq!(r.next_chunk(10, &mut chunk).unwrap(), 1);
    assert_eq!(r.next_chunk(10, &mut chunk).unwrap(), 0);
    assert_eq!(r.columns(), Some(4));
}

#[test]
fn errors_name_the_line() {
    let err = reader("1 2 3\n1 nan 3\n")
        .collect::<Result<Vec<_>, _>>()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "t.xyz:2: y: nan is not a finite coordinate"
    );
    let err = reader("1 2 3\n1 2 1e39\n")
        .collect::<Result<Vec<_>, _>>()
        .unwrap_err();
    assert_eq!(err.location(), Location::Line(2));
    let err = reader("1 2\n").collect::<Result<Vec<_>, _>>().unwrap_err();
    assert_eq!(
        err.to_string(),
        "t.xyz:1: missing z: a point line needs x y z"
    );
    let err = reader("1 2 3\n\n1 2 3 4\n")
        .collect::<Result<Vec<_>, _>>()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "t.xyz:3: 4 columns; the first point line had 3"
    );
    let err = reader("x y z\n")
        .collect::<Result<Vec<_>, _>>()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "t.xyz:1: x: cannot parse \"x\" as a number"
    );
    // The iterator stops after an error.
    let mut r = reader("a\n1 2 3\n");
    assert!(r.next().unwrap().is_err());
    assert!(r.next().is_none());
}

#[test]
fn reads_gzip_and_summarizes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("points.xyz.gz");
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(b"0 0 0\n1 -2 3\n").unwrap();
    std::fs::write(&path, enc.finish().unwrap()).unwrap();
    assert_eq!(Format::detect(&path).unwrap(), Format::Xyz);
    let summary = summarize(&path).unwrap();
    assert_eq!(summary.format, "xyz");
    assert_eq!(summary.points, Some(2));
    let bbox = summary.bbox.unwrap();
    assert_eq!((bbox.min, bbox.max), ([0.0, -2.0, 0.0], [1.0, 0.0, 3.0]));
}

#[test]
fn octomap_scan_has_88206_points() {
    let Some(path) = raypath_io::data::require("octomap/scan.dat.bz2") else {
        return;
    };
    let cloud = xyz::read_xyz(&path).unwrap();
    assert_eq!(cloud.len(), 88_206);
    assert_eq!(cloud.points[0], Point3::new(-0.0434742, -4.82982, 0.499645));
    let summary = summarize(&path).unwrap();
    assert_eq!(summary.format, "xyz");
    assert_eq!(summary.points, Some(88_206));
    // A real indoor/outdoor scan around a sensor at the origin: tens of metres, z mostly above
    // the floor a metre below the sensor.
    let bbox = summary.bbox.unwrap();
    let expect = |v: f64, want: f64| assert!((v - want).abs() < 1e-4, "{v} vs {want}");
    expect(bbox.min[0], -0.0799911);
    expect(bbox.max[0], 27.1628);
    expect(bbox.min[1], -15.1026);
    expect(bbox.max[1], 16.4627);
    expect(bbox.min[2], -1.03673);
    expect(bbox.max[2], 10.1088);
}

fn base() -> Vec<u8> {
    b"# scan\n0.5 1 2\n-1 2e3 3 # c\n\n4 5 6\n7 8 9\n".to_vec()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn truncated_and_mutated_files_never_panic(
        cut in 0usize..64,
        edits in prop::collection::vec((0usize..64, any::<u8>()), 0..5),
    ) {
        let mut bytes = base();
        bytes.truncate(cut.max(bytes.len() / 2).min(bytes.len()));
        for (at, v) in edits {
            if !bytes.is_empty() {
                let i = at % bytes.len();
                bytes[i] = v;
            }
        }
        let result = xyz::read_xyz_from(std::io::Cursor::new(bytes), "m.xyz");
        if let Ok(cloud) = result {
            prop_assert!(cloud.points.iter().all(|p| p.iter().all(|v| v.is_finite())));
        }
    }
}
