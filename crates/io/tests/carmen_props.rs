//! The CARMEN reader never panics: thousands of truncated and mutated versions of a small
//! valid log give records or errors, and every scan it does return is valid.

#![allow(clippy::unwrap_used)]

use std::io::Cursor;

use proptest::prelude::*;
use raypath_io::carmen::{CarmenConfig, CarmenReader, Record};

const LOG: &str = "\
# CARMEN Logfile
PARAM laser_front_laser_resolution 1 0.0 nohost 0
PARAM robot_front_laser_max 30.5 1000.0 host 0.001
PARAM laser_front_laser_flipped 0 nohost 0
ODOM 1.0 2.0 0.5 0.3 -0.1 0.0 1000.25 host 0.25
FLASER 4 1.0 2.0 81.91 4.0 10.0 20.0 1.57 10.5 20.5 1.6 1000.5 robby 0.5
FLASER 4 1.5 81.91 3.0 4.5 10.1 20.0 1.57 10.6 20.5 1.6 1000.6 robby 0.6
RLASER 3 1.0 31.0 2.0 0.0 0.0 0.0 0.0 0.0 0.0 1000.6 robby 0.6
NEFF 27.6 0 pippo 0
ROBOTLASER1 0 -1.0 2.0 1.0 81.9 0.01 1 3 5.0 81.91 6.0 3 100 200 300 1.0 0.0 0.0 0.8 0.0 0.0 0.25 0.1 0.5 0.3 0.2 1000.75 robby 0.75
TRUEPOS 1 2 3 4 5 6 7 h 8
";

/// Tokens that stress number parsing and counts.
const NASTY: [&str; 12] = [
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-0",
    "0",
    "99999999999999999999",
    "18446744073709551615",
    "-3",
    "FLASER",
    "ROBOTLASER1",
    "\u{e9}",
];

#[derive(Clone, Debug)]
enum Mutation {
    Truncate(usize),
    FlipByte(usize, u8),
    DeleteRange(usize, usize),
    ReplaceToken(usize, usize),
    DuplicateLine(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::FlipByte(i, b)),
        (any::<usize>(), 0usize..40).prop_map(|(i, n)| Mutation::DeleteRange(i, n)),
        (any::<usize>(), 0usize..NASTY.len()).prop_map(|(i, t)| Mutation::ReplaceToken(i, t)),
        any::<usize>().prop_map(Mutation::DuplicateLine),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    let len = bytes.len().max(1);
    match *m {
        Mutation::Truncate(i) => bytes.truncate(i % len),
        Mutation::FlipByte(i, b) => {
            if let Some(byte) = bytes.get_mut(i % len) {
                *byte = b;
            }
        }
        Mutation::DeleteRange(i, n) => {
            let start = i % len;
            let end = (start + n).min(bytes.len());
            if start < end {
                bytes.drain(start..end);
            }
        }
        Mutation::ReplaceToken(i, t) => {
            let text = String::from_utf8_lossy(bytes).into_owned();
            let tokens: Vec<&str> = text.split(' ').collect();
            let k = i % tokens.len();
            let mut out: Vec<&str> = tokens.clone();
            out[k] = NASTY[t];
            *bytes = out.join(" ").into_bytes();
        }
        Mutation::DuplicateLine(i) => {
            let text = String::from_utf8_lossy(bytes).into_owned();
            let mut lines: Vec<&str> = text.split('\n').collect();
            let k = i % lines.len();
            lines.insert(k, lines[k]);
            *bytes = lines.join("\n").into_bytes();
        }
    }
}

fn check(bytes: Vec<u8>, lookahead_scans: usize) {
    let config = CarmenConfig {
        lookahead_scans,
        ..CarmenConfig::default()
    };
    let reader = CarmenReader::with_config(Cursor::new(bytes), "fuzz.log", config).unwrap();
    for record in reader {
        match record {
            Ok(Record::Laser(laser)) => {
                assert!(laser.scan.validate().is_ok(), "{laser:?}");
                assert!(laser.scan.ranges.iter().all(|r| r.is_finite()));
                assert!(laser.world_from_laser.is_finite());
                let _ = laser.scan.points(laser.world_from_laser).count();
            }
            Ok(_) => {}
            Err(e) => {
                let text = e.to_string();
                assert!(text.starts_with("fuzz.log"), "{text}");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn mutated_logs_never_panic(
        mutations in prop::collection::vec(mutation(), 1..6),
        lookahead in 1usize..4,
    ) {
        let mut bytes = LOG.as_bytes().to_vec();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        check(bytes, lookahead);
    }

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        check(bytes, 1000);
    }
}

#[test]
fn the_unmutated_log_reads_cleanly() {
    let records: Vec<_> = CarmenReader::new(Cursor::new(LOG.as_bytes().to_vec()), "ok.log")
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(records.len(), 10);
}
