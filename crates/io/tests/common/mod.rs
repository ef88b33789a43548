//! Helpers shared by the tests: poses and scans compared within tolerances (rosbag2 tests),
//! mutated input for the text readers' property tests.
#![allow(dead_code)] // not every test file uses every helper

use raypath_geometry::{Pose2, Pose3, Range, Scan2};

/// Asserts two planar poses agree within `tol` (metres, radians; angles wrapped).
pub fn assert_pose2(a: &Pose2, b: &Pose2, tol: f64, what: &str) {
    assert!(
        (a.x() - b.x()).abs() < tol
            && (a.y() - b.y()).abs() < tol
            && raypath_geometry::wrap_angle(a.theta() - b.theta()).abs() < tol,
        "{what}: {a:?} vs {b:?}"
    );
}

/// Asserts two 3-D poses agree within `tol` (metres of translation, radians of rotation).
pub fn assert_pose3(a: &Pose3, b: &Pose3, tol: f64, what: &str) {
    assert!(
        (a.translation() - b.translation()).norm() < tol
            && a.rotation().angle_to(&b.rotation()) < tol,
        "{what}: {a:?} vs {b:?}"
    );
}

/// Same scans up to float32 rounding: no-returns where the source has them, ranges, angles
/// and intensities equal to float32 precision.
pub fn assert_same_scan(a: &Scan2, b: &Scan2, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: beams");
    assert_eq!(
        a.max_range_m as f32, b.max_range_m as f32,
        "{what}: max range"
    );
    assert!(
        (a.angle_min_rad - b.angle_min_rad).abs() < 1e-6,
        "{what}: angle_min"
    );
    assert!(
        (a.angle_increment_rad - b.angle_increment_rad).abs() < 1e-7,
        "{what}: increment"
    );
    for i in 0..a.len() {
        match (a.range(i), b.range(i)) {
            (Range::Hit(x), Range::Hit(y)) => {
                assert_eq!(x as f32, y as f32, "{what}: beam {i}");
            }
            (Range::NoReturn, Range::NoReturn) => {}
            (x, y) => panic!("{what}: beam {i}: {x:?} vs {y:?}"),
        }
    }
    match (&a.intensities, &b.intensities) {
        (Some(x), Some(y)) => {
            assert!(
                x.iter().zip(y).all(|(p, q)| *p as f32 == *q as f32),
                "{what}: intensities"
            )
        }
        (None, None) => {}
        _ => panic!("{what}: intensities present in one only"),
    }
}

/// `source` cut to the fraction `cut` of its length, with the bytes at `edits` (positions
/// modulo the length) replaced by characters of `alphabet`, and one byte made invalid UTF-8
/// when `invalid_utf8` is set: the mutated input of the text readers' property tests.
pub fn mutated(
    source: &[u8],
    cut: f64,
    edits: &[(usize, usize)],
    invalid_utf8: bool,
    alphabet: &[u8],
) -> Vec<u8> {
    let len = ((source.len() as f64) * cut) as usize;
    let mut bytes = source[..len].to_vec();
    for &(at, c) in edits {
        if !bytes.is_empty() {
            let i = at % bytes.len();
            bytes[i] = alphabet[c % alphabet.len()];
        }
    }
    if invalid_utf8 && !bytes.is_empty() {
        let i = edits.first().map_or(0, |e| e.0 % bytes.len());
        bytes[i] = 0xfe;
    }
    bytes
}
