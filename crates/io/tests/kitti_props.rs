//! KITTI file readers: known answers, error places, and no panic on mutated input.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::io::Cursor;

use proptest::prelude::*;
use raypath_io::Location;
use raypath_io::kitti;

const POSES: &str = "1 0 0 0 0 1 0 0 0 0 1 0\n\
    9.999978e-01 5.272628e-04 -2.066935e-03 -4.690294e-02 -5.296506e-04 9.999992e-01 -1.154865e-03 -2.839928e-02 2.066324e-03 1.155958e-03 9.999971e-01 8.586941e-01\n\
    0 0 1 5 0 1 0 6 -1 0 0 7\n";
const TIMES: &str = "0.000000e+00\n1.037359e-01\n2.073381e-01\n";
const CALIB: &str = "P0: 7.188560000000e+02 0 6.071928e+02 0 0 7.188560e+02 1.852157e+02 0 0 0 1 0\n\
    P1: 7.188560000000e+02 0 6.071928e+02 -3.861448e+02 0 7.188560e+02 1.852157e+02 0 0 0 1 0\n\
    Tr: 4.276802e-04 -9.999672e-01 -8.084491e-03 -1.198459e-02 -7.210626e-03 8.081198e-03 -9.999413e-01 -5.403984e-02 9.999739e-01 4.859485e-04 -7.206982e-03 -2.921968e-01\n";

fn text(s: &str) -> Cursor<Vec<u8>> {
    Cursor::new(s.as_bytes().to_vec())
}

