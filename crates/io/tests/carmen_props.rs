//! The CARMEN reader never panics: thousands of truncated and mutated versions of a small
//! valid log give records or errors, and every scan it does return is valid.

#![allow(clippy::unwrap_used)]

use std::io::Cursor;

use proptest::prelude::*;
use raypath_io::carmen::{CarmenConfig, CarmenReader, Record};
use raypath_io::samples::CARMEN_LOG as LOG;

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
