//! PCD reader robustness: thousands of truncated and mutated files never make it panic.
#![allow(clippy::unwrap_used)]

use proptest::prelude::*;
use raypath_io::pcd::{self, LabelSource, ReadOptions};

/// Valid files of every encoding, with labels, colour, NaN points and exotic skipped fields
/// (`raypath_io::samples::pcd`).
fn bases() -> Vec<Vec<u8>> {
    raypath_io::samples::pcd()
        .unwrap()
        .into_iter()
        .map(|s| s.bytes)
        .collect()
}

fn mutated() -> impl Strategy<Value = (Vec<u8>, usize)> {
    let bases = bases();
    (
        0..bases.len(),
        0.0f64..1.0,
        prop::collection::vec((0.0f64..1.0, any::<u8>()), 0..6),
        0usize..4,
    )
        .prop_map(move |(which, cut, edits, option)| {
            let mut bytes = bases[which].clone();
            // Half the cases keep the whole file and only mutate it.
            if cut < 0.5 {
                let keep = (cut * 2.0 * bytes.len() as f64) as usize;
                bytes.truncate(keep);
            }
            for (at, value) in edits {
                if !bytes.is_empty() {
                    let i = ((at * bytes.len() as f64) as usize).min(bytes.len() - 1);
                    bytes[i] = value;
                }
            }
            (bytes, option)
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn truncated_and_mutated_files_never_panic((bytes, option) in mutated()) {
        let label_from = match option {
            0 => LabelSource::LabelField,
            1 => LabelSource::Intensity,
            2 => LabelSource::Field("w".into()),
            _ => LabelSource::None,
        };
        let options = ReadOptions { label_from };
        if let Ok(read) = pcd::read_pcd_bytes(&bytes, "m.pcd", &options) {
            // Whatever is accepted is consistent.
            prop_assert!(read.cloud.validate().is_ok());
            prop_assert_eq!(read.cloud.len(), read.header.points);
        }
    }
}

#[test]
fn unmutated_bases_read() {
    for bytes in bases() {
        let read = pcd::read_pcd_bytes(&bytes, "b.pcd", &ReadOptions::default()).unwrap();
        assert_eq!(read.cloud.len(), read.header.points);
    }
}