fn velodyne_bytes(n: usize) -> Vec<u8> {
    let mut bytes = Vec::new();
    for i in 0..n {
        for v in [i as f32, 2.0 * i as f32, -1.5, 0.5] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    bytes
}

#[test]
fn velodyne_decodes_and_checks_length() {
    let cloud = kitti::parse_velodyne(&velodyne_bytes(3), "s.bin").unwrap();
    assert_eq!(cloud.len(), 3);
    assert_eq!(cloud.points[2], nalgebra::Point3::new(2.0, 4.0, -1.5));
    assert_eq!(cloud.intensity.as_deref(), Some(&[0.5, 0.5, 0.5][..]));
    let err = kitti::parse_velodyne(&velodyne_bytes(3)[..40], "s.bin").unwrap_err();
    assert_eq!(err.location(), Location::Byte(32));
    let mut nan = velodyne_bytes(3);
    nan[20..24].copy_from_slice(&f32::NAN.to_le_bytes());
    let err = kitti::parse_velodyne(&nan, "s.bin").unwrap_err();
    assert_eq!(err.location(), Location::Byte(16));
    assert!(kitti::parse_velodyne(&[], "s.bin").unwrap().is_empty());
}

#[test]
fn poses_parse_as_world_from_cam0() {
    let poses = kitti::parse_poses(text(POSES), "p.txt").unwrap();
    assert_eq!(poses.len(), 3);
    assert!((poses[1].translation().z - 0.8586941).abs() < 1e-12);
    // The third pose turns camera z (forward) into world −x.
    let forward = poses[2].transform_vector(&nalgebra::Vector3::z());
    assert!(
        (forward - nalgebra::Vector3::x()).norm() < 1e-9,
        "{forward:?}"
    );
    let m = poses[2].to_matrix3x4();
    assert_eq!((m[(0, 3)], m[(1, 3)], m[(2, 3)]), (5.0, 6.0, 7.0));
    // Trailing blank lines are fine, inner ones are not.
    assert_eq!(
        kitti::parse_poses(text(&format!("{POSES}\n\n")), "p.txt")
            .unwrap()
            .len(),
        3
    );
    let gap = POSES.replacen('\n', "\n\n", 1);
    let err = kitti::parse_poses(text(&gap), "p.txt").unwrap_err();
    assert_eq!(err.location(), Location::Line(3));
    let err = kitti::parse_poses(text("1 0 0 0 0 1 0 0 0 0 1\n"), "p.txt").unwrap_err();
    assert!(
        err.to_string()
            .starts_with("p.txt:1: missing matrix entry 12"),
        "{err}"
    );
    let err = kitti::parse_poses(text("2 0 0 0 0 1 0 0 0 0 1 0\n"), "p.txt").unwrap_err();
    assert!(err.to_string().contains("not a rotation"), "{err}");
    let err = kitti::parse_poses(text("1 0 0 nan 0 1 0 0 0 0 1 0\n"), "p.txt").unwrap_err();
    assert_eq!(err.location(), Location::Line(1));
}

#[test]
fn times_are_seconds_in_order() {
    let times = kitti::parse_times(text(TIMES), "t.txt").unwrap();
    assert_eq!(times, [0.0, 0.1037359, 0.2073381]);
    let err = kitti::parse_times(text("0.2\n0.1\n"), "t.txt").unwrap_err();
    assert_eq!(err.location(), Location::Line(2));
    let err = kitti::parse_times(text("0.2 0.3\n"), "t.txt").unwrap_err();
    assert_eq!(err.location(), Location::Line(1));
}

#[test]
fn calib_variants() {
    let calib = kitti::parse_calib(text(CALIB), "calib.txt").unwrap();
    assert_eq!(calib.keys().collect::<Vec<_>>(), ["P0", "P1", "Tr"]);
    let p1 = calib.projection(1).unwrap();
    assert!((p1[(0, 3)] + 386.1448).abs() < 1e-9);
    assert!(calib.projection(2).is_none());
    let tr = calib.cam0_from_velo().unwrap();
    // Velodyne x (forward) is close to camera z (forward).
    let forward = tr.transform_vector(&nalgebra::Vector3::x());
    assert!(forward.z > 0.999);
    // The raw-data spellings give the same transform.
    let tr_line = CALIB
        .lines()
        .nth(2)
        .unwrap()
        .replacen("Tr:", "Tr_velo_to_cam:", 1);
    let named = kitti::parse_calib(text(&tr_line), "c.txt").unwrap();
    assert_eq!(named.cam0_from_velo(), Some(tr));
    let values: Vec<&str> = tr_line.split_whitespace().skip(1).collect();
    let r: Vec<&str> = [0, 1, 2, 4, 5, 6, 8, 9, 10]
        .iter()
        .map(|&i| values[i])
        .collect();
    let t: Vec<&str> = [3, 7, 11].iter().map(|&i| values[i]).collect();
    let raw = format!(
        "calib_time: 15-Mar-2012 11:37:16\nR: {}\nT: {}\n",
        r.join(" "),
        t.join(" ")
    );
    let raw = kitti::parse_calib(text(&raw), "calib_velo_to_cam.txt").unwrap();
    assert_eq!(raw.text["calib_time"], "15-Mar-2012 11:37:16");
    let d = raw.cam0_from_velo().unwrap().inverse() * tr;
    assert!(d.translation().norm() < 1e-12 && d.rotation().angle() < 1e-9);
    // Errors name the line.
    let err = kitti::parse_calib(text("P0: 1 2 3\n"), "c.txt").unwrap_err();
    assert!(
        err.to_string()
            .starts_with("c.txt:1: P0 has 3 values, expected 12"),
        "{err}"
    );
    let err =
        kitti::parse_calib(text("P0: 1 0 0 0 0 1 0 0 0 0 1 0\nno colon\n"), "c.txt").unwrap_err();
    assert_eq!(err.location(), Location::Line(2));
    let err = kitti::parse_calib(text("Tr: a b c\n"), "c.txt").unwrap_err();
    assert_eq!(err.location(), Location::Line(1));
}

/// Characters that keep mutated text close to the format.
const ALPHABET: &[u8] = b"0123456789.-+eE naif:\n\t,PTr";

fn mutate(bytes: &[u8], cut: f64, edits: &[(usize, usize)]) -> Vec<u8> {
    let len = ((bytes.len() as f64) * cut) as usize;
    let mut out = bytes[..len.min(bytes.len())].to_vec();
    for &(at, c) in edits {
        if !out.is_empty() {
            let i = at % out.len();
            out[i] = ALPHABET[c % ALPHABET.len()];
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1200))]

    #[test]
    fn text_readers_never_panic(
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<usize>(), any::<usize>()), 0..5),
        raw in any::<bool>(),
    ) {
        for source in [POSES, TIMES, CALIB] {
            let mut bytes = mutate(source.as_bytes(), cut, &edits);
            if raw && !bytes.is_empty() {
                let i = edits.first().map_or(0, |e| e.0 % bytes.len());
                bytes[i] = 0xff;
            }
            let _ = kitti::parse_poses(Cursor::new(bytes.clone()), "p.txt");
            let _ = kitti::parse_times(Cursor::new(bytes.clone()), "t.txt");
            if let Ok(calib) = kitti::parse_calib(Cursor::new(bytes), "c.txt") {
                let _ = calib.cam0_from_velo();
                let _ = calib.projection(0);
            }
        }
    }

    #[test]
    fn label_reader_never_panics_and_keeps_every_whole_label(
        raw in prop::collection::vec(any::<u32>(), 0..64),
        cut in 0usize..260,
    ) {
        let bytes: Vec<u8> = raw.iter().flat_map(|v| v.to_le_bytes()).collect();
        let cut = cut.min(bytes.len());
        match kitti::parse_labels(&bytes[..cut], "l.label") {
            Ok(labels) => {
                prop_assert_eq!(cut % 4, 0);
                prop_assert_eq!(labels.len(), cut / 4);
                for (label, raw) in labels.iter().zip(&raw) {
                    prop_assert_eq!(label.raw(), *raw);
                }
            }
            Err(err) => {
                prop_assert!(cut % 4 != 0);
                prop_assert_eq!(err.location(), Location::Byte((cut - cut % 4) as u64));
            }
        }
    }

    #[test]
    fn velodyne_reader_never_panics(
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<usize>(), any::<u8>()), 0..6),
    ) {
        let bytes = velodyne_bytes(20);
        let len = ((bytes.len() as f64) * cut) as usize;
        let mut bytes = bytes[..len].to_vec();
        for (at, v) in edits {
            if !bytes.is_empty() {
                let i = at % bytes.len();
                bytes[i] = v;
            }
        }
        match kitti::parse_velodyne(&bytes, "s.bin") {
            Ok(cloud) => {
                prop_assert_eq!(cloud.len() * 16, bytes.len());
                prop_assert!(cloud.points.iter().all(|p| p.iter().all(|v| v.is_finite())));
            }
            Err(e) => prop_assert!(matches!(e.location(), Location::Byte(_))),
        }
    }
}
